"""Nonlinear models, EKF, UKF and EnKF: against finite differences, the Kalman filter on linear
models, and FilterPy's UnscentedKalmanFilter."""

import re

import numpy as np
import pytest

import vistrack as vt
from vistrack.filters import (
    Ensemble,
    EnsembleKalmanFilter,
    ExtendedKalmanFilter,
    IMMFilter,
    JulierSigmaPoints,
    MerweScaledSigmaPoints,
    ParticleFilter,
    UnscentedKalmanFilter,
    ekf_update,
    enkf_update,
    kalman_filter,
    ukf_predict,
    ukf_update,
)
from vistrack.models import (
    CoordinatedTurn,
    MeasurementFunctions,
    NonlinearMeasurement,
    NonlinearMotion,
    RangeBearing,
    growth_model,
    numerical_jacobian,
    psd_sqrt,
    wrap_angle,
)

filterpy_kalman = pytest.importorskip("filterpy.kalman")


# ---------------------------------------------------------------- models
@pytest.mark.parametrize("w", [0.7, -0.3, 1e-6, 0.0])
def test_coordinated_turn_jacobian_equals_finite_differences(rng, w):
    ct = CoordinatedTurn()
    x = np.array([[1.0, -2.0, 3.0, 0.5, w], [0.0, 0.0, -1.0, 2.0, w]])
    for dt in (0.1, 1.0, 2.5):
        J = ct.jacobian(x, dt)
        Jn = numerical_jacobian(lambda z, dt=dt: ct.f(z, dt), x, eps=1e-7)
        np.testing.assert_allclose(J, Jn, rtol=1e-6, atol=1e-7)


def test_coordinated_turn_tends_to_constant_velocity():
    ct, cv = CoordinatedTurn(q=0.3), vt.ConstantVelocity(dim=2, q=0.3)
    x = np.array([1.0, 2.0, 3.0, -4.0])
    for w in (0.0, 1e-9, 1e-5):
        # the velocity turns by w dt: |change| <= |w| dt |v| (|v| = 5), positions by less
        np.testing.assert_allclose(ct.f(np.append(x, w), 0.7)[:4], cv.F(0.7) @ x, rtol=0,
                                   atol=abs(w) * 0.7 * 5.0 + 1e-15)
    np.testing.assert_allclose(ct.Q(0.7)[:4, :4], cv.Q(0.7), rtol=1e-15)


def test_coordinated_turn_turns_a_quarter_circle():
    # speed 1, turn rate pi/2 for 1 s: a quarter of a circle of radius 2/pi
    x = CoordinatedTurn().f(np.array([0.0, 0.0, 1.0, 0.0, np.pi / 2]), 1.0)
    r = 2 / np.pi
    np.testing.assert_allclose(x, [r, r, 0.0, 1.0, np.pi / 2], atol=1e-15)


def test_range_bearing_and_growth_jacobians_equal_finite_differences(rng):
    rb = RangeBearing(sensor=(1.0, -2.0), ndim_state=4)
    x = rng.normal(size=(6, 4)) * 5
    np.testing.assert_allclose(rb.jacobian(x), numerical_jacobian(rb.h, x), rtol=1e-6, atol=1e-9)
    motion, meas = growth_model()
    x = rng.normal(size=(7, 1)) * 3
    np.testing.assert_allclose(motion.jacobian(x, t=3.0),
                               numerical_jacobian(lambda z: motion.f(z, t=3.0), x), rtol=1e-6)
    np.testing.assert_allclose(meas.jacobian(x), numerical_jacobian(meas.h, x), rtol=1e-6)


def test_bearing_residual_and_mean_wrap():
    rb = RangeBearing()
    r = rb.residual(np.array([10.0, np.pi - 0.1]), np.array([9.0, -np.pi + 0.1]))
    np.testing.assert_allclose(r, [1.0, -0.2], atol=1e-12)
    z = np.array([[1.0, np.pi - 0.1], [1.0, -np.pi + 0.1]])
    assert abs(abs(rb.mean(z, np.array([0.5, 0.5]))[1]) - np.pi) < 1e-12
    np.testing.assert_allclose(wrap_angle([np.pi, -np.pi, 3 * np.pi]), [np.pi, np.pi, np.pi])


def test_user_models_fall_back_to_finite_differences(rng):
    F = np.array([[1.0, 0.5], [0.0, 1.0]])
    mo = NonlinearMotion(lambda x, dt, t: x @ F.T, Q=0.1 * np.eye(2), ndim_state=2)
    me = NonlinearMeasurement(lambda x: x[..., :1] ** 3, R=[[0.2]], ndim_state=2)
    x = rng.normal(size=(3, 2))
    np.testing.assert_allclose(mo.jacobian(x), np.broadcast_to(F, (3, 2, 2)), atol=1e-8)
    np.testing.assert_allclose(me.jacobian(x)[:, 0, 0], 3 * x[:, 0] ** 2, rtol=1e-6)


@pytest.mark.parametrize(
    "make, match",
    [
        (lambda: RangeBearing(r_range=0.0), "r_range must be a finite variance"),
        (lambda: RangeBearing(sensor=(1.0, 2.0, 3.0)), r"sensor must have shape \(2,\)"),
        (lambda: CoordinatedTurn(q=-1), "q must be a finite number >= 0"),
        (lambda: NonlinearMeasurement(lambda x: x, R=[[1.0, 0.0], [0.0, -1.0]], ndim_state=2),
         "R"),
        (lambda: NonlinearMeasurement(lambda x: x, R=np.eye(2), ndim_state=2, angles=(2,)),
         "angles must index components 0..1"),
        (lambda: MerweScaledSigmaPoints(alpha=0.0), "alpha must be a finite number > 0; got 0.0"),
    ],
)
def test_bad_model_arguments_raise(make, match):
    with pytest.raises(ValueError, match=match):
        make()


# ---------------------------------------------------------------- EKF / UKF / EnKF on linear models
def linear_problem(rng, T=30, missing=True):
    motion, meas = vt.ConstantVelocity(dim=2, q=0.5), vt.Position(dim=2, r=0.4)
    F, Q, H, R = motion.F(1.0), motion.Q(1.0), meas.H(4), meas.R()
    _, ys = vt.simulate.simulate_lgssm(T, F=F, Q=Q, H=H, R=R, x0=np.zeros(4), rng=rng)
    if missing:
        ys[5] = np.nan
        ys[9, 1] = np.nan
    x0, P0 = np.array([0.5, -0.5, 0.0, 0.0]), np.diag([2.0, 2.0, 1.0, 1.0])
    kf = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0)
    return motion, meas, ys, x0, P0, kf


@pytest.mark.parametrize("name", ["EKF", "UKF Merwe", "UKF Julier"])
def test_ekf_and_ukf_equal_the_kalman_filter_on_a_linear_model(rng, name):
    motion, meas, ys, x0, P0, kf = linear_problem(rng)
    if name == "EKF":
        flt = ExtendedKalmanFilter(motion, meas)
    else:
        pts = MerweScaledSigmaPoints(alpha=0.5) if "Merwe" in name else JulierSigmaPoints(1.0)
        flt = UnscentedKalmanFilter(motion, meas, points=pts)
    res = flt.filter(ys, x0=x0, P0=P0)
    np.testing.assert_allclose(res.means, kf.means, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(res.covs, kf.covs, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(res.pred_covs, kf.pred_covs, rtol=1e-10, atol=1e-12)
    assert res.loglik == pytest.approx(float(kf.loglik), rel=1e-10)


SINGULAR = {"two states equal": [[1.0, 1.0], [1.0, 1.0]],
            "a velocity known": [[2.0, 0.0], [0.0, 0.0]],
            "the state known": [[0.0, 0.0], [0.0, 0.0]]}


@pytest.mark.parametrize("P0", SINGULAR.values(), ids=SINGULAR.keys())
@pytest.mark.parametrize("batch", [False, True], ids=["one series", "a batch"])
def test_the_ukf_from_a_singular_prior_is_the_kalman_filter(P0, batch):
    """A prior known exactly along a direction has no Cholesky factor, but its sigma points
    are well defined (at the mean along that direction): on a linear model the UKF from it is
    the Kalman filter, one series (compiled points) or a batch (numpy's), updating from the
    prior or predicting from it first. It was refused (or, with fused multiply-add, taken only
    when the rounding of a pivot came out positive)."""
    motion, meas = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=1.0)
    mats = dict(F=motion.F(1.0), Q=motion.Q(1.0), H=meas.H(2), R=meas.R())
    x0 = np.array([0.5, 1.0])
    for ys in (np.array([[0.3], [np.nan], [1.2], [2.9]]),
               np.array([[np.nan], [0.3], [1.2], [2.9]])):
        if batch:
            ys = np.stack([ys, ys + 0.5])
        res = UnscentedKalmanFilter(motion, meas).filter(ys, x0=x0, P0=P0)
        kf = kalman_filter(ys, **mats, x0=x0, P0=P0)
        np.testing.assert_allclose(res.means, kf.means, rtol=1e-10, atol=1e-10)
        np.testing.assert_allclose(res.covs, kf.covs, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(res.loglik, kf.loglik, rtol=1e-10)


def test_the_ukf_from_a_prior_singular_to_rounding_is_the_kalman_filter():
    """A rank-2 prior of 4 states whose smallest eigenvalue came out -1.2e-15 (of 5.6) in
    floating point: the prior check accepts it, and so do the sigma points (a Cholesky factor
    with a tolerance refused it)."""
    V = np.array([[-1.3, 0.3], [1.3, -0.4], [-1.3, -1.5], [-0.7, 1.6]])
    P0 = V @ V.T
    motion, meas = vt.ConstantVelocity(dim=2, q=0.1), vt.Position(dim=2, r=1.0)
    mats = dict(F=motion.F(1.0), Q=motion.Q(1.0), H=meas.H(4), R=meas.R())
    ys = np.array([[0.3, -0.2], [np.nan, np.nan], [1.2, 0.4], [2.9, 1.1]])
    for y in (ys, np.stack([ys, ys + 0.5])):
        res = UnscentedKalmanFilter(motion, meas).filter(y, x0=np.zeros(4), P0=P0)
        kf = kalman_filter(y, **mats, x0=np.zeros(4), P0=P0)
        np.testing.assert_allclose(res.means, kf.means, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(res.covs, kf.covs, rtol=1e-9, atol=1e-11)


@pytest.mark.parametrize("pts", [MerweScaledSigmaPoints(alpha=0.5), JulierSigmaPoints(1.0)])
def test_sigma_points_of_a_singular_covariance_have_that_covariance(pts):
    """The points' weighted mean and covariance are the Gaussian's, for a semi-definite
    covariance too (3 states, rank 1 and 2, and zero); a covariance that is not semi-definite
    is refused, named as the caller's argument; one that is positive definite keeps its
    Cholesky factor however badly scaled, and a batch's other members keep theirs."""
    Wm, Wc = pts.weights(3)
    x = np.array([1.0, -2.0, 0.5])
    v = np.array([[1.0, 2.0, -1.0]])
    for P in (v.T @ v, np.diag([4.0, 0.0, 1e-3]), np.zeros((3, 3))):
        for got in (pts.points_one(x, P), pts.points(np.stack([x, x]), P)[1]):
            d = got - x
            np.testing.assert_allclose(Wm @ got, x, rtol=1e-12, atol=1e-12)
            np.testing.assert_allclose((Wc[:, None] * d).T @ d, P, rtol=1e-12, atol=1e-14)
    bad = np.array([[1.0, 2.0, 0.0], [2.0, 1.0, 0.0], [0.0, 0.0, 1.0]])
    for draw, name in ((lambda: pts.points_one(x, bad), "P"),
                       (lambda: pts.points(np.stack([x, x]), bad), "P"),
                       (lambda: ukf_update(vt.Gaussian(x, bad), np.ones(1),
                                           vt.Position(dim=1, r=1.0), points=pts), "g.cov")):
        with pytest.raises(ValueError, match=f"^{name} must be positive semi-definite; its "
                                             "smallest eigenvalue is -1$"):
            draw()
    with pytest.raises(ValueError, match=r"^P must be finite; P\[1, 1\] = nan$"):
        pts.points_one(x, np.diag([1.0, np.nan, 1.0]))
    tiny = np.diag([1.0, 1e-16, 4.0])
    n_lam = 3 + pts._lam(3)
    np.testing.assert_allclose(pts.points_one(np.zeros(3), tiny)[1:4],
                               np.sqrt(n_lam * np.diag(tiny)) * np.eye(3), rtol=1e-15)
    both = pts.points(np.stack([x, x]), np.stack([tiny, v.T @ v]))
    np.testing.assert_array_equal(both[0], pts.points(x, tiny))
    with pytest.raises(ValueError, match=r"^P\[1\] must be positive semi-definite; its "):
        pts.points(np.stack([x, x]), np.stack([tiny, bad]))


def test_one_gaussian_and_a_batch_of_one_get_the_same_points_of_a_singular_covariance():
    """A rank-4 covariance of 5 states (smallest eigenvalue -3.9e-15 or +4.9e-15 by rounding,
    as the processor's LAPACK kernels round) has a Cholesky factor by the compiled
    factorisation, and by LAPACK's on some processors only: the one-Gaussian path and the
    batch path took different roots (points 7 apart, a coordinated turn's prediction 4.6),
    both with the right moments; they take the same now. Where both factorisations succeed,
    the last pivot is the square root of a rounding error, so the two factors may differ
    there by up to sqrt(n eps max|scale P|) (1.4e-7 here; 1.2e-8 seen), and elsewhere by
    rounding."""
    P = np.array([[6.0, 1, 1, 3, -1], [1, 14, -8, -3, 11], [1, -8, 7, 4, -6],
                  [3, -3, 4, 15, -7], [-1, 11, -6, -7, 11]])
    x = np.array([10.0, 0, 0, 1, 0.3])
    for pts in (MerweScaledSigmaPoints(alpha=0.5), JulierSigmaPoints(1.0)):
        pivot = np.sqrt(5 * np.finfo(float).eps * (5 + pts._lam(5)) * np.abs(P).max())
        np.testing.assert_allclose(pts.points_one(x, P), pts.points(x[None], P[None])[0],
                                   rtol=0, atol=pivot)
        ct = vt.models.CoordinatedTurn(q=0.01)
        one = ukf_predict(vt.Gaussian(x, P), ct, points=pts)
        batch = ukf_predict(vt.Gaussian(x[None], P[None]), ct, points=pts)
        np.testing.assert_allclose(one.mean, batch.mean[0], rtol=0, atol=1e-10)
        np.testing.assert_allclose(one.cov, batch.cov[0], rtol=0, atol=1e-9)


def test_batched_updates_equal_one_at_a_time(rng):
    motion, meas, ys, x0, P0, _ = linear_problem(rng)
    B = 5
    g = vt.Gaussian(rng.normal(size=(B, 4)), np.broadcast_to(P0, (B, 4, 4)))
    y = rng.normal(size=(B, 2))
    y[1, 0] = np.nan
    y[3] = np.nan
    for flt, update in ((ExtendedKalmanFilter(motion, meas), ekf_update),
                        (UnscentedKalmanFilter(motion, meas), ukf_update)):
        batch, ll = flt.update(g, y)
        np.testing.assert_array_equal(update(g, y, meas).mean, batch.mean)
        np.testing.assert_array_equal(update(g, y, meas).cov, batch.cov)
        for b in range(B):
            one, ll1 = flt.update(g[b], y[b])
            np.testing.assert_allclose(batch.mean[b], one.mean, rtol=1e-12, atol=1e-14)
            np.testing.assert_allclose(batch.cov[b], one.cov, rtol=1e-12, atol=1e-14)
            assert ll[b] == pytest.approx(float(ll1), rel=1e-12, abs=1e-14)
        np.testing.assert_array_equal(batch.mean[3], g.mean[3])  # a missing row: no change


def test_enkf_tends_to_the_kalman_filter(rng):
    """With N members, the ensemble mean's error is about sqrt(P / N): check it within 5 of
    those, and the covariance within a few per cent."""
    motion, meas, ys, x0, P0, kf = linear_problem(rng, T=12)
    N = 20_000
    res = EnsembleKalmanFilter(motion, meas, n_members=N, rng=7).filter(ys, x0=x0, P0=P0)
    sd = np.sqrt(np.diagonal(kf.covs, axis1=-2, axis2=-1) / N)
    assert np.all(np.abs(res.means - kf.means) < 5 * sd)
    np.testing.assert_allclose(res.covs, kf.covs, rtol=0.08, atol=0.02 * kf.covs.max())


def test_enkf_update_of_a_large_ensemble_equals_the_kalman_update(rng):
    motion, meas, *_ = linear_problem(rng)
    P = np.diag([1.0, 2.0, 0.5, 0.5])
    ens = Ensemble.sample(np.zeros(4), P, 200_000, rng=1)
    out = enkf_update(ens, np.array([1.0, -1.0]), meas, rng=2)
    ref = vt.kf_update(vt.Gaussian(*ens.moments()), np.array([1.0, -1.0]), meas.H(4), meas.R())
    mean, cov = out.moments()
    np.testing.assert_allclose(mean, ref.mean, atol=5 * np.sqrt(2.0 / 200_000) * 3)
    np.testing.assert_allclose(cov, ref.cov, atol=0.01)


# ---------------------------------------------------------------- UKF against FilterPy
def central_mean(z, w, angles=(1,)):
    """The unscented transform's mean of sigma points ``z (k, m)`` about the first, the
    central one: ``z_0 + Σ w_i (z_i - z_0)``, angles' differences wrapped, the mean not."""
    d = z - z[0]
    d[:, list(angles)] = wrap_angle(d[:, list(angles)])
    return z[0] + w @ d


def filterpy_ukf(ys, motion, meas, x0, P0, alpha, beta, kappa, dt):
    from filterpy.kalman import MerweScaledSigmaPoints as FPPoints

    pts = FPPoints(n=len(x0), alpha=alpha, beta=beta, kappa=kappa)
    kf = filterpy_kalman.UnscentedKalmanFilter(
        dim_x=len(x0), dim_z=ys.shape[1], dt=dt, points=pts,
        fx=lambda x, dt: motion.f(x, dt), hx=meas.h,
        residual_z=meas.residual, z_mean_fn=central_mean,
    )
    kf.x, kf.P, kf.Q, kf.R = np.array(x0, float), np.array(P0, float), motion.Q(dt), meas.R()
    kf.sigmas_f = pts.sigma_points(kf.x, kf.P)  # our first step corrects the prior directly
    means, covs = [], []
    for t, y in enumerate(ys):
        if t > 0:
            kf.predict()
        kf.update(y)
        means.append(kf.x.copy())
        covs.append(kf.P.copy())
    return np.array(means), np.array(covs)


def test_ukf_equals_filterpy_on_range_bearing_with_bearings_crossing_pi(rng):
    """A target passes behind the sensor, so its bearing crosses ±π: both filters wrap the
    residual and average the bearing about the central sigma point (FilterPy through its
    residual_z and z_mean_fn hooks)."""
    dt, T = 0.5, 40
    motion, meas = CoordinatedTurn(q=0.05, q_turn=1e-3), RangeBearing(1.0, 1e-3, ndim_state=5)
    x = np.array([-20.0, 8.0, 0.0, -0.8, 0.01])
    states = []
    for _ in range(T):
        states.append(x)
        x = motion.f(x, dt) + psd_sqrt(motion.Q(dt)) @ rng.standard_normal(5)  # any processor
    zs = meas.h(np.array(states)) + rng.normal(size=(T, 2)) * np.sqrt([1.0, 1e-3])
    zs[:, 1] = wrap_angle(zs[:, 1])
    assert np.any(np.abs(np.diff(zs[:, 1])) > np.pi)  # the bearing does cross ±π
    x0, P0 = states[0] + [1.0, -1.0, 0.1, 0.1, 0.0], np.diag([4.0, 4.0, 0.5, 0.5, 1e-3])
    for alpha, beta, kappa in ((1e-3, 2.0, 0.0), (0.3, 2.0, -2.0), (1.0, 0.0, 1.0)):
        pts = MerweScaledSigmaPoints(alpha, beta, kappa)
        res = UnscentedKalmanFilter(motion, meas, points=pts).filter(zs, x0=x0, P0=P0, dt=dt)
        fm, fP = filterpy_ukf(zs, motion, meas, x0, P0, alpha, beta, kappa, dt)
        np.testing.assert_allclose(res.means, fm, rtol=1e-8, atol=1e-8)
        # 1e-8 of the covariance's scale: with alpha = 1e-3 the weights are about -1e6 and
        # 1e5, so both implementations round entries near zero at ~1e-10 of the scale
        np.testing.assert_allclose(res.covs, fP, rtol=1e-8, atol=1e-8 * np.abs(fP).max())
    assert np.max(np.hypot(*(res.means[10:, :2] - np.array(states)[10:, :2]).T)) < 3.0


def _ut_update_extended(x, P, y, pts, r_range, r_bearing):
    """The textbook unscented correction with a range-bearing measurement from ``pts``
    (the sigma points of ``(x, P)``), in extended precision (numpy's longdouble) and with
    the bearings as plain numbers (they lie in a narrow arc away from ±π): an independent
    reference for ``ukf_update``."""
    ld = np.longdouble
    n, alpha = len(x), ld(1) / 1000
    lam = alpha**2 * n - n
    Wm = np.full(2 * n + 1, 1 / (2 * (n + lam)), dtype=ld)
    Wm[0] = lam / (n + lam)
    Wc = Wm.copy()
    Wc[0] += 1 - alpha**2 + 2
    X = pts.astype(ld)
    Z = np.stack([np.hypot(X[:, 0], X[:, 1]), np.arctan2(X[:, 1], X[:, 0])], axis=1)
    zhat = Wm @ Z
    r = Z - zhat
    S = (r * Wc[:, None]).T @ r + np.diag([ld(r_range), ld(r_bearing)])
    C = ((X - X[0]) * Wc[:, None]).T @ r
    Si = np.array([[S[1, 1], -S[0, 1]], [-S[1, 0], S[0, 0]]]) / (S[0, 0] * S[1, 1]
                                                                  - S[0, 1] * S[1, 0])
    K = C @ Si
    e = y.astype(ld) - zhat
    e[1] = (e[1] + np.pi) % (2 * np.pi) - np.pi
    return (X[0] + K @ e).astype(float), (P.astype(ld) - K @ S @ K.T).astype(float)


def test_ukf_update_of_a_vague_prior_near_the_sensor_stays_positive_semidefinite():
    """A range-bearing correction of a prior whose spread is large against its range (a
    target near the sensor, its position known to tens or hundreds of pixels) with van der
    Merwe's default points (α = 1e-3, the first weight about -10^6): the mean and covariance
    equal the textbook equations in extended precision, and every covariance is positive
    semi-definite. The bearing was averaged on the circle, ``atan2(Σ W sin, Σ W cos)``,
    which with these weights is ``1 - σ²/2`` in its cosine and turns by π once the bearing's
    spread σ passes about √2: 28 of these 400 posteriors had a negative eigenvalue (down to
    -1.3 times the largest). One Gaussian at a time (the compiled kernel) and the batch
    both."""
    rng = np.random.default_rng(3)
    meas, pts = RangeBearing(1.0, 1e-4, ndim_state=4), MerweScaledSigmaPoints()
    xs, Ps, ys = [], [], []
    while len(xs) < 400:
        x = np.r_[rng.uniform(20, 300), rng.uniform(-300, 300), rng.normal(0, 30, 2)]
        A = rng.normal(size=(4, 4)) * 10 ** rng.uniform(-1, 2)
        P = A @ A.T + np.diag(10 ** rng.uniform(-6, -2, 4))
        X = pts.points(x[None], P[None])[0]
        if X[:, 0].min() <= 0:  # bearings from -π/2 to π/2: the reference's plain numbers
            continue
        xs.append(x)
        Ps.append(P)
        ys.append(meas.h(x) + rng.normal(0, [1.0, 1e-2]))
    batch = ukf_update(vt.Gaussian(np.array(xs), np.array(Ps)), np.array(ys), meas)
    worst = []
    for b, (x, P, y) in enumerate(zip(xs, Ps, ys)):
        one = ukf_update(vt.Gaussian(x, P), y, meas)
        mean, cov = _ut_update_extended(x, P, y, pts.points(x[None], P[None])[0], 1.0, 1e-4)
        for got in (one, vt.Gaussian(batch.mean[b], batch.cov[b])):
            np.testing.assert_allclose(got.cov, cov, rtol=0, atol=1e-8 * np.abs(cov).max())
            np.testing.assert_allclose(got.mean, mean, rtol=0,
                                       atol=1e-8 * np.sqrt(np.abs(P).max()))
            ev = np.linalg.eigvalsh(got.cov)
            assert ev[0] >= -1e-12 * ev[-1]
        worst.append(ev[0] / ev[-1])
    assert min(worst) < 1e-4  # some posteriors are nearly singular: the test has teeth


def test_ukf_covariances_stay_positive_definite_over_a_long_run(rng):
    dt, T = 1.0, 5000
    motion, meas = CoordinatedTurn(q=1e-6, q_turn=1e-10), RangeBearing(1e-2, 1e-8, ndim_state=5)
    states = [np.array([100.0, 0.0, 0.0, 1.0, 0.0])]
    for _ in range(T - 1):
        states.append(motion.f(states[-1], dt))
    zs = meas.h(np.array(states)) + rng.normal(size=(T, 2)) * np.sqrt([1e-2, 1e-8])
    res = UnscentedKalmanFilter(motion, meas).filter(zs, x0=states[0], P0=np.eye(5) * 1e-2)
    assert np.array_equal(res.covs, np.swapaxes(res.covs, -1, -2))
    np.linalg.cholesky(res.covs)  # raises if any is not positive definite


def test_nonlinear_filter_errors_name_the_argument(rng):
    motion, meas = CoordinatedTurn(), RangeBearing(ndim_state=5)
    flt = ExtendedKalmanFilter(motion, meas)
    with pytest.raises(ValueError, match="ys must have 2 measurement components"):
        flt.filter(np.zeros((3, 3)), x0=np.ones(5), P0=np.eye(5))
    with pytest.raises(ValueError, match=r"^x0 must have shape \(5,\) or \(B, 5\); got \(4,\)$"):
        flt.filter(np.ones((3, 2)), x0=np.ones(4), P0=np.eye(5))
    # a NaN or infinite prior is named (the EKF and the EnKF gave NaN estimates without a word)
    x0 = np.ones(5)
    x0[2] = np.nan
    for f in (flt, EnsembleKalmanFilter(motion, meas, n_members=20, rng=0)):
        with pytest.raises(ValueError, match=r"^x0 must be finite; x0\[2\] = nan$"):
            f.filter(np.ones((3, 2)), x0=x0, P0=np.eye(5))
        with pytest.raises(ValueError, match=r"^P0 must be finite; P0\[0, 0\] = inf$"):
            f.filter(np.ones((3, 2)), x0=np.ones(5), P0=np.diag([np.inf, 1, 1, 1, 1]))
    with pytest.raises(ValueError, match=re.escape(
            "dt must be a scalar, the T-1=2 intervals between steps or T=3 values (dt[0] "
            "unused); got shape (4,)")):
        flt.filter(np.ones((3, 2)), x0=np.ones(5), P0=np.eye(5), dt=[1.0, 2.0, 1.0, 1.0])
    with pytest.raises(ValueError, match=r"times must have shape \(3,\)"):
        flt.filter(np.ones((3, 2)), x0=np.ones(5), P0=np.eye(5), times=[0.0, 1.0])
    with pytest.raises(ValueError, match=r"y must have shape \(2,\)"):
        ekf_update(vt.Gaussian(np.ones(5), np.eye(5)), np.ones(3), meas)
    with pytest.raises(ValueError, match=r"^g.cov must be positive semi-definite; "
                                         r"g.cov\[0, 0\] = -1, a negative variance$"):
        ukf_update(vt.Gaussian(np.ones(5), -np.eye(5)), np.ones(2), meas)
    # an infinite measurement gave a mean of [inf, nan, ...] without a word, as kf_update
    # refuses it (NaN is a missing value)
    for update in (ekf_update, ukf_update):
        with pytest.raises(ValueError, match=r"y must be finite or NaN \(missing\); "
                                             r"y\[0\] = inf"):
            update(vt.Gaussian(np.ones(5), np.eye(5)), [np.inf, 0.1], meas)
    with pytest.raises(TypeError, match="motion must be a motion model"):
        ExtendedKalmanFilter(object(), meas)
    with pytest.raises(ValueError, match="n_members must be an integer >= 2"):
        EnsembleKalmanFilter(motion, meas, n_members=1)


@pytest.mark.parametrize("kind,tol", [("EKF", (1e-10, 1e-10)), ("UKF", (1e-10, 1e-10)),
                                      ("UKF, alpha 1e-3", (1e-7, 1e-5))])
def test_sequence_filters_on_a_batch_equal_each_series_alone(rng, kind, tol):
    """A batch runs the batched numpy code; one series the one-Gaussian path. With sigma-point
    weights of order one (alpha = 0.5) the two agree to 1e-10 (measured: 2e-15 for the means,
    1e-12 for the log-likelihood). With the default alpha = 1e-3 the weights are about -1e6
    and 1e5, and the two summation orders alone move the means by up to 8e-9 of their scale
    and the log-likelihood by up to 2e-6 of itself (measured over 20 seeds; a bearing noise
    of 1e-3 rad makes the log-likelihood a thousand times more sensitive than the means), so
    that case is checked to ten times that."""
    from vistrack.filters.ukf import MerweScaledSigmaPoints

    motion, meas = CoordinatedTurn(q=0.05, q_turn=1e-3), RangeBearing(1.0, 1e-3, ndim_state=5)
    x0 = np.array([-20.0, 8.0, 0.0, -0.8, 0.01])
    _, ys = vt.simulate.simulate(motion, meas, 25, x0=x0, n_series=3, rng=rng)
    ys[0, 5] = np.nan
    ys[2, 8, 1] = np.nan
    P0 = np.diag([4.0, 4.0, 0.5, 0.5, 1e-3])
    flt = (ExtendedKalmanFilter(motion, meas) if kind == "EKF" else
           UnscentedKalmanFilter(motion, meas) if kind != "UKF" else
           UnscentedKalmanFilter(motion, meas, points=MerweScaledSigmaPoints(alpha=0.5)))
    batch = flt.filter(ys, x0=x0, P0=P0)
    for b in range(3):
        one = flt.filter(ys[b], x0=x0, P0=P0)
        for got, want in ((batch.means[b], one.means), (batch.covs[b], one.covs)):
            np.testing.assert_allclose(got, want, rtol=tol[0], atol=tol[0] * np.abs(want).max())
        assert batch.loglik[b] == pytest.approx(float(one.loglik), rel=tol[1])


def test_julier_weights_need_a_positive_spread():
    """``n + kappa`` is the points' spread: at 0 or below the weights have no meaning (a
    division by zero, or negative weights), as for Merwe's points."""
    W, _ = JulierSigmaPoints(kappa=1.0).weights(2)
    assert W.sum() == pytest.approx(1.0) and W[0] == pytest.approx(1 / 3)  # kappa / (n + kappa)
    for kappa in (-2.0, -3.0):
        with pytest.raises(ValueError, match="n \\+ kappa must be > 0"):
            JulierSigmaPoints(kappa=kappa).weights(2)


# ---------------------------------------------------------------- angles and far points
def test_enkf_averages_bearings_on_the_circle():
    """A bearing near ±π: the EnKF's posterior is the mirror of the same problem with the
    bearing near 0 (the oracle: the geometry is symmetric), and near the UKF's. The members'
    bearings used to be averaged as numbers, to about 0, and the variance barely moved
    (0.2565 from 0.25, against 0.0097)."""
    from vistrack.models import ConstantPosition

    rb = RangeBearing(r_range=0.01, r_bearing=1e-4, ndim_state=2)
    P = np.diag([0.01, 0.25])
    out = {}
    for s in (1, -1):
        x = s * np.array([-10.0, 0.0])
        y = np.array([10.0, (np.pi - 0.02) if s == 1 else -0.02])
        ens = Ensemble.sample(x, P, 20000, rng=0)
        post, ll = EnsembleKalmanFilter(ConstantPosition(dim=2), rb, rng=1).update(ens, y)
        m, C = post.moments()
        out[s] = (s * m[1], C[1, 1], float(ll))
        assert s * ukf_update(vt.Gaussian(x, P), y, rb).mean[1] == pytest.approx(s * m[1],
                                                                                 abs=0.01)
    np.testing.assert_allclose(out[1], out[-1], rtol=0.02)
    assert out[1][1] < 0.02


class _BearingOnly:
    """A user's model with ``angles`` and nothing else angle-aware (no residual, no mean)."""

    angles = (0,)

    def h(self, x):
        return np.arctan2(x[..., 1:2], x[..., 0:1])

    def jacobian(self, x):
        r2 = x[..., 0] ** 2 + x[..., 1] ** 2
        return np.stack([-x[..., 1] / r2, x[..., 0] / r2], -1)[..., None, :]

    def R(self):
        return np.array([[1e-3]])


def test_a_model_with_angles_alone_is_filtered_as_an_angle_aware_one():
    """``angles`` without ``residual`` and ``mean``: every path (EKF, the UKF on one Gaussian
    and on a batch) wraps the bearing's innovation, as for the same model built on the
    angle-aware base (the oracle). Before, the EKF and the batched UKF moved y to 44.8 (an
    innovation of -2π + 0.02), the single-Gaussian UKF to -0.043."""
    g = vt.Gaussian(np.array([-10.0, 0.1]), np.diag([0.01, 0.25]))
    y = np.array([-np.pi + 0.01])
    user = _BearingOnly()
    base = NonlinearMeasurement(user.h, user.R(), 2, jacobian=user.jacobian, angles=(0,))
    batch = vt.Gaussian(g.mean[None], g.cov[None])
    for update in (ekf_update, ukf_update):
        want = update(g, y, base)
        got = update(g, y, user)
        np.testing.assert_allclose(got.mean, want.mean, rtol=1e-9)
        np.testing.assert_allclose(got.cov, want.cov, rtol=1e-9)
        np.testing.assert_allclose(update(batch, y[None], user).mean[0], want.mean, rtol=1e-9)
    assert ekf_update(g, y, user).mean[1] == pytest.approx(-0.0429, abs=1e-3)


def test_numerical_jacobian_of_a_bearing_across_pi():
    """Central differences straddling ±π: the angle's difference wrapped gives the analytic
    Jacobian [[-y/r², x/r²]] (it gave 3.1e6 for the second entry, a 2π jump over 2e-6)."""
    x = np.array([-1.0, 1e-8])
    want = _BearingOnly().jacobian(x)
    m = NonlinearMeasurement(_BearingOnly().h, [[0.01]], 2, angles=(0,))
    # a difference of values near π over a step of 2e-6 rounds by about 2e-16 π / 2e-6
    np.testing.assert_allclose(m.jacobian(x), want, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(numerical_jacobian(_BearingOnly().h, x, angles=(0,)), want,
                               rtol=1e-6, atol=1e-9)
    # an EKF update by the numerical Jacobian equals one by the analytic
    g = vt.Gaussian(x, np.diag([0.01, 0.01]))
    y = np.array([np.pi - 0.05])
    exact = NonlinearMeasurement(_BearingOnly().h, [[0.01]], 2, jacobian=_BearingOnly().jacobian,
                                 angles=(0,))
    np.testing.assert_allclose(ekf_update(g, y, m).mean, ekf_update(g, y, exact).mean,
                               rtol=1e-6)


@pytest.mark.parametrize("offset", [0.0, 1e6, 1e8])
def test_ukf_far_from_the_origin_is_the_kalman_filter(offset):
    """A linear model at 10^8: the UKF's prediction and correction equal the Kalman filter's
    (the oracle: exact for linear models). The unscented mean, summed with a first weight of
    about -10^6, was 8e-3 off on a state of unit variance."""
    from vistrack.filters import kf_predict, kf_update, ukf_predict
    from vistrack.models import ConstantVelocity, Position

    cv, pos = ConstantVelocity(dim=1, q=0.1), Position(dim=1, r=0.5)
    for shape in ((), (3,)):
        mean = np.broadcast_to(np.array([offset, 1.0]), shape + (2,))
        g = vt.Gaussian(mean.copy(), np.broadcast_to(np.eye(2), shape + (2, 2)).copy())
        u, k = ukf_predict(g, cv), kf_predict(g, cv.F(1.0), cv.Q(1.0))
        np.testing.assert_allclose(u.mean - k.mean, 0.0, atol=1e-9)
        np.testing.assert_allclose(u.cov, k.cov, atol=1e-4)
        y = np.broadcast_to(np.array([offset + 2.0]), shape + (1,))
        uu, kk = ukf_update(k, y, pos), kf_update(k, y, pos.H(2), pos.R())
        np.testing.assert_allclose(uu.mean - kk.mean, 0.0, atol=1e-6)


@pytest.mark.parametrize("batch", [False, True])
def test_the_ukf_from_a_large_prior_of_rank_two_is_the_kalman_filter(batch):
    """A prior of rank 2 with entries near 2e6, measured to 1: the correction cancels, and
    its rounding left eigenvalues of about -1e-10 where the exact ones are 0, which the next
    prediction refused as not positive semi-definite, naming ``g.cov``, a covariance the user
    never gave (23 of 200 such priors, at step 1). Oracle: the Kalman filter, exact for a
    linear model, on each of 200 random priors."""
    from vistrack.filters import KalmanFilter
    from vistrack.models import ConstantVelocity, Position

    cv, pos = ConstantVelocity(dim=2, q=0.1), Position(dim=2)
    ukf, kf = UnscentedKalmanFilter(cv, pos), KalmanFilter(cv, pos)
    rng = np.random.default_rng(0)
    A = rng.normal(size=(200, 4, 2)) * 1e3
    P0 = A @ np.swapaxes(A, -1, -2)  # rank 2
    ys = rng.normal(size=(200, 5, 2))
    runs = [(ys, np.zeros((200, 4)), P0)] if batch else [
        (ys[b], np.zeros(4), P0[b]) for b in range(200)]
    for y, x0, p0 in runs:
        u, k = ukf.filter(y, x0=x0, P0=p0), kf.filter(y, x0=x0, P0=p0)
        np.testing.assert_allclose(u.means, k.means, rtol=1e-6, atol=1e-6)
        np.testing.assert_allclose(u.covs, k.covs, rtol=1e-6, atol=1e-6)


def test_measurement_functions_of_a_model_with_angles_alone_pickle():
    """The wrapped residual and circular mean of a model with angles alone are module
    functions with the angles bound, so its filters pickle (they were lambdas, which do not:
    a filter could not go to another process)."""
    import pickle

    from vistrack.models import MeasurementFunctions

    me = MeasurementFunctions(_BearingOnly(), 2)
    back = pickle.loads(pickle.dumps(me))
    a, b = np.array([[np.pi - 0.01]]), np.array([[-np.pi + 0.01]])
    np.testing.assert_allclose(back.residual(a, b), [[-0.02]], atol=1e-12)
    m = back.mean(np.array([[np.pi - 0.01], [-np.pi + 0.01]]), np.array([0.5, 0.5]))
    assert abs(wrap_angle(m[0] - np.pi)) < 1e-12  # π (or -π), not 0


def test_angles_at_the_boundary_are_in_minus_pi_pi():
    """(-π, π], as documented: np.mod of a hair below 0 rounds up to 2π, so a hair above π
    was wrapped to -π; and a bearing straight behind along -x with dy = -0.0 came out -π
    (atan2(-0.0, -1)) where dy = +0.0 gives π, numpy and compiled alike."""
    from vistrack.models.nonlinear import wrap_angle

    above = np.nextafter(np.pi, 4)
    assert -np.pi < wrap_angle(above) <= np.pi  # it was -π
    w = wrap_angle(np.array([above, -np.pi, np.pi, 3 * np.pi, -3 * np.pi]))
    assert ((w > -np.pi) & (w <= np.pi)).all()
    rb = RangeBearing(ndim_state=4)
    for x in ([-1.0, -0.0, 0, 0], [-1.0, 0.0, 0, 0]):
        assert rb.h(np.array(x))[1] == np.pi
        out = np.empty(2)
        RangeBearing.jit_h(np.array(x), np.zeros(2), out)
        assert out[1] == np.pi


def test_models_name_a_state_of_the_wrong_size_and_a_dt_of_several_values():
    """A 4-entry state in CoordinatedTurn.f failed with "not enough values to unpack",
    CoordinatedTurn.Q([1.0]) with float()'s "only 0-dimensional arrays", and
    RangeBearing(ndim_state=4) took a 6-entry state, its Jacobian 2 x 4."""
    ct, rb = CoordinatedTurn(), RangeBearing(ndim_state=4)
    for call in (ct.f, ct.jacobian):
        with pytest.raises(ValueError, match=r"x must be CoordinatedTurn states of 5 entries"):
            call(np.zeros(4))
    with pytest.raises(ValueError, match=r"dt must be one value; got shape \(1,\)"):
        ct.Q([1.0])
    for call in (rb.h, rb.jacobian):
        with pytest.raises(ValueError, match=r"x must be RangeBearing states of 4 entries"):
            call(np.ones(6))
    assert rb.jacobian(np.ones((3, 4))).shape == (3, 2, 4)


class _Heading:
    """A linear sensor of an angle (the first state of a constant-velocity heading), whose
    residual wraps: a linear model with a residual of its own."""

    ndim_meas = 1

    def H(self, n):
        return np.eye(1, n)

    def R(self):
        return np.array([[0.01]])

    def residual(self, a, b):
        return wrap_angle(np.asarray(a) - np.asarray(b))


def test_a_linear_model_with_its_own_residual_is_filtered_with_it_on_every_path():
    """A heading crossing +π seen by a linear sensor whose residual wraps: the UKF on one
    series (its compiled path) uses that residual, as on a batch and as the EKF (for a
    linear model, the Kalman filter with the residual wrapped: the oracle here, written
    out). Before, the one-series UKF took plain differences and lost the heading at the
    crossing (-1.63 for 3.15; log-likelihood -622 against 5.9)."""
    from vistrack.filters import ParticleFilter

    motion = vt.ConstantVelocity(dim=1, q=0.01)
    ys = wrap_angle(3.0 + 0.05 * np.arange(8))[:, None]
    x0, P0 = np.array([3.0, 0.05]), np.diag([0.01, 0.01])
    # the oracle: the Kalman filter, its innovation wrapped, from the prior at the first step
    F, Q, H, R = motion.F(1.0), motion.Q(1.0), np.eye(1, 2), np.array([[0.01]])
    m, P, want, ll = x0.copy(), P0.copy(), [], 0.0
    for t, y in enumerate(ys):
        if t:
            m, P = F @ m, F @ P @ F.T + Q
        S = H @ P @ H.T + R
        v = wrap_angle(y - H @ m)
        K = P @ H.T @ np.linalg.inv(S)
        m, P = m + K @ v, (np.eye(2) - K @ H) @ P
        ll += -0.5 * (v @ np.linalg.solve(S, v) + np.log(2 * np.pi * np.linalg.det(S)))
        want.append(m)
    for f in (UnscentedKalmanFilter(motion, _Heading()), ExtendedKalmanFilter(motion, _Heading())):
        one = f.filter(ys, x0=x0, P0=P0)
        np.testing.assert_allclose(one.means, want, rtol=1e-9, atol=1e-9)
        assert float(np.sum(one.loglik)) == pytest.approx(ll, rel=1e-9)
        two = f.filter(np.stack([ys, ys]), x0=x0, P0=P0)
        np.testing.assert_allclose(two.means[0], want, rtol=1e-9, atol=1e-9)
    # the particle filter's compiled path took plain differences too
    pf = ParticleFilter(motion, _Heading(), n_particles=4000, rng=3).filter(ys, x0=x0, P0=P0)
    assert np.abs(pf.means[:, 0] - np.array(want)[:, 0]).max() < 0.05


def test_a_filter_keeps_a_few_time_steps_noise_not_every_one():
    """Timestamps whose steps never repeat: the motion's ``Q`` is kept for the last 16
    distinct steps, not for every one (it grew by 400 bytes a step, for as long as the filter
    lived), and each is the model's; a 0-d array step is a step (it was unhashable)."""
    from vistrack.filters import ekf_predict
    from vistrack.models import MotionFunctions

    ct, rb = CoordinatedTurn(q=0.1), RangeBearing(ndim_state=5)
    ukf = UnscentedKalmanFilter(ct, rb)
    dts = 0.04 + np.random.default_rng(0).uniform(-1e-3, 1e-3, 300)
    ys = np.tile([10.0, 0.1], (300, 1))
    ukf.filter(ys, x0=[10, 0, 0, 1, 0.01], P0=np.eye(5), dt=dts)
    assert len(ukf.motion._Q) <= 16
    mo = MotionFunctions(ct)
    for dt in np.r_[dts[:40], dts[:40]]:
        np.testing.assert_array_equal(mo.Q(dt), ct.Q(dt))
        np.testing.assert_allclose(mo.Q_sqrt(dt) @ mo.Q_sqrt(dt).T, ct.Q(dt), atol=1e-12)
    g = vt.Gaussian(np.array([0.0, 1.0]), np.eye(2))
    cv = vt.ConstantVelocity(dim=1, q=0.5)
    np.testing.assert_array_equal(ekf_predict(g, cv, dt=np.array(0.5)).cov,
                                  ekf_predict(g, cv, dt=0.5).cov)


def _still(x, dt, t):
    return x


def test_a_motion_of_constant_noise_pickles_with_its_filter():
    """``NonlinearMotion`` given one ``Q`` (not a function of ``dt``) pickles, and its filter
    with it (a lambda kept that ``Q``, which does not: a filter could not go to another
    process); the copy's noise and filtering are the original's."""
    import pickle

    motion = NonlinearMotion(_still, 0.3 * np.eye(2), 2)
    ekf = ExtendedKalmanFilter(motion, vt.Position(dim=1))
    back = pickle.loads(pickle.dumps(ekf))
    np.testing.assert_array_equal(back.motion.model.Q(2.0), 0.3 * np.eye(2))
    ys = np.arange(5.0)[:, None]
    kw = dict(x0=np.zeros(2), P0=np.eye(2))
    np.testing.assert_array_equal(back.filter(ys, **kw).means, ekf.filter(ys, **kw).means)
    q = motion.Q(1.0)
    q[0, 0] = 99.0  # a copy: the model's noise stays
    assert motion.Q(1.0)[0, 0] == 0.3


def _cv_ukf():
    return UnscentedKalmanFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1))


def _ct_rb(cls):
    return cls(CoordinatedTurn(), RangeBearing(ndim_state=5))


@pytest.mark.parametrize("call, error, message", [
    # a prior for another number of series than ys: numpy's broadcasting error before
    (lambda: _ct_rb(ExtendedKalmanFilter).filter(np.ones((3, 4, 2)), x0=np.zeros((2, 5)),
                                                 P0=np.eye(5)),
     ValueError, r"x0 must be one for all series or one per series of ys \(B=3\); got 2"),
    (lambda: _ct_rb(EnsembleKalmanFilter).filter(np.ones((3, 4, 2)), x0=np.zeros(5),
                                                 P0=np.stack([np.eye(5)] * 2)),
     ValueError, r"P0 must be one for all series or one per series of ys \(B=3\); got 2"),
    (lambda: _cv_ukf().filter(np.ones((3, 1)), x0=[0, 0], P0=np.eye(2), times=[0, np.nan, 2]),
     ValueError, r"times must be finite; times\[1\] = nan"),
    # named as q before
    (lambda: CoordinatedTurn(q_turn=-1.0), ValueError,
     r"q_turn must be a finite number >= 0; got -1.0"),
    # taken, and the filter blamed R or the covariance
    (lambda: MerweScaledSigmaPoints(beta=np.nan), ValueError,
     r"beta must be a finite number; got nan"),
    (lambda: JulierSigmaPoints(kappa=np.inf), ValueError,
     r"kappa must be a finite number; got inf"),
    # cut to 2, and numpy's TypeError
    (lambda: RangeBearing(ndim_state=2.5), ValueError,
     r"ndim_state must be a whole number >= 2; got 2.5"),
    (lambda: RangeBearing(r_range="1"), TypeError, r"r_range must be a number; got '1'"),
])
def test_nonlinear_filters_name_bad_arguments(call, error, message):
    with pytest.raises(error, match=message):
        call()


def test_an_imm_of_nonlinear_members_names_a_measurement_of_another_size():
    """The width check read ``ndim_meas``, which an EKF or UKF member's measurement functions
    do not have: the error came later as "y must have shape (1, 1) to match g"."""
    from vistrack.filters import IMMFilter

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    imm = IMMFilter([ExtendedKalmanFilter(cv, pos)] * 2, np.full((2, 2), 0.5))
    with pytest.raises(ValueError, match=r"ys must have 1 measurement components \(last "
                                         r"axis\), as Position\(dim=1\) measures; got 2"):
        imm.filter(np.ones((3, 2)), x0=[0.0, 0.0], P0=np.eye(2))


def _nan_after(step):
    """A constant-velocity motion whose ``f`` gives NaN for the predictions to ``step`` and
    after, and a position measurement whose ``h`` gives NaN where the position passes
    ``step - 0.5`` (the series below moves one a step): a model that fails mid-run."""
    F = np.array([[1.0, 1.0], [0.0, 1.0]])

    def f(x, dt, t):
        return x @ F.T + (np.nan if t >= step else 0.0)

    def h(x):
        return np.where(x[..., :1] > step - 0.5, np.nan, x[..., :1])

    jac_h = lambda x: np.broadcast_to(np.array([[1.0, 0.0]]), x.shape[:-1] + (1, 2))  # noqa: E731
    motion = NonlinearMotion(f, 0.01 * np.eye(2), 2, jacobian=lambda x, dt, t: np.broadcast_to(
        F, x.shape[:-1] + (2, 2)))
    return motion, NonlinearMeasurement(h, np.eye(1), ndim_state=2, jacobian=jac_h)


@pytest.mark.parametrize("cls", [ExtendedKalmanFilter, UnscentedKalmanFilter,
                                 EnsembleKalmanFilter])
@pytest.mark.parametrize("batch", [False, True])
def test_a_model_that_gives_nan_mid_run_is_named_at_the_first_step_it_did(cls, batch):
    """NaN from the user's ``f`` or ``h`` was carried silently to every later step (the EKF,
    the UKF on a batch), or reported a step late as the next step's "g.cov must be finite"
    or as R not positive definite (the UKF on one series): the filter now names the step
    and the series where the prediction or the correction first stopped being finite."""
    ys = np.arange(8.0)[:, None] + 0.01 * np.sin(np.arange(8.0))[:, None]
    Y = np.stack([ys, ys]) if batch else ys
    series = " of series 0" if batch else ""
    motion, measurement = _nan_after(5)
    linear_pos = vt.Position(dim=1)
    kw = {"n_members": 64, "rng": 0} if cls is EnsembleKalmanFilter else {}
    with np.errstate(invalid="ignore"):
        with pytest.raises(ValueError, match=f"^the prediction to step 5{series} is not finite "
                           r"\(mean \[nan nan\].*: the motion model gave NaN or infinity there"):
            cls(motion, linear_pos, **kw).filter(Y, x0=[0.0, 1.0], P0=np.eye(2))
        if cls is EnsembleKalmanFilter:
            return  # its measurement model is linear
        cv = vt.ConstantVelocity(dim=1, q=0.01)
        # the UKF names the sigma point, of a batch's too (a batch's NaN was found by the
        # loop alone)
        match = (f"the correction at step 5{series} is not finite.*the measurement model gave"
                 if cls is ExtendedKalmanFilter else
                 r"^step 5: the measurement model gave NaN or infinity at sigma point "
                 + (r"\[0, 0\]" if batch else "0") + r": h\(")
        with pytest.raises(ValueError, match=match):
            cls(cv, measurement).filter(Y, x0=[0.0, 1.0], P0=np.eye(2))
    res = cls(cv, measurement).filter(Y[..., :5, :], x0=[0.0, 1.0], P0=np.eye(2))
    assert np.isfinite(res.means).all()  # before it, the same model runs


@pytest.mark.parametrize("cls", [ExtendedKalmanFilter, UnscentedKalmanFilter,
                                 EnsembleKalmanFilter])
def test_a_models_own_error_mid_run_keeps_its_type(cls):
    """An error a step raises is prefixed with the step only when it is a plain ValueError;
    the model's own (numpy's LinAlgError, a subclass of ValueError, or the user's) passes as
    it was, for the caller that catches it."""
    class OffTheMap(ValueError):
        pass

    F = np.array([[1.0, 1.0], [0.0, 1.0]])
    kw = {"n_members": 16, "rng": 0} if cls is EnsembleKalmanFilter else {}
    ys = np.arange(6.0)[:, None]
    for error in (np.linalg.LinAlgError, OffTheMap):
        def f(x, dt, t, error=error):
            if t >= 3:
                raise error("out of the model's domain")
            return x @ F.T

        motion = NonlinearMotion(f, 0.01 * np.eye(2), 2, jacobian=lambda x, dt, t:
                                 np.broadcast_to(F, x.shape[:-1] + (2, 2)))
        with pytest.raises(error, match="^out of the model's domain$") as info:
            cls(motion, vt.Position(dim=1), **kw).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
        assert type(info.value) is error

    def g(x, dt, t):
        if t >= 3:
            raise ValueError("plain")
        return x @ F.T

    with pytest.raises(ValueError, match="^step 3: plain$"):
        cls(NonlinearMotion(g, 0.01 * np.eye(2), 2), vt.Position(dim=1), **kw).filter(
            ys, x0=[0.0, 1.0], P0=np.eye(2))


def test_the_ukf_blames_h_only_for_a_component_it_uses():
    """A component missing from ``y`` is not used, so ``h``'s NaN there is no fault: where
    the innovation covariance fails for another reason (here Julier's negative centre weight
    on a steep ``h``), the error says so rather than blaming ``h``; NaN in a used component
    is named."""
    def h(x, bad=1):
        z = np.stack([100 * x[..., 0] ** 2, x[..., 1]], axis=-1)
        z[..., bad] = np.nan
        return z

    g, points = vt.Gaussian(np.zeros(2), np.eye(2)), JulierSigmaPoints(kappa=-1.9)
    me = NonlinearMeasurement(h, np.eye(2), ndim_state=2)
    with pytest.raises(ValueError, match="^the innovation covariance is not positive definite"):
        ukf_update(g, [1.0, np.nan], me, points=points)
    me = NonlinearMeasurement(lambda x: h(x, bad=0), np.eye(2), ndim_state=2)
    with pytest.raises(ValueError, match=r"^the measurement model gave NaN or infinity at sigma "
                       r"point 0: h\(\[0\. 0\.\]\) = \[nan  0\.\]$"):
        ukf_update(g, [1.0, 0.5], me, points=points)


def test_a_missing_component_where_h_gives_nan_is_not_used_on_any_path():
    """A component missing from ``y`` is not used, whatever ``h`` (or its Jacobian) gives
    there: ``h(x) = [x0, √x0]`` at a prior on ``x0 = 0`` is NaN for half the sigma points and
    members, and its Jacobian NaN. The batched UKF, the EnKF and the EKF multiplied those NaN
    by the mask's 0 and returned NaN for every estimate, without a word; the oracle is the
    Kalman update on the observed component, which ``h`` takes linearly (the EnKF, drawing
    its noise at random: the same update where ``h`` is finite on the missing component)."""
    from vistrack.filters import kf_update

    def h(x, missing=np.sqrt):
        return np.stack([x[..., 0], missing(x[..., 0])], axis=-1)

    me = NonlinearMeasurement(h, np.diag([0.5, 0.1]), ndim_state=2)
    x, P, y = np.array([0.0, 1.0]), np.eye(2), np.array([1.0, np.nan])
    ref = kf_update(vt.Gaussian(x, P), [1.0], np.array([[1.0, 0.0]]), [[0.5]])
    with np.errstate(invalid="ignore"):
        one = ukf_update(vt.Gaussian(x, P), y, me)
        batch = ukf_update(vt.Gaussian(np.stack([x, x]), np.stack([P, P])), np.stack([y, y]), me)
        ekf = ekf_update(vt.Gaussian(x, P), y, me)
        ens = Ensemble.sample(x, P, 500, rng=0)
        post = enkf_update(ens, y, me, rng=1)
        finite = enkf_update(ens, y, NonlinearMeasurement(
            lambda x: h(x, missing=np.abs), np.diag([0.5, 0.1]), ndim_state=2), rng=1)
    for g in (one, ekf):
        np.testing.assert_allclose(g.mean, ref.mean, atol=1e-9)
        np.testing.assert_allclose(g.cov, ref.cov, atol=1e-9)
    np.testing.assert_allclose(batch.mean, [ref.mean] * 2, atol=1e-9)
    np.testing.assert_allclose(batch.cov, [ref.cov] * 2, atol=1e-9)
    assert np.isfinite(post.members).all()
    np.testing.assert_array_equal(post.members, finite.members)


def test_a_step_per_estimate_and_a_singular_noise_are_named():
    """A ``dt`` per estimate of a batch (tracks seen at different intervals) is refused by
    every prediction with the Kalman filter's words; the UKF, EKF and EnKF failed inside
    numpy (``only 0-dimensional arrays can be converted to Python scalars``, or a broadcast
    of remapped shapes), naming nothing. A measurement noise singular on the observed
    components, which a linear model accepts, is named by the particle filter on both paths
    (it was numpy's bare ``Matrix is not positive definite``)."""
    from vistrack.filters import ParticleFilter, enkf_predict

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    for B in (2, 3):
        g = vt.Gaussian(np.tile([0.0, 1.0], (B, 1)), np.broadcast_to(np.eye(2), (B, 2, 2)))
        dt = np.arange(1.0, B + 1)
        shape = re.escape(f"got shape ({B},)")
        for f in (vt.KalmanFilter, UnscentedKalmanFilter, ExtendedKalmanFilter):
            with pytest.raises(ValueError, match="^dt must be one time step, for every "
                               f"estimate of g; {shape}$"):
                f(cv, pos).predict(g, dt=dt)
        with pytest.raises(ValueError, match="^dt must be one time step, for every ensemble "
                           f"of ens; {shape}$"):
            enkf_predict(Ensemble(np.zeros((B, 10, 2))), cv, dt=dt, rng=0)
    me = vt.models.LinearMeasurement(np.array([[1.0, 0.0], [1.0, 0.0]]), np.ones((2, 2)))
    for compiled in (True, False):
        with pytest.raises(ValueError, match=re.escape(
                "the measurement model's R must be positive definite on the observed "
                "components; on components [0, 1] it is not ([[1.0, 1.0], [1.0, 1.0]])")):
            ParticleFilter(cv, me, 100, rng=0, compiled=compiled).filter(
                np.ones((3, 2)), x0=[0.0, 1.0], P0=np.eye(2))


def test_a_model_setting_changed_after_the_filter_was_made_is_used():
    """The nonlinear filters kept each step's ``Q`` under its ``dt`` alone, so after
    ``motion.q`` was set (as ``KalmanFilter.fit`` sets its copies') a filter made before
    went on with the old ``Q``: the EKF's last variance 0.5954 where the Kalman filter's,
    its oracle on a linear model, is 0.9180. The ensemble and particle filters, drawn from
    one seed, now equal filters made after the change."""
    from vistrack.filters import KalmanFilter, ParticleFilter

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=1.0)
    ys, prior = np.arange(6.0)[:, None], dict(x0=[0.0, 0.0], P0=np.eye(2))
    made = {"ekf": ExtendedKalmanFilter(cv, pos), "ukf": UnscentedKalmanFilter(cv, pos),
            "enkf": EnsembleKalmanFilter(cv, pos, n_members=50),
            "pf": ParticleFilter(cv, pos, n_particles=200, compiled=False)}
    for f in made.values():  # (each keeps the first Q it computes)
        f.filter(ys, **prior)
    cv.q = 10.0
    want = KalmanFilter(cv, pos).filter(ys, **prior)
    for name in ("ekf", "ukf"):
        got = made[name].filter(ys, **prior)
        np.testing.assert_allclose(got.covs, want.covs, rtol=1e-9, err_msg=name)
        np.testing.assert_allclose(got.means, want.means, rtol=1e-9, atol=1e-12, err_msg=name)
    fresh = {"enkf": EnsembleKalmanFilter(cv, pos, n_members=50),
             "pf": ParticleFilter(cv, pos, n_particles=200, compiled=False)}
    for name, f in fresh.items():
        made[name].rng, f.rng = np.random.default_rng(3), np.random.default_rng(3)
        np.testing.assert_array_equal(made[name].filter(ys, **prior).means,
                                      f.filter(ys, **prior).means, err_msg=name)


def test_the_nonlinear_filters_take_the_intervals_between_steps_as_the_kalman_filter_does():
    """``dt=np.diff(times)`` (T-1 intervals) was refused by the EKF, UKF, EnKF, particle and
    IMM filters, which took only a scalar or T values, while ``KalmanFilter`` took it. On a
    linear model the EKF and UKF are the Kalman filter, the oracle; every filter gives with
    the intervals what it gives with ``np.diff(times, prepend=np.nan)``."""
    from vistrack.filters import KalmanFilter, ParticleFilter

    cv, pos = vt.ConstantVelocity(dim=1, q=0.3), vt.Position(dim=1, r=1.0)
    times = np.array([0.0, 0.5, 1.7, 2.0, 3.4])
    ys, prior = np.array([[0.1], [0.9], [2.2], [2.1], [3.9]]), dict(x0=[0.0, 1.0], P0=np.eye(2))
    want = KalmanFilter(cv, pos).filter(ys, dt=np.diff(times), **prior)
    for F in (ExtendedKalmanFilter, UnscentedKalmanFilter):
        got = F(cv, pos).filter(ys, dt=np.diff(times), **prior)
        np.testing.assert_allclose(got.means, want.means, rtol=1e-9, atol=1e-12)
        np.testing.assert_allclose(got.covs, want.covs, rtol=1e-9, atol=1e-12)
    for make in (lambda: EnsembleKalmanFilter(cv, pos, n_members=30, rng=2),
                 lambda: ParticleFilter(cv, pos, n_particles=100, rng=2)):
        a = make().filter(ys, dt=np.diff(times), **prior).means
        b = make().filter(ys, dt=np.diff(times, prepend=np.nan), **prior).means
        np.testing.assert_array_equal(a, b)


def test_a_model_array_changed_in_place_is_used():
    """A constant ``Q`` given as an array and changed in place (``m._Q_const[:] = ...``)
    kept the same identity, so the nonlinear filters went on with the ``Q`` computed
    before. The oracle is a filter made after the change."""
    from vistrack.models import NonlinearMotion

    Q0 = np.diag([0.1, 0.1])
    motion = NonlinearMotion(lambda x, dt, t: x @ np.array([[1.0, 0.0], [dt, 1.0]]),
                             Q0, ndim_state=2)
    pos = vt.Position(dim=1, r=1.0)
    ys, prior = np.arange(6.0)[:, None], dict(x0=[0.0, 0.0], P0=np.eye(2))
    ekf, ukf = ExtendedKalmanFilter(motion, pos), UnscentedKalmanFilter(motion, pos)
    before = ekf.filter(ys, **prior).covs
    ukf.filter(ys, **prior)
    motion._Q_const[:] = np.diag([5.0, 5.0])  # the same array, new values
    fresh = NonlinearMotion(motion._f, np.diag([5.0, 5.0]), ndim_state=2)
    for name, made, new in (("ekf", ekf, ExtendedKalmanFilter(fresh, pos)),
                            ("ukf", ukf, UnscentedKalmanFilter(fresh, pos))):
        got, want = made.filter(ys, **prior), new.filter(ys, **prior)
        np.testing.assert_allclose(got.covs, want.covs, rtol=1e-12, err_msg=name)
    assert not np.allclose(before, ekf.filter(ys, **prior).covs)


def test_an_ensemble_names_a_member_that_is_not_finite_and_a_cov_that_is_no_covariance():
    """One NaN member of 100 made every member NaN at the next update (and the
    log-likelihood NaN), without a word: the update names it. Ensemble.sample drew from the
    lower triangle of a cov that is not symmetric (another covariance), and a cov of another
    size than mean gave numpy's matmul error; the filter's own P0 check names the same
    matrix."""
    from vistrack.filters import Ensemble

    members = np.random.default_rng(0).normal(size=(100, 2))
    members[7, 0] = np.nan
    pos = vt.Position(dim=1)
    with pytest.raises(ValueError, match=re.escape("ens.members must be finite; "
                                                   "ens.members[7, 0] = nan")):
        enkf_update(Ensemble(members), [1.0], pos, rng=0)
    with pytest.raises(ValueError, match=re.escape("ens.members must be finite")):
        EnsembleKalmanFilter(vt.ConstantVelocity(dim=1, q=0.1), pos).update(Ensemble(members),
                                                                            [1.0])
    bad = np.array([[1.0, 0.9], [0.0, 1.0]])
    with pytest.raises(ValueError, match=re.escape("cov must be symmetric; cov[0, 1] = 0.9")):
        Ensemble.sample(np.zeros(2), bad, 10, rng=0)
    with pytest.raises(ValueError, match=re.escape("cov must have shape (n, n) or (..., n, n) "
                                                   "with n = 3, the size of mean (3,); got "
                                                   "(2, 2)")):
        Ensemble.sample(np.zeros(3), np.eye(2), 10, rng=0)
    # a singular covariance still draws on its subspace
    ens = Ensemble.sample(np.zeros(2), np.array([[1.0, 1.0], [1.0, 1.0]]), 50, rng=0)
    np.testing.assert_allclose(ens.members[:, 0], ens.members[:, 1])


def test_the_unscented_and_ensemble_filters_name_what_they_cannot_use():
    """A measurement model giving NaN at some sigma points (or members) made a batch's
    estimates NaN in ukf_update, and every member NaN in enkf_update, without a word (a
    single Gaussian's update named it); points_one took a covariance larger than x and used
    its top-left block; points met numpy's broadcast error; weights(-1) and weights(2.5)
    failed in numpy's words; a state of the wrong size met numpy's matmul error; an IMM
    member without a motion model failed on the attribute."""
    from vistrack.filters import (
        EnsembleKalmanFilter,
        IMMFilter,
        JulierSigmaPoints,
        KalmanFilter,
        MerweScaledSigmaPoints,
        enkf_predict,
        enkf_update,
        ukf_predict,
        ukf_update,
    )
    from vistrack.filters.enkf import Ensemble
    from vistrack.models import ConstantVelocity, NonlinearMeasurement, Position

    h = NonlinearMeasurement(lambda x: np.where(x[..., :1] > 0.5, np.nan, x[..., :1]), [[0.5]],
                             ndim_state=2)
    p = MerweScaledSigmaPoints(alpha=1.0)
    with pytest.raises(ValueError, match=re.escape(
            "the measurement model gave NaN or infinity at sigma point [0, 1]: "
            "h([1.4142 0.    ]) = [nan]")):
        ukf_update(vt.Gaussian(np.zeros((1, 2)), np.eye(2)[None]), [[0.0]], h, points=p)
    with pytest.raises(ValueError, match=r"the measurement model gave NaN or infinity at "
                                         r"member \[\d+\]"):
        enkf_update(Ensemble.sample([0, 0], np.eye(2), 50, rng=0), [0.0], h, rng=0)
    for call in (lambda: p.points_one(np.zeros(2), np.diag([1.0, 4.0, 9.0])),
                 lambda: p.points(np.zeros((3, 2)), np.diag([1.0, 4.0, 9.0]))):
        with pytest.raises(ValueError, match=re.escape(
                "P must be (..., 2, 2), the size of x's 2 values; got shape (3, 3)")):
            call()
    with pytest.raises(ValueError, match=re.escape("P must be symmetric")):
        p.points_one(np.zeros(2), [[1.0, 0.9], [0.0, 1.0]])
    assert p.points(np.zeros((3, 2)), np.eye(2)).shape == (3, 5, 2)
    for points, n in ((MerweScaledSigmaPoints(), -1), (JulierSigmaPoints(3), 2.5)):
        with pytest.raises(ValueError, match=re.escape(f"n must be a whole number >= 1; got "
                                                       f"{n}")):
            points.weights(n)
    with pytest.raises(ValueError, match=re.escape(
            "g must have a state of 4 values, the motion model's; got 2")):
        ukf_predict(vt.Gaussian(np.zeros(2), np.eye(2)), ConstantVelocity(dim=2))
    with pytest.raises(ValueError, match=re.escape(
            "ens must have members of 4 values, the motion model's; got 2")):
        enkf_predict(Ensemble.sample([0, 0], np.eye(2), 20, rng=0), ConstantVelocity(dim=2))

    class NoMotion:
        def predict(self, g, dt=1.0, t=0.0):
            return g

        def update(self, g, y):
            return g, 0.0

    kf = KalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1))
    with pytest.raises(TypeError, match=re.escape(
            "filters[1] must have predict(g, dt, t), update(g, y) and a motion model "
            "(.motion.ndim_state); got NoMotion")):
        IMMFilter([kf, NoMotion()], [[0.9, 0.1], [0.1, 0.9]])
    # an EnKF has both steps and a motion model, but its steps take ensembles: it was
    # taken, and filter() failed on "ens must be a vistrack.filters.Ensemble", an argument
    # the caller never gave
    enkf = EnsembleKalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1), rng=0)
    with pytest.raises(TypeError, match=re.escape(
            "filters[0] is an EnsembleKalmanFilter, whose steps take and give ensembles; "
            "IMMFilter mixes Gaussians")):
        IMMFilter([enkf, kf], [[0.9, 0.1], [0.1, 0.9]])


def test_the_nonlinear_filters_refuse_a_motion_q_that_is_no_covariance():
    """A user's model whose Q(dt) had a typo (an eigenvalue -0.0043): the Kalman filter
    refused it, the EKF gave covariances with a negative eigenvalue without a word (and
    Q = -I was named as R), the particle filter's square root clipped it. Each nonlinear
    filter names it now, with its dt; a Q of another shape too."""
    from vistrack.filters import ekf_predict, enkf_predict
    from vistrack.filters.particle import ParticleFilter
    from vistrack.models import ConstantVelocity, Position

    class Typo(ConstantVelocity):
        def Q(self, dt):
            return self.q * np.array([[dt ** 3 / 3, dt], [dt, dt]])

    class Wide(ConstantVelocity):
        def Q(self, dt):
            return np.eye(3)

    g = vt.Gaussian(np.zeros(2), np.eye(2))
    typo = Typo(dim=1, q=1.0)
    assert np.linalg.eigvalsh(typo.Q(0.1))[0] < 0
    ens = Ensemble(np.zeros((50, 2)))
    for call in (lambda m: ekf_predict(g, m, 0.1), lambda m: ukf_predict(g, m, 0.1),
                 lambda m: enkf_predict(ens, m, 0.1, rng=0),
                 lambda m: ParticleFilter(m, Position(dim=1, r=1.0), 100,
                                          rng=0).filter(np.zeros((3, 1)), x0=[0.0, 0.0],
                                                        P0=np.eye(2), dt=0.1)):
        with pytest.raises(ValueError, match=re.escape(
                "motion.Q(0.1) must be positive semi-definite; its smallest eigenvalue is")):
            call(typo)
        with pytest.raises(ValueError, match=re.escape(
                "motion.Q(0.1) must have shape (2, 2), the state's; got (3, 3)")):
            call(Wide(dim=1, q=1.0))


def test_the_check_of_a_models_q_never_serves_another_q():
    """A model's Q is checked once for each value it takes (kept by the matrix's values,
    not by the model): a setting changed between single steps, even inside a list the
    model holds, gives its own Q (oracle: a new model with that setting), from threads at
    once too."""
    from concurrent.futures import ThreadPoolExecutor

    from vistrack.filters import ekf_predict
    from vistrack.models import ConstantVelocity

    class Held(ConstantVelocity):  # its noise in a list: changed in place
        def __init__(self, box):
            super().__init__(dim=1, q=1.0)
            self.box = box

        def Q(self, dt):
            return self.box[0] * super().Q(dt)

    g = vt.Gaussian(np.array([0.0, 1.0]), np.eye(2))
    cv, held = ConstantVelocity(dim=1, q=0.1), Held([0.1])
    for predict in (ekf_predict, ukf_predict):
        for model, set_q in ((cv, lambda q: setattr(cv, "q", q)),
                             (held, lambda q: held.box.__setitem__(0, q))):
            a = predict(g, model, 0.5)
            set_q(10.0)
            b = predict(g, model, 0.5)
            set_q(0.1)
            np.testing.assert_allclose(a.cov, predict(g, ConstantVelocity(dim=1, q=0.1),
                                                      0.5).cov)
            np.testing.assert_allclose(b.cov, predict(g, ConstantVelocity(dim=1, q=10.0),
                                                      0.5).cov)
    dts = np.random.default_rng(0).uniform(0.1, 2.0, 400)
    with ThreadPoolExecutor(8) as pool:
        got = list(pool.map(lambda dt: ekf_predict(g, cv, dt).cov, dts))
    for dt, cov in zip(dts, got):
        np.testing.assert_allclose(cov, ekf_predict(g, ConstantVelocity(dim=1, q=0.1),
                                                    dt).cov)


def test_a_state_or_a_measurement_of_another_size_is_named():
    """ekf_predict with a state of 4 values and a model of 2 failed in numpy's broadcasting
    (ukf_predict named it); a measurement model whose h gives 3 values and whose R is 2 x 2
    failed so in the EKF, and the UKF's step for one Gaussian read the first 2 values and
    returned a wrong estimate without a word."""
    from vistrack.filters import ekf_predict
    from vistrack.models import ConstantVelocity

    with pytest.raises(ValueError, match=re.escape("g must have a state of 2 values, the "
                                                   "motion model's; got 4")):
        ekf_predict(vt.Gaussian(np.zeros(4), np.eye(4)), ConstantVelocity(dim=1), 1.0)
    meas = NonlinearMeasurement(lambda x: x[..., :3], R=np.eye(2), ndim_state=5)
    message = re.escape("the measurement model's h(x) gives values of shape (")
    for g in (vt.Gaussian(np.ones(5), np.eye(5)),
              vt.Gaussian(np.ones((2, 5)), np.broadcast_to(np.eye(5), (2, 5, 5)).copy())):
        for update in (ekf_update, ukf_update):
            with pytest.raises(ValueError, match=message + r"(.* )?3,?\) for states of shape "
                               r".* its R is 2 x 2"):
                update(g, np.ones(g.mean.shape[:-1] + (2,)), meas)
    # an h that drops the measurement's axis (m = 1): said as such, not as 5 values a state
    flat = NonlinearMeasurement(lambda x: x[..., 0], R=np.eye(1), ndim_state=5)
    with pytest.raises(ValueError, match=re.escape(
            "gives values of shape (11,) for states of shape (11, 5); its R is 1 x 1, so "
            "(11, 1) was expected")):
        ukf_update(vt.Gaussian(np.ones(5), np.eye(5)), np.ones(1), flat)


def test_coordinated_turn_names_a_dt_that_is_not_one_finite_step():
    """CoordinatedTurn.f and .jacobian took a NaN step (every state NaN) or a negative one
    (the states moved backwards), where Q and every filter refused them."""
    ct, x = CoordinatedTurn(), np.array([0.0, 0.0, 1.0, 0.0, 0.5])
    for call in (ct.f, ct.jacobian, lambda x, dt: ct.Q(dt)):
        for bad in (np.nan, -0.5, np.inf):
            with pytest.raises(ValueError, match=r"dt must be finite and >= 0"):
                call(x, bad)
        with pytest.raises(ValueError, match=r"dt must be one value; got shape \(2,\)"):
            call(x, [1.0, 2.0])
        with pytest.raises(TypeError, match=r"dt must be a number"):
            call(x, True)
    # the same numbers as before for a good step: a quarter turn at ω = π/2 (closed form)
    np.testing.assert_allclose(ct.f(np.array([0.0, 0.0, 1.0, 0.0, np.pi / 2]), 1.0),
                               [2 / np.pi, 2 / np.pi, 0.0, 1.0, np.pi / 2], atol=1e-15)


def test_numerical_jacobian_names_a_scalar_point():
    """A scalar x was an IndexError from x.shape[-1]; one value is a point of shape (1,)."""
    with pytest.raises(ValueError, match=r"x must be points of shape \(\.\.\., n\).*scalar 2\.0"):
        numerical_jacobian(np.sin, 2.0)
    np.testing.assert_allclose(numerical_jacobian(np.sin, np.array([2.0])), [[np.cos(2.0)]],
                               rtol=1e-9)


class _Double:
    """A residual twice the difference, to see which residual an update used."""

    def __call__(self, a, b):
        return 2.0 * (np.asarray(a) - np.asarray(b))


@pytest.mark.parametrize("update", ["ekf", "ukf", "enkf"])
def test_a_residual_given_with_measurement_functions_is_used(update):
    """ekf_update(g, y, MeasurementFunctions(...), residual=f) ignored f: the functions' own
    residual was used. Given with functions already made, f is used, as with a model; the
    oracle is the same update with the residual given beside the model itself."""
    g = vt.Gaussian(np.array([0.0, 1.0]), np.diag([1.0, 0.5]))
    model = vt.Position(dim=1, r=0.25)
    me = MeasurementFunctions(model, 2)
    if update == "enkf":
        ens = Ensemble.sample(g.mean, g.cov, 200, rng=0)

        def run(m, **kw):
            return enkf_update(ens, [1.5], m, rng=1, **kw).members.mean(0)
    else:
        fn = ekf_update if update == "ekf" else ukf_update

        def run(m, **kw):
            return fn(g, [1.5], m, **kw).mean
    flipped = run(model, residual=_Double())
    np.testing.assert_array_equal(run(me, residual=_Double()), flipped)
    assert not np.allclose(flipped, run(me))   # (the residual does change the answer)
    np.testing.assert_array_equal(run(me), run(model))


def test_ukf_names_an_asymmetric_covariance():
    """The UKF's square root read g.cov's lower triangle alone, where kf_predict reads the
    whole matrix: [[1, 0.9], [0, 1]] gave the points of [[1, 0.9], [0.9, 1]]. It is named, on
    the one-Gaussian (compiled) path and on a batch, as a prior is."""
    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=0.5)
    bad = np.array([[1.0, 0.9], [0.0, 1.0]])
    for mean, cov in ((np.zeros(2), bad), (np.zeros((3, 2)), np.stack([np.eye(2), bad, bad]))):
        g = vt.Gaussian(mean, cov)
        y = np.ones(mean.shape[:-1] + (1,))
        with pytest.raises(ValueError, match=r"g\.cov must be symmetric; g\.cov\[.*0, 1\] = 0\.9"):
            ukf_predict(g, cv)
        with pytest.raises(ValueError, match=r"g\.cov must be symmetric; g\.cov\[.*0, 1\] = 0\.9"):
            ukf_update(g, y, pos)
    # symmetric to rounding (1e-12 of the largest entry) is taken, and on a linear model the
    # UKF's prediction is the Kalman filter's (the oracle)
    ok = np.array([[1.0, 0.3], [0.3 + 1e-12, 2.0]])
    g = vt.Gaussian(np.array([0.5, 1.0]), ok)
    want = vt.filters.kf_predict(g, F=cv.F(1.0), Q=cv.Q(1.0))
    got = ukf_predict(g, cv)
    np.testing.assert_allclose(got.mean, want.mean, rtol=1e-9)  # (W0 about -1e6: digits lost)
    np.testing.assert_allclose(got.cov, want.cov, rtol=1e-9)


def test_the_ensemble_filter_checks_before_it_draws_and_names_model_values_of_wrong_size():
    """`EnsembleKalmanFilter.filter` drew its first ensemble before `dt`, `times` and `ys`
    were checked, so a refused call used up the generator and the next one differed from a
    fresh filter's; an `h` of one value too few was broadcast over the measurement (a
    posterior, without a word), an `f` of one too few kept members of the wrong size (the
    unscented filter read zeros past them: [0, 0]); `Ensemble.sample` and
    `EnsembleKalmanFilter.update` met numpy's broadcast and matmul errors. Oracles: a fresh
    filter of the same seed, and the EKF's words for `h` (`ekf_update`)."""
    from vistrack.filters import (
        EnsembleKalmanFilter,
        ekf_predict,
        ekf_update,
        enkf_predict,
        enkf_update,
        ukf_predict,
    )
    from vistrack.filters.enkf import Ensemble
    from vistrack.models import NonlinearMeasurement, NonlinearMotion

    cv, pos = vt.ConstantVelocity(dim=1, q=0.3), vt.Position(dim=1, r=0.7)
    ys, prior = np.arange(5.0)[:, None], dict(x0=[0.0, 0.0], P0=np.eye(2))
    fresh = EnsembleKalmanFilter(cv, pos, n_members=30, rng=5).filter(ys, **prior).means
    for bad in (dict(dt=-1.0), dict(dt=np.ones(3)), dict(times=[0.0, 1.0]),
                dict(ys=np.zeros((5, 2)))):
        f = EnsembleKalmanFilter(cv, pos, n_members=30, rng=5)
        with pytest.raises(ValueError):
            f.filter(bad.pop("ys", ys), **bad, **prior)
        assert np.array_equal(f.filter(ys, **prior).means, fresh)
    g = vt.Gaussian([0.0, 1.0], np.eye(2))
    h = NonlinearMeasurement(lambda x: x[..., :1], np.eye(2), ndim_state=2)
    with pytest.raises(ValueError, match=re.escape(
            "the measurement model's h(x) gives values of shape (1,) for states of shape (2,)"
            "; its R is 2 x 2, so (2,) was expected")):
        ekf_update(g, [1.0, 2.0], h)
    with pytest.raises(ValueError, match=re.escape(
            "the measurement model's h(x) gives values of shape (100, 1) for states of shape "
            "(100, 2); its R is 2 x 2, so (100, 2) was expected")):
        enkf_update(Ensemble.sample([0.0, 1.0], np.eye(2), 100, rng=0), [1.0, 2.0], h, rng=1)
    for Q in (np.zeros((2, 2)), 0.1 * np.eye(2)):
        mo = NonlinearMotion(lambda x, dt, t: x[..., :1], Q, ndim_state=2)
        ens = Ensemble.sample([0.0, 1.0], np.eye(2), 10, rng=0)
        for predict, state, shape in ((ekf_predict, g, "(2,)"), (ukf_predict, g, "(5, 2)"),
                                      (enkf_predict, ens, "(10, 2)")):
            with pytest.raises(ValueError, match=re.escape(
                    f"for states of shape {shape}; its ndim_state is 2, so {shape} was "
                    "expected")):
                predict(state, mo)
    with pytest.raises(ValueError, match=re.escape(
            "mean and cov must have batch shapes that broadcast; got mean (3, 2) and cov "
            "(4, 2, 2)")):
        Ensemble.sample(np.zeros((3, 2)), np.broadcast_to(np.eye(2), (4, 2, 2)), 10, rng=0)
    with pytest.raises(ValueError, match=re.escape(
            "ens must have members of 2 values, the motion model's; got 3")):
        EnsembleKalmanFilter(cv, pos).update(Ensemble(np.zeros((5, 3))), [0.0])


def test_the_sigma_point_filters_and_the_ekf_refuse_what_their_other_path_refuses():
    """The batched sigma points took a NaN covariance (LAPACK's factor is NaN, no error: the
    update blamed `h`) where the one-Gaussian path named it, and an infinite one on both;
    a measurement model's `R` of a negative variance gave a posterior variance of -1.33
    (UKF and EKF), an asymmetric one was read by its lower triangle in the UKF and whole in
    the EKF; `alpha` 1e155 met float's OverflowError and `kappa` 1e308 gave NaN weights;
    `points(x (2,), P (3, 2, 2))` met numpy's words; the EKF took a covariance of a
    negative variance; `points="merwe"` failed at the first step and `points=0` was the
    default. Oracles: the other path's words, and `Q`'s checks for `R`."""
    from vistrack.filters import (
        MerweScaledSigmaPoints,
        UnscentedKalmanFilter,
        ekf_predict,
        ekf_update,
        ukf_predict,
        ukf_update,
    )

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    nan = np.array([[np.nan, 0.0], [0.0, 1.0]])
    for g in (vt.Gaussian(np.zeros(2), nan), vt.Gaussian(np.zeros((1, 2)), nan[None]),
              vt.Gaussian(np.zeros(2), np.diag([np.inf, 1.0]))):
        with pytest.raises(ValueError, match=r"^g\.cov must be finite"):
            ukf_predict(g, cv)
        with pytest.raises(ValueError, match=r"^g\.cov must be finite"):
            ukf_update(g, np.zeros(g.mean.shape[:-1] + (1,)), pos)
    with pytest.raises(ValueError, match=r"^P must be finite"):
        MerweScaledSigmaPoints(0.5).points(np.zeros((1, 2)), nan[None])
    prior = vt.Gaussian(np.zeros(2), 4 * np.eye(2))
    class Plain:  # (a user's own model: NonlinearMeasurement checks its R itself)
        def __init__(self, R):
            self._R = np.asarray(R, float)

        def h(self, x):
            return x

        def jacobian(self, x):
            return np.broadcast_to(np.eye(2), x.shape[:-1] + (2, 2))

        def R(self):
            return self._R

    for R, said in ((np.diag([-1.0, 1.0]), "measurement.R() must be positive semi-definite"),
                    ([[1.0, 0.5], [0.0, 1.0]], "measurement.R() must be symmetric")):
        me = Plain(R)
        for update in (ukf_update, ekf_update):
            with pytest.raises(ValueError, match=re.escape(said)):
                update(prior, [1.0, 1.0], me)
    for kw in (dict(alpha=1e155), dict(alpha=10.0, kappa=1e308)):
        with pytest.raises(ValueError, match=re.escape("alpha**2 * (n + kappa) must be "
                                                       "finite")):
            MerweScaledSigmaPoints(**kw).weights(2)
    p = MerweScaledSigmaPoints(0.5)
    many = p.points(np.zeros(2), np.broadcast_to(np.eye(2), (3, 2, 2)))
    assert many.shape == (3, 5, 2) and np.array_equal(many[1], p.points_one(np.zeros(2),
                                                                            np.eye(2)))
    with pytest.raises(ValueError, match=re.escape(
            "x and P must have batch shapes that broadcast; got x (3, 2) and P (4, 2, 2)")):
        p.points(np.zeros((3, 2)), np.broadcast_to(np.eye(2), (4, 2, 2)))
    for call in (lambda: ekf_update(vt.Gaussian(np.zeros(2), [[1.0, 2.0], [2.0, 1.0]]), [1.0],
                                    pos),
                 lambda: ekf_predict(vt.Gaussian(np.zeros(2), -np.eye(2)), cv)):
        with pytest.raises(ValueError, match=r"^g\.cov must be positive semi-definite"):
            call()
    for points in ("merwe", 0):
        with pytest.raises(TypeError, match="^points must be MerweScaledSigmaPoints or "
                                            "JulierSigmaPoints"):
            UnscentedKalmanFilter(cv, pos, points=points)
        with pytest.raises(TypeError, match="^points must be"):
            ukf_predict(prior, cv, points=points)


def test_the_second_reading_of_the_filters_checks():
    """From the second reading: a particle filter's `h` of the wrong size failed in numpy's
    IndexError (the other filters name it); a measurement's `R` of the wrong shape was said
    to be "the state's" size; `axes_predict` took `np.timedelta64` through float()'s bare
    TypeError; the EKF's check of its covariance cost an eigendecomposition every step
    (the numbers are the same as an exact Kalman filter's, the oracle)."""
    from vistrack.filters import KalmanFilter, axes_predict, ekf_update
    from vistrack.filters.particle import ParticleFilter
    from vistrack.models import NonlinearMeasurement

    short = NonlinearMeasurement(lambda x: x[..., :1], np.eye(2), ndim_state=2)
    pf = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1), short, 50, rng=0)
    with pytest.raises(ValueError, match=re.escape("the measurement model's h(x) gives values "
                                                   "of shape (50, 1)")):
        pf.filter(np.zeros((2, 2)), x0=[0.0, 0.0], P0=np.eye(2))

    class Plain:
        def h(self, x):
            return x

        def jacobian(self, x):
            return np.broadcast_to(np.eye(2), x.shape[:-1] + (2, 2))

        def R(self):
            return np.eye(2, 3)

    with pytest.raises(ValueError, match=re.escape(
            "measurement.R() must have shape (3, 3), the measurement's; got (2, 3)")):
        ekf_update(vt.Gaussian(np.zeros(2), np.eye(2)), [0.0, 0.0, 0.0], Plain())
    with pytest.raises(ValueError, match="dt must be one finite number"):
        axes_predict([[0.0, 1.0]], [[[1.0, 0.0, 1.0]]], np.timedelta64(1, "s"), [[0.0, 0.0]])
    from vistrack.filters import ExtendedKalmanFilter

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    ys = np.cumsum(np.random.default_rng(0).normal(size=(200, 1)), axis=0)
    ekf = ExtendedKalmanFilter(cv, pos).filter(ys, x0=[0.0, 0.0], P0=np.eye(2))
    kf = KalmanFilter(cv, pos).filter(ys, x0=[0.0, 0.0], P0=np.eye(2))
    np.testing.assert_allclose(ekf.means, kf.means, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("make, tol", [
    (lambda cv, pos: ExtendedKalmanFilter(cv, pos), 1e-9),
    (lambda cv, pos: UnscentedKalmanFilter(cv, pos), 1e-9),
    (lambda cv, pos: EnsembleKalmanFilter(cv, pos, n_members=2000, rng=2), 0.3),
    (lambda cv, pos: ParticleFilter(cv, pos, 2000, rng=2, compiled=True), 0.3),
    (lambda cv, pos: ParticleFilter(cv, pos, 2000, rng=2, compiled=False), 0.3),
    (lambda cv, pos: IMMFilter([ExtendedKalmanFilter(cv, pos)] * 2, np.full((2, 2), 0.5)),
     1e-9),
], ids=["ekf", "ukf", "enkf", "pf-compiled", "pf-numpy", "imm"])
def test_times_alone_are_the_steps(make, tol):
    """`times` given without `dt` were filtered with steps of 1, whatever they said: a gap of
    4.9 s was predicted over 1 s (the EKF's prediction 0.42 for 10), without a word.
    Oracles: the Kalman filter given `dt = np.diff(times)` (the filters are exact on this
    linear model, the sampled ones within their error: 0.14 at most over five seeds, where
    steps of 1 are 6.8 off), and the same filter given that `dt`; times that disagree with
    `dt`, or go back, are named."""
    from vistrack.filters import KalmanFilter

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=0.01)
    t = np.array([0.0, 0.1, 5.0, 5.1])
    ys, prior = (2.0 * t)[:, None], dict(x0=[0.0, 2.0], P0=np.eye(2))
    got = make(cv, pos).filter(ys, times=t, **prior)
    want = make(cv, pos).filter(ys, dt=np.diff(t), **prior)
    assert np.array_equal(got.means, want.means)
    exact = KalmanFilter(cv, pos).filter(ys, dt=np.diff(t), **prior).means
    assert np.abs(got.means - exact).max() < tol
    with pytest.raises(ValueError, match=re.escape(
            "dt and times disagree: the step to step 1 is 1.0 in dt and 0.1 in times "
            "(times[1] - times[0]); give one of them")):
        make(cv, pos).filter(ys, dt=1.0, times=t, **prior)
    with pytest.raises(ValueError, match=re.escape(
            "times must not decrease; times[1] = 5.0 comes after times[0] = 5.1")):
        make(cv, pos).filter(ys, times=t[::-1], **prior)
    # an epoch's seconds beside their steps: equal within the times' own rounding; float32
    # times of 1/30 s beside float64 steps, 5e-9 apart, within theirs (they were refused)
    epoch = make(cv, pos).filter(ys, dt=np.diff(t), times=1.7e9 + t, **prior)
    assert np.array_equal(epoch.means, want.means)
    t32 = (np.arange(4) / 30).astype(np.float32)
    assert np.array_equal(make(cv, pos).filter(ys, dt=1 / 30, times=t32, **prior).means,
                          make(cv, pos).filter(ys, dt=1 / 30, **prior).means)


def test_ekf_filter_equals_filterpy_and_the_numpy_correction():
    """The EKF's filter corrects one Gaussian in one compiled call and skips the checks of
    a Gaussian given on its own states (it ran at 0.25 ms a step, FilterPy's at 0.13).
    Oracles: FilterPy's ExtendedKalmanFilter (given the model's f, Jacobians and
    residual) on a coordinated turn seen by range and bearing, means, covariances and
    log-likelihood; with a component missing, the numpy correction
    (`reference.condition_on`) step by step; a subclass's own update is still called."""
    from filterpy.kalman import ExtendedKalmanFilter as FilterPyEKF

    from vistrack.filters.ekf import ekf_predict
    from vistrack.filters.reference import condition_on

    motion, meas = CoordinatedTurn(q=0.05, q_turn=1e-3), RangeBearing(1.0, 1e-3, ndim_state=5)
    x0 = np.array([-20.0, 8.0, 0.0, -0.8, 0.01])
    P0 = np.diag([4.0, 4.0, 0.5, 0.5, 1e-3])
    _, zs = vt.simulate.simulate(motion, meas, 60, x0=x0, rng=5)
    got = ExtendedKalmanFilter(motion, meas).filter(zs, x0=x0, P0=P0)

    class Turn(FilterPyEKF):
        def predict_x(self, u=0):
            self.x = motion.f(self.x, 1.0)

    kf = Turn(dim_x=5, dim_z=2)
    kf.x, kf.P, kf.Q, kf.R = x0.copy(), P0.copy(), motion.Q(1.0), meas.R()
    ll = 0.0
    for k, z in enumerate(zs):
        if k:
            kf.F = motion.jacobian(kf.x, 1.0)
            kf.predict()
        kf.update(z, meas.jacobian, meas.h, residual=meas.residual)
        ll += kf.log_likelihood
        assert np.abs(got.means[k] - kf.x).max() < 1e-9
        assert np.abs(got.covs[k] - kf.P).max() < 1e-9
    assert got.loglik == pytest.approx(ll, abs=1e-8)
    # a bearing missing every third step: numpy's correction of the observed range alone
    ys = zs.copy()
    ys[::3, 1] = np.nan
    got = ExtendedKalmanFilter(motion, meas).filter(ys, x0=x0, P0=P0)
    g = vt.Gaussian(x0, P0)
    for k, y in enumerate(ys):
        if k:
            g = ekf_predict(g, motion)
        obs = ~np.isnan(y)
        e = meas.residual(np.where(obs, y, 0.0), meas.h(g.mean))
        mean, cov, _ = condition_on(g.mean, g.cov, meas.jacobian(g.mean), meas.R(), e, obs)
        g = vt.Gaussian(mean, cov)
        assert np.abs(got.means[k] - mean).max() < 1e-9
        assert np.abs(got.covs[k] - cov).max() < 1e-9
    calls = []

    class Counted(ExtendedKalmanFilter):
        def update(self, g, y):
            calls.append(1)
            return super().update(g, y)

    Counted(motion, meas).filter(zs[:5], x0=x0, P0=P0)
    assert len(calls) == 5


def test_ekf_filter_corrects_in_the_kernel_and_checks_what_is_not_its_own(monkeypatch):
    """The filter's one-Gaussian corrections go through the compiled kernel, fully or partly
    observed (numpy's correction made to fail here); a predict or update of a subclass's, of
    the instance's or patched on the class is called, and what it gives is checked (a
    subclass's prediction of a variance of -5 was corrected without a word, an instance's
    predict was skipped); a Jacobian of the wrong shape is named (it met numba's reshape
    error). Oracle: the code before the kernel, whose messages these are."""
    from unittest import mock

    import vistrack.filters.ekf as ekf_module
    from vistrack.filters import ekf_predict

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=0.5)
    prior = dict(x0=[0.0, 1.0], P0=np.eye(2))
    ys = np.array([[0.0], [1.0], [np.nan], [3.1]])
    want = kalman_filter(ys, F=cv.F(1.0), Q=cv.Q(1.0), H=pos.H(2), R=pos.R(), **prior)

    def numpy_path(*args, **kwargs):
        raise AssertionError("numpy's correction")

    with monkeypatch.context() as m:
        m.setattr(ekf_module, "condition_on", numpy_path)
        got = ExtendedKalmanFilter(cv, pos).filter(ys, **prior)
        motion, meas = CoordinatedTurn(q=0.05), RangeBearing(1.0, 1e-3, ndim_state=5)
        zs = np.array([[20.0, 0.3], [np.nan, 0.31], [19.5, np.nan]])
        ExtendedKalmanFilter(motion, meas).filter(
            zs, x0=[-20.0, 8.0, 0.0, -0.8, 0.01], P0=np.diag([4.0, 4.0, 0.5, 0.5, 1e-3]))
    np.testing.assert_allclose(got.means, want.means, atol=1e-12)
    np.testing.assert_allclose(got.loglik, want.loglik, atol=1e-12)

    class NegativePredict(ExtendedKalmanFilter):
        def predict(self, g, dt=1.0, t=0.0):
            p = ekf_predict(g, self.motion, dt, t)
            return vt.Gaussian(p.mean, np.array([[1.0, 3.0], [3.0, 1.0]]))

    with pytest.raises(ValueError, match="step 1: g.cov must be positive semi-definite"):
        NegativePredict(cv, pos).filter(ys, **prior)
    still = ExtendedKalmanFilter(cv, pos)
    still.predict = lambda g, dt=1.0, t=0.0: vt.Gaussian(g.mean, g.cov)
    np.testing.assert_allclose(  # (predicting nothing: the Kalman filter of F = I, Q = 0)
        still.filter(ys[:2], **prior).means,
        kalman_filter(ys[:2], F=np.eye(2), Q=np.zeros((2, 2)), H=pos.H(2), R=pos.R(),
                      **prior).means, atol=1e-12)
    with mock.patch.object(ExtendedKalmanFilter, "update", autospec=True,
                           side_effect=ExtendedKalmanFilter.update) as patched:
        ExtendedKalmanFilter(cv, pos).filter(ys, **prior)
    assert patched.call_count == 3  # (the step of no measurement is predicted only)
    wide = vt.models.NonlinearMeasurement(lambda x: x[..., :1], np.eye(1), ndim_state=2,
                                          jacobian=lambda x: np.ones(x.shape[:-1] + (1, 3)))
    with pytest.raises(ValueError, match=re.escape(
            "the measurement model's jacobian(x) gives shape (1, 3) for states of shape (2,); "
            "(..., 1, 2) was expected (its R is 1 x 1)")):
        ExtendedKalmanFilter(cv, wide).filter(ys, **prior)


def test_an_ensemble_drawn_for_a_batch_of_covariances_has_draws_of_its_own():
    """One mean beside a batch of covariances drew one set of normals and scaled it for
    every ensemble: the two ensembles' members correlated exactly 1. Each now has its own
    draws (the oracle: independent members correlate near 0, within 5 standard errors,
    and each ensemble's sample covariance is its own)."""
    from vistrack.filters import Ensemble

    covs = np.stack([np.eye(2), 4 * np.eye(2)])
    m = Ensemble.sample(np.zeros(2), covs, 20000, rng=0).members
    assert m.shape == (2, 20000, 2)
    r = np.corrcoef(m[0, :, 0], m[1, :, 0])[0, 1]
    assert abs(r) < 5 / np.sqrt(20000), r
    for b in range(2):
        np.testing.assert_allclose(np.cov(m[b].T), covs[b], atol=5 * covs[b, 0, 0]
                                   * np.sqrt(2 / 20000))
    # a batch of means with one covariance draws as it did: the same members
    same = Ensemble.sample(np.zeros((2, 2)), np.eye(2), 50, rng=3).members
    z = np.random.default_rng(3).standard_normal((2, 50, 2))
    np.testing.assert_array_equal(same, z @ np.linalg.cholesky(np.eye(2)).T)


def test_an_ensemble_of_a_singular_covariance_of_far_apart_scales_has_its_variances():
    """A constant-acceleration process noise at dt 1e-4 beside a component known exactly
    (singular): the principal root gave the position 35/36 of its variance (a sample of
    400,000 had 0.971 of it). The oracle: each component's sample variance against the
    covariance's own, within 5 standard errors (sqrt(2 / N))."""
    from vistrack.filters import Ensemble
    Q = vt.ConstantAcceleration(dim=1, q=1.0).Q(1e-4)
    cov = np.zeros((4, 4))
    cov[:3, :3] = Q
    N = 400_000
    m = Ensemble.sample(np.zeros(4), cov, N, rng=0).members
    ratio = m[:, :3].var(0) / np.diag(Q)
    np.testing.assert_allclose(ratio, 1.0, atol=5 * np.sqrt(2 / N))
    assert (m[:, 3] == 0).all()


def test_the_ensemble_steps_name_an_argument_that_is_no_ensemble():
    """A Gaussian given to an ensemble step failed in Python's words (no attribute
    'members'); a measurement of the wrong size was said "to match g", a name the ensemble
    functions do not have."""
    from vistrack.filters import Ensemble, EnsembleKalmanFilter, enkf_predict, enkf_update

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    g = vt.Gaussian(np.zeros(2), np.eye(2))
    with pytest.raises(TypeError, match="ens must be a vistrack.filters.Ensemble .*got Gaussian"):
        enkf_predict(g, cv)
    with pytest.raises(TypeError, match="ens must be .*got ndarray"):
        enkf_update(np.zeros((10, 2)), [1.0], pos)
    with pytest.raises(TypeError, match="ens must be .*got Gaussian"):
        EnsembleKalmanFilter(cv, pos, rng=0).update(g, [1.0])
    ens = Ensemble.sample(np.zeros(2), np.eye(2), 10, rng=0)
    with pytest.raises(ValueError, match=re.escape("y must have shape (1,) to match ens; got "
                                                   "(2,)")):
        enkf_update(ens, [1.0, 2.0], pos)


# ---------------------------------------------------------------- the EKF's compiled path
def _jit_jacobian_cases():
    from vistrack.models import GrowthMeasurement, GrowthMotion

    rng = np.random.default_rng(3)
    ct, rb = CoordinatedTurn(), RangeBearing(sensor=(1.0, -2.0), ndim_state=5)
    growth, square = GrowthMotion(), GrowthMeasurement()
    cases = []
    for w in (0.7, -0.3, 1e-6, 0.0, 3.0):  # (|ω dt| < 1e-4: the series)
        for dt in (0.1, 1.0, 2.5):
            x = np.r_[rng.normal(0, 5, 4), w]
            cases.append((ct, x, dt, 0.0))
    cases += [(rb, np.r_[rng.normal(0, 5, 2), 0.0, 0.0, 0.1], None, None) for _ in range(4)]
    cases += [(growth, np.array([v]), 1.0, t) for v, t in ((0.3, 0.0), (-4.0, 3.0))]
    cases += [(square, np.array([v]), None, None) for v in (2.0, -7.5)]
    return cases


@pytest.mark.parametrize("model, x, dt, t", _jit_jacobian_cases())
def test_compiled_jacobians_equal_the_models_and_finite_differences(model, x, dt, t):
    """Each model's compiled Jacobian (``jit_jacobian``, what the EKF's compiled path calls)
    against its numpy ``jacobian`` (to rounding) and central differences of its compiled
    ``jit_f`` / ``jit_h`` (an independent oracle of the derivative)."""
    motion = dt is not None
    n = len(x)
    if motion:
        p = model.jit_params(np.array([dt]), np.array([t]))[0]
        rows = n
        want = model.jacobian(x, dt, t)

        def value(z):
            out = np.empty(n)
            model.jit_f(z, dt, t, p, out)
            return out
    else:
        p = model.jit_params()
        rows = model.ndim_meas if hasattr(model, "ndim_meas") else 1
        want = model.jacobian(x)

        def value(z):
            out = np.empty(rows)
            model.jit_h(z, p, out)
            return out

    got = np.full((rows, n), np.nan)
    if motion:
        model.jit_jacobian(x, dt, t, p, got)
    else:
        model.jit_jacobian(x, p, got)
    np.testing.assert_allclose(got, want, rtol=1e-13, atol=1e-14)
    h = 1e-6 * np.maximum(1.0, np.abs(x))
    diff = np.column_stack([(value(x + h[k] * np.eye(n)[k]) - value(x - h[k] * np.eye(n)[k]))
                            / (2 * h[k]) for k in range(n)])
    np.testing.assert_allclose(got, diff, rtol=1e-6, atol=1e-6)


def _turn_series():
    """A coordinated turn seen by range and bearing over 80 steps, bearings missing every
    third step and step 7 missing whole; its prior, uneven steps with their times, and a
    batch of three such series."""
    motion, meas = CoordinatedTurn(q=0.05, q_turn=1e-3), RangeBearing(1.0, 1e-3, ndim_state=5)
    x0 = np.array([-20.0, 8.0, 0.0, -0.8, 0.01])
    P0 = np.diag([4.0, 4.0, 0.5, 0.5, 1e-3])
    _, zs = vt.simulate.simulate(motion, meas, 80, x0=x0, rng=5)
    zs[::3, 1] = np.nan
    zs[7] = np.nan
    dt = np.r_[1.0, np.random.default_rng(0).uniform(0.2, 2.0, 79)]
    times = np.r_[0.0, np.cumsum(dt[1:])] + 5.0
    return motion, meas, x0, P0, zs, dt, times, np.stack([zs, zs + 0.05, zs * 1.01])


def _python_steps(cls=ExtendedKalmanFilter):
    """``cls`` (a filter) with its steps called from Python: a subclass's own update runs
    the loop of `run_sequence` (or, as an IMM's member, the IMM's steps from Python), the
    path before the compiled one."""
    class Steps(cls):
        def update(self, g, y):
            return super().update(g, y)
    return Steps


def test_ekf_filter_runs_compiled_and_equals_its_steps_from_python(monkeypatch):
    """With models of compiled functions and Jacobians (the coordinated turn, range and
    bearing, the growth model) the EKF's filter runs in one compiled call (Python's loop
    made to fail here) and gives what its steps from Python give, to rounding: bearings
    missing every third step, a step missing whole, steps of different lengths with their
    times (the growth model's forcing depends on the time), a batch of three series with a
    prior each, and one prior for all. Oracle: the steps from Python (`ekf_predict`,
    `ekf_update`; FilterPy's EKF is the oracle of `test_ekf_filter_equals_filterpy_and_the_numpy
    _correction`, which now runs this path)."""
    import vistrack.filters._nonlinear as nl
    import vistrack.filters.ekf as ekf_module

    motion, meas, x0, P0, zs, dt, times, batch = _turn_series()
    priors = (dict(x0=x0, P0=P0),
              dict(x0=np.stack([x0, x0 + 0.5, x0 - 0.5]), P0=np.stack([P0, 2 * P0, P0])))
    gm, gh = growth_model(q=10.0, r=1.0)
    _, gys = vt.simulate.simulate(gm, gh, 60, x0=[0.1], rng=2)
    gys[4] = np.nan
    cases = [(motion, meas, zs, dict(x0=x0, P0=P0), {}),
             (motion, meas, zs, dict(x0=x0, P0=P0), dict(dt=dt, times=times)),
             (gm, gh, gys, dict(x0=[0.1], P0=[[5.0]]), dict(times=np.arange(60.0)))]
    cases += [(motion, meas, batch, prior, dict(dt=dt)) for prior in priors]
    results = []
    with monkeypatch.context() as m:
        def no_loop(*args, **kwargs):
            raise AssertionError("the filter's loop in Python")

        m.setattr(ekf_module, "run_sequence", no_loop)
        for mo, me, ys, prior, when in cases:
            results.append(ExtendedKalmanFilter(mo, me).filter(ys, **prior, **when))
    assert nl.run_sequence is not None
    for (mo, me, ys, prior, when), got in zip(cases, results):
        want = _python_steps()(mo, me).filter(ys, **prior, **when)
        assert got.means.shape == want.means.shape
        for name in ("means", "covs", "pred_means", "pred_covs"):
            a, b = getattr(got, name), getattr(want, name)
            np.testing.assert_allclose(a, b, rtol=1e-11, atol=1e-11 * np.abs(b).max())
            assert not a.flags.writeable
        np.testing.assert_allclose(got.loglik, want.loglik, rtol=1e-11)
        np.testing.assert_allclose(got.last.mean, want.last.mean, rtol=1e-11, atol=1e-11)


def test_ekf_filter_names_what_its_compiled_path_cannot_take_as_its_steps_from_python():
    """What the compiled call cannot take (a state at the sensor, where range-bearing's
    Jacobian divides by 0; a motion model's noise that makes a prediction infinite) is
    filtered again from Python, which gives the same error as the steps from Python."""
    motion, meas = CoordinatedTurn(q=0.05), RangeBearing(1.0, 1e-3, ndim_state=5)
    zs = np.array([[1.0, 0.2], [1.1, 0.25], [1.2, 0.3]])
    cases = [dict(x0=[0.0, 0.0, 0.0, 0.0, 0.0], P0=np.eye(5)),  # at the sensor
             dict(x0=[1.0, 1.0, 1e200, 1e200, 0.0], P0=np.eye(5) * 1e300)]
    for prior in cases:
        with pytest.raises(Exception) as want:
            _python_steps()(motion, meas).filter(zs, **prior)
        with pytest.raises(type(want.value)) as got:
            ExtendedKalmanFilter(motion, meas).filter(zs, **prior)
        assert str(got.value) == str(want.value)


def test_ukf_filter_runs_compiled_and_equals_its_steps_from_python(monkeypatch):
    """With models of compiled functions (`jit_f`, `jit_h`) the UKF's filter runs in one
    compiled call (Python's loop made to fail here) and gives what its steps from Python
    give: bearings missing every third step, a step missing whole, steps of different
    lengths with their times, a batch with a prior each, the growth model, and sigma points
    of three settings. With the default points (α = 1e-3, weights near -1e6 and 1e5) the
    two round apart by up to 1e-8 of the scale, as FilterPy's do from them (the oracle of
    `test_ukf_equals_filterpy_on_range_bearing_with_bearings_crossing_pi`, which now runs
    this path); with α = 0.3 or Julier's points to 1e-11. A batch's series are compared
    with the steps from Python on each alone, within three times the distance between those
    and the steps from Python for the batch (numpy's sums, not the one-Gaussian kernels):
    its second series, of a wider prior, rounds apart by up to 7e-7 of its scale there with
    the default points, 4e-12 with α = 0.3. A prior whose covariance has no Cholesky factor
    (ω known exactly) is filtered from Python, as before."""
    import vistrack.filters.ukf as ukf_module

    motion, meas, x0, P0, zs, dt, times, batch = _turn_series()
    gm, gh = growth_model(q=10.0, r=1.0)
    _, gys = vt.simulate.simulate(gm, gh, 60, x0=[0.1], rng=2)
    gys[4] = np.nan
    cases = []
    for pts, tol in ((MerweScaledSigmaPoints(), 1e-8), (MerweScaledSigmaPoints(0.3), 1e-11),
                     (JulierSigmaPoints(kappa=1.0), 1e-11)):
        cases += [(motion, meas, pts, tol, zs, dict(x0=x0, P0=P0), {}),
                  (motion, meas, pts, tol, zs, dict(x0=x0, P0=P0), dict(dt=dt, times=times)),
                  (gm, gh, pts, tol, gys, dict(x0=[0.1], P0=[[5.0]]),
                   dict(times=np.arange(60.0)))]

    results = []
    with monkeypatch.context() as m:
        def no_loop(*args, **kwargs):
            raise AssertionError("the filter's loop in Python")

        m.setattr(ukf_module, "run_sequence", no_loop)
        for mo, me, pts, _, ys, prior, when in cases:
            results.append(UnscentedKalmanFilter(mo, me, points=pts).filter(ys, **prior, **when))
    for (mo, me, pts, tol, ys, prior, when), got in zip(cases, results):
        want = _python_steps(UnscentedKalmanFilter)(mo, me, points=pts).filter(
            ys, **prior, **when)
        for name in ("means", "covs", "pred_means", "pred_covs"):
            a, b = getattr(got, name), getattr(want, name)
            np.testing.assert_allclose(a, b, rtol=tol, atol=tol * np.abs(b).max())
            assert not a.flags.writeable
        np.testing.assert_allclose(got.loglik, want.loglik, rtol=tol)
    X0, PP = np.stack([x0, x0 + 0.5, x0 - 0.5]), np.stack([P0, 2 * P0, P0])
    for pts, tol in ((MerweScaledSigmaPoints(), 1e-8), (MerweScaledSigmaPoints(0.3), 1e-11),
                     (JulierSigmaPoints(kappa=1.0), 1e-11)):
        with monkeypatch.context() as m:
            m.setattr(ukf_module, "run_sequence", no_loop)
            got = UnscentedKalmanFilter(motion, meas, points=pts).filter(batch, x0=X0, P0=PP,
                                                                         dt=dt)
        steps = _python_steps(UnscentedKalmanFilter)(motion, meas, points=pts)
        numpy_sums = steps.filter(batch, x0=X0, P0=PP, dt=dt)
        for b in range(3):
            want = steps.filter(batch[b], x0=X0[b], P0=PP[b], dt=dt)
            for name in ("means", "covs", "pred_means", "pred_covs"):
                a, w, other = getattr(got, name)[b], getattr(want, name), getattr(
                    numpy_sums, name)[b]
                spread = max(3 * np.abs(other - w).max(), tol * np.abs(w).max())
                assert np.abs(a - w).max() <= spread, (name, b, np.abs(a - w).max(), spread)
    # ω known exactly: no Cholesky factor; the steps from Python take its points from the
    # eigendecomposition, as before
    singular = np.diag([4.0, 4.0, 0.5, 0.5, 0.0])
    got = UnscentedKalmanFilter(motion, meas).filter(zs, x0=x0, P0=singular)
    want = _python_steps(UnscentedKalmanFilter)(motion, meas).filter(zs, x0=x0, P0=singular)
    assert np.array_equal(got.means, want.means) and np.array_equal(got.covs, want.covs)
    # a subclass's own step, a state mean of its own: the steps from Python
    calls = []

    class Counted(UnscentedKalmanFilter):
        def predict(self, g, dt=1.0, t=0.0):
            calls.append(1)
            return super().predict(g, dt, t)

    Counted(motion, meas).filter(zs[:5], x0=x0, P0=P0)
    UnscentedKalmanFilter(motion, meas, state_mean=lambda p, w: np.einsum("...kn,k->...n", p, w)
                          ).filter(zs[:5], x0=x0, P0=P0)
    assert len(calls) == 4


_USER_MODELS = '''
import numpy as np
from numba import njit


@njit(cache=False)
def drift_f(x, dt, t, params, out):
    out[0] = x[0] + SPEED * params[0] * dt


@njit(cache=False)
def drift_jacobian(x, dt, t, params, out):
    out[0, 0] = 1.0


@njit(cache=False)
def seen_h(x, params, out):
    out[0] = x[0]


@njit(cache=False)
def seen_jacobian(x, params, out):
    out[0, 0] = 1.0


class Drift:
    """x' = x + SPEED drift dt, its drift a row of jit_params a step."""
    ndim_state = 1
    jit_f = staticmethod(drift_f)
    jit_jacobian = staticmethod(drift_jacobian)

    def __init__(self, rows=0):
        self.rows = rows  # rows of jit_params more than the steps

    def jit_params(self, dt, t):
        return np.full((len(t) + self.rows, 1), 2.0)

    def f(self, x, dt=1.0, t=0.0):
        return np.asarray(x) + SPEED * 2.0 * dt

    def jacobian(self, x, dt=1.0, t=0.0):
        return np.ones(np.shape(x) + (1,))

    def Q(self, dt=1.0):
        return np.array([[0.1 * dt]])


class Seen:
    ndim_state = 1
    jit_h = staticmethod(seen_h)
    jit_jacobian = staticmethod(seen_jacobian)

    def jit_params(self):
        return np.zeros(0)

    def h(self, x):
        return np.asarray(x)[..., :1]

    def jacobian(self, x):
        return np.ones(np.shape(x)[:-1] + (1, 1))

    def R(self):
        return np.array([[0.5]])
'''


@pytest.mark.parametrize("cls", [ExtendedKalmanFilter, UnscentedKalmanFilter])
def test_the_compiled_filters_run_only_the_functions_the_models_are(cls, tmp_path,
                                                                     monkeypatch):
    """The compiled path (EKF, UKF) is taken only where the compiled functions are the
    models': a subclass of a shipped model that overrides `f` or `h` (which inherits
    `jit_f` / `jit_h`, and gave the base model's estimates), an `f` set on the instance, a
    measurement model of another state's size (its compiled functions read past the state:
    estimates without a word, or garbage), a `Q` that refuses a step (named without its
    step), a `Q` of one step never taken, `jit_params` of another number of rows (numpy's
    reshape error), and a user's module changed and reloaded (the old kernel's estimates)
    all filter as the steps from Python do. Oracle: the steps from Python (a subclass's own
    update), which were the filter before the compiled path."""
    import importlib
    import sys

    motion, meas, x0, P0, zs, _, _, _ = _turn_series()
    zs = zs[:12]
    steps = _python_steps(cls)

    def same(mo, me, ys, **kw):
        try:
            want = steps(mo, me).filter(ys, **kw)
        except ValueError as e:
            with pytest.raises(ValueError) as got:
                cls(mo, me).filter(ys, **kw)
            assert str(got.value) == str(e)
            return
        got = cls(mo, me).filter(ys, **kw)
        np.testing.assert_allclose(got.means, want.means, rtol=1e-7, atol=1e-9)
        np.testing.assert_allclose(got.pred_means, want.pred_means, rtol=1e-7, atol=1e-9)

    class Damped(CoordinatedTurn):
        def f(self, x, dt=1.0, t=0.0):
            out = super().f(x, dt, t)
            out[..., 2:4] *= 0.9
            return out

        def jacobian(self, x, dt=1.0, t=0.0):
            J = super().jacobian(x, dt, t)
            J[..., 2:4, :] *= 0.9
            return J

    class Biased(RangeBearing):
        def h(self, x):
            z = super().h(x)
            z[..., 0] += 5.0
            return z

    class Fussy(CoordinatedTurn):
        def Q(self, dt=1.0):
            if dt > 1.5:
                raise ValueError(f"a step of {dt} is too long for this model")
            return super().Q(dt)

    prior = dict(x0=x0, P0=P0)
    same(Damped(q=0.05, q_turn=1e-3), meas, zs, **prior)
    same(motion, Biased(1.0, 1e-3, ndim_state=5), zs, **prior)
    patched = CoordinatedTurn(q=0.05, q_turn=1e-3)
    patched.f = lambda x, dt=1.0, t=0.0: CoordinatedTurn.f(patched, x, dt, t) + 1.0
    same(patched, meas, zs, **prior)
    for n in (4, 6):
        same(motion, RangeBearing(1.0, 1e-3, ndim_state=n), zs, **prior)
    same(vt.models.GrowthMotion(), RangeBearing(ndim_state=2), zs[:, :1].repeat(2, 1),
         x0=[0.5], P0=[[1.0]])
    same(Fussy(q=0.05), meas, zs, dt=np.r_[1.0, 1.0, 1.0, 2.0, np.ones(8)], **prior)
    same(Fussy(q=0.05), meas, zs[:1], dt=5.0, **prior)  # one step: nothing predicted
    # a user's models, in a module of their own
    monkeypatch.syspath_prepend(str(tmp_path))
    name = f"user_models_{cls.__name__.lower()}"
    (tmp_path / f"{name}.py").write_text("SPEED = 1.0\n" + _USER_MODELS)
    user = importlib.import_module(name)
    ys = np.array([[0.5], [2.6], [4.4], [6.4]])
    kw = dict(x0=[0.0], P0=[[1.0]])
    same(user.Drift(), user.Seen(), ys, **kw)
    same(user.Drift(rows=1), user.Seen(), ys, **kw)
    (tmp_path / f"{name}.py").write_text("SPEED = 10.0\n" + _USER_MODELS)
    importlib.invalidate_caches()
    user = importlib.reload(user)
    same(user.Drift(), user.Seen(), ys, **kw)
    assert cls(user.Drift(), user.Seen()).filter(ys, **kw).pred_means[1, 0] > 10
    sys.modules.pop(name, None)


def test_the_compiled_particle_filter_runs_only_the_functions_the_models_are():
    """The particle filter's compiled path, likewise: not for a subclass's own `f` or `h`
    (it moved the particles by the base model's), nor for a measurement model of another
    state's size (range and bearing of a state of one value read past it); those run on
    numpy, which takes the subclass's functions and names the sizes."""
    motion, meas = CoordinatedTurn(q=0.05), RangeBearing(1.0, 1e-3, ndim_state=5)

    class Damped(CoordinatedTurn):
        def f(self, x, dt=1.0, t=0.0):
            return super().f(x, dt, t) * 0.9

    class Biased(RangeBearing):
        def h(self, x):
            return super().h(x) + 5.0

    assert ParticleFilter(motion, meas, 50, rng=0)._fused is not None
    assert ParticleFilter(Damped(q=0.05), meas, 50, rng=0)._fused is None
    assert ParticleFilter(motion, Biased(1.0, 1e-3, ndim_state=5), 50, rng=0)._fused is None
    small = ParticleFilter(vt.models.GrowthMotion(), RangeBearing(ndim_state=2), 50, rng=0)
    assert small._fused is None
    with pytest.raises(ValueError, match="RangeBearing states of 2 entries"):
        small.filter(np.ones((3, 2)), x0=[0.5], P0=[[1.0]])


@pytest.mark.parametrize("which", ["ekf", "ukf", "enkf", "imm"])
def test_a_list_of_masked_series_keeps_each_mask(which):
    """A batch given as a list of masked series: the values under the masks are missing, as
    for one masked series and for kalman_filter (np.asarray of the list dropped the masks,
    and 1e6 hidden at a step was filtered as a measurement: means of 7e5). Oracle: the same
    batch with NaN where the masks are."""
    from vistrack.filters import (
        EnsembleKalmanFilter,
        ExtendedKalmanFilter,
        IMMFilter,
        KalmanFilter,
        UnscentedKalmanFilter,
    )

    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=0.5)
    y = np.array([[0.1], [0.9], [2.1], [3.2]])
    hidden = np.array([[0], [0], [1], [0]], bool)
    series = [np.ma.masked_array(np.where(hidden, 1e6, y), mask=hidden),
              np.ma.masked_array(y.copy(), mask=np.zeros_like(hidden))]
    nan = np.stack([np.where(hidden, np.nan, y), y])
    make = {"ekf": lambda: ExtendedKalmanFilter(cv, pos),
            "ukf": lambda: UnscentedKalmanFilter(cv, pos),
            "enkf": lambda: EnsembleKalmanFilter(cv, pos, n_members=50, rng=3),
            "imm": lambda: IMMFilter([KalmanFilter(cv, pos),
                                      KalmanFilter(vt.ConstantVelocity(dim=1, q=5.0), pos)],
                                     [[0.9, 0.1], [0.1, 0.9]])}[which]
    prior = dict(x0=[0.0, 1.0], P0=np.eye(2))
    a, b = make().filter(series, **prior), make().filter(nan, **prior)
    np.testing.assert_array_equal(a.means, b.means)
    np.testing.assert_array_equal(a.loglik, b.loglik)
    assert np.abs(a.means).max() < 10


def test_an_ensemble_refuses_masked_and_complex_values():
    """Ensemble and Ensemble.sample read the values under a mask as members (a mean of 999
    drawn about) and complex values as their real parts with a warning alone; the filters'
    priors refuse both. Named now, as x0 is."""
    from vistrack.filters import Ensemble

    masked = np.ma.masked_array([0.0, 999.0], mask=[0, 1])
    with pytest.raises(ValueError, match=r"^mean must not have masked entries .*; mean\[1\] is "
                                         r"masked$"):
        Ensemble.sample(masked, np.eye(2), 10, rng=0)
    with pytest.raises(ValueError, match=r"^cov must not have masked entries"):
        Ensemble.sample([0.0, 0.0], np.ma.masked_array(np.eye(2), mask=np.eye(2)), 10, rng=0)
    with pytest.raises(ValueError, match=r"^members must not have masked entries .*; "
                                         r"members\[1, 0\] is masked$"):
        Ensemble(np.ma.masked_array([[1.0, 2.0], [3.0, 4.0]], mask=[[0, 0], [1, 0]]))
    with pytest.raises(TypeError, match=r"^members must be real numbers"):
        Ensemble(np.array([[1 + 5j, 2], [3, 4 + 1j]]))
    with pytest.raises(TypeError, match=r"^mean must be real numbers"):
        Ensemble.sample(np.array([1j, 0]), np.eye(2), 10, rng=0)
    with pytest.raises(TypeError, match=r"^members must be an array of numbers"):
        Ensemble("ab")
    # more members than memory holds: numpy's "Maximum allowed dimension exceeded" before
    with pytest.raises(ValueError, match=r"^n_members 10+ makes an ensemble of 2e\+30 "
                                         r"values, more than memory holds$"):
        Ensemble.sample([0.0, 0.0], np.eye(2), 10 ** 30, rng=0)
    # an unmasked masked array is an array
    ens = Ensemble.sample(np.ma.masked_array([1.0, 2.0]), np.eye(2), 4, rng=0)
    np.testing.assert_array_equal(ens.members, Ensemble.sample([1.0, 2.0], np.eye(2), 4,
                                                               rng=0).members)
