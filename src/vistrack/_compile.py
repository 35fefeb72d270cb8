"""Watch numba compile: say so once, and count the seconds, so that rates can leave them out.

The compiled kernels are built the first time a machine runs them and read from numba's cache
afterwards (a load from the cache is not a compilation and is not counted). :func:`watch`
installs a listener for the duration of a command; :func:`seconds` is the compile time so far
(0 when nothing watches), which :func:`vistrack.pipeline.run` takes off each stage's time.
"""

from __future__ import annotations

import time
from collections.abc import Iterator
from contextlib import contextmanager
from typing import TextIO

__all__ = ["watch", "seconds"]

_total = 0.0


def seconds() -> float:
    """Seconds spent compiling since the first :func:`watch` of this process."""
    return _total


@contextmanager
def watch(stream: TextIO | None, what: str = "vistrack") -> Iterator[None]:
    """Count top-level numba compilations while the block runs; before the first, write one
    line to ``stream`` (none if it is None) saying that kernels are being compiled, once.

    Does nothing (and imports nothing) when numba is not installed."""
    try:
        from numba.core import event
    except ImportError:  # pragma: no cover - numba is a dependency
        yield
        return

    class _Listener(event.Listener):
        def __init__(self) -> None:
            self.depth = 0
            self.start = 0.0
            self.said = False

        def on_start(self, ev: event.Event) -> None:
            if self.depth == 0:
                if not self.said and stream is not None:
                    print(f"{what}: compiling its kernels for this machine, once (later runs "
                          "reuse them); rates below leave this out", file=stream, flush=True)
                self.said = True
                self.start = time.perf_counter()
            self.depth += 1

        def on_end(self, ev: event.Event) -> None:
            global _total
            self.depth -= 1
            if self.depth == 0:
                _total += time.perf_counter() - self.start

    listener = _Listener()
    event.register("numba:compile", listener)
    try:
        yield
    finally:
        event.unregister("numba:compile", listener)
