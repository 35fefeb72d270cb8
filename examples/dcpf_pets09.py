"""The seed's detector-confidence particle filter (Breitenstein et al.; seed 004) on
PETS09-S2L1 from pixels, and its ablation table: Det, Det+DetConf, Det+Class, all three.

    python examples/dcpf_pets09.py    # writes examples/figures/dcpf_pets09.png, prints the table

The video is ``opencv-vtest/vtest.avi`` (= MOT15's PETS09-S2L1, 795 frames), scored with
CLEAR MOT against MOT15's ground truth. OpenCV's HOG people detector is evaluated densely on
every frame (:class:`vistrack.frontends.detectors.HOGConfidence`, five person heights from 55
to 145 pixels): its SVM margins are the continuous confidence ``d_c``, and its peaks above a
margin of 0.5 the discrete detections. Computing the maps takes about 90 s of one core: the
first run computes them on two threads while the trackers run, and keeps them in
``out/cache/`` for the next run. The four configurations switch terms of the
observation model off (``gamma=0``: no detector confidence, ``eta=0``: no classifier); all
else is the same. Each configuration runs with five seeds of the particle filters' random
numbers; the table gives means and standard deviations.
"""

from __future__ import annotations

import sys
import threading
from collections import deque
from collections.abc import Iterator
from concurrent.futures import ThreadPoolExecutor
from itertools import islice
from pathlib import Path

import numpy as np
from matplotlib import patheffects
from matplotlib.figure import Figure
from matplotlib.patches import Rectangle

from vistrack.evaluation.mot import evaluate_mot
from vistrack.frontends.detectors import ConfidenceMap, HOGConfidence
from vistrack.io import VideoReader, read_mot
from vistrack.io.motchallenge import MOTTable
from vistrack.tracking.dcpf import DetectorConfidencePF

ROOT = Path(__file__).resolve().parents[1]
DATA = ROOT.parent / "shared" / "data"
VIDEO = DATA / "opencv-vtest" / "vtest.avi"
GT = DATA / "mot15" / "PETS09-S2L1" / "gt" / "gt.txt"
CACHE = ROOT / "out" / "cache" / "pets09_hog_confidence.npz"
OUT = ROOT / "examples" / "figures" / "dcpf_pets09.png"
DET_THRESHOLD = 0.5
CONFIGS = {"1: Det+DetConf+Class": {}, "2: Det+DetConf": dict(eta=0.0),
           "3: Det+Class": dict(gamma=0.0), "4: Det": dict(gamma=0.0, eta=0.0)}
SEED = {"1: Det+DetConf+Class": (70.0, 72.9, 26.8, 0.3, 0),
        "2: Det+DetConf": (64.0, 54.5, 28.2, 17.2, 5),
        "3: Det+Class": (65.0, 55.3, 31.3, 13.4, 0), "4: Det": (67.0, 40.9, 30.7, 28.0, 10)}
SHOW = 150
SEEDS = 5


def confidence_maps(frames: list[np.ndarray]) -> Iterator[ConfidenceMap]:
    """The HOG confidence map of every frame in turn, from the cache when it matches.
    Otherwise they are computed a few frames ahead on two threads (OpenCV's HOG runs without
    Python's lock), so that the trackers, which take each map as it comes, run meanwhile; the
    cache is written once all are done. Every map is as stored (float16), so that every run
    sees the same."""
    heights = HOGConfidence().heights
    if CACHE.exists():
        z = np.load(CACHE)
        # the cache matches if its levels map to the image as this version's do (the first
        # frame's map, made to compare; before 2026-12-01 the grids were placed by the
        # nominal resize factor, one stride for both axes)
        first = HOGConfidence(heights)(frames[0])
        if (np.array_equal(z["heights"], heights) and z["strides"].shape == first.strides.shape
                and np.array_equal(z["strides"], first.strides)
                and np.array_equal(z["origins"], first.origins)):
            stored = [z[f"level{k}"] for k in range(len(heights))]  # each read once
            origins, strides = z["origins"], z["strides"]
            for t in range(len(stored[0])):
                yield ConfidenceMap(heights, [level[t].astype(float) for level in stored],
                                    origins, strides)
            return
    local = threading.local()

    def hog(image: np.ndarray) -> ConfidenceMap:
        if not hasattr(local, "hog"):  # one detector a thread
            local.hog = HOGConfidence(heights)
        return local.hog(image)

    levels: list[list[np.ndarray]] = [[] for _ in heights]
    with ThreadPoolExecutor(2) as pool:
        images = iter(frames)
        pending = deque(pool.submit(hog, image) for image in islice(images, 8))
        while pending:
            m = pending.popleft().result()
            for image in islice(images, 1):
                pending.append(pool.submit(hog, image))
            stored = [s.astype(np.float16) for s in m.scores]
            for k, s in enumerate(stored):
                levels[k].append(s)
            if len(levels[0]) % 100 == 0:
                print(f"  HOG confidence: frame {len(levels[0])}", file=sys.stderr)
            yield ConfidenceMap(heights, [s.astype(float) for s in stored],
                                np.asarray(m.origins), np.asarray(m.strides))
    CACHE.parent.mkdir(parents=True, exist_ok=True)
    np.savez(CACHE, heights=heights, origins=m.origins, strides=m.strides,
             **{f"level{k}": np.stack(level) for k, level in enumerate(levels)})


def main():
    if not VIDEO.exists() or not GT.exists():
        sys.exit(f"{VIDEO} or {GT} not found: the shared data must be beside this checkout")
    gt = read_mot(GT)
    frames = [f.image for f in VideoReader(VIDEO)]
    # every configuration and seed a frame at a time, each map as soon as it is ready
    trackers = {(name, seed): DetectorConfidencePF(rng=seed, frame_rate=7, **cfg)  # 7 frames/s
                for name, cfg in CONFIGS.items() for seed in range(SEEDS)}
    rows: dict[tuple[str, int], list] = {key: [] for key in trackers}
    results, shown = {}, None  # the trackers at frame SHOW, and its map, for the figure
    for t, (image, cmap) in enumerate(zip(frames, confidence_maps(frames), strict=True), 1):
        if t == SHOW:
            shown = cmap
        for (name, seed), tracker in trackers.items():
            out = tracker.update(image, cmap.detections(DET_THRESHOLD), cmap)
            rows[name, seed] += [(t, i, *b) for i, b in zip(out.ids, out.xywh)]
            if t == SHOW and seed == 0:
                results[name] = (tracker.particles[..., :2].copy(), out)
    table = {}
    for name in CONFIGS:
        clear = [evaluate_mot(gt, MOTTable.from_rows(rows[name, seed]), len(frames))
                 for seed in range(SEEDS)]
        table[name] = np.array([[100 * c.MOTP, 100 * c.MOTA, 100 * c.FN / c.gt_dets,
                                 100 * c.FP / c.gt_dets, c.IDSW, 100 * c.HOTA, 100 * c.IDF1]
                                for c in clear])
        print(f"  {name}: MOTA " + ", ".join(f"{v:.1f}" for v in table[name][:, 1]),
              file=sys.stderr)
    lines = ["| observation model terms | MOTP | MOTA | FN | FP | ID sw. | HOTA | IDF1 | "
             "seed: MOTP | MOTA | FN | FP | ID sw. |",
             "|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"]
    for name, t in table.items():
        m, sd, s = t.mean(0), t.std(0), SEED[name]
        lines.append(f"| {name} | {m[0]:.1f} % | {m[1]:.1f} ± {sd[1]:.1f} % | {m[2]:.1f} % | "
                     f"{m[3]:.1f} % | {m[4]:.0f} ± {sd[4]:.0f} | {m[5]:.1f} | {m[6]:.1f} | "
                     f"{s[0]:.1f} % | {s[1]:.1f} % | {s[2]:.1f} % | {s[3]:.1f} % | {s[4]} |")
    print(f"mean ± standard deviation over {SEEDS} runs (particle-filter seeds 0-{SEEDS - 1})")
    print("\n".join(lines))

    fig = Figure(figsize=(11, 4.6), layout="constrained")
    ax1, ax2 = fig.subplots(1, 2, width_ratios=[1.25, 1])
    ax1.imshow(frames[SHOW - 1][:, :, ::-1])
    particles, out = results["1: Det+DetConf+Class"]
    cmap = shown
    k = int(np.argmin(np.abs(cmap.heights - 90)))
    ny, nx = cmap.scores[k].shape
    x0, y0 = cmap.origins[k]
    sx, sy = cmap.strides[k]  # the cells' spacing along x and y
    conf = np.ma.masked_less(1 / (1 + np.exp(-cmap.scores[k])), 0.3)
    ax1.imshow(conf, cmap="autumn_r", alpha=0.5, vmin=0.3, vmax=1,
               extent=(x0 - sx / 2, x0 + sx * (nx - 0.5), y0 + sy * (ny - 0.5), y0 - sy / 2))
    for p in particles:
        ax1.plot(p[:, 0], p[:, 1], ".", ms=1.5)
    for i, b in zip(out.ids, out.xywh):
        ax1.add_patch(Rectangle(b[:2], b[2], b[3], fill=False, ec="white", lw=1.2))
        ax1.text(b[0], b[1] - 3, str(i), color="white", fontsize=8, fontweight="bold",
                 path_effects=[patheffects.withStroke(linewidth=2, foreground="black")])
    ax1.set_title(f"frame {SHOW}: particles, boxes, and the HOG confidence above 0.3 "
                  f"({cmap.heights[k]:.0f} px level)", fontsize=9)
    ax1.set_xticks([])
    ax1.set_yticks([])
    names = list(results)
    x = np.arange(len(names))
    ours = np.array([table[n].mean(0)[[1, 2, 3]] for n in names])
    seed = np.array([SEED[n][1:4] for n in names])
    for j, (label, col) in enumerate((("MOTA", "tab:green"), ("FN", "tab:orange"),
                                      ("FP", "tab:red"))):
        ax2.bar(x + (j - 1) * 0.27, ours[:, j], 0.25, color=col, label=f"{label} (vistrack)")
        ax2.plot(x + (j - 1) * 0.27, seed[:, j], "k_", ms=12, mew=2,
                 label="the seed's" if j == 0 else None)
    ax2.set_xticks(x, [n.split(": ")[1] for n in names], fontsize=8)
    ax2.set_ylabel("%")
    ax2.legend(fontsize=7)
    ax2.set_title(f"ablation on PETS09-S2L1 (bars: vistrack, mean of {SEEDS} runs; ticks: "
                  "the seed)", fontsize=9)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(OUT, dpi=90)
    print(f"wrote {OUT}")


if __name__ == "__main__":
    main()
