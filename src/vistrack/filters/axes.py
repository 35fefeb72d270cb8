r"""The Kalman filter of a state made of independent (value, rate) pairs, batched over tracks.

The state holds ``A`` values and their rates, values first,
``x = [p_1 … p_A, v_1 … v_A]`` (as the box state ``[cx, cy, w, h, vcx, vcy, vw, vh]`` of
:class:`~vistrack.models.BoxMotion`). Each value moves by its rate, ``F = [[I, dt I], [0, I]]``,
the process noise ``Q`` is diagonal, and the values alone are measured, ``H = [I 0]``, with
diagonal noise ``R``. No matrix then couples two axes: from a covariance with no terms across
axes the filter is ``A`` independent filters of two states, and each covariance is one 2×2
matrix per axis, kept as its three entries ``[pp, pv, vv]``: shape ``(K, A, 3)`` for ``K``
states. Predict and update are a few elementwise operations over all states where the full
filter (:func:`~vistrack.filters.kf_predict`, :func:`~vistrack.filters.kf_update`) multiplies
``2A × 2A`` matrices; the tests check that the two agree.

Per axis, the prediction over ``dt`` with process noise variances ``q_p`` (value) and ``q_v``
(rate) is

.. math::
    p^- = p + dt\, v, \quad v^- = v, \quad
    P^-_{pp} = P_{pp} + dt\,(2 P_{pv} + dt\, P_{vv}) + q_p, \quad
    P^-_{pv} = P_{pv} + dt\, P_{vv}, \quad P^-_{vv} = P_{vv} + q_v,

and the update with a measurement ``z`` of the value, of noise variance ``r``,

.. math::
    S = P_{pp} + r, \quad k_p = P_{pp} / S, \quad k_v = P_{pv} / S, \quad y = z - p,

    p^+ = p + k_p\, y, \quad v^+ = v + k_v\, (y + o), \quad
    P^+_{pp} = P_{pp} - k_p P_{pp}, \quad P^+_{pv} = P_{pv} - k_p P_{pv}, \quad
    P^+_{vv} = P_{vv} - k_v P_{pv},

the covariance in the form ``(I - K H) P``. ``o`` is an optional offset of the rate's
innovation (zero in the Kalman filter): motion the rate is to learn that the value was moved by
outside the filter, such as a camera's shift the box tracker applied to a prediction
(:mod:`vistrack.tracking.box`).

:func:`axes_predict` and :func:`axes_update` are the numpy reference; the compiled versions
that update arrays in place (private, for the box tracker's compiled step) compute the same
expressions in the same order, and so give the same numbers bit for bit. :func:`axes_to_full`
and :func:`full_to_axes` convert between the per-axis covariances and full ``2A × 2A`` ones.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .._jit import njit
from .._prebuilt import kernel

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["axes_predict", "axes_update", "axes_to_full", "full_to_axes"]


def _state(mean: ArrayLike, cov: ArrayLike) -> tuple[np.ndarray, np.ndarray, int]:
    m = np.asarray(mean, dtype=np.float64)
    c = np.asarray(cov, dtype=np.float64)
    if c.ndim < 2 or c.shape[-1] != 3:
        raise ValueError(f"cov must have shape (..., A, 3); got {c.shape}")
    A = c.shape[-2]
    if m.shape != c.shape[:-2] + (2 * A,):
        raise ValueError(f"mean must have shape {c.shape[:-2] + (2 * A,)} to match cov "
                         f"{c.shape}; got {m.shape}")
    return m, c, A


def _per_state(value: ArrayLike, name: str, shape: tuple[int, ...], *,
               variance: bool = False) -> np.ndarray:
    """``value`` as floats of ``shape``; a ``variance`` finite and not below zero (else a
    ValueError naming ``name`` and the first bad entry)."""
    v = np.asarray(value, dtype=np.float64)
    if v.shape != shape:
        raise ValueError(f"{name} must have shape {shape}; got {v.shape}")
    if variance and not (np.isfinite(v).all() and (v >= 0).all()):
        idx = tuple(int(i) for i in np.argwhere(~(np.isfinite(v) & (v >= 0)))[0])
        raise ValueError(f"{name} holds variances, finite and >= 0; {name}{list(idx)} = "
                         f"{v[idx]}")
    return v


def _time_step(dt: object) -> float:
    """``dt`` as a float: one finite number for every state (an array of one per state
    broadcast along the axes instead, silently)."""
    import numbers

    # (a 0-d array of True was a step of 1, of "2.0" one of 2, of a complex number
    # float()'s bare TypeError)
    if isinstance(dt, (np.ndarray, np.generic)):  # (np.timedelta64 is a numbers.Real)
        ok = dt.ndim == 0 and dt.dtype.kind in "iuf"
    else:
        ok = isinstance(dt, numbers.Real) and not isinstance(dt, bool)
    if ok:
        value = float(dt)  # type: ignore[arg-type]  # (a real number, or a 0-d array)
        if np.isfinite(value):
            return value
    raise ValueError(f"dt must be one finite number of time units for every state; "
                     f"got {dt!r}")


def axes_predict(mean: ArrayLike, cov: ArrayLike, dt: float,
                 q: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Predict states of independent (value, rate) pairs over ``dt`` (see the module).

    Parameters
    ----------
    mean : array, shape (K, 2A)
        States, the ``A`` values first, then their rates.
    cov : array, shape (K, A, 3)
        Per-axis covariances ``[pp, pv, vv]``.
    dt : float
        Time step (negative: backwards in time; ``q`` is then the noise of ``|dt|``).
    q : array, shape (K, 2A)
        The diagonal of the process noise ``Q`` over this step, values first (for noise that
        depends on the state, such as a box's size, evaluate it at the predicted values
        ``mean[:, :A] + dt * mean[:, A:]``).

    Returns
    -------
    mean : ndarray, shape (K, 2A)
        ``F x`` with ``F = [[I, dt I], [0, I]]``.
    cov : ndarray, shape (K, A, 3)
        ``F P F' + Q`` per axis:
        ``[pp + dt (2 pv + dt vv) + q_p, pv + dt vv, vv + q_v]``.

    Raises
    ------
    ValueError
        If ``dt`` is not one finite number, a shape does not match, or ``q`` holds a negative
        or non-finite variance.

    Examples
    --------
    One box ``[cx, cy, w, h]`` moving 2 pixels a frame to the right:

    >>> import numpy as np
    >>> mean = np.array([[10.0, 20.0, 4.0, 8.0, 2.0, 0.0, 0.0, 0.0]])
    >>> cov = np.tile([1.0, 0.0, 1.0], (1, 4, 1))
    >>> m, c = axes_predict(mean, cov, 1.0, np.full((1, 8), 0.5))
    >>> m[0, :4].tolist(), c[0, 0].tolist()
    ([12.0, 20.0, 4.0, 8.0], [2.5, 1.0, 1.5])
    """
    m, c, A = _state(mean, cov)
    dt = _time_step(dt)
    qd = _per_state(q, "q", m.shape, variance=True)
    out = m.copy()
    out[..., :A] += dt * m[..., A:]
    pp, pv, vv = c[..., 0], c[..., 1], c[..., 2]
    return out, np.stack([pp + dt * (2.0 * pv + dt * vv) + qd[..., :A], pv + dt * vv,
                          vv + qd[..., A:]], axis=-1)


def axes_update(mean: ArrayLike, cov: ArrayLike, z: ArrayLike, r: ArrayLike,
                rate_offset: ArrayLike | None = None) -> tuple[np.ndarray, np.ndarray]:
    r"""Correct states of independent (value, rate) pairs with measurements of their values
    (see the module).

    Parameters
    ----------
    mean : array, shape (K, 2A)
        States, the ``A`` values first, then their rates.
    cov : array, shape (K, A, 3)
        Per-axis covariances ``[pp, pv, vv]``.
    z : array, shape (K, A)
        One measurement of the values per state; NaN where a value is not measured (its axis
        is left as predicted, as :func:`~vistrack.filters.kf_update` leaves a missing
        component).
    r : array, shape (K, A)
        The diagonal of each measurement's noise ``R`` (finite, ``>= 0``).
    rate_offset : array, shape (K, A), optional
        Added to the innovation the rates learn from, ``y + o`` (default none: the Kalman
        filter): motion the values were moved by outside the filter.

    Returns
    -------
    mean : ndarray, shape (K, 2A)
        ``x + K y`` with the gains ``k_p = pp / S``, ``k_v = pv / S``, ``S = pp + r``,
        ``y = z - p`` (the rates' innovation ``y + o``).
    cov : ndarray, shape (K, A, 3)
        ``(I - K H) P`` per axis: ``[pp - k_p pp, pv - k_p pv, vv - k_v pv]``.

    Raises
    ------
    ValueError
        If a shape does not match, ``z`` holds an infinite value, ``r`` a negative or
        non-finite variance, ``rate_offset`` a value that is not finite, or a measured
        value's innovation variance ``pp + r`` is not > 0 (each named).

    Examples
    --------
    A value measured 1 above its prediction, with noise equal to its variance, moves halfway
    there, and its rate by ``pv / S`` of it:

    >>> import numpy as np
    >>> m, c = axes_update([[0.0, 0.0]], [[[1.0, 0.5, 1.0]]], [[1.0]], [[1.0]])
    >>> m.tolist(), c.tolist()
    ([[0.5, 0.25]], [[[0.5, 0.25, 0.875]]])
    """
    m, c, A = _state(mean, cov)
    shape = m.shape[:-1] + (A,)
    zv, rv = _per_state(z, "z", shape), _per_state(r, "r", shape, variance=True)
    pp, pv, vv = c[..., 0], c[..., 1], c[..., 2]
    S = pp + rv
    if np.isinf(zv).any():
        idx = tuple(int(i) for i in np.argwhere(np.isinf(zv))[0])
        raise ValueError(f"z must be finite or NaN (not measured); z{list(idx)} = {zv[idx]}")
    missing = np.isnan(zv)
    flat = ~missing & ~(S > 0)
    if flat.any():
        # a value known exactly measured exactly: no gain (0 / 0), and the state went NaN
        # with a RuntimeWarning alone, where kf_update names it
        idx = tuple(int(i) for i in np.argwhere(flat)[0])
        raise ValueError(f"the innovation variance pp + r must be > 0 where a value is "
                         f"measured; at {list(idx)} it is {S[idx]}")
    if missing.any():  # (an unmeasured axis may have S = 0: no gain there, below)
        kp = np.divide(pp, S, out=np.zeros_like(S), where=~missing)
        kv = np.divide(pv, S, out=np.zeros_like(S), where=~missing)
    else:
        kp, kv = pp / S, pv / S
    y = zv - m[..., :A]
    if missing.any():  # no gain on an axis not measured: it stays as predicted
        kp, kv, y = (np.where(missing, 0.0, a) for a in (kp, kv, y))
    out = m.copy()
    out[..., :A] += kp * y
    if rate_offset is not None:
        o = _per_state(rate_offset, "rate_offset", shape)
        if not np.isfinite(o).all():  # (a NaN made the rate NaN; inf did where unmeasured)
            idx = tuple(int(i) for i in np.argwhere(~np.isfinite(o))[0])
            raise ValueError(f"rate_offset must be finite; rate_offset{list(idx)} = {o[idx]}")
        y = y + np.where(missing, 0.0, o)
    out[..., A:] += kv * y
    return out, np.stack([pp - kp * pp, pv - kp * pv, vv - kv * pv], axis=-1)


def axes_to_full(cov: ArrayLike) -> np.ndarray:
    """Per-axis covariances ``(..., A, 3)`` (``pp, pv, vv`` of each value and its rate) as full
    ``(..., 2A, 2A)`` ones, in the order of the state (the ``A`` values, then their rates).

    Parameters
    ----------
    cov : (..., A, 3) array_like
        Per-axis covariances ``[pp, pv, vv]``.

    Returns
    -------
    (..., 2A, 2A) ndarray
        The full covariances: ``P[a, a] = pp``, ``P[a, A + a] = P[A + a, a] = pv`` and
        ``P[A + a, A + a] = vv`` for each axis ``a``, zero across axes.

    Examples
    --------
    >>> axes_to_full([[1.0, 0.5, 2.0]]).tolist()
    [[1.0, 0.5], [0.5, 2.0]]
    """
    c = np.asarray(cov, dtype=np.float64)
    if c.ndim < 2 or c.shape[-1] != 3:  # (an IndexError, naming nothing)
        raise ValueError(f"cov must have shape (..., A, 3); got {c.shape}")
    A = c.shape[-2]
    P = np.zeros(c.shape[:-2] + (2 * A, 2 * A))
    a = np.arange(A)
    P[..., a, a], P[..., a, a + A] = c[..., 0], c[..., 1]
    P[..., a + A, a], P[..., a + A, a + A] = c[..., 1], c[..., 2]
    return P


def full_to_axes(P: ArrayLike) -> np.ndarray:
    """Full ``(..., 2A, 2A)`` covariances as per-axis ones ``(..., A, 3)``: the inverse of
    :func:`axes_to_full` for covariances with no terms across axes (any are dropped).

    Parameters
    ----------
    P : (..., 2A, 2A) array_like
        Full covariances, in the order of the state (the ``A`` values, then their rates).

    Returns
    -------
    (..., A, 3) ndarray
        ``[P[a, a], P[a, A + a], P[A + a, A + a]]`` for each axis ``a``.

    Raises
    ------
    ValueError
        If ``P`` is not a stack of square matrices of even size.

    Examples
    --------
    >>> full_to_axes([[1.0, 0.5], [0.5, 2.0]]).tolist()
    [[1.0, 0.5, 2.0]]
    """
    P = np.asarray(P, dtype=np.float64)
    if P.ndim < 2 or P.shape[-1] != P.shape[-2] or P.shape[-1] % 2:
        raise ValueError(f"P must have shape (..., 2A, 2A); got {P.shape}")
    a = np.arange(P.shape[-1] // 2)
    A = len(a)
    return np.stack([P[..., a, a], P[..., a, a + A], P[..., a + A, a + A]], axis=-1)


# ------------------------------------------------------------------------------------------------
# Compiled, in place: the same expressions in the same order as the reference above (no fast
# math), so the results are equal bit for bit. They take (K, 2A) and (K, A, 3) arrays and may be
# called from other compiled functions.


@kernel
@njit(cache=True)
def _predicted_values(mean, dt):
    """The values :func:`axes_predict` predicts, ``mean[:, :A] + dt * mean[:, A:]`` ``(K, A)``,
    new: where process noise that depends on the state is evaluated."""
    A = mean.shape[1] // 2
    out = np.empty((mean.shape[0], A))
    for i in range(mean.shape[0]):
        for a in range(A):
            out[i, a] = mean[i, a] + dt * mean[i, A + a]
    return out


@njit(cache=True)
def _predict_inplace(mean, cov, dt, q):
    """:func:`axes_predict` of every row of ``mean (K, 2A)``, ``cov (K, A, 3)`` in place."""
    A = cov.shape[1]
    for i in range(mean.shape[0]):
        for a in range(A):
            mean[i, a] += dt * mean[i, A + a]
        for a in range(A):
            pp, pv, vv = cov[i, a, 0], cov[i, a, 1], cov[i, a, 2]
            cov[i, a, 0] = pp + dt * (2.0 * pv + dt * vv) + q[i, a]
            cov[i, a, 1] = pv + dt * vv
            cov[i, a, 2] = vv + q[i, A + a]


@njit(cache=True)
def _update_inplace(mean, cov, rows, z, r, rate_offset):
    """:func:`axes_update` of the rows ``rows (M,)`` of ``mean (K, 2A)``, ``cov (K, A, 3)`` in
    place, with ``z``, ``r`` and ``rate_offset`` of shape ``(M, A)``, one row per updated
    state."""
    A = cov.shape[1]
    for k in range(rows.shape[0]):
        i = rows[k]
        for a in range(A):
            pp, pv, vv = cov[i, a, 0], cov[i, a, 1], cov[i, a, 2]
            S = pp + r[k, a]
            kp, kv = pp / S, pv / S
            y = z[k, a] - mean[i, a]
            mean[i, a] += kp * y
            mean[i, A + a] += kv * (y + rate_offset[k, a])
            cov[i, a, 0], cov[i, a, 1], cov[i, a, 2] = pp - kp * pp, pv - kp * pv, vv - kv * pv
