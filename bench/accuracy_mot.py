"""Tracking accuracy on MOT15 and MOT17 train, per sequence and combined (TrackEval's
conventions, vistrack's scorer, which equals TrackEval), with the public detections.

    python bench/accuracy_mot.py [--tracker NAME] [--offline] [--write docs/mot.md]

MOT15: SORT's Faster R-CNN detections (``det/det.txt``); MOT17: the FRCNN detections. The
same configuration for every sequence.
"""

from __future__ import annotations

import argparse
import platform
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from _markdown import replace_section  # noqa: E402  (bench/ is on the path of its scripts)
from vistrack.pipeline import evaluate_files, track_sequence

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"


def run(bench: str, tracker: str, offline: bool, tmp: Path):
    root = DATA / bench.lower()
    seqs = sorted(p for p in root.iterdir() if (p / "seqinfo.ini").exists())
    pairs, speed, skipped = [], {}, []
    for d in seqs:
        r = track_sequence(d, tmp / bench / f"{d.name}.txt", tracker=tracker, offline=offline,
                           force=True, progress=None)
        speed[d.name] = r.fps
        if (d / "gt" / "gt.txt").exists():
            pairs.append((d.name, d / "gt" / "gt.txt", r.out, d / "seqinfo.ini"))
        else:
            skipped.append(d.name)
    return evaluate_files(pairs), speed, skipped


def table(res, speed):
    out = ["| sequence | HOTA | DetA | AssA | MOTA | IDF1 | IDSW | FP | FN | tracker fps |",
           "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, c in res.items():
        fps = f"{speed[name]:.0f}" if name in speed else ""
        out.append(f"| {name} | {100 * c.HOTA:.1f} | {100 * c.DetA:.1f} | {100 * c.AssA:.1f} | "
                   f"{100 * c.MOTA:.1f} | {100 * c.IDF1:.1f} | {c.IDSW} | {c.FP} | {c.FN} | {fps} |")
    return "\n".join(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--tracker", default="bytetrack")
    ap.add_argument("--offline", action="store_true")
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    if not DATA.exists():
        sys.exit(f"{DATA} not found: the shared MOTChallenge data must be beside this checkout")
    parts = []
    with tempfile.TemporaryDirectory() as tmp:
        for bench in ("MOT15", "MOT17"):
            res, speed, skipped = run(bench, args.tracker, args.offline, Path(tmp))
            note = (f" Not scored (no ground truth here): {', '.join(skipped)}." if skipped
                    else "")
            mode = ", offline" if args.offline else ""
            parts.append(f"**{bench} train, `{args.tracker}`{mode}**{note}\n\n"
                         f"{table(res, speed)}\n")
    env = f"Python {platform.python_version()}, numpy {np.__version__}, {time.strftime('%Y-%m-%d')}"
    flag = " --offline" if args.offline else ""
    title = "Offline accuracy" if args.offline else "Accuracy"
    section = (f"## {title} on MOT15 and MOT17 train\n\nMeasured with `python "
               f"bench/accuracy_mot.py --tracker {args.tracker}{flag}` ({env}).\n\n"
               + "\n".join(parts))
    print(section)
    if args.write:
        replace_section(args.write, section)


if __name__ == "__main__":
    main()
