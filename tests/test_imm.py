"""The IMM filter: against single Kalman filters, the closed form of the seed's multiple-model
filter, a manoeuvring target with a known switch time, and members of different sizes."""

import numpy as np
import pytest

import vistrack as vt
from vistrack.filters import ExtendedKalmanFilter, IMMFilter, UnscentedKalmanFilter, kalman_filter

# (a member class whose own update runs the IMM's steps from Python, the filter before
# its compiled path)
from .test_nonlinear import _python_steps


def cv(q, r=1.0, dim=1):
    return ExtendedKalmanFilter(vt.ConstantVelocity(dim=dim, q=q), vt.Position(dim=dim, r=r))


def kf_run(q, ys, x0, P0, r=1.0):
    m, p = vt.ConstantVelocity(dim=1, q=q), vt.Position(dim=1, r=r)
    return kalman_filter(ys, F=m.F(1.0), Q=m.Q(1.0), H=p.H(2), R=p.R(), x0=x0, P0=P0)


def test_identical_members_are_the_kalman_filter(rng):
    _, ys = vt.simulate.simulate(vt.ConstantVelocity(dim=1, q=0.3), vt.Position(dim=1), 30,
                                 x0=[0.0, 1.0], rng=rng)
    ys[7] = np.nan
    x0, P0 = np.zeros(2), np.eye(2)
    kf = kf_run(0.3, ys, x0, P0)
    for members in ([cv(0.3)], [cv(0.3), cv(0.3)]):
        M = len(members)
        Pi = np.full((M, M), 0.1 / max(M - 1, 1)) + np.eye(M) * (0.9 - 0.1 / max(M - 1, 1))
        res = IMMFilter(members, Pi if M > 1 else [[1.0]]).filter(ys, x0=x0, P0=P0)
        np.testing.assert_allclose(res.means, kf.means, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(res.covs, kf.covs, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(res.mode_probs, 1.0 / M, rtol=1e-12)
        assert res.loglik == pytest.approx(float(kf.loglik), rel=1e-10)


def test_identity_switching_is_the_seeds_multiple_model_filter(rng):
    """With Π = I the filters never mix: each runs alone, and the model probabilities are the
    prior times each model's likelihood of the measurements so far, normalised."""
    T = 15
    _, ys = vt.simulate.simulate(vt.ConstantVelocity(dim=1, q=0.5), vt.Position(dim=1), T,
                                 x0=[0.0, 1.0], rng=rng)
    x0, P0, qs, prior = np.zeros(2), np.eye(2), (0.01, 2.0), np.array([0.3, 0.7])
    res = IMMFilter([cv(q) for q in qs], np.eye(2), mode_probs=prior).filter(ys, x0=x0, P0=P0)
    for j, q in enumerate(qs):
        np.testing.assert_allclose(res.member_means[j], kf_run(q, ys, x0, P0).means, rtol=1e-10)
    cum = np.array([[float(kf_run(q, ys[: t + 1], x0, P0).loglik) for q in qs] for t in range(T)])
    expected = prior * np.exp(cum - cum.max(1, keepdims=True))
    np.testing.assert_allclose(res.mode_probs, expected / expected.sum(1, keepdims=True),
                               rtol=1e-9)


def test_a_model_of_probability_0_still_runs_its_own_filter(rng):
    """Π = I and a prior of (1, 0): the second model has no mass to mix, and keeps running on
    its own, as the Kalman filter of its model does (the oracle); it was reset to a zero mean
    and covariance at every step. The combined estimate is the first model's."""
    T = 12
    _, ys = vt.simulate.simulate(vt.ConstantVelocity(dim=1, q=0.5), vt.Position(dim=1), T,
                                 x0=[5.0, 1.0], rng=rng)
    x0, P0, qs = np.array([5.0, 1.0]), np.eye(2), (0.01, 2.0)
    res = IMMFilter([cv(q) for q in qs], np.eye(2), mode_probs=[1.0, 0.0]).filter(
        ys, x0=x0, P0=P0)
    for j, q in enumerate(qs):
        np.testing.assert_allclose(res.member_means[j], kf_run(q, ys, x0, P0).means, rtol=1e-10)
    np.testing.assert_allclose(res.means, kf_run(qs[0], ys, x0, P0).means, rtol=1e-10)
    np.testing.assert_allclose(res.mode_probs[:, 1], 0.0)


def manoeuvre(rng, T=80, switch=40):
    """1-D: speed 1, then at ``switch`` a jump to speed -3 (known switch time)."""
    v = np.where(np.arange(T) < switch, 1.0, -3.0)
    x = np.concatenate([[0.0], np.cumsum(v[1:])])
    return x, (x + rng.normal(size=T))[:, None]


def test_imm_beats_either_single_model_on_a_manoeuvring_target():
    Pi = [[0.97, 0.03], [0.03, 0.97]]
    err = {"smooth": [], "agile": [], "imm": []}
    prob_after = []
    for seed in range(20):
        x, ys = manoeuvre(np.random.default_rng(seed))
        x0, P0 = np.array([0.0, 1.0]), np.eye(2)
        for name, q in (("smooth", 1e-3), ("agile", 3.0)):
            err[name].append(kf_run(q, ys, x0, P0).means[:, 0] - x)
        res = IMMFilter([cv(1e-3), cv(3.0)], Pi).filter(ys, x0=x0, P0=P0)
        err["imm"].append(res.means[:, 0] - x)
        prob_after.append(res.mode_probs[40:46, 1].max())
    rmse = {k: np.sqrt(np.mean(np.square(v))) for k, v in err.items()}
    assert rmse["imm"] < rmse["smooth"] and rmse["imm"] < rmse["agile"], rmse
    assert np.mean(prob_after) > 0.9  # the agile model takes over right after the switch


def test_members_of_different_sizes_give_no_lag_and_smooth_when_still():
    """The seed's P vs PV example: a target that stands, walks, stands."""
    P_model = ExtendedKalmanFilter(vt.ConstantPosition(dim=1, q=1e-4), vt.Position(dim=1, r=0.05))
    PV_model = ExtendedKalmanFilter(vt.ConstantVelocity(dim=1, q=0.05), vt.Position(dim=1, r=0.05))
    v = np.r_[np.zeros(40), np.full(40, 0.5), np.zeros(40)]
    x = np.cumsum(v)
    still, moving = np.r_[10:40, 90:120], np.r_[50:80]
    errs = {"P": [], "PV": [], "imm": []}
    p_still, p_moving = [], []
    for seed in range(10):
        ys = (x + np.random.default_rng(seed).normal(scale=np.sqrt(0.05), size=len(x)))[:, None]
        imm = IMMFilter([P_model, PV_model], [[0.95, 0.05], [0.05, 0.95]])
        res = imm.filter(ys, x0=[0.0, 0.0], P0=np.eye(2))
        p = res.mode_probs[:, 0]
        p_still.append(p[still].mean())
        p_moving.append(p[moving].mean())
        errs["imm"].append(res.means[:, 0] - x)
        errs["P"].append(res.member_means[0][:, 0] - x)
        errs["PV"].append(res.member_means[1][:, 0] - x)
    assert np.mean(p_still) > 0.6 and np.mean(p_moving) < 0.2
    rms = {k: np.sqrt(np.mean(np.square(np.array(e)), axis=0)) for k, e in errs.items()}
    assert rms["imm"][moving].mean() < 0.7 * rms["P"][moving].mean()  # no lag
    assert rms["imm"][still].mean() < rms["PV"][still].mean()  # smooth when still


def test_log_domain_probabilities_survive_an_outlier(rng):
    """A measurement 1e6 standard deviations away has likelihood exp(-5e11) under both
    models: 0 in floating point. In the log domain the probabilities stay defined."""
    x, ys = manoeuvre(rng, T=20)
    ys[10] = 1e6
    res = IMMFilter([cv(1e-3), cv(3.0)], [[0.9, 0.1], [0.1, 0.9]]).filter(
        ys, x0=[0.0, 1.0], P0=np.eye(2))
    assert np.all(np.isfinite(res.mode_probs))
    np.testing.assert_allclose(res.mode_probs.sum(-1), 1.0, rtol=1e-12)
    assert res.mode_probs[10, 1] > 0.999  # the wide model explains the jump far better


def test_nonlinear_members_with_different_state_sizes(rng):
    """Coordinated turn (UKF, 5 states) and constant velocity (EKF, 4 states) from range and
    bearing: the turn model gains probability during a turn."""
    ct = vt.models.CoordinatedTurn(q=0.01, q_turn=1e-4)
    rb = vt.models.RangeBearing(0.25, 1e-5, sensor=(0.0, -50.0), ndim_state=5)
    x = np.array([0.0, 0.0, 1.0, 0.0, 0.0])
    states = []
    for t in range(90):
        x = x.copy()
        x[4] = 0.15 if 30 <= t < 50 else 0.0
        states.append(x)
        x = ct.f(x, 1.0)
    states = np.array(states)
    ys = rb.h(states) + rng.normal(size=(90, 2)) * np.sqrt([0.25, 1e-5])
    members = [UnscentedKalmanFilter(ct, rb),
               ExtendedKalmanFilter(vt.ConstantVelocity(dim=2, q=0.01),
                                    vt.models.RangeBearing(0.25, 1e-5, sensor=(0.0, -50.0)))]
    res = IMMFilter(members, [[0.95, 0.05], [0.05, 0.95]]).filter(
        ys, x0=[0.0, 0.0, 1.0, 0.0, 0.0], P0=np.diag([1.0, 1.0, 0.1, 0.1, 0.01]))
    assert res.means.shape == (90, 5) and res.member_means[1].shape == (90, 4)
    p_turn = res.mode_probs[:, 0]
    assert p_turn[35:50].mean() > p_turn[5:30].mean() + 0.2
    assert np.sqrt(np.mean(np.sum((res.means[:, :2] - states[:, :2]) ** 2, 1))) < 2.0


@pytest.mark.parametrize(
    "transition, kwargs, match",
    [
        ([[0.9, 0.2], [0.1, 0.9]], {}, r"rows sum to 1; got shape \(2, 2\) and row sums \[1.1, "),
        ([[1.0]], {}, r"transition must be a \(2, 2\) non-negative matrix whose rows sum to 1; "
                      r"got shape \(1, 1\)"),
        ([[0.9, 0.1], [0.1, 0.9]], {"mode_probs": [0.5, 0.6]}, "mode_probs must be 2"),
        # NaN passed the checks (NaN < 0 and |NaN - 1| > 1e-9 are both False)
        ([[0.9, 0.1], [0.1, 0.9]], {"mode_probs": [0.5, np.nan]},
         r"mode_probs must be finite; mode_probs\[1\] = nan"),
        ([[0.9, 0.1], [0.1, 0.9]], {"mode_probs": [np.nan, np.nan]},
         r"mode_probs must be finite; mode_probs\[0\] = nan"),
        ([[0.9, 0.1], [0.1, 0.9]], {"mode_probs": [np.inf, 0.0]},
         r"mode_probs must be finite; mode_probs\[0\] = inf"),
        ([[0.9, np.nan], [0.1, 0.9]], {}, r"transition must be finite; transition\[0, 1\] = nan"),
    ],
)
def test_bad_arguments_raise(transition, kwargs, match):
    with pytest.raises(ValueError, match=match):
        IMMFilter([cv(0.1), cv(1.0)], transition, **kwargs)


def test_masked_measurements_are_missing():
    """A numpy masked array's masked entries are missing, as NaN (the documented convention);
    before, the values under the mask were measured."""
    _, ys = vt.simulate.simulate(vt.ConstantVelocity(dim=2, q=0.3), vt.Position(dim=2), 30,
                                 x0=[0.0, 0.0, 1.0, 0.5], rng=3)
    mask = np.zeros(ys.shape, bool)
    mask[[4, 11, 12]] = True
    mask[20, 1] = True
    masked = np.ma.masked_array(np.where(mask, 1e6, ys), mask=mask)
    nan = np.where(mask, np.nan, ys)
    imm = IMMFilter([cv(0.1, dim=2), cv(3.0, dim=2)], [[0.95, 0.05], [0.05, 0.95]])
    kw = dict(x0=[0.0, 0.0, 1.0, 0.5], P0=np.eye(4))
    a, b = imm.filter(masked, **kw), imm.filter(nan, **kw)
    np.testing.assert_array_equal(a.means, b.means)
    np.testing.assert_array_equal(a.mode_probs, b.mode_probs)
    assert np.abs(a.means[:, :2] - ys).max() < 10
    # a prior has no missing value: a masked entry is named, not carried as NaN
    x0 = np.ma.masked_array([0.0, 0.0, 1.0, 0.5], mask=[0, 0, 1, 0])
    with pytest.raises(ValueError, match=r"x0 must not have masked entries .*; x0\[2\] is masked"):
        imm.filter(nan, x0=x0, P0=np.eye(4))


def test_zero_likelihood_everywhere_is_reported():
    class Never(ExtendedKalmanFilter):
        def update(self, g, y):
            return g, np.full(np.shape(y)[:-1], -np.inf)

    bad = Never(vt.ConstantVelocity(dim=1), vt.Position(dim=1))
    with pytest.raises(ValueError,
                       match="zero likelihood to the measurement of series 0 at step 0"):
        IMMFilter([bad, bad], np.eye(2)).filter(np.ones((3, 1)), x0=[0.0, 0.0], P0=np.eye(2))


def test_a_batch_of_series_equals_each_series_alone(rng):
    members = [cv(1e-3), cv(3.0)]
    Pi = [[0.97, 0.03], [0.03, 0.97]]
    ys = np.stack([manoeuvre(np.random.default_rng(s), T=30, switch=15)[1] for s in range(3)])
    ys[1, 4] = np.nan
    x0 = rng.normal(size=(3, 2))
    batch = IMMFilter(members, Pi).filter(ys, x0=x0, P0=np.eye(2))
    for b in range(3):
        one = IMMFilter(members, Pi).filter(ys[b], x0=x0[b], P0=np.eye(2))
        np.testing.assert_allclose(batch.means[b], one.means, rtol=1e-10, atol=1e-12)
        np.testing.assert_allclose(batch.mode_probs[b], one.mode_probs, rtol=1e-10, atol=1e-14)
        assert batch.loglik[b] == pytest.approx(float(one.loglik), rel=1e-12)


def test_p_vs_pv_on_a_real_pedestrian_who_stands_and_walks():
    """PETS09-S2L1 person 15 walks in, stands about 6 s, edges forward, stands 3 s more and
    walks off (MOT15 annotations, 7 frames/s):
    the position-only model's probability is high while the annotated speed is below 3 px/s
    and low above 15 px/s (measured: 0.93 and 0.03). examples/mm_pets09.py draws it."""
    from vistrack.io import read_mot

    from .conftest import SHARED

    path = SHARED / "data" / "mot15" / "PETS09-S2L1" / "gt" / "gt.txt"
    if not path.exists():
        pytest.skip(f"{path} not found: the shared data is not beside this checkout")
    t = read_mot(path)
    t = t[t.ids == 15]
    c = t.boxes[:, :2] + t.boxes[:, 2:] / 2
    step = np.linalg.norm(np.diff(c, axis=0), axis=1) * 7.0
    ones = np.ones(5)  # a 5-frame mean, over the frames there at the ends
    speed = (np.convolve(np.r_[step[0], step], ones, mode="same")
             / np.convolve(np.ones(len(c)), ones, mode="same"))
    P = ExtendedKalmanFilter(vt.ConstantPosition(dim=2, q=1.0), vt.Position(dim=2, r=4.0))
    PV = ExtendedKalmanFilter(vt.ConstantVelocity(dim=2, q=400.0), vt.Position(dim=2, r=4.0))
    res = IMMFilter([P, PV], [[0.95, 0.05], [0.05, 0.95]]).filter(
        c, x0=np.r_[c[0], 0, 0], P0=np.diag([25, 25, 400, 400.0]), dt=1 / 7)
    p = res.mode_probs[:, 0]
    assert (speed < 3).sum() > 40 and (speed > 15).sum() > 60
    assert p[speed < 3].mean() > 0.85 and p[speed > 15].mean() < 0.1


def test_a_member_s_nan_log_likelihood_is_named_and_loglik_is_read_only():
    """One member's NaN log-likelihood was reported as "every model gives zero likelihood"
    (the other's was finite); `IMMResult.loglik` was writable where the docstring says every
    array is read-only. Oracle: the member that gave NaN, and the docstring."""
    import re

    from vistrack.filters import ExtendedKalmanFilter, IMMFilter

    class NaNLL(ExtendedKalmanFilter):
        def update(self, g, y):
            g2, ll = super().update(g, y)
            return g2, np.full(np.shape(ll), np.nan)

    good = ExtendedKalmanFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1))
    bad = NaNLL(vt.ConstantVelocity(dim=1, q=1.0), vt.Position(dim=1))
    with pytest.raises(ValueError, match=re.escape(
            "filters[1] gave a log-likelihood of NaN for the measurement of series 0 at "
            "step 0")):
        IMMFilter([good, bad], [[0.9, 0.1], [0.1, 0.9]]).filter(np.ones((3, 1)), x0=[0, 0],
                                                                  P0=np.eye(2))
    imm = IMMFilter([good, ExtendedKalmanFilter(vt.ConstantVelocity(dim=1, q=1.0),
                                                vt.Position(dim=1))], [[0.9, 0.1], [0.1, 0.9]])
    for ys in (np.ones((3, 1)), np.ones((2, 3, 1))):
        res = imm.filter(ys, x0=[0, 0], P0=np.eye(2))
        with pytest.raises(ValueError, match="read-only"):
            res.loglik[...] = 0.0


def test_kalman_members_run_compiled_and_equal_the_steps_from_python(monkeypatch):
    """Members that are Kalman filters of linear models (`KalmanFilter`, or
    `ExtendedKalmanFilter` of linear models) run the whole IMM in one compiled call
    (`_mix`, the steps from Python, made to fail here). Oracle: the same IMM of members
    whose own update runs the steps from Python, to 1e-10: members of one size and of two
    (a position-only model beside constant velocity), components missing, a step missing
    whole, uneven steps, a batch with a prior each, a model of probability 0."""
    import vistrack.filters.imm as imm_module
    from vistrack.filters import KalmanFilter

    rng = np.random.default_rng(4)
    T = 60
    ys = np.cumsum(rng.normal(0, 1, (T, 2)), 0)
    ys[::7, 1] = np.nan
    ys[10] = np.nan
    dt = np.r_[1.0, rng.uniform(0.2, 1.5, T - 1)]
    cp, cvs, cvf = (vt.ConstantPosition(dim=2, q=1.0), vt.ConstantVelocity(dim=2, q=0.01),
                    vt.ConstantVelocity(dim=2, q=10.0))
    pos, loose = vt.Position(dim=2, r=1.0), vt.Position(dim=2, r=4.0)
    x0, P0 = np.zeros(4), np.eye(4) * 10
    Pi = [[0.97, 0.03], [0.03, 0.97]]
    batch = np.stack([ys, ys + 1.0, ys * 0.5])
    cases = []
    for cls in (KalmanFilter, ExtendedKalmanFilter):
        cases += [([cls(cvs, pos), cls(cvf, loose)], Pi, {}, ys, dict(x0=x0, P0=P0)),
                  ([cls(cp, pos), cls(cvf, pos)], Pi, {}, ys, dict(x0=x0, P0=P0, dt=dt)),
                  ([cls(cp, pos), cls(cvs, pos), cls(cvf, pos)],
                   [[0.9, 0.05, 0.05], [0.05, 0.9, 0.05], [0.05, 0.05, 0.9]], {}, batch,
                   dict(x0=np.stack([x0, x0 + 1, x0 - 1]), P0=P0, dt=0.5)),
                  ([cls(cvs, pos), cls(cvf, pos)], np.eye(2), dict(mode_probs=[1.0, 0.0]),
                   ys, dict(x0=x0, P0=P0))]
    got = []
    with monkeypatch.context() as m:
        def no_python(*args, **kwargs):
            raise AssertionError("the IMM's steps from Python")

        m.setattr(imm_module, "_mix", no_python)
        for members, Pi_, kw, y, prior in cases:
            got.append(IMMFilter(members, Pi_, **kw).filter(y, **prior))
    for (members, Pi_, kw, y, prior), res in zip(cases, got):
        slow = [_python_steps(type(f))(f.motion if isinstance(f, KalmanFilter)
                                       else f.motion.model,
                                       f.measurement if isinstance(f, KalmanFilter)
                                       else f.measurement.model) for f in members]
        want = IMMFilter(slow, Pi_, **kw).filter(y, **prior)
        for name in ("means", "covs", "mode_probs"):
            np.testing.assert_allclose(getattr(res, name), getattr(want, name), rtol=1e-10,
                                       atol=1e-11)
            assert not getattr(res, name).flags.writeable
        for a, b in zip(res.member_means, want.member_means):
            np.testing.assert_allclose(a, b, rtol=1e-10, atol=1e-11)
        np.testing.assert_allclose(res.loglik, want.loglik, rtol=1e-11)


def test_compiled_imm_equals_filterpy_s_imm_estimator():
    """FilterPy's IMMEstimator (its Kalman filters given the models' matrices) as an
    independent oracle of the compiled IMM: the combined means and covariances and the mode
    probabilities, step by step, on a target that walks, stands and runs."""
    from filterpy.kalman import IMMEstimator
    from filterpy.kalman import KalmanFilter as FilterPyKF

    from vistrack.filters import KalmanFilter

    rng = np.random.default_rng(2)
    v = np.r_[np.full(30, 1.0), np.zeros(30), np.full(30, -4.0)]
    x = np.cumsum(v)
    ys = np.column_stack([x, 0.5 * x]) + rng.normal(0, 1.0, (90, 2))
    slow, fast, pos = (vt.ConstantVelocity(dim=2, q=0.01), vt.ConstantVelocity(dim=2, q=5.0),
                       vt.Position(dim=2, r=1.0))
    Pi = np.array([[0.95, 0.05], [0.1, 0.9]])
    x0, P0 = np.zeros(4), np.eye(4) * 4.0
    res = IMMFilter([KalmanFilter(slow, pos), KalmanFilter(fast, pos)], Pi).filter(
        ys, x0=x0, P0=P0)
    members = []
    for model in (slow, fast):
        k = FilterPyKF(dim_x=4, dim_z=2)
        k.F, k.Q, k.H, k.R = model.F(1.0), model.Q(1.0), pos.H(4), pos.R()
        k.x, k.P = x0.copy(), P0.copy()
        members.append(k)
    # FilterPy weighs the first measurement by mu Π (vistrack by the first step's prior, the
    # mode probabilities given): its mu is the one that mu Π makes uniform
    est = IMMEstimator(members, np.linalg.solve(Pi.T, [0.5, 0.5]), Pi)
    for t, y in enumerate(ys):
        if t:  # (the first step's prior is x0, P0)
            est.predict()
        est.update(y)
        np.testing.assert_allclose(res.means[t], est.x, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(res.covs[t], est.P, rtol=1e-9, atol=1e-9)
        np.testing.assert_allclose(res.mode_probs[t], est.mu, rtol=1e-9, atol=1e-12)


def test_compiled_imm_names_what_it_cannot_take_as_the_steps_from_python():
    """What the compiled IMM cannot take is filtered again from Python, which names it as
    before: a measurement every model gives zero likelihood (an outlier of 1e200), a motion
    model whose matrix is not finite."""
    from vistrack.filters import KalmanFilter

    pos = vt.Position(dim=1, r=1.0)
    members = [KalmanFilter(vt.ConstantVelocity(dim=1, q=q), pos) for q in (0.01, 1.0)]
    slow = [_python_steps(KalmanFilter)(f.motion, pos) for f in members]
    ys = np.array([[0.0], [1.0], [1e200], [3.0]])
    for y in (ys,):
        with pytest.raises(ValueError) as want:
            IMMFilter(slow, np.eye(2)).filter(y, x0=[0.0, 0.0], P0=np.eye(2))
        with pytest.raises(ValueError) as got:
            IMMFilter(members, np.eye(2)).filter(y, x0=[0.0, 0.0], P0=np.eye(2))
        assert str(got.value) == str(want.value)
        assert "zero likelihood" in str(got.value)

    class Broken(vt.ConstantVelocity):
        def F(self, dt=1.0):
            return super().F(dt) * np.nan

    bad = [KalmanFilter(Broken(dim=1, q=0.1), pos), members[1]]
    with pytest.raises(ValueError) as want:
        IMMFilter([_python_steps(KalmanFilter)(f.motion, pos) for f in bad], np.eye(2)
                  ).filter(ys[:2], x0=[0.0, 0.0], P0=np.eye(2))
    with pytest.raises(ValueError) as got:
        IMMFilter(bad, np.eye(2)).filter(ys[:2], x0=[0.0, 0.0], P0=np.eye(2))
    assert str(got.value) == str(want.value)


def test_compiled_imm_takes_its_members_as_their_steps_do(monkeypatch):
    """The compiled IMM takes each member's models as the member's own steps take them, and
    leaves to those steps what they refuse: a patch of `KalmanFilter.update` made before
    the first IMM is called (it was taken for the class's own, and never called); an EKF of
    a linear measurement model without `ndim_meas` (AttributeError); an EKF's `Q` with a
    negative eigenvalue (filtered where its steps refuse it); matrices of the wrong shape
    (broadcast into the kernel's blocks, where the steps name them); an EKF's `R` as it
    kept it when it was made, not the model's changed since. Oracle: the same members
    whose own update runs the steps from Python."""
    from vistrack.filters import KalmanFilter

    ys = np.c_[np.r_[np.zeros(10), np.arange(1.0, 11.0)]]
    Pi = [[0.95, 0.05], [0.05, 0.95]]
    prior = dict(x0=[0.0, 0.0], P0=np.eye(2))

    def same(make, classes=(KalmanFilter, ExtendedKalmanFilter)):
        def run(cls):
            try:
                return IMMFilter(make(cls), Pi).filter(ys, **prior)
            except (ValueError, AttributeError) as e:
                return f"{type(e).__name__}: {e}"

        for cls in classes:
            got, want = run(cls), run(_python_steps(cls))
            if isinstance(want, str):
                assert got == want
            else:
                np.testing.assert_allclose(got.means, want.means, rtol=1e-10, atol=1e-12)
                np.testing.assert_allclose(got.mode_probs, want.mode_probs, rtol=1e-10,
                                           atol=1e-12)

    class PositionOnly:  # linear, no ndim_meas
        def H(self, n):
            return np.eye(1, n)

        def R(self):
            return np.array([[0.1]])

    class NotPSD(vt.ConstantPosition):
        def Q(self, dt=1.0):
            return np.array([[0.0, 0.3], [0.3, 0.0]]) + super().Q(dt)

    class ScalarQ:
        ndim_state = 1

        def F(self, dt):
            return np.eye(1)

        def Q(self, dt):
            return 0.1 * dt

    class FlatH(PositionOnly):
        ndim_meas = 1

        def H(self, n):
            return np.eye(1, n)[0]

    cp, cv_ = vt.ConstantPosition(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=0.01)
    pos = vt.Position(dim=1, r=0.1)
    same(lambda cls: [cls(cp, PositionOnly()), cls(cv_, PositionOnly())],
         (ExtendedKalmanFilter,))  # (a KalmanFilter asks for ndim_meas)
    same(lambda cls: [cls(NotPSD(dim=2, q=0.01), vt.Position(dim=2, r=0.1))])
    same(lambda cls: [cls(ScalarQ(), pos), cls(cv_, pos)])
    same(lambda cls: [cls(cp, FlatH()), cls(cv_, FlatH())])

    class Mutable(PositionOnly):
        ndim_meas = 1
        r = 0.1

        def R(self):
            return np.array([[self.r]])

    def changed_after(cls):
        sensor = Mutable()
        members = [cls(cp, sensor), cls(cv_, sensor)]
        sensor.r = 25.0
        return members

    same(changed_after, (ExtendedKalmanFilter,))  # (a KalmanFilter asks R each step)
    calls = []
    original = KalmanFilter.update

    def counted(self, g, y):
        calls.append(1)
        return original(self, g, y)

    monkeypatch.setattr(KalmanFilter, "update", counted)
    IMMFilter([KalmanFilter(cp, pos), KalmanFilter(cv_, pos)], Pi).filter(ys, **prior)
    assert len(calls) == 2 * len(ys)
