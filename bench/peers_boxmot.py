"""Run boxmot's trackers over MOTChallenge sequence folders and write results files.

    PYTHON_WITH_BOXMOT bench/peers_boxmot.py [--squash=clip|logistic] OUT_DIR SEQ_DIR ...

Writes ``OUT_DIR/<tracker>/<sequence>.txt`` for BoT-SORT (no ReID, no camera-motion
compensation: neither has images here), ByteTrack and OC-SORT, each with the defaults its
constructor gives and the sequence's frame rate where the constructor takes one. Runs in an
interpreter of its own: boxmot pins ``filterpy<2`` and ``opencv-python<5``, which clash with
vistrack's test dependencies, so :mod:`accuracy_mot` calls this script with ``--boxmot-python``.
It reads and writes the files itself (numpy only), and does not import vistrack.
"""

from __future__ import annotations

import configparser
import inspect
import sys
import time
import warnings
from pathlib import Path

import numpy as np

SQUASH = "clip"


def trackers():
    from boxmot import BotSort, ByteTrack, OcSort

    def make(cls, fps, **kw):
        if "frame_rate" in inspect.signature(cls.__init__).parameters:
            kw["frame_rate"] = int(round(fps))
        return cls(**kw)

    return {
        "boxmot BoT-SORT": lambda fps: make(BotSort, fps, use_cmc=False, use_embeddings=False),
        "boxmot ByteTrack": lambda fps: make(ByteTrack, fps),
        "boxmot OC-SORT": lambda fps: make(OcSort, fps),
    }


def seqinfo(seq: Path) -> tuple[float, int, int, int]:
    cp = configparser.ConfigParser()
    cp.read(seq / "seqinfo.ini")
    s = cp["Sequence"]
    return (float(s["frameRate"]), int(s["seqLength"]), int(s["imWidth"]), int(s["imHeight"]))


def run(make, seq: Path) -> tuple[np.ndarray, float]:
    fps, n, w, h = seqinfo(seq)
    det = np.loadtxt(seq / "det" / "det.txt", delimiter=",", ndmin=2, encoding="utf-8-sig")
    det = det[(det[:, 4] > 0) & (det[:, 5] > 0)]  # boxmot refuses empty boxes
    if len(det) and (det[:, 6].min() < 0 or det[:, 6].max() > 1):
        # boxmot refuses scores outside [0, 1]; raw scores (logits, such as PointRCNN's) are
        # clipped to [0, 1], which scores higher on KITTI than the logistic function
        # (--squash=logistic)
        det[:, 6] = (np.clip(det[:, 6], 0, 1) if SQUASH == "clip"
                     else 1 / (1 + np.exp(-det[:, 6])))
    tr = make(fps)
    image = np.zeros((h, w, 3), np.uint8)
    rows, sec = [], 0.0
    for f in range(1, n + 1):
        d = det[det[:, 0] == f]
        dets = np.c_[d[:, 2:4], d[:, 2:4] + d[:, 4:6], d[:, 6], np.zeros(len(d))].astype(np.float32)
        t0 = time.perf_counter()
        out = tr.update(dets, image)
        sec += time.perf_counter() - t0
        for x0, y0, x1, y1, tid, conf, *_ in np.asarray(out).reshape(-1, 8):
            rows.append((f, int(tid), x0, y0, x1 - x0, y1 - y0, conf))
    return np.array(rows, float).reshape(-1, 7), n / max(sec, 1e-9)


def main() -> None:
    global SQUASH
    args = sys.argv[1:]
    if args and args[0].startswith("--squash="):
        SQUASH = args.pop(0).split("=", 1)[1]
    out_dir, seqs = Path(args[0]), [Path(p) for p in args[1:]]
    warnings.filterwarnings("ignore")
    for name, make in trackers().items():
        d = out_dir / name
        d.mkdir(parents=True, exist_ok=True)
        for seq in seqs:
            rows, fps = run(make, seq)
            with open(d / f"{seq.name}.txt", "w") as fh:
                for f, i, x, y, ww, hh, c in rows:
                    fh.write(f"{int(f)},{int(i)},{x:.2f},{y:.2f},{ww:.2f},{hh:.2f},{c:.4f},-1,-1,-1\n")
            print(f"{name}\t{seq.name}\t{fps:.1f}", flush=True)


if __name__ == "__main__":
    main()
