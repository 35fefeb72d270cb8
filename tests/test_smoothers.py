"""RTS and the seeds' two-filter smoother: equal to each other and to the batch posterior."""

import numpy as np
import pytest

import vistrack as vt
from vistrack.filters import kalman_filter, rts_smooth, two_filter_smooth

from .conftest import exact_posterior, random_model


@pytest.mark.parametrize("tv", [False, True])
def test_rts_equals_two_filter(rng, tv):
    n, m, T, B = 4, 2, 50, 3
    mod = random_model(rng, n, m, T, tv=tv)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), n_series=B, rng=rng)
    ys[rng.random((B, T)) < 0.1] = np.nan
    ys[rng.random((B, T, m)) < 0.1] = np.nan
    x0, P0 = rng.normal(size=(B, n)), 2.0 * np.eye(n)
    rts = rts_smooth(kalman_filter(ys, **mod, x0=x0, P0=P0), F=mod["F"], Q=mod["Q"])
    two = two_filter_smooth(ys, **mod, x0=x0, P0=P0)
    np.testing.assert_allclose(two.means, rts.means, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(two.covs, rts.covs, rtol=1e-8, atol=1e-10)


def test_smoother_equals_batch_posterior(rng):
    """The smoothed marginals equal the exact Gaussian conditional of all states given all data."""
    n, m, T = 2, 1, 8
    mod = random_model(rng, n, m)
    F, Q, H, R = mod["F"], mod["Q"], mod["H"], mod["R"]
    x0, P0 = rng.normal(size=n), np.eye(n)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=x0, rng=rng)
    # prior of all states: block-bidiagonal precision J, from x0 ~ N(x0, P0),
    # x_t - F x_{t-1} ~ N(0, Q)
    A = np.zeros((T * n, T * n))
    A[:n, :n] = np.eye(n)
    for t in range(1, T):
        A[t * n:(t + 1) * n, t * n:(t + 1) * n] = np.eye(n)
        A[t * n:(t + 1) * n, (t - 1) * n:t * n] = -F
    W = np.kron(np.eye(T), np.linalg.inv(Q))
    W[:n, :n] = np.linalg.inv(P0)
    J = A.T @ W @ A
    h = A.T @ W @ np.r_[x0, np.zeros((T - 1) * n)]
    Hb = np.kron(np.eye(T), H)
    Rinv = np.kron(np.eye(T), np.linalg.inv(R))
    C = np.linalg.inv(J + Hb.T @ Rinv @ Hb)
    mu = C @ (h + Hb.T @ Rinv @ ys.ravel())
    sm = rts_smooth(kalman_filter(ys, **mod, x0=x0, P0=P0), F=F, Q=Q)
    np.testing.assert_allclose(sm.means.ravel(), mu, rtol=1e-9, atol=1e-10)
    for t in range(T):
        np.testing.assert_allclose(sm.covs[t], C[t * n:(t + 1) * n, t * n:(t + 1) * n], rtol=1e-9)


def test_smoothed_variance_is_never_larger_than_filtered(rng):
    cv = vt.ConstantVelocity(dim=1, q=0.1)
    kf = vt.KalmanFilter(cv, vt.Position(dim=1, r=1.0))
    _, ys = vt.simulate.simulate(cv, vt.Position(dim=1), 40, x0=[0, 1], rng=rng)
    sm = kf.smooth(ys)
    fP, sP = sm.filtered.covs, sm.covs
    assert np.all(np.linalg.eigvalsh(fP - sP) > -1e-10)
    np.testing.assert_allclose(fP[-1], sP[-1])


def test_rts_needs_covariances(rng):
    mod = random_model(rng, 2, 1)
    res = kalman_filter(rng.normal(size=(5, 1)), **mod, x0=np.zeros(2), P0=np.eye(2),
                        store_covs=False)
    with pytest.raises(ValueError, match="store_covs=True"):
        rts_smooth(res, F=mod["F"], Q=mod["Q"])
    with pytest.raises(TypeError, match="result must be a FilterResult"):
        rts_smooth(np.zeros(3), F=mod["F"], Q=mod["Q"])


@pytest.mark.parametrize("tv", [False, True])
def test_rts_equals_filterpy_rts_smoother(rng, tv):
    filterpy_kalman = pytest.importorskip("filterpy.kalman")
    n, m, T = 4, 2, 40
    mod = random_model(rng, n, m, T, tv=tv)
    _, ys = vt.simulate.simulate_lgssm(T, **mod, x0=np.zeros(n), rng=rng)
    ys[[7, 8, 20]] = np.nan
    res = kalman_filter(ys, **mod, x0=np.zeros(n), P0=np.eye(n))
    # FilterPy's rts_smoother(Xs, Ps, Fs, Qs) uses Fs[k+1], Qs[k+1] between steps k and k+1,
    # as we do
    Fs = mod["F"] if tv else [mod["F"]] * T
    Qs = mod["Q"] if tv else [mod["Q"]] * T
    kf = filterpy_kalman.KalmanFilter(dim_x=n, dim_z=m)
    xs, Ps, _, _ = kf.rts_smoother(np.array(res.means), np.array(res.covs), Fs=Fs, Qs=Qs)
    sm = rts_smooth(res, F=mod["F"], Q=mod["Q"])
    np.testing.assert_allclose(sm.means, xs, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(sm.covs, Ps, rtol=1e-8, atol=1e-10)


def test_two_filter_smooth_names_an_exact_measurement():
    """R singular on the observed components (the second component measured exactly): the
    information filter cannot add H' R^-1 H, and says so with the step and the way out,
    rts_smooth, which smooths it (its result at the last step is the filter's). Before:
    numpy's LinAlgError, "Singular matrix"."""
    rng = np.random.default_rng(90)
    F, Q = 0.5 * rng.normal(size=(3, 3)), 0.1 * np.eye(3)
    H, R = rng.normal(size=(2, 3)), np.array([[1.0, 0.0], [0.0, 0.0]])
    ys = rng.normal(size=(10, 2))
    model = dict(F=F, Q=Q, H=H, R=R, x0=np.zeros(3), P0=np.eye(3))
    with pytest.raises(ValueError, match=r"^R at step 9 is singular on the observed "
                       r"components: .*rts_smooth"):
        two_filter_smooth(ys, **model)
    fwd = kalman_filter(ys, **model)
    sm = rts_smooth(fwd, F=F, Q=Q)
    np.testing.assert_allclose(sm.means[-1], fwd.means[-1])
    # the exact component is the measurement at every step
    np.testing.assert_allclose((sm.means @ H.T)[:, 1], ys[:, 1], atol=1e-8)


def test_two_filter_smooth_names_an_r_singular_to_rounding():
    """R = v v' is singular, but numpy's solve inverts its rounded form without a word: the
    backward information was then wrong and the smoothed means 0.48 off the RTS smoother's
    (the oracle: rts_smooth equals the batch posterior above). Its numerical rank is taken
    as numpy's matrix_rank takes it, so a small but regular R is smoothed as before."""
    rng = np.random.default_rng(3)
    v = np.array([[0.3], [0.7]])
    F, Q, H = np.eye(3) + 0.1 * rng.normal(size=(3, 3)), 0.1 * np.eye(3), rng.normal(size=(2, 3))
    ys = rng.normal(size=(5, 2))
    assert np.linalg.matrix_rank(v @ v.T) == 1
    model = dict(F=F, Q=Q, H=H, x0=np.zeros(3), P0=np.eye(3))
    with pytest.raises(ValueError, match=r"^R at step 4 is singular on the observed"):
        two_filter_smooth(ys, **model, R=v @ v.T)
    # regular, if small: as the RTS smoother
    R = np.diag([1.0, 1e-8])
    two = two_filter_smooth(ys, **model, R=R)
    rts = rts_smooth(kalman_filter(ys, **model, R=R), F=F, Q=Q)
    np.testing.assert_allclose(two.means, rts.means, atol=1e-7)
    # the same problem measured in units 1e10 times smaller, a component missing at a step:
    # the rank is judged on the observed block's own scale
    ys[2, 1] = np.nan
    small = dict(model, H=1e-10 * H)
    R = np.diag([1.0, 0.5]) * 1e-20
    two = two_filter_smooth(1e-10 * ys, **small, R=R)
    rts = rts_smooth(kalman_filter(1e-10 * ys, **small, R=R), F=F, Q=Q)
    np.testing.assert_allclose(two.means, rts.means, atol=1e-9)
    # components in units far apart (variances 1e8 and 1e-8, a ratio past 1 / eps) are
    # regular: the rank is judged on the correlation matrix (it was refused as singular to
    # rounding); as the RTS smoother, as closely as the small R above
    ys[2, 1] = 0.2
    R = np.diag([1e8, 1e-8])
    two = two_filter_smooth(ys, **model, R=R)
    rts = rts_smooth(kalman_filter(ys, **model, R=R), F=F, Q=Q)
    np.testing.assert_allclose(two.means, rts.means, atol=1e-7)


@pytest.mark.parametrize("case", ["short", "state", "nan_cov", "nan_mean"])
def test_rts_checks_a_results_covs_against_its_means(rng, case):
    """A FilterResult made by hand, its covs not matching its means: the compiled smoother
    indexed covs by the means' shape, read and wrote past the arrays and crashed the
    interpreter (heap corruption) or returned garbage; NaN came back as NaN. Each is now
    named."""
    from dataclasses import replace

    mod = random_model(rng, 2, 1)
    res = kalman_filter(rng.normal(size=(4, 1)), **mod, x0=np.zeros(2), P0=np.eye(2))
    covs, means = np.array(res.covs), np.array(res.means)
    if case == "short":
        bad, msg = replace(res, covs=covs[:2]), r"result.covs must have shape \(4, 2, 2\)"
    elif case == "state":
        bad, msg = replace(res, covs=covs[:, :1, :1]), r"got \(4, 1, 1\)"
    elif case == "nan_cov":
        covs[1, 0, 0] = np.nan
        bad, msg = replace(res, covs=covs), r"result.covs must be finite; result.covs\[1, 0, 0\]"
    else:
        means[2, 1] = np.inf
        bad, msg = replace(res, means=means), r"result.means must be finite; result.means\[2, 1\]"
    with pytest.raises(ValueError, match=msg):
        rts_smooth(bad, F=mod["F"], Q=mod["Q"])


def test_masked_measurements_are_smoothed_as_missing_as_by_pykalman(rng):
    """A numpy masked array (pykalman's missing steps) is smoothed with its masked entries
    missing, one series or a list of them (a batch). Before, the values under the mask were
    measured: the review's positions [-85.8, -195.7, -310.2, -381.7] for pykalman's
    [0.065, 1.052, 2.057, 3.067]."""
    pykalman = pytest.importorskip("pykalman")
    F, Q = np.array([[1.0, 1.0], [0.0, 1.0]]), 0.01 * np.eye(2)
    H, R = np.array([[1.0, 0.0]]), np.array([[0.25]])
    model = dict(F=F, Q=Q, H=H, R=R, x0=np.zeros(2), P0=np.eye(2))
    ym = np.ma.masked_array([[0.1], [0.9], [-999.0], [3.2]], mask=[[0], [0], [1], [0]])
    pk = pykalman.KalmanFilter(transition_matrices=F, observation_matrices=H,
                               transition_covariance=Q, observation_covariance=R,
                               initial_state_mean=np.zeros(2), initial_state_covariance=np.eye(2))
    sm, sP = pk.smooth(ym)
    np.testing.assert_allclose(sm[:, 0], [0.065, 1.052, 2.057, 3.067], atol=5e-4)
    two = two_filter_smooth(ym, **model)
    np.testing.assert_allclose(two.means, sm, rtol=1e-8, atol=1e-10)
    np.testing.assert_allclose(two.covs, sP, rtol=1e-8, atol=1e-10)
    # a batch given as a list of masked series: each its own mask
    mod = random_model(rng, 3, 2)
    _, ys = vt.simulate.simulate_lgssm(30, **mod, x0=np.zeros(3), n_series=2, rng=rng)
    series = []
    for b in range(2):
        mask = np.zeros(ys[b].shape, bool)
        mask[rng.choice(30, 6, replace=False)] = True
        series.append(np.ma.masked_array(np.where(mask, 1e6, ys[b]), mask=mask))
    batch = two_filter_smooth(series, **mod, x0=np.zeros(3), P0=np.eye(3))
    for b, y in enumerate(series):
        pk = pykalman.KalmanFilter(transition_matrices=mod["F"], observation_matrices=mod["H"],
                                   transition_covariance=mod["Q"],
                                   observation_covariance=mod["R"],
                                   initial_state_mean=np.zeros(3),
                                   initial_state_covariance=np.eye(3))
        sm, sP = pk.smooth(y)
        np.testing.assert_allclose(batch.means[b], sm, rtol=1e-8, atol=1e-10)
        np.testing.assert_allclose(batch.covs[b], sP, rtol=1e-8, atol=1e-10)


def test_two_filter_smooth_names_a_step_whose_information_form_rounding_makes_singular():
    """Variances 1e10 beside 1e-10 (a valid model: rts_smooth smooths it) made I + P Λ
    singular to rounding, and numpy's bare LinAlgError ("Singular matrix") came out, naming
    nothing. The step is named, and rts_smooth pointed to."""
    from vistrack.filters import kalman_filter, rts_smooth, two_filter_smooth

    F, H = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    Q, R, P0 = np.diag([1e-10, 1e10]), np.array([[1e-10]]), np.diag([1e10, 1e-10])
    ys = np.random.default_rng(0).normal(size=(10, 1)) * 10
    ys[4] = np.nan
    kw = dict(F=F, Q=Q, H=H, R=R, x0=[1.0, -1.0], P0=P0)
    assert np.isfinite(rts_smooth(kalman_filter(ys, **kw), F=F, Q=Q).means).all()
    with pytest.raises(ValueError, match=r"^step 4: I \+ P Λ is singular to working precision "
                                         r".*; rts_smooth smooths such a model$"):
        two_filter_smooth(ys, **kw)


def test_rts_covariances_keep_small_variances_beside_large_ones():
    """Variances 1e10 beside 1e-10 (the model two_filter_smooth refuses, naming rts_smooth):
    the smoothed covariance as P + G (P_s - P⁻) G' subtracted numbers of 1e10 to get one of
    1e-10, and gave velocity variances of exactly 0, one 1e4 times too large, and negative
    eigenvalues at half the steps. Oracle: the exact posterior of all states, in fractions."""
    from vistrack.filters.reference import smooth_step

    F, H = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    Q, R, P0 = np.diag([1e-10, 1e10]), np.array([[1e-10]]), np.diag([1e10, 1e-10])
    ys = np.random.default_rng(0).normal(size=(10, 1)) * 10
    ys[4] = np.nan
    filtered = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=[1.0, -1.0], P0=P0)
    sm = rts_smooth(filtered, F=F, Q=Q)
    _, C = exact_posterior(ys, F=F, Q=Q, H=H, R=R, x0=[1.0, -1.0], P0=P0)
    exact = np.array([C[2 * t:2 * t + 2, 2 * t:2 * t + 2] for t in range(len(ys))])
    d, d_exact = np.diagonal(sm.covs, axis1=1, axis2=2), np.diagonal(exact, axis1=1, axis2=2)
    np.testing.assert_allclose(d, d_exact, rtol=1e-6)
    assert np.linalg.eigvalsh(sm.covs).min() >= 0.0
    # the reference step, the specification the kernel follows, likewise
    Ps, ref = sm.covs[-1], [sm.covs[-1]]
    for t in range(len(ys) - 2, -1, -1):
        Ps = smooth_step(filtered.means[t], filtered.covs[t], sm.means[t + 1], Ps, F, Q)[1]
        ref.append(Ps)
    d_ref = np.diagonal(np.array(ref[::-1]), axis1=1, axis2=2)
    np.testing.assert_allclose(d_ref, d_exact, rtol=1e-6)
