"""Freed memory given back to the system during long runs (vistrack._memory)."""

from __future__ import annotations

import platform
import subprocess
import sys
import textwrap
from functools import partial
from itertools import count

import pytest

from vistrack import _memory, pipeline
from vistrack.tracking import BoxTracker
from vistrack.types import Detections, Frame

GLIBC = sys.platform.startswith("linux") and platform.libc_ver()[0] == "glibc"


@pytest.mark.skipif(not GLIBC, reason="malloc_trim is glibc's")
def test_release_gives_the_heaps_free_memory_back_to_the_system():
    """60 MB of 1 kB blocks, every 100th kept: freeing the rest leaves them in the heap, whose
    resident size (VmRSS, read from /proc) falls only when the free memory is released."""
    script = textwrap.dedent("""
        from pathlib import Path
        from vistrack._memory import release_free_memory
        def rss():
            for line in Path("/proc/self/status").read_text().splitlines():
                if line.startswith("VmRSS:"):
                    return int(line.split()[1]) / 1024
        kept, freed = [], []
        for i in range(60_000):
            (kept if i % 100 == 0 else freed).append(bytes(1000 + i % 7))
        full = rss()
        del freed
        after_free = rss()
        ok = release_free_memory()
        print(full, after_free, rss(), ok)
    """)
    out = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True,
                         check=True).stdout.split()
    full, after_free, released = map(float, out[:3])
    assert out[3] == "True"
    assert after_free > full - 10  # freed, but still held by the heap
    assert released < after_free - 40  # about 58 MB given back


def test_release_answers_false_where_there_is_no_malloc_trim(monkeypatch):
    monkeypatch.setattr(_memory, "_trim", False)
    assert _memory.release_free_memory() is False


def _frames(n):
    return [Frame(k, (k - 1) / 25) for k in range(1, n + 1)]


def _boxes(frame):
    return Detections.from_xywh([[10.0 + 4 * frame.index, 20, 30, 60]], [0.9])


def test_run_releases_every_10_s_and_at_the_end_of_a_long_run(monkeypatch):
    """A clock that moves 3 s a frame: released at 12 s and 24 s of 10 frames, then once
    more after the outputs are closed; a run shorter than 10 s is never released."""
    calls = []
    monkeypatch.setattr(_memory, "release_free_memory", lambda: calls.append(1) or True)
    ticks = count(0, 3.0)
    monkeypatch.setattr(pipeline, "PeriodicRelease",
                        partial(_memory.PeriodicRelease, clock=lambda: next(ticks)))
    assert pipeline.run(_frames(10), _boxes, BoxTracker()).frames == 10
    assert len(calls) == 3
    calls.clear()
    monkeypatch.setattr(pipeline, "PeriodicRelease", _memory.PeriodicRelease)
    pipeline.run(_frames(10), _boxes, BoxTracker())
    assert calls == []
