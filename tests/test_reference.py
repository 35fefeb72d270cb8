"""The plain-numpy equations of ``vistrack.filters.reference`` against FilterPy and scipy, and
every compiled path (kf_predict, kf_update, kf_step, kalman_filter, rts_smooth) and the EKF
against them."""

import numpy as np
import pytest
from scipy import stats

import vistrack as vt
from vistrack.filters import kalman_filter, kf_predict, kf_step, kf_update, rts_smooth
from vistrack.filters.reference import condition_on, kalman_update, predict, smooth_step

from .conftest import random_model

filterpy_kalman = pytest.importorskip("filterpy.kalman")


def spd(rng, k, scale=1.0, lead=()):
    A = rng.normal(size=lead + (k, k))
    return scale * (A @ np.swapaxes(A, -1, -2) / k + np.eye(k))


@pytest.mark.parametrize("n,m", [(1, 1), (2, 1), (4, 2), (6, 3), (2, 4)])
def test_predict_and_update_equal_filterpy_and_scipy(rng, n, m):
    mod = random_model(rng, n, m)
    x, P = rng.normal(size=n), spd(rng, n)
    y = rng.normal(size=m)
    y[rng.random(m) < 0.3] = np.nan
    o = ~np.isnan(y)
    kf = filterpy_kalman.KalmanFilter(dim_x=n, dim_z=m)
    kf.x, kf.P = x.copy(), P.copy()
    kf.predict(F=mod["F"], Q=mod["Q"])
    xp, Pp = predict(x, P, mod["F"], mod["Q"])
    np.testing.assert_allclose(xp, kf.x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(Pp, kf.P, rtol=1e-12, atol=1e-12)
    mean, cov, ll = kalman_update(xp, Pp, y, mod["H"], mod["R"])
    if o.any():
        H, R = mod["H"][o], mod["R"][np.ix_(o, o)]
        kf.update(y[o], R=R, H=H)
        S = H @ Pp @ H.T + R
        assert ll == pytest.approx(stats.multivariate_normal(H @ xp, S).logpdf(y[o]), rel=1e-10)
    else:
        assert ll == 0.0
    np.testing.assert_allclose(mean, kf.x, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(cov, kf.P, rtol=1e-10, atol=1e-10)
    np.testing.assert_array_equal(cov, cov.T)


def test_condition_on_takes_a_jacobian_per_gaussian(rng):
    n, m, B = 3, 2, 5
    x, P = rng.normal(size=(B, n)), spd(rng, n, lead=(B,))
    H, R = rng.normal(size=(B, m, n)), spd(rng, m)
    e = rng.normal(size=(B, m))
    mean, cov, ll = condition_on(x, P, H, R, e)
    for b in range(B):
        one = condition_on(x[b], P[b], H[b], R, e[b])
        np.testing.assert_allclose(mean[b], one[0], rtol=1e-12)
        np.testing.assert_allclose(cov[b], one[1], rtol=1e-12)
        assert ll[b] == pytest.approx(float(one[2]), rel=1e-12)


def test_smooth_step_equals_filterpy_rts_smoother(rng):
    n, m, T = 4, 2, 30
    mod = random_model(rng, n, m)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), rng=rng)
    res = kalman_filter(ys, **mod, x0=np.zeros(n), P0=np.eye(n))
    xs, Ps = np.array(res.means), np.array(res.covs)
    fm, fP, _, _ = filterpy_kalman.rts_smoother(xs, Ps, np.tile(mod["F"], (T, 1, 1)),
                                                np.tile(mod["Q"], (T, 1, 1)))
    sm, sP = xs.copy(), Ps.copy()
    for t in range(T - 2, -1, -1):
        sm[t], sP[t] = smooth_step(xs[t], Ps[t], sm[t + 1], sP[t + 1], mod["F"], mod["Q"])
    np.testing.assert_allclose(sm, fm, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(sP, fP, rtol=1e-9, atol=1e-10)


@pytest.mark.parametrize("n,m,B", [(1, 1, 7), (2, 1, 5), (4, 2, 9), (8, 4, 6), (3, 5, 4)])
def test_compiled_kernels_equal_the_reference(rng, n, m, B):
    mod = random_model(rng, n, m)
    x, P = rng.normal(size=(B, n)), spd(rng, n, lead=(B,))
    y = rng.normal(size=(B, m))
    y[rng.random((B, m)) < 0.3] = np.nan
    y[0] = np.nan  # one Gaussian with nothing observed
    g = vt.Gaussian(x, P)
    pred = kf_predict(g, mod["F"], mod["Q"])
    xp, Pp = predict(x, P, mod["F"], mod["Q"])
    np.testing.assert_allclose(pred.mean, xp, rtol=1e-12, atol=1e-13)
    np.testing.assert_allclose(pred.cov, Pp, rtol=1e-12, atol=1e-13)
    mean, cov, ll = kalman_update(xp, Pp, y, mod["H"], mod["R"])
    for post in (kf_update(pred, y, mod["H"], mod["R"]),
                 kf_step(g, y, mod["F"], mod["Q"], mod["H"], mod["R"])):
        np.testing.assert_allclose(post.mean, mean, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(post.cov, cov, rtol=1e-10, atol=1e-12)
    np.testing.assert_array_equal(mean[0], xp[0])
    assert ll[0] == 0.0


@pytest.mark.parametrize("batch", [False, True])
def test_sequence_filter_and_rts_equal_the_reference_loop(rng, batch):
    n, m, T = 4, 2, 25
    mod = random_model(rng, n, m)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), rng=rng)
    ys[rng.random(ys.shape) < 0.2] = np.nan
    if batch:
        ys = np.stack([ys, ys[::-1]])
    res = kalman_filter(ys, **mod, x0=np.zeros(n), P0=np.eye(n))
    sm = rts_smooth(res, F=mod["F"], Q=mod["Q"])
    for b, series in enumerate(ys if batch else ys[None]):
        x, P, total = np.zeros(n), np.eye(n), 0.0
        xs, Ps = [], []
        for t, y in enumerate(series):
            if t > 0:
                x, P = predict(x, P, mod["F"], mod["Q"])
            x, P, ll = kalman_update(x, P, y, mod["H"], mod["R"])
            total += float(ll)
            xs.append(x)
            Ps.append(P)
        means = res.means[b] if batch else res.means
        covs = res.covs[b] if batch else res.covs
        np.testing.assert_allclose(means, xs, rtol=1e-9, atol=1e-11)
        np.testing.assert_allclose(covs, Ps, rtol=1e-9, atol=1e-11)
        assert (res.loglik[b] if batch else res.loglik) == pytest.approx(total, rel=1e-10)
        s_m, s_P = list(xs), list(Ps)
        for t in range(T - 2, -1, -1):
            s_m[t], s_P[t] = smooth_step(xs[t], Ps[t], s_m[t + 1], s_P[t + 1], mod["F"], mod["Q"])
        np.testing.assert_allclose(sm.means[b] if batch else sm.means, s_m, rtol=1e-8,
                                   atol=1e-10)
        np.testing.assert_allclose(sm.covs[b] if batch else sm.covs, s_P, rtol=1e-8,
                                   atol=1e-10)


def test_ekf_is_condition_on_with_the_models_residual_and_jacobian(rng):
    """On a linear model the EKF's update is the reference Kalman update."""
    cv, pos = vt.models.ConstantVelocity(dim=2, q=0.1), vt.models.Position(dim=2, r=0.5)
    x, P = rng.normal(size=(6, 4)), spd(rng, 4, lead=(6,))
    y = rng.normal(size=(6, 2))
    y[2, 1] = y[4] = np.nan
    post = vt.filters.ekf_update(vt.Gaussian(x, P), y, pos)
    mean, cov, _ = kalman_update(x, P, y, pos.H(4), pos.R())
    np.testing.assert_allclose(post.mean, mean, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(post.cov, cov, rtol=1e-13, atol=1e-14)
    pred = vt.filters.ekf_predict(vt.Gaussian(x, P), cv, dt=0.5)
    xp, Pp = predict(x, P, cv.F(0.5), cv.Q(0.5))
    np.testing.assert_allclose(pred.mean, xp, rtol=1e-13, atol=1e-14)
    np.testing.assert_allclose(pred.cov, Pp, rtol=1e-13, atol=1e-14)


def test_condition_on_refuses_an_indefinite_innovation_covariance():
    with pytest.raises(ValueError, match="not positive definite"):
        condition_on(np.zeros(2), np.zeros((2, 2)), np.eye(2), -np.eye(2), np.ones(2))
