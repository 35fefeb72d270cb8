"""Elementary functions for compiled loops: ones LLVM can vectorise, and the angle wrap the
compiled filters share.

numba compiles ``math.exp`` to a call into the C library, one element at a time; a loop that
calls it cannot be vectorised. :func:`exp_weight` is ``exp`` written as arithmetic (Cody-Waite
range reduction and a polynomial), for the one place where it is the bottleneck: turning a
particle cloud's log weights into weights.
"""

from __future__ import annotations

import math

from .._jit import intrinsic, njit


@intrinsic
def _int_bits_as_float(typingctx, bits):
    """The float64 whose IEEE 754 bit pattern is the int64 ``bits``."""
    from numba.core import types

    if bits != types.int64:
        return None

    def codegen(context, builder, signature, args):
        from llvmlite import ir

        return builder.bitcast(args[0], ir.DoubleType())

    return types.float64(types.int64), codegen


@intrinsic
def _float_bits_as_int(typingctx, x):
    """The int64 with the IEEE 754 bit pattern of the float64 ``x``."""
    from numba.core import types

    if x != types.float64:
        return None

    def codegen(context, builder, signature, args):
        from llvmlite import ir

        return builder.bitcast(args[0], ir.IntType(64))

    return types.int64(types.float64), codegen


_SHIFTER = 6755399441055744.0  # 1.5 * 2**52: adding it rounds to an integer, kept in the low bits
_LOG2E = 1.4426950408889634
_LN2_HI = 6.93147180369123816490e-01  # ln 2 in two parts (fdlibm): k * _LN2_HI is exact
_LN2_LO = 1.90821492927058770002e-10


@njit(inline="always", error_model="numpy")
def exp_weight(x):
    """``exp(x)`` for ``x <= 0``, within 2 ulp; exactly 0 below -708 (where ``exp`` leaves the
    normal doubles; a weight that small next to the largest, which is 1, is zero to every sum
    it enters). NaN gives NaN.

    ``exp(x) = 2^k exp(r)`` with ``k = round(x / ln 2)``, ``|r| <= ln 2 / 2``, and ``exp(r)``
    its Taylor polynomial of degree 13 (truncation error below ``4.4e-18``).
    """
    kd = x * _LOG2E + _SHIFTER
    k = kd - _SHIFTER
    r = (x - k * _LN2_HI) - k * _LN2_LO
    p = 1.0 / 6227020800.0
    p = p * r + 1.0 / 479001600.0
    p = p * r + 1.0 / 39916800.0
    p = p * r + 1.0 / 3628800.0
    p = p * r + 1.0 / 362880.0
    p = p * r + 1.0 / 40320.0
    p = p * r + 1.0 / 5040.0
    p = p * r + 1.0 / 720.0
    p = p * r + 1.0 / 120.0
    p = p * r + 1.0 / 24.0
    p = p * r + 1.0 / 6.0
    p = p * r + 0.5
    p = p * r + 1.0
    p = p * r + 1.0
    # 2^k: the low bits of kd hold k; (k + 1023) << 52 is the double 2^k
    scale = _int_bits_as_float((_float_bits_as_int(kd) + 1023) << 52)
    return p * scale if x > -708.0 else (x if x != x else 0.0)


@njit(inline="always", error_model="numpy")
def wrap_angle(d):
    """``d`` plus a multiple of ``2π``, in ``(-π, π]``: the compiled filters' residual of an
    angle, as :func:`vistrack.models.nonlinear.wrap_angle` wraps arrays (the modulo of a hair
    below 0 rounds up to ``2π``: a hair above ``π`` would come out as ``-π``)."""
    w = math.pi - ((math.pi - d) % (2.0 * math.pi))
    return w + 2.0 * math.pi if w <= -math.pi else w
