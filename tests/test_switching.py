"""Switching linear dynamic systems: sampling, and estimation by the Rao-Blackwellised particle
filter and the IMM against the exact posterior, enumerated over every mode sequence."""

import itertools
import re

import numpy as np
import pytest

import vistrack as vt
from vistrack.filters import IMMFilter, SwitchingParticleFilter, kalman_filter
from vistrack.models import SwitchingLinearSystem


def make_system():
    return SwitchingLinearSystem(
        [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=5.0)],
        vt.Position(dim=1, r=0.5), [[0.9, 0.1], [0.3, 0.7]], mode_probs=[0.6, 0.4])


def exact_posterior(slds, ys, x0, P0):
    """p(x_T, z_T | y) by enumerating all k^T mode sequences, each a Kalman filter."""
    k, T = len(slds.motions), len(ys)
    H, R = slds.measurement.H(2), slds.measurement.R()
    logs, means, covs, last = [], [], [], []
    logPi = np.log(slds.transition)
    for seq in itertools.product(range(k), repeat=T):
        prior = np.log(slds.mode_probs[seq[0]]) + sum(logPi[a, b] for a, b in zip(seq, seq[1:]))
        F = np.stack([slds.motions[z].F(1.0) for z in seq])
        Q = np.stack([slds.motions[z].Q(1.0) for z in seq])
        res = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0)
        logs.append(prior + float(res.loglik))
        means.append(res.means[-1])
        covs.append(res.covs[-1])
        last.append(seq[-1])
    logs = np.array(logs)
    w = np.exp(logs - logs.max())
    w /= w.sum()
    mean = w @ np.array(means)
    d = np.array(means) - mean
    cov = np.einsum("s,sij->ij", w, np.array(covs) + d[:, :, None] * d[:, None, :])
    probs = np.bincount(last, weights=w, minlength=k)
    loglik = logs.max() + np.log(np.exp(logs - logs.max()).sum())
    return mean, cov, probs, loglik


def test_sampling_follows_the_switching_matrix():
    slds = make_system()
    zs, xs, ys = slds.sample(20_000, x0=[0.0, 0.0], rng=1)
    counts = np.zeros((2, 2))
    np.add.at(counts, (zs[:-1], zs[1:]), 1)
    np.testing.assert_allclose(counts / counts.sum(1, keepdims=True), slds.transition, atol=0.015)
    # velocity changes are N(0, q) per mode (white-noise acceleration, dt = 1: var q)
    dv = np.diff(xs[:, 1])
    for j, q in enumerate((0.01, 5.0)):
        assert np.var(dv[zs[1:] == j]) == pytest.approx(q, rel=0.05)


def test_rbpf_and_imm_against_the_exact_posterior():
    slds = make_system()
    T = 8
    zs, xs, ys = slds.sample(T, x0=[0.0, 1.0], rng=4)
    ys[3] = np.nan
    x0, P0 = np.array([0.0, 1.0]), np.eye(2)
    mean, cov, probs, loglik = exact_posterior(slds, ys, x0, P0)
    rb = SwitchingParticleFilter(slds, n_particles=20_000, rng=5).filter(ys, x0=x0, P0=P0)
    sd = np.sqrt(np.diag(cov))
    # Monte Carlo error with 20,000 particles (effective size >= ~5,000): ~0.015 sd
    assert np.all(np.abs(rb.means[-1] - mean) < 0.06 * sd)
    np.testing.assert_allclose(rb.covs[-1], cov, rtol=0.05)
    np.testing.assert_allclose(rb.mode_probs[-1], probs, atol=0.02)
    assert rb.loglik == pytest.approx(loglik, abs=0.05)


def test_imm_is_near_the_exact_posterior_and_nearer_than_either_model_alone():
    """The IMM merges the k^T Gaussians into k at every step: an approximation, whose error
    depends on the draw (on one draw its mode probability was 0.126 from the exact one, on
    another 0.003). Over 40 draws of 8 steps its last mean lies on average within 0.3 of the
    exact posterior's standard deviation on each state (0.20 and 0.14 measured), nearer than
    the Kalman filter of either mode alone (0.36 and 0.55 for the better on each), and its
    mode probability within 0.1 (0.05 measured)."""
    slds = make_system()
    H, R = slds.measurement.H(2), slds.measurement.R()
    x0, P0 = np.array([0.0, 1.0]), np.eye(2)
    err_imm, err_alone, err_prob = [], [], []
    for seed in range(40):
        _, _, ys = slds.sample(8, x0=[0.0, 1.0], rng=seed)
        ys[3] = np.nan
        mean, cov, probs, _ = exact_posterior(slds, ys, x0, P0)
        sd = np.sqrt(np.diag(cov))
        imm = IMMFilter.from_system(slds).filter(ys, x0=x0, P0=P0)
        err_imm.append(np.abs(imm.means[-1] - mean) / sd)
        err_prob.append(np.abs(imm.mode_probs[-1] - probs).max())
        err_alone.append([np.abs(kalman_filter(ys, F=m.F(1.0), Q=m.Q(1.0), H=H, R=R, x0=x0,
                                               P0=P0).means[-1] - mean) / sd
                          for m in slds.motions])
    imm_mean, alone_mean = np.mean(err_imm, axis=0), np.mean(err_alone, axis=0)
    assert np.all(imm_mean < 0.3), imm_mean
    assert np.all(imm_mean < alone_mean.min(axis=0)), (imm_mean, alone_mean)
    assert np.mean(err_prob) < 0.1


def test_result_arrays_are_read_only_as_the_imms():
    """SwitchingResult's arrays are read-only, as IMMResult's and kalman_filter's."""
    slds = make_system()
    _, _, ys = slds.sample(20, x0=[0.0, 1.0], rng=2)
    res = SwitchingParticleFilter(slds, n_particles=50, rng=3).filter(ys, x0=[0.0, 1.0],
                                                                      P0=np.eye(2))
    imm = IMMFilter.from_system(slds).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    assert not imm.means.flags.writeable and not imm.mode_probs.flags.writeable
    for name in ("means", "covs", "mode_probs", "ess"):
        a = getattr(res, name)
        assert not a.flags.writeable, name
        with pytest.raises(ValueError, match="read-only"):
            a[...] = 0


def test_bad_systems_raise():
    cv, ca = vt.ConstantVelocity(dim=1), vt.ConstantAcceleration(dim=1)
    with pytest.raises(ValueError, match=r"motions must share one state size; got sizes \[2, 3\]"):
        SwitchingLinearSystem([cv, ca], vt.Position(dim=1), np.eye(2))
    with pytest.raises(ValueError, match="rows sum to 1"):
        SwitchingLinearSystem([cv, cv], vt.Position(dim=1), [[0.5, 0.6], [0.5, 0.5]])


@pytest.mark.parametrize("transition, mode_probs, match", [
    ([[0.9, 0.1], [0.3, 0.7]], [0.5, np.nan], r"mode_probs must be finite; mode_probs\[1\] = nan"),
    ([[0.9, 0.1], [0.3, 0.7]], [np.nan, np.nan], r"mode_probs\[0\] = nan"),
    ([[0.9, 0.1], [0.3, 0.7]], [np.inf, 0.0], r"mode_probs must be finite; mode_probs\[0\] = inf"),
    ([[0.9, 0.1], [np.nan, 0.7]], None, r"transition must be finite; transition\[1, 0\] = nan"),
])
def test_a_nan_probability_is_named(transition, mode_probs, match):
    """NaN mode_probs were accepted (NaN < 0 and |NaN - 1| > 1e-9 are both False): sample()
    then failed in numpy ("Probabilities contain NaN") and the IMM built from the system
    reported zero likelihood at step 0. The documented contract: finite non-negative
    probabilities summing to one, a bad one named."""
    cv = vt.ConstantVelocity(dim=1)
    with pytest.raises(ValueError, match=match):
        SwitchingLinearSystem([cv, cv], vt.Position(dim=1), transition, mode_probs=mode_probs)


@pytest.mark.parametrize("P0, match", [
    ([[1.0, 0.0], [0.0, -1.0]],
     r"^P0 must be positive semi-definite; P0\[1, 1\] = -1, a negative variance$"),
    (np.eye(3), r"^P0 must have shape \(2, 2\); got \(3, 3\)$"),
    ([[1.0, np.nan], [np.nan, 1.0]], r"^P0 must be finite; P0\[0, 1\] = nan$"),
])
def test_sample_names_a_bad_prior(P0, match):
    """A prior covariance that cannot be sampled is refused with ``P0`` named (numpy's
    ``multivariate_normal`` only warned of an indefinite one, and drew from it)."""
    with pytest.raises(ValueError, match=match):
        make_system().sample(3, x0=[0.0, 1.0], P0=P0)


def test_sample_with_a_prior_spreads_the_first_state_by_it():
    """The first state is ``x0`` plus noise of covariance ``P0`` (over 4,000 draws, within
    their sampling error), ``P0`` singular along one direction included."""
    slds = make_system()
    P0 = np.array([[4.0, 2.0], [2.0, 1.0]])  # rank one: the velocity half the position
    first = np.array([slds.sample(1, x0=[1.0, 2.0], P0=P0, rng=s)[1][0] for s in range(4000)])
    np.testing.assert_allclose(first.mean(axis=0), [1.0, 2.0], atol=4 * np.sqrt(4.0 / 4000))
    np.testing.assert_allclose(np.cov(first.T), P0, rtol=0.1, atol=1e-12)
    np.testing.assert_allclose(first[:, 1] - 2.0, 0.5 * (first[:, 0] - 1.0), atol=1e-12)


@pytest.mark.parametrize("row", [[0.99999, 0.0], [0.5, 0.50001]])
def test_transition_rows_off_one_by_1e_5_are_refused(row):
    """The rows' check kept numpy's relative tolerance of 1e-5 beside its absolute 1e-9: a
    row of 0.99999 was taken, the particle filter gave the unreachable mode a probability up
    to 3.8e-5, and ``sample`` then refused the same matrix (numpy's own check)."""
    from vistrack.models import ConstantVelocity, Position

    Pi = np.array([row, [0.0, 1.0]])
    cv, pos = ConstantVelocity(dim=1, q=0.1), Position(dim=1)
    with pytest.raises(ValueError, match="transition must be a \\(2, 2\\) non-negative matrix"):
        SwitchingLinearSystem([cv, cv], pos, Pi)
    kf = vt.filters.KalmanFilter(cv, pos)
    with pytest.raises(ValueError, match="transition must be a \\(2, 2\\) non-negative matrix"):
        IMMFilter([kf, kf], Pi)
    SwitchingLinearSystem([cv, cv], pos, [[1 - 1e-10, 1e-10], [0.0, 1.0]])  # within 1e-9


class _TopUniforms:
    """numpy's generator, except that every uniform is its largest, 1 - 2**-53."""

    def __init__(self, seed):
        self._g = np.random.default_rng(seed)

    def random(self, size=None):
        return 1.0 - 2.0**-53 if size is None else np.full(size, 1.0 - 2.0**-53)

    def __getattr__(self, name):
        return getattr(self._g, name)


def test_a_mode_of_probability_zero_is_never_drawn():
    """Rows within the system's 1e-9 of summing to 1 can sum below it: a row (0.7, 0.3 -
    1e-12, 0) has cumulative sums that end at 1 - 1e-12, and a uniform above that went to the
    last mode, of probability 0 (so did the first draw from mode_probs). With every uniform
    the largest numpy gives, no particle may be in mode 2 at any step: its probability there
    is exactly 0 (the exact posterior's, as the mode cannot be entered)."""
    cv = vt.ConstantVelocity(dim=1, q=0.1)
    Pi = [[0.7, 0.3 - 1e-12, 0.0], [0.4, 0.6 - 1e-12, 0.0], [0.5, 0.5, 0.0]]
    slds = SwitchingLinearSystem([cv, cv, cv], vt.Position(dim=1), Pi,
                                 mode_probs=[0.5, 0.5 - 1e-12, 0.0])
    ys = np.arange(6.0)[:, None]
    f = SwitchingParticleFilter(slds, n_particles=20, rng=0)
    f.rng = _TopUniforms(0)
    res = f.filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    assert (res.mode_probs[:, 2] == 0).all(), res.mode_probs
    np.testing.assert_allclose(res.mode_probs.sum(1), 1.0)


def test_an_ess_threshold_of_one_resamples_at_every_step_as_the_particle_filter():
    """``ess_threshold=1`` resamples at every step, as ParticleFilter's docstring says and it
    does; the switching filter compared ``ess < N``, so at equal weights (step 0 has no
    measurement: ESS = N) it did not. The resampler's calls are counted."""
    slds = make_system()
    _, _, ys = slds.sample(8, x0=[0.0, 1.0], rng=2)
    ys[0] = np.nan
    calls = []

    def counting(w, n, rng):
        calls.append(len(w))
        return np.arange(n)  # every particle once: the filter's estimates are unchanged

    f = SwitchingParticleFilter(slds, n_particles=30, rng=3, ess_threshold=1.0)
    f.resample = counting
    f.filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    assert calls == [30] * 8
    calls.clear()
    f = SwitchingParticleFilter(slds, n_particles=30, rng=3, ess_threshold=0.0)
    f.resample = counting
    f.filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    assert calls == []


def test_a_measurement_no_particle_can_explain_is_named_as_the_imm_names_it():
    """A finite measurement every model gives zero likelihood (1e200 for a walker near 5):
    IMMFilter names it, where the switching particle filter's weights became NaN from that
    step on (NaN means, mode probabilities and log-likelihood) with only a RuntimeWarning."""
    slds = SwitchingLinearSystem([vt.ConstantVelocity(dim=1, q=0.01),
                                  vt.ConstantVelocity(dim=1, q=4.0)],
                                 vt.Position(dim=1, r=0.5), [[0.95, 0.05], [0.2, 0.8]])
    ys = np.arange(10.0)[:, None]
    ys[5] = 1e200
    with pytest.raises(ValueError, match="zero likelihood to the measurement of series 0 at "
                                         "step 5"):
        IMMFilter.from_system(slds).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    with pytest.raises(ValueError, match="every particle gives zero likelihood to the "
                                         "measurement at step 5"):
        SwitchingParticleFilter(slds, n_particles=50, rng=0).filter(ys, x0=[0.0, 1.0],
                                                                    P0=np.eye(2))


def test_a_negative_transition_entry_is_named_not_its_rows_sums():
    """[[1.1, -0.1], [0, 1]] sums to 1 on each row: the message gave the row sums, [1.0,
    1.0], as if they were wrong; it names the negative entry now."""
    bad = [[1.1, -0.1], [0.0, 1.0]]
    cv = vt.ConstantVelocity(dim=1, q=0.1)
    with pytest.raises(ValueError, match=re.escape("transition[0, 1] = -0.1")):
        SwitchingLinearSystem([cv, cv], vt.Position(dim=1), bad)
    with pytest.raises(ValueError, match=re.escape("transition[0, 1] = -0.1")):
        IMMFilter([vt.KalmanFilter(cv, vt.Position(dim=1))] * 2, bad)


def test_a_switching_system_names_what_it_cannot_sample():
    """A NaN x0 without P0 gave NaN states and measurements, with numpy's warning alone; an
    array dt met numpy's broadcast error; a nonlinear motion or measurement was taken, and
    failed at sample() with "'CoordinatedTurn' object has no attribute 'F'"; a boolean
    transition or mode_probs was read as probabilities 1 and 0."""
    cv = vt.ConstantVelocity(dim=1, q=0.01)
    s = SwitchingLinearSystem([cv, cv], vt.Position(dim=1), [[0.9, 0.1], [0.1, 0.9]])
    with pytest.raises(ValueError, match=r"x0 must be finite"):
        s.sample(3, x0=[np.nan, np.inf], rng=0)
    with pytest.raises(ValueError, match=r"dt must be one time step, the same for every step"):
        s.sample(3, x0=[0.0, 1.0], dt=[1.0, 2.0, 1.0], rng=0)
    with pytest.raises(TypeError, match=r"motions\[0\] must be a linear motion model"):
        SwitchingLinearSystem([vt.models.CoordinatedTurn(), vt.models.CoordinatedTurn(q=4.0)],
                              vt.Position(dim=2), np.eye(2))
    with pytest.raises(TypeError, match=r"measurement must be a linear measurement model"):
        SwitchingLinearSystem([vt.ConstantVelocity(dim=2)] * 2,
                              vt.models.RangeBearing(ndim_state=4), np.eye(2))
    for kw in (dict(transition=[[True, False], [False, True]]),
               dict(transition=np.eye(2), mode_probs=[True, False])):
        with pytest.raises(TypeError, match=r"must be probabilities; got"):
            SwitchingLinearSystem([cv, cv], vt.Position(dim=1), **kw)
        with pytest.raises(TypeError, match=r"must be probabilities; got"):
            IMMFilter([vt.KalmanFilter(cv, vt.Position(dim=1))] * 2, **kw)
    # a good draw is as before: the first state exactly x0, the same seed the same draw
    zs, xs, ys = s.sample(5, x0=[0.0, 1.0], rng=3)
    np.testing.assert_array_equal(xs[0], [0.0, 1.0])
    np.testing.assert_array_equal(s.sample(5, x0=[0.0, 1.0], rng=3)[2], ys)
