"""Giving freed memory back to the system during long runs.

A long run decodes, converts and frees a frame's buffers many times a second. glibc keeps
freed blocks for reuse in the heap of the thread that freed them, raising its threshold for
handing large blocks straight back to the system as they come and go; the process's resident
memory then drifts with whatever happens to be free, by tens of MB over an hour of video
(``bench/bench_soak.py``). :class:`PeriodicRelease` returns that free memory every few seconds
of a run, at the cost of a few milliseconds each time.
"""

from __future__ import annotations

import ctypes
import sys
import time
from collections.abc import Callable
from typing import Any

__all__ = ["release_free_memory", "PeriodicRelease"]

_trim: Any = None  # libc's malloc_trim once looked up; False where there is none


def release_free_memory() -> bool:
    """Return the free memory the C library holds to the system (glibc's ``malloc_trim``).

    Returns
    -------
    bool
        True if it was asked to, False where there is no such call (another C library, another
        system).
    """
    global _trim
    if _trim is None:
        _trim = False
        if sys.platform.startswith("linux"):
            try:
                fn = ctypes.CDLL("libc.so.6").malloc_trim
            except (OSError, AttributeError):  # musl, or no libc.so.6
                pass
            else:
                fn.argtypes, fn.restype = [ctypes.c_size_t], ctypes.c_int
                _trim = fn
    if _trim is False:
        return False
    _trim(0)
    return True


class PeriodicRelease:
    """Call :func:`release_free_memory` at most every ``every`` seconds of a run.

    Parameters
    ----------
    every : float
        Seconds between releases.
    clock : callable
        The time in seconds (``time.monotonic``).

    Examples
    --------
    >>> now = [0.0]
    >>> release = PeriodicRelease(10.0, clock=lambda: now[0])
    >>> _ = release(); release.times
    0
    >>> now[0] = 10.0
    >>> _ = release(); release.times
    1
    """

    def __init__(self, every: float = 10.0, clock: Callable[[], float] = time.monotonic):
        self.every = float(every)
        self.clock = clock
        self.start = self.last = clock()
        self.times = 0

    def __call__(self) -> bool:
        """Release if ``every`` seconds have passed since the last release (or the start);
        True if it did."""
        now = self.clock()
        if now - self.last < self.every:
            return False
        self.last = now
        self.times += 1
        return release_free_memory()

    def end(self) -> bool:
        """At the end of a run that lasted ``every`` seconds or more, release once more (what
        closing the outputs freed); True if it did."""
        if self.clock() - self.start < self.every:
            return False
        self.times += 1
        return release_free_memory()
