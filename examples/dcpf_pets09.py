"""The seed's detector-confidence particle filter (Breitenstein et al.; seed 004) on
PETS09-S2L1 from pixels, and its ablation table: Det, Det+DetConf, Det+Class, all three.

    python examples/dcpf_pets09.py    # writes examples/figures/dcpf_pets09.png, prints the table

The video is ``opencv-vtest/vtest.avi`` (= MOT15's PETS09-S2L1, 795 frames), scored with
CLEAR MOT against MOT15's ground truth. OpenCV's HOG people detector is evaluated densely on
every frame (:class:`vistrack.frontends.detectors.HOGConfidence`, five person heights from 55
to 145 pixels): its SVM margins are the continuous confidence ``d_c``, and its peaks above a
margin of 0.5 the discrete detections. The maps take about 3 minutes to compute; they are
kept in ``out/cache/`` for the next run. The four configurations switch terms of the
observation model off (``gamma=0``: no detector confidence, ``eta=0``: no classifier); all
else is the same. Each configuration runs with five seeds of the particle filters' random
numbers; the table gives means and standard deviations.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
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


def confidence_maps() -> list[ConfidenceMap]:
    """The HOG confidence map of every frame, from the cache when it matches."""
    hog = HOGConfidence()
    if CACHE.exists():
        z = np.load(CACHE)
        if np.array_equal(z["heights"], hog.heights):
            return [ConfidenceMap(z["heights"], [z[f"level{k}"][t].astype(float)
                                                 for k in range(len(z["heights"]))],
                                  z["origins"], z["strides"]) for t in range(len(z["level0"]))]
    maps = []
    for frame in VideoReader(VIDEO, prefetch=4):
        maps.append(hog(frame.image))
        if frame.index % 100 == 0:
            print(f"  HOG confidence: frame {frame.index}", file=sys.stderr)
    CACHE.parent.mkdir(parents=True, exist_ok=True)
    np.savez(CACHE, heights=hog.heights, origins=maps[0].origins, strides=maps[0].strides,
             **{f"level{k}": np.stack([m.scores[k] for m in maps]).astype(np.float16)
                for k in range(len(hog.heights))})
    return confidence_maps()        # as stored (float16), so that every run sees the same


def run(frames, maps, gt, seed=0, **config):
    tracker = DetectorConfidencePF(rng=seed, frame_rate=7, **config)  # PETS09: 7 frames/s
    rows, snapshot = [], None
    for t, (image, cmap) in enumerate(zip(frames, maps), 1):
        out = tracker.update(image, cmap.detections(DET_THRESHOLD), cmap)
        rows += [(t, i, *b) for i, b in zip(out.ids, out.xywh)]
        if t == SHOW:
            snapshot = (tracker.particles[..., :2].copy(), out)
    return evaluate_mot(gt, MOTTable.from_rows(rows), len(frames)), snapshot


def main():
    if not VIDEO.exists() or not GT.exists():
        sys.exit(f"{VIDEO} or {GT} not found: the shared data must be beside this checkout")
    gt = read_mot(GT)
    frames = [f.image for f in VideoReader(VIDEO)]
    maps = confidence_maps()
    results, table = {}, {}
    for name, cfg in CONFIGS.items():
        runs = [run(frames, maps, gt, seed=seed, **cfg) for seed in range(SEEDS)]
        results[name] = runs[0]
        table[name] = np.array([[100 * c.MOTP, 100 * c.MOTA, 100 * c.FN / c.gt_dets,
                                 100 * c.FP / c.gt_dets, c.IDSW, 100 * c.HOTA, 100 * c.IDF1]
                                for c, _ in runs])
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
    particles, out = results["1: Det+DetConf+Class"][1]
    cmap = maps[SHOW - 1]
    k = int(np.argmin(np.abs(cmap.heights - 90)))
    ny, nx = cmap.scores[k].shape
    x0, y0 = cmap.origins[k]
    st = cmap.strides[k]
    conf = np.ma.masked_less(1 / (1 + np.exp(-cmap.scores[k])), 0.3)
    ax1.imshow(conf, cmap="autumn_r", alpha=0.5, vmin=0.3, vmax=1,
               extent=(x0 - st / 2, x0 + st * (nx - 0.5), y0 + st * (ny - 0.5), y0 - st / 2))
    for p in particles:
        ax1.plot(p[:, 0], p[:, 1], ".", ms=1.5)
    for i, b in zip(out.ids, out.xywh):
        ax1.add_patch(Rectangle(b[:2], b[2], b[3], fill=False, ec="white", lw=1))
        ax1.text(b[0], b[1] - 3, str(i), color="white", fontsize=7)
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
