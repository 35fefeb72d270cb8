"""PDA and JPDA against the Kalman filter, explicit formulas and brute-force enumeration."""

from __future__ import annotations

import itertools
import math
import re
import warnings

import numpy as np
import pytest

from vistrack import Gaussian
from vistrack.association import jipda_weights, jpda_weights, likelihoods, pda_weights
from vistrack.filters import kf_update, pda_update


def random_tracks(rng, T, n=4, m=2):
    A = rng.normal(size=(T, n, n))
    P = A @ A.transpose(0, 2, 1) + np.eye(n)
    return Gaussian(rng.normal(size=(T, n)), P), np.eye(m, n), 0.5 * np.eye(m)


def test_pda_with_one_sure_measurement_is_the_kalman_update():
    rng = np.random.default_rng(0)
    g, H, R = random_tracks(rng, 3)
    Z = rng.normal(size=(1, 2))
    for t in range(3):
        gt = g[t:t + 1]
        S = H @ gt.cov @ H.T + R
        lik = likelihoods(gt.mean @ H.T, S, Z)
        beta, beta0 = pda_weights(lik, np.ones((1, 1), bool), p_detect=1.0, p_gate=1.0)
        assert beta0[0] == 0 and beta[0, 0] == 1
        got = pda_update(gt, Z, H, R, beta, beta0)
        want = kf_update(g[t], Z[0], H, R)
        np.testing.assert_allclose(got.mean[0], want.mean, rtol=1e-10)
        np.testing.assert_allclose(got.cov[0], want.cov, rtol=1e-10, atol=1e-12)


def test_a_covariance_that_is_not_positive_definite_is_named_as_mahalanobis_names_it():
    """S[1] = [[1, 2], [2, 1]] has eigenvalues 3 and -1: likelihoods refuses it with the
    ValueError of mahalanobis, naming the track, not numpy's LinAlgError."""
    from vistrack.association import mahalanobis

    S = np.stack([np.eye(2), np.array([[1.0, 2.0], [2.0, 1.0]])])
    assert np.linalg.eigvalsh(S[1]).min() == pytest.approx(-1.0)
    zp, Z = np.zeros((2, 2)), np.ones((3, 2))
    msg = r"S must be positive definite for every track; S\[1\] is not"
    with pytest.raises(ValueError, match=msg):
        mahalanobis(zp, S, Z)
    with pytest.raises(ValueError, match=msg):
        likelihoods(zp, S, Z)
    # a positive definite S: the density of scipy's multivariate normal
    stats = pytest.importorskip("scipy.stats")
    S[1] = [[2.0, 0.5], [0.5, 1.0]]
    lik = likelihoods(zp + [[0.0, 0.0], [1.0, -1.0]], S, Z)
    np.testing.assert_allclose(lik[1], stats.multivariate_normal([1.0, -1.0], S[1]).pdf(Z),
                               rtol=1e-12)


def test_pda_update_equals_the_textbook_equations():
    rng = np.random.default_rng(1)
    g, H, R = random_tracks(rng, 4)
    Z = rng.normal(size=(5, 2))
    S = H @ g.cov @ H.T + R
    lik = likelihoods(g.mean @ H.T, S, Z)
    gate = rng.random((4, 5)) < 0.7
    beta, beta0 = pda_weights(lik, gate, p_detect=0.8, clutter_density=0.05, p_gate=0.95)
    np.testing.assert_allclose(beta.sum(1) + beta0, 1.0)
    got = pda_update(g, Z, H, R, beta, beta0)
    for t in range(4):
        P, m = g.cov[t], g.mean[t]
        St = H @ P @ H.T + R
        # the likelihood by the density formula
        for j in range(5):
            r = Z[j] - H @ m
            want = np.exp(-0.5 * r @ np.linalg.inv(St) @ r) / np.sqrt(np.linalg.det(2 * np.pi * St))
            assert lik[t, j] == pytest.approx(want, rel=1e-10)
        K = P @ H.T @ np.linalg.inv(St)
        nus = [Z[j] - H @ m for j in range(5)]
        nu = sum(beta[t, j] * nus[j] for j in range(5))
        Pc = P - K @ St @ K.T
        spread = sum(beta[t, j] * np.outer(nus[j], nus[j]) for j in range(5)) - np.outer(nu, nu)
        np.testing.assert_allclose(got.mean[t], m + K @ nu, rtol=1e-10)
        np.testing.assert_allclose(got.cov[t], beta0[t] * P + (1 - beta0[t]) * Pc
                                   + K @ spread @ K.T, rtol=1e-9, atol=1e-12)


def brute_jpda(G, B):
    T, D = G.shape
    beta, beta0, total = np.zeros((T, D)), np.zeros(T), 0.0
    for event in itertools.product(*[[-1] + list(range(D))] * T):
        used = [j for j in event if j >= 0]
        if len(used) != len(set(used)) or any(j >= 0 and G[t, j] == 0 for t, j in enumerate(event)):
            continue
        w = np.prod([B if j < 0 else G[t, j] for t, j in enumerate(event)])
        total += w
        for t, j in enumerate(event):
            if j < 0:
                beta0[t] += w
            else:
                beta[t, j] += w
    return beta / total, beta0 / total


def against_brute_force(rng, T, D, density):
    lik = rng.uniform(0.001, 0.05, (T, D))
    gate = rng.random((T, D)) < density
    pd, lam, pg = 0.85, 0.01, 0.97
    beta, beta0 = jpda_weights(lik, gate, p_detect=pd, clutter_density=lam, p_gate=pg)
    want_b, want_b0 = brute_jpda(np.where(gate, pd * lik / lam, 0.0), 1 - pd * pg)
    np.testing.assert_allclose(beta, want_b, rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(beta0, want_b0, rtol=1e-10)


@pytest.fixture(params=["events", "subsets"])
def exact_by(request, monkeypatch):
    """Both of the exact sums for clusters of three tracks or more: small clusters event by
    event, the others by subsets of their smaller side (each forced in turn)."""
    from vistrack.association import pda

    monkeypatch.setattr(pda, "_ENUMERATED", 10**9 if request.param == "events" else 0)
    return request.param


@pytest.mark.parametrize("seed", range(12))
def test_jpda_equals_brute_force_enumeration(seed, exact_by):
    rng = np.random.default_rng(seed)
    against_brute_force(rng, rng.integers(1, 5), rng.integers(0, 5), 0.7)


@pytest.mark.parametrize("T, D", [(7, 3), (3, 8), (5, 6), (6, 2)])
def test_jpda_equals_brute_force_with_more_tracks_or_more_detections(T, D, exact_by):
    """Clusters summed by the subsets of their tracks (T <= D) and of their detections (T >
    D), or event by event, past the random shapes above, against every event written out."""
    against_brute_force(np.random.default_rng(T * 10 + D), T, D, 0.8)


def test_clusters_summed_event_by_event_neither_overflow_nor_underflow():
    """A cluster of three tracks, two tracks' weights and misses multiplied by 1e200, or by
    1e-200 (every event has one factor of each track's, so the probabilities are the same):
    their product would overflow (1e400) or underflow."""
    from vistrack.association.pda import _clusters, _joint

    rng = np.random.default_rng(3)
    G, B = rng.uniform(0.5, 50, (3, 4)) * (rng.random((3, 4)) < 0.8), np.full(3, 0.1)
    # one cluster, summed event by event in the compiled call (none left to the subsets)
    lt, ld, left = np.empty(3, np.int64), np.empty(4, np.int64), np.empty(3, bool)
    assert _clusters(G, B, 12, 20_000, np.zeros((3, 4)), np.ones(3), lt, ld, left) == 1
    assert not left[0] and (lt == 0).all()
    want = brute_jpda(G, 0.1)
    for k in (1.0, 1e200, 1e-200):
        s = np.array([k, k, 1.0])[:, None]
        beta, beta0 = _joint(G * s, B * s[:, 0], np.ones((3, 4), bool), 12)
        np.testing.assert_allclose(beta, want[0], rtol=1e-12, atol=1e-15)
        np.testing.assert_allclose(beta0, want[1], rtol=1e-12)


def test_jpda_of_many_clusters_at_once_is_each_cluster_s_alone(exact_by):
    """Nine blocks of 1-4 tracks and 1-6 detections (some summed by their tracks, some by
    their detections; the one track of (1, 3) alone in its cluster, by PDA's closed form),
    placed apart in one problem, each against the brute force of its own block (a block
    that falls into two clusters is their product), and two tracks with nothing in their
    gates left alone."""
    rng = np.random.default_rng(7)
    shapes = [(2, 3), (2, 5), (3, 3), (3, 6), (4, 2), (3, 1), (2, 2), (4, 4), (1, 3)]
    T, D = sum(t for t, _ in shapes) + 2, sum(d for _, d in shapes)
    lik, gate = rng.uniform(0.001, 0.05, (T, D)), np.zeros((T, D), bool)
    blocks, t0, d0 = [], 0, 0
    for t, d in shapes:
        g = rng.random((t, d)) < 0.8
        g[np.arange(t), np.arange(t) % d] = True  # each track with a detection in its gate
        g[np.arange(d) % t, np.arange(d)] = True  # one cluster: every detection gated
        gate[t0:t0 + t, d0:d0 + d] = g
        blocks.append((slice(t0, t0 + t), slice(d0, d0 + d)))
        t0, d0 = t0 + t, d0 + d
    pd, lam, pg = 0.85, 0.01, 0.97
    beta, beta0 = jpda_weights(lik, gate, p_detect=pd, clutter_density=lam, p_gate=pg)
    for rows, cols in blocks:
        want_b, want_b0 = brute_jpda(np.where(gate, pd * lik / lam, 0.0)[rows, cols],
                                     1 - pd * pg)
        np.testing.assert_allclose(beta[rows, cols], want_b, rtol=1e-10, atol=1e-14)
        np.testing.assert_allclose(beta0[rows], want_b0, rtol=1e-10)
    assert beta0[-2:].tolist() == [1.0, 1.0] and not beta[-2:].any()
    assert beta[~gate].max() == 0.0


def equal_weights(T, D, pd=0.9, lam=0.01, pg=0.99, ell=0.004):
    """JPDA of a dense cluster, every track in every detection's gate with one likelihood,
    in closed form: the events that pair k tracks number C(T, k) C(D, k) k!, each weighing
    G^k B^(T - k), or (G / B)^k over B^T, so a track is missed with probability
    sum_k (1 - k/T) w_k / sum_k w_k and takes each detection with an equal share of the
    rest. Returns vistrack's beta and beta0 and the closed form's two values."""
    G, B = pd * ell / lam, 1 - pd * pg
    k = np.arange(min(T, D) + 1)
    w = np.array([math.comb(T, i) * math.comb(D, i) * math.factorial(i) * (G / B) ** i
                  for i in k])
    missed = float(((1 - k / T) * w).sum() / w.sum())
    beta, beta0 = jpda_weights(np.full((T, D), ell), np.ones((T, D), bool), p_detect=pd,
                               clutter_density=lam, p_gate=pg)
    return beta, beta0, (1 - missed) / D, missed


@pytest.mark.parametrize("T, D", [(12, 12), (14, 5), (5, 14), (1, 9), (400, 2), (2, 400),
                                  (12, 40)])
def test_jpda_of_a_dense_cluster_of_equal_weights_is_the_closed_form(T, D):
    """A 12 x 12 cluster has 1.4e11 events; it is computed exactly, not by Fitzgerald's
    approximation. 400 tracks sharing 2 detections: the sums carry B^400 (1e-385), which
    underflowed to an error (or, at 200 tracks and B = 0.02, to probabilities over 1)
    before they were rescaled row by row."""
    beta, beta0, share, missed = equal_weights(T, D)
    np.testing.assert_allclose(beta0, missed, rtol=1e-12)
    np.testing.assert_allclose(beta, share, rtol=1e-12)


def test_clusters_of_two_tracks_have_no_cancellation():
    """Clusters of two tracks have a closed form of their own, whose terms must not cancel:
    two tracks that share a heavy detection, the second also seeing a faint one (1e-9 of
    it), and misses weighing 1e-12, where the events that give each track a detection
    weigh S1 S2 - sum_j G1j G2j = (1 + 1e-9) - 1 if written so (8e-8 off in floating
    point). Against every event written out, to 1e-10."""
    G = np.array([[1.0, 0.0], [1.0, 1e-9]])
    B = 1e-12
    beta, beta0 = jpda_weights(G, G > 0, p_detect=1.0, p_gate=1.0 - B, clutter_density=1.0)
    want_b, want_b0 = brute_jpda(G, 1.0 - (1.0 - B))
    np.testing.assert_allclose(beta, want_b, rtol=1e-10, atol=1e-300)
    np.testing.assert_allclose(beta0, want_b0, rtol=1e-10)


def test_clusters_of_two_tracks_with_huge_weights_do_not_overflow():
    """Weights of 1e200 (a tiny innovation covariance, or a clutter density in odd units):
    an event's two pairs weigh 1e400, past a float, and the closed form gave NaN. Each
    event has one factor of each track's, so (G s, B) has the probabilities of (G, B / s):
    against every event written out at the smaller scale."""
    g = np.array([[1.0, 0.5], [0.7, 1.0]])
    pd, pg = 0.9, 0.99
    beta, beta0 = jpda_weights(1e200 * g, np.ones((2, 2), bool), p_detect=pd, p_gate=pg,
                               clutter_density=1.0)
    want_b, want_b0 = brute_jpda(pd * g, (1 - pd * pg) * 1e-200)
    np.testing.assert_allclose(beta, want_b, rtol=1e-10)
    np.testing.assert_allclose(beta0, want_b0, rtol=1e-10, atol=1e-300)


def _log_brute_jipda(log_lik, gate, eps, pd, log_lam, pg):
    """JIPDA's probabilities with every joint event written out in logarithms (a weight
    past the largest float is a finite logarithm): each track absent (1 - eps), there and
    missed (eps (1 - pd pg)) or there with detection j (eps pd lik / lam). eps = 1 is JPDA,
    one track alone IPDA (and PDA with eps = 1)."""
    from scipy.special import logsumexp

    T, D = log_lik.shape
    logs, takes = [], []
    for event in itertools.product(*[["absent", "missed"] + [j for j in range(D) if gate[t, j]]
                                     for t in range(T)]):
        used = [j for j in event if not isinstance(j, str)]
        if len(used) != len(set(used)):
            continue
        lw = 0.0
        for t, j in enumerate(event):
            miss = eps[t] * (1 - pd * pg)  # (0 with P_D P_G = 1: no such event)
            lw += (math.log1p(-eps[t]) if j == "absent" and eps[t] < 1 else -math.inf
                   if j == "absent" else (math.log(miss) if miss > 0 else -math.inf)
                   if j == "missed" else math.log(eps[t] * pd) + log_lik[t, j] - log_lam)
        logs.append(lw)
        takes.append(event)
    logs = np.array(logs) - logsumexp(logs)
    ex, joint, missed = np.zeros(T), np.zeros((T, D)), np.zeros(T)
    for lw, event in zip(logs, takes):
        for t, j in enumerate(event):
            if j != "absent":
                ex[t] += math.exp(lw)
            if j == "missed":  # (summed, not 1 - the others: that cancels to 0)
                missed[t] += math.exp(lw)
            elif not isinstance(j, str):
                joint[t, j] += math.exp(lw)
    return joint / ex[:, None], missed / ex, ex


def test_weights_past_the_largest_float_give_the_limit_not_nan():
    """A likelihood of 1e200 over a clutter density of 1e-110 is a weight of 1e310, past a
    float: PDA, JPDA, IPDA and JIPDA gave NaN probabilities without a word. Each track's
    factors are scaled alike where one overflows; against every event written out in
    logarithms."""
    from vistrack.association import ipda_weights, jipda_weights

    log_lik = np.log(np.array([[1e200, 1.0, 1e199], [1.0, 1e200, 3.0], [2.0, 0.5, 1.0]]))
    gate = np.array([[True, True, True], [True, True, False], [True, True, True]])
    lik, pd, lam, pg = np.exp(log_lik), 0.9, 1e-110, 0.99
    eps = np.array([0.5, 0.7, 0.9])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # (overflow encountered in multiply, before)
        b, b0 = pda_weights(lik[:1], gate[:1], p_detect=pd, clutter_density=lam, p_gate=pg)
        jb, jb0 = jpda_weights(lik, gate, p_detect=pd, clutter_density=lam, p_gate=pg)
        ib, ib0, iex = ipda_weights(lik, gate, eps, p_detect=pd, clutter_density=lam,
                                    p_gate=pg)
        qb, qb0, qex = jipda_weights(lik, gate, eps, p_detect=pd, clutter_density=lam,
                                     p_gate=pg)
    ones = np.ones(3)
    for got, want in [((b, b0), _log_brute_jipda(log_lik[:1], gate[:1], ones[:1], pd,
                                                 math.log(lam), pg)[:2]),
                      ((jb, jb0), _log_brute_jipda(log_lik, gate, ones, pd, math.log(lam),
                                                   pg)[:2]),
                      ((qb, qb0, qex), _log_brute_jipda(log_lik, gate, eps, pd, math.log(lam),
                                                        pg))]:
        for g, w in zip(got, want):
            assert np.isfinite(g).all()
            np.testing.assert_allclose(g, w, rtol=1e-9, atol=1e-300)
    for t in range(3):
        want = _log_brute_jipda(log_lik[t:t + 1], gate[t:t + 1], eps[t:t + 1], pd,
                                math.log(lam), pg)
        for g, w in zip((ib[t:t + 1], ib0[t:t + 1], iex[t:t + 1]), want):
            np.testing.assert_allclose(g, w, rtol=1e-9, atol=1e-300)


def test_weights_whose_sum_passes_the_largest_float_and_the_cheap_jpda_of_them():
    """Finite weights whose sum passes the largest float (two of 9e307) gave probabilities of
    0 (IPDA: a track with two sure detections did not exist); and a rescaled track in
    Fitzgerald's cheap JPDA (whose column sums mix the tracks) read as missed. Oracles: the
    closed forms in exact rational arithmetic."""
    from fractions import Fraction as F

    from vistrack.association import ipda_weights

    lik, gate = np.array([[1e304, 1e304]]), np.ones((1, 2), bool)
    b, b0 = pda_weights(lik, gate, clutter_density=1e-4)
    np.testing.assert_allclose(b, [[0.5, 0.5]], rtol=1e-12)
    assert 0 < b0[0] < 1e-300
    b, b0, ex = ipda_weights(lik, gate, [0.5], clutter_density=1e-4)
    np.testing.assert_allclose(b, [[0.5, 0.5]], rtol=1e-12)
    np.testing.assert_allclose(ex, [1.0], rtol=1e-12)
    # the cheap JPDA (max_exact 0), its formula in exact arithmetic: G / (S_t + S_j - G + B)
    pd, pg, lam = 0.9, 0.99, 1e-4
    lik = np.array([[1e305, 2e305, 0.0], [1.0, 3.0, 0.5], [0.0, 2.0, 1.0]])
    gate = lik > 0
    beta, beta0 = jpda_weights(lik, gate, p_detect=pd, p_gate=pg, clutter_density=lam,
                               max_exact=0)
    G = [[F(pd) * F(x) / F(lam) if x > 0 else F(0) for x in row] for row in lik]
    B = 1 - F(pd) * F(pg)
    want = np.zeros((3, 3))
    want0 = np.zeros(3)
    for t in range(3):
        b = [G[t][j] / (sum(G[t]) + sum(G[u][j] for u in range(3)) - G[t][j] + B)
             if G[t][j] else F(0) for j in range(3)]
        b0 = max(F(0), 1 - sum(b))
        tot = sum(b) + b0
        want[t] = [float(x / tot) for x in b]
        want0[t] = float(b0 / tot)
    np.testing.assert_allclose(beta, want, rtol=1e-9, atol=1e-300)
    # (beta0 is 1 minus the row's sum, by the method's definition: to a few hundred units of
    # a float's rounding of 1, here for a true 1e-305)
    np.testing.assert_allclose(beta0, want0, rtol=1e-9, atol=1e-13)


def test_weights_spanning_more_than_a_float_give_the_exact_answer_not_nan():
    """With P_D P_G = 1 a track certain to exist has a miss of weight 0, and the other two
    tracks' misses are the only events left. Rescaled to weights of about 1 (not 1e300), two
    misses of 5e-310 multiplied to 0: JIPDA gave NaN, and JPDA a row summing to 0.59. Now
    the weights of 1e309 give the exact answer; and so do weights of 1e328 against a miss of
    0.5, past what any scaling of a float holds, which were named as too wide: their cluster
    is summed in logarithms. Beside them, three tracks among two detections whose weights
    span 1e328 to 1e-280: each track's probabilities were those of another event (the second
    track took the second detection, where, given it exists, it takes the first), against
    every event written out in logarithms."""
    from vistrack.association import jipda_weights

    b, b0, ex = jipda_weights(np.array([[1e306], [1e306], [1.0]]), np.ones((3, 1), bool),
                              [0.5, 0.5, 1.0], p_detect=1.0, p_gate=1.0,
                              clutter_density=1e-3)
    np.testing.assert_array_equal(ex, [0, 0, 1])
    np.testing.assert_array_equal(b.ravel(), [0, 0, 1])
    b, b0, ex = jipda_weights(np.array([[1e308], [1e308], [1.0]]), np.ones((3, 1), bool),
                              [0.5, 0.5, 1.0], p_detect=1.0, p_gate=1.0, clutter_density=1e-20)
    np.testing.assert_array_equal(ex, [0, 0, 1])
    np.testing.assert_array_equal(b.ravel(), [0, 0, 1])
    lik = np.array([[1e308, 1e308], [1e308, 1.0], [1.0, 1e-300]])
    got = jipda_weights(lik, np.ones((3, 2), bool), [0.5, 0.5, 1.0], p_detect=1.0,
                        p_gate=1.0, clutter_density=1e-20)
    want = _log_brute_jipda(np.log(lik), np.ones((3, 2), bool), [0.5, 0.5, 1.0], 1.0,
                            math.log(1e-20), 1.0)
    for g, w in zip(got, want):
        np.testing.assert_allclose(g, w, atol=1e-12)
    np.testing.assert_allclose(got[0], [[0, 1], [1, 0], [1, 0]], atol=1e-7)
    # a cluster's column sum past the largest float, every row finite (three weights of
    # 9e307 on one detection): the cheap JPDA gave 0 and 1; Fitzgerald's formula, 1/3, 2/3
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        b, b0 = jpda_weights(np.array([[1e304]] * 3), np.ones((3, 1), bool),
                             clutter_density=1e-4, max_exact=0)
    np.testing.assert_allclose(b.ravel(), [1 / 3] * 3, rtol=1e-12)
    np.testing.assert_allclose(b0, [2 / 3] * 3, rtol=1e-12)
    # two tracks, one detection: which misses weighs by their misses' ratio, which a
    # subnormal scale (weights taken to 1) held to a few digits (0.6658 for 2/3)
    b, _ = jpda_weights(np.array([[1e308], [5e307]]), np.ones((2, 1), bool),
                        clutter_density=1e-12)
    np.testing.assert_allclose(b.ravel(), [2 / 3, 1 / 3], rtol=1e-9)


def test_subset_sums_hold_weights_that_span_past_a_float(monkeypatch):
    """The sums by subsets (a large cluster; forced here on small ones) scaled each row's
    partial sums to a largest of 1, so a partial sum more than 1e308 below it was lost, and
    with it every event it led to: with P_D P_G = 1 the one event that misses no track
    (weight 1e-247) was lost and a miss given probability 1; weights of 1e-150 to 1e150 gave
    errors of 1 and NaN. Such a cluster is now summed in logarithms, against every event
    written out in logarithms."""
    from vistrack.association import pda

    monkeypatch.setattr(pda, "_ENUMERATED", 0)
    # P_D = P_G = 1: the events that miss the fewest tracks
    lik = np.array([[1e-250, 0.0], [1e80, 1e3]])
    b, b0 = jpda_weights(lik, lik > 0, p_detect=1.0, clutter_density=1.0, p_gate=1.0)
    np.testing.assert_array_equal(b, [[1, 0], [0, 1]])
    np.testing.assert_array_equal(b0, [0, 0])
    rng = np.random.default_rng(9)
    for T, D in [(6, 3), (3, 6), (5, 4)]:
        lik = 10 ** rng.uniform(-150, 150, (T, D))
        gate = rng.random((T, D)) < 0.9
        b, b0 = jpda_weights(lik, gate, p_detect=0.9, clutter_density=1.0, p_gate=0.99)
        wb, wb0, _ = _log_brute_jipda(np.log(lik), gate, np.ones(T), 0.9, 0.0, 0.99)
        np.testing.assert_allclose(b, wb, atol=1e-12)
        np.testing.assert_allclose(b0, wb0, atol=1e-12)
        assert np.isfinite(b).all() and np.isfinite(b0).all()


def test_subset_sums_of_ordinary_weights_do_not_take_the_logarithms(monkeypatch):
    """The logarithms are the exception: weights of 1e-10 to 1e10 are summed as before."""
    from vistrack.association import pda

    monkeypatch.setattr(pda, "_ENUMERATED", 0)
    monkeypatch.setattr(pda, "_matchings_log", None)  # (calling it would raise)
    rng = np.random.default_rng(4)
    lik = 10 ** rng.uniform(-10, 10, (6, 5))
    b, b0 = jpda_weights(lik, np.ones((6, 5), bool), p_detect=0.9, clutter_density=1.0)
    wb, wb0, _ = _log_brute_jipda(np.log(lik), np.ones((6, 5), bool), np.ones(6), 0.9, 0.0,
                                  0.99)
    np.testing.assert_allclose(b, wb, atol=1e-12)
    np.testing.assert_allclose(b0, wb0, atol=1e-12)


def test_max_exact_bounds_and_unbounds_the_exact_sums():
    """max_exact 0 asks for the cheap JPDA on every cluster of more than one track, two
    tracks included (the formula written out); a huge max_exact (2**62) is no bound, and
    costs nothing to check (its bound on the work was computed as 2**max_exact: seconds,
    or a MemoryError)."""
    g = np.array([[1.0, 0.5], [0.7, 1.0]])
    kw = dict(p_detect=0.9, p_gate=0.99, clutter_density=1.0)
    beta, beta0 = jpda_weights(g, np.ones((2, 2), bool), max_exact=0, **kw)
    G, B = 0.9 * g, 1 - 0.9 * 0.99
    b = G / (G.sum(1)[:, None] + G.sum(0)[None, :] - G + B)
    b0 = np.clip(1 - b.sum(1), 0, 1)
    np.testing.assert_allclose(beta, b / (b.sum(1) + b0)[:, None], rtol=1e-12)
    rng = np.random.default_rng(4)
    lik, gate = rng.uniform(0.5, 1.5, (3, 3)), np.ones((3, 3), bool)
    for a, w in zip(jpda_weights(lik, gate, max_exact=2**62, **kw),
                    brute_jpda(0.9 * lik, 1 - 0.9 * 0.99)):
        np.testing.assert_allclose(a, w, rtol=1e-10)


def test_a_cluster_too_costly_to_sum_gets_the_cheap_approximation():
    """12 tracks among 200 detections, all in one another's gates: summed exactly it took
    60 ms (12 among 1,000, 0.3 s), beyond four times a 12 x 12 cluster's cost, so it gets
    Fitzgerald's cheap JPDA, as it did before the sums (its formula written out here), and
    12 among 40 is still summed exactly (the closed form above)."""
    beta, beta0, share, missed = equal_weights(12, 200)
    assert abs(beta0[0] - missed) > 0.01
    pd, lam, pg, ell = 0.9, 0.01, 0.99, 0.004
    g = np.full((12, 200), pd * ell / lam)
    b = g / (g.sum(1)[:, None] + g.sum(0)[None, :] - g + (1 - pd * pg))
    b0 = np.clip(1 - b.sum(1), 0, 1)
    np.testing.assert_allclose(beta, b / (b.sum(1) + b0)[:, None], rtol=1e-12)
    np.testing.assert_allclose(beta0, b0 / (b.sum(1) + b0), rtol=1e-12, atol=1e-15)


def test_a_pair_whose_weight_underflows_is_in_no_event():
    """A likelihood of 5e-324 over a clutter density of 10 weighs 0 as a float. With P_D
    P_G = 1 the lone track it belonged to got 0 / 0 (NaN, and a NaN existence from JIPDA);
    it is left as a track with nothing in its gate is (beta0 1, as pda_weights leaves it),
    and the other track keeps its detection."""
    from vistrack.association import jipda_weights

    lik = np.array([[5e-324, 0.0], [0.0, 0.2]])
    gate = np.array([[True, False], [False, True]])
    kw = dict(p_detect=1.0, clutter_density=10.0, p_gate=1.0)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        b, b0 = jpda_weights(lik, gate, **kw)
        pb, pb0 = pda_weights(lik, gate, **kw)
        jb, jb0, ex = jipda_weights(lik, gate, [0.5, 1.0], **kw)
    assert b.tolist() == pb.tolist() == [[0.0, 0.0], [0.0, 1.0]]
    assert b0.tolist() == pb0.tolist() == [1.0, 0.0]
    assert np.isfinite(jb).all() and np.isfinite(ex).all() and ex[1] == 1.0


def test_max_exact_must_be_a_whole_number():
    gate = np.ones((2, 2), bool)
    for bad in (-1, 2.5, True):
        with pytest.raises(ValueError, match=re.escape(f"max_exact must be a whole number "
                                                       f">= 0; got {bad!r}")):
            jpda_weights(np.full((2, 2), 0.01), gate, max_exact=bad)
    with pytest.raises(TypeError, match="max_exact"):
        jpda_weights(np.full((2, 2), 0.01), gate, max_exact="8")


def test_jpda_reduces_to_pda_and_cheap_jpda_is_a_distribution():
    rng = np.random.default_rng(3)
    lik = rng.uniform(0.001, 0.05, (1, 6))
    gate = np.ones((1, 6), bool)
    for a, b in zip(jpda_weights(lik, gate), pda_weights(lik, gate)):
        np.testing.assert_allclose(a, b, rtol=1e-12)
    lik = rng.uniform(0.001, 0.05, (12, 12))
    gate = rng.random((12, 12)) < 0.5
    beta, beta0 = jpda_weights(lik, gate, max_exact=4)
    np.testing.assert_allclose(beta.sum(1) + beta0, 1.0)
    assert np.all(beta[~gate] == 0) and np.all(beta >= 0)
    with pytest.raises(ValueError, match="clutter_density must be a finite number > 0"):
        pda_weights(lik, gate, clutter_density=0.0)


def test_a_certain_detection_p_detect_and_p_gate_1_is_the_limit_of_nearly_certain():
    """P_D P_G = 1 makes every event that misses a track weigh 0. The weights are then the
    limit of P_G -> 1: a track with nothing in its gate kept (beta0 = 1), and two tracks that
    can share one detection only split it by their likelihoods. Before, both gave NaN."""
    from vistrack.association import jpda_weights, pda_weights

    b, b0 = pda_weights(np.array([[0.5, 0.2]]), np.array([[False, False]]), p_detect=1.0,
                        p_gate=1.0)
    assert b.tolist() == [[0.0, 0.0]] and b0.tolist() == [1.0]
    rng = np.random.default_rng(2)
    for _ in range(200):
        T, D = rng.integers(1, 5, 2)
        lik = rng.uniform(0.01, 1.0, (T, D))
        gate = rng.random((T, D)) < 0.6
        b, b0 = jpda_weights(lik, gate, p_detect=1.0, p_gate=1.0)
        near, near0 = jpda_weights(lik, gate, p_detect=1.0, p_gate=1.0 - 1e-9)
        assert np.isfinite(b).all() and np.isfinite(b0).all()
        np.testing.assert_allclose(b, near, atol=1e-6)
        np.testing.assert_allclose(b0, near0, atol=1e-6)
        np.testing.assert_allclose(b.sum(1) + b0, 1.0)
        pb, pb0 = pda_weights(lik, gate, p_detect=1.0, p_gate=1.0)
        pn, pn0 = pda_weights(lik, gate, p_detect=1.0, p_gate=1.0 - 1e-9)
        np.testing.assert_allclose(pb, pn, atol=1e-6)
        np.testing.assert_allclose(pb0, pn0, atol=1e-6)


def brute_jipda(lik, gate, eps, pd, lam, pg):
    """Every joint hypothesis of which tracks exist and which detection each existing one
    made, weighed by the likelihood of the whole set of detections: lam for each detection
    that is clutter, pd * lik for a track's (in its gate), 1 - pd * pg for a track that
    exists and made none, and each track's prior of existing or not."""
    T, D = lik.shape
    ex, joint = np.zeros(T), np.zeros((T, D))
    total = 0.0
    options = [["absent", "missed"] + [j for j in range(D) if gate[t, j]] for t in range(T)]
    for event in itertools.product(*options):
        used = [j for j in event if not isinstance(j, str)]
        if len(used) != len(set(used)):
            continue
        w = lam ** (D - len(used))
        for t, j in enumerate(event):
            w *= (1 - eps[t] if j == "absent" else
                  eps[t] * (1 - pd * pg) if j == "missed" else eps[t] * pd * lik[t, j])
        total += w
        for t, j in enumerate(event):
            if j != "absent":
                ex[t] += w
            if not isinstance(j, str):
                joint[t, j] += w
    ex, joint = ex / total, joint / total
    return joint / ex[:, None], 1 - joint.sum(1) / ex, ex


@pytest.mark.parametrize("seed", range(12))
def test_jipda_and_ipda_equal_brute_force_over_existence_and_events(seed):
    """JIPDA's existence and its association probabilities given existence against every
    joint hypothesis written out; IPDA's against the same with each track alone."""
    from vistrack.association import ipda_weights, jipda_weights

    rng = np.random.default_rng(seed)
    T, D = int(rng.integers(1, 4)), int(rng.integers(0, 5))
    lik = rng.uniform(0.001, 0.05, (T, D))
    gate = rng.random((T, D)) < 0.7
    eps = rng.uniform(0.05, 0.99, T)
    pd, lam, pg = 0.85, 0.01, 0.97
    beta, beta0, ex = jipda_weights(lik, gate, eps, p_detect=pd, clutter_density=lam, p_gate=pg)
    want = brute_jipda(lik, gate, eps, pd, lam, pg)
    for got, w in zip((beta, beta0, ex), want):
        np.testing.assert_allclose(got, w, rtol=1e-10, atol=1e-14)
    beta, beta0, ex = ipda_weights(lik, gate, eps, p_detect=pd, clutter_density=lam, p_gate=pg)
    for t in range(T):
        want = brute_jipda(lik[t:t + 1], gate[t:t + 1], eps[t:t + 1], pd, lam, pg)
        for got, w in zip((beta[t:t + 1], beta0[t:t + 1], ex[t:t + 1]), want):
            np.testing.assert_allclose(got, w, rtol=1e-10, atol=1e-14)
    # given existence, IPDA's association is PDA's
    b, b0 = pda_weights(lik, gate, p_detect=pd, clutter_density=lam, p_gate=pg)
    np.testing.assert_allclose(beta, b, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(beta0, b0, rtol=1e-12)


@pytest.mark.parametrize("seed", range(8))
def test_jipda_with_tracks_certain_or_not_there_equals_brute_force(seed):
    """Existence exactly 0 (a track whose weights are all 0, in no cluster) and exactly 1
    beside others, against every joint hypothesis written out; a track that is not there
    keeps its existence 0 and takes no detection."""
    from vistrack.association import jipda_weights

    rng = np.random.default_rng(100 + seed)
    T, D = int(rng.integers(2, 5)), int(rng.integers(1, 5))
    lik = rng.uniform(0.001, 0.05, (T, D))
    gate = rng.random((T, D)) < 0.8
    eps = rng.choice([0.0, 1.0, 0.5, 0.9], T)
    eps[:2] = [0.0, 1.0]
    pd, lam, pg = 0.85, 0.01, 0.97
    beta, beta0, ex = jipda_weights(lik, gate, eps, p_detect=pd, clutter_density=lam, p_gate=pg)
    with np.errstate(invalid="ignore", divide="ignore"):  # (the absent track's 0 / 0)
        want_b, want_b0, want_ex = brute_jipda(lik, gate, eps, pd, lam, pg)
    np.testing.assert_allclose(ex, want_ex, rtol=1e-10, atol=1e-14)
    there = eps > 0
    np.testing.assert_allclose(beta[there], want_b[there], rtol=1e-10, atol=1e-14)
    np.testing.assert_allclose(beta0[there], want_b0[there], rtol=1e-10, atol=1e-14)
    assert ex[0] == 0.0 and beta0[0] == 1.0 and not beta[0].any()


def test_jipda_of_tracks_certain_to_exist_and_to_be_detected_is_the_limit_of_existence():
    """P_D P_G = 1 with existence 1 is a contradiction wherever a track must go without a
    detection (two tracks, one detection): JIPDA gives the limit as the existence tends to
    1, against every joint hypothesis written out at 1 - 1e-9, for existence, association
    given existence and all."""
    from vistrack.association import jipda_weights

    rng = np.random.default_rng(4)
    for _ in range(200):
        T, D = int(rng.integers(1, 4)), int(rng.integers(0, 4))
        lik = rng.uniform(0.001, 0.05, (T, D))
        gate = rng.random((T, D)) < 0.7
        eps = rng.choice([1.0, 0.5, 0.9], T)
        b, b0, ex = jipda_weights(lik, gate, eps, p_detect=1.0, clutter_density=0.01,
                                  p_gate=1.0)
        with np.errstate(invalid="ignore", divide="ignore"):
            wb, wb0, wex = brute_jipda(lik, gate, np.where(eps == 1, 1 - 1e-9, eps), 1.0,
                                       0.01, 1.0)
        np.testing.assert_allclose(ex, wex, atol=1e-6)
        there = wex > 1e-3
        np.testing.assert_allclose(b[there], wb[there], atol=1e-6)
        np.testing.assert_allclose(b0[there], wb0[there], atol=1e-6)
    # the docstring's case: one detection between two tracks
    b, b0, ex = jipda_weights([[0.02], [0.01]], [[True], [True]], [1.0, 1.0], p_detect=1.0,
                              clutter_density=0.01, p_gate=1.0)
    np.testing.assert_allclose(ex, [2 / 3, 1 / 3])
    assert b.ravel().tolist() == [1.0, 1.0] and b0.tolist() == [0.0, 0.0]


def test_jipda_of_certain_tracks_is_jpda_and_clutter_lowers_existence_on_average():
    """With every existence 1, JIPDA is JPDA and the existence stays 1. And IPDA's evidence
    in clutter alone (Poisson detections, uniform over a track's gate) multiplies the odds of
    existence by 1 on average: the mean of the posterior odds over many draws equals the
    prior's, while the median falls."""
    from scipy.stats import chi2

    from vistrack.association import ipda_weights, jipda_weights

    rng = np.random.default_rng(5)
    lik = rng.uniform(0.001, 0.05, (3, 4))
    gate = rng.random((3, 4)) < 0.7
    b, b0, ex = jipda_weights(lik, gate, np.ones(3))
    jb, jb0 = jpda_weights(lik, gate)
    np.testing.assert_allclose(b, jb, rtol=1e-12)
    np.testing.assert_allclose(b0, jb0, rtol=1e-12)
    np.testing.assert_allclose(ex, 1.0)
    # one track at the origin, S = I in 2-D, gate 99 %: its area is pi * g; clutter of
    # density lam falls in it, each point's likelihood N(z; 0, I)
    pd, pg, lam = 0.9, 0.99, 0.02
    g = chi2.ppf(pg, 2)
    odds = []
    for _ in range(20000):
        k = rng.poisson(lam * np.pi * g)
        r = np.sqrt(g * rng.random(k))
        lk = np.exp(-0.5 * r ** 2) / (2 * np.pi)
        e = ipda_weights(lk[None], np.ones((1, k), bool), [0.5], p_detect=pd,
                         clutter_density=lam, p_gate=pg)[2][0]
        odds.append(e / (1 - e))
    assert abs(np.mean(odds) - 1.0) < 0.05 and np.median(odds) < 0.2


def test_a_nan_detection_outside_every_gate_changes_nothing():
    """A NaN detection is outside the gates chi2_gate draws, so its weight is 0; it still
    made every track's mean and covariance NaN (0 × NaN in the sums)."""
    from vistrack.association import chi2_gate, mahalanobis

    rng = np.random.default_rng(3)
    g, H, R = random_tracks(rng, 3)
    Z = np.vstack([rng.normal(size=(2, 2)), [np.nan, np.nan]])
    zp, S = g.mean @ H.T, H @ g.cov @ H.T + R
    gate = chi2_gate(mahalanobis(zp, S, Z), 2)
    assert not gate[:, 2].any()
    for weigh in (pda_weights, jpda_weights):
        beta, beta0 = weigh(likelihoods(zp, S, Z), gate, clutter_density=0.01)
        assert (beta[:, 2] == 0).all()
        post = pda_update(g, Z, H, R, beta, beta0)
        kept = pda_update(g, Z[:2], H, R, beta[:, :2], beta0)  # the oracle: the column dropped
        np.testing.assert_allclose(post.mean, kept.mean, rtol=0, atol=1e-12)
        np.testing.assert_allclose(post.cov, kept.cov, rtol=0, atol=1e-12)


@pytest.mark.parametrize("weigh", ["pda", "jpda", "ipda", "jipda"])
def test_the_four_weightings_name_a_nan_likelihood_in_the_gate_and_a_gate_of_another_shape(weigh):
    """A NaN likelihood in the gate gave three different answers (NaN weights, the whole
    gate dropped, the pair dropped); a gate of another shape, numpy's broadcast error."""
    from vistrack import association

    fn = getattr(association, f"{weigh}_weights")
    extra = ([0.5],) if weigh.startswith(("i", "ji")) else ()
    with pytest.raises(ValueError, match=r"lik\[0, 0\] = nan"):
        fn(np.array([[np.nan, 0.1]]), np.ones((1, 2), bool), *extra)
    with pytest.raises(ValueError,
                       match=r"gate must have the shape of lik, \(1, 3\); got \(1, 2\)"):
        fn(np.ones((1, 3)), np.ones((1, 2), bool), *extra)
    # outside the gate a NaN likelihood is not looked at: the same as a likelihood of 0
    a = fn(np.array([[np.nan, 0.1]]), np.array([[False, True]]), *extra)
    b = fn(np.array([[0.0, 0.1]]), np.array([[False, True]]), *extra)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


@pytest.mark.parametrize("change,message", [
    ({"g": Gaussian(np.zeros(2), np.eye(2))}, "g must be a batch of tracks, batch shape (T,)"),
    ({"Z": np.zeros((2, 3))}, "Z must have shape (D, 2); got (2, 3)"),
    ({"beta": np.full((2, 2), 0.5)}, "beta must have shape (1, 2), tracks by detections"),
    ({"beta0": np.zeros(2)}, "beta0 must have shape (1,); got (2,)"),
    ({"H": np.eye(3)}, "H must have shape (m, 2); got (3, 3)"),
    ({"R": np.eye(3)}, "R must have shape (2, 2), as H has 2 rows; got (3, 3)"),
    ({"Z": np.array([[0.5, 0.0], [np.nan, 0.0]])},
     "Z[1] is not finite but has weight beta[0, 1] = 0.4"),
    # weights that are not probabilities gave a covariance with a negative eigenvalue, or a
    # NaN mean, without a word
    ({"beta": np.array([[2.0, -1.0]]), "beta0": np.array([0.0])},
     "beta must hold probabilities in [0, 1]; beta[0, 0] = 2.0"),
    ({"beta": np.array([[0.5, np.nan]])},
     "beta must hold probabilities in [0, 1]; beta[0, 1] = nan"),
    ({"beta0": np.array([-0.1])}, "beta0 must hold probabilities in [0, 1]; beta0[0] = -0.1"),
    ({"beta": np.array([[0.5, 0.5]])},
     "beta0 and beta of a track must add up to 1 (one of its events happens); track 0's add "
     "up to 1.1"),
    # a model that is not one: NaN posteriors, or a covariance larger than the prior's after
    # a correction (R = -3 I), or numpy's "Singular matrix", each without naming it
    ({"R": np.full((2, 2), np.nan)}, "R must be finite; R[0, 0] = nan"),
    ({"H": np.array([[1.0, np.inf], [0.0, 1.0]])}, "H must be finite; H[0, 1] = inf"),
    ({"g": Gaussian(np.array([[np.nan, 0.0]]), np.eye(2)[None])},
     "g.mean must be finite; g.mean[0, 0] = nan"),
    ({"g": Gaussian(np.zeros((1, 2)), np.full((1, 2, 2), np.nan))},
     "g.cov must be finite; g.cov[0, 0, 0] = nan"),
    ({"R": -3 * np.eye(2)}, "R must be positive semi-definite"),
    ({"R": np.array([[1.0, 0.5], [0.0, 1.0]])}, "R must be symmetric"),
    ({"g": Gaussian(np.zeros((1, 2)), np.zeros((1, 2, 2))), "R": np.zeros((2, 2))},
     "the innovation covariance S = H P H' + R of track 0 is singular"),
])
def test_pda_update_names_what_does_not_fit(change, message):
    args = {"g": Gaussian(np.zeros((1, 2)), np.eye(2)[None]), "Z": np.zeros((2, 2)),
            "H": np.eye(2), "R": np.eye(2), "beta": np.array([[0.5, 0.4]]),
            "beta0": np.array([0.1])} | change
    with pytest.raises(ValueError, match=re.escape(message)):
        pda_update(**args)


def test_likelihoods_names_s_and_z_of_the_wrong_shape_as_mahalanobis_does():
    zp = np.zeros((2, 2))
    with pytest.raises(ValueError, match=re.escape("S must have shape (2, 2, 2); got (2, 2)")):
        likelihoods(zp, np.eye(2), np.zeros((3, 2)))
    with pytest.raises(ValueError, match=re.escape("Z must have shape (D, 2); got (3, 3)")):
        likelihoods(zp, np.stack([np.eye(2)] * 2), np.zeros((3, 3)))
    assert likelihoods(zp, np.stack([np.eye(2)] * 2), []).shape == (2, 0)
    # a z_pred of another rank: Python's "too many values to unpack (expected 2)"
    from vistrack.association import mahalanobis

    for f in (likelihoods, mahalanobis):
        with pytest.raises(ValueError, match=re.escape("z_pred must have shape (T, m); got "
                                                       "(2, 1, 2)")):
            f(np.zeros((2, 1, 2)), np.stack([np.eye(2)] * 2), np.zeros((3, 2)))


def test_a_track_s_prediction_that_is_not_finite_is_named_not_dropped():
    """A NaN prediction's likelihoods were NaN, outside every gate: the track was given
    beta0 = 1 and never corrected, without a word. And numpy's Cholesky factor reads the
    lower triangle alone, so an S that is not symmetric was taken for another."""
    from vistrack.association import mahalanobis
    from vistrack.association.costs import mahalanobis_pairs

    S, Z = np.stack([np.eye(2)] * 2), np.zeros((3, 2))
    for f in (likelihoods, mahalanobis, lambda *a: mahalanobis_pairs(*a, threshold=9.0)):
        with pytest.raises(ValueError, match=re.escape("z_pred must be finite; z_pred[1] = "
                                                       "[nan, 0.0]")):
            f(np.array([[0.0, 0.0], [np.nan, 0.0]]), S, Z)
        with pytest.raises(ValueError, match=re.escape("S must be symmetric; S[0, 0, 1] = 100.0 "
                                                       "but its transpose entry is 0.0")):
            f(np.zeros((2, 2)), np.array([[[1.0, 100.0], [0.0, 1.0]], np.eye(2)]), Z)


@pytest.mark.parametrize("weigh", ["pda", "jpda"])
def test_a_gate_of_other_than_true_or_false_is_named(weigh):
    """A gate of 0.5 or NaN was taken as inside."""
    from vistrack.association import pda_weights

    fn = pda_weights if weigh == "pda" else jpda_weights
    for bad in (0.5, np.nan):
        with pytest.raises(ValueError, match=re.escape("gate must hold True / False (or 1 / 0);"
                                                       " gate[0, 1] = ")):
            fn(np.full((1, 2), 0.1), np.array([[1.0, bad]]), clutter_density=0.01)
    a = fn(np.full((1, 2), 0.1), np.array([[1, 0]]), clutter_density=0.01)
    b = fn(np.full((1, 2), 0.1), np.array([[True, False]]), clutter_density=0.01)
    for x, y in zip(a, b):
        np.testing.assert_array_equal(x, y)


def test_chi2_gate_names_a_negative_distance_and_a_p_that_is_not_a_number():
    from vistrack.association import chi2_gate

    np.testing.assert_array_equal(chi2_gate(np.array([[np.nan, 1.0]]), 2), [[False, True]])
    with pytest.raises(ValueError, match=re.escape("d2 must hold squared distances, >= 0; "
                                                   "d2[0, 1] = -1.0")):
        chi2_gate(np.array([[1.0, -1.0]]), 2)
    with pytest.raises(ValueError, match=re.escape("p must be a number in (0, 1); got "
                                                   "array([0.9 , 0.99])")):
        chi2_gate(np.array([[1.0]]), 2, p=np.array([0.9, 0.99]))


def test_pda_update_refuses_an_innovation_covariance_singular_to_rounding():
    """A rank-1 S whose pivot rounds to a tiny number above 0 (P = v v', R = 0) passed the
    solve, and the covariance grew in a direction the prior gave no variance (trace 1.75
    against the prior's 1.0), where kf_update and the association's costs refuse that S.
    Oracle: the rank of v v', 1; of 1,000 random such P, every one is refused now."""
    from vistrack import Gaussian
    from vistrack.filters import pda_update

    rng = np.random.default_rng(0)
    for v in [np.array([0.6, 0.8])] + [rng.normal(size=2) for _ in range(1000)]:
        P = np.outer(v, v)[None]
        with pytest.raises(ValueError, match=re.escape(
                "the innovation covariance S = H P H' + R of track 0 is singular")):
            pda_update(Gaussian(np.zeros((1, 2)), P), [[1.0, 2.0]], np.eye(2),
                       np.zeros((2, 2)), [[0.5]], [0.5])
    ok = pda_update(Gaussian(np.zeros((2, 2)), np.tile(np.eye(2), (2, 1, 1))),
                    [[1.0, 2.0]], np.eye(2), 0.1 * np.eye(2), [[0.5], [0.5]], [0.5, 0.5])
    assert np.isfinite(ok.mean).all()
    # axes of other units are no singularity: S = diag(1e4 + 1, 1e-7), a correlation near 1
    # and a tiny S are taken, and with one detection of weight 1 the update is Kalman's
    from vistrack.filters import kf_update

    for P, R in ((np.diag([1e4, 0.0]), np.diag([1.0, 1e-7])),
                 (np.array([[1.0, 1 - 1e-10], [1 - 1e-10, 1.0]]), np.zeros((2, 2))),
                 (np.zeros((2, 2)), 1e-300 * np.eye(2))):
        g = Gaussian(np.zeros((1, 2)), P[None])
        z = [[1e-6, 2e-6]]
        got = pda_update(g, z, np.eye(2), R, [[1.0]], [0.0])
        want = kf_update(g, z, np.eye(2), R)
        np.testing.assert_allclose(got.mean, want.mean, rtol=1e-6, atol=1e-12)


def test_probabilities_that_are_not_numbers_are_named():
    """A boolean p_detect, clutter_density or p_gate was taken as 1 (a clutter density of 1
    among them), an existence of [True] as 1; a string met "'<' not supported" and an array
    numpy's "truth value ... is ambiguous", naming neither."""
    from vistrack.association import ipda_weights

    L, G = np.array([[0.5]]), np.array([[True]])
    for kw in ("p_detect", "clutter_density", "p_gate"):
        for bad in (True, "0.9", np.array([0.9, 0.5])):
            with pytest.raises(TypeError, match=rf"{kw} must be a number; got"):
                pda_weights(L, G, **{kw: bad})
    with pytest.raises(TypeError, match=r"existence must be probabilities; got \[True\]"):
        ipda_weights(L, G, [True])
    with pytest.raises(TypeError, match=r"lik must be real numbers; got complex"):
        pda_weights(L + 1j, G)
    # numbers of other types are numbers: the same weights as floats (the oracle)
    from fractions import Fraction

    b, b0 = pda_weights(L, G, p_detect=Fraction(9, 10), clutter_density=np.float32(0.5))
    b_, b0_ = pda_weights(L, G, p_detect=0.9, clutter_density=0.5)
    np.testing.assert_allclose(b, b_, rtol=1e-7)


@pytest.mark.parametrize("lik, pd, lam, pg", [
    ([1.0, 3.0], 0.9, 1e-322, 0.99),
    ([1.0, 3.0], 1.0, 1e-305, 1 - 2**-52),
    ([1.0, 1.0], 1.0, 1e-310, 1 - 2**-52),
    ([0.02, 0.05], 1.0, 1e-320, 0.5),
])
def test_two_tracks_whose_miss_is_below_the_smallest_normal_float_are_exact(lik, pd, lam, pg):
    """Two tracks sharing a detection, whose miss weight against the track's largest weight
    is below the smallest normal float (2.2e-308): the closed form of two tracks kept a few
    of its digits, or none, and gave 0.333 / 0.667 for 0.25 / 0.75, or refused the weights
    as spanning more than a float holds (JPDA and JIPDA). Oracle: every joint event written
    out in logarithms."""
    lik = np.array(lik)[:, None]
    gate = np.ones((2, 1), bool)
    beta, beta0 = jpda_weights(lik, gate, p_detect=pd, clutter_density=lam, p_gate=pg)
    want, want0, _ = _log_brute_jipda(np.log(lik), gate, np.ones(2), pd, math.log(lam), pg)
    np.testing.assert_allclose(beta, want, rtol=1e-9)
    np.testing.assert_allclose(beta0, want0, rtol=1e-6, atol=1e-300)
    eps = np.array([0.6, 0.9])
    beta, beta0, ex = jipda_weights(lik, gate, eps, p_detect=pd, clutter_density=lam,
                                    p_gate=pg)
    want, want0, want_ex = _log_brute_jipda(np.log(lik), gate, eps, pd, math.log(lam), pg)
    np.testing.assert_allclose(beta, want, rtol=1e-9)
    np.testing.assert_allclose(ex, want_ex, rtol=1e-9)


@pytest.mark.parametrize("T, D, e", [(30, 12, 24.1), (12, 4, 70.0), (20, 3, 90.0),
                                     (30, 6, 45.0)])
def test_jpda_of_a_dense_cluster_of_heavy_weights_is_the_closed_form(T, D, e):
    """Weights 10^e times a miss's, in clusters summed by subsets: the backward pass took
    the product of two scaled sums below what a float holds, unguarded (and its margin was
    the smallest normal float, where 1e-280 was meant: the constant was defined twice), and
    a huge weight times it gave some tracks no detection at all (β0 1 against 0.85). The
    oracle: :func:`equal_weights`'s closed form, in logarithms."""
    pd, pg = 0.9, 0.99
    B = 1 - pd * pg
    ell = 10.0 ** e * B / pd  # G / B = 10^e at a clutter density of 1
    k = np.arange(min(T, D) + 1)
    logw = np.array([math.lgamma(T + 1) - math.lgamma(i + 1) - math.lgamma(T - i + 1)
                     + math.lgamma(D + 1) - math.lgamma(D - i + 1) + i * e * math.log(10)
                     for i in k])
    w = np.exp(logw - logw.max())
    missed = float(((1 - k / T) * w).sum() / w.sum())
    beta, beta0 = jpda_weights(np.full((T, D), ell), np.ones((T, D), bool), p_detect=pd,
                               clutter_density=1.0, p_gate=pg)
    np.testing.assert_allclose(beta0, missed, rtol=1e-9)
    np.testing.assert_allclose(beta, (1 - missed) / D, rtol=1e-9)


def test_subset_sums_of_a_huge_weight_give_every_row_its_share():
    """Three rows sharing one column at a weight of 1e200 against misses of 1: 1/3 each
    (by symmetry), where the subset sums gave the middle row 0."""
    from vistrack.association.pda import _matchings

    pair, row0, col0 = _matchings(np.full((3, 1), 1e200), np.ones(3), np.ones(1))
    np.testing.assert_allclose(pair.ravel(), [1 / 3] * 3, rtol=1e-12)


def test_a_large_likelihood_outside_the_gate_raises_no_overflow_warning():
    """A track whose weights overflow is rescaled; a likelihood of 1e300 outside its gate
    overflowed in the rescaling's product (then dropped by the gate: the weights were
    right) with a RuntimeWarning. Oracle: the closed form, beta = 1 for the one gated
    detection and beta0 = (1 - P_D P_G) lambda / (P_D lik) beside it."""
    import warnings

    from vistrack.association import pda_weights

    with warnings.catch_warnings():
        warnings.simplefilter("error")
        beta, beta0 = pda_weights(np.array([[1e10, 1e300]]), np.array([[True, False]]),
                                  clutter_density=1e-300)
    np.testing.assert_allclose(beta, [[1.0, 0.0]])
    np.testing.assert_allclose(beta0, [(1 - 0.9 * 0.99) * 1e-300 / (0.9 * 1e10)], rtol=1e-12)
