"""Drawing tracks on frames: vistrack's `viz.Annotator` beside supervision's annotators, in
one run.

    python bench/bench_annotate.py [--write docs/benchmarks.md]

Two scenes of simulated tracks, the same frames and tracks for both libraries:

- 520 particles on random walks over 640x424 frames (trackpy's bulk-water clip's size and
  count), each a point with a covariance: vistrack draws its trail, its 2-sigma ellipse and
  a dot (its numbers left out, as they would cover the frame); supervision a trace
  (`TraceAnnotator`) and a dot (`DotAnnotator`);
- 30 boxes walking over 768x576 frames (PETS09's size): vistrack draws each trail, ellipse,
  box and number; supervision a trace, a box (`BoxAnnotator`) and a label (`LabelAnnotator`).

Both keep 20 frames of trail. The table gives the median milliseconds a frame over 200
frames (three runs after a warm-up) and the ratio to vistrack.
"""

from __future__ import annotations

import argparse
import platform
import sys
import time

import numpy as np

from vistrack.types import Tracks
from vistrack.viz import Annotator

from _common import median_time, optional  # noqa: E402  (bench/ is on the path of its scripts)
from _markdown import publish  # noqa: E402

FRAMES = 200


def scene(n: int, size: tuple[int, int], boxes: bool, seed: int = 0):
    """``FRAMES`` frames of ``n`` objects on random walks: a list of (ids, centres (n, 2),
    boxes (n, 4) or None, covariances (n, 2, 2))."""
    rng = np.random.default_rng(seed)
    w, h = size
    at = rng.uniform([0, 0], [w, h], (n, 2))
    wh = rng.uniform([20, 50], [60, 150], (n, 2))
    out = []
    for _ in range(FRAMES):
        at = at + rng.normal(0, 1.0 if not boxes else 3.0, at.shape)
        a = rng.normal(size=(n, 2, 2)) * (0.5 if not boxes else 4.0)
        cov = a @ np.swapaxes(a, 1, 2) + np.eye(2) * 0.1
        b = np.c_[at - wh / 2, at + wh / 2] if boxes else None
        out.append((np.arange(1, n + 1), at.copy(), b, cov))
    return out


def run_vistrack(frames, image):
    ann = Annotator(trail=20)
    for ids, centres, b, cov in frames:
        t = Tracks(ids=ids, boxes=b, points=None if b is not None else centres,
                   scores=np.ones(len(ids)), classes=np.zeros(len(ids)), covs=cov)
        ann.draw(image, t)


def run_supervision(frames, image, sv):
    trace = sv.TraceAnnotator(trace_length=20, position=sv.Position.CENTER)
    marks = [sv.DotAnnotator(radius=3)] if frames[0][2] is None else [
        sv.BoxAnnotator(), sv.LabelAnnotator()]
    for ids, centres, b, _ in frames:
        xyxy = b if b is not None else np.c_[centres - 1, centres + 1]
        d = sv.Detections(xyxy=xyxy.astype(np.float32), tracker_id=ids,
                          class_id=np.zeros(len(ids), int))
        out = trace.annotate(image.copy(), d)
        for m in marks:
            out = m.annotate(out, d, **({"labels": [str(i) for i in ids]}
                                        if isinstance(m, sv.LabelAnnotator) else {}))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--write", metavar="MD")
    args = ap.parse_args()
    sv = optional("supervision")
    rows = []
    for label, n, size, boxes in (("520 particles, 640x424", 520, (640, 424), False),
                                  ("30 boxes, 768x576", 30, (768, 576), True)):
        frames = scene(n, size, boxes)
        image = np.full((size[1], size[0], 3), 90, np.uint8)
        sec, _ = median_time(lambda: run_vistrack(frames, image), 3)
        ours = sec / FRAMES * 1e3
        rows.append(f"| {label} | vistrack `Annotator` (trail, ellipse, "
                    f"{'box, number' if boxes else 'dot'}) | {ours:.2f} | 1 |")
        if sv is not None:
            sec, _ = median_time(lambda: run_supervision(frames, image, sv), 3)
            theirs = sec / FRAMES * 1e3
            rows.append(f"| {label} | supervision {sv.__version__} trace + "
                        f"{'box + label' if boxes else 'dot'} | {theirs:.2f} | "
                        f"{theirs / ours:.2g} |")
    env = (f"Python {platform.python_version()}, numpy {np.__version__}, "
           f"{time.strftime('%Y-%m-%d')}")
    section = f"""## Drawing tracks

Measured with `python bench/bench_annotate.py` ({env}): simulated tracks drawn on 200
frames, the median milliseconds a frame; the ratio is the time over vistrack's.

| scene | library | ms a frame | times vistrack's |
|---|---|---:|---:|
{chr(10).join(rows)}
"""
    publish(section, args.write)


if __name__ == "__main__":
    sys.exit(main())
