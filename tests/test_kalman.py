"""The Kalman filter against FilterPy, pykalman, a joint-Gaussian oracle and the seeds' 1-D
equations."""

import dataclasses
import re

import numpy as np
import pytest
from scipy import stats

import vistrack as vt
from vistrack.filters import kalman_filter, kalman_filter_1d, kf_predict, kf_step, kf_update
from vistrack.filters.kalman import _update

from .conftest import random_model

filterpy_kalman = pytest.importorskip("filterpy.kalman")
pykalman = pytest.importorskip("pykalman")

RTOL = 1e-8


def at(A, t):
    return A[t] if A.ndim == 3 else A


def loglik_tol(ll, ys):
    """How far two correct log-likelihoods of ``ys`` may differ: 1e-10 of it, plus what
    rounding the innovations ``y - H x`` costs. A random model may be unstable (an
    eigenvalue of F above 1), its measurements growing to 1e8 in 60 steps; each innovation
    then carries rounding of about eps |y|, and each step's ``-w'w / 2`` (``w`` the whitened
    innovation, a few units; the innovation's standard deviation 0.7 or more here) about
    |w| eps |y| / 0.7. A term of the formula missed or doubled (``log 2 pi / 2`` is 0.92) is
    far above that."""
    return 1e-10 * abs(ll) + 16 * np.finfo(float).eps * float(np.nansum(np.abs(ys)))


def filterpy_run(ys, F, Q, H, R, x0, P0):
    """Step FilterPy's predict/update (batch_filter of 2.0.0 rejects (T, m) arrays)."""
    n, m = len(x0), ys.shape[1]
    kf = filterpy_kalman.KalmanFilter(dim_x=n, dim_z=m)
    kf.x, kf.P = np.array(x0, float), np.array(P0, float)
    means, covs, ll = [], [], 0.0
    for t, y in enumerate(ys):
        if t > 0:
            kf.predict(F=at(F, t), Q=at(Q, t))
        o = ~np.isnan(y)
        if o.any():
            Ht, Rt = at(H, t)[o], at(R, t)[np.ix_(o, o)]
            kf.update(y[o], R=Rt, H=Ht)
            ll += kf.log_likelihood
        means.append(kf.x.copy())
        covs.append(kf.P.copy())
    return np.array(means), np.array(covs), ll


def with_missing(rng, ys, rows=0.15, comps=0.15):
    ys = ys.copy()
    ys[rng.random(ys.shape[:-1]) < rows] = np.nan
    ys[rng.random(ys.shape) < comps] = np.nan
    return ys


@pytest.mark.parametrize("tv", [False, True])
@pytest.mark.parametrize("n,m", [(1, 1), (2, 1), (4, 2), (6, 3), (1, 3), (2, 4)])
def test_equals_filterpy_with_missing_components(rng, n, m, tv):
    T = 40
    mod = random_model(rng, n, m, T, tv=tv)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), rng=rng)
    ys = with_missing(rng, ys)
    x0, P0 = rng.normal(size=n), 2.0 * np.eye(n)
    res = kalman_filter(ys, **mod, x0=x0, P0=P0)
    fm, fP, fll = filterpy_run(ys, **mod, x0=x0, P0=P0)
    np.testing.assert_allclose(res.means, fm, rtol=RTOL, atol=1e-10)
    np.testing.assert_allclose(res.covs, fP, rtol=RTOL, atol=1e-10)
    assert res.loglik == pytest.approx(fll, rel=0, abs=loglik_tol(fll, ys))


@pytest.mark.parametrize("tv", [False, True])
def test_filter_and_rts_equal_pykalman(rng, tv):
    n, m, T = 4, 2, 60
    mod = random_model(rng, n, m, T, tv=tv)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), rng=rng)
    ys[[3, 17, 18, 40]] = np.nan  # pykalman handles whole missing rows only (pykalman #58)
    x0, P0 = rng.normal(size=n), 3.0 * np.eye(n)
    # pykalman's transition_matrices[t] maps t -> t+1; ours F[t] maps t-1 -> t
    pk = pykalman.KalmanFilter(
        transition_matrices=mod["F"][1:] if tv else mod["F"],
        transition_covariance=mod["Q"][1:] if tv else mod["Q"],
        observation_matrices=mod["H"],
        observation_covariance=mod["R"],
        initial_state_mean=x0,
        initial_state_covariance=P0,
    )
    masked = np.ma.masked_invalid(ys)
    pm, pP = pk.filter(masked)
    sm, sP = pk.smooth(masked)
    res = kalman_filter(ys, **mod, x0=x0, P0=P0)
    np.testing.assert_allclose(res.means, pm, rtol=RTOL, atol=1e-10)
    np.testing.assert_allclose(res.covs, pP, rtol=RTOL, atol=1e-10)
    smooth = vt.rts_smooth(res, F=mod["F"], Q=mod["Q"])
    np.testing.assert_allclose(smooth.means, sm, rtol=RTOL, atol=1e-10)
    np.testing.assert_allclose(smooth.covs, sP, rtol=RTOL, atol=1e-10)
    if not tv:  # pykalman's loglikelihood() fails on per-step observation matrices
        want = pk.loglikelihood(masked)
        assert res.loglik == pytest.approx(want, rel=0, abs=loglik_tol(want, ys))


def test_loglik_equals_joint_gaussian_density(rng):
    """log p(y_0..y_T-1) from the filter equals the density of the stacked Gaussian vector."""
    n, m, T = 3, 2, 6
    mod = random_model(rng, n, m)
    x0, P0 = rng.normal(size=n), np.eye(n)
    F, Q, H, R = mod["F"], mod["Q"], mod["H"], mod["R"]
    # joint of states: x_t = F^t x_0 + sum F^(t-s) w_s
    Phi = [np.linalg.matrix_power(F, t) for t in range(T)]
    mean_x = np.concatenate([Phi[t] @ x0 for t in range(T)])
    Cx = np.zeros((T * n, T * n))
    for s in range(T):
        for t in range(T):
            k = min(s, t)
            c = Phi[s] @ P0 @ Phi[t].T
            for r in range(1, k + 1):
                c = c + Phi[s - r] @ Q @ Phi[t - r].T
            Cx[s * n:(s + 1) * n, t * n:(t + 1) * n] = c
    Hbig = np.kron(np.eye(T), H)
    Cy = Hbig @ Cx @ Hbig.T + np.kron(np.eye(T), R)
    y = rng.multivariate_normal(Hbig @ mean_x, Cy).reshape(T, m)
    y[2, 1] = np.nan
    y[4] = np.nan
    keep = ~np.isnan(y.ravel())
    want = stats.multivariate_normal(
        (Hbig @ mean_x)[keep], Cy[np.ix_(keep, keep)]).logpdf(y.ravel()[keep])
    got = kalman_filter(y, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0).loglik
    assert got == pytest.approx(want, rel=1e-10)


def _scalar_model(rng, T, missing):
    """A random scalar model's per-step ``d, m, sigma_d, sigma_m`` and a series ``ys`` with
    the steps ``missing`` unmeasured."""
    d = 1 + 0.05 * rng.normal(size=T)
    mm = 1 + 0.2 * rng.random(T)
    sd, sm = 0.3 + rng.random(T), 0.5 + rng.random(T)
    ys = rng.normal(size=T).cumsum()
    ys[missing] = np.nan
    return d, mm, sd, sm, ys


def test_scalar_equations_equal_matrix_form(rng):
    d, mm, sd, sm, ys = _scalar_model(rng, 50, [5, 6, 30])
    s = kalman_filter_1d(ys, d=d, m=mm, sigma_d=sd, sigma_m=sm, x0=0.5, sigma0=2.0)
    res = kalman_filter(ys[:, None], F=d[:, None, None], Q=(sd**2)[:, None, None],
                        H=mm[:, None, None], R=(sm**2)[:, None, None], x0=[0.5], P0=[[4.0]])
    np.testing.assert_allclose(s.mean, res.means[:, 0], rtol=1e-12)
    np.testing.assert_allclose(s.std ** 2, res.covs[:, 0, 0], rtol=1e-12)
    np.testing.assert_allclose(s.pred_mean, res.pred_means[:, 0], rtol=1e-12)
    np.testing.assert_allclose(s.pred_std ** 2, res.pred_covs[:, 0, 0], rtol=1e-12)


def test_per_step_matrices_are_pykalmans_one_step_on(rng):
    """README said the per-step ``F[t]`` (predicting step t from t-1) was pykalman's
    convention too; pykalman's ``transition_matrices[t]`` predicts t+1 from t, so the same
    array gave dynamics one step apart (means 1, 2, 6 against 1, 3, 15). Oracle: pykalman
    given ``F[1:]`` and ``Q[1:]``, as README now says."""
    T = 12
    F = 1 + 0.3 * rng.random((T, 2, 2))
    Q = np.stack([np.eye(2) * q for q in 0.1 + rng.random(T)])
    ys = rng.normal(size=(T, 1)).cumsum(0)
    ys[[3, 7]] = np.nan
    H, R, x0, P0 = [[1.0, 0.5]], [[0.8]], [0.2, -0.1], np.eye(2)
    ours = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0)
    pk = pykalman.KalmanFilter(transition_matrices=F[1:], transition_covariance=Q[1:],
                               observation_matrices=H, observation_covariance=R,
                               initial_state_mean=x0, initial_state_covariance=P0)
    means, covs = pk.filter(np.ma.masked_invalid(ys))
    np.testing.assert_allclose(ours.means, means, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(ours.covs, covs, rtol=1e-10, atol=1e-12)


@pytest.mark.parametrize("scale", [1e-150, 1e-100, 1e-77, 1e77, 1e80, 1e150])
def test_scalar_equations_hold_at_any_scale_the_filter_takes(rng, scale):
    """The scalar filter squared products of standard deviations: from 1e77 they overflowed
    (a std of inf, then NaN means, then "the innovation variance is 0"), from 1e-77 they
    underflowed (stds of 0 and wrong means, unsaid), well inside the 1.34e154 it takes.
    Oracle: the same series at unit scale, filtered in matrix form, times the scale (the
    filter is linear in the measurements and the standard deviations together)."""
    d, mm, sd, sm, ys = _scalar_model(rng, 30, [5, 6, 20])
    s = kalman_filter_1d(ys * scale, d=d, m=mm, sigma_d=sd * scale, sigma_m=sm * scale,
                         x0=0.5 * scale, sigma0=2.0 * scale)
    res = kalman_filter(ys[:, None], F=d[:, None, None], Q=(sd**2)[:, None, None],
                        H=mm[:, None, None], R=(sm**2)[:, None, None], x0=[0.5], P0=[[4.0]])
    np.testing.assert_allclose(s.mean / scale, res.means[:, 0], rtol=1e-12)
    np.testing.assert_allclose(s.std / scale, np.sqrt(res.covs[:, 0, 0]), rtol=1e-12)
    np.testing.assert_allclose(s.pred_std / scale, np.sqrt(res.pred_covs[:, 0, 0]), rtol=1e-12)


@pytest.mark.parametrize("missing", [True, False], ids=["missing", "full"])
@pytest.mark.parametrize("store_covs", [True, False])
def test_batch_shared_and_general_paths_agree_with_single_series(rng, store_covs, missing):
    """Series that share their covariances (the same prior and missing steps) filtered once
    for all, equal to each filtered alone: with steps missing the covariances come from the
    batch kernel run on one series; fully measured and with the covariances kept, from the
    one-series kernel, which stops updating them at their steady state."""
    n, m, T, B = 4, 2, 30, 70  # B > one chunk of the kernel, and not a multiple of it
    mod = random_model(rng, n, m)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), n_series=B, rng=rng)
    if missing:
        pattern = rng.random((T, m)) < 0.2
        ys[:, pattern] = np.nan  # the same missing pattern in every series
    x0 = rng.normal(size=(B, n))
    P0 = np.eye(n)
    shared = kalman_filter(ys, **mod, x0=x0, P0=P0, store_covs=store_covs)
    general = kalman_filter(ys, **mod, x0=x0, P0=np.broadcast_to(P0, (B, n, n)),
                            store_covs=store_covs)
    assert shared.shared_covs and not general.shared_covs
    for b in (0, 33, B - 1):
        one = kalman_filter(ys[b], **mod, x0=x0[b], P0=P0)
        for res in (shared, general):
            np.testing.assert_allclose(res.means[b], one.means, rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose(res.loglik[b], one.loglik, rtol=1e-12)
            np.testing.assert_allclose(res.last.cov[b], one.covs[-1], rtol=1e-12, atol=1e-14)
            if store_covs:
                np.testing.assert_allclose(res.pred_means[b], one.pred_means, rtol=1e-12,
                                           atol=1e-12)
                np.testing.assert_allclose(res.covs[b], one.covs, rtol=1e-12, atol=1e-14)
                np.testing.assert_allclose(res.pred_covs[b], one.pred_covs, rtol=1e-12, atol=1e-14)
            else:
                assert res.covs is None and res.pred_covs is None and res.pred_means is None


def test_different_missing_patterns_use_per_series_covariances(rng):
    n, m, T, B = 2, 2, 20, 5
    mod = random_model(rng, n, m)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), n_series=B, rng=rng)
    ys[2, 5, 0] = np.nan
    res = kalman_filter(ys, **mod, x0=np.zeros(n), P0=np.eye(n))
    assert not res.shared_covs
    one = kalman_filter(ys[2], **mod, x0=np.zeros(n), P0=np.eye(n))
    np.testing.assert_allclose(res.covs[2], one.covs, rtol=1e-12)
    assert not np.allclose(res.covs[1, 5], res.covs[2, 5])


def test_all_missing_row_only_predicts(rng):
    mod = random_model(rng, 3, 2)
    ys = rng.normal(size=(5, 2))
    ys[2] = np.nan
    res = kalman_filter(ys, **mod, x0=np.zeros(3), P0=np.eye(3))
    np.testing.assert_array_equal(res.means[2], res.pred_means[2])
    np.testing.assert_array_equal(res.covs[2], res.pred_covs[2])


def test_masked_measurements_are_missing_as_in_pykalman(rng):
    """A numpy masked array, pykalman's way of marking missing steps, has its masked entries
    missing whatever values lie under the mask. Before, np.asarray dropped the mask and the
    placeholders were measured (the review's example: log-likelihood -1379134.8 instead of
    pykalman's -4.0953)."""
    n, m, T = 4, 2, 40
    mod = random_model(rng, n, m)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), rng=rng)
    rows = [0, 3, 17, 18, 39]
    mask = np.zeros(ys.shape, bool)
    mask[rows] = True
    masked = np.ma.masked_array(np.where(mask, -999.0, ys), mask=mask)
    x0, P0 = rng.normal(size=n), 3.0 * np.eye(n)
    pk = pykalman.KalmanFilter(transition_matrices=mod["F"], transition_covariance=mod["Q"],
                               observation_matrices=mod["H"], observation_covariance=mod["R"],
                               initial_state_mean=x0, initial_state_covariance=P0)
    pm, pP = pk.filter(masked)
    sm, sP = pk.smooth(masked)
    res = kalman_filter(masked, **mod, x0=x0, P0=P0)
    np.testing.assert_allclose(res.means, pm, rtol=RTOL, atol=1e-10)
    np.testing.assert_allclose(res.covs, pP, rtol=RTOL, atol=1e-10)
    want = pk.loglikelihood(masked)
    assert res.loglik == pytest.approx(want, rel=0, abs=loglik_tol(want, masked.filled(np.nan)))
    smooth = vt.rts_smooth(res, F=mod["F"], Q=mod["Q"])
    np.testing.assert_allclose(smooth.means, sm, rtol=RTOL, atol=1e-10)
    np.testing.assert_allclose(smooth.covs, sP, rtol=RTOL, atol=1e-10)
    # a masked component is a missing one, NaN (the documented convention), in the functions
    # and the model-built filter alike; the caller's array is left as it was
    masked[[5, 9], [1, 0]] = np.ma.masked
    nan = np.where(masked.mask, np.nan, masked.data)
    for a, b in ((kalman_filter(masked, **mod, x0=x0, P0=P0),
                  kalman_filter(nan, **mod, x0=x0, P0=P0)),
                 (vt.KalmanFilter(vt.ConstantVelocity(dim=2), vt.Position(dim=2)).filter(
                     masked, x0=x0, P0=P0),
                  vt.KalmanFilter(vt.ConstantVelocity(dim=2), vt.Position(dim=2)).filter(
                      nan, x0=x0, P0=P0))):
        np.testing.assert_array_equal(a.means, b.means)
        np.testing.assert_array_equal(a.loglik, b.loglik)
    assert np.all(masked.data[rows] == -999.0) and masked.mask.sum() == len(rows) * m + 2


def test_read_only_matrices_reach_the_kernels_as_writable_copies():
    """The kernels are compiled at install for writable arrays; F, Q, H or R kept read-only
    (setflags(write=False), as a model's constants may be) made kf_step compile them all
    again on first use (26 s measured). They are copied, and the step is the same."""
    from vistrack.filters.kalman import _small_matrix

    F, Q, H, R = np.eye(2), np.eye(2) * 0.1, np.eye(2), np.eye(2) * 2.0
    g = vt.Gaussian(np.zeros(2), np.eye(2))
    want = vt.kf_step(g, [1.0, 2.0], F, Q, H, R)
    for a in (F, Q, H, R):
        a.setflags(write=False)
    assert all(_small_matrix(a, "M", 2, 2).flags.writeable for a in (F, Q, H, R))
    got = vt.kf_step(g, [1.0, 2.0], F, Q, H, R)
    np.testing.assert_array_equal(got.mean, want.mean)
    np.testing.assert_array_equal(got.cov, want.cov)


def test_result_is_read_only(rng):
    mod = random_model(rng, 2, 1)
    res = kalman_filter(rng.normal(size=(5, 1)), **mod, x0=np.zeros(2), P0=np.eye(2))
    with pytest.raises(ValueError):
        res.means[0, 0] = 1.0
    with pytest.raises(dataclasses.FrozenInstanceError):
        res.means = None


def test_predict_update_kernels_equal_the_sequence_filter(rng):
    n, m = 4, 2
    mod = random_model(rng, n, m)
    ys = rng.normal(size=(7, 3, m))  # batch of 7 tracks, 3 steps
    ys[1, 1, 0] = np.nan
    ys[4, 2] = np.nan
    seq = kalman_filter(ys, **mod, x0=np.zeros(n), P0=np.eye(n))
    g = vt.Gaussian(np.zeros((7, n)), np.broadcast_to(np.eye(n), (7, n, n)))
    total = np.zeros(7)
    for t in range(3):
        if t > 0:
            g = kf_predict(g, mod["F"], mod["Q"])
            np.testing.assert_allclose(g.mean, seq.pred_means[:, t], rtol=1e-12, atol=1e-13)
        prev = g
        g, ll = _update(g, ys[:, t], mod["H"], mod["R"])
        total += ll
        np.testing.assert_array_equal(kf_update(prev, ys[:, t], mod["H"], mod["R"]).mean, g.mean)
        np.testing.assert_allclose(g.mean, seq.means[:, t], rtol=1e-12, atol=1e-13)
        np.testing.assert_allclose(g.cov, seq.covs[:, t], rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(total, seq.loglik, rtol=1e-12)


@pytest.mark.parametrize("B", [1, 5, 300])  # scalar path below 8 Gaussians, SoA path above
def test_kf_step_equals_predict_then_update(rng, B):
    n, m = 4, 2
    mod = random_model(rng, n, m)
    A = rng.normal(size=(B, n, n))
    g = vt.Gaussian(rng.normal(size=(B, n)), A @ np.swapaxes(A, 1, 2) + np.eye(n))
    y = rng.normal(size=(B, m))
    y[0, 1] = np.nan
    got = kf_step(g, y, mod["F"], mod["Q"], mod["H"], mod["R"])
    want = kf_update(kf_predict(g, mod["F"], mod["Q"]), y, mod["H"], mod["R"])
    np.testing.assert_allclose(got.mean, want.mean, rtol=1e-13, atol=1e-13)
    np.testing.assert_allclose(got.cov, want.cov, rtol=1e-13, atol=1e-13)
    # and both equal FilterPy on the first Gaussian
    kf = filterpy_kalman.KalmanFilter(dim_x=n, dim_z=m)
    kf.x, kf.P = g.mean[0].copy(), g.cov[0].copy()
    kf.predict(F=mod["F"], Q=mod["Q"])
    kf.update(y[0, :1], H=mod["H"][:1], R=mod["R"][:1, :1])
    np.testing.assert_allclose(got.mean[0], kf.x, rtol=1e-10)
    np.testing.assert_allclose(got.cov[0], kf.P, rtol=1e-10)


def test_kernels_keep_batch_shape(rng):
    g = vt.Gaussian(np.zeros((2, 3, 2)), np.broadcast_to(np.eye(2), (2, 3, 2, 2)))
    p = kf_predict(g, np.eye(2), np.eye(2))
    u = kf_update(p, np.ones((2, 3, 1)), [[1.0, 0.0]], [[1.0]])
    assert p.batch_shape == u.batch_shape == (2, 3)
    single = kf_update(vt.Gaussian(np.zeros(2), np.eye(2)), [1.0], [[1.0, 0.0]], [[1.0]])
    assert single.mean.shape == (2,)
    np.testing.assert_allclose(single.mean, [0.5, 0.0])


def test_batches_of_any_rank_reach_the_kernels_with_one_batch_axis(rng, monkeypatch):
    """The kernels are compiled at install for a single Gaussian and a batch of one axis; a
    batch of two axes is passed as one (no compilation on first use) and comes back in its
    shape, each Gaussian as if alone."""
    from vistrack.filters import _kernels

    ranks = []
    for name in ("predict_batch_py", "update_batch_py", "step_batch"):
        real = getattr(_kernels, name)

        def spy(*args, _real=real):
            ranks.append(tuple(x.ndim for x in args[:2]))
            return _real(*args)

        monkeypatch.setattr(_kernels, name, spy)
    A = rng.normal(size=(2, 3, 2, 2))
    g = vt.Gaussian(rng.normal(size=(2, 3, 2)), A @ np.swapaxes(A, -1, -2) + np.eye(2))
    y = rng.normal(size=(2, 3, 1))
    y[1, 2] = np.nan
    F, Q, H, R = [[1.0, 1.0], [0.0, 1.0]], 0.1 * np.eye(2), [[1.0, 0.0]], [[0.5]]
    batch = {"predict": kf_predict(g, F, Q), "update": _update(g, y, H, R),
             "step": kf_step(g, y, F, Q, H, R)}
    assert ranks == [(2, 3)] * 3
    assert batch["update"][1].shape == (2, 3)
    for i in range(2):
        for j in range(3):
            a = vt.Gaussian(g.mean[i, j], g.cov[i, j])
            alone = {"predict": kf_predict(a, F, Q), "update": _update(a, y[i, j], H, R),
                     "step": kf_step(a, y[i, j], F, Q, H, R)}
            for key in ("predict", "step"):
                np.testing.assert_array_equal(batch[key].mean[i, j], alone[key].mean)
                np.testing.assert_array_equal(batch[key].cov[i, j], alone[key].cov)
            np.testing.assert_array_equal(batch["update"][0].mean[i, j], alone["update"][0].mean)
            np.testing.assert_array_equal(batch["update"][0].cov[i, j], alone["update"][0].cov)
            assert batch["update"][1][i, j] == alone["update"][1]


def test_kalman_filter_class_uses_true_dt(rng):
    """Variable time steps give the per-step matrices of the model (dropped frames, sort#22)."""
    cv, pos = vt.ConstantVelocity(dim=2, q=0.3), vt.Position(dim=2, r=0.5)
    kf = vt.KalmanFilter(cv, pos)
    times = np.cumsum(rng.uniform(0.5, 3.0, size=25))
    ys = rng.normal(size=(25, 2)).cumsum(0)
    x0, P0 = np.zeros(4), 10 * np.eye(4)
    got = kf.filter(ys, dt=np.diff(times), x0=x0, P0=P0)
    dts = np.r_[0.0, np.diff(times)]
    want = kalman_filter(ys, F=cv.F(dts), Q=cv.Q(dts), H=pos.H(4), R=pos.R(), x0=x0, P0=P0)
    np.testing.assert_allclose(got.means, want.means, rtol=1e-12)
    sm = kf.smooth(ys, dt=np.diff(times), x0=x0, P0=P0)
    np.testing.assert_allclose(sm.means, vt.rts_smooth(want, F=cv.F(dts), Q=cv.Q(dts)).means,
                               rtol=1e-12)


def test_default_prior_starts_at_first_measurement():
    kf = vt.KalmanFilter(vt.ConstantVelocity(dim=2), vt.Position(dim=2, r=2.0))
    ys = np.array([[np.nan, 4.0], [3.0, 5.0], [4.0, 6.0]])
    x0, P0 = kf.default_prior(ys)
    np.testing.assert_allclose(x0, [3.0, 4.0, 0.0, 0.0])
    np.testing.assert_allclose(np.diag(P0), [2.0, 2.0, 2e6, 2e6])
    res = kf.filter(ys)
    assert np.all(np.isfinite(res.means))


E = np.eye(2)


@pytest.mark.parametrize(
    "kwargs,exc,match",
    [
        (dict(ys=np.ones((5, 3))), ValueError,
         r"ys must have 2 values a step, as H \(2, 2\) and R \(2, 2\) measure; got 3"),
        (dict(ys=np.ones(5)), ValueError, "ys must be 2-D or 3-D; got shape"),
        (dict(ys=[[np.inf, 1.0]] * 3), ValueError, "ys must be finite or NaN"),
        (dict(F=[[1.0, np.nan], [0.0, 1.0]]), ValueError, r"F must be finite; F\[0, 0, 1\] = nan"),
        (dict(F=np.eye(3)), ValueError,
         r"F must have shape \(2, 2\) or \(T=5, 2, 2\); got \(3, 3\)"),
        (dict(F=np.stack([E] * 4)), ValueError, r"F must have shape .*got \(4, 2, 2\)"),
        (dict(Q=-E), ValueError, "Q must be positive semi-definite"),
        (dict(R=[[1.0, 0.3], [0.2, 1.0]]), ValueError, "R must be symmetric"),
        (dict(P0=-E), ValueError, "P0 must be positive semi-definite"),
        (dict(P0=np.eye(3)), ValueError,
         r"P0 must have shape \(2, 2\) or \(B=1, 2, 2\); got \(3, 3\)"),
        (dict(x0=np.zeros((3, 2))), ValueError, r"x0 must have shape \(2,\) or \(B=1, 2\)"),
        (dict(x0="ab"), TypeError, "x0 must be an array of numbers"),
        (dict(R=np.zeros((2, 2)), P0=np.zeros((2, 2))), ValueError,
         "not positive definite at step 0"),
    ],
)
def test_bad_arguments_raise_naming_the_argument(kwargs, exc, match):
    args = dict(ys=np.ones((5, 2)), F=E, Q=E, H=E, R=E, x0=np.zeros(2), P0=E)
    args.update(kwargs)
    ys = args.pop("ys")
    with pytest.raises(exc, match=match):
        kalman_filter(ys, **args)


def test_kernel_argument_errors():
    g = vt.Gaussian(np.zeros((3, 2)), np.broadcast_to(E, (3, 2, 2)))
    # (the shape was printed as a tuple with 'm' quoted in it)
    with pytest.raises(ValueError, match=re.escape(
            "y must have shape (3, m), a measurement of m values for each of g's (3,); got "
            "(4, 1)")):
        kf_update(g, np.ones((4, 1)), [[1.0, 0.0]], [[1.0]])
    with pytest.raises(TypeError, match="g must be a vistrack.Gaussian"):
        kf_predict(np.zeros(2), E, E)
    with pytest.raises(ValueError, match=r"Gaussian cov must have shape"):
        vt.Gaussian(np.zeros(2), np.eye(3))
    bad = np.array([[1.0, np.inf]])
    with pytest.raises(ValueError, match="F must be finite"):
        kf_step(g, np.ones((3, 1)), np.full((2, 2), np.nan), E, [[1.0, 0.0]], [[1.0]])
    with pytest.raises(ValueError, match="H must be finite"):
        kf_step(g, np.ones((3, 1)), E, E, bad, [[1.0]])
    with pytest.raises(ValueError, match="R must be symmetric"):
        kf_update(g, np.ones((3, 2)), E, [[1.0, 0.5], [0.0, 1.0]])
    # an infinite measurement (NaN is a missing one): it gave means of NaN, where
    # kalman_filter and OnlineFilter refuse it
    y = np.ones((3, 1))
    y[2, 0] = -np.inf
    with pytest.raises(ValueError) as e:
        kf_update(g, y, [[1.0, 0.0]], [[1.0]])
    assert str(e.value) == "y must be finite or NaN (missing); y[2, 0] = -inf"
    with pytest.raises(ValueError, match=re.escape("y[2, 0] = -inf")):
        kf_step(g, y, E, E, [[1.0, 0.0]], [[1.0]])
    y[2, 0] = np.nan
    assert np.isfinite(kf_update(g, y, [[1.0, 0.0]], [[1.0]]).mean).all()
    many = vt.Gaussian(np.zeros((40, 2)), np.tile(np.eye(2), (40, 1, 1)))  # numpy's check
    y = np.ones((40, 1))
    y[31, 0] = np.inf
    with pytest.raises(ValueError, match=re.escape("y[31, 0] = inf")):
        kf_update(many, y, [[1.0, 0.0]], [[1.0]])
    with pytest.raises(ValueError, match="Q must be symmetric"):
        kf_predict(g, E, [[1.0, 0.5], [0.0, 1.0]])
    with pytest.raises(ValueError, match=r"H must have shape \(1, 2\); got \(1, 3\)"):
        kf_update(g, np.ones((3, 1)), [[1.0, 0.0, 0.0]], [[1.0]])
    with pytest.raises(ValueError, match="not positive definite"):
        kf_update(vt.Gaussian(np.zeros((3, 2)), np.zeros((3, 2, 2))), np.ones((3, 1)), [[1.0, 0.0]],
                  [[0.0]])
    # a covariance holding NaN: named by its entry, before S is made (it was the message
    # above, about R; then the batch member alone)
    cov = np.tile(np.eye(2), (2, 3, 1, 1))
    cov[1, 2, 0, 0] = np.nan
    nan_g = vt.Gaussian(np.zeros((2, 3, 2)), cov)
    for call in (lambda: kf_update(nan_g, np.ones((2, 3, 1)), [[1.0, 0.0]], [[1.0]]),
                 lambda: kf_step(nan_g, np.ones((2, 3, 1)), E, E, [[1.0, 0.0]], [[1.0]])):
        with pytest.raises(ValueError) as e:
            call()
        assert str(e.value) == "g.cov must be finite; g.cov[1, 2, 0, 0] = nan"
    with pytest.raises(ValueError, match=re.escape("g.cov must be finite; g.cov[0, 0] = nan")):
        kf_update(vt.Gaussian(np.zeros(2), np.full((2, 2), np.nan)), [1.0], [[1.0, 0.0]], [[1.0]])
    with pytest.raises(ValueError, match="sigma_m must be a scalar or have shape"):
        kalman_filter_1d(np.ones(4), d=1, m=1, sigma_d=1, sigma_m=np.ones(3), x0=0, sigma0=1)
    # no step: refused as the n-D filter refuses it (it returned empty results)
    for call in (lambda: kalman_filter_1d([], d=1, m=1, sigma_d=1, sigma_m=1, x0=0, sigma0=1),
                 lambda: kalman_filter(np.zeros((0, 1)), F=[[1.0]], Q=[[1.0]], H=[[1.0]],
                                       R=[[1.0]], x0=[0.0], P0=[[1.0]])):
        with pytest.raises(ValueError, match=re.escape("ys must have at least one step; got "
                                                       "shape (0,")):
            call()


@pytest.mark.parametrize("bad,message", [
    ({"ys": [1.0, np.inf, 2.0]}, "ys[1] = inf"),
    ({"x0": np.nan}, "x0 must be a finite number; got nan"),
    ({"sigma0": np.inf}, "sigma0 must be a finite number >= 0; got inf"),
    ({"sigma0": -1.0}, "sigma0 must be a finite number >= 0; got -1.0"),
    ({"sigma_m": -0.5}, "sigma_m must be standard deviations >= 0; got -0.5"),
])
def test_scalar_filter_refuses_what_gave_infinite_or_nan_means(bad, message):
    """An infinite measurement or a NaN prior gave inf or NaN means without a word, where
    the matrix filter refuses them by name."""
    args = {"ys": [1.0, 2.0, 3.0], "d": 1.0, "m": 1.0, "sigma_d": 0.5, "sigma_m": 1.0,
            "x0": 0.0, "sigma0": 1.0} | bad
    with pytest.raises(ValueError, match=re.escape(message)):
        kalman_filter_1d(args.pop("ys"), **args)


def test_online_filter_equals_the_sequence_filter(rng):
    cv, pos = vt.ConstantVelocity(dim=2, q=0.3), vt.Position(dim=2, r=0.7)
    kf = vt.KalmanFilter(cv, pos)
    T = 30
    times = np.cumsum(rng.uniform(0.5, 2.0, size=T))
    _, ys = vt.simulate.simulate(cv, pos, T, x0=[0, 0, 1, 1], dt=np.diff(times), rng=rng)
    ys[4] = np.nan
    ys[9, 0] = np.nan
    x0, P0 = np.zeros(4), 5 * np.eye(4)
    want = kf.filter(ys, dt=np.diff(times), x0=x0, P0=P0)
    f = kf.online(x0, P0, dt=1.0)
    total = f.update(ys[0])
    np.testing.assert_allclose(f.mean, want.means[0], rtol=1e-12)
    for t in range(1, T):
        total += f.step(ys[t], dt=times[t] - times[t - 1])
        np.testing.assert_allclose(f.mean, want.means[t], rtol=1e-11, atol=1e-12)
        np.testing.assert_allclose(f.cov, want.covs[t], rtol=1e-11, atol=1e-12)
    assert total == pytest.approx(float(want.loglik), rel=1e-12)
    f.predict()  # default dt back to 1.0
    np.testing.assert_allclose(f.mean, cv.F(1.0) @ want.means[-1], rtol=1e-12)
    with pytest.raises(ValueError):
        f.mean[0] = 1.0  # a read-only view
    snap = f.gaussian
    f.step([1.0, 2.0])
    assert not np.allclose(snap.mean, f.mean)


def test_online_filter_errors_leave_the_state_unchanged():
    kf = vt.KalmanFilter(vt.ConstantVelocity(dim=1), vt.Position(dim=1))
    f = kf.online([0.0, 1.0], np.eye(2))
    before = f.gaussian
    with pytest.raises(ValueError, match=r"y must have shape \(1,\); got \(2,\)"):
        f.step([1.0, 2.0])
    with pytest.raises(ValueError, match="y must be finite or NaN"):
        f.step([np.inf])
    np.testing.assert_array_equal(f.mean, before.mean)
    np.testing.assert_array_equal(f.cov, before.cov)
    with pytest.raises(ValueError, match=r"x0 must have shape \(2,\)"):
        kf.online([0.0, 1.0, 2.0], np.eye(3))
    # a dt that is no number: named ("could not convert string to float: 'a'"), text that
    # reads as one too ("0.5" moved the mean by half a step)
    for bad in ("a", [1, 2], object(), "0.5", b"2", True):
        with pytest.raises(ValueError, match=r"^dt must be a number; got "):
            f.predict(dt=bad)
    np.testing.assert_array_equal(f.mean, before.mean)
    # x0 of the wrong length, P0 of the model's: x0 is named (P0 was), as filter() names it
    with pytest.raises(ValueError, match=r"^x0 must have shape \(2,\) or \(B=1, 2\) to match "
                                         r"P0 and F; got \(3,\)$"):
        kf.online([0.0, 1.0, 2.0], np.eye(2))
    degenerate = vt.KalmanFilter(vt.LinearMotion(np.eye(1), np.zeros((1, 1))),
                                 vt.LinearMeasurement([[1.0]], [[0.0]])).online([0.0], [[0.0]])
    with pytest.raises(ValueError, match="not positive definite"):
        degenerate.update([1.0])
    np.testing.assert_array_equal(degenerate.mean, [0.0])


@pytest.mark.parametrize(
    "motion,Qfix",
    [(vt.ConstantVelocity(dim=2, q=0.1), None), (vt.ConstantVelocity(dim=2), 0.1 * np.eye(4)),
     (vt.ConstantPosition(dim=3, q=1.0), None), (vt.ConstantAcceleration(dim=1, q=0.01), None)],
)
def test_steady_state_phase_of_one_series_equals_filterpy_and_the_batch_kernel(rng, motion, Qfix):
    """Long, fully observed series with constant matrices: the one-series kernel freezes the
    converged covariance; with sparse missing steps it leaves and re-enters that phase."""
    n = motion.ndim_state
    dim = motion.dim
    F, Q = motion.F(1.0), (motion.Q(1.0) if Qfix is None else Qfix)
    H, R = np.eye(dim, n), 0.8 * np.eye(dim)
    T = 600
    _, ys = vt.simulate.simulate_lgssm(T, F=F, Q=Q, H=H, R=R, x0=np.zeros(n), rng=rng)
    ys[[300, 301, 450]] = np.nan
    ys[500, 0] = np.nan
    x0, P0 = np.zeros(n), 10.0 * np.eye(n)
    one = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0)
    # the batch kernel (one covariance per series) on two copies
    two = kalman_filter(np.stack([ys, ys]), F=F, Q=Q, H=H, R=R, x0=x0, P0=np.stack([P0, P0]))
    assert not two.shared_covs
    np.testing.assert_allclose(one.means, two.means[1], rtol=1e-11, atol=1e-11)
    np.testing.assert_allclose(one.covs, two.covs[1], rtol=1e-11, atol=1e-13)
    np.testing.assert_allclose(one.loglik, two.loglik[1], rtol=1e-12)
    fm, fP, fll = filterpy_run(ys, F, Q, H, R, x0, P0)
    np.testing.assert_allclose(one.means, fm, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(one.covs, fP, rtol=1e-9, atol=1e-12)
    assert one.loglik == pytest.approx(fll, rel=1e-10)


def test_cholesky_helpers_factor_and_solve(rng):
    """The compiled Cholesky factor and triangular solves that the Kalman and UKF kernels
    share: ``L L' = A``, ``L X = B``, ``L' X = B``, and ``chol_solve`` is the three in turn;
    a matrix that is not positive definite is refused."""
    from vistrack.filters._kernels import back_solve, chol_factor, chol_solve, forward_solve

    n, k = 5, 3
    G = rng.normal(size=(n, n))
    A, B = G @ G.T + n * np.eye(n), rng.normal(size=(n, k))
    L = np.zeros((n, n))
    assert chol_factor(L, A, n)
    np.testing.assert_allclose(L, np.linalg.cholesky(A), rtol=1e-12, atol=1e-14)
    X = B.copy()
    forward_solve(L, X, n, k)
    np.testing.assert_allclose(L @ X, B, rtol=1e-12, atol=1e-12)
    Y = X.copy()
    back_solve(L, Y, n, k)
    np.testing.assert_allclose(A @ Y, B, rtol=1e-12, atol=1e-12)
    L2, X2 = np.zeros((n, n)), B.copy()
    assert chol_solve(L2, A, X2, n, k)
    assert np.array_equal(L2, L) and np.array_equal(X2, Y)
    assert not chol_factor(np.zeros((n, n)), -A, n)


def test_kalman_filter_class_predict_update_equal_the_functions_and_the_sequence(rng):
    cv, pos = vt.models.ConstantVelocity(dim=2, q=0.3), vt.models.Position(dim=2, r=0.7)
    kf = vt.filters.KalmanFilter(cv, pos)
    ys = rng.normal(size=(3, 6, 2)).cumsum(1)
    ys[0, 2] = np.nan
    seq = kf.filter(ys, x0=np.zeros(4), P0=np.eye(4), dt=0.5)
    g, total = vt.Gaussian(np.zeros((3, 4)), np.tile(np.eye(4), (3, 1, 1))), np.zeros(3)
    for t in range(6):
        if t > 0:
            want = kf_predict(g, cv.F(0.5), cv.Q(0.5))
            g = kf.predict(g, dt=0.5)
            np.testing.assert_array_equal(g.mean, want.mean)
        g, ll = kf.update(g, ys[:, t])
        total += ll
        np.testing.assert_allclose(g.mean, seq.means[:, t], rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(total, seq.loglik, rtol=1e-12)


def test_a_series_of_the_wrong_width_and_a_position_wider_than_the_motion_are_named():
    """Measurements three wide for a 2-D position: named with both sizes, by every method
    that takes a series (numpy said it as a matrix product's core-dimension mismatch); a
    3-D position of a 2-D motion (it would read x, y and vx as the position) is refused."""
    kf = vt.KalmanFilter(vt.ConstantVelocity(dim=2), vt.Position(dim=2))
    want = ("ys must have shape (T, 2) or (B, T, 2): 2 values a step, as Position(dim=2) "
            "measures; got {}")
    for shape in ((10, 3), (4, 10, 1)):
        for method in (kf.filter, kf.smooth, kf.fit, kf.default_prior):
            with pytest.raises(ValueError) as e:
                method(np.zeros(shape))
            assert str(e.value) == want.format(shape)
    with pytest.raises(ValueError) as e:
        vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=1.0), vt.Position(dim=3))
    assert str(e.value) == ("measurement Position(dim=3) measures 3 position components, but "
                            "motion ConstantVelocity(dim=2, q=1.0) moves in 2")
    # fewer is a choice (x alone of a 2-D motion), and works
    one = vt.KalmanFilter(vt.ConstantVelocity(dim=2), vt.Position(dim=1))
    assert one.filter(np.arange(5.0)[:, None]).means.shape == (5, 4)


def test_kf_update_names_the_measurement_when_h_and_r_agree_on_another_size():
    """y three wide where H (2 x 4) and R (2 x 2) agree on two: y is named, not H; where H
    disagrees with R or the state, H is named as before."""
    g = vt.Gaussian(np.zeros(4), np.eye(4))
    with pytest.raises(ValueError) as e:
        kf_update(g, np.zeros(3), np.eye(2, 4), np.eye(2))
    assert str(e.value) == ("y must have 2 values a Gaussian, one for each row of H (2, 4); "
                            "got shape (3,)")
    with pytest.raises(ValueError, match=r"H must have shape \(2, 4\); got \(3, 4\)"):
        kf_update(g, np.zeros(2), np.eye(3, 4), np.eye(2))
    with pytest.raises(ValueError, match=r"H must have shape \(2, 4\); got \(2, 3\)"):
        kf_update(g, np.zeros(2), np.eye(2, 3), np.eye(2))


def test_single_steps_refuse_a_negative_variance_or_a_correlation_beyond_one():
    """kf_predict, kf_update and kf_step accept every positive semi-definite Q and R (rank
    deficient ones too: a constant-velocity model's discrete white-noise Q has rank 1 per
    axis) and refuse a negative variance or a |correlation| above 1 by name; before, Q = -3 I
    gave a prediction with covariance -2 I and R = -0.5 I an update with -I."""
    rng = np.random.default_rng(4)
    g = vt.Gaussian(np.zeros(3), np.eye(3))
    F, H = np.eye(3), np.eye(3)
    y = np.ones(3)
    dt = 0.5
    G = np.array([dt ** 2 / 2, dt, 1.0])
    psd = [np.outer(G, G), np.zeros((3, 3)), np.diag([1.0, 0.0, 2.0])]
    for _ in range(40):
        A = rng.normal(size=(3, int(rng.integers(1, 4))))
        psd.append(A @ A.T)
    for M in psd:
        assert np.linalg.eigvalsh(M).min() >= -1e-12  # the oracle: semi-definite
        kf_predict(g, F, M)
        kf_update(g, y, H, M + np.eye(3) * 1e-9)
        kf_step(g, y, F, M, H, M + np.eye(3) * 1e-9)
    bad = [-0.5 * np.eye(3), np.diag([1.0, -1e-3, 1.0]),
           np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]])]
    for M in bad:
        assert np.linalg.eigvalsh(M).min() < 0
        with pytest.raises(ValueError, match=r"^Q must be positive semi-definite"):
            kf_predict(g, F, M)
        with pytest.raises(ValueError, match=r"^R must be positive semi-definite"):
            kf_update(g, y, H, M)
        with pytest.raises(ValueError, match=r"^Q must be positive semi-definite"):
            kf_step(g, y, F, M, H, np.eye(3))
        with pytest.raises(ValueError, match=r"^R must be positive semi-definite"):
            kf_step(g, y, F, np.eye(3), H, M)


def test_the_filter_class_names_ys_and_dt_where_numpy_or_another_argument_was_named():
    kf = vt.KalmanFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=1.0))
    with pytest.raises(ValueError, match=re.escape("ys must be 2-D or 3-D; got shape (4,)")):
        kf.smooth(np.ones(4))  # an IndexError before
    g = vt.Gaussian(np.zeros(2), np.eye(2))
    with pytest.raises(ValueError, match=re.escape("dt must be one time step, for every "
                                                   "estimate of g; got shape (2,)")):
        kf.predict(g, dt=np.array([1.0, 2.0]))  # "F must have shape (2, 2)" before
    np.testing.assert_array_equal(kf.predict(g, dt=np.float64(2.0)).mean, [0.0, 0.0])


def test_the_steady_state_waits_for_every_variance_at_its_own_scale():
    """A fast random walk (variance 1e8) beside a static level (variance about 1e-2 / t): the
    level's variance moves by far less than 8 ulp of 1e8 a step long before it converges,
    and the shortcut froze it at step 189 (its last mean 20 of its standard deviations off,
    the log-likelihood 22 lower). The oracle is the closed form of a static level, the
    posterior variance 1 / (1/P0 + t/r) and mean their precision-weighted sum; the one-series
    kernel, a batch (the generated kernel) and the same model as a per-step stack (no
    shortcut) all give it."""
    rng = np.random.default_rng(5)
    T = 20000
    F, Q, H, R = np.eye(2), np.diag([1e8, 0.0]), np.eye(2), np.diag([1e8, 1e-2])
    ys = np.c_[1e4 * rng.standard_normal(T), 3.0 + 0.1 * rng.standard_normal(T)]
    kw = dict(Q=Q, H=H, R=R)
    t = np.arange(1, T + 1)
    for P1 in (1.0, 1.5):
        want_var = 1 / (1 / P1 + t / 1e-2)
        want_mean = np.cumsum(ys[:, 1]) / 1e-2 * want_var
        one = kalman_filter(ys, F=F, **kw, x0=[0.0, 0.0], P0=np.diag([1e8, P1]))
        np.testing.assert_allclose(one.covs[:, 1, 1], want_var, rtol=1e-9)
        np.testing.assert_allclose(one.means[:, 1], want_mean, rtol=1e-9)
        stack = kalman_filter(ys, F=np.tile(F, (T, 1, 1)), **kw, x0=[0.0, 0.0],
                              P0=np.diag([1e8, P1]))
        assert float(one.loglik) == pytest.approx(float(stack.loglik), rel=1e-12)
    P0 = np.stack([np.diag([1e8, 1.0 + 0.5 * b]) for b in range(6)])  # a covariance each
    batch = kalman_filter(np.stack([ys] * 6), F=F, **kw, x0=np.zeros((6, 2)), P0=P0)
    for b in (0, 1, 5):
        want_var = 1 / (1 / P0[b, 1, 1] + t / 1e-2)
        np.testing.assert_allclose(batch.covs[b, :, 1, 1], want_var, rtol=1e-9)
        np.testing.assert_allclose(batch.means[b, :, 1],
                                   np.cumsum(ys[:, 1]) / 1e-2 * want_var, rtol=1e-9)


def test_a_models_filter_names_a_prior_of_another_size_and_takes_every_form_of_dt():
    """A prior of 1 state for a model of 2 was named as F ("F must have shape (1, 1) ...;
    got (2, 2)"), a matrix the user never gave, in KalmanFilter.filter and simulate;
    LinearMotion refused the T-1 intervals it is documented to take (the unused first step
    was given dt 0) and np.diff(times, prepend=nan). Each form of dt filters as the scalar
    (the oracle: the same discrete model)."""
    from vistrack.filters import KalmanFilter
    from vistrack.models import ConstantVelocity, LinearMeasurement, LinearMotion, Position
    from vistrack.simulate import simulate

    kf = KalmanFilter(ConstantVelocity(dim=1), Position(dim=1))
    with pytest.raises(ValueError, match=re.escape("x0 must have shape (2,) or (B, 2), as the "
                                                   "motion model ConstantVelocity(dim=1")):
        kf.filter(np.arange(5.0)[:, None], x0=[0.0], P0=[[1.0]])
    with pytest.raises(ValueError, match=re.escape("P0 must have shape (2, 2) or (B=1, 2, 2)")):
        kf.filter(np.arange(5.0)[:, None], x0=[0.0, 0.0], P0=[[1.0]])
    with pytest.raises(ValueError, match=re.escape("x0 must have shape (4,)")):
        simulate(ConstantVelocity(dim=2), Position(dim=2), 3, x0=[0.0, 0.0])
    lin = KalmanFilter(LinearMotion([[1.0, 1.0], [0.0, 1.0]], 0.1 * np.eye(2)),
                       LinearMeasurement([[1.0, 0.0]], [[1.0]]))
    ys = np.arange(5.0)[:, None] ** 1.5
    prior = dict(x0=[0.0, 0.0], P0=np.eye(2))
    want = lin.filter(ys, **prior).means
    times = np.arange(5.0)
    for dt in (np.ones(4), np.ones(5), np.diff(times, prepend=np.nan)):
        np.testing.assert_array_equal(lin.filter(ys, dt=dt, **prior).means, want)
    cv = KalmanFilter(ConstantVelocity(dim=1, q=0.3), Position(dim=1))
    np.testing.assert_array_equal(cv.filter(ys, dt=np.diff(times, prepend=np.nan), **prior).means,
                                  cv.filter(ys, dt=1.0, **prior).means)


def test_one_step_and_the_1d_filter_name_what_the_n_d_filter_names():
    """kf_step given a measurement of the wrong size named H (kf_update names y, and kf_step
    says it makes the same checks); the 1-D filter returned NaN (or raised ZeroDivisionError)
    where the n-D filter with n = 1 refuses a step of zero innovation variance; and a
    LinearMotion with a Q per step and one F refused f(x)."""
    from vistrack.models import LinearMotion

    g = vt.Gaussian(np.zeros(2), np.eye(2))
    args = (np.eye(2), np.eye(2), [[1.0, 0.0]], [[1.0]])
    for call in (lambda: kf_step(g, [1.0, 2.0], *args),
                 lambda: kf_update(g, [1.0, 2.0], *args[2:])):
        with pytest.raises(ValueError, match=re.escape("y must have 1 value a Gaussian, one "
                                                       "for each row of H (1, 2); got shape "
                                                       "(2,)")):
            call()
    for kw in (dict(sigma_m=[1.0, 0.0, 0.0], sigma_d=0.0), dict(sigma_m=0.0, sigma0=0.0),
               dict(m=0.0, sigma_m=0.0)):
        model = dict(d=1.0, m=1.0, sigma_d=0.5, sigma_m=1.0, x0=0.0, sigma0=1.0) | kw
        with pytest.raises(ValueError, match=r"the innovation variance sigma_m\^2 \+ m\^2 "
                                             r"pred_std\^2 is 0 at step \d"):
            kalman_filter_1d([1.0, 2.0, 3.0], **model)
        T = 3
        arr = {k: np.broadcast_to(np.asarray(v, float), (T,)) for k, v in model.items()
               if k not in ("x0", "sigma0")}
        if "sigma_d" in kw:
            continue  # (the n-D filter's Joseph form leaves 6e-33 there, and goes on)
        with pytest.raises(ValueError, match="not positive definite"):  # the n-D filter
            kalman_filter(np.array([1.0, 2.0, 3.0])[:, None], F=arr["d"][:, None, None],
                          Q=(arr["sigma_d"] ** 2)[:, None, None], H=arr["m"][:, None, None],
                          R=(arr["sigma_m"] ** 2)[:, None, None], x0=[model["x0"]],
                          P0=[[model["sigma0"] ** 2]])
    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    per_step_q = LinearMotion(F, np.stack([np.eye(2)] * 3))
    np.testing.assert_array_equal(per_step_q.f(np.array([0.0, 2.0])), F @ [0.0, 2.0])


@pytest.mark.parametrize("batch", [False, True])
@pytest.mark.parametrize("kind", ["kalman_filter", "ukf"])
def test_changing_the_last_estimate_leaves_the_read_only_results_as_they_are(batch, kind):
    """``FilterResult.last``, where a tracker goes on from, is the results' last estimate but
    not a view of them: ``last.mean`` was a writable view of the read-only ``means`` (the
    UKF's ``last.cov`` of ``covs``), so going on from it in place changed the stored results
    (and what a smoother then read). The oracle is the results before the change."""
    F, Q, H, R = [[1.0, 1.0], [0.0, 1.0]], 0.01 * np.eye(2), [[1.0, 0.0]], [[0.25]]
    ys = np.array([[0.1], [0.9], [np.nan], [3.2]])
    ys = np.stack([ys, ys + 1]) if batch else ys
    if kind == "kalman_filter":
        res = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=[0.0, 1.0], P0=np.eye(2))
    else:
        res = vt.filters.UnscentedKalmanFilter(vt.ConstantVelocity(dim=1, q=0.01),
                                               vt.Position(dim=1, r=0.25)).filter(
            ys, x0=[0.0, 1.0], P0=np.eye(2))
    means, covs = np.array(res.means), np.array(res.covs)
    np.testing.assert_array_equal(res.last.mean, means[..., -1, :])
    res.last.mean[...] = 1e9
    if res.last.cov.flags.writeable:  # (one covariance shared by a batch: broadcast, read-only)
        res.last.cov[...] = 1e9
    np.testing.assert_array_equal(res.means, means)
    np.testing.assert_array_equal(res.covs, covs)
    assert not res.means.flags.writeable


def test_a_covariance_symmetric_to_rounding_is_taken_by_the_step_functions():
    """The step functions' compiled check measured asymmetry against each entry's own size:
    a rotated isotropic R, whose off-diagonal entries near 0 differ from their transposes
    by 1e-18, was "R must be symmetric" in kf_update, kf_predict and kf_step, while
    kalman_filter and the model constructors took it (500 of 500 rotations). Oracle: the
    textbook update with the matrix made exactly symmetric; and an asymmetry beyond the
    tolerance of the largest entry is still refused, naming the entry."""
    rng = np.random.default_rng(0)
    U, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    R = U @ np.diag([0.3, 0.3, 0.3]) @ U.T
    assert np.abs(R - R.T).max() > 0
    g = vt.Gaussian(np.zeros(3), np.eye(3))
    y = np.array([0.5, -1.0, 2.0])
    post = kf_update(g, y, np.eye(3), R)
    Rs = (R + R.T) / 2
    K = np.linalg.solve(np.eye(3) + Rs, np.eye(3)).T  # P H' S^-1 with P = H = I
    np.testing.assert_allclose(post.mean, K @ y, atol=1e-12)
    kf_predict(g, np.eye(3), R)
    kf_step(g, y, np.eye(3), R, np.eye(3), R)
    bad = np.eye(3)
    bad[0, 2] = 1e-3
    for call, name in ((lambda: kf_predict(g, np.eye(3), bad), "Q"),
                       (lambda: kf_update(g, y, np.eye(3), bad), "R")):
        with pytest.raises(ValueError, match=re.escape(
                f"{name} must be symmetric; {name}[0, 2] = 0.001 but its transpose entry is "
                "0.0")):
            call()


def test_the_step_functions_name_what_they_passed_on_as_nan():
    """A NaN or infinite mean or covariance in g came out as NaN means without a word (the
    whole-series filter refuses a NaN x0); the matrices' own errors named no entry; a state
    of the wrong size blamed the model's F or H; a ragged F or H gave numpy's words; a
    standard deviation past 1.3e154 an OverflowError; a single series' loglik was
    writable; default_prior took a scale of NaN."""
    from vistrack.filters import KalmanFilter, kalman_filter_1d
    from vistrack.models import ConstantVelocity, Position

    H, R = np.array([[1.0, 0.0]]), np.array([[0.25]])
    for mean, cov, name, where in (([np.nan, 0.0], np.eye(2), "g.mean", "g.mean[0] = nan"),
                                   ([0.0, 0.0], [[1, 0], [0, np.inf]], "g.cov",
                                    "g.cov[1, 1] = inf")):
        g = vt.Gaussian(np.array(mean), np.array(cov, float))
        for call in (lambda g=g: kf_update(g, [1.0], H, R),
                     lambda g=g: kf_predict(g, np.eye(2), np.eye(2)),
                     lambda g=g: kf_step(g, [1.0], np.eye(2), np.eye(2), H, R)):
            with pytest.raises(ValueError, match=re.escape(f"{name} must be finite; {where}")):
                call()
    g = vt.Gaussian(np.zeros(2), np.eye(2))
    with pytest.raises(ValueError, match=re.escape("Q must be finite; Q[1, 0] = nan")):
        kf_predict(g, np.eye(2), [[1, 0], [np.nan, 1]])
    with pytest.raises(ValueError, match=re.escape(
            "R must be positive semi-definite; R[0, 0] = -1, a negative variance")):
        kf_update(g, [1.0], H, [[-1.0]])
    with pytest.raises(ValueError, match=re.escape(
            "Q must be positive semi-definite; Q[0, 1] = 2, beyond the product of the two "
            "standard deviations, 1")):
        kf_predict(g, np.eye(2), [[1.0, 2.0], [2.0, 1.0]])
    # a prediction that overflows from a finite g is named as such (g.mean was blamed)
    with pytest.raises(ValueError, match=re.escape(
            "the prediction F m, F P F' + Q is not finite: it overflowed")):
        kf_step(vt.Gaussian(np.array([1e200, 0.0]), np.eye(2)), [0.0, 0.0], 1e200 * np.eye(2),
                np.eye(2), np.eye(2), np.eye(2))
    # the entry the compiled check refused, at its tolerances (-1e-20 beside 1 is a
    # variance of 0 there, and 1 + 1e-12 beside 1 a correlation of 1)
    g3 = vt.Gaussian(np.zeros(3), np.eye(3))
    for Q in ([[-1e-20, 0, 0], [0, 1, 2], [0, 2, 1]],
              [[1, 1 + 1e-12, 0], [1 + 1e-12, 1, 2], [0, 2, 1]]):
        with pytest.raises(ValueError, match=re.escape(
                "Q must be positive semi-definite; Q[1, 2] = 2, beyond the product")):
            kf_predict(g3, np.eye(3), Q)
    kf = KalmanFilter(ConstantVelocity(dim=2, q=0.1), Position(dim=2, r=0.5))
    for call in (lambda: kf.predict(g), lambda: kf.update(g, [1.0, 2.0])):
        with pytest.raises(ValueError, match=re.escape(
                "g must have a state of 4 values, the motion model's (ConstantVelocity); got 2 "
                "(g.mean of shape (2,))")):
            call()
    with pytest.raises(TypeError, match="F must be an array of numbers"):
        kalman_filter([[1.0]], F=[[1, 1], [0]], Q=np.eye(2), H=H, R=R, x0=np.zeros(2),
                      P0=np.eye(2))
    with pytest.raises(TypeError, match="H must be an array of numbers"):
        kf_update(g, [1.0], [[1, 0], [0]], R)
    for kw in ({"sigma_d": 1e200}, {"sigma0": 1e200}, {"m": 1e160}):
        args = {"d": 1, "m": 1, "sigma_d": 1, "sigma_m": 1, "x0": 0, "sigma0": 1, **kw}
        name = next(iter(kw))
        with pytest.raises(ValueError, match=re.escape(f"{name} must be below 1.341e+154 in "
                                                       "size, its square a finite number")):
            kalman_filter_1d([1.0, 2.0], **args)
    assert kalman_filter_1d([1.0, 2.0], d=1, m=1, sigma_d=1e100, sigma_m=1, x0=0,
                            sigma0=1e100).mean[1] == pytest.approx(2.0)
    res = kalman_filter(np.array([[1.0], [2.0]]), F=np.eye(2), Q=np.eye(2), H=H, R=R,
                        x0=np.zeros(2), P0=np.eye(2))
    assert not res.loglik.flags.writeable
    ys = np.array([[1.0, 2.0], [2.0, 3.0]])
    for bad in (np.nan, -2.0):
        with pytest.raises(ValueError, match="scale must be a finite number >= 0"):
            kf.default_prior(ys, scale=bad)
    assert kf.default_prior(ys, scale=0.0)[1].diagonal()[2:].tolist() == [0.0, 0.0]
    with pytest.raises(TypeError, match="scale must be a number"):
        kf.default_prior(ys, scale="a")


@pytest.mark.parametrize("B", [3, 40])
def test_a_batch_names_the_series_whose_innovation_covariance_fails(B):
    """A batch said "not positive definite at step 0" and left the series to be guessed;
    it names the series (here the one whose prior leaves a noiseless component exact, so
    that S = H P0 H' + R has a zero variance there: diag(2, 0))."""
    P0 = np.broadcast_to(np.eye(2), (B, 2, 2)).copy()
    P0[B // 2] = np.diag([1.0, 0.0])
    args = dict(F=np.eye(2), Q=np.eye(2), H=np.eye(2), R=np.diag([1.0, 0.0]),
                x0=np.zeros(2))
    with pytest.raises(ValueError, match=rf"not positive definite at step 0 of series {B // 2};"):
        kalman_filter(np.ones((B, 4, 2)), P0=P0, **args)
    with pytest.raises(ValueError, match=r"not positive definite at step 0; R must"):
        kalman_filter(np.ones((4, 2)), P0=P0[B // 2], **args)
    # the other series alone filter (the oracle of which one fails)
    kalman_filter(np.ones((4, 2)), P0=P0[0], **args)


def test_complex_measurements_and_priors_are_refused():
    """Complex values were cast to their real parts with numpy's ComplexWarning alone."""
    E = np.eye(2)
    args = dict(F=E, Q=E, H=E, R=E, x0=np.zeros(2), P0=E)
    for name, value in (("ys", np.ones((5, 2)) + 1j), ("x0", np.zeros(2) + 0j),
                        ("P0", E.astype(complex)), ("F", E.astype(np.complex64))):
        kw = dict(args, ys=np.ones((5, 2)))
        kw[name] = value
        ys = kw.pop("ys")
        with pytest.raises(TypeError, match=rf"{name} must be real numbers; got complex"):
            kalman_filter(ys, **kw)


def test_a_complex_gaussian_is_refused():
    """Gaussian([1+5j, 0], I) became mean [1, 0] with numpy's ComplexWarning alone, and
    kf_predict and the UKF took it."""
    with pytest.raises(TypeError, match=r"Gaussian mean must be real numbers; got complex"):
        vt.Gaussian(np.array([1 + 5j, 0.0]), np.eye(2))
    with pytest.raises(TypeError, match=r"Gaussian cov must be real numbers; got complex"):
        vt.Gaussian(np.zeros(2), np.eye(2) + 1j)
    assert vt.Gaussian([1, 0], np.eye(2, dtype=int)).mean.dtype == np.float64


_LONG_MEASUREMENT = """
import numpy as np
from vistrack.filters import kalman_filter

def numpy_filter(ys, F, Q, H, R, x0, P0):
    x, P, ll, means = np.array(x0, float), np.array(P0, float), 0.0, []
    for t, y in enumerate(ys):
        if t:
            x, P = F @ x, F @ P @ F.T + Q
        S = H @ P @ H.T + R
        K = np.linalg.solve(S, H @ P).T
        e = y - H @ x
        ll -= 0.5 * (e @ np.linalg.solve(S, e) + np.linalg.slogdet(2 * np.pi * S)[1])
        x, P = x + K @ e, P - K @ S @ K.T
        means.append(x)
    return np.array(means), ll

for n, m in ((1, 60), (2, 10), (4, 20)):
    rng = np.random.default_rng(n + m)
    F, Q = np.eye(n), 0.1 * np.eye(n)
    H, R = rng.normal(size=(m, n)), 0.5 * np.eye(m)
    ys = rng.normal(size=(500, m))
    r = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=np.zeros(n), P0=np.eye(n))
    means, ll = numpy_filter(ys, F, Q, H, R, np.zeros(n), np.eye(n))
    assert np.abs(r.means - means).max() < 1e-9 and abs(float(r.loglik) - ll) < 1e-6 * abs(ll)
blocks = [np.ones(k) for k in range(1, 3000)]  # (the heap, used after the filter)
print("ok")
"""


def test_a_measurement_longer_than_the_state_does_not_write_past_its_work_space():
    """Once the covariance reached its steady state, the single-series kernel wrote each
    step's whitened innovation (m values) into a work array of n rows: with m > n it wrote
    past it, and the process died after the filter (status 139, n = 1 and m = 60). Run in a
    process of its own; the oracle is a plain numpy Kalman filter."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _LONG_MEASUREMENT], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0 and done.stdout.strip() == "ok", (done.returncode,
                                                                   done.stderr[-2000:])


def test_a_negative_variance_is_named_and_a_noise_of_units_far_apart_is_taken():
    """A negative variance was refused as "its smallest eigenvalue is -0.5", and kf_predict,
    whose compiled check takes -0.5 beside 1e10 for rounding but then refuses the pair,
    named Q[0, 1] = 0 beside a NaN: each names the variance now. Semi-definiteness keeps the
    tolerance of a computed covariance's rounding, 1e-10 of the largest entry (as scipy's);
    a positive definite noise given, judged on its correlation matrix, is taken at units far
    apart (diag(1e4, 1e-7) was refused, "its smallest eigenvalue is 1e-07"), and the
    eigenvalue named is the one judged."""
    ys = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 2.0]])
    kw = dict(F=np.eye(2), H=np.eye(2), x0=[0.0, 0.0], P0=np.eye(2))
    with pytest.raises(ValueError, match=re.escape(  # (one matrix: "(matrix [0])" before)
            "Q must be positive semi-definite; Q[1, 1] = -0.5, a negative variance")):
        kalman_filter(ys, Q=np.diag([1.0, -0.5]), R=np.eye(2), **kw)
    with pytest.raises(ValueError, match=re.escape("R[1, 1] = -0.1, a negative variance")):
        kalman_filter(ys, Q=np.eye(2), R=np.diag([1.0, -0.1]), **kw)
    with pytest.raises(ValueError, match=re.escape(
            "Q must be positive semi-definite; Q[1, 1] = -0.5, a negative variance")):
        kf_predict(vt.Gaussian(np.zeros(2), np.eye(2)), np.eye(2), np.diag([1e10, -0.5]))
    # rounding is not refused: a variance of -1e-20 beside 1, and the posterior of two exact
    # measurements, P - K S K', whose variances come out about -1e-12
    kalman_filter(ys, Q=np.diag([1.0, -1e-20]), R=np.eye(2), **kw)
    from vistrack._validate import check_psd

    rng = np.random.default_rng(0)
    for _ in range(200):
        A = rng.normal(size=(3, 3))
        P = A @ A.T
        H = np.eye(3)[:2]
        K = np.linalg.solve(H @ P @ H.T, H @ P).T
        post = P - K @ (H @ P @ H.T) @ K.T
        check_psd(0.5 * (post + post.T), "P")
    r = vt.Position(dim=2, r=np.diag([1e4, 1e-7]))
    np.testing.assert_array_equal(r.R(), np.diag([1e4, 1e-7]))
    with pytest.raises(ValueError, match=re.escape("r[1, 1] = 0, a variance of 0")):
        vt.Position(dim=2, r=np.diag([1e4, 0.0]))
    near = 1e10 * np.array([[1.0, 1 - 1e-11], [1 - 1e-11, 1.0]])
    with pytest.raises(ValueError, match=r"^r must be positive definite; its correlation "
                                         r"matrix's smallest eigenvalue is [0-9.e+-]+$") as e:
        vt.Position(dim=2, r=near)
    assert float(str(e.value).rsplit(" ", 1)[1]) < 1e-10


def test_a_linear_measurement_keeps_its_own_matrices():
    """LinearMeasurement kept the caller's H and R and gave them out: an R changed after the
    check (to -3), or through the array R() returned, was used unchecked. Its own copies
    now, as LinearMotion's."""
    from vistrack.models import LinearMeasurement

    H, R = np.array([[1.0, 0.0]]), np.array([[0.5]])
    me = LinearMeasurement(H, R)
    R[0, 0], H[0, 0] = -3.0, 7.0
    assert me.R().tolist() == [[0.5]] and me.H().tolist() == [[1.0, 0.0]]
    me.R()[0, 0] = -7.0
    me.H()[0, 1] = 9.0
    assert me.R().tolist() == [[0.5]] and me.H().tolist() == [[1.0, 0.0]]
    # and Position and NonlinearMeasurement, which kept a view of the caller's r and R
    from vistrack.models import NonlinearMeasurement

    r = np.eye(2)
    pos = vt.Position(dim=2, r=r)
    nl = NonlinearMeasurement(lambda x: x[..., :2], r, ndim_state=2)
    r[1, 1] = -3.0
    assert pos.R().tolist() == nl.R().tolist() == [[1.0, 0.0], [0.0, 1.0]]


def test_a_model_matrix_at_fault_is_named_by_its_index_as_given():
    """One Q or R (n, n) at fault was named by the index of its stack, Q[0, 0, 1], an index
    the matrix given does not have (kalman_filter, em); a per-step stack's keeps its step."""
    from vistrack.filters import em

    A = np.array([[1.0, 0.5], [0.2, 1.0]])
    kw = dict(F=np.eye(2), H=np.array([[1.0, 0.0]]), x0=np.zeros(2), P0=np.eye(2))
    ys = np.zeros((5, 1))
    for run in (kalman_filter, em):
        with pytest.raises(ValueError, match=r"^Q must be symmetric; Q\[0, 1\] = 0\.5 but its "
                                             r"transpose entry is 0\.2$"):
            run(ys, Q=A, R=np.eye(1), **kw)
    with pytest.raises(ValueError, match=r"^R must be positive semi-definite; R\[1, 1\] = -1, a "
                                         r"negative variance$"):
        kalman_filter(np.zeros((5, 2)), F=np.eye(2), Q=np.eye(2), H=np.eye(2),
                      R=np.diag([1.0, -1.0]), x0=np.zeros(2), P0=np.eye(2))
    with pytest.raises(ValueError, match=r"^Q must be symmetric; Q\[4, 0, 1\] = 0\.5"):
        kalman_filter(ys, Q=np.stack([np.eye(2)] * 4 + [A]), R=np.eye(1), **kw)


def test_arguments_the_filters_took_or_named_in_other_words():
    """From a new user's walk: ``KalmanFilter.online`` took the text "0.5" as a step and True
    as 1 (``predict`` refuses both), and None or an array failed in ``float()``'s words;
    ``filter(dt=None)`` said "got nan"; the EKF's ``loglik`` was writable though
    ``FilterResult``'s arrays are read-only; ``pda_update`` given a tuple failed on "has no
    attribute 'mean'"; the filters took ``BoxMotion`` and failed at the first step on
    "boxes must have shape (K, 4)"; ``kalman_filter_1d`` said "d[] = nan" and read None as
    NaN. Oracle: the words each argument's own check gives elsewhere."""
    from vistrack.filters import ExtendedKalmanFilter, KalmanFilter, pda_update
    from vistrack.models import BoxMotion, ConstantVelocity, LinearMeasurement, Position

    kf = KalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1))
    for dt in ("0.5", True, None, np.array([1.0, 2.0])):
        with pytest.raises(ValueError, match=re.escape(f"dt must be a number; got {dt!r}")):
            kf.online([0.0, 1.0], np.eye(2), dt=dt)
    f = kf.online([0.0, 1.0], np.eye(2), dt=np.float32(0.5))  # a number of numpy's: taken
    f.predict()
    np.testing.assert_allclose(f.mean, [0.5, 1.0])
    with pytest.raises(ValueError, match=re.escape(
            "dt must be a number or an array of numbers; got None")):
        kf.filter(np.zeros((3, 1)), dt=None)
    ekf = ExtendedKalmanFilter(ConstantVelocity(dim=1), Position(dim=1))
    r = ekf.filter(np.zeros((3, 1)), x0=[0.0, 0.0], P0=np.eye(2))
    assert not r.loglik.flags.writeable and not r.means.flags.writeable
    with pytest.raises(TypeError, match=re.escape("g must be a vistrack.Gaussian; got tuple")):
        pda_update((np.zeros((1, 2)), np.eye(2)[None]), np.zeros((1, 2)), np.eye(2),
                   np.eye(2), [[0.5]], [0.5])
    box = (BoxMotion(), LinearMeasurement(np.eye(4, 8), np.eye(4)))
    for make in (KalmanFilter, ExtendedKalmanFilter):
        with pytest.raises(TypeError, match=re.escape(
                "motion is a BoxMotion, whose noise Q(boxes, dt) follows the boxes' sizes")):
            make(*box)
    one = dict(m=1, sigma_d=1, sigma_m=1, sigma0=1)
    with pytest.raises(ValueError, match=re.escape("d must be finite; got nan")):
        kalman_filter_1d([1.0], d=np.nan, x0=0, **one)
    with pytest.raises(ValueError, match=re.escape("x0 must be a finite number; got None")):
        kalman_filter_1d([1.0], d=1, x0=None, **one)
