"""Watch numba compile: say so once, and count the seconds, so that rates can leave them out.

The compiled kernels are built the first time a machine runs them and read from numba's cache
afterwards (a load from the cache is not a compilation and is not counted). :func:`watch`
installs a listener for the duration of a command; :func:`seconds` is the compile time so far
(0 when nothing watches), which :func:`vistrack.pipeline.run` takes off each stage's time.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from typing import TextIO

from . import _jit

__all__ = ["watch", "seconds", "forget"]

_total = 0.0
# the watches under way: each one's hook for numba's import, its listener once registered, and
# whether it is still active
_watches: list[tuple[Callable[[], None], list[object], list[bool]]] = []


def seconds() -> float:
    """Seconds spent compiling since the first :func:`watch` of this process."""
    return _total


@contextmanager
def watch(stream: TextIO | None, what: str = "vistrack", rates: bool = True) -> Iterator[None]:
    """Count top-level numba compilations while the block runs; before the first, write one
    line to ``stream`` (none if it is None) saying that kernels are being compiled, once,
    and, with ``rates``, that the rates the command prints leave that time out.

    Imports nothing: the listener is registered once numba is imported (a command served by
    the kernels compiled at install never imports it, :mod:`vistrack._jit`)."""
    said = [False]
    registered: list[object] = []
    active = [True]

    def register() -> None:
        if not active[0]:
            return
        from numba.core import event

        class _Listener(event.Listener):
            def __init__(self) -> None:
                self.depth = 0
                self.start = 0.0

            def on_start(self, ev: event.Event) -> None:
                if self.depth == 0:
                    if not said[0] and stream is not None:
                        print(f"{what}: compiling its kernels for this machine, once (later "
                              "runs reuse them)" + ("; rates below leave this out" if rates
                                                    else ""), file=stream, flush=True)
                    said[0] = True
                    self.start = time.perf_counter()
                self.depth += 1

            def on_end(self, ev: event.Event) -> None:
                global _total
                self.depth -= 1
                if self.depth == 0:
                    _total += time.perf_counter() - self.start

        listener = _Listener()
        event.register("numba:compile", listener)
        registered.append(listener)

    watch_ = (register, registered, active)
    _watches.append(watch_)
    _jit.on_import(register)
    try:
        yield
    finally:
        _stop(*watch_)
        if watch_ in _watches:
            _watches.remove(watch_)


def _stop(register: Callable[[], None], registered: list[object], active: list[bool]) -> None:
    active[0] = False
    _jit.cancel(register)
    if registered:
        from numba.core import event

        event.unregister("numba:compile", registered.pop())


def forget() -> None:
    """In a process forked while a :func:`watch` ran (a pool's worker): stop watching here and
    start the count afresh, as in a process started anew (the watch is its parent's)."""
    global _total
    for watch_ in _watches:
        _stop(*watch_)
    _watches.clear()
    _total = 0.0
