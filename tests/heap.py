"""How much memory the process holds, for tests that it does not grow."""

from __future__ import annotations

import sys


def heap_meter():
    """A function giving the bytes this process holds, and one to call when done.

    With glibc: the C allocator's bytes in use in its main arena, where this thread's
    allocations go (``mallinfo2``: numpy's arrays, the compiled kernels' arrays, every Python
    object over 512 bytes), and in blocks of their own, plus Python's small-object blocks
    counted at 512 bytes each, the most one can hold. For code run in this thread it misses
    nothing tracemalloc sees, it sees the compiled kernels' allocations, which tracemalloc
    does not, and it costs nothing to keep. Elsewhere: tracemalloc's traced bytes (the
    tracker then runs about five times slower)."""
    import ctypes
    import ctypes.util
    import tracemalloc

    class MallInfo2(ctypes.Structure):
        _fields_ = [(name, ctypes.c_size_t) for name in (
            "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
            "fordblks", "keepcost")]

    try:
        mallinfo2 = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").mallinfo2
    except (OSError, AttributeError):
        tracemalloc.start()
        return (lambda: tracemalloc.get_traced_memory()[0]), tracemalloc.stop
    mallinfo2.restype, mallinfo2.argtypes = MallInfo2, []

    def held():
        m = mallinfo2()
        return m.uordblks + m.hblkhd + 512 * sys.getallocatedblocks()

    return held, (lambda: None)
