import os
from pathlib import Path

# Under pytest-xdist (make test), each worker keeps its own numba cache. numba's on-disk index
# is read, extended and written back without a lock: two processes compiling two signatures of
# one function at once can both name their code file ``.1``, and one signature then loads the
# other's code (numba/core/caching.py, IndexDataCacheFile.save). Set before numba is imported:
# this file is loaded before any test module.
if os.environ.get("PYTEST_XDIST_WORKER") and "NUMBA_CACHE_DIR" not in os.environ:
    os.environ["NUMBA_CACHE_DIR"] = str(Path(__file__).resolve().parents[1] / ".pytest_cache"
                                        / f"numba-{os.environ['PYTEST_XDIST_WORKER']}")
    _seed = True
else:
    _seed = False

import numpy as np  # noqa: E402
import pytest  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
NUMBA_KEPT = ROOT / "build" / "numba-cache"
"""numba's compilations of the kernels, kept by the build of the ahead-of-time kernels
(``make kernels``, which ``make test`` runs; see :func:`vistrack._prebuilt_build.build`)."""


def seed_numba_cache(dest):
    """Copy the build's compilations of the kernels into the numba cache ``dest``, if they
    were made from the sources as they are: a process using ``dest`` then loads them instead
    of compiling the kernels again for those argument types (numba compiles the rest as
    usual). Returns the number of functions copied."""
    from vistrack import _prebuilt
    from vistrack._prebuilt_build import copy_numba_cache

    try:
        sources = (NUMBA_KEPT / "sources").read_text(encoding="utf-8").strip()
    except OSError:
        return 0
    if sources != _prebuilt.source_hash():
        return 0
    return copy_numba_cache(NUMBA_KEPT, Path(dest))


if _seed:  # before any test compiles
    seed_numba_cache(os.environ["NUMBA_CACHE_DIR"])

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


def pytest_addoption(parser):
    parser.addoption("--write-digests", action="store_true",
                     help="store the result files' digests (tests/test_accuracy.py) instead "
                          "of checking them")


def need(path):
    """``path``, or skip the test with the reason when the shared data is absent."""
    if not path.exists():
        pytest.skip(f"{path} not found: the shared data is not beside this checkout")
    return path


@pytest.fixture
def rng():
    return np.random.default_rng(12345)


def random_model(rng, n, m, T=None, *, tv=False):
    """A well-conditioned random linear-Gaussian model; per-step matrices when ``tv``."""

    def spd(k, scale, lead=()):
        A = rng.normal(size=lead + (k, k))
        return scale * (A @ np.swapaxes(A, -1, -2) / k + np.eye(k))

    lead = (T,) if tv else ()
    F = np.eye(n) + 0.3 * rng.normal(size=lead + (n, n)) / np.sqrt(n)
    H = rng.normal(size=lead + (m, n))
    return dict(F=F, Q=spd(n, 0.2, lead), H=H, R=spd(m, 0.5, lead))


def exact_posterior(ys, *, F, Q, H, R, x0, P0, fractions=False):
    """The posterior of every state of a linear-Gaussian model given ``ys (T, m)`` (a step
    with a NaN is not measured; ``F, Q, H, R`` constant), in exact rational arithmetic: the
    means ``(T, n)`` and the covariance of all states ``(T n, T n)``, the inverse of the
    block-tridiagonal posterior precision by Gauss-Jordan on fractions (floats lose a small
    variance beside a large one). For a few steps and states: it is cubic in ``T n`` on
    fractions whose digits grow. With ``fractions``, the two as fractions (lists), for sums
    that must not round either."""
    from fractions import Fraction

    def inv(M):
        k = len(M)
        A = [[Fraction(x) for x in row] + [Fraction(int(i == j)) for j in range(k)]
             for i, row in enumerate(M)]
        for c in range(k):
            p = next(r for r in range(c, k) if A[r][c] != 0)
            A[c], A[p] = A[p], A[c]
            A[c] = [x / A[c][c] for x in A[c]]
            for r in range(k):
                if r != c and A[r][c] != 0:
                    f = A[r][c]
                    A[r] = [a - f * b for a, b in zip(A[r], A[c])]
        return [row[k:] for row in A]

    def mul(A, B):
        return [[sum(a * b for a, b in zip(row, col)) for col in zip(*B)] for row in A]

    def tr(A):
        return [list(col) for col in zip(*A)]

    def frac(A):
        return [[Fraction(float(x)) for x in row] for row in np.atleast_2d(A)]

    ys = np.asarray(ys, float)
    T, n = len(ys), len(np.asarray(x0))
    Fq, Hq, Qi, Ri, P0i = frac(F), frac(H), inv(frac(Q)), inv(frac(R)), inv(frac(P0))
    N = T * n
    J = [[Fraction(0)] * N for _ in range(N)]
    h = [Fraction(0)] * N

    def add(i, j, M):
        for a in range(n):
            for b in range(n):
                J[i * n + a][j * n + b] += M[a][b]

    add(0, 0, P0i)
    for a, v in enumerate(mul(P0i, [[Fraction(float(x))] for x in x0])):
        h[a] += v[0]
    FtQi = mul(tr(Fq), Qi)
    for t in range(1, T):
        add(t, t, Qi)
        add(t - 1, t - 1, mul(FtQi, Fq))
        add(t, t - 1, [[-x for x in row] for row in mul(Qi, Fq)])
        add(t - 1, t, [[-x for x in row] for row in FtQi])
    HtRi = mul(tr(Hq), Ri)
    for t in range(T):
        if not np.isnan(ys[t]).any():
            add(t, t, mul(HtRi, Hq))
            for a, v in enumerate(mul(HtRi, [[Fraction(float(y))] for y in ys[t]])):
                h[t * n + a] += v[0]
    C = inv(J)
    mu = [sum(C[i][j] * h[j] for j in range(N)) for i in range(N)]
    if fractions:
        return mu, C
    return (np.array([float(v) for v in mu]).reshape(T, n),
            np.array([[float(x) for x in row] for row in C]))
