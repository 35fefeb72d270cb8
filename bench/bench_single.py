"""Single-object tracking on OTB "Crossing" and VOT2015 "bag": vistrack's trackers beside
OpenCV contrib's CSRT and KCF, in one run.

    python bench/bench_single.py [--write docs/benchmarks.md]

Success rate (IoU > 0.5), AUC of the success curve, precision (centre within 20 px) and
frames per second of the tracker's updates. VOT's rotated boxes become axis-aligned boxes of
the same area (VOT's and SiamFC's rule); the corners' bounding box is shown too.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time
from pathlib import Path

import cv2
import numpy as np

from vistrack.evaluation.single import precision, read_boxes, success_curve, success_rate
from vistrack.tracking.compose import Composite
from vistrack.tracking.single import single_tracker

from _markdown import publish  # noqa: E402  (bench/ is on the path of its scripts)

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
SEQS = {
    "OTB Crossing": (DATA / "otb-crossing" / "Crossing" / "img", "*.jpg",
                     DATA / "otb-crossing" / "Crossing" / "groundtruth_rect.txt"),
    "VOT15 bag": (DATA / "vot15-bag" / "imgs", "*.jpg", DATA / "vot15-bag" / "groundtruth.txt"),
}
METHODS = (("vistrack colour (default)", "colour"), ("vistrack camshift", "camshift"),
           ("vistrack particle (colour CONDENSATION)", "particle"),
           ("vistrack template", "template"),
           ("vistrack klt (median flow)", "klt"), ("vistrack wsl (online appearance)", "wsl"),
           ("vistrack meanshift (colour, fixed size)", "meanshift"),
           ("vistrack snake", "snake"),
           ("vistrack meanshift + snake (Composite)", "compose"),
           ("OpenCV CSRT", "csrt"), ("OpenCV KCF", "kcf"))


def make(method):
    if method == "compose":     # the composition of examples/compose_bag.py
        return Composite({"colour": (single_tracker("meanshift"), (0.1, 1.0)),
                          "shape": (single_tracker("snake"), (0.2, 0.05))})
    return single_tracker(method)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    rows = []
    for seq, (folder, pattern, gt_path) in SEQS.items():
        files = sorted(folder.glob(pattern))
        if not files:
            sys.exit(f"{folder} not found: the shared data must be beside this checkout")
        frames = [cv2.imread(str(f)) for f in files]
        gt = read_boxes(gt_path)
        gt_mm = read_boxes(gt_path, rule="minmax") if gt_path.name == "groundtruth.txt" else None
        for label, method in METHODS:
            tr = make(method)
            tr.init(frames[0], gt[0])
            out = [gt[0]]
            t = time.perf_counter()
            for f in frames[1:]:
                out.append(tr.update(f))
            fps = (len(frames) - 1) / (time.perf_counter() - t)
            out = np.array(out)
            mm = f"{100 * success_rate(out, gt_mm):.0f}" if gt_mm is not None else ""
            rows.append((seq, label, 100 * success_rate(out, gt), mm,
                         100 * success_curve(out, gt)[2], 100 * precision(out, gt), fps))
            print(f"  {seq}, {label}: {rows[-1][2]:.0f} %", file=sys.stderr)
    t = ["| sequence | tracker | success (IoU > 0.5) | success, corners' box | AUC | "
         "precision (20 px) | frames/s |", "|---|---|---:|---:|---:|---:|---:|"]
    t += [f"| {s} | {m} | {a:.0f} % | {mm}{' %' if mm else ''} | {c:.0f} % | {p:.0f} % | "
          f"{f:.0f} |" for s, m, a, mm, c, p, f in rows]
    env = (f"Python {platform.python_version()}, OpenCV {cv2.__version__}, "
           f"{time.strftime('%Y-%m-%d')}")
    section = (f"## Single-object tracking\n\nMeasured with `python bench/bench_single.py` "
               f"({env}), started from the first ground-truth box.\n\n" + "\n".join(t) + "\n")
    publish(section, args.write)


if __name__ == "__main__":
    main()
