"""The filter of independent (value, rate) pairs: its compiled version against the numpy
reference (bit for bit), and both against the full Kalman filter on the equivalent matrices."""

import numpy as np
import pytest

from vistrack import Gaussian
from vistrack.filters import (
    axes_predict,
    axes_to_full,
    axes_update,
    full_to_axes,
    kf_predict,
    kf_update,
)
from vistrack.filters.axes import _predict_inplace, _predicted_values, _update_inplace


def random_state(rng, K, A):
    """States of K tracks with A axes, and per-axis covariances that are positive definite."""
    mean = np.c_[rng.uniform(-50, 500, (K, A)), rng.normal(0, 3, (K, A))]
    pp, vv = rng.uniform(0.5, 20, (K, A)), rng.uniform(0.01, 2, (K, A))
    pv = rng.uniform(-0.9, 0.9, (K, A)) * np.sqrt(pp * vv)
    return mean, np.stack([pp, pv, vv], axis=-1)


def transition(A, dt):
    return np.kron(np.array([[1.0, dt], [0.0, 1.0]]), np.eye(A))


@pytest.mark.parametrize("A", [1, 2, 4])
def test_compiled_steps_equal_the_reference_bit_for_bit(A):
    rng = np.random.default_rng(A)
    K = 40
    for dt in (1.0, 3.0, -2.0, 0.5):
        mean, cov = random_state(rng, K, A)
        q = rng.uniform(0, 2, (K, 2 * A))
        m_ref, c_ref = axes_predict(mean, cov, dt, q)
        assert np.array_equal(_predicted_values(mean, dt), m_ref[:, :A])
        view = np.c_[mean, mean][:, : 2 * A]  # not contiguous
        assert np.array_equal(_predicted_values(view, dt), mean[:, :A] + dt * mean[:, A:])
        m, c = mean.copy(), cov.copy()
        _predict_inplace(m, c, dt, q)
        assert np.array_equal(m, m_ref) and np.array_equal(c, c_ref)
        # update a subset of the rows, in an order of their own
        rows = rng.permutation(K)[: K // 2]
        z = m_ref[rows, :A] + rng.normal(0, 2, (len(rows), A))
        r = rng.uniform(0.1, 9, (len(rows), A))
        offset = rng.normal(0, 3, (len(rows), A)) * (rng.random((len(rows), 1)) < 0.5)
        for off in (offset, np.zeros_like(offset)):
            m_exp, c_exp = m_ref.copy(), c_ref.copy()
            m_exp[rows], c_exp[rows] = axes_update(m_ref[rows], c_ref[rows], z, r, off)
            m2, c2 = m.copy(), c.copy()
            _update_inplace(m2, c2, rows, z, r, off)
            assert np.array_equal(m2, m_exp) and np.array_equal(c2, c_exp)
        # no offset: the Kalman filter, as with a zero one
        m_none, c_none = axes_update(m_ref[rows], c_ref[rows], z, r)
        assert np.array_equal(m_none, m_exp[rows]) and np.array_equal(c_none, c_exp[rows])


@pytest.mark.parametrize("A", [1, 3, 4])
def test_steps_equal_the_full_kalman_filter(A):
    """Predictions and updates over several steps equal kf_predict and kf_update (Joseph form)
    on the full 2A x 2A matrices ``F = [[I, dt I], [0, I]]``, diagonal ``Q``, ``H = [I 0]``,
    diagonal ``R``."""
    rng = np.random.default_rng(10 + A)
    K = 25
    mean, cov = random_state(rng, K, A)
    full = [Gaussian(mean[k].copy(), axes_to_full(cov[k])) for k in range(K)]
    H = np.eye(A, 2 * A)
    for dt in (1.0, 2.0, 1.0, -1.0, 4.0):
        q = rng.uniform(0, 1, (K, 2 * A))
        mean, cov = axes_predict(mean, cov, dt, q)
        full = [kf_predict(g, transition(A, dt), np.diag(q[k])) for k, g in enumerate(full)]
        np.testing.assert_allclose(mean, [g.mean for g in full], rtol=1e-12, atol=1e-9)
        np.testing.assert_allclose(axes_to_full(cov), [g.cov for g in full], rtol=1e-12,
                                   atol=1e-9)
        z = mean[:, :A] + rng.normal(0, 2, (K, A))
        r = rng.uniform(0.1, 5, (K, A))
        mean, cov = axes_update(mean, cov, z, r)
        full = [kf_update(g, z[k], H, np.diag(r[k])) for k, g in enumerate(full)]
        np.testing.assert_allclose(mean, [g.mean for g in full], rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(axes_to_full(cov), [g.cov for g in full], rtol=1e-9,
                                   atol=1e-12)


def test_compiled_steps_equal_the_full_kalman_filter():
    """The compiled steps, on the box state (four axes), against the full filter."""
    rng = np.random.default_rng(3)
    K, A = 30, 4
    mean, cov = random_state(rng, K, A)
    full = [Gaussian(mean[k].copy(), axes_to_full(cov[k])) for k in range(K)]
    for dt in (1.0, 3.0, 1.0):
        q = rng.uniform(0, 1, (K, 2 * A))
        _predict_inplace(mean, cov, dt, q)
        rows = np.flatnonzero(rng.random(K) < 0.7)
        z = mean[rows, :A] + rng.normal(0, 2, (len(rows), A))
        r = rng.uniform(0.1, 5, (len(rows), A))
        _update_inplace(mean, cov, rows, z, r, np.zeros((len(rows), A)))
        for k in range(K):
            full[k] = kf_predict(full[k], transition(A, dt), np.diag(q[k]))
        for n, k in enumerate(rows):
            full[k] = kf_update(full[k], z[n], np.eye(A, 2 * A), np.diag(r[n]))
        np.testing.assert_allclose(mean, [g.mean for g in full], rtol=1e-10, atol=1e-9)
        np.testing.assert_allclose(axes_to_full(cov), [g.cov for g in full], rtol=1e-9,
                                   atol=1e-12)


def test_rate_offset_is_motion_the_rate_learns():
    """A value moved by ``d`` outside the filter and measured where it was moved to: with
    ``rate_offset = d`` the rate moves as if the value had been measured ``d`` further,
    the value and the covariance as without it."""
    mean, cov = np.array([[10.0, 1.0]]), np.array([[[4.0, 1.0, 1.0]]])
    z, r, d = np.array([[12.0]]), np.array([[4.0]]), np.array([[3.0]])
    m0, c0 = axes_update(mean, cov, z, r)
    m1, c1 = axes_update(mean, cov, z, r, d)
    assert m1[0, 0] == m0[0, 0] and np.array_equal(c1, c0)
    assert m1[0, 1] == pytest.approx(m0[0, 1] + 1.0 / 8.0 * 3.0)


def test_conversions_between_axes_and_full_covariances():
    rng = np.random.default_rng(0)
    _, cov = random_state(rng, 6, 4)
    P = axes_to_full(cov)
    assert P.shape == (6, 8, 8) and np.array_equal(P, np.swapaxes(P, -1, -2))
    assert np.all(np.linalg.eigvalsh(P) > 0)
    assert np.array_equal(full_to_axes(P), cov)
    assert np.array_equal(full_to_axes(P[0]), cov[0])


def test_shapes_are_checked():
    mean, cov = np.zeros((3, 8)), np.ones((3, 4, 3))
    with pytest.raises(ValueError, match="mean must have shape"):
        axes_predict(np.zeros((3, 6)), cov, 1.0, np.zeros((3, 8)))
    with pytest.raises(ValueError, match="q must have shape"):
        axes_predict(mean, cov, 1.0, np.zeros((3, 4)))
    with pytest.raises(ValueError, match="cov must have shape"):
        axes_update(mean, np.ones((3, 4, 2)), np.zeros((3, 4)), np.ones((3, 4)))
    with pytest.raises(ValueError, match="r must have shape"):
        axes_update(mean, cov, np.zeros((3, 4)), np.ones((3, 2)))
    with pytest.raises(ValueError, match="P must have shape"):
        full_to_axes(np.zeros((3, 7, 7)))


def test_a_value_not_measured_is_left_as_the_full_filter_leaves_it():
    """NaN in ``z``: that axis keeps its prediction, the others are corrected, as the full
    filter with the component missing (``kalman_update``, the reference, drops it); it
    turned the state into NaN before."""
    from vistrack.filters.reference import kalman_update

    rng = np.random.default_rng(8)
    K, A = 6, 4
    mean, cov = random_state(rng, K, A)
    z = mean[:, :A] + rng.normal(0, 2, (K, A))
    z[0, 1] = z[2, 0] = z[2, 3] = z[4] = np.nan
    r = rng.uniform(0.1, 5, (K, A))
    got_m, got_c = axes_update(mean, cov, z, r)
    for k in range(K):
        want_m, want_P, _ = kalman_update(mean[k], axes_to_full(cov[k]), z[k], np.eye(A, 2 * A),
                                       np.diag(r[k]))
        np.testing.assert_allclose(got_m[k], want_m, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(axes_to_full(got_c[k]), want_P, rtol=1e-10, atol=1e-12)
    assert np.array_equal(got_m[4], mean[4]) and np.array_equal(got_c[4], cov[4])
    # every value measured: the same numbers as before, bit for bit, with NaN elsewhere
    full = ~np.isnan(z).any(axis=1)
    m1, c1 = axes_update(mean[full], cov[full], z[full], r[full])
    assert np.array_equal(m1, got_m[full]) and np.array_equal(c1, got_c[full])


@pytest.mark.parametrize("call, message", [
    (lambda m, c: axes_predict(m, c, np.ones(3), np.zeros((3, 2))),
     r"dt must be one finite number of time units for every state; got array"),
    (lambda m, c: axes_predict(m, c, float("nan"), np.zeros((3, 2))),
     r"dt must be one finite number .*; got nan"),
    # a 0-d array of True was a step of 1, of "2.0" one of 2 (True itself is refused), of a
    # complex number float()'s bare TypeError
    (lambda m, c: axes_predict(m, c, np.array(True), np.zeros((3, 2))),
     r"dt must be one finite number .*; got array\(True\)"),
    (lambda m, c: axes_predict(m, c, np.array("2.0"), np.zeros((3, 2))),
     r"dt must be one finite number .*; got array\('2.0'"),
    (lambda m, c: axes_predict(m, c, np.array(2 + 1j), np.zeros((3, 2))),
     r"dt must be one finite number .*; got array\(2.\+1.j\)"),
    (lambda m, c: axes_predict(m, c, 1.0, -np.ones((3, 2))),
     r"q holds variances, finite and >= 0; q\[0, 0\] = -1.0"),
    (lambda m, c: axes_update(m, c, np.zeros((3, 1)), [[1.0], [-1.0], [1.0]]),
     r"r holds variances, finite and >= 0; r\[1, 0\] = -1.0"),
    (lambda m, c: axes_update(m, c, [[0.0], [np.inf], [0.0]], np.ones((3, 1))),
     r"z must be finite or NaN \(not measured\); z\[1, 0\] = inf"),
])
def test_bad_steps_are_named(call, message):
    """A time step per state (three states, one axis) broadcast along the axes instead of the
    states, a negative variance gave infinities with a RuntimeWarning alone: refused, each
    naming its argument."""
    mean, cov = np.zeros((3, 2)), np.tile([1.0, 0.0, 1.0], (3, 1, 1))
    with pytest.raises(ValueError, match=message):
        call(mean, cov)


def test_an_exact_value_measured_exactly_and_bad_offsets_are_named():
    """`pp + r = 0` on a measured axis gave the state NaN with a RuntimeWarning alone, where
    `kf_update` names it; a NaN `rate_offset` gave the rate NaN, and an infinite one on an
    axis not measured too (documented as left as predicted); `axes_to_full` of a shape that
    is no per-axis covariance failed with an IndexError."""
    import re
    import warnings

    from vistrack.filters.axes import axes_to_full, axes_update

    with pytest.raises(ValueError, match=re.escape(
            "the innovation variance pp + r must be > 0 where a value is measured; at [0, 0] "
            "it is 0.0")):
        axes_update([[2.0, 1.0]], [[[0.0, 0.0, 1.0]]], [[2.0]], [[0.0]])
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # unmeasured, such an axis is left as predicted
        m, c = axes_update([[2.0, 1.0]], [[[0.0, 0.0, 1.0]]], [[np.nan]], [[0.0]])
    assert m.tolist() == [[2.0, 1.0]] and c.tolist() == [[[0.0, 0.0, 1.0]]]
    with pytest.raises(ValueError, match=re.escape("rate_offset must be finite; "
                                                   "rate_offset[0, 0] = nan")):
        axes_update([[0.0, 0.0]], [[[1.0, 0.5, 1.0]]], [[1.0]], [[1.0]], rate_offset=[[np.nan]])
    m, _ = axes_update([[0.0, 0.0, 0.0, 0.0]], [[[1.0, 0.5, 1.0]] * 2], [[1.0, np.nan]],
                       [[1.0, 1.0]], rate_offset=[[0.5, 3.0]])
    assert m[0, 3] == 0.0 and m[0, 2] == pytest.approx(0.25 * 1.5)
    for bad in ([[1.0, 2.0]], [1.0, 2.0, 3.0]):
        with pytest.raises(ValueError, match=re.escape("cov must have shape (..., A, 3)")):
            axes_to_full(bad)
