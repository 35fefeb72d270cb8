"""Random numbers and resampling inside compiled kernels.

The compiled particle filter draws its process noise and resampling uniforms in the kernel,
from its own generator, rather than asking numpy for arrays of draws at every step (numpy's
normals cost about twice as much as these, and the arrays cost memory traffic):

- **xoshiro256++** (Blackman and Vigna, 2021, "Scrambled linear pseudorandom number
  generators"), 256 bits of state, seeded from the caller's numpy ``Generator``;
- standard normals by the **ziggurat** method (Marsaglia and Tsang, 2000) with 256 layers and
  52-bit mantissas, as in numpy's ``Generator.standard_normal``;
- the four resampling schemes of :data:`vistrack.filters.particle.RESAMPLERS`, in linear time.

The functions are ``inline="always"`` and pass the generator's state as a tuple, in and out, so
that a kernel that calls them keeps it in registers.
"""

from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from .._prebuilt import kernel

SCHEMES = ("multinomial", "stratified", "systematic", "residual")
"""Resampling schemes the kernels implement, by code: ``SCHEMES.index(name)``."""


def _ziggurat_tables(r: float = 3.6541528853610088, v: float = 0.00492867323399):
    """Marsaglia and Tsang's tables for 256 layers of area ``v`` with base strip edge ``r``,
    scaled to 52-bit integers: ``ki`` (acceptance limits), ``wi`` (widths), ``fi`` (densities)."""
    m1 = 2.0**52
    ki, wi, fi = np.zeros(256, np.uint64), np.zeros(256), np.zeros(256)
    dn = tn = r
    q = v / math.exp(-0.5 * dn * dn)
    ki[0], ki[1] = np.uint64(dn / q * m1), 0
    wi[0], wi[255] = q / m1, dn / m1
    fi[0], fi[255] = 1.0, math.exp(-0.5 * dn * dn)
    for i in range(254, 0, -1):
        dn = math.sqrt(-2.0 * math.log(v / dn + math.exp(-0.5 * dn * dn)))
        ki[i + 1] = np.uint64(dn / tn * m1)
        tn = dn
        fi[i] = math.exp(-0.5 * dn * dn)
        wi[i] = dn / m1
    return ki, wi, fi


_KI, _WI, _FI = _ziggurat_tables()
_R = 3.6541528853610088  # the edge of the base strip
_U53 = 1.0 / 9007199254740992.0  # 2**-53


def seed(rng: np.random.Generator) -> np.ndarray:
    """A generator state (4 ``uint64``) drawn from ``rng``: reproducible from its seed."""
    s = rng.integers(0, 2**64, size=4, dtype=np.uint64, endpoint=False)
    if not s.any():  # the one state xoshiro cannot leave
        s[0] = 1
    return s


@njit(inline="always")
def _rotl(x, k):
    return (x << np.uint64(k)) | (x >> np.uint64(64 - k))


@njit(inline="always")
def next_u64(st):
    """The next 64 random bits of the xoshiro256++ state ``st`` (a tuple of 4 ``uint64``,
    kept in registers), and the next state."""
    s0, s1, s2, s3 = st
    out = _rotl(s0 + s3, 23) + s0
    t = s1 << np.uint64(17)
    s2 ^= s0
    s3 ^= s1
    s1 ^= s2
    s0 ^= s3
    s2 ^= t
    s3 = _rotl(s3, 45)
    return out, (s0, s1, s2, s3)


@njit(inline="always")
def uniform(st):
    """A uniform draw in [0, 1) with 53 random bits, and the next state."""
    r, st = next_u64(st)
    return np.int64(r >> np.uint64(11)) * _U53, st


@njit(inline="always")
def normal(st):
    """A standard normal draw (ziggurat: one 64-bit draw and one comparison 99 % of the time),
    and the next state."""
    while True:
        r, st = next_u64(st)
        i = np.intp(r & np.uint64(0xFF))
        r >>= np.uint64(8)
        a = (r >> np.uint64(1)) & np.uint64(0x000FFFFFFFFFFFFF)
        x = np.int64(a) * _WI[i]
        if r & np.uint64(1):
            x = -x
        if a < _KI[i]:
            return x, st
        if i == 0:  # the tail beyond R, by Marsaglia's method
            while True:
                u1, st = uniform(st)
                u2, st = uniform(st)
                xx = -math.log1p(-u1) / _R
                yy = -math.log1p(-u2)
                if yy + yy > xx * xx:
                    return (-(_R + xx) if (a >> np.uint64(8)) & np.uint64(1) else _R + xx), st
        else:
            u, st = uniform(st)
            if (_FI[i - 1] - _FI[i]) * u + _FI[i] < math.exp(-0.5 * x * x):
                return x, st


@njit(inline="always")
def last_drawable(cw):
    """The first index of the cumulative weights ``cw`` that reaches their end: the last of
    positive weight, which a uniform rounded up to 1 takes (the indices of weight 0 after it
    have the same cumulative weight)."""
    last = cw.shape[0] - 1
    while last > 0 and cw[last - 1] >= cw[-1]:
        last -= 1
    return last


@njit(inline="always")
def last_positive(w):
    """The last index of a positive weight in ``w`` (0 if none is)."""
    last = w.shape[0] - 1
    while last > 0 and not w[last] > 0.0:
        last -= 1
    return last


@njit(inline="always")
def _merge_uniforms(cw, scheme, st, out):
    # out[k] = the first i with u_k < cw[i], for sorted u_k in [0, 1): stratified
    # (k + U_k) / n, or multinomial (normalised cumulative sums of n + 1 exponentials, the
    # sum drawn first and the same draws again, from a copy of the state)
    n, last = out.shape[0], last_drawable(cw)
    total, start = 1.0, st
    if scheme == 0:
        total = 0.0
        for _ in range(n + 1):
            u, st = uniform(st)
            total -= math.log1p(-u)
        st, start = start, st
    i, acc = 0, 0.0
    for k in range(n):
        u, st = uniform(st)
        if scheme == 0:
            acc -= math.log1p(-u)
            u = acc / total
        else:
            u = (k + u) / n
        while i < last and cw[i] <= u:
            i += 1
        out[k] = i
    return start if scheme == 0 else st


@njit(inline="always")
def resample_into(w, scheme, st, cw, out):
    """Indices ``out (n,)`` drawn from weights ``w (N,)`` (any positive scale whose sum is
    finite: the filters' normalised weights; ``particle.RESAMPLERS`` scales others) by scheme
    code ``scheme`` (:data:`SCHEMES`), each ``i`` ``n w_i / Σ w`` times in expectation, from
    state ``st``; returns the next state. ``cw (N,)`` is scratch."""
    N, n = w.shape[0], out.shape[0]
    total = 0.0
    for i in range(N):
        total += w[i]
    if scheme == 2:  # systematic: u_k = (k + u) / n; index i for every k < ceil(n c_i - u)
        u0, st = uniform(st)
        scale = n / total
        c, i, k = 0.0, 0, 0
        while i < N and k < n - 1:
            # branch-free for up to 2 copies: write i to the next two slots whatever the
            # count (the next index overwrites what is not this one's); a loop for more
            c += w[i]
            edge = min(np.intp(math.ceil(c * scale - u0)), n)
            out[k] = i
            out[k + 1] = i
            j = k + 2
            while j < edge:
                out[j] = i
                j += 1
            k = max(edge, k)
            i += 1
        while i < N:
            c += w[i]
            edge = min(np.intp(math.ceil(c * scale - u0)), n)
            while k < edge:
                out[k] = i
                k += 1
            i += 1
        # rounding of the last edge (u0 within n/2 ulp of 1), and the slots the loop above
        # wrote ahead: the last index of weight > 0 (N - 1 may have none), sought only here
        last = last_positive(w)
        while k < n:
            out[k] = last
            k += 1
        return st
    if scheme == 3:  # residual: floor(n w_i) copies, the rest multinomial on what remains
        # (n w_i within 4 N ulp below a whole number counts as it, as particle._whole_copies:
        # n equal weights give one copy each, not a draw at random; the plain floor where
        # that would make more than n)
        grace = 1.0 + 4.0 * N * 2.220446049250313e-16
        whole = 0
        for i in range(N):
            whole += math.floor(n * (w[i] / total) * grace)
        if whole > n:
            grace = 1.0
        k, rest = 0, 0.0
        for i in range(N):
            nw = n * (w[i] / total)
            copies = math.floor(nw * grace)
            for _ in range(int(copies)):
                out[k] = i
                k += 1
            rest += max(nw - copies, 0.0)
            cw[i] = rest
        if k < n:
            for i in range(N):
                cw[i] /= rest
            st = _merge_uniforms(cw, 0, st, out[k:])
        return st
    c = 0.0
    for i in range(N):
        c += w[i]
        cw[i] = c / total
    return _merge_uniforms(cw, scheme, st, out)


# ---------------------------------------------------------------- array entry points
@kernel
@njit(cache=True, error_model="numpy")
def _fill(s, out, normals):
    st = (s[0], s[1], s[2], s[3])
    for i in range(out.shape[0]):
        if normals:
            out[i], st = normal(st)
        else:
            out[i], st = uniform(st)
    s[0], s[1], s[2], s[3] = st
    return out


def normals(s: np.ndarray, out: np.ndarray) -> np.ndarray:
    """Fill ``out`` (1-D) with standard normals, advancing the state array ``s (4,)``."""
    return _fill(s, out, True)


def uniforms(s: np.ndarray, out: np.ndarray) -> np.ndarray:
    """Fill ``out`` (1-D) with uniforms in [0, 1), advancing the state array ``s (4,)``."""
    return _fill(s, out, False)


@njit(cache=True, error_model="numpy")
def resample_indices(w, scheme, s, n):
    """``n`` indices drawn from weights ``w`` by scheme code ``scheme``, advancing ``s (4,)``."""
    out = np.empty(n, np.int64)
    st = resample_into(w, scheme, (s[0], s[1], s[2], s[3]), np.empty(w.shape[0]), out)
    s[0], s[1], s[2], s[3] = st
    return out
