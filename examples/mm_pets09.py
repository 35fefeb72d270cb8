"""The seeds' P vs PV multiple-model filter on a real pedestrian: PETS09-S2L1 (MOT15), person
15, who walks in, stands about 6 s among others, edges forward, stands 3 s more and walks
off.

    python examples/mm_pets09.py          # writes examples/figures/mm_pets09.png

Two models of the centre's motion, as in seed 000 ("Multiple model filters"): P, the position
alone (a random walk, 1 px²/s), and PV, position and velocity (white acceleration,
400 px²/s³), mixed by an IMM that switches with probability 0.05 a frame, at the sequence's
7 frames/s. Measured twice: by the annotated box centres (every frame), and by the public
detections matched to them (IoU >= 0.5; standing in a group, the person is rarely detected).
The figure shows the annotated speed and the probability of P.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

import vistrack as vt
from vistrack.evaluation import box_iou_xywh
from vistrack.filters import ExtendedKalmanFilter, IMMFilter
from vistrack.io import read_mot

SEQ = Path(__file__).resolve().parents[2] / "shared" / "data" / "mot15" / "PETS09-S2L1"
OUT = Path(__file__).resolve().parent / "figures" / "mm_pets09.png"
FPS, PERSON = 7.0, 15


def measurements():
    gt, det = read_mot(SEQ / "gt" / "gt.txt"), read_mot(SEQ / "det" / "det.txt")
    t = gt[gt.ids == PERSON]
    centres = t.boxes[:, :2] + t.boxes[:, 2:] / 2
    detected = np.full_like(centres, np.nan)
    for k, f in enumerate(t.frames):
        d = det[det.frames == f]
        if len(d):
            ov = box_iou_xywh(t.boxes[k:k + 1], d.boxes)[0]
            if ov.max() >= 0.5:
                j = int(np.argmax(ov))
                detected[k] = d.boxes[j, :2] + d.boxes[j, 2:] / 2
    step = np.linalg.norm(np.diff(centres, axis=0), axis=1) * FPS
    speed = np.r_[step[0], step]  # the first frame's speed is its first step's
    # a 5-frame mean, over the frames there are at the ends (no zeros padded in)
    kernel = np.ones(5)
    smooth = (np.convolve(speed, kernel, mode="same")
              / np.convolve(np.ones_like(speed), kernel, mode="same"))
    return t.frames, centres, detected, smooth


def p_probability(ys):
    P = ExtendedKalmanFilter(vt.ConstantPosition(dim=2, q=1.0), vt.Position(dim=2, r=4.0))
    PV = ExtendedKalmanFilter(vt.ConstantVelocity(dim=2, q=400.0), vt.Position(dim=2, r=4.0))
    imm = IMMFilter([P, PV], [[0.95, 0.05], [0.05, 0.95]])
    first = ys[~np.isnan(ys[:, 0])][0]
    res = imm.filter(ys, x0=np.r_[first, 0, 0], P0=np.diag([25, 25, 400, 400.0]), dt=1 / FPS)
    return res.mode_probs[:, 0]


def main():
    if not SEQ.exists():
        sys.exit(f"{SEQ} not found: the shared data must be beside this checkout")
    frames, centres, detected, speed = measurements()
    p_ann, p_det = p_probability(centres), p_probability(detected)
    still, walking = speed < 3, speed > 15
    fig = Figure(figsize=(9, 5.5))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    ax1.plot(frames, speed, "k-", lw=1)
    ax1.set_ylabel("annotated speed (px/s)")
    ax1.set_title(f"PETS09-S2L1, person {PERSON}: P vs PV (seed 000), IMM")
    for ax in (ax1, ax2):
        ax.fill_between(frames, 0, 1, where=still, color="tab:green", alpha=0.15,
                        transform=ax.get_xaxis_transform(), label="standing (< 3 px/s)")
    ax2.plot(frames, p_ann, "-", color="tab:blue", label="measured by the annotations")
    seen = ~np.isnan(detected[:, 0])
    ax2.plot(frames[seen], p_det[seen], ".", color="tab:orange", ms=4,
             label="measured by the detections (frames with one)")
    ax2.set_ylabel("P(position-only model)")
    ax2.set_xlabel("frame")
    ax2.set_ylim(-0.02, 1.02)
    # below the plot: inside, it covered the fall of P as the person walks off
    ax2.legend(loc="upper center", bbox_to_anchor=(0.5, -0.22), ncols=3, fontsize=8)
    fig.tight_layout()
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=100)
    print(f"wrote {OUT}")
    print(f"  annotations: P(position-only) standing {p_ann[still].mean():.2f}, walking "
          f"{p_ann[walking].mean():.2f}")
    print(f"  detections: the person is detected in {seen[still].mean():.0%} of the standing "
          f"frames and {seen[walking].mean():.0%} of the walking ones; where detected, "
          f"P(position-only) standing {p_det[still & seen].mean():.2f}, walking "
          f"{p_det[walking & seen].mean():.2f}")


if __name__ == "__main__":
    main()
