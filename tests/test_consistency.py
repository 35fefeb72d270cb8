"""Simulation statistics, NEES/NIS consistency, and long-run numerical stability."""

import re

import numpy as np
import pytest
from scipy import stats

import vistrack as vt
from vistrack.evaluation import chi2_band, nees, nis, rmse
from vistrack.filters import _codegen
from vistrack.simulate import simulate, simulate_lgssm


def test_simulated_state_covariance_matches_closed_form():
    """Var(x_t) of a random walk from a fixed start is t·q·dt; checked over many series."""
    cp = vt.ConstantPosition(dim=1, q=0.5)
    xs, ys = simulate(cp, vt.Position(dim=1, r=2.0), 11, x0=[0.0], dt=2.0, n_series=20000, rng=3)
    var_x = xs[:, 10, 0].var()
    var_y_minus_x = (ys - xs)[:, :, 0].var()
    # sampling sd of a variance estimate is var * sqrt(2 / N): use 5 sd
    assert var_x == pytest.approx(10 * 0.5 * 2.0, rel=5 * np.sqrt(2 / 20000))
    assert var_y_minus_x == pytest.approx(2.0, rel=5 * np.sqrt(2 / (20000 * 11)))


def test_simulate_is_reproducible_and_validates():
    a = simulate_lgssm(5, F=np.eye(2), Q=np.eye(2), H=np.eye(1, 2), R=[[1.0]], x0=[0, 0], rng=7)
    b = simulate_lgssm(5, F=np.eye(2), Q=np.eye(2), H=np.eye(1, 2), R=[[1.0]], x0=[0, 0], rng=7)
    np.testing.assert_array_equal(a[1], b[1])
    with pytest.raises(ValueError, match="T must be a positive integer"):
        simulate_lgssm(0, F=np.eye(2), Q=np.eye(2), H=np.eye(1, 2), R=[[1.0]], x0=[0, 0])
    with pytest.raises(TypeError, match="rng must be"):
        simulate_lgssm(3, F=np.eye(2), Q=np.eye(2), H=np.eye(1, 2), R=[[1.0]], x0=[0, 0], rng="x")


def test_simulate_checks_dt_alike_for_linear_and_nonlinear_models():
    """dt is a scalar, the T-1 intervals or T values (dt[0] unused) for either kind of model:
    the intervals and T values give the same draws, and another length is refused with the
    same message (it used to be accepted, or fail with an IndexError, for nonlinear models)."""
    T, intervals = 6, [0.5, 1.0, 2.0, 0.25, 1.5]
    linear = (vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1), [0.0, 1.0])
    nonlinear = (*vt.models.growth_model(), [0.1])
    for motion, meas, x0 in (linear, nonlinear):
        a = simulate(motion, meas, T, x0=x0, dt=intervals, rng=4)
        b = simulate(motion, meas, T, x0=x0, dt=[9.0] + intervals, rng=4)
        np.testing.assert_array_equal(a[0], b[0])
        np.testing.assert_array_equal(a[1], b[1])
        for bad in (intervals[:3], intervals + [1.0, 1.0]):
            with pytest.raises(ValueError, match=rf"dt must be a scalar, the T-1={T - 1} "
                               rf"intervals between steps or T={T} values .*got shape "
                               rf"\({len(bad)},\)"):
                simulate(motion, meas, T, x0=x0, dt=bad, rng=4)
    # the growth model's f uses the time: with steps of 2 the state at step t is f at 2 (t-1)
    motion, meas = vt.models.growth_model(q=0.0, r=1.0)
    xs, _ = simulate(motion, meas, 3, x0=[0.1], dt=[2.0, 2.0], rng=0)
    x1 = 0.5 * 0.1 + 25 * 0.1 / (1 + 0.1**2) + 8 * np.cos(1.2 * 2.0)
    assert xs[1, 0] == pytest.approx(x1, rel=1e-12)


def test_nees_and_nis_of_a_correct_filter_lie_in_the_chi2_band():
    cv, pos = vt.ConstantVelocity(dim=2, q=0.2), vt.Position(dim=2, r=1.5)
    N, T = 200, 60
    x0, P0 = np.array([0.0, 0.0, 1.0, -1.0]), np.diag([4.0, 4.0, 1.0, 1.0])
    xs, ys = simulate(cv, pos, T, x0=x0, P0=P0, n_series=N, rng=11)
    kf = vt.KalmanFilter(cv, pos)
    res = kf.filter(ys, x0=x0, P0=P0)
    e = nees(xs, res.means, res.covs)  # (N, T)
    lo, hi = chi2_band(4, n_runs=N)
    frac = np.mean((e.mean(0) > lo) & (e.mean(0) < hi))
    # each step is inside its 95 % band with probability 0.95: 60 steps, allow 3 binomial sd
    assert frac >= 0.95 - 3 * np.sqrt(0.95 * 0.05 / T)
    lo_all, hi_all = chi2_band(4, n_runs=N * T)
    assert lo_all < e.mean() < hi_all
    v, dof = nis(ys, res, H=pos.H(4), R=pos.R())
    assert np.all(dof == 2)
    lo2, hi2 = chi2_band(2, n_runs=N * T)
    assert lo2 < v.mean() < hi2
    # a filter that believes in 100x too little process noise is caught by NEES
    bad = vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=0.002), pos).filter(ys, x0=x0, P0=P0)
    assert nees(xs, bad.means, bad.covs).mean() > 2 * hi_all
    # and smoothing beats filtering
    sm = kf.smooth(ys, x0=x0, P0=P0)
    assert rmse(sm.means[..., :2], xs[..., :2]) < rmse(res.means[..., :2], xs[..., :2])


def test_nis_counts_only_observed_components():
    pos = vt.Position(dim=2, r=1.0)
    kf = vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=1.0), pos)
    ys = np.array([[0.0, 0.0], [1.0, np.nan], [np.nan, np.nan]])
    res = kf.filter(ys, x0=np.zeros(4), P0=np.eye(4))
    v, dof = nis(ys, res, H=pos.H(4), R=pos.R())
    np.testing.assert_array_equal(dof, [2, 1, 0])
    S = res.pred_covs[1, 0, 0] + 1.0
    assert v[1] == pytest.approx((1.0 - res.pred_means[1, 0]) ** 2 / S)
    assert v[2] == 0.0


def test_chi2_band_matches_scipy():
    lo, hi = chi2_band(3, n_runs=10, level=0.9)
    assert lo == pytest.approx(stats.chi2.ppf(0.05, 30) / 10)
    assert hi == pytest.approx(stats.chi2.ppf(0.95, 30) / 10)
    with pytest.raises(ValueError):
        chi2_band(0)


def test_the_consistency_scores_name_what_does_not_fit():
    """A (1, 1) ``R`` for measurements of 2 values was added to every entry of ``S`` (NIS
    2.998 where a right filter gives 2), a (1, n) ``H`` broadcast over the rows (NIS 31,952);
    ``nees`` read a covariance that is not symmetric by its lower triangle, and failed inside
    numpy on scalars; ``chi2_band(nan)`` gave a band of NaN; ``rmse`` of nothing was NaN."""
    pos = vt.Position(dim=2, r=1.0)
    kf = vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=1.0), pos)
    ys = np.array([[0.0, 0.0], [1.0, 0.5], [2.0, 1.0]])
    res = kf.filter(ys, x0=np.zeros(4), P0=np.eye(4))
    for kw, message in (({"H": pos.H(4), "R": [[1.0]]}, r"R must be \(2, 2\) or \(3, 2, 2\) "
                         r"for ys of 2 values and states of 4; got \(1, 1\)"),
                        ({"H": pos.H(4)[:1], "R": pos.R()}, r"H must be \(2, 4\)"),
                        ({"H": np.tile(pos.H(4), (2, 1, 1)), "R": pos.R()},
                         r"H must be \(2, 4\) or \(3, 2, 4\).*got \(2, 2, 4\)")):
        with pytest.raises(ValueError, match=message):
            nis(ys, res, **kw)
    with pytest.raises(ValueError, match=r"covs must be symmetric; covs\[0, 1\] = 0.9"):
        nees([1.0, 1.0], [0.0, 0.0], [[1.0, 0.9], [0.0, 1.0]])
    with pytest.raises(ValueError, match="truth and means must have the same shape"):
        nees(1.0, 0.0, 1.0)
    for bad in (np.nan, 2.5):
        with pytest.raises(ValueError, match="dof must be a whole number >= 1"):
            chi2_band(bad)


def test_the_consistency_scores_name_each_argument_and_step():
    """chi2_band named its three values together (``level=95``: "need whole numbers dof >= 1
    and n_runs >= 1, and 0 < level < 1; got 2, 1, 95"), and a string level met a bare
    comparison; nees and nis gave numpy's "Matrix is not positive definite" alone for one
    singular step among a hundred; nis read S's lower triangle alone, so an R that is not
    symmetric gave a NIS that depended on the triangle holding the slip (2.5 and 2.0 at the
    first step for R and its transpose, the filter's own refusing both), and a series' length
    was named by the batch's shapes."""
    for kw, message in (({"level": 95}, "level must be a probability in (0, 1); got 95"),
                        ({"level": "0.95"}, "level must be a probability in (0, 1); got '0.95'"),
                        ({"n_runs": 0}, "n_runs must be a whole number >= 1; got 0")):
        with pytest.raises(ValueError, match=re.escape(message)):
            chi2_band(2, **kw)
    P = np.tile(np.eye(2), (100, 1, 1))
    P[57] = np.diag([1.0, 0.0])
    with pytest.raises(np.linalg.LinAlgError, match=re.escape("covs[57] is not positive "
                                                              "definite")):
        nees(np.zeros((100, 2)), np.ones((100, 2)), P)
    P[57] = np.eye(2)  # the oracle: e' P^-1 e with P = I
    np.testing.assert_array_equal(nees(np.zeros((100, 2)), np.ones((100, 2)), P), 2.0)
    ys = np.array([[1.0, 2.0], [1.5, 2.5], [2.0, 2.0]])
    res = vt.kalman_filter(ys, F=np.eye(2), Q=np.zeros((2, 2)), H=np.eye(2), R=np.eye(2),
                           x0=[0.0, 0.0], P0=np.diag([1.0, 0.0]))
    with pytest.raises(np.linalg.LinAlgError, match=re.escape("S = H P H' + R at step 0 is "
                                                              "not positive definite")):
        nis(ys, res, H=np.eye(2), R=np.zeros((2, 2)))
    with pytest.raises(ValueError, match=re.escape("R must be symmetric; R[0, 1] = 0.9 but its "
                                                   "transpose entry is 0.0")):
        nis(ys, res, H=np.eye(2), R=[[1.0, 0.9], [0.0, 1.0]])
    with pytest.raises(ValueError, match=re.escape("R must be positive semi-definite; R[1, 1] = "
                                                   "-5, a negative variance")):
        nis(ys, res, H=np.eye(2), R=np.diag([1.0, -5.0]))
    with pytest.raises(ValueError, match=re.escape("ys has 2 steps (shape (2, 2)) but the "
                                                   "result covers 3")):
        nis(ys[:2], res, H=np.eye(2), R=np.eye(2))
    # the oracle for a good R: nu' S^-1 nu from the predictions
    v, _ = nis(ys, res, H=np.eye(2), R=np.eye(2))
    nu = ys - res.pred_means
    S = res.pred_covs + np.eye(2)
    np.testing.assert_allclose(v, np.einsum("ti,tij,tj->t", nu, np.linalg.inv(S), nu),
                               rtol=1e-12)
    with pytest.raises(ValueError, match="estimates and truth are empty"):
        rmse([], [])


@pytest.mark.slow
@pytest.mark.parametrize("kernel", ["one series", "batch", "loop batch"])
def test_covariances_stay_symmetric_positive_definite_over_a_million_steps(kernel, monkeypatch):
    """A badly scaled model: states in metres and km/s-scale velocities, tiny process noise.

    "one series" runs the scalar kernel; "batch" two series with their own priors, which run
    the kernel generated for this model; "loop batch" the same through the loop kernel."""
    if kernel == "loop batch":
        monkeypatch.setattr(_codegen, "MIN_STEPS", 1 << 62)
    T = 1_000_000
    dt = 1e-3
    ca = vt.ConstantAcceleration(dim=1, q=1e-9)
    F, Q = ca.F(dt), ca.Q(dt)  # Q spans ~1e-24 .. 1e-12
    H = np.array([[1.0, 0.0, 0.0]])
    R = np.array([[1e4]])
    _, ys = simulate_lgssm(2000, F=F, Q=Q, H=H, R=R, x0=[0.0, 1e3, 1.0], rng=5)
    ys = np.resize(ys, (T, 1))
    ys[::7] = np.nan
    P0 = np.diag([1e6, 1e2, 1e-2])
    if kernel != "one series":
        ys = np.stack([ys, ys[::-1]])
        P0 = np.stack([P0, 2 * P0])
    res = vt.kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=[0.0, 1e3, 1.0], P0=P0)
    assert not res.shared_covs
    P = res.covs.reshape(-1, 3, 3)
    assert np.array_equal(P, np.swapaxes(P, -1, -2))
    # positive definite: a Cholesky factorisation of every covariance succeeds
    for chunk in range(0, len(P), 100_000):
        np.linalg.cholesky(P[chunk:chunk + 100_000])
    assert np.all(np.isfinite(res.means))
