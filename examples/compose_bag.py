"""Tracker composition on VOT15 bag: colour and shape fused into one estimate (seed 001,
"Tracker composition: color and shape", "Combining trackers ⇒ robustness").

    python examples/compose_bag.py    # writes examples/figures/compose_bag.png

- **colour alone**: mean shift on the colour model (``meanshift``: the window keeps its first
  size). It stays on the bag, but the bag grows to about 1.6 times its first width as the
  camera closes in, and the window does not;
- **shape alone**: the B-spline snake (``snake``), its box the contour's bounding box. Its
  radial search snaps to the strong edges of the ground and the goal posts, and it is lost
  within a few frames;
- **composition**: :class:`~vistrack.tracking.compose.Composite` with the colour tracker
  trusted for the centre (standard deviation 0.1 of the box's size, its size ignored: 1.0 in
  log size) and the snake for the size (0.05 in log size, its centre at 0.2). Each frame
  both trackers start from the fused box.

Scores are against VOT's area-preserving boxes (:func:`vistrack.evaluation.single.read_boxes`).
"""

from __future__ import annotations

import sys
from pathlib import Path

import cv2
import numpy as np
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from vistrack.evaluation.single import overlaps, read_boxes, success_rate
from vistrack.tracking.compose import Composite
from vistrack.tracking.single import single_tracker

SEQ = Path(__file__).resolve().parents[2] / "shared" / "data" / "vot15-bag"
OUT = Path(__file__).resolve().parent / "figures" / "compose_bag.png"
NOISE = {"meanshift": (0.1, 1.0), "snake": (0.2, 0.05)}
SHOW = (30, 90, 150, 195)


def composite() -> Composite:
    return Composite({name: (single_tracker(name), sd) for name, sd in NOISE.items()})


def run(tracker, frames, first):
    tracker.init(frames[0], first)
    out, snaps = [first], {}
    for k, frame in enumerate(frames[1:], 1):
        out.append(tracker.update(frame))
        if k in SHOW:
            snake = getattr(tracker, "members", {}).get("snake", tracker)
            snaps[k] = snake.snake.contour() if hasattr(snake, "snake") else None
    return np.array(out), snaps


def main():
    files = sorted((SEQ / "imgs").glob("*.jpg"))
    if not files:
        sys.exit(f"{SEQ} not found: the shared data must be beside this checkout")
    frames = [cv2.imread(str(f)) for f in files]
    gt = read_boxes(SEQ / "groundtruth.txt")
    runs = {"colour alone (mean shift)": run(single_tracker("meanshift"), frames, gt[0]),
            "shape alone (snake)": run(single_tracker("snake"), frames, gt[0]),
            "colour + shape (Composite)": run(composite(), frames, gt[0])}
    fig = Figure(figsize=(10, 5.6), layout="constrained")
    grid = fig.add_gridspec(2, len(SHOW), height_ratios=[1.2, 1])
    colours = ("tab:blue", "tab:orange", "tab:red")
    for c, k in enumerate(SHOW):
        ax = fig.add_subplot(grid[0, c])
        # (imshow puts pixel k's centre at k, as the snake's contour has it; a box's pixel k
        # spans [k, k + 1), half a pixel on)
        ax.imshow(frames[k][:, :, ::-1])
        for (label, (boxes, snaps)), col in zip(runs.items(), colours):
            b = boxes[k]
            ax.add_patch(Rectangle(
                b[:2] - 0.5, b[2], b[3], fill=False, ec=col, lw=1.5))
            if snaps.get(k) is not None and label.startswith("colour +"):
                pts = np.vstack([snaps[k], snaps[k][:1]])
                ax.plot(pts[:, 0], pts[:, 1], "-", color="yellow", lw=0.8)
        g = gt[k]
        ax.add_patch(Rectangle(
            g[:2] - 0.5, g[2], g[3], fill=False, ec="lime", lw=1, ls="--"))
        ax.set_title(f"frame {k + 1}", fontsize=9)
        ax.set_xticks([])
        ax.set_yticks([])
    ax = fig.add_subplot(grid[1, :])
    for (label, (boxes, _)), col in zip(runs.items(), colours):
        rate = success_rate(boxes, gt)
        ax.plot(np.arange(1, len(gt) + 1), overlaps(boxes, gt), "-", color=col,
                label=f"{label}: success {100 * rate:.0f} %")
        print(f"  {label}: success (IoU > 0.5) {100 * rate:.0f} %, mean IoU "
              f"{overlaps(boxes, gt).mean():.2f}")
    ax.axhline(0.5, color="grey", lw=0.5, label="IoU 0.5: success")
    ax.set_xlabel("frame")
    ax.set_ylabel("IoU with the annotation")
    ax.set_ylim(0, 1)
    # below the plot: inside, it covered the snake's curve over frames 143-165
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.25), ncols=2)
    fig.suptitle("VOT15 bag: colour and shape trackers alone and composed (seed 001); "
                 "dashed green: annotation, yellow: the composite's snake", fontsize=10)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=90)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
