"""The seed's snake (a B-spline contour, radial edge search, least squares in a Kalman filter;
seed 001, "Snakes: basic approach") on VOT15 bag.

    python examples/snake_bag.py    # writes examples/figures/snake_bag.png

Started at frame 131 on the ellipse inscribed in the annotated box, where the bag is large and
white against the ground, the contour follows it to the last frame (196). Started at frame 1,
where the bag is small and the ground's texture has edges as strong as the bag's, it is lost
within 25 frames (`examples/compose_bag.py` holds it there by composing it with colour).
Scores are against the bounding box of VOT's polygon (the contour's box is a bounding box).
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import cv2
import numpy as np
from matplotlib.figure import Figure

from vistrack.evaluation.single import overlaps, read_boxes
from vistrack.tracking.snake import SnakeTracker

SEQ = Path(__file__).resolve().parents[2] / "shared" / "data" / "vot15-bag"
OUT = Path(__file__).resolve().parent / "figures" / "snake_bag.png"
FIRST, SHOW = 131, (132, 150, 170, 196)


def main():
    files = sorted((SEQ / "imgs").glob("*.jpg"))
    if not files:
        sys.exit(f"{SEQ} not found: the shared data must be beside this checkout")
    frames = [cv2.imread(str(f)) for f in files]
    gt = read_boxes(SEQ / "groundtruth.txt", rule="minmax")
    runs = {}
    for first in (1, FIRST):
        tracker = SnakeTracker()
        tracker.init(frames[first - 1], gt[first - 1])
        boxes, contours = [], {}
        t0 = time.perf_counter()
        for k in range(first, len(frames)):
            boxes.append(tracker.update(frames[k]))
            if k + 1 in SHOW:
                contours[k + 1] = tracker.snake.contour()
        ms = 1e3 * (time.perf_counter() - t0) / (len(frames) - first)
        ov = overlaps(np.array(boxes), gt[first:])
        runs[first] = (ov, contours)
        print(f"  from frame {first}: success (IoU > 0.5) {np.mean(ov > 0.5):.0%}, mean IoU "
              f"{ov.mean():.2f}, {ms:.1f} ms a frame")
    fig = Figure(figsize=(10, 5.4), layout="constrained")
    grid = fig.add_gridspec(2, len(SHOW), height_ratios=[1.2, 1])
    for c, f in enumerate(SHOW):
        ax = fig.add_subplot(grid[0, c])
        ax.imshow(frames[f - 1][:, :, ::-1])
        pts = runs[FIRST][1][f]
        pts = np.vstack([pts, pts[:1]])
        ax.plot(pts[:, 0], pts[:, 1], "-", color="yellow", lw=1.2)
        ax.set_title(f"frame {f}", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    ax = fig.add_subplot(grid[1, :])
    for first, col in ((1, "tab:orange"), (FIRST, "tab:blue")):
        ov = runs[first][0]
        ax.plot(np.arange(first + 1, len(frames) + 1), ov, "-", color=col,
                label=f"started at frame {first}: success {np.mean(ov > 0.5):.0%}")
    ax.axhline(0.5, color="grey", lw=0.5, label="IoU 0.5: success")
    ax.set_xlabel("frame")
    ax.set_ylabel("IoU with the annotation")
    ax.set_ylim(0, 1)
    ax.legend(fontsize=8)
    fig.suptitle("Snake (B-spline, radial edge search, Kalman least squares) on VOT15 bag",
                 fontsize=10)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=90)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
