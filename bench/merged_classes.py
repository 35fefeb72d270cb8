"""A detector of several classes in one file: each KITTI drive of `../shared/data` that has
both classes (cars and pedestrians, PointRCNN's detections on scales of their own) tracked
from one file of both, beside each class tracked from a file of its own, online and offline.

    python bench/merged_classes.py [--write docs/mot.md]

Each class's rows of the one file's results are scored against that class's ground truth
(TrackEval's MOT15 convention, as `vistrack eval` scores KITTI), HOTA / MOTA / IDF1. A
tracker that keeps classes apart should score both ways alike: the box tracker never lets
a track take another class's detections, and calibrates each class's scores on their own.
What still couples the classes: the camera's motion, estimated from every track, and the
frames the detector did not deliver, found in the whole file (a frame of pedestrians alone
was delivered to the cars too).
"""

from __future__ import annotations

import argparse
import shutil
import sys
import tempfile
import warnings
from pathlib import Path

import pandas as pd

from vistrack.evaluation.files import evaluate_files
from vistrack.io import read_mot
from vistrack.pipeline import track_sequence

from _markdown import publish  # noqa: E402  (bench/ is on the path of its scripts)

KITTI = Path(__file__).resolve().parents[2] / "shared" / "data" / "kitti-tracking"
CLASSES = (("Car", 2), ("Pedestrian", 0))


def drives() -> list[str]:
    """The drives with a folder of each class."""
    return sorted(p.name[len("KITTI-"):-len("-Car")] for p in KITTI.glob("KITTI-*-Car")
                  if (KITTI / p.name.replace("-Car", "-Pedestrian")).is_dir())


def one_file(drive: str, folder: Path) -> Path:
    """A sequence folder holding both classes' detections in one CSV (class 2 the cars,
    0 the pedestrians), with the drive's seqinfo.ini."""
    seq = folder / f"KITTI-{drive}"
    seq.mkdir()
    shutil.copy(KITTI / f"KITTI-{drive}-Car" / "seqinfo.ini", seq / "seqinfo.ini")
    parts = []
    for name, cls in CLASSES:
        d = read_mot(KITTI / f"KITTI-{drive}-{name}" / "det" / "det.txt")
        parts.append(pd.DataFrame({"frame": d.frames, "bb_left": d.boxes[:, 0],
                                   "bb_top": d.boxes[:, 1], "bb_width": d.boxes[:, 2],
                                   "bb_height": d.boxes[:, 3], "conf": d.conf, "class": cls}))
    pd.concat(parts).sort_values("frame", kind="stable").to_csv(seq / "both.csv", index=False)
    return seq


def score(name: str, results: Path) -> tuple[float, float, float]:
    gt = KITTI / f"KITTI-{name}"
    r = evaluate_files([(name, gt / "gt" / "gt.txt", results, gt / "seqinfo.ini")])[name]
    return 100 * r.HOTA, 100 * r.MOTA, 100 * r.IDF1


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--write", metavar="FILE", help="put the section into this markdown file")
    args = ap.parse_args()
    if not KITTI.is_dir():
        sys.exit(f"{KITTI} not found: the shared data must be beside this checkout")
    rows = []
    with tempfile.TemporaryDirectory() as tmp, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # (the files' own warnings: several classes, ...)
        tmp_path = Path(tmp)
        for drive in drives():
            seq = one_file(drive, tmp_path)
            for offline in (False, True):
                mode = "offline" if offline else "online"
                both = tmp_path / f"{drive}-{mode}.csv"
                track_sequence(seq, both, detections=seq / "both.csv", offline=offline)
                table = pd.read_csv(both)
                for name, cls in CLASSES:
                    alone = tmp_path / f"{drive}-{name}-{mode}.txt"
                    track_sequence(KITTI / f"KITTI-{drive}-{name}", alone, offline=offline)
                    part = tmp_path / f"{drive}-{name}-{mode}-of-both.csv"
                    table[table["class"] == cls].to_csv(part, index=False)
                    rows.append((f"KITTI-{drive}-{name}", mode, score(f"{drive}-{name}", alone),
                                 score(f"{drive}-{name}", part)))
    lines = ["## A detector of several classes in one file", "",
             "Measured with `python bench/merged_classes.py`: each KITTI drive with both "
             "classes, tracked from one file of both (classes 2 and 0) and from a file of each "
             "class alone; each class's rows scored against its own ground truth, HOTA / MOTA / "
             "IDF1.", "",
             "| sequence | mode | each class alone | from one file of both |",
             "|---|---|---|---|"]
    for name, mode, alone, both in rows:
        lines.append(f"| {name} | {mode} | {' / '.join(f'{v:.1f}' for v in alone)} | "
                     f"{' / '.join(f'{v:.1f}' for v in both)} |")
    publish("\n".join(lines) + "\n", args.write)


if __name__ == "__main__":
    main()
