"""From pixels with a camera that moves: the bundled PETS09-S2L1 clip (200 frames, a still
camera) cut from windows that move, so that every person's box is known (the ground truth
moved with the window and clipped to it; boxes less than half inside left out).

    python bench/moving_view.py

Each window is tracked as `vistrack track` does (`track_video`, the bgsub front-end and
bytetrack) with the background model following the view (the default), and without
(`follow_view=False`, `--still-camera`); beside them, the whole still clip's own tracks seen
through the same window (what a still camera gives: it sees people before they come into
the window). HOTA / MOTA / IDF1 against the moved ground truth. The windows:

- 560 x 400 moving 1 pixel a frame to the right from the first frame; 1 pixel a frame to the
  left, swaying up and down by 30; 2 pixels a frame, turning back at frame 100; still for 60
  frames, then 1 pixel a frame to the right;
- 480 x 360 wandering as a hand-held camera does: 6 pixels a frame (three draws) or 10 (one
  draw) in a direction that turns by a normal step of 0.3 radians a frame, bouncing inside
  the frame.

Needs nothing from ../shared: the clip and its ground truth are bundled.
"""

from __future__ import annotations

import argparse
import tempfile
import warnings
from pathlib import Path

import numpy as np

from vistrack.evaluation import evaluate_mot
from vistrack.io import MOTTable, VideoReader, VideoWriter
from vistrack.pipeline import track_video

CLIP = Path(__file__).resolve().parents[1] / "src" / "vistrack" / "data" / "pets09-s2l1"
N = 200


def wander(seed: int, speed: float, size: tuple[int, int]) -> np.ndarray:
    """(N, 2) whole-pixel corners of a window that wanders inside the 768 x 576 frame."""
    w, h = size
    rng = np.random.default_rng(seed)
    pos, ang, out = np.array([144.0, 108.0]), rng.uniform(0, 2 * np.pi), []
    for _ in range(N):
        out.append(pos.copy())
        ang += rng.normal(0, 0.3)
        v = speed * np.array([np.cos(ang), np.sin(ang)])
        nxt = pos + v
        for a, lim in ((0, 768 - w), (1, 576 - h)):
            if not 0 <= nxt[a] <= lim:  # bounce
                v[a] = -v[a]
                ang = float(np.arctan2(v[1], v[0]))
        pos = np.clip(pos + v, 0, [768 - w, 576 - h])
    return np.round(np.array(out)).astype(int)


def windows() -> list[tuple[str, np.ndarray, tuple[int, int]]]:
    k = np.arange(N)
    still_then = 60 + np.maximum(0, k - 60)
    turn = np.where(k < 100, 2 * k, 200 - 2 * (k - 100))
    return [
        ("560 x 400, 1 pixel a frame to the right, from the first frame",
         np.c_[k, np.full(N, 40)], (560, 400)),
        ("560 x 400, 1 pixel a frame to the left, swaying up and down by 30",
         np.c_[200 - k, 40 + np.round(30 * np.sin(k / 40)).astype(int)], (560, 400)),
        ("560 x 400, 2 pixels a frame, turning back at frame 100",
         np.c_[turn, np.full(N, 40)], (560, 400)),
        ("560 x 400, still for 60 frames, then 1 pixel a frame to the right",
         np.c_[still_then, np.full(N, 40)], (560, 400)),
        *[(f"480 x 360 wandering, 6 pixels a frame (draw {s})", wander(s, 6.0, (480, 360)),
           (480, 360)) for s in (0, 1, 2)],
        ("480 x 360 wandering, 10 pixels a frame (draw 0)", wander(0, 10.0, (480, 360)),
         (480, 360)),
    ]


def seen_through(rows: np.ndarray, corners: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """MOTChallenge rows moved into the window of each frame and clipped to it; boxes less
    than half inside left out."""
    w, h = size
    r = np.array(rows, float)
    f = r[:, 0].astype(int) - 1
    a, b = r[:, 2] - corners[f, 0], r[:, 3] - corners[f, 1]
    ca, cb = np.clip(a, 0, w), np.clip(b, 0, h)
    cc, cd = np.clip(a + r[:, 4], 0, w), np.clip(b + r[:, 5], 0, h)
    inside = (cc - ca) * (cd - cb) >= 0.5 * r[:, 4] * r[:, 5]
    r[:, 2], r[:, 3], r[:, 4], r[:, 5] = ca, cb, cc - ca, cd - cb
    return r[inside]


def scores(gt: MOTTable, rows: np.ndarray) -> str:
    s = evaluate_mot(gt, MOTTable.from_rows(rows[:, :7], "tracks"), N)
    return f"{100 * s.HOTA:.1f} / {100 * s.MOTA:.1f} / {100 * s.IDF1:.1f}".replace("-", "−")


def tracks(video: Path, out: Path, **kw) -> np.ndarray:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the view moves: said, and known here
        run = track_video(video, out, annotate=False, stop=N, force=True, **kw)
    return np.loadtxt(run.files["tracks"], delimiter=",", ndmin=2)


def main() -> None:
    argparse.ArgumentParser(description=__doc__.split("\n\n")[0]).parse_args()
    frames = [f.image for f in VideoReader(CLIP / "pets09-s2l1.mp4", stop=N)]
    gt = np.loadtxt(CLIP / "gt.txt", delimiter=",")
    gt = gt[gt[:, 0] <= N]
    with tempfile.TemporaryDirectory() as tmp:
        d = Path(tmp)
        still = tracks(CLIP / "pets09-s2l1.mp4", d / "still")
        print("| window | following the view | not following (--still-camera) "
              "| the still clip's tracks, seen through the window |")
        print("|---|---|---|---|")
        for name, corners, (w, h) in windows():
            video = d / "window.mp4"
            with VideoWriter(video, fps=7) as out:
                for im, (x, y) in zip(frames, corners):
                    out.write(im[y:y + h, x:x + w])
            truth = MOTTable.from_rows(seen_through(gt, corners, (w, h)), "gt")
            follows = scores(truth, tracks(video, d / "follows"))
            fixed = scores(truth, tracks(video, d / "fixed", follow_view=False))
            ref = scores(truth, seen_through(still, corners, (w, h)))
            print(f"| {name} | {follows} | {fixed} | {ref} |", flush=True)


if __name__ == "__main__":
    main()
