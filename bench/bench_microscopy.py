"""Microscopy: spots and the point tracker beside trackpy, on trackpy's bulk-water clip (50
PNG frames, 640x424, about 520 particles a frame), in one run.

    python bench/bench_microscopy.py [--write docs/benchmarks.md]

Then linking alone on a simulated field of 2,000 and 8,000 diffusing particles a frame:
vistrack's point tracker (`gnn`, `jpda`, `pda`) beside trackpy's `link`, time and peak memory.

vistrack: `frontends.spots.locate` (Crocker-Grier with trackpy's conventions) and
`PointTracker("gnn")` with the constant-position (drifting points) model, and the same with
`PointTracker("jpda")` (every particle in a track's gate weighed by its joint association
probability, for linking in clutter, which trackpy does not do). trackpy: `locate`
and `link` (search range 5 px, memory 3 frames). Frames per second of locating and linking
together, the median of three runs after a warm-up; the agreement of the two.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
import tracemalloc
import warnings
from pathlib import Path

import cv2
import numpy as np
from scipy.spatial import cKDTree

from vistrack.frontends.spots import locate
from vistrack.models import ConstantPosition, Position
from vistrack.tracking import PointTracker
from vistrack.types import Detections

from _markdown import publish  # noqa: E402  (bench/ is on the path of its scripts)

FRAMES = Path(__file__).resolve().parents[2] / "shared" / "data" / "trackpy-bulk-water" / "frames"


def run_vistrack(frames, association="gnn"):
    tr = PointTracker(association, motion=ConstantPosition(dim=2, q=24.0),
                      measurement=Position(dim=2, r=0.01), frame_rate=24.0, confirm_hits=1,
                      max_lost=3.5 / 24, p_gate=0.999)
    out = []
    for k, im in enumerate(frames):
        r = tr.step(k + 1, locate(im, 11, invert=True, minmass=20).detections())
        out.append((r.ids, r.points))
    return out


def field(n, frames=10, seed=0):
    """``n`` particles diffusing in a square at the clip's density (about 1.9 a thousand
    square pixels), 0.5 px a frame along each axis, seen at 0.1 px: one ``(n, 2)`` array of
    positions a frame."""
    rng = np.random.default_rng(seed)
    side = np.sqrt(n / 1.9e-3)
    p = rng.uniform(0, side, (n, 2))
    out = []
    for _ in range(frames):
        p = p + rng.normal(0, 0.5, p.shape)
        out.append(p + rng.normal(0, 0.1, p.shape))
    return out


def link_vistrack(points, association):
    """:func:`run_vistrack`'s tracker on given positions (linking alone)."""
    tr = PointTracker(association, motion=ConstantPosition(dim=2, q=24.0),
                      measurement=Position(dim=2, r=0.01), frame_rate=24.0, confirm_hits=1,
                      max_lost=3.5 / 24, p_gate=0.999)
    return [tr.step(k + 1, Detections(points=p)) for k, p in enumerate(points)]


def link_trackpy(points):
    import pandas as pd
    import trackpy as tp

    tp.quiet()
    df = pd.DataFrame({"x": np.concatenate([p[:, 0] for p in points]),
                       "y": np.concatenate([p[:, 1] for p in points]),
                       "frame": np.repeat(np.arange(len(points)), [len(p) for p in points])})
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return tp.link(df, 5, memory=3)


def peak_memory(fn):
    """``fn()``'s result, its time and the peak of the memory it allocated (tracemalloc,
    which numpy's arrays report to)."""
    tracemalloc.start()
    t = time.perf_counter()
    res = fn()
    sec = time.perf_counter() - t
    peak = tracemalloc.get_traced_memory()[1]
    tracemalloc.stop()
    return res, sec, peak


def field_rows(sizes=(2_000, 8_000)):
    """Linking alone on :func:`field`'s particles: each tracker's median time a frame over
    three runs (after a warm-up), and its peak memory, in one table."""
    rows = []
    runs = [(f'vistrack `PointTracker("{a}")`', lambda pts, a=a: link_vistrack(pts, a))
            for a in ("gnn", "jpda", "pda")]
    runs.append(("trackpy `link` (search 5 px, memory 3)", link_trackpy))
    for n in sizes:
        pts = field(n)
        for name, fn in runs:
            fn(pts[:2])
            got = [peak_memory(lambda: fn(pts)) for _ in range(3)]
            sec = statistics.median(g[1] for g in got)
            rows.append(f"| {n:,} | {name} | {sec / len(pts) * 1e3:.1f} | "
                        f"{max(g[2] for g in got) / 1e6:.0f} |")
    return rows


def run_trackpy(frames):
    import trackpy as tp

    tp.quiet()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        f = tp.batch(frames, 11, invert=True, minmass=20)
        return tp.link(f, 5, memory=3)


def trajectories(out):
    """The number of identities in a run's ``(ids, points)`` frames, and of those seen in 25
    frames or more."""
    _, frames = np.unique(np.concatenate([ids for ids, _ in out]), return_counts=True)
    return len(frames), int((frames >= 25).sum())


def timed(fn, frames):
    fn(frames[:3])
    secs = []
    res = None
    for _ in range(3):
        t = time.perf_counter()
        res = fn(frames)
        secs.append(time.perf_counter() - t)
    return res, len(frames) / statistics.median(secs)


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    files = sorted(FRAMES.glob("*.png"))
    if not files:
        sys.exit(f"{FRAMES} not found: the shared data must be beside this checkout")
    frames = [cv2.imread(str(f), cv2.IMREAD_GRAYSCALE) for f in files]
    ours, fps_ours = timed(run_vistrack, frames)
    jpda, fps_jpda = timed(lambda fs: run_vistrack(fs, "jpda"), frames)
    links, fps_tp = timed(run_trackpy, frames)
    near, ids_of = [], {}
    for k, (ids, pts) in enumerate(ours):
        theirs = links[links.frame == k]
        d, j = cKDTree(pts).query(theirs[["x", "y"]].values)
        near.append(d < 0.5)
        for pid, i, ok in zip(theirs.particle.values, ids[j], d < 0.5):
            if ok:
                ids_of.setdefault(pid, set()).add(int(i))
    near = np.concatenate(near)
    n_ours, long_ours = trajectories(ours)
    long_tp = int((links.groupby("particle").size() >= 25).sum())
    env = (f"Python {platform.python_version()}, numpy {np.__version__}, trackpy "
           f"{__import__('trackpy').__version__}, {time.strftime('%Y-%m-%d')}")
    row_ours = (f'| vistrack: spots + `PointTracker("gnn")`, constant position | {fps_ours:.0f} '
                f"| {n_ours} | {long_ours} |")
    n_jpda, long_jpda = trajectories(jpda)
    row_jpda = (f'| vistrack: spots + `PointTracker("jpda")`, constant position | '
                f"{fps_jpda:.0f} | {n_jpda} | {long_jpda} |")
    row_tp = (f"| trackpy: `locate` + `link` (search 5 px, memory 3) | {fps_tp:.0f} "
              f"| {links.particle.nunique()} | {long_tp} |")
    n_tp = links.particle.nunique()
    many = "\n".join(field_rows())
    len_note = (f"vistrack's {n_ours} trajectories against trackpy's {n_tp}, "
                f"{long_ours} against {long_tp} of 25 frames or more")
    section = f"""## Microscopy

Measured with `python bench/bench_microscopy.py` ({env}): trackpy's bulk-water clip, 50
frames, about 520 particles a frame; locating and linking together.

| | frames/s | trajectories | of 25 frames or more |
|---|---:|---:|---:|
{row_ours}
{row_jpda}
{row_tp}

vistrack is {fps_ours / fps_tp:.1f} times as fast with `gnn`, {fps_jpda / fps_tp:.1f} times with
`jpda` (its probabilistic associations over the gated pairs only, a k-d tree finding them, as
`gnn`'s: over every pair of track and particle, 270,000 a frame, it ran at 13 frames/s of
tracking alone, now about 100). `spots.locate` finds exactly trackpy's
particles at trackpy's positions (a test checks it to 1e-9 px); {100 * near.mean():.1f} % of
trackpy's linked positions have a vistrack track within 0.5 px (the tracks report filtered
estimates), and {100 * np.mean([len(v) == 1 for v in ids_of.values()]):.1f} % of trackpy's
trajectories are one vistrack identity throughout. Both keep a lost particle for 3 frames
(vistrack's track predicting, its covariance growing, and taking it back within its gate;
trackpy's memory):
{len_note}.

Linking alone, on many particles: a simulated field at the clip's density, diffusing 0.5 px
a frame, 10 frames, the positions given (the same tracker settings; trackpy's `link` on a
table of them). Milliseconds a frame (median of three runs) and the peak memory the run
allocated (Python's `tracemalloc`, which numpy's arrays report to):

| particles a frame | tracker | ms a frame | peak memory, MB |
|---:|---|---:|---:|
{many}
"""
    publish(section, args.write)


if __name__ == "__main__":
    main()
