"""The seed's robust online appearance model (WSL; Jepson, Fleet and El-Maraghi, seed 000) on a
real occlusion, and its online EM on the seed's 1-D signal.

    python examples/wsl_pets09.py    # writes examples/figures/wsl_pets09.png, wsl_crossing.png
                                     # and wsl_online_em.png

**wsl_pets09.png** is the seed's Figure 3 on PETS09-S2L1 (``opencv-vtest/vtest.avi``, MOT15
ground truth): person 12, standing, is tracked from frame 150 by :class:`WSLTracker`, and
person 13 walks in front of her (frames 157 to 164 cover up to 84 % of her box). Each row
shows the tracked region, the stable component's mixing probability ``m_s``, its mean
``μ_s`` and the ownership ``o_s`` of the current view; the red outline in the last column is
where the annotated box of person 13 falls in the view. The bottom panel follows, over time,
the mean ownership inside and outside that region and the overlap of the tracked box with
the annotation.

**wsl_crossing.png** is the same layout on OTB Crossing, which has no occlusion: around
frame 50 the background behind the pedestrian's upper body turns from shaded road to the
sunlit stripes of the crossing, and the stable component gives up its ownership of those
pixels (the mean o_s falls from about 0.8 to 0.57) while it keeps the person's.

**wsl_online_em.png** is the seed's Figure 2: one "pixel" whose true value drifts, observed
with noise that is Gaussian with probability 0.9 and uniform with probability 0.1, except for
15 frames at 300 that are pure outliers; the stable mean follows the truth and holds through
the outliers, while the lost component's mixing probability rises.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from matplotlib.colors import ListedColormap
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from vistrack.evaluation import box_iou_xywh
from vistrack.evaluation.single import read_boxes
from vistrack.io import VideoReader, read_mot
from vistrack.tracking.appearance import WSLModel, WSLTracker

DATA = Path(__file__).resolve().parents[2] / "shared" / "data"
VIDEO = DATA / "opencv-vtest" / "vtest.avi"
GT = DATA / "mot15" / "PETS09-S2L1" / "gt" / "gt.txt"
FIGS = Path(__file__).resolve().parent / "figures"
TARGET, OCCLUDER, FIRST, LAST = 12, 13, 150, 185
ROWS = (155, 158, 160, 162, 166)
CROSSING = DATA / "otb-crossing" / "Crossing"
CROSSING_ROWS = (20, 50, 62, 70, 90)


def occluder_mask(tracker: WSLTracker, box: np.ndarray) -> np.ndarray:
    """The view's pixels whose image position falls inside ``box`` (x, y, w, h)."""
    step = tracker.w / tracker.vw
    x = tracker.centre[0] + step * (np.arange(tracker.vw) - (tracker.vw - 1) / 2)
    y = tracker.centre[1] + step * (np.arange(tracker.vh) - (tracker.vh - 1) / 2)
    inx = (x >= box[0]) & (x <= box[0] + box[2])
    iny = (y >= box[1]) & (y <= box[1] + box[3])
    return iny[:, None] & inx[None, :]


def track_occlusion():
    gt = read_mot(GT)
    boxes = {i: {int(f): b for f, b in zip(gt[gt.ids == i].frames, gt[gt.ids == i].boxes)}
             for i in (TARGET, OCCLUDER)}
    tracker, log, rows = WSLTracker(), [], {}
    for frame in VideoReader(VIDEO, start=FIRST, stop=LAST):
        f, truth = frame.index, boxes[TARGET][frame.index]
        if f == FIRST:
            tracker.init(frame.image, truth)
            continue
        box = tracker.update(frame.image)
        o_s = tracker.ownership[0]
        occ = boxes[OCCLUDER].get(f)
        mask = occluder_mask(tracker, occ) if occ is not None else np.zeros_like(o_s, bool)
        log.append((f, float(box_iou_xywh(box[None], truth[None])[0, 0]),
                    float(o_s[mask].mean()) if mask.any() else np.nan,
                    float(o_s[~mask].mean()), mask.mean()))
        if f in ROWS:
            pad = 1.6 * max(box[2], box[3]) / 2
            c = box[:2] + box[2:] / 2
            x0, y0 = int(max(c[0] - pad, 0)), int(max(c[1] - pad, 0))
            crop = frame.image[y0:int(c[1] + pad), x0:int(c[0] + pad), ::-1]
            rows[f] = (crop, box - [x0, y0, 0, 0], tracker.model.m[0].copy(),
                       tracker.model.mu_s.copy(), o_s.copy(), mask)
    return np.array(log), rows


def rows_figure(rows, title):
    """The seed's Figure 3 layout: a row per frame (region, m_s, μ_s, o_s) and a panel below;
    returns the figure and the panel's axes."""
    show = sorted(rows)
    fig = Figure(figsize=(7.5, 13))
    grid = fig.add_gridspec(len(show) + 1, 4, height_ratios=[1] * len(show) + [1.1])
    titles = ("tracked region", "$m_s$", r"$\mu_s$", "$o_s$")
    for r, f in enumerate(show):
        crop, box, m_s, mu_s, o_s, mask = rows[f]
        for c, (img, kw) in enumerate(((crop, {}), (m_s, dict(cmap="gray", vmin=0, vmax=1)),
                                       (mu_s, dict(cmap="gray", vmin=0, vmax=1)),
                                       (o_s, dict(cmap="gray", vmin=0, vmax=1)))):
            ax = fig.add_subplot(grid[r, c])
            ax.imshow(img, interpolation="nearest", **kw)
            ax.set_xticks([])
            ax.set_yticks([])
            if r == 0:
                ax.set_title(titles[c])
            if c == 0:
                ax.add_patch(Rectangle(box[:2], box[2], box[3], fill=False, ec="lime"))
                ax.set_ylabel(f"frame {f}")
            if c == 3 and mask is not None and mask.any():
                # a tint rather than an outline: the covered part reaches the panel's edges,
                # where an outline is left open (a stray line)
                ax.imshow(np.where(mask, 1.0, np.nan), cmap=ListedColormap(["red"]),
                          alpha=0.35, interpolation="nearest")
    fig.suptitle(title, fontsize=10)
    return fig, fig.add_subplot(grid[len(show), :])


def occlusion_figure(log, rows):
    fig, ax = rows_figure(rows, f"WSL appearance model, PETS09-S2L1 person {TARGET} occluded "
                          f"by person {OCCLUDER}\n(seed 000, Fig. 3; red: where person "
                          f"{OCCLUDER} covers the view)")
    f = log[:, 0]
    ax.plot(f, log[:, 2], "r.-", label="mean $o_s$ where person 13 covers the view")
    ax.plot(f, log[:, 3], "k.-", label="mean $o_s$ elsewhere in the view")
    ax.plot(f, log[:, 1], "g--", label="IoU of the tracked box with the annotation")
    ax.set_xlabel("frame")
    ax.set_ylabel("mean, or IoU")
    ax.set_ylim(0, 1.02)
    # below the panel: inside, it hid the lowest o_s, the occlusion the figure is about
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.3), ncols=2)
    fig.tight_layout()
    return fig


def track_crossing():
    """WSL on OTB Crossing from its first annotated box: per frame the IoU with the
    annotation and the mean o_s and m_s; the rows of CROSSING_ROWS."""
    import cv2

    files = sorted((CROSSING / "img").glob("*.jpg"))
    gt = read_boxes(CROSSING / "groundtruth_rect.txt")
    tracker, log, rows = WSLTracker(), [], {}
    for k, path in enumerate(files):
        image = cv2.imread(str(path))
        if k == 0:
            tracker.init(image, gt[0])
            continue
        box = tracker.update(image)
        log.append((k + 1, float(box_iou_xywh(box[None], gt[k][None])[0, 0]),
                    float(tracker.ownership[0].mean()), float(tracker.model.m[0].mean())))
        if k + 1 in CROSSING_ROWS:
            pad = 1.6 * max(box[2], box[3]) / 2
            c = box[:2] + box[2:] / 2
            x0, y0 = int(max(c[0] - pad, 0)), int(max(c[1] - pad, 0))
            rows[k + 1] = (image[y0:int(c[1] + pad), x0:int(c[0] + pad), ::-1],
                           box - [x0, y0, 0, 0], tracker.model.m[0].copy(),
                           tracker.model.mu_s.copy(), tracker.ownership[0].copy(), None)
    return np.array(log), rows


def crossing_figure(log, rows):
    fig, ax = rows_figure(rows, "WSL appearance model, OTB Crossing: the background behind\n"
                          "turns from shade to sunlit stripes (no occlusion)")
    ax.plot(log[:, 0], log[:, 2], "k.-", ms=3, label="mean $o_s$")
    ax.plot(log[:, 0], log[:, 3], "b.-", ms=3, label="mean $m_s$")
    ax.plot(log[:, 0], log[:, 1], "g--", label="IoU of the tracked box with the annotation")
    ax.set_xlabel("frame")
    ax.set_ylabel("mean, or IoU")
    ax.set_ylim(0, 1.02)
    ax.legend(fontsize=8, loc="upper center", bbox_to_anchor=(0.5, -0.3), ncols=3)
    fig.tight_layout()
    return fig


def online_em_signal(seed: int = 0, n: int = 600):
    """The seed's Figure 2 signal: truth, observations, and which frames are outliers."""
    rng = np.random.default_rng(seed)
    t = np.arange(n)
    truth = 0.5 + 0.15 * np.sin(2 * np.pi * t / 400)
    outlier = rng.random(n) < 0.1
    outlier[300:315] = True
    d = np.where(outlier, rng.random(n), truth + rng.normal(0, 0.02, n))
    return truth, d, outlier


def online_em_figure():
    truth, d, outlier = online_em_signal()
    model = WSLModel((1,))
    model.init(d[:1])
    mu, m = [model.mu_s[0]], [model.m[:, 0].copy()]
    for x in d[1:]:
        model.update(x[None])
        mu.append(model.mu_s[0])
        m.append(model.m[:, 0].copy())
    mu, m = np.array(mu), np.array(m)
    fig = Figure(figsize=(8, 5))
    ax1, ax2 = fig.subplots(2, 1, sharex=True)
    ax1.plot(d, "-", color="tab:red", lw=0.5, label="data")
    ax1.plot(truth, "b--", label="true state")
    ax1.plot(mu, "k-", lw=2, label=r"stable mean $\mu_s$")
    ax1.legend(fontsize=8, loc="upper right")
    ax1.set_title("Online EM of the WSL mixture on one pixel (seed 000, Fig. 2)")
    ax2.plot(m[:, 0], "k-", label="S (stable)")
    ax2.plot(m[:, 1], "r--", label="W (wandering)")
    ax2.plot(m[:, 2], "-", color="tab:green", label="L (lost: outliers)")
    ax2.set_ylabel("mixing probability")
    ax1.set_ylabel("pixel value")
    ax2.set_xlabel("frame")
    ax2.legend(fontsize=8)
    fig.tight_layout()
    err = np.abs(mu - truth)
    return fig, float(np.median(err[50:])), float(err[300:315].max()), m


def main():
    if not VIDEO.exists() or not GT.exists():
        sys.exit(f"{VIDEO} or {GT} not found: the shared data must be beside this checkout")
    FIGS.mkdir(parents=True, exist_ok=True)
    log, rows = track_occlusion()
    occlusion_figure(log, rows).savefig(FIGS / "wsl_pets09.png", dpi=90)
    print(f"wrote {FIGS / 'wsl_pets09.png'}")
    covered = log[:, 4] > 0.2
    print(f"  IoU with the annotation: min {log[:, 1].min():.2f}, mean {log[:, 1].mean():.2f} "
          f"over frames {FIRST + 1}-{LAST}")
    print(f"  frames where person 13 covers > 20 % of the view: {covered.sum()}; mean o_s there "
          f"{np.nanmean(log[covered, 2]):.2f} inside the covered part, "
          f"{log[covered, 3].mean():.2f} outside it")
    if CROSSING.exists():
        clog, crows = track_crossing()
        crossing_figure(clog, crows).savefig(FIGS / "wsl_crossing.png", dpi=90)
        print(f"wrote {FIGS / 'wsl_crossing.png'}")
        print(f"  Crossing: success (IoU > 0.5) {np.mean(clog[:, 1] > 0.5):.0%}; mean o_s "
              f"{clog[:, 2].min():.2f} at its lowest (frame {int(clog[np.argmin(clog[:, 2]), 0])}"
              f"), {np.median(clog[:, 2]):.2f} median")
    fig, med, burst, m = online_em_figure()
    fig.savefig(FIGS / "wsl_online_em.png", dpi=90)
    print(f"wrote {FIGS / 'wsl_online_em.png'}")
    print(f"  |mu_s - truth|: median {med:.3f} after frame 50, at most {burst:.3f} during the "
          f"outlier burst; m_l {m[299, 2]:.2f} before it, {m[314, 2]:.2f} at its end")


if __name__ == "__main__":
    main()
