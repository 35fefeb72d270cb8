"""Dask: batches larger than memory filtered and smoothed chunk by chunk (equal to the
in-memory filter on each chunk), and many inputs tracked on a Dask cluster's workers."""

import subprocess
import sys

import numpy as np
import pytest

from tests.test_batch import _alone, bench  # noqa: F401 (a fixture)
from vistrack.filters import kalman_filter, rts_smooth

da = pytest.importorskip("dask.array")

F = np.block([[np.eye(2), np.eye(2)], [np.zeros((2, 2)), np.eye(2)]])
MODEL = dict(F=F, Q=0.1 * np.eye(4), H=np.eye(2, 4), R=np.eye(2))


@pytest.mark.parametrize("per_series_prior", [False, True])
def test_a_chunked_batch_is_filtered_and_smoothed_as_each_chunk_in_memory(per_series_prior):
    import dask

    rng = np.random.default_rng(0)
    B, T = 700, 40
    ys = rng.normal(size=(B, T, 2)).cumsum(axis=1)
    ys[rng.random((B, T)) < 0.1] = np.nan  # missing steps, different in each series
    ys[:, 3, 1] = np.nan  # and a missing component
    x0 = rng.normal(size=(B, 4)) if per_series_prior else np.zeros(4)
    P0 = np.eye(4)
    lazy = kalman_filter(da.from_array(ys, chunks=(250, 20, 2)), **MODEL, x0=x0, P0=P0)
    assert isinstance(lazy.means, da.Array) and lazy.means.chunks[0] == (250, 250, 200)
    smoothed = rts_smooth(lazy, F=F, Q=MODEL["Q"])
    got = dask.compute(lazy.means, lazy.covs, lazy.loglik, lazy.last.mean, smoothed.means,
                       smoothed.covs, scheduler="threads")
    for a, b in [(0, 250), (250, 500), (500, 700)]:
        ref = kalman_filter(ys[a:b], **MODEL, x0=x0[a:b] if per_series_prior else x0, P0=P0)
        sm = rts_smooth(ref, F=F, Q=MODEL["Q"])
        want = (ref.means, ref.covs, ref.loglik, ref.last.mean, sm.means, sm.covs)
        for g, w in zip(got, want):
            np.testing.assert_array_equal(g[a:b], w)


def test_a_chunks_last_state_does_not_keep_its_means_alive():
    from vistrack.filters.chunked import _chunk_filter

    out = _chunk_filter(np.zeros((3, 5, 2)), np.zeros(4), np.eye(4), MODEL, False)
    assert out[5].base is None and out[6].base is None


def test_the_chunked_filter_checks_its_input():
    ys = da.zeros((10, 5, 2), chunks=(5, 5, 2))
    with pytest.raises(ValueError, match="x0 must be shared"):
        kalman_filter(ys, **MODEL, x0=np.zeros((3, 4)), P0=np.eye(4))
    with pytest.raises(ValueError, match=r"\(B, T, m\)"):
        kalman_filter(da.zeros((5, 2)), **MODEL, x0=np.zeros(4), P0=np.eye(4))
    lazy = kalman_filter(ys, **MODEL, x0=np.zeros(4), P0=np.eye(4), store_covs=False)
    with pytest.raises(ValueError, match="store_covs=True"):
        rts_smooth(lazy, F=F, Q=MODEL["Q"])


def test_vistrack_does_not_import_dask():
    code = ("import sys, numpy as np, vistrack, vistrack.filters as f, vistrack.batch;"
            "f.kalman_filter(np.zeros((3, 1)), F=np.eye(1), Q=np.eye(1), H=np.eye(1),"
            " R=np.eye(1), x0=[0.0], P0=np.eye(1));"
            "print(sorted(m for m in sys.modules if m.split('.')[0] in ('dask', 'distributed')))")
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True,
                         text=True).stdout.strip()
    assert out == "[]"


@pytest.fixture(scope="module")
def cluster():
    distributed = pytest.importorskip("distributed")
    import dask

    # one worker process; no dashboard (it would listen on every interface); no nanny
    # environment (its MALLOC_TRIM_THRESHOLD_ slows numpy's allocations)
    with dask.config.set({"distributed.nanny.pre-spawn-environ": {}}), \
            distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                     dashboard_address=None) as c:
        yield c


@pytest.mark.slow
def test_many_inputs_on_a_dask_cluster_give_what_each_gives_alone(bench, tmp_path, cluster):  # noqa: F811
    from distributed import Client

    from vistrack.batch import track_many
    from vistrack.cli import main

    with Client(cluster, set_as_default=False) as client:
        outcomes = track_many([bench], tmp_path / "out", executor=client.get_executor())
    assert [o.ok for o in outcomes] == [True, True, True]
    for o in outcomes:
        assert o.out.read_bytes() == _alone(o.input, tmp_path / f"{o.input.name}.txt")
    out = tmp_path / "cli"
    assert main(["track", str(bench), "--out", str(out), "--scheduler",
                 cluster.scheduler_address, "--quiet"]) == 0
    assert [p.read_bytes() for p in sorted(out.iterdir())] == \
        [o.out.read_bytes() for o in outcomes]
