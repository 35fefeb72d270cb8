"""Clutter that stays where it is: MOT17's FRCNN detections with a few false boxes added that
recur in place, scoring no higher than the lowest real detection, vistrack beside the peers of
``accuracy_mot.py``, scored the same way (COMBINED over the seven sequences).

    python bench/static_clutter.py [--boxes 0,2,5] [--no-peers] [--boxmot-python PY]
                                   [--write docs/mot.md]

A detector fires again and again on the same poster, mannequin or reflection, mostly at low
scores: such false positives persist from frame to frame as a real object does, which is what
vistrack's score calibration learns confidence from (``vistrack.tracking.calibration``). For
each sequence and each count ``K`` of ``--boxes``, ``K`` places are drawn at random (seeded
by the sequence's name), each with the size of one of the sequence's own detections,
anywhere in the image; in each frame, each place has a box with probability 0.9, its corner
moved from the place by 2 pixels (standard deviation, in x and y), scoring uniformly up to
half the lowest score's magnitude below the sequence's lowest score (written to four
significant digits, as every score: a few equal the lowest). ``K = 0`` is MOT17 as it is.
Trackers whose thresholds on the raw scores lie above these scores (OC-SORT, BoT-SORT,
boxmot's ByteTrack) never take them; a calibration that trusted persistence over the
detector's ranking would start tracks from them.
"""

from __future__ import annotations

import argparse
import platform
import shutil
import sys
import tempfile
import time
import warnings
import zlib
from pathlib import Path

import accuracy_mot as acc  # bench/ is on the path of its scripts
import numpy as np

from vistrack.io import read_mot, read_seqinfo, write_mot
from vistrack.pipeline import track_sequence

from _markdown import publish  # noqa: E402


def add_clutter(src: Path, k: int, root: Path) -> Path:
    """A copy of sequence folder ``src`` under ``root`` (its ``seqinfo.ini`` and ground truth)
    with ``k`` boxes that stay in place added to its detections (see the module)."""
    rng = np.random.default_rng(zlib.crc32(src.name.encode()))
    out = root / src.name
    (out / "det").mkdir(parents=True)
    (out / "gt").mkdir()
    shutil.copy(src / "seqinfo.ini", out / "seqinfo.ini")
    shutil.copy(src / "gt" / "gt.txt", out / "gt" / "gt.txt")
    info, det = read_seqinfo(src), read_mot(src / "det" / "det.txt")
    wh = det.boxes[rng.integers(0, len(det.conf), k), 2:]
    xy = rng.uniform(0, [info.im_width, info.im_height], (k, 2)) - wh / 2
    lo = float(det.conf.min())
    spread = abs(lo) / 2 or 0.5
    frames, boxes, conf = [det.frames], [det.boxes], [det.conf]
    for f in range(1, info.seq_length + 1):
        on = rng.random(k) < 0.9
        n = int(on.sum())
        frames.append(np.full(n, f))
        boxes.append(np.c_[xy[on] + rng.normal(0, 2, (n, 2)), wh[on]])
        conf.append(lo - spread * rng.random(n))
    f, b, c = np.concatenate(frames), np.concatenate(boxes), np.concatenate(conf)
    order = np.argsort(f, kind="stable")
    write_mot(out / "det" / "det.txt", f[order], np.full(len(f), -1), b[order], c[order])
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--boxes", default="0,2,5",
                    help="comma-separated counts of boxes that stay, one run each")
    ap.add_argument("--no-peers", action="store_true")
    ap.add_argument("--boxmot-python", type=Path,
                    default=acc.ROOT / ".venv-boxmot" / "bin" / "python")
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    try:
        counts = [int(x) for x in args.boxes.split(",")]
    except ValueError:
        ap.error(f"--boxes must be comma-separated integers; got {args.boxes!r}")
    if any(k < 0 for k in counts):
        ap.error(f"--boxes must be >= 0; got {args.boxes!r}")
    if not acc.DATA.exists():
        sys.exit(f"{acc.DATA} not found: the shared data must be beside this checkout")
    warnings.filterwarnings("ignore")
    peers = {} if args.no_peers else acc.trackers_peers()
    boxmot = None if args.no_peers or not args.boxmot_python.exists() else args.boxmot_python
    names = ["vistrack", "vistrack offline"]
    res: dict = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        for k in counts:
            seqs = [add_clutter(d, k, tmp / f"data{k}") for d in acc.sequences("MOT17")]
            out = tmp / f"out{k}"
            for label, offline in (("vistrack", False), ("vistrack offline", True)):
                for d in seqs:
                    track_sequence(d, out / label / f"{d.name}.txt", offline=offline,
                                   force=True)
                res[label, k] = acc.score(seqs, out / label)["COMBINED"]
            for label, make in peers.items():
                acc.run_trackers(make, seqs, out / label)
                res[label, k] = acc.score(seqs, out / label)["COMBINED"]
            if boxmot is not None:
                for label in acc.run_boxmot(boxmot, seqs, out):
                    res[label, k] = acc.score(seqs, out / label)["COMBINED"]
            for label in (lb for lb, kk in res if kk == k and lb not in names):
                names.append(label)
    head = " | ".join(f"{k} a frame" if k else "none" for k in counts)
    rows = [f"| tracker | {head} |", "|---" + "|---" * len(counts) + "|"]
    for label in names:
        bold = "**" if label.startswith("vistrack") else ""
        cells = [f"{100 * c.HOTA:.1f} / {100 * c.MOTA:.1f} / {100 * c.IDF1:.1f} ({c.FP})"
                 if (c := res.get((label, k))) is not None else "" for k in counts]
        rows.append(f"| {bold}{label}{bold} | " + " | ".join(cells) + " |")
    cmd = "python bench/static_clutter.py" + (f" --boxes {args.boxes}"
                                              if args.boxes != "0,2,5" else "")
    section = "\n".join([
        "## Clutter that stays",
        "",
        f"Measured with `{cmd}` (Python {platform.python_version()}, "
        f"{time.strftime('%Y-%m-%d')}): MOT17's FRCNN detections with boxes added that recur "
        "in place (in nine frames of ten, 2 pixels about their place), scoring below the "
        "lowest real detection (a few equal to it), as a detector's false positives on a "
        "poster or a reflection do (see the script). COMBINED HOTA / MOTA / IDF1 (false "
        "positives), by the number of such boxes in each sequence; one draw of their places "
        "and scores:",
        "",
        *rows,
        ""])
    publish(section, args.write)


if __name__ == "__main__":
    main()
