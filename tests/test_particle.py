"""Particle filter: resampling schemes against their expected counts, the filter against the
Kalman filter on a linear model, log-domain weights, degeneracy, and the mode."""

import dataclasses
import gc
import hashlib
import re
import warnings
from pathlib import Path

import numpy as np
import pytest

import vistrack as vt
from vistrack.filters import (
    RESAMPLERS,
    ParticleDegeneracyError,
    ParticleFilter,
    _random,
    effective_sample_size,
    kalman_filter,
    particle_mode,
    resample,
    weighted_cov,
    weighted_mean,
)

W = np.array([0.3, 0.0, 0.05, 0.25, 1e-4, 0.1, 0.0999, 0.2])  # includes zero and tiny weights


@pytest.mark.parametrize("method", sorted(RESAMPLERS))
def test_resampling_is_unbiased(method):
    """Mean counts over 4000 draws equal N w within 5 standard errors (the standard error
    from the multinomial variance N w (1 - w), at least that of a count that is floor or ceil of
    N w, 1/4); zero weights are never drawn."""
    rng = np.random.default_rng(3)
    N, reps = 16, 4000
    counts = np.zeros((reps, len(W)))
    for r in range(reps):
        idx = resample(W, method, n=N, rng=rng)
        assert np.all(np.diff(idx) >= 0)  # sorted, as every scheme here returns them
        counts[r] = np.bincount(idx, minlength=len(W))
    expected = N * W
    se = np.sqrt(np.maximum(N * W * (1 - W), 0.25) / reps)
    assert np.all(np.abs(counts.mean(0) - expected) < 5 * se)
    assert np.all(counts[:, W == 0] == 0)


@pytest.mark.parametrize("method", ["systematic", "residual"])
def test_low_variance_schemes_keep_the_deterministic_part(method):
    rng = np.random.default_rng(4)
    for _ in range(200):
        w = rng.dirichlet(np.ones(30) * 0.5)
        c = np.bincount(resample(w, method, rng=rng), minlength=30)
        assert np.all(c >= np.floor(30 * w) - (method == "systematic"))
        if method == "systematic":  # each count is floor or ceil of N w (up to rounding)
            assert np.all(c <= np.ceil(30 * w) + 1)


@pytest.mark.parametrize("method", sorted(RESAMPLERS))
def test_a_batch_of_sets_is_resampled_as_each_set_alone(method):
    """Rows of ``(B, N)`` weights are resampled independently, drawing from the generator in
    row order: the same indices as one call per row; systematic rows draw particle ``i``
    ``N w_i`` times, within one."""
    rng = np.random.default_rng(0)
    w = rng.random((50, 37)) ** 3
    w[::7, ::3] = 0.0
    w /= w.sum(1, keepdims=True)
    got = resample(w, method, n=40, rng=11)
    g = np.random.default_rng(11)
    np.testing.assert_array_equal(got, np.stack([resample(r, method, n=40, rng=g) for r in w]))
    if method == "systematic":
        counts = np.stack([np.bincount(r, minlength=37) for r in resample(w, rng=1)])
        assert np.abs(counts - 37 * w).max() < 1.0 and (counts.sum(1) == 37).all()
    assert resample(np.zeros((0, 5)), method, rng=0).shape == (0, 5)


def test_resampling_arguments_are_checked():
    with pytest.raises(ValueError, match="weights must sum to 1; they sum to 0.9"):
        resample([0.5, 0.4])
    with pytest.raises(ValueError, match="weights must be finite and >= 0; got -0.1"):
        resample([1.1, -0.1])
    with pytest.raises(ValueError, match=r"method must be one of \['multinomial', 'residual', "):
        resample([1.0], "bogus")
    with pytest.raises(ValueError, match="n must be a whole number >= 1; got 0"):
        resample([1.0], n=0)
    with pytest.raises(ValueError, match="weights must sum to 1; row 1 sums to 0.5"):
        resample([[0.5, 0.5], [0.25, 0.25]])
    with pytest.raises(ValueError, match="weights must be 1-D or 2-D"):
        resample(np.ones((1, 1, 1)))


def linear_problem(rng, T=25):
    motion, meas = vt.ConstantVelocity(dim=1, q=0.2), vt.Position(dim=1, r=0.5)
    xs, ys = vt.simulate.simulate(motion, meas, T, x0=[0.0, 1.0], rng=rng)
    x0, P0 = np.array([0.0, 1.0]), np.diag([1.0, 0.25])
    F, Q, H, R = motion.F(1.0), motion.Q(1.0), meas.H(2), meas.R()
    return motion, meas, ys, x0, P0, kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0)


def test_particle_filter_mean_approaches_the_kalman_filter(rng):
    motion, meas, ys, x0, P0, kf = linear_problem(rng)
    sd = np.sqrt(np.diagonal(kf.covs, axis1=-2, axis2=-1))
    errs = {}
    for N in (300, 30_000):
        res = ParticleFilter(motion, meas, n_particles=N, rng=5).filter(ys, x0=x0, P0=P0)
        errs[N] = np.sqrt(np.mean(((res.means - kf.means) / sd) ** 2))
    # Monte Carlo error shrinks like 1/sqrt(N): 10 times here, allow a factor 4
    assert errs[30_000] < errs[300] / 4
    assert errs[30_000] < 0.03
    # the log-likelihood estimate is consistent too
    res = ParticleFilter(motion, meas, n_particles=30_000, rng=6).filter(ys, x0=x0, P0=P0)
    assert res.loglik == pytest.approx(float(kf.loglik), abs=0.5)


def test_log_domain_weights_survive_vanishing_likelihoods(rng):
    """A constant offset of -1e5 in every log-likelihood underflows exp() to 0 for every
    particle, but does not change normalised weights: the runs must match exactly."""
    motion, meas, ys, x0, P0, _ = linear_problem(rng, T=10)

    def loglik(y, x):
        return -0.5 * (y[0] - x[:, 0]) ** 2 / 0.5

    runs = [ParticleFilter(motion, lambda y, x, c=c: loglik(y, x) + c, n_particles=500,
                           rng=9).filter(ys, x0=x0, P0=P0) for c in (0.0, -1e5)]
    np.testing.assert_allclose(runs[0].means, runs[1].means, rtol=1e-12)
    assert runs[1].loglik == pytest.approx(runs[0].loglik - 10 * 1e5, rel=1e-12)


def test_degeneracy_is_reported_with_the_step(rng):
    motion, meas, ys, x0, P0, _ = linear_problem(rng, T=6)

    calls = [0]  # how many times loglik was called

    def loglik(y, x):
        calls[0] += 1
        return np.full(len(x), -np.inf if calls[0] == 4 else 0.0)

    with pytest.raises(ParticleDegeneracyError, match="zero likelihood at step 3"):
        ParticleFilter(motion, loglik, n_particles=100, rng=1).filter(ys, x0=x0, P0=P0)


def test_ess_threshold_controls_resampling(rng):
    motion, meas, ys, x0, P0, _ = linear_problem(rng, T=10)
    never = ParticleFilter(motion, meas, 200, ess_threshold=0.0, rng=1).filter(ys, x0=x0, P0=P0)
    always = ParticleFilter(motion, meas, 200, ess_threshold=1.0, rng=1).filter(ys, x0=x0, P0=P0)
    assert not never.resampled.any() and always.resampled.all()
    half = ParticleFilter(motion, meas, 200, ess_threshold=0.5, rng=1).filter(ys, x0=x0, P0=P0)
    np.testing.assert_array_equal(half.resampled, half.ess < 100)
    assert effective_sample_size(np.full(4, 0.25)) == pytest.approx(4.0)


def test_effective_sample_size_of_any_weights_and_what_it_refuses():
    """(sum w)^2 / sum w^2: the same for weights and any multiple of them; the filters' ess
    (normalised weights) is that of their weights. Before, [] gave inf, a negative weight a
    number and NaN NaN."""
    rng = np.random.default_rng(3)
    w = rng.uniform(0, 1, 50)
    assert effective_sample_size(w) == pytest.approx(w.sum() ** 2 / (w ** 2).sum())
    assert effective_sample_size(7.5 * w) == pytest.approx(effective_sample_size(w / w.sum()))
    assert effective_sample_size([0.0, 2.0, 0.0]) == 1.0
    assert effective_sample_size([1e308, 1e308]) == 2.0  # the sum overflowed: inf
    for bad, msg in (([], "weights is empty"), ([0.5, -0.5, 1.0], r"weights\[1\] is -0.5"),
                     ([0.5, np.nan], r"weights\[1\] is nan"), ([0.0, 0.0], "all 0"),
                     (np.ones((2, 2)), "weights")):
        with pytest.raises(ValueError, match=msg):
            effective_sample_size(bad)


@pytest.mark.parametrize("d", [1, 2, 4])
def test_the_mode_of_one_peak_holds_all_the_weight(d):
    """20,000 particles of a standard normal: one peak, so the mode's confidence is 1 and the
    mode near 0. Starts in the tails that had not climbed the broad peak within the
    mean-shift's steps, or stopped on a bump of a few particles, were peaks of their own:
    confidence 0.17, 0.34 and 0.25 in 1, 2 and 4 dimensions."""
    x = np.random.default_rng(0).normal(size=(20000, d))
    mode, conf = particle_mode(x, np.full(20000, 1 / 20000))
    assert conf == 1.0
    assert np.abs(mode).max() < 0.3
    if d == 1:
        # a gamma(3) cloud's mode is its density's, 2: over 10 clouds (one cloud's estimate
        # errs by 0.16, a standard deviation over 30 of them), within 3 standard errors
        modes = []
        for seed in range(10):
            g = np.random.default_rng(seed).gamma(3.0, size=(20000, 1))
            mode, conf = particle_mode(g, np.full(20000, 1 / 20000))
            assert conf == 1.0
            modes.append(mode[0])
        assert abs(np.mean(modes) - 2.0) < 3 * 0.16 / np.sqrt(10)


def test_a_point_between_two_peaks_does_not_join_them():
    """Peaks apart stay apart: a third, small peak between two (weights 0.45, 0.1, 0.45, 5
    apart), or the weighted mean's start stuck in the valley of a mirrored cloud, had no
    valley with either side and joined them into one peak of confidence 1."""
    rng = np.random.default_rng(0)
    k = rng.multinomial(20000, [0.45, 0.1, 0.45])
    x = np.concatenate([rng.normal(-5, 1, k[0]), rng.normal(0, 1, k[1]),
                        rng.normal(5, 1, k[2])])[:, None]
    mode, conf = particle_mode(x, np.full(20000, 1 / 20000))
    assert abs(abs(mode[0]) - 5) < 0.2 and conf == pytest.approx(0.45, abs=0.02)
    half = rng.normal(3, 1, 10000)
    mode, conf = particle_mode(np.concatenate([half, -half])[:, None], np.full(20000, 5e-5))
    # the subsample's peaks a little off the mirror: a few particles nearest the other
    assert abs(abs(mode[0]) - 3) < 0.2 and conf == pytest.approx(0.5, abs=0.01)


def test_mode_finds_the_tallest_peak_and_its_weight():
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal([-6, 0], 1.0, (4000, 2)), rng.normal([5, 3], 0.7, (2000, 2))])
    w = np.concatenate([np.full(4000, 0.35 / 4000), np.full(2000, 0.65 / 2000)])
    mode, conf = particle_mode(x, w)
    np.testing.assert_allclose(mode, [5, 3], atol=0.15)
    assert conf == pytest.approx(0.65, abs=0.05)
    # the weighted mean sits between the peaks, where there is no particle
    assert np.linalg.norm(w @ x - mode) > 4


def test_weighted_moments_take_lists_and_equal_numpy():
    """weighted_mean and weighted_cov against numpy's np.average and np.cov (aweights, no bias
    correction), from lists as from arrays and from weights on any scale (particle_mode too
    gives the same mode); wrong shapes and bad weights are named."""
    rng = np.random.default_rng(4)
    x = rng.normal(size=(50, 3))
    w = rng.random(50)
    w /= w.sum()
    mean = np.average(x, axis=0, weights=w)
    cov = np.cov(x.T, aweights=w, bias=True)
    for args in ((x, w), (x.tolist(), w.tolist())):
        np.testing.assert_allclose(weighted_mean(*args), mean, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(weighted_cov(*args), cov, rtol=1e-12, atol=1e-15)
    # weights as they come (likelihoods, on any scale) are divided by their sum, as
    # np.average divides them; they were taken as normalised, and 3 w gave 3 times the mean
    for scale in (3.0, 1e300, 1e-300):
        np.testing.assert_allclose(weighted_mean(x, w * scale), mean, rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(weighted_cov(x, w * scale), cov, rtol=1e-12, atol=1e-15)
    mode = particle_mode(x, w)
    for scale in (3.0, 1e300):
        got = particle_mode(x, w * scale)
        np.testing.assert_allclose(got[0], mode[0], rtol=1e-12, atol=1e-12)
        assert got[1] == pytest.approx(mode[1], abs=1e-12)
    for f in (weighted_mean, weighted_cov):
        with pytest.raises(ValueError, match=r"weights\[2\] is -0.5: weights must be finite "
                                             "and >= 0"):
            f(x[:3], [0.5, 1.0, -0.5])
        with pytest.raises(ValueError, match=r"weights\[1\] is nan"):
            f(x[:3], [0.5, np.nan, 0.5])
        with pytest.raises(ValueError, match=r"weights are all 0 \(of 3 particles\)"):
            f(x[:3], [0.0, 0.0, 0.0])
    with pytest.raises(ValueError, match=r"weights must have shape \(50,\), one per particle"):
        weighted_cov(x, w[:-1].tolist())
    with pytest.raises(ValueError, match="particles must be 2-D"):
        weighted_mean(x[:, 0], w)
    with pytest.raises(ValueError, match="weights must be 1-D"):
        weighted_mean(x, w[:, None])


def test_growth_model_runs_with_modes_and_a_user_likelihood():
    motion, meas = vt.models.growth_model()
    xs, ys = vt.simulate.simulate(motion, meas, 60, x0=[0.1], rng=2)
    pf = ParticleFilter(motion, meas, n_particles=3000, rng=3)
    res = pf.filter(ys, x0=[0.0], P0=[[5.0]], modes=True)
    assert res.modes.shape == (60, 1) and np.all((res.mode_confidence > 0)
                                                 & (res.mode_confidence <= 1))
    rmse = np.sqrt(np.mean((res.means[:, 0] - xs[:, 0]) ** 2))
    assert rmse < 8  # the posterior is bimodal (sign ambiguity); the literature reports ~4.5-6
    custom = ParticleFilter(motion, lambda y, x: -0.5 * (y[0] - x[:, 0] ** 2 / 20) ** 2,
                            n_particles=3000, rng=3).filter(ys, x0=[0.0], P0=[[5.0]])
    np.testing.assert_allclose(custom.means, res.means, rtol=1e-10)  # the same likelihood


def test_particle_filter_arguments_are_checked():
    motion, meas = vt.models.growth_model()
    with pytest.raises(ValueError, match="resampling must be one of"):
        ParticleFilter(motion, meas, resampling="best")
    with pytest.raises(ValueError, match=re.escape("ess_threshold must be a finite number >= 0 "
                                                   "and <= 1; got 2.0")):
        ParticleFilter(motion, meas, ess_threshold=2.0)
    # measurements of another size: named on the compiled path, an IndexError deep inside
    # the numpy one (modes=True, compiled=False)
    cv, pos = vt.ConstantVelocity(dim=1), vt.Position(dim=1)
    for kw in ({"compiled": False}, {"compiled": True}):
        for modes in (False, True):
            with pytest.raises(ValueError, match="ys must have 1 measurement components; "
                                                 "got 2"):
                ParticleFilter(cv, pos, **kw).filter(np.zeros((3, 2)), x0=[0.0, 1.0],
                                                      P0=np.eye(2), modes=modes)
    cloud = np.zeros((10, 1))
    cloud[3] = np.nan  # read as "every particle has zero likelihood": the target lost
    with pytest.raises(ValueError, match=re.escape("particles must be finite; particles[3] = "
                                                   "[nan]")):
        ParticleFilter(motion, meas, 10).filter(np.ones((3, 1)), particles=cloud)
    for n in (np.nan, np.inf, 2.5):  # NaN was "cannot convert float NaN to integer"
        with pytest.raises(ValueError, match=f"n_particles must be a whole number >= 1; got {n}"):
            ParticleFilter(motion, meas, n_particles=n)
    with pytest.raises(ValueError, match="n_particles must be a whole number >= 1; got 0"):
        ParticleFilter(motion, meas, n_particles=0)
    with pytest.raises(ValueError, match="ndim_state is needed"):
        ParticleFilter(lambda x, dt, t, rng: x, meas)
    with pytest.raises(ValueError, match=r"particles must have shape \(10, 1\)"):
        ParticleFilter(motion, meas, 10).filter(np.ones((3, 1)), particles=np.ones((5, 1)))
    # the first cloud was drawn from N(x0, -1) with numpy's warning alone
    with pytest.raises(ValueError, match=re.escape("P0 must be positive semi-definite; "
                                                   "P0[0, 0] = -1, a negative variance")):
        ParticleFilter(motion, meas, 10).filter(np.ones((3, 1)), x0=[0.0], P0=[[-1.0]])


def compiled_models(model):
    if model == "growth":
        motion, meas = vt.models.growth_model(q=0.0)
        x0, P0 = np.array([0.1]), np.array([[5.0]])
    elif model == "coordinated turn, range-bearing":
        motion = vt.models.CoordinatedTurn(q=0.0, q_turn=0.0)
        meas = vt.models.RangeBearing(1.0, 1e-3, ndim_state=5)
        x0, P0 = np.array([-20.0, 8.0, 0.0, -0.8, 0.02]), np.diag([1.0, 1.0, 0.1, 0.1, 1e-4])
    else:  # linear: F x and H x
        motion, meas = vt.ConstantVelocity(dim=2, q=0.0), vt.Position(dim=2, r=0.5)
        x0, P0 = np.array([0.0, 0.0, 1.0, -1.0]), np.diag([1.0, 1.0, 0.25, 0.25])
    return motion, meas, x0, P0


@pytest.mark.parametrize("model", ["growth", "coordinated turn, range-bearing", "linear"])
def test_compiled_path_equals_the_numpy_path_without_noise(model):
    """The compiled path draws from its own generator, so runs are compared where no draw
    matters: no process noise, no resampling, the same first cloud. Then every output must be
    the numpy path's to rounding, through missing measurements and components."""
    motion, meas, x0, P0 = compiled_models(model)
    xs, ys = vt.simulate.simulate(motion, meas, 40, x0=x0, rng=4)
    ys[7] = np.nan
    ys[9, 0] = np.nan
    cloud = np.random.default_rng(5).multivariate_normal(x0, P0, size=500)
    runs = [ParticleFilter(motion, meas, n_particles=500, ess_threshold=0.0, rng=5,
                           compiled=c).filter(ys, particles=cloud) for c in (True, False)]
    assert ParticleFilter(motion, meas, compiled=True)._fused is not None
    np.testing.assert_allclose(runs[0].means, runs[1].means, rtol=1e-9, atol=1e-10)
    np.testing.assert_allclose(runs[0].covs, runs[1].covs, rtol=1e-7, atol=1e-10)
    np.testing.assert_allclose(runs[0].ess, runs[1].ess, rtol=1e-9)
    np.testing.assert_allclose(runs[0].particles, runs[1].particles, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(runs[0].weights, runs[1].weights, rtol=1e-9, atol=1e-300)
    assert runs[0].loglik == pytest.approx(runs[1].loglik, rel=1e-10)
    assert not runs[0].resampled.any()


@pytest.mark.parametrize("model", ["growth", "linear"])
def test_the_step_before_the_first_measurement_is_not_used_on_either_path(model):
    """``dt[0]`` is the step before the first measurement, which no filter takes:
    ``np.diff(times, prepend=np.nan)`` gives NaN there, and the Kalman filter and the numpy
    path ignore it. The compiled path evaluated the model at it and refused the run (``dt
    must be finite and >= 0; got nan``). Each path now gives, with NaN or -1 there, exactly
    the run with any valid step there; and, without noise, the two paths agree."""
    motion, meas, x0, P0 = compiled_models(model)
    times = np.cumsum(np.random.default_rng(2).uniform(0.5, 1.5, 25))
    _, ys = vt.simulate.simulate(motion, meas, 25, x0=x0, dt=np.diff(times), rng=4)
    cloud = np.random.default_rng(5).multivariate_normal(x0, P0, size=300)
    runs = {}
    for compiled in (True, False):
        for first in (np.nan, -1.0, 0.7):
            dt = np.concatenate([[first], np.diff(times)])
            runs[compiled, first] = ParticleFilter(
                motion, meas, n_particles=300, ess_threshold=0.0, rng=5,
                compiled=compiled).filter(ys, dt=dt, particles=cloud)
        for first in (np.nan, -1.0):
            np.testing.assert_array_equal(runs[compiled, first].means,
                                          runs[compiled, 0.7].means)
    np.testing.assert_allclose(runs[True, np.nan].means, runs[False, np.nan].means,
                               rtol=1e-9, atol=1e-10)


def test_equal_and_unequal_steps_call_the_compiled_kernel_with_one_type(monkeypatch):
    """numba compiles a kernel once for each distinct tuple of argument types. With every step
    the same, the motion noise's root went to the compiled kernel as a broadcast view (read-only,
    of no fixed layout), with unequal steps as a C array: two compilations of each model's
    kernel (about 10 s each). Oracle: the types numba's dispatch reads (`_prebuilt._argument`)
    of the two calls are one tuple, and the values are the root of each step's ``Q`` (1 x 1)."""
    from vistrack import _prebuilt
    from vistrack.filters import particle

    motion, meas = vt.models.growth_model(q=0.5)
    x0, P0 = np.array([0.1]), np.array([[5.0]])
    made, calls = particle._fused_kernel, []

    def spy(*key):
        run = made(*key)

        def record(*args):
            calls.append(([_prebuilt._argument(a) for a in args], args[12].copy()))
            return run(*args)

        return record

    monkeypatch.setattr(particle, "_fused_kernel", spy)
    _, ys = vt.simulate.simulate(motion, meas, 6, x0=x0, rng=4)
    steps = {"equal": np.ones(6), "unequal": np.array([1.0, 1.0, 0.5, 2.0, 1.0, 0.5])}
    for dt in steps.values():
        ParticleFilter(motion, meas, 50, rng=5, compiled=True).filter(ys, dt=dt, x0=x0, P0=P0)
    assert len(calls) == 2 and calls[0][0] == calls[1][0]
    for (_, S), dt in zip(calls, steps.values()):
        want = [np.sqrt(motion.Q(v)) for v in np.concatenate([[dt[1]], dt[1:]])]  # (1 x 1)
        np.testing.assert_array_equal(S, want)


@pytest.mark.parametrize("compiled", [True, False])
def test_both_paths_approach_the_kalman_filter_with_resampling(rng, compiled):
    """With noise and resampling (every step, and by ESS), each path's mean is the Kalman
    filter's within Monte Carlo error, for every scheme the compiled path implements."""
    motion, meas, ys, x0, P0, kf = linear_problem(rng)
    sd = np.sqrt(np.diagonal(kf.covs, axis1=-2, axis2=-1))
    for method in _random.SCHEMES:
        for threshold in (1.0, 0.5):
            pf = ParticleFilter(motion, meas, n_particles=20_000, resampling=method,
                                ess_threshold=threshold, rng=7, compiled=compiled)
            assert (pf._fused is not None) == compiled
            res = pf.filter(ys, x0=x0, P0=P0)
            err = np.sqrt(np.mean(((res.means - kf.means) / sd) ** 2))
            assert err < 0.04, (method, threshold, err)
            np.testing.assert_allclose(np.sqrt(np.diagonal(res.covs, axis1=1, axis2=2)), sd,
                                       rtol=0.05)
            assert res.loglik == pytest.approx(float(kf.loglik), abs=0.5)
            assert res.resampled.all() == (threshold == 1.0)


def test_compiled_path_is_reproducible_and_reports_degeneracy():
    motion, meas = vt.models.growth_model()
    xs, ys = vt.simulate.simulate(motion, meas, 30, x0=[0.1], rng=1)
    a, b = (ParticleFilter(motion, meas, 300, rng=8).filter(ys, x0=[0.0], P0=[[5.0]])
            for _ in range(2))
    np.testing.assert_array_equal(a.means, b.means)
    ys[12] = 1e300  # (y - h)^2 overflows: every log weight is -inf
    with pytest.raises(ParticleDegeneracyError, match="zero likelihood at step 12"):
        ParticleFilter(motion, meas, 300, rng=8).filter(ys, x0=[0.0], P0=[[5.0]])


def test_kernel_normals_are_standard_normal():
    """xoshiro256++ with the ziggurat: 10^6 draws pass a Kolmogorov-Smirnov test against
    N(0, 1) at the 0.1 % level (fixed seed), and the tail beyond the ziggurat's base strip,
    drawn by a separate method, has the right mass within 4 standard errors."""
    stats = pytest.importorskip("scipy.stats")
    z = _random.normals(_random.seed(np.random.default_rng(11)), np.empty(1_000_000))
    assert stats.kstest(z, "norm").pvalue > 1e-3
    p = 2 * stats.norm.sf(3.6541528853610088)
    tail = np.mean(np.abs(z) > 3.6541528853610088)
    assert abs(tail - p) < 4 * np.sqrt(p * (1 - p) / z.size)
    u = _random.uniforms(_random.seed(np.random.default_rng(12)), np.empty(1_000_000))
    assert stats.kstest(u, "uniform").pvalue > 1e-3 and 0.0 <= u.min() and u.max() < 1.0


@pytest.mark.parametrize("method", _random.SCHEMES)
def test_kernel_resampling_is_unbiased(method):
    """The compiled path's resamplers, like :func:`resample`: mean counts equal N w within 5
    standard errors, zero weights never drawn; weights need not be normalised."""
    s = _random.seed(np.random.default_rng(3))
    N, reps = 16, 4000
    counts = np.zeros((reps, len(W)))
    for r in range(reps):
        counts[r] = np.bincount(_random.resample_indices(W * 7.5, _random.SCHEMES.index(method),
                                                         s, N), minlength=len(W))
    expected = N * W
    se = np.sqrt(np.maximum(N * W * (1 - W), 0.25) / reps)
    assert np.all(np.abs(counts.mean(0) - expected) < 5 * se)
    assert np.all(counts[:, W == 0] == 0)
    if method == "systematic":  # each count is floor or ceil of N w
        assert np.all(counts <= np.ceil(N * W) + 1e-9) and np.all(counts >= np.floor(N * W))


def test_source_hash_reads_the_files_and_closes_them():
    """The compiled kernel's cache key: sha1 of the modules' source files, read with hashlib on
    the files themselves; no file is left open (no ResourceWarning)."""
    from vistrack.filters import _codegen, _jitmath

    names = (_random.__name__, _jitmath.__name__)
    ref = hashlib.sha1(b"".join(Path(m.__file__).read_bytes() for m in (_random, _jitmath)))
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        got = _codegen.source_hash(*names)
        gc.collect()
    assert got == ref.hexdigest()[:16]
    assert not [w for w in caught if issubclass(w.category, ResourceWarning)]


@pytest.mark.parametrize("compiled, modes", [(True, False), (False, False), (False, True)])
def test_result_arrays_are_read_only_as_the_kalman_filters(compiled, modes):
    """Every array of a ParticleResult is read-only, as in kalman_filter's FilterResult."""
    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    ys = np.arange(6.0)[:, None]
    kf = vt.KalmanFilter(cv, pos).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    pf = ParticleFilter(cv, pos, 200, rng=0, compiled=compiled)
    assert (pf._fused is not None) == compiled
    res = pf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2), modes=modes)
    arrays = {f.name: getattr(res, f.name) for f in dataclasses.fields(res)
              if isinstance(getattr(res, f.name), np.ndarray)}
    assert len(arrays) == (8 if modes else 6)
    assert not kf.means.flags.writeable
    for name, a in arrays.items():
        assert not a.flags.writeable, name
        with pytest.raises(ValueError, match="read-only"):
            a[...] = 0


def test_resample_takes_only_an_integral_n_and_names_it_as_given():
    """n=2.7 was cut to 2 indices without a word, and n=0.5 reported "got 0"; numpy integers
    and integral floats are counts as before."""
    for n in (2.7, 0.5, np.float64(3.9), np.nan, True):
        with pytest.raises(ValueError, match=f"n must be a whole number >= 1; got "
                                             f"{re.escape(repr(n))}$"):
            resample([0.5, 0.5], n=n, rng=0)
    with pytest.raises(TypeError, match="n must be a number; got '3'$"):  # (no number at all)
        resample([0.5, 0.5], n="3", rng=0)
    with pytest.raises(ValueError, match="n must be a whole number >= 1; got -2"):
        resample([0.5, 0.5], n=-2)
    for method in sorted(RESAMPLERS):
        want = resample(W, method, n=5, rng=9)
        assert want.shape == (5,)
        for n in (5.0, np.int64(5), np.float32(5)):
            np.testing.assert_array_equal(resample(W, method, n=n, rng=9), want)


@pytest.mark.parametrize("method", sorted(RESAMPLERS))
def test_every_registered_scheme_takes_weights_of_any_scale(method):
    """RESAMPLERS' functions are f(weights, n, rng): three normalised the weights and
    'residual' did not (floor(4 (2, 1, 1)) = 16 copies for 4 draws: "negative dimensions are
    not allowed"). The draws of w and of c w are the same (exactly, for scales that divide
    exactly), unbiased on the package's test weights scaled by 7.5, and the residual scheme
    keeps its deterministic part floor(n w / sum w) there, as the compiled kernel's does."""
    f = RESAMPLERS[method]
    want = f(np.array([0.5, 0.25, 0.25]), 4, np.random.default_rng(0))
    for scaled in ([2.0, 1.0, 1.0], [0.2, 0.1, 0.1], [1e-300, 5e-301, 5e-301]):
        got = f(np.array(scaled), 4, np.random.default_rng(0))
        np.testing.assert_array_equal(got, want)
    rng = np.random.default_rng(3)
    N, reps = 16, 4000
    counts = np.stack([np.bincount(f(W * 7.5, N, rng), minlength=len(W)) for _ in range(reps)])
    assert (counts.sum(1) == N).all() and np.all(counts[:, W == 0] == 0)
    se = np.sqrt(np.maximum(N * W * (1 - W), 0.25) / reps)
    assert np.all(np.abs(counts.mean(0) - N * W) < 5 * se)
    if method == "residual":
        s = _random.seed(np.random.default_rng(5))
        kernel = np.stack([np.bincount(_random.resample_indices(W * 7.5, 3, s, N),
                                       minlength=len(W)) for _ in range(200)])
        for c in (counts, kernel):
            assert (c >= np.floor(N * W)).all()


def test_mode_ignores_particles_of_zero_weight_however_near():
    """A start whose nearest particle has zero weight, with every weighted particle more than
    ~38 bandwidths away: the mean-shift kernel was scaled by that particle's term, every
    other term underflowed to 0 and the mode was (nan, 1.0). Oracles: the cloud without the
    zero-weight particle, and the maximum of the weighted kernel density on a fine grid (the
    two weighted clusters are symmetric: its peaks are at their midpoints, -99.75 with 0.6 of
    the weight)."""
    x = np.array([[-100.0], [-99.5], [0.0], [99.5], [100.0]])
    w = np.array([0.3, 0.3, 0.0, 0.2, 0.2])
    with warnings.catch_warnings():
        warnings.simplefilter("error")                        # no 0/0 on the way
        mode, conf = particle_mode(x, w, bandwidth=1.0)
    keep = w > 0
    alone, conf_alone = particle_mode(x[keep], w[keep], bandwidth=1.0)
    grid = np.linspace(-101, 101, 404001)
    kde = (w * np.exp(-0.5 * (grid[:, None] - x[:, 0]) ** 2)).sum(1)
    np.testing.assert_allclose(mode, alone, atol=1e-9)
    np.testing.assert_allclose(mode, [grid[np.argmax(kde)]], atol=1e-3)
    assert mode[0] == pytest.approx(-99.75, abs=1e-6)
    assert conf == conf_alone == pytest.approx(0.6)
    # in 2-D, zero-weight particles between weighted clusters 80 bandwidths apart
    rng = np.random.default_rng(1)
    a, b = rng.normal([-40, 0], 0.3, (50, 2)), rng.normal([40, 0], 0.3, (30, 2))
    x2 = np.concatenate([a, rng.normal(0, 5, (40, 2)), b])
    w2 = np.concatenate([np.full(50, 0.7 / 50), np.zeros(40), np.full(30, 0.3 / 30)])
    mode2, conf2 = particle_mode(x2, w2, bandwidth=0.5, n_starts=20)
    pos = w2 > 0
    alone2, _ = particle_mode(x2[pos], w2[pos], bandwidth=0.5, n_starts=20)
    assert np.isfinite(mode2).all() and np.linalg.norm(mode2 - [-40, 0]) < 0.3
    assert np.linalg.norm(mode2 - alone2) < 1e-6 and conf2 == pytest.approx(0.7)


def test_mode_arguments_are_checked_and_named():
    """particle_mode checked nothing: 1-D particles and a weight too many were numpy's
    unpacking and matmul errors, bandwidth=0 a silent NaN, max_points=0 a ZeroDivisionError,
    an empty cloud an IndexError."""
    x, w = np.array([[0.0], [0.1], [5.0]]), np.array([0.4, 0.4, 0.2])
    cases = [
        (([0.0, 2.0], [0.25, 0.75]), {}, r"particles must be 2-D; got shape \(2,\)"),
        (([[0.0], [2.0]], [0.25, 0.5, 0.25]), {},
         r"weights must have shape \(2,\), one per particle"),
        ((x, w), {"bandwidth": 0.0}, r"bandwidth must be finite and > 0; got 0.0"),
        ((x, w), {"bandwidth": [1.0, np.nan]}, r"bandwidth must be a number or \(1,\)"),
        ((np.zeros((3, 2)), w), {"bandwidth": [1.0, -1.0]},
         r"bandwidth must be finite and > 0; got \[1.0, -1.0\]"),
        ((x, w), {"max_points": 0}, "max_points must be a whole number >= 1; got 0"),
        ((x, w), {"n_starts": 0}, "n_starts must be a whole number >= 1; got 0"),
        ((x, w), {"n_starts": 2.5}, "n_starts must be a whole number >= 1; got 2.5"),
        ((x, w), {"max_iter": -1}, "max_iter must be a whole number >= 0; got -1"),
        ((np.zeros((0, 1)), np.zeros(0)), {},
         r"particles must hold at least one particle; got shape \(0, 1\)"),
        ((x, [0.5, np.nan, 0.5]), {}, r"weights\[1\] is nan: weights must be finite"),
        ((x, [0.5, -0.1, 0.6]), {}, r"weights\[1\] is -0.1: weights must be finite and >= 0"),
        ((x, np.zeros(3)), {}, r"weights are all 0 \(of 3 particles\)"),
        (([[0.0], [np.inf], [1.0]], w), {}, r"particles must be finite; particles\[1, 0\]"),
    ]
    for args, kw, msg in cases:
        with pytest.raises(ValueError, match=msg):
            particle_mode(*args, **kw)
    # valid arguments of other types give what they gave
    want = particle_mode(x, w, bandwidth=0.5)
    got = particle_mode(x.tolist(), w.tolist(), bandwidth=[0.5], n_starts=8.0,
                        max_points=np.int64(5000))
    np.testing.assert_array_equal(got[0], want[0])
    assert got[1] == want[1]


def test_a_propagate_callable_must_return_n_finite_particles_of_the_state():
    """A propagate callable returning (N, 1) for a 2-D state was broadcast into (T, 2) means
    (both columns the position) with a (500, 1) last cloud, or failed in the measurement
    model's matmul; the shape and finiteness are checked each step, naming the callable."""
    def forgets_velocity(x, dt, t, rng):
        return (x[:, :1] + x[:, -1:] * dt) + rng.normal(0, 0.1, (len(x), 1))

    def blows_up(x, dt, t, rng):
        out = x + rng.normal(0, 0.1, x.shape)
        if t >= 3:
            out[7, 1] = np.inf
        return out

    def loglik(y, x):
        return -0.5 * (y[0] - x[:, 0]) ** 2

    ys = np.arange(5.0)[:, None]
    prior = {"x0": [0.0, 1.0], "P0": 0.1 * np.eye(2)}
    for likelihood in (loglik, vt.Position(dim=1)):
        with pytest.raises(ValueError, match=re.escape(
                "motion (a propagate callable) must return particles of shape (N, n) = "
                "(500, 2); got shape (500, 1) at step 1")):
            ParticleFilter(forgets_velocity, likelihood, 500, rng=0, ndim_state=2).filter(
                ys, **prior)
        with pytest.raises(ValueError, match=re.escape(
                "motion (a propagate callable) returned non-finite particles at step 3 "
                "(1 of 500); particles[7] = [")):
            ParticleFilter(blows_up, likelihood, 500, rng=0, ndim_state=2).filter(ys, **prior)
    # a correct callable: the same as the motion model it copies (a linear-Gaussian model,
    # drawn from the same generator on the numpy path)
    cv = vt.ConstantVelocity(dim=1, q=0.1)
    F, S = cv.F(1.0), np.linalg.cholesky(cv.Q(1.0))

    def propagate(x, dt, t, rng):
        return x @ F.T + rng.standard_normal(x.shape) @ S.T

    a = ParticleFilter(propagate, loglik, 500, rng=0, ndim_state=2).filter(ys, **prior)
    assert a.particles.shape == (500, 2) and np.isfinite(a.means).all()
    assert np.abs(a.means[:, 0] - ys[:, 0]).max() < 0.5


def test_a_non_finite_prior_is_named_not_read_as_degeneracy():
    """x0 or P0 with NaN or inf went into multivariate_normal and came out as
    "ParticleDegeneracyError: every particle has zero likelihood at step 0" (or, with no
    measurement, silently NaN means), on both paths."""
    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    cases = [({"x0": [np.nan, 0.0], "P0": np.eye(2)}, "x0 must be finite; x0[0] = nan"),
             ({"x0": [np.inf, 0.0], "P0": np.eye(2)}, "x0 must be finite; x0[0] = inf"),
             ({"x0": [0.0, 0.0], "P0": np.full((2, 2), np.nan)},
              "P0 must be finite; P0[0, 0] = nan"),
             ({"x0": [0.0, 0.0], "P0": [[1.0, 0.0], [0.0, np.inf]]},
              "P0 must be finite; P0[1, 1] = inf")]
    for compiled in (True, False):
        for ys in (np.zeros((2, 1)), np.full((2, 1), np.nan)):
            for prior, msg in cases:
                with pytest.raises(ValueError, match=re.escape(msg)):
                    ParticleFilter(cv, pos, 10, rng=0, compiled=compiled).filter(ys, **prior)


def test_a_likelihood_of_plus_infinity_is_named_not_read_as_degeneracy():
    """+inf from a likelihood callable (a bug, as NaN) made log-sum-exp NaN and was reported
    as "every particle has zero likelihood ... the filter has lost the target"."""
    def loglik(y, x):
        out = -0.5 * (y[0] - x[:, 0]) ** 2
        out[3] = np.inf
        return out

    pf = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1), loglik, n_particles=100, rng=0)
    with pytest.raises(ValueError, match=re.escape(
            "likelihood returned +inf for 1 of 100 particles at step 0 (measurement [0.0]); "
            "it must return log p(y | x) for each particle, finite or -inf where y is "
            "impossible")):
        pf.filter(np.zeros((3, 1)), x0=[0.0, 0.0], P0=np.eye(2))
    # -inf is an impossible particle, as before: its weight is 0
    def impossible(y, x):
        out = -0.5 * (y[0] - x[:, 0]) ** 2
        out[:50] = -np.inf
        return out

    res = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1), impossible, n_particles=100,
                         rng=0, ess_threshold=0.0).filter(np.zeros((1, 1)), x0=[0.0, 0.0],
                                                          P0=np.eye(2))
    assert (res.weights[:50] == 0).all() and res.weights.sum() == pytest.approx(1.0)


def test_residual_keeps_one_copy_of_each_of_n_equal_weights():
    """n equal weights: the residual scheme's deterministic part is one copy of each, and no
    draw is left to chance. n * (1 / n) can round below 1, whose floor lost the copy: the
    whole set was drawn at random (1,000 equal weights kept 651 distinct particles with numpy,
    621 compiled). Both paths, for weights normalised as the filter does (exp of equal
    log-weights over their sum) and for 1 / N; and on random weights both keep at least the
    copies floor(n w_i / sum w) of exact rational arithmetic."""
    from fractions import Fraction

    for N in (3, 10, 49, 300, 1000, 4096):
        for w in (np.full(N, 1.0 / N), np.exp(np.full(N, -np.log(N))) / np.exp(
                np.full(N, -np.log(N))).sum()):
            idx = resample(w, "residual", rng=0)
            assert (np.bincount(idx, minlength=N) == 1).all(), N
            s = _random.seed(np.random.default_rng(1))
            assert (np.bincount(_random.resample_indices(w, 3, s, N), minlength=N) == 1).all()
    rng = np.random.default_rng(8)
    for _ in range(100):
        N, n = int(rng.integers(2, 60)), int(rng.integers(1, 80))
        w = rng.dirichlet(np.full(N, 0.7))
        total = sum(Fraction(float(v)) for v in w)
        floor = np.array([(n * Fraction(float(v))) // total for v in w])
        s = _random.seed(rng)
        for idx in (resample(w, "residual", n=n, rng=rng), _random.resample_indices(w, 3, s, n)):
            c = np.bincount(idx, minlength=N)
            assert c.sum() == n and (c >= floor).all()


def _state_drawing(value_bits: str, at: int) -> np.ndarray:
    """A xoshiro256++ state whose draw number ``at`` (from 0) gives 64 bits of ``'ones'`` (the
    uniform 1 - 2**-53) or ``'zeros'`` (the uniform 0): a state of that output, walked back
    ``at`` steps by the generator's inverse, worked out from its published step."""
    m = (1 << 64) - 1

    def rotr(x, k):
        return ((x >> k) | (x << (64 - k))) & m

    s0, s3 = 0, (m if value_bits == "ones" else 0)  # rotl(s0 + s3, 23) + s0
    st = [s0, 0x9E3779B97F4A7C15, 0xD1B54A32D192ED03, s3]
    for _ in range(at):
        S0, S1, S2, S3 = st
        x = rotr(S3, 45)  # s1 ^ s3
        a = S0 ^ x
        y, z = S1 ^ a, S2 ^ a  # s1 ^ s2, s2 ^ (s1 << 17)
        w = y ^ z  # s1 ^ (s1 << 17)
        b = (w ^ (w << 17) ^ (w << 34) ^ (w << 51)) & m
        st = [a, b, y ^ b, x ^ b]
    return np.array(st, dtype=np.uint64)


def test_the_crafted_generator_states_draw_what_they_are_made_to():
    """The oracle of the next test: the state made by walking back draws the chosen bits."""
    for at in (0, 1, 2, 5):
        u = _random.uniforms(_state_drawing("ones", at), np.empty(at + 1))
        assert u[at] == 1.0 - 2.0**-53
        assert _random.uniforms(_state_drawing("zeros", at), np.empty(at + 1))[at] == 0.0


class _Uniforms:
    """A generator whose every uniform is ``u`` and whose exponentials are given."""

    def __init__(self, u=1.0 - 2.0**-53, exponentials=None):
        self.u, self.e = u, exponentials

    def random(self, size=None):
        return self.u if size is None else np.full(size, self.u)

    def standard_exponential(self, size):
        return np.asarray(self.e, float)


def test_a_uniform_rounded_up_to_one_never_draws_a_particle_of_weight_zero():
    """Weights (1/2, 1/2, 0): the last particle has no weight, and the exact draws are 0, 1, 1
    for every scheme here. A uniform within an ulp of 1 rounds up: systematic's last edge
    ceil(3 - u0) is 2, so its third slot was filled with the last index; stratified's
    (2 + U) / 3 and multinomial's e_3 / e_4 (a last exponential of 0) are exactly 1, and the
    search ran on to the last index. Both paths, each scheme; the compiled one from
    generator states made to draw that uniform."""
    w = np.array([0.5, 0.5, 0.0])
    exact = [0, 1, 1]
    top = _Uniforms()
    assert RESAMPLERS["systematic"](w, 3, top).tolist() == exact
    assert RESAMPLERS["stratified"](w, 3, top).tolist() == exact
    assert RESAMPLERS["multinomial"](w, 3, _Uniforms(exponentials=[1, 1, 1, 0])).tolist() \
        == exact
    from vistrack.filters.particle import _systematic_rows
    rows = _systematic_rows(np.stack([w, w[[2, 0, 1]]]), np.full(2, 1.0 - 2.0**-53),
                            np.empty((2, 3), np.int64))
    assert rows.tolist() == [exact, [1, 2, 2]]
    # residual: whole copies 1, 1, 0, and one draw on the remainders (1/2, 1/2, 0)
    assert RESAMPLERS["residual"](w, 3, _Uniforms(exponentials=[1, 0])).tolist() == exact
    # compiled: systematic's u0 is the first draw, stratified's third the last slot's, the
    # multinomial's fourth (the sum's last exponential) and the residual's second
    for scheme, bits, at in ((2, "ones", 0), (1, "ones", 2), (0, "zeros", 3), (3, "zeros", 1)):
        idx = _random.resample_indices(w, scheme, _state_drawing(bits, at), 3)
        assert idx.tolist() == exact, _random.SCHEMES[scheme]
    # the fast branch of the compiled systematic scheme writes two slots ahead: zero weights
    # after the last positive one (where the edges round, which index of positive weight a
    # slot takes may differ from exact arithmetic: (1 + u0) / 4 rounds to 1/2)
    w5 = np.array([0.25, 0.25, 0.5, 0.0, 0.0])
    for idx in (_random.resample_indices(w5, 2, _state_drawing("ones", 0), 4),
                RESAMPLERS["systematic"](w5, 4, top)):
        assert len(idx) == 4 and (w5[idx] > 0).all() and idx[-1] == 2, idx


def test_weights_normalised_in_float32_are_taken():
    """Ten float32 weights divided by their sum are off 1 by up to some 6e-8 in float64, past the
    check of 1e-9 sqrt(N) for float64 weights: they were refused. The tolerance is N ulp of
    the array's own type; float64 weights keep theirs, and a float32 row off by 1e-3 is
    still named."""
    w = np.random.default_rng(4).random(10).astype(np.float32)
    w /= w.sum()
    assert abs(float(w.astype(float).sum()) - 1.0) > 1e-9 * np.sqrt(10)  # the case
    for method in RESAMPLERS:
        idx = resample(w, method, rng=0)
        assert idx.shape == (10,) and (w[idx] > 0).all()
    # the same draws as the weights made to sum to 1 in float64 (any positive scale is drawn
    # alike by the schemes)
    w64 = w.astype(float) / w.astype(float).sum()
    np.testing.assert_array_equal(resample(w, rng=5), resample(w64, rng=5))
    with pytest.raises(ValueError, match="weights must sum to 1; they sum to 1.00"):
        resample(np.full(10, 0.1001, np.float32))
    with pytest.raises(ValueError, match="weights must sum to 1"):
        resample(w.astype(float) * (1 + 1e-8))


@pytest.mark.parametrize("value, shown, error", [
    (True, "True", ValueError), (np.True_, "True", ValueError), ("5", "'5'", TypeError),
    (2.5, "2.5", ValueError), (float("nan"), "nan", ValueError), (0, ">= 1", ValueError)])
def test_n_particles_of_another_kind_is_named(value, shown, error):
    """``n_particles=True`` was taken as one particle and ``"5"`` failed in a bare TypeError;
    both filters name it now, by the package's rules for counts and bounded numbers (a
    TypeError for what is no number, as every other setting's)."""
    from vistrack.filters import SwitchingParticleFilter
    from vistrack.models import SwitchingLinearSystem

    slds = SwitchingLinearSystem([vt.ConstantVelocity(dim=1)], vt.Position(dim=1), [[1.0]])
    for make in (lambda **kw: ParticleFilter(vt.ConstantVelocity(dim=1), vt.Position(dim=1),
                                             **kw),
                 lambda **kw: SwitchingParticleFilter(slds, **kw)):
        with pytest.raises(error, match="n_particles must be") as e:
            make(n_particles=value)
        assert shown in str(e.value)
        for bad in (float("nan"), 1.5, -0.1, float("inf")):
            with pytest.raises(ValueError, match=re.escape(
                    f"ess_threshold must be a finite number >= 0 and <= 1; got {bad!r}")):
                make(ess_threshold=bad)
        for bad in (True, "0.5", None):
            with pytest.raises(TypeError, match=re.escape(
                    f"ess_threshold must be a number; got {bad!r}")):
                make(ess_threshold=bad)
        with pytest.raises(ValueError, match="resampling must be one of"):
            make(resampling=["systematic"])
    assert ParticleFilter(vt.ConstantVelocity(dim=1), vt.Position(dim=1),
                          n_particles=np.int32(7), ess_threshold=np.float32(0.5)).n_particles == 7


def test_a_model_that_gives_nan_is_named_not_taken_for_a_lost_target():
    """One particle's NaN log-weight made the largest NaN, and a model's error (a motion or
    measurement function giving NaN for some particles, or a NaN dt) was raised as
    ParticleDegeneracyError, "the filter has lost the target", which a caller catching it
    to start again would hide. Oracle: the models, which give NaN where x > 0 (half the
    cloud) and finite values elsewhere; and a target truly lost still is degeneracy."""
    from vistrack.models import NonlinearMeasurement, NonlinearMotion

    nm = NonlinearMotion(lambda x, dt, t: np.where(x[..., :1] > 0, np.nan, x), 0.1 * np.eye(2),
                         2)
    pf = ParticleFilter(nm, vt.Position(dim=1), 10, rng=0)
    with pytest.raises(ValueError, match=r"the motion model gave NaN or infinity for \d+ of 10 "
                                         r"particles at step 1; particles\[\d+\] = \[nan, nan\]"):
        pf.filter(np.zeros((3, 1)), x0=[0, 0], P0=np.eye(2))
    h = NonlinearMeasurement(lambda x: np.where(x[..., :1] > 0.5, np.nan, x[..., :1]), [[0.5]],
                             ndim_state=2)
    pf = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1), h, 10, rng=0)
    with pytest.raises(ValueError, match=r"the measurement model gave NaN or infinity for "
                                         r"\d+ of 10 particles at step 0 \(measurement "
                                         r"\[0.0\]\)"):
        pf.filter(np.zeros((3, 1)), x0=[0, 0], P0=np.eye(2))
    for fused in (True, False):
        pf = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1), 10, rng=0)
        if not fused:
            pf._fused = None
        with pytest.raises(ValueError, match=re.escape(
                "dt must be finite and >= 0 (dt[0], before the first step, aside); the step "
                "to step 1 is nan")):
            pf.filter(np.zeros((3, 1)), x0=[0, 0], P0=np.eye(2), dt=[1, np.nan, 1])
    # every particle's likelihood 0 at step 1: a lost target
    pf = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1),
                        lambda y, x: np.full(len(x), 0.0 if y[0] < 1 else -np.inf), 10,
                        rng=0)
    with pytest.raises(ParticleDegeneracyError, match="at step 1"):
        pf.filter(np.array([[0.0], [5.0]]), x0=[0, 0], P0=np.eye(2))


def test_clouds_and_priors_a_filter_cannot_use_are_named():
    """weighted_mean and weighted_cov gave NaN for a NaN particle even of weight 0 (which
    particle_mode names), and numpy's "zero-size array" for no particles; filter(particles=,
    x0=, P0=) dropped x0 and P0 without a word; ndim_state 2.5 was cut to 2."""
    for f in (weighted_mean, weighted_cov):
        with pytest.raises(ValueError, match=re.escape("particles must be finite; "
                                                       "particles[0, 0] = nan")):
            f([[np.nan], [1.0]], [0.0, 1.0])
        with pytest.raises(ValueError, match=re.escape(
                "particles must hold at least one particle; got shape (0, 2)")):
            f(np.zeros((0, 2)), [])
    pf = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1), 10, rng=0)
    with pytest.raises(ValueError, match=re.escape(
            "give particles or x0 and P0, not both; got particles and x0 and P0")):
        pf.filter(np.zeros((3, 1)), particles=np.zeros((10, 2)), x0=[100, 0], P0=np.eye(2))
    with pytest.raises(ValueError, match=re.escape("ndim_state must be a whole number >= 1; "
                                                   "got 2.5")):
        ParticleFilter(lambda x, dt, t, rng: x, vt.Position(dim=1), 10, ndim_state=2.5)


def test_flags_sizes_methods_and_masks_are_named():
    """modes="no" and compiled="no" were true; a conflicting ndim_state beside a model was
    dropped; resample with a list for its method met "unhashable type"; a boolean mask was
    taken as weights or a bandwidth; a boolean dt as a step of 1 (the models refuse it)."""
    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    ys = np.arange(5.0)[:, None]
    pf = ParticleFilter(cv, pos, 100, rng=0)
    with pytest.raises(TypeError, match=r"modes must be True or False"):
        pf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2), modes="no")
    with pytest.raises(TypeError, match=r"compiled must be True or False"):
        ParticleFilter(cv, pos, 10, compiled="no")
    with pytest.raises(ValueError, match=r"ndim_state is 7, where the motion model's states "
                                         r"have 2 values"):
        ParticleFilter(cv, pos, 100, ndim_state=7)
    assert ParticleFilter(cv, pos, 100, ndim_state=2).ndim_state == 2
    with pytest.raises(ValueError, match=r"method must be one of .*got \['systematic'\]"):
        resample([0.5, 0.5], ["systematic"])
    for call in (lambda: resample([True, False]), lambda: effective_sample_size([True, True]),
                 lambda: particle_mode(np.zeros((2, 1)), [True, True])):
        with pytest.raises(TypeError, match=r"weights must be numbers >= 0"):
            call()
    with pytest.raises(TypeError, match=r"bandwidth must be one number > 0"):
        particle_mode(np.zeros((2, 1)), [0.5, 0.5], bandwidth=True)
    for bad in (True, [True] * 5, np.True_):
        with pytest.raises(TypeError, match=r"dt must be a number or an array of numbers"):
            pf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2), dt=bad)
        with pytest.raises(TypeError, match=r"dt must be a number or an array of numbers"):
            vt.filters.IMMFilter([vt.KalmanFilter(cv, pos)], [[1.0]]).filter(
                ys, x0=[0.0, 1.0], P0=np.eye(2), dt=bad)
        with pytest.raises(TypeError, match=r"dt must be a number or an array of numbers"):
            vt.simulate.simulate(cv, pos, 3, x0=[0.0, 1.0], dt=bad, rng=0)
    with pytest.raises(TypeError, match=r"rng must be a numpy Generator, an int seed or None"):
        ParticleFilter(cv, pos, 10, rng=True)
    # the same numbers as before for a good call (the oracle: the same seed twice)
    a = pf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2)).means
    b = ParticleFilter(cv, pos, 100, rng=0).filter(ys, x0=[0.0, 1.0], P0=np.eye(2)).means
    np.testing.assert_array_equal(a, b)


def test_a_negative_dt_is_refused_before_any_particle_is_drawn():
    """A negative step was refused by the motion model after the first particles were
    drawn: the generator's draws were used up, and the next call's particles differed from
    a fresh filter's of the same seed."""
    cv, pos = vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1)
    ys = np.arange(4.0)[:, None]
    for fused in (True, False):
        pf = ParticleFilter(cv, pos, 50, rng=0)
        if not fused:
            pf._fused = None
        for bad in (-1.0, [1.0, 1.0, -1.0, 1.0]):
            with pytest.raises(ValueError, match=r"dt must be finite and >= 0"):
                pf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2), dt=bad)
        fresh = ParticleFilter(cv, pos, 50, rng=0)
        if not fused:
            fresh._fused = None
        np.testing.assert_array_equal(pf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2)).means,
                                      fresh.filter(ys, x0=[0.0, 1.0], P0=np.eye(2)).means)


def test_a_model_that_gives_infinity_for_some_particles_is_named_not_averaged():
    """A motion model giving infinity for some particles gave NaN means without a word (an
    infinite particle weighs 0, and the largest weight stayed finite; both paths); a
    measurement model giving infinity was read as "lost target" where all did, and weighed
    those particles 0 where some did. Both are a model's fault, named as a NaN is. Oracle:
    the docstring's contract (a ValueError naming the model)."""
    from vistrack.filters.particle import ParticleFilter

    class Blows:
        ndim_state = 1

        def F(self, dt):
            return np.array([[1e308]])

        def Q(self, dt):
            return np.array([[1e-300]])

    for compiled in (True, False):
        pf = ParticleFilter(Blows(), vt.Position(dim=1, r=1.0), n_particles=500, rng=0,
                            compiled=compiled)
        with np.errstate(over="ignore"), pytest.raises(ValueError, match=re.escape(
                "the motion model gave NaN or infinity for ")):
            pf.filter(np.zeros((2, 1)), x0=[0.0], P0=[[1.0]])

    class Some:
        ndim_meas = 1

        def h(self, x):
            return np.where(x[..., :1] > 0.5, np.inf, x[..., :1])

        def jacobian(self, x):
            return np.ones(x.shape[:-1] + (1, 1))

        def R(self):
            return np.array([[1.0]])

    class All(Some):
        def h(self, x):
            return np.full(x.shape[:-1] + (1,), np.inf)

    for model in (Some(), All()):
        pf = ParticleFilter(vt.ConstantPosition(dim=1, q=0.1), model, n_particles=500, rng=0)
        with pytest.raises(ValueError, match=re.escape(
                "the measurement model gave NaN or infinity for ")):
            pf.filter(np.zeros((3, 1)), x0=[0.0], P0=[[1.0]])


def test_particle_mode_with_one_start_starts_from_the_weighted_mean_alone():
    """`n_starts=1` ran two mean-shift starts (the mean and a particle), as `n_starts=2`
    does, where the docstring says the mean and `n_starts - 1` particles. Oracle: mean shift
    from the weighted mean alone, with the documented kernel and bandwidth, written out."""
    from vistrack.filters.particle import particle_mode

    rng = np.random.default_rng(0)
    x = np.r_[rng.normal(0, 3, 600), rng.normal(10, 0.1, 400)][:, None]
    w = np.full(1000, 1e-3)
    one, _ = particle_mode(x, w, n_starts=1)
    two, _ = particle_mode(x, w, n_starts=2)
    assert abs(two[0] - 10) < 0.1 and abs(one[0] - 10) > 5  # the mean's own peak
    z = float(np.average(x[:, 0], weights=w))
    sd = np.sqrt(np.average((x[:, 0] - z) ** 2, weights=w))
    h = sd * (4 / 3 / 1000) ** 0.2  # (Silverman's, the documented bandwidth; N_eff 1000)
    for _ in range(500):
        k = w * np.exp(-0.5 * ((x[:, 0] - z) / h) ** 2)
        z_next = float((k * x[:, 0]).sum() / k.sum())
        if abs(z_next - z) < 1e-10:
            break
        z = z_next
    assert one[0] == pytest.approx(z, abs=1e-3)


def test_particle_mode_of_a_cloud_with_a_dimension_of_one_value():
    """A dimension in which every particle has one value (a state the prior leaves fixed)
    got a bandwidth of about 1e-150, and its last bits outweighed every real distance: the
    docstring's cloud beside a constant 1000 gave the weighted mean (1.25) with confidence
    1. The oracle: the same cloud without that dimension (mode 3.95, confidence 0.70), at
    the bandwidth Silverman's rule gives it in two dimensions, over constants of several
    sizes and with unequal weights."""
    rng = np.random.default_rng(0)
    x = np.concatenate([rng.normal(-5, 1, (300, 1)), rng.normal(4, 1, (700, 1))])
    for w in (np.full(1000, 1e-3), rng.uniform(0.5, 1.5, 1000)):
        w = w / w.sum()
        h = np.sqrt(weighted_cov(x, w)[0, 0]) * (4.0 / (4 * effective_sample_size(w))) ** (1 / 6)
        alone, conf = particle_mode(x, w, bandwidth=h)
        for value in (1000.0, 0.0, -3.7e5, 1.234):
            mode, c = particle_mode(np.column_stack([x[:, 0], np.full(1000, value)]), w)
            assert mode[1] == pytest.approx(value, rel=1e-12, abs=1e-12)
            assert mode[0] == pytest.approx(alone[0], abs=1e-6) and c == pytest.approx(conf)


def test_particle_mode_climbs_a_skewed_peak_to_the_top():
    """With the default of 50 steps a gamma(3) cloud's mode stopped 0.08 short of the peak
    of the kernel density it climbs; the oracle is that density's largest value on a grid
    of 1e-4 (the same Gaussian kernel and Silverman bandwidth)."""
    for seed in range(3):
        x = np.random.default_rng(seed).gamma(3.0, 1.0, (5000, 1))
        w = np.full(5000, 1 / 5000)
        h = x[:, 0].std() * (4.0 / (3 * 5000)) ** (1 / 5)
        grid = np.arange(1.0, 3.5, 1e-4)
        dens = np.array([np.exp(-0.5 * ((g - x[:, 0]) / h) ** 2).sum() for g in grid])
        mode, _ = particle_mode(x, w)
        assert mode[0] == pytest.approx(grid[dens.argmax()], abs=2e-3)


def test_the_resamplers_take_weights_whose_sum_overflows():
    """The schemes take weights of any positive scale, but three of 1e308 summed to inf and
    every scheme drew one particle alone. The oracle: the draws of the same weights scaled
    by a power of two (1e308 / 2^1000), which leave their ratios as they were."""
    from vistrack.filters.particle import RESAMPLERS

    w = np.array([1e308, 1e308, 1e308])
    for name, scheme in RESAMPLERS.items():
        got = scheme(w, 300, np.random.default_rng(4))
        want = scheme(np.ldexp(w, -1000), 300, np.random.default_rng(4))
        np.testing.assert_array_equal(got, want, err_msg=name)
        assert set(np.bincount(got, minlength=3)) <= set(range(90, 111)), name


def test_a_negative_seed_and_a_likelihood_of_text_are_named():
    """``rng=-1`` failed in numpy's words ("expected non-negative integer"), and a
    likelihood returning text in numpy's ("could not convert string to float")."""
    with pytest.raises(ValueError, match="rng must be a seed >= 0, a numpy Generator or None; "
                                         "got -1"):
        resample([0.5, 0.5], rng=-1)
    text = lambda y, x: np.full(len(x), "a")  # noqa: E731
    pf = ParticleFilter(vt.ConstantPosition(dim=1), text, n_particles=10, rng=0)
    with pytest.raises(TypeError, match=r"likelihood must return \(N,\) = \(10,\) "
                                        "log-likelihoods, numbers; got .* at step 0"):
        pf.filter(np.zeros((2, 1)), x0=[0.0], P0=[[1.0]])
