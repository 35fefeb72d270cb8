"""numba made on first need (vistrack._jit): the same compiled functions, numba imported only
when something is compiled."""

import subprocess
import sys
import textwrap

import numpy as np

from vistrack import _jit


def _run(script: str) -> str:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(script)], check=True,
                          capture_output=True, text=True).stdout.strip()


def test_decorating_imports_nothing_and_the_first_call_compiles_with_numba():
    out = _run("""
        import sys
        import numpy as np
        from vistrack._jit import njit, intrinsic

        @intrinsic
        def bits(typingctx, x):
            from numba.core import types
            def codegen(context, builder, signature, args):
                from llvmlite import ir
                return builder.bitcast(args[0], ir.IntType(64))
            return types.int64(types.float64), codegen

        @njit(inline="always")
        def twice(x):
            return 2.0 * x

        @njit(error_model="numpy")
        def total(a):
            s = 0.0
            for i in range(a.shape[0]):
                s += twice(a[i])
            return s, bits(1.0)

        before = "numba" in sys.modules
        s, b = total(np.arange(4.0))
        print(before, "numba" in sys.modules, s, b, type(total.real).__name__,
              total.signatures, twice.py_func(6.0))
    """)
    before, after, s, b, kind, *rest = out.split(" ", 5)
    assert (before, after) == ("False", "True")
    assert float(s) == 12.0 and int(b) == np.float64(1.0).view(np.int64)
    assert kind == "CPUDispatcher" and "Array(float64, 1, 'C'" in rest[0]
    assert rest[0].endswith(" 12.0")  # the Python function, as numba's py_func


def test_prange_is_numbas_once_numba_is_imported():
    out = _run("""
        import sys
        from vistrack.tracking import _affine
        print(_affine.prange is range, "numba" in sys.modules)
        import numba
        # noticed at the next need of a numba object (here: a compiled call's dispatcher)
        _affine._ncc.real
        print(_affine.prange is numba.prange)
    """)
    assert out.splitlines() == ["True False", "True"]


def test_with_numba_imported_first_the_decorators_are_numbas_own():
    import numba

    seen = []
    _jit.on_import(lambda: seen.append(1))
    assert seen == [1]  # numba is imported: at once

    @_jit.njit(cache=False)
    def f(x):
        return x + 1

    assert isinstance(f, numba.core.registry.CPUDispatcher) and f(1) == 2


def test_a_lazy_function_keeps_the_python_functions_name_and_documentation():
    def g(x):
        """doc"""
        return x

    lazy = _jit.Lazy(g, lambda numba: numba.njit(g))
    assert (lazy.__name__, lazy.__doc__, lazy.py_func, lazy.__wrapped__) == ("g", "doc", g, g)
    assert "compiled on first use" in repr(lazy)
    assert lazy(3) == 3 and "CPUDispatcher" in repr(lazy)


def test_a_hook_cancelled_before_numba_is_imported_never_runs():
    out = _run("""
        from vistrack import _compile, _jit
        import io
        s = io.StringIO()
        for _ in range(3):
            with _compile.watch(s):
                pass
        print(len(_jit._hooks))
    """)
    assert out == "0"
