"""A first run says once that it compiles, and rates leave the compilation out."""

import io
import os
import subprocess
import sys
import textwrap

import numpy as np
from numba import njit

from vistrack import _compile
from vistrack.pipeline import run
from vistrack.types import Frame, Tracks

SCRIPT = textwrap.dedent("""
    import io, sys
    from numba import njit
    from vistrack import _compile

    @njit(cache=True)
    def inner(x):
        return x + 1.0

    @njit(cache=True)
    def outer(x):
        return inner(x) * 2.0

    out = io.StringIO()
    with _compile.watch(out):
        assert outer(1.0) == 4.0
        assert outer(2.0) == 6.0
    print(repr(out.getvalue()), _compile.seconds() > 0)
""")


def test_message_once_on_a_cold_cache_and_none_on_a_warm_one(tmp_path):
    script = tmp_path / "kernels.py"
    script.write_text(SCRIPT)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"))
    cold = subprocess.run([sys.executable, str(script)], env=env, capture_output=True,
                          text=True, check=True).stdout
    warm = subprocess.run([sys.executable, str(script)], env=env, capture_output=True,
                          text=True, check=True).stdout
    message, compiled = cold.rsplit(" ", 1)
    assert message.count("compiling") == 1 and compiled.strip() == "True"
    assert warm.strip() == "'' False"  # loaded from the cache: nothing compiled, nothing said


def test_the_message_speaks_of_rates_only_where_the_command_prints_them():
    """``vistrack demo kalman`` printed "rates below leave this out" and no rate."""
    @njit
    def once(x):
        return x * 3.0

    @njit
    def twice(x):
        return x * 5.0

    told, untold = io.StringIO(), io.StringIO()
    with _compile.watch(told):
        once(1.0)
    with _compile.watch(untold, rates=False):
        twice(1.0)
    assert told.getvalue() == ("vistrack: compiling its kernels for this machine, once (later "
                               "runs reuse them); rates below leave this out\n")
    assert untold.getvalue() == ("vistrack: compiling its kernels for this machine, once "
                                 "(later runs reuse them)\n")


class _CompilingTracker:
    """Compiles a new kernel at its first step (as the box tracker does on a first run)."""

    def __init__(self):
        @njit
        def kernel(x):
            s = 0.0
            for v in x:
                s += v
            return s

        self.kernel = kernel

    def step(self, frame, detections):
        self.kernel(np.ones(3))
        return Tracks.empty()

    def reset(self):
        pass


def test_run_takes_compilation_out_of_the_stage_it_happened_in():
    frames = [Frame(k, k / 25.0) for k in range(1, 6)]
    before = _compile.seconds()
    with _compile.watch(io.StringIO()):
        stats = run(frames, None, _CompilingTracker())
    compiled = _compile.seconds() - before
    assert compiled > 0
    assert stats.seconds["compile"] == compiled
    # the tracker's own work is a few microseconds a frame; the compilation is not in it
    assert stats.seconds["tracker"] < compiled / 2


def test_the_message_comes_when_numba_is_first_imported_inside_the_block(tmp_path):
    # a command's kernels import numba only when one must be compiled: the listener is
    # registered then, and the first compilation is announced and counted
    script = textwrap.dedent("""
        import io, sys
        import numpy as np
        from vistrack import _compile
        from vistrack.models import BoxMotion

        out = io.StringIO()
        with _compile.watch(out):
            before = "numba" in sys.modules
            BoxMotion().Q_diag(np.array([[0.0, 0.0, 10.0, 20.0]]))
        print(before, repr(out.getvalue()), _compile.seconds() > 0)
    """)
    env = dict(os.environ, NUMBA_CACHE_DIR=str(tmp_path / "cache"), VISTRACK_PREBUILT="0")
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True,
                         text=True, check=True).stdout.strip()
    before, rest = out.split(" ", 1)
    message, compiled = rest.rsplit(" ", 1)
    assert before == "False" and message.count("compiling") == 1 and compiled == "True"
