"""The inputs that docs/frontends.md's examples run on, made from the bundled clip:

- ``pan.mp4``: 150 frames of PETS09-S2L1 (the bundled clip), each cut from a 560 x 400 window
  that moves right by 1.3 pixels a frame and sways up and down by 20 (a sine of 50 frames),
  for the background model that follows a moving view;
- ``dets.csv``: 30 frames of two detections each, a person (class 0) walking right and a car
  (class 2) driving left, scores 0.9, for a detections file of several classes.

    python examples/doc_inputs.py [OUT_FOLDER]

Then, in ``OUT_FOLDER`` (default: the current folder):

    vistrack track pan.mp4 --out-dir out
    vistrack track pan.mp4 --still-camera --out-dir still
    vistrack track dets.csv --fps 10 --out tracks.parquet
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from vistrack.data import demo_clip
from vistrack.io import VideoReader, VideoWriter

N_PAN, W, H = 150, 560, 400


def pan_corners() -> np.ndarray:
    """(N_PAN, 2) whole-pixel top-left corners of the moving window."""
    k = np.arange(N_PAN)
    x = 10 + 1.3 * k
    y = 88 + 20 * np.sin(2 * np.pi * k / 50)
    return np.round(np.c_[x, y]).astype(int)


def write_pan(path: Path) -> None:
    corners = pan_corners()
    with VideoWriter(path, fps=7) as out:
        for (x, y), frame in zip(corners, VideoReader(demo_clip().video, stop=N_PAN)):
            out.write(frame.image[y:y + H, x:x + W])


def write_dets(path: Path) -> None:
    lines = ["frame,bb_left,bb_top,bb_width,bb_height,conf,class"]
    for f in range(1, 31):
        lines.append(f"{f},{100 + 4 * f},200,40,100,0.9,0")  # a person, walking right
        lines.append(f"{f},{600 - 10 * f},300,120,60,0.9,2")  # a car, driving left
    path.write_text("\n".join(lines) + "\n")


def main() -> None:
    out = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(".")
    out.mkdir(parents=True, exist_ok=True)
    write_pan(out / "pan.mp4")
    write_dets(out / "dets.csv")
    print(f"wrote {out / 'pan.mp4'} and {out / 'dets.csv'}")


if __name__ == "__main__":
    main()
