"""Switching linear dynamic systems: sampling, and estimation by the Rao-Blackwellised particle
filter and the IMM against the exact posterior, enumerated over every mode sequence."""

import itertools

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
    # the IMM merges the k^T Gaussians into k at every step: an approximation, but close here
    imm = IMMFilter.from_system(slds).filter(ys, x0=x0, P0=P0)
    assert np.all(np.abs(imm.means[-1] - mean) < 0.2 * sd)
    np.testing.assert_allclose(imm.mode_probs[-1], probs, atol=0.1)


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
