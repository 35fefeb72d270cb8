"""The box tracker's worst case for its last association stage: clutter that never persists.

    python bench/bench_clutter.py

2,000 boxes a frame (20-60 pixels, anywhere on a 4000x4000 image, scores 0.5-1 taken as they
are), 30 frames at 2 frames/s, none related to the frame before: every box starts a tentative
track, and every tentative track is left unmatched in the next frame, where the last stage
(``tentative_gate``, a chi-square gate that reaches 3.5 boxes at this rate) looks for a
detection in its gate. ``BoxTracker.step`` with the stage and without (``tentative_gate=0``),
in turn, five times; milliseconds a frame, medians.
"""

from __future__ import annotations

import statistics
import time

import numpy as np

from vistrack.tracking import BoxTracker
from vistrack.types import Detections


def main() -> None:
    rng = np.random.default_rng(0)
    frames = []
    for _ in range(30):
        xy, wh = rng.uniform(0, 4000, (2000, 2)), rng.uniform(20, 60, (2000, 2))
        frames.append(Detections(boxes=np.c_[xy, xy + wh], scores=rng.uniform(0.5, 1, 2000)))
    times: dict[float, list[float]] = {13.28: [], 0.0: []}
    for _ in range(5):
        for gate in times:
            tr = BoxTracker(frame_rate=2.0, scores="raw", tentative_gate=gate)
            tr.step(1, frames[0])  # (the first frame loads the kernels)
            t0 = time.perf_counter()
            for f, d in enumerate(frames[1:], start=2):
                tr.step(f, d)
            times[gate].append((time.perf_counter() - t0) / (len(frames) - 1) * 1e3)
    on, off = statistics.median(times[13.28]), statistics.median(times[0.0])
    print(f"with the stage {on:.2f} ms a frame, without {off:.2f} ms a frame ({on / off:.1f}x)")


if __name__ == "__main__":
    main()
