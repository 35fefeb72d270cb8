"""Snakes: vistrack's B-spline snake (radial edge search, Kalman update over the control
points) beside scikit-image's `active_contour`, each following the same moving, turning
ellipse from the last frame's contour, 100 contour points, in one run.

    python bench/bench_snake.py [--write docs/benchmarks.md]

Milliseconds per frame (median over the frames after the first) and the contour's mean
distance to the true boundary.
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.test_snake import distance_to_ellipse, ellipse_frame  # noqa: E402
from vistrack.tracking.snake import Snake  # noqa: E402

from _markdown import publish  # noqa: E402  (bench/ is on the path of its scripts)


def scene(T=30):
    rng = np.random.default_rng(1)
    geos = [(100 + 2 * k, 120 + np.sin(k / 6) * 10, 40 + k * 0.3, 25, 10 + 2 * k)
            for k in range(T)]
    return [ellipse_frame(*g, rng=rng) for g in geos], geos


def run_vistrack(frames, geos):
    s = Snake(n_control=20, n_samples=100)
    s.init_circle((100, 120), 30)
    sec, err = [], []
    for im, g in zip(frames, geos):
        t = time.perf_counter()
        pts = s.track(im)
        sec.append(time.perf_counter() - t)
        err.append(distance_to_ellipse(pts, *g).mean())
    return sec, err


def run_skimage(frames, geos):
    from skimage.filters import gaussian
    from skimage.segmentation import active_contour

    a = np.linspace(0, 2 * np.pi, 100, endpoint=False)
    snake = np.c_[120 + 30 * np.sin(a), 100 + 30 * np.cos(a)]  # (row, col)
    sec, err = [], []
    for im, g in zip(frames, geos):
        t = time.perf_counter()
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            snake = active_contour(gaussian(im, 2, preserve_range=False), snake, alpha=0.01,
                                   beta=0.1, gamma=0.01, w_edge=1)  # its defaults
        sec.append(time.perf_counter() - t)
        err.append(distance_to_ellipse(snake[:, ::-1], *g).mean())
    return sec, err


def main():
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    frames, geos = scene()
    run_vistrack(frames[:3], geos[:3])  # compiled code loaded
    rows = []
    for name, fn in (("vistrack `Snake` (B-spline, affine shape space, radial search, Kalman)",
                      run_vistrack),
                     ("scikit-image `active_contour` (its defaults: up to 2,500 iterations)",
                      run_skimage)):
        sec, err = fn(frames, geos)
        rows.append((name, 1e3 * statistics.median(sec[1:]), float(np.median(err[5:]))))
        print(f"  {name}: {rows[-1][1]:.2f} ms", file=sys.stderr)
    import skimage

    env = (f"Python {platform.python_version()}, numpy {np.__version__}, scikit-image "
           f"{skimage.__version__}, {time.strftime('%Y-%m-%d')}")
    t = ["| tracker | ms a frame | mean distance to the boundary (px) |", "|---|---:|---:|"]
    t += [f"| {n} | {ms:.2f} | {e:.2f} |" for n, ms, e in rows]
    section = (f"## Snakes\n\nMeasured with `python bench/bench_snake.py` ({env}): a "
               f"320×240 ellipse moving 2 px a frame, growing and turning, with noise; 100 "
               f"contour points, each frame started from the last contour.\n\n"
               + "\n".join(t) + "\n")
    publish(section, args.write)


if __name__ == "__main__":
    main()
