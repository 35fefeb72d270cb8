"""Helpers shared by the benchmark scripts."""

from __future__ import annotations

import statistics
import sys
import time


def optional(name: str):
    """The module ``name``, or None (with a note on stderr) when it does not import."""
    try:
        return __import__(name)
    except Exception as exc:  # noqa: BLE001 - any import failure means "not available"
        print(f"  ({name} not available: {exc})", file=sys.stderr)
        return None


def median_time(fn, repeats: int):
    """The median of ``repeats`` timed calls of ``fn`` after one untimed call (compilation,
    caches), and the last call's result."""
    out = fn()
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return statistics.median(times), out


def per_frame(fn, frames, repeats: int = 3):
    """Median over ``repeats`` passes of the mean milliseconds a frame of ``fn(frame)``."""
    out = []
    for _ in range(repeats):
        t = time.perf_counter()
        for f in frames:
            fn(f)
        out.append((time.perf_counter() - t) / len(frames) * 1e3)
    return statistics.median(out)
