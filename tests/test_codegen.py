"""The batch kernels generated per model structure (vistrack.filters._codegen).

Large per-series batches run these; the tests lower the size threshold so that small batches
do too, and check them against FilterPy and against the loop kernel.
"""

import os
import re
import stat
import tempfile
import threading
import warnings
from pathlib import Path

import numpy as np
import pytest

import vistrack as vt
from vistrack.filters import _codegen, kalman_filter, kalman_filter_1d

from .conftest import random_model
from .test_kalman import filterpy_run, with_missing


@pytest.fixture
def generated(monkeypatch):
    """Every per-series batch runs a generated kernel; yields the list of patterns used."""
    used = []
    make = _codegen.batch_kernel

    def spy(*key):
        used.append(key)
        return make(*key)

    monkeypatch.setattr(_codegen, "MIN_STEPS", 0)
    monkeypatch.setattr(_codegen, "batch_kernel", spy)
    return used


def loop_kernel(monkeypatch):
    monkeypatch.setattr(_codegen, "MIN_STEPS", 1 << 62)


def cv_model(dt):
    motion, meas = vt.ConstantVelocity(dim=2, q=0.5), vt.Position(dim=2, r=0.3)
    return dict(F=motion.F(dt), Q=motion.Q(dt), H=meas.H(4), R=meas.R())


@pytest.mark.parametrize("case", ["constant velocity", "dense, time-varying"])
def test_generated_kernel_equals_filterpy(rng, generated, case):
    B, T = 130, 25  # more than one chunk of 128 series, and not a multiple of it
    if case == "constant velocity":
        mod = cv_model(0.5)
    else:
        mod = random_model(rng, 3, 2, T, tv=True)
    n = mod["H"].shape[-1]
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), n_series=B, rng=rng)
    ys = with_missing(rng, ys)  # rows and single components, different in every series
    x0 = rng.normal(size=(B, n))
    A = rng.normal(size=(B, n, n))
    P0 = A @ np.swapaxes(A, 1, 2) + np.eye(n)
    res = kalman_filter(ys, **mod, x0=x0, P0=P0)
    assert len(generated) == 1 and not res.shared_covs
    codes = generated[0][2:]
    if case == "constant velocity":  # the structure is in the code: zeros, ones, dt
        assert codes[0] == ((1, 0, 2, 0), (0, 1, 0, 2), (0, 0, 1, 0), (0, 0, 0, 1))
        assert codes[2] == ((1, 0, 0, 0), (0, 1, 0, 0))
    else:
        assert all(c == 2 for rows in codes for row in rows for c in row)
    for b in (0, 77, 128, B - 1):
        fm, fP, fll = filterpy_run(ys[b], **mod, x0=x0[b], P0=P0[b])
        np.testing.assert_allclose(res.means[b], fm, rtol=1e-9, atol=1e-10)
        np.testing.assert_allclose(res.covs[b], fP, rtol=1e-9, atol=1e-10)
        assert res.loglik[b] == pytest.approx(fll, rel=1e-10)
        np.testing.assert_array_equal(res.last.cov[b], res.covs[b, -1])
    assert np.array_equal(res.covs, np.swapaxes(res.covs, -1, -2))


def test_steady_state_phase_equals_filterpy(rng, generated):
    """Fully observed constant models converge to a steady state, where only the means move;
    a missing component in any series of a chunk leaves it until P converges again."""
    B, T = 130, 300
    mod = cv_model(0.5)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(4), n_series=B, rng=rng)
    ys[7, 150, 1] = np.nan  # chunk 0 leaves the steady state at step 150
    x0 = rng.normal(size=(B, 4))
    P0 = (1.0 + rng.random(B))[:, None, None] * np.eye(4)
    res = kalman_filter(ys, **mod, x0=x0, P0=P0)
    assert generated
    for b in (0, 7, 129):
        fm, fP, fll = filterpy_run(ys[b], **mod, x0=x0[b], P0=P0[b])
        np.testing.assert_allclose(res.means[b], fm, rtol=1e-9, atol=1e-10)
        np.testing.assert_allclose(res.covs[b], fP, rtol=1e-9, atol=1e-12)
        F, Q = mod["F"], mod["Q"]
        pred = F @ fP[:-1] @ F.T + Q
        np.testing.assert_allclose(res.pred_covs[b, 1:], pred, rtol=1e-9, atol=1e-12)
        assert res.loglik[b] == pytest.approx(fll, rel=1e-10)
    # frozen: the covariance is bitwise constant over the steady steps
    assert np.array_equal(res.covs[129, 100], res.covs[129, -1])
    assert np.array_equal(res.covs[0, 100], res.covs[0, 149])
    assert not np.array_equal(res.covs[7, 149], res.covs[7, 150])


@pytest.mark.parametrize("store_covs", [True, False])
def test_generated_kernel_equals_loop_kernel(rng, monkeypatch, generated, store_covs):
    B, T = 40, 30
    mod = cv_model(0.1)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(4), n_series=B, rng=rng)
    ys = with_missing(rng, ys)
    x0, P0 = rng.normal(size=(B, 4)), np.broadcast_to(3.0 * np.eye(4), (B, 4, 4))
    gen = kalman_filter(ys, **mod, x0=x0, P0=P0, store_covs=store_covs)
    loop_kernel(monkeypatch)
    ref = kalman_filter(ys, **mod, x0=x0, P0=P0, store_covs=store_covs)
    assert len(generated) == 1
    for name in ("means", "covs", "pred_means", "pred_covs", "loglik"):
        a, b = getattr(gen, name), getattr(ref, name)
        if store_covs:
            np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-12, err_msg=name)
        elif name != "means" and name != "loglik":
            assert a is None and b is None
    np.testing.assert_allclose(gen.last.cov, ref.last.cov, rtol=1e-12, atol=1e-13)
    # the first step has no prediction: its predicted moments are the prior
    if store_covs:
        np.testing.assert_array_equal(gen.pred_means[:, 0], x0)
        np.testing.assert_array_equal(gen.pred_covs[:, 0], P0)


@pytest.mark.parametrize("scale", [1e-70, 1e70])
def test_loglik_is_exact_when_determinants_leave_the_float_range(
    rng, monkeypatch, generated, scale
):
    """The log-determinant is summed as a running product with rescaling; with innovation
    standard deviations of 1e±70 the product of a few steps would overflow or underflow."""
    B, T = 9, 200
    mod = random_model(rng, 3, 2)
    F = 0.95 * mod["F"] / np.abs(np.linalg.eigvals(mod["F"])).max()  # stable over 200 steps
    mod = dict(mod, F=F, Q=mod["Q"] * scale**2, R=mod["R"] * scale**2)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(3), n_series=B, rng=rng)
    ys = with_missing(rng, ys)
    P0 = np.broadcast_to(scale**2 * np.eye(3), (B, 3, 3))
    gen = kalman_filter(ys, **mod, x0=np.zeros(3), P0=P0, store_covs=False)
    assert generated
    loop_kernel(monkeypatch)
    ref = kalman_filter(ys, **mod, x0=np.zeros(3), P0=P0, store_covs=False)
    assert np.all(np.abs(gen.loglik) > 1e4)  # 2 T log(scale) dominates
    np.testing.assert_allclose(gen.loglik, ref.loglik, rtol=1e-12)
    fm, _, fll = filterpy_run(ys[4], **mod, x0=np.zeros(3), P0=P0[4])
    assert gen.loglik[4] == pytest.approx(fll, rel=1e-10)


def test_generated_kernel_reports_the_first_bad_step(generated):
    F, Q = np.eye(2), np.zeros((2, 2))
    H, R = np.eye(2), np.diag([1.0, 0.0])
    ys = np.ones((3, 4, 2))
    ys[:, :2, 1] = np.nan  # the zero-variance component is missing at steps 0 and 1 only
    ys[0, 2, 1] = np.nan  # ... and at step 2 of series 0, whose S is then positive definite
    P0 = np.broadcast_to(np.diag([1.0, 0.0]), (3, 2, 2))
    with pytest.raises(ValueError, match="not positive definite at step 2 of series 1;"):
        kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=np.zeros(2), P0=P0)
    assert generated


def test_kernel_source_is_cached_in_the_cache_directory(tmp_path, monkeypatch):
    monkeypatch.setenv("VISTRACK_CACHE_DIR", str(tmp_path))
    codes = (((2,),), ((2,),), ((1,),), ((2,),))
    _codegen.batch_kernel.cache_clear()
    try:
        kernel = _codegen.batch_kernel(1, 1, *codes)
    finally:
        _codegen.batch_kernel.cache_clear()  # later calls use the default directory again
    (path,) = tmp_path.glob("vistrack_kf_1_1_*.py")
    assert path.read_text() == _codegen.source(1, 1, *codes)
    ys = np.array([[[1.0], [np.nan], [3.0]]])
    out = [np.empty((1, 3, 1)), np.empty((1, 3, 1, 1)), np.empty((1, 3, 1)), np.empty((1, 3, 1, 1))]
    loglik, last = np.empty(1), np.empty((1, 1, 1))
    one = np.ones((1, 1, 1))
    assert kernel(ys, one, one, one, one, np.zeros((1, 1)), one, *out, loglik, last, True) == -1
    # the oracle: the seeds' scalar equations, and the Gaussian density of each measurement
    ref = kalman_filter_1d(ys[0, :, 0], d=1.0, m=1.0, sigma_d=1.0, sigma_m=1.0, x0=0.0,
                           sigma0=1.0)
    np.testing.assert_allclose(out[0][0, :, 0], ref.mean, rtol=1e-14)
    seen = ~np.isnan(ys[0, :, 0])
    s2 = ref.pred_std[seen] ** 2 + 1.0
    ll = -0.5 * np.sum(np.log(2 * np.pi * s2) + (ys[0, seen, 0] - ref.pred_mean[seen]) ** 2 / s2)
    assert loglik[0] == pytest.approx(ll, rel=1e-14)
    # a source file damaged into bytes that are not UTF-8 is rewritten (its reading raised
    # UnicodeDecodeError, which stopped the filter)
    damaged = bytearray(path.read_bytes())
    damaged[100:102] = b"\xff\xfe"
    path.write_bytes(bytes(damaged))
    _codegen.batch_kernel.cache_clear()
    try:
        _codegen.batch_kernel(1, 1, *codes)
    finally:
        _codegen.batch_kernel.cache_clear()
    assert path.read_text(encoding="utf-8") == _codegen.source(1, 1, *codes)


def test_small_or_large_models_use_the_loop_kernel():
    assert _codegen.worth_it(4, 2, 10_000 * 500)
    assert not _codegen.worth_it(4, 2, 1000)  # a new pattern's compilation would not pay
    assert not _codegen.worth_it(9, 3, 10_000 * 500)  # code and compile time grow as n² m


@pytest.mark.parametrize("n,m", [(1, 1), (2, 1), (4, 2), (6, 3)])
def test_work_rows_fill_the_flat_array_without_overlap(n, m):
    """Every work row of a generated kernel is a row of W; the rows tile W exactly."""
    dense = (((2,) * n,) * n, ((2,) * n,) * n, ((2,) * n,) * m, ((2,) * m,) * m)
    src = _codegen.source(n, m, *dense)
    assert not re.search(r"\b(X|PP|XP|PPP|Y|KL|D|DS|LL)\[", src)
    layout = _codegen._Layout(n, m)
    nt = n * (n + 1) // 2
    sizes = {"X": n, "PP": nt, "XP": n, "PPP": nt, "Y": m, "D": 1, "DS": 1, "LL": 1,
             "KL": n * m + m * (m + 1) // 2}
    starts = sorted((layout.offsets[k], sizes[k]) for k in sizes)
    assert starts[0][0] == 0
    assert all(a + s == b for (a, s), (b, _) in zip(starts, starts[1:]))
    total = starts[-1][0] + starts[-1][1]
    assert f"W = np.empty({total * _codegen.CH})" in src


# ------------------------------------------------- the kernel folder: private, checked before use
SRC = "VALUE = 41 + 1\n"  # a module to load (no kernel: these tests are about the folder)


@pytest.fixture
def folders(tmp_path, monkeypatch):
    """Every folder the cache may choose, under tmp_path: the configured one is ``cache``, the
    temporary directory ``tmp`` (its shared fallback ``tmp/vistrack-kernels-{uid}``), and the
    process's private folder is made afresh."""
    (tmp_path / "tmp").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    monkeypatch.setattr(_codegen, "_PRIVATE_DIR", [])
    monkeypatch.delenv("XDG_CACHE_HOME", raising=False)
    monkeypatch.setenv("VISTRACK_CACHE_DIR", str(tmp_path / "cache"))
    return tmp_path / "cache", tmp_path / "tmp" / f"vistrack-kernels-{os.getuid()}"


def _load_where():
    """Load SRC; the folder its source file went to."""
    module = _codegen.load("vistrack_foldertest", SRC)
    assert module.VALUE == 42
    return {p.parent for p in Path(tempfile.gettempdir()).parent.rglob("vistrack_foldertest_*.py")}


def _mode(d):
    return stat.S_IMODE(os.lstat(d).st_mode)


def test_a_new_cache_folder_is_private(folders):
    cache, _ = folders
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _load_where() == {cache}
    assert _mode(cache) == 0o700
    assert not list(cache.glob("*.tmp"))


@pytest.mark.parametrize("env", ["XDG_CACHE_HOME", "HOME"])
def test_the_cache_folder_follows_xdg_cache_home_then_home(tmp_path, monkeypatch, folders, env):
    monkeypatch.delenv("VISTRACK_CACHE_DIR")
    monkeypatch.setenv(env, str(tmp_path / "home"))
    want = tmp_path / "home" / ("" if env == "XDG_CACHE_HOME" else ".cache") / "vistrack/kernels"
    assert _load_where() == {want}
    assert _mode(want) == 0o700


def test_an_existing_private_folder_of_the_user_is_used(folders):
    cache, _ = folders
    cache.mkdir(mode=0o755)
    os.chmod(cache, 0o755)  # written by others: no; read by others: harmless
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert _load_where() == {cache}


def _refused(d, why, then):
    return re.escape(f"vistrack does not use the kernel folder {d}: {why}; {then}") + "$"


@pytest.mark.parametrize("mode", [0o777, 0o775, 0o757])
def test_a_folder_others_may_write_to_is_refused(folders, mode):
    cache, shared = folders
    cache.mkdir()
    os.chmod(cache, mode)
    with pytest.warns(RuntimeWarning, match=_refused(
            cache, f"others may write to it (mode {mode:#o})", f"it tries {shared}")):
        assert _load_where() == {shared}
    assert _mode(shared) == 0o700
    assert not list(cache.iterdir())


def test_a_symbolic_link_is_refused(folders, tmp_path):
    cache, shared = folders
    (tmp_path / "elsewhere").mkdir(mode=0o700)
    cache.symlink_to(tmp_path / "elsewhere")
    with pytest.warns(RuntimeWarning, match=_refused(
            cache, "it is a symbolic link", f"it tries {shared}")):
        assert _load_where() == {shared}
    assert not list((tmp_path / "elsewhere").iterdir())


def test_a_file_is_refused(folders):
    cache, shared = folders
    cache.write_text("not a folder")
    with pytest.warns(RuntimeWarning, match=_refused(
            cache, "it is not a directory", f"it tries {shared}")):
        assert _load_where() == {shared}


@pytest.mark.skipif(not hasattr(os, "getuid") or os.getuid() != 0,
                    reason="giving a folder to another user (os.chown) needs root; "
                           "test_a_folder_of_another_user_is_refused_by_uid covers the check")
def test_a_folder_of_another_user_is_refused(folders):
    """The attack: another local user creates the shared temporary folder first."""
    cache, shared = folders
    os.chmod(cache.parent, 0o755)
    cache.write_text("")  # the configured folder is unusable, so the shared one is tried
    shared.mkdir(mode=0o700)
    os.chown(shared, 65534, 65534)
    with pytest.warns(RuntimeWarning) as record:
        found = _load_where()
    assert re.match(_refused(shared, "it belongs to user id 65534, not to this user (0)",
                             "it uses a new temporary folder for this process instead"),
                    str(record[-1].message))
    assert found == {_codegen._PRIVATE_DIR[0]}
    assert _mode(_codegen._PRIVATE_DIR[0]) == 0o700
    assert not list(shared.iterdir())


def test_a_folder_of_another_user_is_refused_by_uid(folders, monkeypatch):
    cache, shared = folders
    cache.mkdir(mode=0o700)
    me = os.getuid()
    monkeypatch.setattr(_codegen, "_uid", lambda: me + 1)  # as if the folder were another's
    # (and the folders above it too, unless this user is root: those are the next tests')
    monkeypatch.setattr(_codegen, "_unsafe_parents", lambda d: None)
    shared = shared.parent / f"vistrack-kernels-{me + 1}"  # (named after the uid)
    with pytest.warns(RuntimeWarning) as record:
        found = _load_where()
    assert [str(w.message) for w in record] == [
        f"vistrack does not use the kernel folder {d}: it belongs to user id {me}, not to this "
        f"user ({me + 1}); " + then for d, then in (
            (cache, f"it tries {shared}"),
            (shared, "it uses a new temporary folder for this process instead"))]
    assert found == {_codegen._PRIVATE_DIR[0]}


def test_when_both_folders_are_refused_the_process_gets_its_own(folders):
    cache, shared = folders
    for d in (cache, shared):
        d.mkdir()
        os.chmod(d, 0o777)
    with pytest.warns(RuntimeWarning) as record:
        found = _load_where()
    assert [str(w.message) for w in record] == [
        f"vistrack does not use the kernel folder {cache}: others may write to it (mode 0o777); "
        f"it tries {shared}",
        f"vistrack does not use the kernel folder {shared}: others may write to it (mode "
        "0o777); it uses a new temporary folder for this process instead",
    ]
    (private,) = found
    assert private == _codegen._PRIVATE_DIR[0] and _mode(private) == 0o700
    assert private.parent == Path(tempfile.gettempdir())


# ------------------------------- the folders above it: no one else may replace the kernel folder
def _open_to_all(folder, mode=0o777):
    folder.mkdir()
    os.chmod(folder, mode)  # (mkdir's mode is cut by the umask)
    return folder


def _someone_could_swap(folder):
    return (f"others may write to {folder}, a folder above it (mode "
            f"{_mode(folder):#o}, no sticky bit), and put another folder in its place; "
            f"'chmod go-w {folder}' makes it safe")


@pytest.mark.parametrize("mode", [0o777, 0o775, 0o757, 0o730])
def test_a_folder_above_that_others_may_write_to_is_refused(folders, tmp_path, monkeypatch,
                                                            mode):
    """Group or others could rename the folder that holds the cache and put their own there:
    refused before anything is made under it (by mode bits: whoever runs the tests)."""
    _, shared = folders
    above = _open_to_all(tmp_path / "open", mode)
    cache = above / "sub" / "kernels"
    monkeypatch.setenv("VISTRACK_CACHE_DIR", str(cache))
    with pytest.warns(RuntimeWarning, match=_refused(cache, _someone_could_swap(above),
                                                     f"it tries {shared}")):
        assert _load_where() == {shared}
    assert not list(above.iterdir())


def test_a_folder_above_with_the_sticky_bit_is_safe_as_tmp_is(folders, tmp_path, monkeypatch):
    """Mode 1777 (/tmp): only an entry's owner may rename or delete it. The folders made
    below it are private, whatever the umask (with 002 they were 775 once)."""
    above = _open_to_all(tmp_path / "shared", 0o1777)
    cache = above / "me" / "cache" / "kernels"
    monkeypatch.setenv("VISTRACK_CACHE_DIR", str(cache))
    umask = os.umask(0o002)
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("error")
            assert _load_where() == {cache}
    finally:
        os.umask(umask)
    assert [_mode(d) for d in (cache, cache.parent, cache.parent.parent)] == [0o700] * 3


def test_a_folder_above_of_another_user_is_refused(folders, tmp_path, monkeypatch):
    above = tmp_path / "theirs"
    above.mkdir()
    os.chmod(above, 0o755)
    cache = above / "kernels"
    monkeypatch.setenv("VISTRACK_CACHE_DIR", str(cache))
    me = os.getuid()
    if me == 0:  # root owns every folder of tmp_path: give this one away
        os.chown(above, 65534, -1)
        owner, shared = 65534, folders[1]
    else:  # as if this user were another, whose folders these are not
        monkeypatch.setattr(_codegen, "_uid", lambda: me + 1)
        owner, shared = me, folders[1].parent / f"vistrack-kernels-{me + 1}"
    with pytest.warns(RuntimeWarning) as record:
        _load_where()
    assert str(record[0].message) == (
        f"vistrack does not use the kernel folder {cache}: {above}, a folder above it, belongs "
        f"to user id {owner}, neither this user ({_codegen._uid()}) nor root; set "
        f"VISTRACK_CACHE_DIR to a folder of your own; it tries {shared}")
    assert not cache.exists()


def test_folders_above_are_checked_through_symbolic_links(folders, tmp_path, monkeypatch):
    """A link to a folder open to all, and a link that lies in a folder open to all (it could
    be pointed elsewhere): both refused."""
    _, shared = folders
    _open_to_all(tmp_path / "real")
    (tmp_path / "link").symlink_to(tmp_path / "real")
    (tmp_path / "safe").mkdir(mode=0o700)
    open_ = _open_to_all(tmp_path / "open")
    (open_ / "link").symlink_to(tmp_path / "safe")
    for cache, culprit in ((tmp_path / "link" / "kernels", tmp_path / "link"),
                           (open_ / "link" / "kernels", open_)):
        monkeypatch.setenv("VISTRACK_CACHE_DIR", str(cache))
        with pytest.warns(RuntimeWarning, match=_refused(cache, _someone_could_swap(culprit),
                                                         f"it tries {shared}")):
            assert _load_where() == {shared}
    assert not list((tmp_path / "real").iterdir()) and not list((tmp_path / "safe").iterdir())


def test_a_temporary_directory_under_an_open_folder_gets_no_cache(folders, tmp_path):
    """Every folder refused, the process's own one too (it would be made in the temporary
    directory, which others could replace): the kernels compile without a cache."""
    cache, shared = folders
    cache.write_text("")  # the configured folder is unusable
    tmp = Path(tempfile.gettempdir())
    os.chmod(tmp, 0o777)
    with pytest.warns(RuntimeWarning) as record:
        assert _load_where() == set()
    assert [str(w.message) for w in record] == [
        f"vistrack does not use the kernel folder {cache}: it is not a directory; it tries "
        f"{shared}",
        f"vistrack does not use the kernel folder {shared}: {_someone_could_swap(tmp)}; it "
        "uses a new temporary folder for this process instead",
        f"vistrack does not make a kernel folder in {tmp}: {_someone_could_swap(tmp)}; it "
        "compiles the kernels without a cache instead"]
    assert _codegen._PRIVATE_DIR == [] and list(tmp.iterdir()) == []


def test_threads_write_through_temporary_files_of_their_own(tmp_path, monkeypatch):
    """Eight threads write the same file at once: each through its own temporary file."""
    names, replace = [], os.replace
    barrier = threading.Barrier(8)

    def recording_replace(src, dst):
        names.append(os.fspath(src))
        barrier.wait(timeout=10)  # every thread has its temporary file before any replaces
        replace(src, dst)

    monkeypatch.setattr(_codegen.os, "replace", recording_replace)
    target = tmp_path / "kernel.py"
    threads = [threading.Thread(target=_codegen._write, args=(target, SRC)) for _ in range(8)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(set(names)) == 8
    assert target.read_text() == SRC
    assert [p.name for p in tmp_path.iterdir()] == ["kernel.py"]
