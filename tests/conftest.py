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
