"""Learning linear-Gaussian models (vistrack.filters.learn): EM equals pykalman's step by step,
a never decreasing likelihood, frozen parameters untouched, pooled batches, the
missing-step equivalence and known parameters recovered."""

import io
import re
import warnings

import numpy as np
import pytest

import vistrack as vt
from vistrack.filters import em, mle
from vistrack.filters import learn as learn_module
from vistrack.simulate import simulate_lgssm

CV, POS = vt.ConstantVelocity(dim=2, q=0.5), vt.Position(dim=2, r=4.0)


def cv_model(dt=1.0):
    return dict(F=CV.F(dt), Q=CV.Q(dt), H=POS.H(4), R=POS.R(), x0=np.zeros(4),
                P0=10.0 * np.eye(4))


def series(T, seed, **model):
    return simulate_lgssm(T, **(model or cv_model()), rng=seed)[1]


PK_NAMES = {"F": "transition_matrices", "Q": "transition_covariance",
            "H": "observation_matrices", "R": "observation_covariance",
            "x0": "initial_state_mean", "P0": "initial_state_covariance"}


@pytest.mark.parametrize("learn", [("Q", "R"), ("F", "H"), ("F", "Q", "H", "R", "x0", "P0")])
def test_each_iteration_equals_pykalmans_em(learn):
    pykalman = pytest.importorskip("pykalman")
    ys = series(150, 1)
    ys[[5, 17, 18, 90]] = np.nan  # whole steps missing (pykalman masks a step whole)
    start = dict(F=CV.F(1.0) + 0.05 * np.eye(4), Q=np.eye(4), H=POS.H(4), R=np.eye(2),
                 x0=np.ones(4), P0=np.eye(4))
    pk = pykalman.KalmanFilter(
        transition_matrices=start["F"], observation_matrices=start["H"],
        transition_covariance=start["Q"], observation_covariance=start["R"],
        initial_state_mean=start["x0"], initial_state_covariance=start["P0"],
        transition_offsets=np.zeros(4), observation_offsets=np.zeros(2),
        em_vars=[PK_NAMES[k] for k in learn])
    X = np.ma.masked_invalid(ys)
    for k in range(1, 6):
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            pk = pk.em(X, n_iter=1)
        fit = em(ys, **start, learn=learn, max_iter=k, tol=-np.inf)
        assert fit.iterations == k
        for name, attr in PK_NAMES.items():
            np.testing.assert_allclose(getattr(fit, name), getattr(pk, attr), rtol=1e-6,
                                       atol=1e-9, err_msg=f"{name} after {k} iterations")
        np.testing.assert_allclose(fit.loglik[-1], pk.loglikelihood(X), rtol=1e-9)


def test_masked_measurements_are_missing_as_in_pykalmans_em():
    """A numpy masked array, pykalman's missing steps, has its masked entries missing, whatever
    lies under the mask; before, the placeholders were fitted as measurements."""
    pykalman = pytest.importorskip("pykalman")
    ys = series(120, 3)
    rows = [0, 5, 17, 18, 90]
    mask = np.zeros(ys.shape, bool)
    mask[rows] = True
    masked = np.ma.masked_array(np.where(mask, -999.0, ys), mask=mask)
    start = dict(F=CV.F(1.0), Q=np.eye(4), H=POS.H(4), R=np.eye(2), x0=np.ones(4),
                 P0=np.eye(4))
    pk = pykalman.KalmanFilter(
        transition_matrices=start["F"], observation_matrices=start["H"],
        transition_covariance=start["Q"], observation_covariance=start["R"],
        initial_state_mean=start["x0"], initial_state_covariance=start["P0"],
        em_vars=["transition_covariance", "observation_covariance"])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        pk = pk.em(masked, n_iter=3)
    fit = em(masked, **start, max_iter=3, tol=-np.inf)
    np.testing.assert_allclose(fit.Q, pk.transition_covariance, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(fit.R, pk.observation_covariance, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(fit.loglik[-1], pk.loglikelihood(masked), rtol=1e-9)
    # mle and a batch given as a list of masked series: masked is NaN (the documented missing
    # value), a component masked alone too
    masked[7, 1] = np.ma.masked
    nan = np.where(masked.mask, np.nan, masked.data)
    a, b = mle(masked, **cv_model()), mle(nan, **cv_model())
    np.testing.assert_array_equal(a.Q, b.Q)
    np.testing.assert_array_equal(a.R, b.R)
    a = em([masked, masked[::-1]], **cv_model(), max_iter=3)
    b = em(np.stack([nan, nan[::-1]]), **cv_model(), max_iter=3)
    np.testing.assert_array_equal(a.loglik, b.loglik)
    np.testing.assert_array_equal(a.Q, b.Q)
    P0 = np.ma.masked_array(np.eye(4), mask=np.eye(4, k=1, dtype=bool))
    with pytest.raises(ValueError, match=r"P0 must not have masked entries .*P0\[0, 1\] is"):
        em(nan, **{**cv_model(), "P0": P0})


@pytest.mark.parametrize("F, match", [
    (np.ones(4), r"F must be 2-D or 3-D; got shape \(4,\)"),
    (1.0, r"F must be 2-D or 3-D; got shape \(\)"),
    (np.eye(3), r"F must have shape \(4, 4\) or \(T=20, 4, 4\); got \(3, 3\)"),
    (np.eye(5), r"F must have shape \(4, 4\) or \(T=20, 4, 4\); got \(5, 5\)"),
])
def test_a_malformed_F_is_named_as_by_kalman_filter(F, match):
    """em and mle named x0 for a malformed F (a 1-D F: "x0 must have shape (0,) or (B, 0);
    got (4,)"; a 3 x 3 F: "x0 must have shape (3,) ..."): the model is checked before the
    prior, with kalman_filter's message."""
    ys = series(20, 4)
    model = {**cv_model(), "F": F}
    for fit in (vt.filters.kalman_filter, em, mle):
        with pytest.raises(ValueError, match=match):
            fit(ys, **model)
    # the other matrices as well, before the iterations
    for name, bad, msg in (("Q", np.eye(3), r"Q must have shape \(4, 4\)"),
                           ("H", np.eye(2, 3), r"H must have shape \(2, 4\)"),
                           ("R", -np.eye(2), "R must be positive semi-definite")):
        for fit in (vt.filters.kalman_filter, em, mle):
            with pytest.raises(ValueError, match=msg):
                fit(ys, **{**cv_model(), name: bad})
    # and the prior, where F and the other matrices agree on the state
    with pytest.raises(ValueError, match=r"x0 must have shape \(4,\)"):
        em(ys, **{**cv_model(), "x0": np.zeros(3)})


@pytest.mark.parametrize("R_form", ["full", "diag", "scaled"])
def test_log_likelihood_never_decreases_with_missing_steps_and_components(R_form, rng):
    ys = np.stack([series(120, s) for s in range(3)])
    ys[rng.random(ys.shape) < 0.15] = np.nan  # single components
    ys[rng.random(ys.shape[:2]) < 0.05] = np.nan  # whole steps
    R = np.array([[1.0, 0.3], [0.3, 2.0]]) if R_form != "diag" else np.eye(2)
    # H's rows are coupled by a correlated R where components are missing: H with "diag" only
    learn = ("F", "Q", "R", "x0", "P0") + (("H",) if R_form == "diag" else ())
    fit = em(ys, **{**cv_model(), "Q": np.eye(4), "R": R}, learn=learn, R_form=R_form,
             tol=-np.inf, max_iter=500)
    assert fit.iterations == 500 and np.isfinite(fit.loglik).all()
    assert np.diff(fit.loglik).min() >= -1e-9 * abs(fit.loglik[-1])
    for name in ("F", "Q", "H", "R", "x0", "P0"):
        assert np.isfinite(getattr(fit, name)).all(), name
    assert np.linalg.eigvalsh(fit.Q).min() > 0 and np.linalg.eigvalsh(fit.R).min() > 0


def test_frozen_parameters_stay_bit_identical():
    model = cv_model()
    fit = em(series(100, 2), **{**model, "Q": np.eye(4)}, learn=("Q",), max_iter=5)
    for name in ("F", "H", "R", "x0", "P0"):
        assert getattr(fit, name).tobytes() == np.asarray(model[name]).tobytes(), name
    assert not np.array_equal(fit.Q, np.eye(4))


def test_a_pooled_batch_of_one_series_repeated_equals_that_series():
    ys = series(200, 3)
    start = {**cv_model(), "Q": np.eye(4), "R": np.eye(2)}
    one = em(ys, **start, learn=("Q", "R", "P0"), max_iter=20)
    three = em(np.stack([ys] * 3), **start, learn=("Q", "R", "P0"), max_iter=20)
    for name in ("Q", "R", "P0"):
        np.testing.assert_allclose(getattr(three, name), getattr(one, name), rtol=1e-9)
    np.testing.assert_allclose(three.loglik, 3 * one.loglik, rtol=1e-12)


def test_series_that_share_their_gains_are_smoothed_as_each_alone():
    """The E-step of a batch whose series share their covariances smooths every series' means
    with the one sequence of gains: equal to the RTS smoother run on each series alone."""
    from vistrack.filters import kalman_filter, rts_smooth
    from vistrack.filters.learn import _smoothed

    ys = np.stack([series(150, s) for s in (6, 7, 8)])
    ys[:, 40:43] = np.nan  # the same steps missing in every series: still shared
    model = {**cv_model(), "Q": 0.3 * cv_model()["Q"]}
    res = kalman_filter(ys, **model)
    assert res.shared_covs
    ms, Ps, _, mult = _smoothed(res, model["F"], model["Q"])
    assert mult == 3 and Ps.shape[0] == 1
    for b in range(3):
        alone = rts_smooth(kalman_filter(ys[b], **model), F=model["F"], Q=model["Q"])
        np.testing.assert_allclose(ms[b], alone.means, rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(Ps[0], alone.covs, rtol=1e-10, atol=1e-12)


def test_one_fit_per_series_equals_each_series_fitted_alone():
    ys = np.stack([series(100, s) for s in (4, 5)])
    ys[1, 30:33] = np.nan  # the series do not share covariances
    start = {**cv_model(), "Q": np.eye(4), "R": np.eye(2)}
    both = em(ys, **start, learn=("Q", "R"), pooled=False, max_iter=30)
    for b in range(2):
        alone = em(ys[b], **start, learn=("Q", "R"), max_iter=30)
        np.testing.assert_allclose(both.Q[b], alone.Q, rtol=1e-10)
        np.testing.assert_allclose(both.R[b], alone.R, rtol=1e-10)
        k = len(alone.loglik)
        np.testing.assert_allclose(both.loglik[b, :k], alone.loglik, rtol=1e-12)
        assert np.isnan(both.loglik[b, k:]).all() and both.iterations[b] == alone.iterations


def test_a_missing_step_is_the_step_removed_and_the_time_step_doubled():
    """The white-noise-acceleration model composes exactly over time (F(a) F(b) = F(a + b),
    F(a) Q(b) F(a)' + Q(a) = Q(a + b)), so a series with some steps missing has the same
    likelihood for every q and R as the series without those steps and the time steps
    joined: the maximum, and EM's estimates there, are the same."""
    T = 300
    dts = np.ones(T)
    dts[0] = 0.0
    times = np.cumsum(dts)
    _, ys = simulate_lgssm(T, F=CV.F(dts), Q=CV.Q(dts), H=POS.H(4), R=POS.R(),
                           x0=np.zeros(4), P0=10.0 * np.eye(4), rng=6)
    gone = np.arange(10, T - 10, 7)
    ys_nan = ys.copy()
    ys_nan[gone] = np.nan
    keep = np.setdiff1d(np.arange(T), gone)
    dts_kept = np.r_[0.0, np.diff(times[keep])]
    fits = []
    for y, d in ((ys_nan, dts), (ys[keep], dts_kept)):
        fits.append(em(y, F=CV.F(d), Q=CV.Q(d) / 0.5, H=POS.H(4), R=np.eye(2),
                       x0=np.zeros(4), P0=10.0 * np.eye(4), learn=("Q", "R"),
                       Q_form="scaled", R_form="diag", tol=1e-10, max_iter=5000))
    a, b = fits
    assert a.converged and b.converged
    assert abs(a.loglik[-1] - b.loglik[-1]) < 1e-6
    np.testing.assert_allclose(a.q, b.q, rtol=1e-4)
    np.testing.assert_allclose(np.diag(a.R), np.diag(b.R), rtol=1e-4)


def test_a_batch_of_100_recovers_q_and_R():
    """100 series of 1,000 steps, started from q = 1 and R = I: q within 5 % of 0.5, R's
    diagonal within 3 % of 4 (standard errors about 1.5 % and 0.5 %)."""
    model = cv_model()
    ys = np.stack([series(1000, s) for s in range(100)])
    fit = em(ys, **{**model, "Q": CV.Q(1.0) / 0.5, "R": np.eye(2)}, learn=("Q", "R"),
             Q_form="scaled", R_form="diag", tol=1e-3, max_iter=500)
    assert fit.converged
    assert abs(fit.q / 0.5 - 1) < 0.05, fit.q
    np.testing.assert_allclose(np.diag(fit.R), 4.0, rtol=0.03)
    np.testing.assert_allclose(fit.Q, fit.q * CV.Q(1.0) / 0.5, rtol=1e-12)


def test_scaled_noise_is_the_exact_maximum_over_its_factor():
    """With everything else fixed, the log-likelihood as a function of the scale of Q (or R)
    is highest at EM's fixed point: one step of EM from there does not move it."""
    ys = series(300, 7)
    fit = em(ys, **{**cv_model(), "Q": CV.Q(1.0)}, learn=("Q",), Q_form="scaled", tol=1e-12,
             max_iter=3000)
    assert fit.converged

    def ll(q):
        return float(vt.kalman_filter(ys, **{**cv_model(), "Q": q * CV.Q(1.0)}).loglik)

    best = ll(fit.q)
    for f in (0.99, 1.01):
        assert ll(fit.q * f) < best


def test_progress_and_errors():
    ys = series(50, 8)
    out = io.StringIO()
    fit = em(ys, **cv_model(), learn=("R",), max_iter=3, tol=-np.inf, progress=out)
    lines = out.getvalue().splitlines()
    assert len(lines) == 4 and lines[0].startswith("EM iteration 0: log-likelihood ")
    assert float(lines[-1].rsplit(" ", 1)[1]) == pytest.approx(fit.loglik[-1], abs=1e-6)
    with pytest.raises(ValueError, match="learn must name some of"):
        em(ys, **cv_model(), learn=("B",))
    with pytest.raises(ValueError, match="R_form must be one of"):
        em(ys, **cv_model(), R_form="banded")
    with pytest.raises(ValueError, match="max_iter must be an integer >= 1"):
        em(ys, **cv_model(), max_iter=0)
    with pytest.raises(ValueError, match="tol must be a number"):
        em(ys, **cv_model(), tol="small")
    with pytest.raises(ValueError, match="at least 2 steps"):
        em(ys[:1], **cv_model(), learn=("Q",))
    partial = ys.copy()
    partial[3, 0] = np.nan
    correlated = {**cv_model(), "R": np.array([[4.0, 1.9], [1.9, 1.0]])}
    for R_form in ("full", "scaled"):
        with pytest.raises(ValueError, match="needs a diagonal R"):
            em(partial, **correlated, learn=("H", "R"), R_form=R_form)
    with pytest.raises(ValueError, match="needs a diagonal R"):
        em(partial, **correlated, learn=("H",))
    em(partial, **cv_model(), learn=("H",), max_iter=2)  # a diagonal R, given: the M-step
    never = ys.copy()
    never[:, 1] = np.nan
    with pytest.raises(ValueError, match="component 1 of ys is never measured"):
        em(never, **cv_model(), learn=("H",), R_form="diag")
    with pytest.raises(ValueError, match="learn must be a sequence of names"):
        em(ys, **cv_model(), learn="x0")
    with pytest.raises(ValueError, match="x0 must be one for all series or one per series"):
        em(np.stack([ys] * 3), **{**cv_model(), "x0": np.zeros((5, 4))})
    with pytest.raises(ValueError, match="ys has no measurement"):
        em(np.full_like(ys, np.nan), **cv_model())
    per_step_R = {**cv_model(), "R": np.stack([4.0 * np.eye(2)] * len(ys))}
    with pytest.raises(ValueError, match="learning H needs one R for all steps"):
        em(ys, **per_step_R, learn=("H",))
    with pytest.raises(ValueError, match="learning F needs one Q for all steps"):
        em(ys, **{**cv_model(), "Q": np.stack([CV.Q(1.0)] * len(ys))}, learn=("F",))
    with pytest.raises(ValueError, match="Q must not be zero to learn its factor"):
        em(ys, **{**cv_model(), "Q": np.zeros((4, 4))}, learn=("Q",), Q_form="scaled")


@pytest.mark.parametrize("R_form", ["diag", "scaled"])
def test_the_score_equals_finite_differences_of_the_log_likelihood(R_form, rng):
    ys = np.stack([series(150, s) for s in (9, 10)])
    ys[rng.random(ys.shape) < 0.1] = np.nan  # missing components and steps
    m = cv_model()
    y, p, _ = learn_module._problem(ys, m["F"], m["Q"], m["H"], np.diag([1.0, 2.0]), m["x0"],
                                    m["P0"], ("Q", "R"), 10)
    lik = learn_module._Structured(y, p, ("Q", "R"), R_form)
    theta = lik.start() + rng.normal(0, 0.3, size=lik.nq + lik.nr)
    _, g = lik.value_and_grad(theta)
    h = 1e-5
    fd = [(lik.value_and_grad(theta + h * e)[0] - lik.value_and_grad(theta - h * e)[0]) / (2 * h)
          for e in np.eye(len(theta))]
    np.testing.assert_allclose(g, fd, rtol=1e-6)


def test_maximum_likelihood_and_em_reach_the_same_maximum():
    ys = np.stack([series(400, s) for s in (11, 12, 13)])
    ys[0, 50:60] = np.nan
    start = {**cv_model(), "Q": CV.Q(1.0), "R": np.eye(2)}
    by_em = em(ys, **start, learn=("Q", "R"), Q_form="scaled", R_form="diag", tol=1e-9,
               max_iter=5000)
    by_ml = mle(ys, **start)
    assert by_em.converged and by_ml.converged
    assert by_ml.loglik[-1] >= by_em.loglik[-1] - 1e-6
    assert by_ml.loglik[-1] - by_em.loglik[-1] < 1e-4
    np.testing.assert_allclose(by_ml.q, by_em.q, rtol=1e-3)
    np.testing.assert_allclose(by_ml.r, np.diag(by_em.R), rtol=1e-3)
    np.testing.assert_allclose(by_ml.Q, by_ml.q * CV.Q(1.0), rtol=1e-12)
    assert np.all(np.diff(by_ml.loglik) >= -1e-9 * abs(by_ml.loglik[-1]))


def test_standard_error_of_a_variance_equals_the_closed_form(rng):
    """With F = 0 the states are independent, so y_t ~ N(0, q + r) and the maximum of r is
    mean(y^2) - q, with the observed information T / (2 (q + r)^2) there."""
    q, T = 2.0, 4000
    ys = rng.normal(0.0, np.sqrt(q + 3.0), size=(T, 1))
    fit = mle(ys, F=[[0.0]], Q=[[q]], H=[[1.0]], R=[[1.0]], x0=[0.0], P0=[[q]], learn=("R",))
    r = float(np.mean(ys ** 2)) - q
    np.testing.assert_allclose(fit.r, [r], rtol=1e-6)
    np.testing.assert_allclose(fit.stderr["r"], [(q + r) * np.sqrt(2 / T)], rtol=1e-3)
    assert fit.Q.tobytes() == np.array([[q]]).tobytes() and "q" not in fit.stderr


def test_maximum_likelihood_of_q_alone_leaves_a_full_or_per_step_R_as_given():
    ys = series(200, 18)
    R_full = np.array([[4.0, 1.0], [1.0, 3.0]])
    for R in (R_full, np.stack([R_full] * 200)):
        fit = mle(ys, **{**cv_model(), "R": R}, learn=("Q",))
        assert fit.converged and fit.R.tobytes() == R.tobytes()
        assert set(fit.stderr) == {"q"}


def test_maximum_likelihood_refuses_what_it_does_not_learn():
    ys = series(50, 14)
    # learn=() ran EM one iteration (mle none) and returned the model as given, "converged"
    for fit in (em, mle):
        for nothing in ((), []):
            with pytest.raises(ValueError, match=r"learn must name at least one of \["):
                fit(ys, **cv_model(), learn=nothing)
    with pytest.raises(ValueError, match=r"learn must name some of \['Q', 'R'\]"):
        mle(ys, **cv_model(), learn=("F",))
    with pytest.raises(ValueError, match="R_form must be 'diag' or 'scaled'"):
        mle(ys, **cv_model(), R_form="full")


def test_a_kalman_filter_learns_q_and_R_of_irregularly_sampled_measurements():
    """Time steps of 0.2-3 s: Q(dt) = q Q1(dt) for every step, one q learned, within four of
    its standard errors of the truth; the new filter's log-likelihood is the fit's maximum."""
    rng = np.random.default_rng(15)
    dts = rng.uniform(0.2, 3.0, size=1999)
    truth = vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=0.5), vt.Position(dim=2, r=4.0))
    _, ys = vt.simulate.simulate(truth.motion, truth.measurement, 2000, x0=np.zeros(4),
                                 dt=dts, rng=16)
    start = vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=1.0), vt.Position(dim=2, r=1.0))
    kf, fit = start.fit(ys, dt=dts)
    assert fit.converged and isinstance(kf.measurement, vt.Position)
    assert fit.q == kf.motion.q  # in the model's units, as its standard error
    assert abs(kf.motion.q - 0.5) < 4 * fit.stderr["q"]
    assert np.all(np.abs(kf.measurement.R().diagonal() - 4.0) < 4 * fit.stderr["r"])
    ll = float(kf.filter(ys, dt=dts, x0=fit.x0, P0=fit.P0).loglik)
    np.testing.assert_allclose(ll, fit.loglik[-1], rtol=1e-12)
    # the prior does not come from the noise guessed: another guess, the same maximum
    kf_far, _ = vt.KalmanFilter(vt.ConstantVelocity(dim=2, q=50.0),
                                vt.Position(dim=2, r=0.01)).fit(ys, dt=dts)
    np.testing.assert_allclose(kf_far.motion.q, kf.motion.q, rtol=1e-3)
    np.testing.assert_allclose(kf_far.measurement.R(), kf.measurement.R(), rtol=1e-3)
    assert start.motion.q == 1.0  # the models given are left as they were
    kf_em, fit_em = start.fit(ys, dt=dts, method="em", tol=1e-9, max_iter=5000)
    np.testing.assert_allclose(kf_em.motion.q, kf.motion.q, rtol=1e-3)
    np.testing.assert_allclose(kf_em.measurement.R(), kf.measurement.R(), rtol=1e-3, atol=1e-9)


def test_fitting_names_a_model_it_cannot_learn():
    ys = series(50, 17)
    kf = vt.KalmanFilter(vt.models.LinearMotion(CV.F(1.0), CV.Q(1.0)), POS)
    with pytest.raises(TypeError, match="a motion model with a q > 0 whose Q is q times"):
        kf.fit(ys)
    kf.fit(ys, learn=("R",))  # R alone is fine
    with pytest.raises(ValueError, match="method must be 'mle' or 'em'"):
        vt.KalmanFilter(CV, POS).fit(ys, method="newton")
    with pytest.raises(ValueError, match=r"learn must name some of \['q', 'R'\]"):
        vt.KalmanFilter(CV, POS).fit(ys, learn=("Q",))


def test_one_x0_for_priors_of_different_covariances_reaches_the_maximum():
    """A shared x0 with a P0 per series: each series weighs by its P0's inverse; at EM's end
    the log-likelihood's slope in x0 (finite differences) is zero."""
    ys = np.stack([series(50, b) for b in range(3)])
    P0 = np.stack([0.01 * np.eye(4), 100 * np.eye(4), np.eye(4)])
    start = {**cv_model(), "P0": P0, "x0": np.full(4, 3.0)}
    fit = em(ys, **start, learn=("x0",), tol=1e-12, max_iter=20000)
    assert fit.converged and np.diff(fit.loglik).min() >= -1e-9

    def ll(x0):
        return float(np.sum(vt.kalman_filter(ys, **{**start, "x0": x0}).loglik))

    slope = [(ll(fit.x0 + 1e-5 * e) - ll(fit.x0 - 1e-5 * e)) / 2e-5 for e in np.eye(4)]
    np.testing.assert_allclose(slope, 0.0, atol=1e-3)


@pytest.mark.parametrize("chunked", [False, True])
def test_one_x0_for_priors_of_which_one_is_singular(chunked):
    """A shared x0 with a P0 per series, one of them singular (a prior that knows the first
    velocity exactly): the M-step inverted each P0, numpy's bare "Singular matrix". Oracle:
    the limit of that P0 made regular by ``eps`` on its zero, ``eps`` -> 0, whose M-step is
    the ordinary weighted one; along the direction held exactly, x0 stays as it was."""
    ys = np.stack([series(50, b) for b in range(3)])
    P0 = np.stack([np.diag([1.0, 1.0, 1.0, 0.0]), 100 * np.eye(4), np.eye(4)])
    start = {**cv_model(), "P0": P0, "x0": np.full(4, 3.0)}
    if chunked:
        da = pytest.importorskip("dask.array")
        ys = da.from_array(ys, chunks=(2, 50, 2))
    fit = em(ys, **start, learn=("x0", "Q"), max_iter=4, tol=-np.inf)
    assert fit.x0[3] == 3.0 and np.diff(fit.loglik).min() >= -1e-9
    near = P0.copy()
    near[0, 3, 3] = 1e-10
    limit = em(ys, **{**start, "P0": near}, learn=("x0", "Q"), max_iter=4, tol=-np.inf)
    np.testing.assert_allclose(fit.x0, limit.x0, rtol=1e-6, atol=1e-6)
    np.testing.assert_allclose(fit.Q, limit.Q, rtol=1e-6, atol=1e-9)
    # every prior holding every direction: nothing to learn, x0 as it was
    none = em(ys, **{**start, "P0": np.zeros((3, 4, 4))}, learn=("x0",), max_iter=2,
              tol=-np.inf)
    np.testing.assert_array_equal(none.x0, start["x0"])


def test_a_prior_given_once_in_a_batch_axis_is_one_prior():
    ys = np.stack([series(60, b) for b in range(3)])
    start = {**cv_model(), "Q": np.eye(4)}
    one = em(ys, **start, learn=("Q", "x0", "P0"), max_iter=5)
    boxed = em(ys, **{**start, "x0": start["x0"][None], "P0": start["P0"][None]},
               learn=("Q", "x0", "P0"), max_iter=5)
    assert boxed.x0.shape == (4,) and boxed.P0.shape == (4, 4)
    np.testing.assert_array_equal(boxed.loglik, one.loglik)
    each = em(ys, **{**start, "x0": start["x0"][None]}, learn=("Q",), pooled=False,
              max_iter=3)
    assert each.Q.shape == (3, 4, 4)


def test_a_fall_from_a_start_outside_the_family_does_not_stop_em():
    """A per-step R to start from, one R learned: the first iteration lowers the likelihood
    here (the start is no single R); EM goes on to the maximum, which a long run of plain
    iterations confirms."""
    rng = np.random.default_rng(11)
    T = 150
    H = np.stack([POS.H(4) + 0.3 * rng.normal(size=(2, 4)) for _ in range(T)])
    R = np.stack([(lambda A: A @ A.T + 0.5 * np.eye(2))(rng.normal(size=(2, 2)))
                  for _ in range(T)])
    model = {**cv_model(), "H": H, "R": R}
    ys = np.stack([simulate_lgssm(T, **model, rng=b)[1] for b in range(3)])
    ys[rng.random(ys.shape) < 0.25] = np.nan
    start = {**model, "R": 2.0 * R}
    fit = em(ys, **start, learn=("R",))  # default tol
    assert fit.loglik[1] < fit.loglik[0]  # the fall
    long = em(ys, **start, learn=("R",), tol=-np.inf, max_iter=300)
    assert fit.converged and fit.iterations > 1
    assert fit.loglik[-1] == pytest.approx(long.loglik[-1], abs=1e-3)


def test_a_singular_start_learns_a_positive_semi_definite_Q():
    """The Euler-discretised constant velocity puts noise on the velocities only; learning
    every entry of Q from it, rounding must not leave Q below zero. The positions' noise is 0
    in the start and in every E-step after it (w's position part is 0 given x_{t+1}): it
    stays within 1e-20 of 0, where the smoothed covariances' differences left 4e-14 there
    (which also kept the smallest eigenvalue above the eigen solver's rounding of the
    largest, -8.5e-18 beside 0.55: the bound below is that rounding, n eps of the largest)."""
    from vistrack._validate import check_psd

    euler = vt.ConstantVelocity(dim=2, q=0.5, discretisation="euler")
    ys = series(200, 20)
    fit = em(ys, **{**cv_model(), "Q": euler.Q(1.0)}, learn=("Q",), tol=-np.inf, max_iter=60)
    assert np.isfinite(fit.loglik).all()
    check_psd(fit.Q, "Q")
    w = np.linalg.eigvalsh(fit.Q)
    assert w.min() >= -4 * np.finfo(float).eps * w.max()
    assert np.abs(fit.Q[:2, :2]).max() < 1e-20  # (positions first)


# an M-step's Q of the test above (Euler constant velocity, learned from its singular start): the
# positions' noise is 1e-26 and eigh takes its smallest eigenvalue for -7.9e-24 or 1.8e-16, its
# rounding of 0 beside 0.75
SINGULAR_Q = np.array([
    [5.8939661151002438e-27, 5.6703423332470284e-28, 6.9517341318935990e-15,
     -2.5680840112435432e-15],
    [5.6703423332470284e-28, 1.9925032476479880e-26, -1.0914910667263281e-15,
     -5.6667758968670966e-15],
    [6.9517341318935990e-15, -1.0914910667263281e-15, 5.9764098867218896e-01,
     7.0841932254915072e-02],
    [-2.5680840112435432e-15, -5.6667758968670966e-15, 7.0841932254915072e-02,
     7.2290930604238934e-01]])


def test_a_learned_noise_keeps_its_digits_where_it_is_not_below_zero():
    """The M-step lifts a learned noise's eigenvalues below zero to zero. It rebuilt the whole
    matrix from its eigenvectors, on a negative eigenvalue of -7.9e-24 that is the eigen
    solver's rounding beside 0.75: the positions' noise, 1e-26, became 1.8e-16. Oracles: a
    matrix negative only within that rounding is kept; one with a true negative eigenvalue
    (-1e-3, along the velocities' eigenvector v of eigenvalue lam) becomes its nearest
    positive semi-definite matrix, ``SINGULAR_Q - lam v v'`` (the eigenvalue's part taken
    away), the positions' noise among its entries (2e-26) to within 1e-28 (the eigenvectors'
    rounding times their 1e-14 parts there)."""
    psd = learn_module._psd
    assert psd(SINGULAR_Q) is SINGULAR_Q
    lam, V = np.linalg.eigh(SINGULAR_Q)
    v = V[:, 2]  # (0.566: the velocities', its positions' parts 1e-14)
    bad = SINGULAR_Q - (lam[2] + 1e-3) * np.outer(v, v)
    want = SINGULAR_Q - lam[2] * np.outer(v, v)
    got = psd(bad)
    assert np.abs(got[:2, :2] - want[:2, :2]).max() < 1e-28
    assert np.abs(got - want).max() < 4 * np.finfo(float).eps
    assert np.linalg.eigvalsh(got).min() >= -4 * np.finfo(float).eps
    stack = psd(np.stack([SINGULAR_Q, bad]))  # (per step: each judged on its own)
    assert (stack[0] == SINGULAR_Q).all() and (stack[1] == got).all()


def test_maximum_likelihood_names_what_it_cannot_learn_from():
    ys = series(60, 21)
    with pytest.raises(ValueError, match="R's diagonal must be > 0"):
        mle(ys, **{**cv_model(), "R": np.diag([4.0, 0.0])})
    with pytest.raises(ValueError, match="Q must not be zero"):
        mle(ys, **{**cv_model(), "Q": np.zeros((4, 4))})
    with pytest.raises(ValueError, match="ys has no measurement"):
        mle(np.full_like(ys, np.nan), **cv_model())
    never = ys.copy()
    never[:, 1] = np.nan
    with pytest.raises(ValueError, match="component 1 of ys is never measured"):
        mle(never, **cv_model())
    with pytest.raises(ValueError, match="xtol must be a number > 0"):
        mle(ys, **cv_model(), xtol="a")
    with pytest.raises(ValueError, match="learn must be a sequence of names"):
        mle(ys, **cv_model(), learn="Q")


def test_fit_refuses_a_string_for_learn():
    with pytest.raises(ValueError, match="learn must be a sequence of names"):
        vt.KalmanFilter(CV, POS).fit(series(30, 22), learn="qR")


def shared_problem(B, T, x0_per_series, rng):
    """Series of the constant-velocity model far from the origin, some steps missing in all
    of them, and a start away from the truth."""
    ys = np.stack([series(T, s) for s in range(B)]) + 500.0
    if T > 40:
        ys[:, [3, 4, 30, T - 2]] = np.nan
    p = {k: np.array(v, dtype=float) for k, v in cv_model().items()}
    p.update(Q=2.0 * p["Q"], R=np.array([[1.0, 0.2], [0.2, 2.0]]))
    if x0_per_series:
        p["x0"] = rng.normal(500.0, 10.0, size=(B, 4))
    return learn_module._Observed(ys), p


@pytest.mark.parametrize("B, T, x0_per_series", [(1, 1000, False), (300, 200, True),
                                                 (2, 2, False), (3, 1, True)])
def test_the_compiled_e_step_equals_the_general_one(B, T, x0_per_series, rng):
    """Series that share their covariances take one compiled pass, which stops computing
    the covariances at their steady state; every sum the M-step uses equals the general
    E-step's (filter, RTS smoother, sums in numpy), over blocks of series and a remainder."""
    o, p = shared_problem(B, T, x0_per_series, rng)
    learn = ("Q", "R", "x0", "P0")
    assert learn_module._shares_covariances(o, p, learn)
    fast, general = learn_module._estep(o, p, True), learn_module._EStep(o, p)
    assert isinstance(fast, learn_module._SharedEStep)
    np.testing.assert_allclose(fast.ll, general.ll, rtol=1e-12)
    F = p["F"]
    if T > 1:
        np.testing.assert_allclose(fast.process_noise_sums(F).sum(axis=0),
                                   general.process_noise_sums(F).sum(axis=0), rtol=1e-10)
    np.testing.assert_allclose(fast.vv(p["H"]).sum(axis=0), general.vv(p["H"]).sum(axis=0),
                               rtol=1e-10)
    for a, b in zip(fast.prior(learn), general.prior(learn)):
        np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-10)


@pytest.mark.parametrize("B, T", [(1, 1000), (130, 60), (2, 2)])
def test_the_compiled_e_step_reads_nothing_left_in_its_work_space(B, T, rng):
    """EM gives the compiled E-step one work space for all its iterations (arrays allocated
    afresh at each call doubled a first fit's time): what a call left there, or NaN, changes
    nothing of the next, to the bit, over blocks of series and a remainder; a work space too
    small is refused before anything is written."""
    from vistrack.filters._estep import WORK_TOO_SMALL, estep_shared, work_layout

    o, p = shared_problem(B, T, True, rng)
    first = learn_module._SharedEStep(o, p)
    work = o.work(4)
    assert o.work(4) is work and work.shape == (work_layout.py_func(T, 4, 2, B)[0],)
    learn_module._SharedEStep(o, {**p, "Q": 7.0 * p["Q"]})  # another model's run left there
    again = learn_module._SharedEStep(o, p)
    work[:] = np.nan
    after_nan = learn_module._SharedEStep(o, p)
    for e in (again, after_nan):
        assert e.done and e.ll == first.ll
        for name in ("A", "V", "ms0", "Ps0"):
            assert getattr(e, name).tobytes() == getattr(first, name).tobytes(), name

    args = [np.ascontiguousarray(p[k]) for k in ("F", "Q", "H", "R")]
    outs = [np.full_like(a, -1.0) for a in (first.A, first.V, first.ms0, first.Ps0)]
    out = np.zeros(2)
    estep_shared(o.yt, *args, p["x0"], p["P0"], *outs, np.empty(work.size - 1), out)
    assert out[1] == WORK_TOO_SMALL and all((a == -1.0).all() for a in outs)


def test_the_process_noise_is_summed_term_by_term():
    """``E[w_t w_t']`` from the smoothed means' differences and the covariances equals ``S11
    - F S10' - S10 F' + F S00 F'`` (the textbook form) where that form loses nothing: near
    the origin."""
    ys = series(300, 3)[None]
    p = {k: np.array(v, dtype=float) for k, v in cv_model().items()}
    e = learn_module._EStep(learn_module._Observed(ys), p)
    S11, S10, S00 = e.transition_sums()
    F = p["F"]
    textbook = S11 - F @ np.swapaxes(S10, -1, -2) - S10 @ F.T + F @ S00 @ F.T
    np.testing.assert_allclose(e.process_noise_sums(p["F"]), textbook, rtol=1e-9, atol=1e-9)


def test_one_fit_per_series_checks_each_series():
    """With ``pooled=False`` each series is one fit, checked as one: a component one series
    never measures leaves its row of ``H`` unknown though another series measures it (numpy's
    "Singular matrix" before); the error names the series."""
    ys = np.random.default_rng(0).normal(size=(3, 30, 2)).cumsum(axis=1)
    ys[1, :, 1] = np.nan
    M = dict(F=np.eye(2), Q=np.eye(2), H=np.eye(2), R=np.eye(2), x0=np.zeros(2), P0=np.eye(2))
    with pytest.raises(ValueError, match="series 1 of ys \\(pooled=False\\): component 1 of ys "
                       "is never measured: H's row for it cannot be learned"):
        em(ys, **M, learn=("H",), pooled=False, max_iter=3)
    em(ys, **M, learn=("H",), max_iter=3)  # pooled, another series measures it


def test_one_fit_per_series_of_a_batch_of_one_keeps_the_batch_axis():
    """``pooled=False`` on a batch ``(1, T, m)``: every attribute with its batch axis of one,
    as for two series (it was the pooled fit's, without it); one series ``(T, m)`` has none."""
    ys = np.stack([series(60, s) for s in (1, 2)])
    start = {**cv_model(), "Q": np.eye(4), "R": np.eye(2)}
    two = em(ys, **start, pooled=False, max_iter=5)
    one = em(ys[:1], **start, pooled=False, max_iter=5)
    for name in ("Q", "R", "F", "x0", "loglik", "iterations", "converged", "q"):
        a, b = np.asarray(getattr(one, name)), np.asarray(getattr(two, name))
        assert a.shape == (1,) + b.shape[1:], name
        np.testing.assert_array_equal(a[0], b[0], err_msg=name)
    alone = em(ys[0], **start, pooled=False, max_iter=5)
    assert alone.Q.shape == (4, 4) and alone.loglik.shape == (6,)


def test_em_with_the_compiled_e_step_equals_em_without_it(monkeypatch, rng):
    o, p = shared_problem(40, 300, False, rng)
    kw = dict(learn=("Q", "R", "x0", "P0"), Q_form="scaled", R_form="diag", tol=-np.inf,
              max_iter=30)
    fast = em(o.y, **p, **kw)
    fast_ml = mle(o.y, **p, R_form="diag")
    monkeypatch.setattr(learn_module, "_shares_covariances", lambda *a: False)
    general = em(o.y, **p, **kw)
    general_ml = mle(o.y, **p, R_form="diag")
    np.testing.assert_allclose(fast.loglik, general.loglik, rtol=1e-11)
    for name in ("Q", "R", "x0", "P0"):
        np.testing.assert_allclose(getattr(fast, name), getattr(general, name), rtol=1e-8,
                                   atol=1e-10, err_msg=name)
    np.testing.assert_allclose(fast_ml.Q, general_ml.Q, rtol=1e-6)
    np.testing.assert_allclose(fast_ml.R, general_ml.R, rtol=1e-6)


def test_what_does_not_share_covariances_takes_the_general_e_step(rng):
    o, p = shared_problem(3, 100, False, rng)
    y = o.y.copy()
    y[1, 50] = np.nan  # one series misses a step the others measure
    assert not learn_module._shares_covariances(learn_module._Observed(y), p, ("Q", "R"))
    y = o.y.copy()
    y[:, 60, 0] = np.nan  # a step measured in part
    assert not learn_module._shares_covariances(learn_module._Observed(y), p, ("Q", "R"))
    assert not learn_module._shares_covariances(o, p, ("F", "Q"))
    assert not learn_module._shares_covariances(o, {**p, "P0": np.stack([p["P0"]] * 3)},
                                                ("Q",))


def test_a_singular_predicted_covariance_is_named_as_by_the_smoother():
    """The compiled E-step cannot invert a singular prediction for the smoother's gain; the
    general one then says where."""
    ys = series(50, 0)
    model = {**cv_model(), "Q": np.zeros((4, 4)), "P0": np.zeros((4, 4))}
    with pytest.raises(ValueError, match="from step 48 to 49 is not positive definite"):
        em(ys, **model, learn=("R",), max_iter=3)  # (a zero Q learned is refused first)


def _augmented_R_step(ys, F, Q, H, R, x0, P0):
    """One M-step of ``R`` by hand, with a plain RTS smoother on the state ``[x; v]``
    (``v`` the measurement noise, drawn anew each step, so ``y = [H I] [x; v]`` exactly):
    ``R = mean_t E[v_t v_t' | y]``, each step's measured components selected. Independent of
    the package's filter, smoother and conditional expectations."""
    n, m = F.shape[0], H.shape[0]
    Fa = np.block([[F, np.zeros((n, m))], [np.zeros((m, n + m))]])
    Qa = np.block([[Q, np.zeros((n, m))], [np.zeros((m, n)), R]])
    Ha = np.c_[H, np.eye(m)]
    mean, cov = np.r_[x0, np.zeros(m)], np.block([[P0, np.zeros((n, m))],
                                                  [np.zeros((m, n)), R]])
    fm, fP, pm, pP = [], [], [], []
    for t, y in enumerate(ys):
        if t:
            mean, cov = Fa @ mean, Fa @ cov @ Fa.T + Qa
        pm.append(mean)
        pP.append(cov)
        o = ~np.isnan(y)
        Ho = Ha[o]
        S = Ho @ cov @ Ho.T
        K = cov @ Ho.T @ np.linalg.pinv(S)
        mean = mean + K @ (y[o] - Ho @ mean)
        cov = cov - K @ Ho @ cov
        fm.append(mean)
        fP.append(cov)
    sm, sP = [fm[-1]], [fP[-1]]
    for t in range(len(ys) - 2, -1, -1):
        G = fP[t] @ Fa.T @ np.linalg.pinv(pP[t + 1])
        sm.insert(0, fm[t] + G @ (sm[0] - pm[t + 1]))
        sP.insert(0, fP[t] + G @ (sP[0] - pP[t + 1]) @ G.T)
    return np.mean([P[n:, n:] + np.outer(x[n:], x[n:]) for x, P in zip(sm, sP)], axis=0)


@pytest.mark.parametrize("R", [[[2.0, 1.2], [1.2, 1.5]], [[0.0, 0.0], [0.0, 1.0]]],
                         ids=["correlated", "one-noiseless"])
def test_R_from_steps_that_measure_some_components_equals_an_augmented_smoother(R):
    """Where a step measures some components, the M-step of a full ``R`` needs the missing
    noise given the measured one: ``E[v_m | v_o]`` through ``R_mo R_oo^-1``. Replacing it by
    0 passed every test before; and a noiseless measured component (``R = diag(0, 1)``,
    which the filter takes) made ``R_oo`` singular: a bare "Singular matrix" from numpy. The
    oracle: the noise as part of the state, smoothed by hand."""
    rng = np.random.default_rng(4)
    model = {**cv_model(), "R": np.array(R)}
    ys = series(120, 3, **model)
    hide = rng.random(ys.shape) < 0.3
    hide[hide.all(1)] = [True, False]  # every step measures something
    ys[hide] = np.nan
    fit = em(ys, **model, learn=("R",), max_iter=1, tol=-np.inf)
    want = _augmented_R_step(ys, **{k: np.asarray(v, float) for k, v in model.items()})
    np.testing.assert_allclose(fit.R, want, rtol=1e-7, atol=1e-9)


def test_a_zero_noise_or_prior_learned_is_refused():
    """A zero start is a fixed point of EM whatever the form: from ``Q = 0`` learned as
    ``"full"`` EM stayed at ``|Q| = 1e-14`` and said it had converged (on 200 steps of a
    constant-velocity model, 1,285 nats below the fit from the identity). Refused for
    ``Q``, ``R`` and ``P0`` as for a ``"scaled"`` noise; ``pooled`` and ``progress`` are
    checked before any work."""
    ys = series(60, 0)
    for name in ("Q", "R", "P0"):
        model = cv_model()
        model[name] = np.zeros_like(model[name])
        with pytest.raises(ValueError, match=f"^{name} must not be zero to learn it: EM keeps "
                                             f"a zero {name} zero"):
            em(ys, **model, learn=(name,), Q_form="diag")
    with pytest.raises(TypeError, match="^pooled must be True or False; got 'no'$"):
        em(ys, **cv_model(), pooled="no")
    with pytest.raises(TypeError, match=r"^progress must be a stream with write\(\)"):
        em(ys, **cv_model(), progress=True)


@pytest.mark.parametrize("learn, Q_form", [(("Q", "R"), "full"), (("F", "Q", "R"), "diag"),
                                           (("Q", "R", "x0", "P0"), "scaled")])
def test_a_series_padded_with_missing_steps_is_fitted_as_the_series_alone(learn, Q_form):
    """Steps after a series' last measurement (the padding of a shorter series in a batch)
    tell nothing, but their transitions entered the M-steps of ``F`` and ``Q`` with the
    current values' own terms, holding each step back toward them. Oracle: the same series
    without the padding, which has the same likelihood for every model; every iteration
    equal to rounding (before, ``Q`` differed from the first iteration on)."""
    ys = series(120, 3)
    ys[[10, 11, 40]] = np.nan
    padded = np.concatenate([ys, np.full((200, 2), np.nan)])
    start = dict(cv_model(), Q=np.eye(4), R=np.eye(2), F=CV.F(1.0) + 0.02 * np.eye(4))
    if Q_form == "scaled":  # one Q a step, the padding's too
        start["Q"] = np.stack([CV.Q(1.0 + 0.01 * t) for t in range(320)])
    alone = em(ys, **dict(start, Q=start["Q"][:120] if Q_form == "scaled" else start["Q"]),
               learn=learn, Q_form=Q_form, max_iter=6, tol=-np.inf)
    fit = em(padded, **start, learn=learn, Q_form=Q_form, max_iter=6, tol=-np.inf)
    np.testing.assert_allclose(fit.loglik, alone.loglik, rtol=1e-12)
    for name in ("F", "H", "R", "x0", "P0", "q"):
        np.testing.assert_allclose(getattr(fit, name), getattr(alone, name), rtol=1e-9,
                                   atol=1e-12, err_msg=name)
    Q = fit.Q[:120] if Q_form == "scaled" else fit.Q
    np.testing.assert_allclose(Q, alone.Q, rtol=1e-9, atol=1e-12)
    if Q_form == "full":  # and the score of mle, whose sums are the same E-step's
        start["Q"] = CV.Q(1.0)
        want, got = mle(ys, **start), mle(padded, **start)
        assert got.converged and got.iterations == want.iterations
        np.testing.assert_allclose([got.q, *got.r], [want.q, *want.r], rtol=1e-9)


def test_series_of_unequal_length_pool_each_series_own_transitions():
    """Pooled over series of 40, 90 and 150 steps padded to 150: the M-step of ``Q`` and
    ``R`` is the mean over every series' own transitions and measured steps. Oracle:
    pykalman's one EM iteration on each series alone, at its own length, weighed by its
    transitions (``Q``) and steps (``R``); and the fit reaches the same likelihood in far
    fewer iterations than it took when the padding's transitions held ``Q`` back."""
    pykalman = pytest.importorskip("pykalman")
    lengths = (40, 90, 150)
    ys = np.full((3, 150, 2), np.nan)
    for b, n in enumerate(lengths):
        ys[b, :n] = series(n, 10 + b)
    start = dict(cv_model(), Q=np.eye(4), R=np.eye(2))
    Qs, Rs = [], []
    for b, n in enumerate(lengths):
        pk = pykalman.KalmanFilter(
            transition_matrices=start["F"], observation_matrices=start["H"],
            transition_covariance=start["Q"], observation_covariance=start["R"],
            initial_state_mean=start["x0"], initial_state_covariance=start["P0"],
            transition_offsets=np.zeros(4), observation_offsets=np.zeros(2),
            em_vars=["transition_covariance", "observation_covariance"])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            pk = pk.em(ys[b, :n], n_iter=1)
        Qs.append(pk.transition_covariance * (n - 1))
        Rs.append(pk.observation_covariance * n)
    fit = em(ys, **start, learn=("Q", "R"), max_iter=1, tol=-np.inf)
    np.testing.assert_allclose(fit.Q, sum(Qs) / sum(n - 1 for n in lengths), rtol=1e-7)
    np.testing.assert_allclose(fit.R, sum(Rs) / sum(lengths), rtol=1e-7)
    # a random walk, 19 series of 50 steps and one of 1,000: 914 iterations to tol 1e-6
    # with the padding's transitions in Q's M-step, 114 without, at the same maximum
    walk = dict(F=[[1.0]], H=[[1.0]], x0=[0.0], P0=[[1.0]])
    short = np.full((20, 1000, 1), np.nan)
    for b in range(20):
        n = 1000 if b == 19 else 50
        short[b, :n] = simulate_lgssm(n, Q=[[0.5]], R=[[4.0]], rng=b, **walk)[1]
    fit = em(short, Q=[[5.0]], R=[[0.4]], **walk, tol=1e-6, max_iter=2000)
    assert fit.converged and fit.iterations < 200
    best = mle(short, Q=[[5.0]], R=[[0.4]], **walk)
    assert fit.loglik[-1] >= best.loglik[-1] - 1e-3
    np.testing.assert_allclose([fit.Q[0, 0], fit.R[0, 0]], [best.Q[0, 0], best.R[0, 0]],
                               rtol=2e-3)


def test_a_series_never_measured_after_its_first_step_or_at_all_says_nothing():
    """Learning ``F`` from series with no transition up to their last measured step (a track
    of one detection, padded) failed in numpy's solve ("Singular matrix") once padding was
    left out: nothing depends on ``F`` there, and it is kept, as ``Q`` and ``R`` are. A
    series never measured held the shared prior's M-steps back toward the current ``x0`` and
    ``P0`` (its smoothed first state is the prior). Oracle: the batch without that series,
    every iteration, in memory and on a Dask array."""
    m = cv_model()
    one = np.full((2, 30, 2), np.nan)
    one[:, 0] = [[1.0, 2.0], [3.0, 1.0]]
    fit = em(one, **m, learn=("F", "Q", "R"), max_iter=3, tol=-np.inf)
    np.testing.assert_array_equal(fit.F, m["F"])
    each = em(one, **m, learn=("F", "Q", "R"), pooled=False, max_iter=3, tol=-np.inf)
    np.testing.assert_array_equal(each.F, np.stack([m["F"]] * 2))
    ys = np.stack([series(60, b) for b in range(4)])
    blank = np.concatenate([ys, np.full((1, 60, 2), np.nan)])
    start = dict(m, Q=np.eye(4), x0=np.ones(4), P0=np.eye(4))
    for learn in (("x0", "P0"), ("Q", "R", "x0"), ("F", "Q", "R", "P0")):
        want = em(ys, **start, learn=learn, max_iter=5, tol=-np.inf)
        got = [em(blank, **start, learn=learn, max_iter=5, tol=-np.inf)]
        da = pytest.importorskip("dask.array")
        got.append(em(da.from_array(blank, chunks=(4, 60, 2)), **start, learn=learn,
                      max_iter=5, tol=-np.inf))
        for fit in got:
            for name in ("F", "Q", "R", "x0", "P0", "loglik"):
                np.testing.assert_allclose(getattr(fit, name), getattr(want, name),
                                           rtol=1e-9, atol=1e-12, err_msg=f"{learn} {name}")


def test_the_shared_e_step_waits_for_each_variance_at_its_own_scale():
    """The shared E-step took a covariance as settled when it changed by a few units in the
    last place of its largest entry: with Q = diag(1e10, 1e-4), the small state's variance
    was frozen while it still changed, the log-likelihood at the start parameters was 0.13
    nats off the filter's and EM learned Q22 9.15e-4 where the series' own path (P0 per
    series) learns 7.50e-4. Oracle: the Kalman filter's log-likelihood at the same
    parameters, and the general path's fit."""
    from vistrack.filters import em, kalman_filter

    rng = np.random.default_rng(0)
    B, T = 2, 1500
    q, r = np.array([1e10, 1e-4]), np.array([1e10, 1.0])
    x = np.cumsum(rng.normal(size=(B, T, 2)) * np.sqrt(q), axis=1)
    ys = x + rng.normal(size=(B, T, 2)) * np.sqrt(r)
    kw = dict(F=np.eye(2), Q=np.diag(q), H=np.eye(2), R=np.diag(r), x0=np.zeros((B, 2)))
    P0 = np.diag([1e10, 1.0])
    shared = em(ys, **kw, P0=P0, Q_form="diag", R_form="diag", max_iter=15)
    general = em(ys, **kw, P0=np.stack([P0, P0]), Q_form="diag", R_form="diag", max_iter=15)
    exact = kalman_filter(ys, F=np.eye(2), Q=np.diag(q), H=np.eye(2), R=np.diag(r),
                          x0=np.zeros((B, 2)), P0=P0).loglik.sum()
    assert shared.loglik[0] == pytest.approx(exact, abs=1e-6)
    np.testing.assert_allclose(np.diagonal(shared.Q), np.diagonal(general.Q), rtol=1e-6)


def test_mle_says_when_it_stops_on_the_bound_of_its_search():
    """mle searches each noise factor within e^±20 of its start: a random walk scaled by
    1e5, started from Q = R = 1, stopped at q = r = 4.85e8 (e^20), converged False, with
    no word and no word of the bound in the docs. Oracle: the truth (q = 0.5, r = 4 in the
    data's units times 1e10), which em, without a bound, finds."""
    import warnings

    from vistrack.filters import em, mle

    rng = np.random.default_rng(1)
    T, s = 3000, 1e5
    x = np.cumsum(rng.normal(0, np.sqrt(0.5), T))
    ys = (s * (x + rng.normal(0, 2, T)))[:, None]
    kw = dict(F=np.eye(1), Q=np.eye(1), H=np.eye(1), R=np.eye(1), x0=np.zeros(1),
              P0=np.eye(1) * s ** 2)
    with pytest.warns(RuntimeWarning, match=re.escape(
            "mle: q, r[0] reached e^±20 times its start, the bound of the search")):
        fit = mle(ys, **kw)
    assert not fit.converged and fit.q == pytest.approx(np.exp(20))
    learned = em(ys, **kw, max_iter=300, tol=1e-9)
    assert learned.Q[0, 0] / s ** 2 == pytest.approx(0.5, rel=0.15)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mle(ys / s, **{**kw, "P0": np.eye(1)})  # at the data's scale: no bound reached


def test_an_unpooled_series_without_a_measurement_is_named():
    """With pooled=False a series of NaN alone came back converged at its start (loglik 0),
    where em refuses it given alone and the docs say each series is checked so."""
    ys = np.random.default_rng(0).normal(size=(3, 20, 1))
    ys[1] = np.nan
    kw = dict(F=np.eye(1), Q=np.eye(1), H=np.eye(1), R=np.eye(1), x0=np.zeros(1), P0=np.eye(1))
    with pytest.raises(ValueError, match=re.escape(
            "series 1 of ys (pooled=False): it has no measurement: every value is NaN")):
        em(ys, **kw, pooled=False)
    with pytest.raises(ValueError, match=re.escape("ys has no measurement")):
        em(ys[1], **kw)


def test_learn_that_is_no_sequence_is_named():
    """learn=None was "'NoneType' object is not iterable"."""
    E = np.eye(1)
    with pytest.raises(TypeError, match=r"learn must be a sequence of names, some of .*got None"):
        em(np.ones((10, 1)), F=E, Q=E, H=E, R=E, x0=[0.0], P0=E, learn=None)


def test_noise_learned_from_constant_data_is_not_reported_converged():
    """Constant measurements fit a random walk with no noise at all: the likelihood has no
    maximum (it grows as Q and R fall). EM ran on until both were subnormal (1e-323) and said
    it had converged there; it warns and reports the fit not converged. With noise in the
    data, the same call converges without a word (the oracle: the data's own variance)."""
    E = np.eye(1)
    with pytest.warns(RuntimeWarning, match=r"Q fell to zero .* the fit is not converged"):
        fit = em(np.full((30, 1), 5.0), F=E, Q=E, H=E, R=E, x0=[5.0], P0=E, max_iter=2000)
    assert not fit.converged
    assert fit.Q[0, 0] < np.finfo(float).tiny
    rng = np.random.default_rng(0)
    walk = 5.0 + np.cumsum(rng.normal(0.0, 1.0, 2000))  # Q = 1
    ys = (walk + rng.normal(0.0, 2.0, 2000))[:, None]  # R = 4
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        fit = em(ys, F=E, Q=E, H=E, R=E, x0=[5.0], P0=E, max_iter=2000)
    assert fit.converged
    assert fit.Q[0, 0] == pytest.approx(1.0, rel=0.3)
    assert fit.R[0, 0] == pytest.approx(4.0, rel=0.15)


def test_the_compiled_e_step_keeps_a_small_process_noise_beside_a_large_one():
    """Q = diag(1e-8, 1e8): the compiled E-step (series that share their covariances: every
    step measured, Q and R learned) took its smoothed covariances and each transition's as
    differences of numbers of 1e8, and learned Q[0, 0] = 1.2e-7 in one iteration on 8 steps
    (2.1e-7 on 30) where the exact M-step gives 3.0e-8 (a series with a value missing among
    several measured at a step took the other E-step, and 3.0e-8). Oracle: the M-step from
    the exact posterior of all states, its sums in fractions."""
    from fractions import Fraction

    from vistrack.simulate import simulate_lgssm

    from .conftest import exact_posterior

    F, H = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    Q = np.diag([1e-8, 1e8])
    T = 8
    _, ys = simulate_lgssm(T, F=F, Q=Q, H=H, R=[[1.0]], x0=[0.0, 0.0], P0=np.eye(2), rng=3)
    start = dict(F=F, Q=3 * Q, H=H, R=np.array([[2.0]]), x0=np.zeros(2), P0=np.eye(2))
    got = em(ys, **start, max_iter=1, tol=-np.inf)
    mu, C = exact_posterior(ys, **start, fractions=True)
    f = [[Fraction(float(v)) for v in row] for row in F]

    def w(t, a, b):  # E[w_t[a] w_t[b]], w_t = x_{t+1} - F x_t, exactly
        def coef(k):  # the coefficients of w_t[k] on the states' entries
            c = {2 * (t + 1) + k: Fraction(1)}
            for j in range(2):
                c[2 * t + j] = c.get(2 * t + j, Fraction(0)) - f[k][j]
            return c

        ca, cb = coef(a), coef(b)
        mean_a = sum(v * mu[i] for i, v in ca.items())
        mean_b = sum(v * mu[i] for i, v in cb.items())
        return mean_a * mean_b + sum(va * vb * C[i][j] for i, va in ca.items()
                                     for j, vb in cb.items())

    exact = np.array([[float(sum(w(t, a, b) for t in range(T - 1)) / (T - 1))
                       for b in range(2)] for a in range(2)])
    np.testing.assert_allclose(np.diag(got.Q), np.diag(exact), rtol=1e-6)
