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
    assert out[5].base is None and not np.shares_memory(out[6], out[0])
    assert out[6].shape == (3, 4, 4) and out[6].strides[0] == 0  # one covariance, shared


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
    # a model of 2 states and 1 measurement, whose filter comes compiled with vistrack
    code = ("import sys, numpy as np, vistrack, vistrack.filters as f, vistrack.batch;"
            "f.kalman_filter(np.zeros((3, 1)), F=np.eye(2), Q=np.eye(2), H=np.eye(1, 2),"
            " R=np.eye(1), x0=[0.0, 0.0], P0=np.eye(2));"
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
def test_many_inputs_on_a_dask_cluster_give_what_each_gives_alone(bench, tmp_path, cluster,  # noqa: F811
                                                                   capsys):
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
    capsys.readouterr()
    # and scored there: the table of one process
    tables = []
    for where in (["--scheduler", cluster.scheduler_address], ["--jobs", "1"]):
        assert main(["eval", "--gt-dir", str(bench), "--pred-dir", str(out), "--json",
                     *where]) == 0
        tables.append(capsys.readouterr().out)
    assert tables[0] == tables[1] and '"SIM-1"' in tables[0]
    assert main(["eval", "--gt-dir", str(bench), "--pred-dir", str(out), "--jobs", "2",
                 "--scheduler", cluster.scheduler_address]) == 2
    assert "--jobs goes with the local pool" in capsys.readouterr().err


@pytest.mark.slow
def test_a_scheduler_that_does_not_answer_is_one_line(bench, tmp_path, capsys):  # noqa: F811
    """--scheduler at an address where nothing listens: Dask's own 55-line traceback came
    after 30 s with the status of a bug (1); now one line naming the address, status 2."""
    pytest.importorskip("distributed")
    import socket

    from vistrack.cli import main

    with socket.socket() as s:  # a port free now, where nothing will listen
        s.bind(("127.0.0.1", 0))
        address = f"tcp://127.0.0.1:{s.getsockname()[1]}"
    for seq in bench.iterdir():  # each sequence's ground truth as its results
        (tmp_path / f"{seq.name}.txt").write_text((seq / "gt" / "gt.txt").read_text())
    assert main(["eval", "--gt-dir", str(bench), "--pred-dir", str(tmp_path),
                 "--scheduler", address]) == 2
    out, err = capsys.readouterr()
    assert out == "" and len(err.splitlines()) == 1
    assert err.startswith(f"vistrack eval: error: --scheduler {address}: no Dask scheduler "
                          "answers there (")


def _em_problem(B=30, T=80, missing=True):
    from vistrack.simulate import simulate_lgssm

    G = np.array([[0.5, 0], [0, 0.5], [1, 0], [0, 1]])
    truth = dict(F=F, Q=0.5 * G @ G.T, H=np.eye(2, 4), R=4 * np.eye(2), x0=np.zeros(4),
                 P0=np.eye(4))
    ys = np.stack([simulate_lgssm(T, rng=i, **truth)[1] for i in range(B)])
    if missing:
        rng = np.random.default_rng(0)
        ys[rng.random((B, T)) < 0.1] = np.nan  # missing steps
        ys[:, :, 1][rng.random((B, T)) < 0.1] = np.nan  # and missing components
    return ys


START = dict(F=F, Q=np.eye(4), H=np.eye(2, 4), R=np.eye(2), x0=np.zeros(4), P0=np.eye(4))


@pytest.mark.parametrize("kw", [
    dict(learn=("Q", "R")),
    dict(learn=("Q", "R"), Q_form="scaled", R_form="diag"),
    dict(learn=("F", "Q", "H", "R", "x0", "P0"), R_form="diag"),
    dict(learn=("x0", "P0", "Q")),
    dict(learn=("x0", "Q"), P0=np.stack([np.eye(4) * (1 + b) for b in range(30)])),
    dict(learn=("P0", "R"), x0=np.arange(120.0).reshape(30, 4) / 10),
])
def test_em_on_a_chunked_batch_equals_em_in_memory(kw):
    import dask

    from vistrack.filters import em

    ys = _em_problem()
    args = dict(START, max_iter=25, tol=-np.inf)
    args.update(kw)
    want = em(ys, **args)
    with dask.config.set(scheduler="threads"):
        got = em(da.from_array(ys, chunks=(7, 40, 2)), **args)
    # the same sums, added in another order: equal to rounding after 25 iterations
    for name in ("F", "Q", "H", "R", "x0", "P0", "loglik", "q", "r"):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-9,
                                   atol=1e-12, err_msg=name)
    assert got.iterations == want.iterations == 25
    assert np.all(np.diff(got.loglik) >= -1e-9)


@pytest.mark.parametrize("chunk", [1, 2, 3, 7])
def test_em_on_a_chunked_batch_with_a_series_never_measured_equals_em_in_memory(chunk):
    """``P0`` learned beside an ``x0`` given per series, one series never measured: a chunk
    of two or more took the measured series' first means less every series' ``x0`` (a
    wrong ``P0`` without a word at chunks of 2, numpy's broadcast error at 3). The oracle:
    em in memory, which leaves that series out (its prior says nothing)."""
    import dask

    from vistrack.filters import em

    ys = _em_problem()
    ys[1] = np.nan
    args = dict(START, learn=("P0", "R"), max_iter=5, tol=-np.inf,
                x0=np.arange(120.0).reshape(30, 4) / 10)
    want = em(ys, **args)
    with dask.config.set(scheduler="synchronous"):
        got = em(da.from_array(ys, chunks=(chunk, 40, 2)), **args)
    for name in ("P0", "R", "loglik"):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-9,
                                   atol=1e-12, err_msg=name)


def test_em_on_a_chunked_batch_returns_a_shared_dask_prior_learned_as_numpy():
    """A shared prior given as Dask arrays and learned came back as Dask arrays (their
    graphs one iteration longer at each), against the documented numpy parameters."""
    import dask

    from vistrack.filters import em

    ys = _em_problem()
    args = dict(START, learn=("x0", "P0", "Q"), max_iter=5, tol=-np.inf)
    want = em(ys, **args)
    with dask.config.set(scheduler="synchronous"):
        got = em(da.from_array(ys, chunks=(7, 40, 2)),
                 **dict(args, x0=da.zeros(4), P0=da.from_array(np.eye(4))))
    for name in ("x0", "P0", "Q"):
        assert type(getattr(got, name)) is np.ndarray, name
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-9,
                                   atol=1e-12, err_msg=name)


def test_em_on_a_chunked_batch_of_padded_series_equals_em_in_memory():
    """Series of unequal length, padded with missing steps: each chunk leaves its series'
    padding out of ``Q``'s M-step and counts the transitions it keeps, as in memory."""
    import dask

    from vistrack.filters import em

    ys = _em_problem(B=12, T=60, missing=False)
    for b in range(12):
        ys[b, 10 + 4 * b:] = np.nan
    args = dict(START, learn=("F", "Q", "R"), max_iter=15, tol=-np.inf)
    want = em(ys, **args)
    with dask.config.set(scheduler="threads"):
        got = em(da.from_array(ys, chunks=(5, 60, 2)), **args)
    for name in ("F", "Q", "R", "loglik"):
        np.testing.assert_allclose(getattr(got, name), getattr(want, name), rtol=1e-9,
                                   atol=1e-12, err_msg=name)


@pytest.mark.parametrize("per_series_prior", [False, True])
def test_em_one_fit_per_series_on_a_chunked_batch_is_lazy_and_equal_chunk_by_chunk(
        per_series_prior):
    import dask

    from vistrack.filters import em

    ys = _em_problem(B=9, T=40)
    args = dict(START, learn=("Q", "R", "x0"), R_form="diag", max_iter=60, tol=1e-2,
                pooled=False)
    if per_series_prior:
        args["x0"] = np.arange(36.0).reshape(9, 4)
    want = em(ys, **args)
    lazy = em(da.from_array(ys, chunks=(4, 40, 2)), **args)
    assert isinstance(lazy.Q, da.Array) and lazy.Q.chunks[0] == (4, 4, 1)
    names = ("F", "Q", "H", "R", "x0", "P0", "q", "r", "loglik", "iterations", "converged")
    got = dask.compute(*(getattr(lazy, k) for k in names), scheduler="threads")
    assert want.iterations.min() < want.iterations.max()  # series stop apart
    for name, g in zip(names, got):
        w = np.asarray(getattr(want, name))
        if name == "loglik":  # padded to max_iter + 1 lazily, to the longest fit in memory
            assert np.isnan(g[:, w.shape[1]:]).all()
            g = g[:, :w.shape[1]]
        assert g.dtype == w.dtype and g.shape == w.shape, name
        np.testing.assert_array_equal(g, w, err_msg=name)


def test_em_on_a_chunked_batch_checks_its_input():
    from vistrack.filters import em

    ys = _em_problem(B=6, T=10)
    chunked = da.from_array(ys, chunks=(3, 10, 2))
    with pytest.raises(ValueError, match="learning x0 pooled on a Dask array needs one x0"):
        em(chunked, **dict(START, x0=np.zeros((6, 4))), learn=("x0",))
    with pytest.raises(ValueError, match="progress is not available"):
        em(chunked, **START, pooled=False, progress=sys.stderr)
    bad = ys.copy()
    bad[4, 2, 1] = np.inf
    with pytest.raises(ValueError, match=r"ys\[4, 2, 1\] = inf"):
        em(da.from_array(bad, chunks=(3, 10, 2)), **START)
    with pytest.raises(ValueError, match="no measurement"):
        em(da.full((4, 5, 2), np.nan, chunks=(2, 5, 2)), **START)
    with pytest.raises(ValueError, match="at least 2 steps"):
        em(chunked[:, :1], **START)
    with pytest.raises(ValueError, match="max_iter"):
        em(chunked, **START, max_iter=0)
    missing_one = ys.copy()
    missing_one[:, :, 1] = np.nan
    with pytest.raises(ValueError, match="component 1 of ys is never measured"):
        em(da.from_array(missing_one, chunks=(3, 10, 2)), **START, learn=("H",))


@pytest.mark.slow
def test_a_dask_worker_killed_mid_job_is_replaced_and_the_outputs_are_complete(tmp_path):
    import os
    import signal
    import threading
    import time

    distributed = pytest.importorskip("distributed")
    import dask

    from tests.test_fit import _sequence
    from vistrack.batch import track_many

    rng = np.random.default_rng(8)
    seqs = [_sequence(tmp_path / "in" / f"LONG-{k}", rng, n_objects=400, T=150,
                      std=(0.002, 0.00005)) for k in range(3)]
    out = tmp_path / "out"
    killed: list[int] = []
    with dask.config.set({"distributed.nanny.pre-spawn-environ": {}}), \
            distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                     dashboard_address=None) as cluster, \
            distributed.Client(cluster, set_as_default=False) as client:
        pids = list(client.run(os.getpid).values())

        def killer():
            # once a job is writing its results (both workers busy), kill one worker
            deadline = time.monotonic() + 120
            while time.monotonic() < deadline and not killed:
                if out.exists() and any(p.name.startswith(".") for p in out.iterdir()):
                    os.kill(pids[0], signal.SIGKILL)
                    killed.append(pids[0])
                time.sleep(0.01)

        thread = threading.Thread(target=killer)
        thread.start()
        outcomes = track_many(seqs, out, executor=client.get_executor())
        killed.append(0)  # (stops the thread if it saw nothing)
        thread.join()
        killed.pop()
        after = list(client.run(os.getpid).values())
        # the scheduler ran some job twice: on the worker killed, then on another
        starts: dict = {}
        for key, _, finish, *_ in cluster.scheduler.transition_log:
            if finish == "processing":
                starts[key] = starts.get(key, 0) + 1
    assert killed, "no worker was seen running a job"
    assert pids[0] not in after and len(after) == 2  # the nanny started a new worker
    assert len(starts) == 3 and max(starts.values()) == 2, starts
    assert all(o.ok for o in outcomes), [o.error for o in outcomes]
    for o in outcomes:
        assert o.out.read_bytes() == _alone(o.input, tmp_path / f"{o.input.name}.txt")
    assert not [p for p in out.iterdir() if p.name.startswith(".")]  # no partial file left


def test_em_on_dask_names_a_malformed_f_as_in_memory():
    """em on a Dask array fitted chunk by chunk checked the model against F's own size, so a
    3 x 3 F for a 4-state prior was reported as Q's shape; it is named as F, as em names it
    on a numpy array."""
    from vistrack.filters import em

    rng = np.random.default_rng(0)
    ys = rng.normal(size=(4, 20, 2))
    model = dict(F=np.eye(3), Q=np.eye(4), H=np.eye(2, 4), R=np.eye(2), x0=np.zeros(4),
                 P0=np.eye(4))
    match = r"F must have shape \(4, 4\) or \(T=20, 4, 4\); got \(3, 3\)"
    with pytest.raises(ValueError, match=match):
        em(ys, **model, max_iter=2)
    with pytest.raises(ValueError, match=match):
        em(da.from_array(ys, chunks=(2, 20, 2)), **model, max_iter=2)


@pytest.mark.parametrize("learn", [("Q", "R"), ("F", "Q", "R")])
def test_em_on_a_chunked_batch_learns_q_far_from_the_origin_as_in_memory(learn):
    """A state a million units from the origin (UTM coordinates, say): the chunks' sums of
    ``Q``'s M-step are added term by term, as in memory, so the fit equals the in-memory one
    there, and with ``F`` as given (translation invariant) the fit near the origin. From the
    transition sums, whose terms cancel there, ``Q`` was 20 % off at 1e6."""
    import dask

    from vistrack.filters import em

    rng = np.random.default_rng(4)
    B, T, F1 = 40, 200, np.array([[1, 1.0], [0, 1]])
    X = np.zeros((B, T, 2))
    X[:, 0] = [0.0, 3.0]
    for t in range(1, T):
        X[:, t] = X[:, t - 1] @ F1.T + rng.normal(size=(B, 2)) * 1e-2
    ys = X[..., :1] + rng.normal(size=(B, T, 1)) * 0.5
    start = dict(F=F1, Q=1e-3 * np.eye(2), H=np.array([[1.0, 0]]), R=[[1.0]], P0=np.eye(2))
    # F is learned from sums about the origin, which lose digits far from it, in memory as
    # here (a regression through the origin): 1e4 there, where the old Q was already off by
    # more than this test allows
    off = 1e4 if "F" in learn else 1e6
    args = dict(start, x0=[off, 3.0], learn=learn, max_iter=10, tol=-np.inf)
    in_memory = em(ys + off, **args)
    with dask.config.set(scheduler="synchronous"):
        far = em(da.from_array(ys + off, chunks=(10, T, 1)), **args)
    for name in ("F", "Q", "R"):
        want = getattr(in_memory, name)
        np.testing.assert_allclose(getattr(far, name), want, rtol=1e-7 if name == "F" else 0,
                                   atol=1e-8 * np.abs(want).max(), err_msg=name)
    if "F" not in learn:
        near = em(ys, **dict(args, x0=[0.0, 3.0]))
        np.testing.assert_allclose(far.Q, near.Q, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(far.R, near.R, rtol=1e-9)


def test_em_one_fit_per_series_on_a_chunked_batch_checks_as_in_memory():
    """``pooled=False``: a model em refuses is refused at once (it was fitted, and its
    log-likelihood fell; a zero "scaled" Q raised ZeroDivisionError when computed), and a
    series' own fault when its chunk is computed, naming the series in the batch."""
    import dask

    from vistrack.filters import em

    rng = np.random.default_rng(1)
    ys = rng.normal(size=(4, 20, 2)).cumsum(axis=1)
    chunked = da.from_array(ys, chunks=(2, 20, 2))
    per_step = dict(START, Q=np.stack([np.eye(4) * (1 + t % 2) for t in range(20)]))
    for model in (ys, chunked):
        with pytest.raises(ValueError, match="learning F needs one Q for all steps"):
            em(model, **per_step, learn=("F",), pooled=False)
        with pytest.raises(ValueError, match=r"Q must not be zero to learn its factor"):
            em(model, **dict(START, Q=np.zeros((4, 4))), learn=("Q",), Q_form="scaled",
               pooled=False)
    ys[3, :, 1] = np.nan
    lazy = em(da.from_array(ys, chunks=(2, 20, 2)), **START, learn=("H",), pooled=False,
              max_iter=3)
    with pytest.raises(ValueError, match=r"series 3 of ys \(pooled=False\): component 1 of "
                       "ys is never measured"):
        dask.compute(lazy.H, scheduler="synchronous")


def test_the_chunked_filter_takes_a_prior_with_a_batch_axis_of_one():
    """``x0 (1, n)`` and ``P0 (1, n, n)``: one prior for every series, as the in-memory filter
    and em take it (it was refused as a prior per series of the wrong batch)."""
    ys = np.random.default_rng(2).normal(size=(4, 6, 2))
    x0, P0 = np.arange(4.0)[None], np.eye(4)[None]
    lazy = kalman_filter(da.from_array(ys, chunks=(2, 6, 2)), **MODEL, x0=x0, P0=P0)
    want = kalman_filter(ys, **MODEL, x0=x0, P0=P0)
    np.testing.assert_array_equal(lazy.means.compute(scheduler="synchronous"), want.means)


def test_empty_and_unknown_chunks_and_errors_by_place_in_the_batch():
    """A chunk of no series (a selection's, after `compute_chunk_sizes`) failed with an
    IndexError; unknown chunk sizes (a boolean selection's) with "cannot convert float NaN
    to integer"; an infinite measurement in the second chunk was named by its place in the
    chunk (ys[1, ...] for ys[3, ...]) and an x0 of the wrong size with the chunk's B. Oracle:
    the in-memory filter's own results and messages."""
    import re

    rng = np.random.default_rng(0)
    F, H, R, Q = np.array([[1.0, 1.0], [0.0, 1.0]]), np.eye(1, 2), [[0.5]], np.diag([0.0, 0.1])
    y = rng.normal(size=(4, 6, 1))
    model = dict(F=F, Q=Q, H=H, R=R, x0=np.zeros(2), P0=np.eye(2))
    want = rts_smooth(kalman_filter(y, **model), F=F, Q=Q).means
    keep = np.array([True, True, False, True])
    picked = da.from_array(y, chunks=(2, 6, 1))[da.from_array(keep, chunks=2)]
    with pytest.raises(ValueError, match=re.escape(
            "ys has chunks of unknown size (a boolean selection's): call "
            "ys.compute_chunk_sizes() first")):
        kalman_filter(picked, **model)
    empty = da.from_array(y, chunks=((4, 0), -1, -1))  # (as a selection can leave them)
    got = rts_smooth(kalman_filter(empty, **model), F=F, Q=Q).means.compute()
    np.testing.assert_allclose(got, want, rtol=0, atol=1e-12)
    bad = y.copy()
    bad[3, 2, 0] = np.inf
    for ys in (bad, da.from_array(bad, chunks=(2, 6, 1))):
        with pytest.raises(ValueError, match=re.escape(
                "ys must be finite or NaN (missing); ys[3, 2, 0] = inf")):
            kalman_filter(ys, **model).means.compute() if not isinstance(ys, np.ndarray) \
                else kalman_filter(ys, **model)
    with pytest.raises(ValueError, match=re.escape("(B=4, 2)")):
        kalman_filter(da.from_array(y, chunks=(2, 6, 1)), **(model | {"x0": np.zeros((4, 3))}))


def test_a_masked_dask_array_is_missing_where_masked_and_priors_are_named_by_batch_place():
    """A masked Dask array's blocks were read with ``np.asarray``, which keeps the values
    under the mask: a placeholder of -999 was filtered as a measurement (mean -745 where the
    in-memory filter gives 2.6) and pooled EM learned R = 41,590 for 0.2. A bad per-series
    P0 was named by its place in its chunk (matrix [1] for [5]), and only once computed.
    Oracle: the in-memory filter and EM on the same masked array, and their messages."""
    import re

    from vistrack.filters import em

    rng = np.random.default_rng(0)
    F1 = np.array([[1.0, 1.0], [0.0, 1.0]])
    model = dict(F=F1, Q=np.diag([0.01, 0.1]), H=np.eye(1, 2), R=[[0.5]], x0=np.zeros(2),
                 P0=np.eye(2))
    y = rng.normal(size=(4, 6, 1)).cumsum(1)
    mask = np.zeros_like(y, bool)
    mask[1, 2, 0] = mask[3, 0, 0] = True
    ym = np.ma.masked_array(np.where(mask, -999.0, y), mask=mask)
    lazy = da.from_array(ym, chunks=(2, 6, 1), asarray=False)
    want = kalman_filter(ym, **model)
    np.testing.assert_allclose(kalman_filter(lazy, **model).means.compute(), want.means,
                               rtol=0, atol=1e-12)
    fit = dict(learn=("R",), max_iter=3, tol=-np.inf)
    np.testing.assert_allclose(em(lazy, **model, **fit).R, em(ym, **model, **fit).R,
                               rtol=1e-10)
    np.testing.assert_allclose(em(lazy, **model, **fit, pooled=False).R.compute(),
                               em(ym, **model, **fit, pooled=False).R, rtol=1e-10)
    ys = rng.normal(size=(6, 20, 1)).cumsum(1)
    P0 = np.stack([np.eye(2)] * 5 + [np.diag([1.0, -1.0])])
    bad = model | {"P0": P0}
    said = "P0 must be positive semi-definite (matrix [5]); P0[1, 1] = -1, a negative variance"
    with pytest.raises(ValueError, match=re.escape(said)):
        em(ys, **bad, max_iter=2)  # the oracle's words
    chunked = da.from_array(ys, chunks=(4, 20, 1))
    for call in (lambda: em(chunked, **bad, max_iter=2),
                 lambda: em(chunked, **bad, max_iter=2, pooled=False),  # (lazy: at once)
                 lambda: kalman_filter(chunked, **bad)):
        with pytest.raises(ValueError, match=re.escape(said)):
            call()
