r"""The Gaussian filter's equations as plain numpy: the specification the fast paths follow.

Three steps make every linear-Gaussian filter and smoother in :mod:`vistrack.filters`:

.. math::

    \textbf{predict:}\quad & \bar x^- = F \bar x, \qquad P^- = F P F' + Q,

    \textbf{condition on } y\textbf{:}\quad & e = y - H \bar x^-, \quad S = H P^- H' + R, \quad
    K = P^- H' S^{-1},

    & \bar x^+ = \bar x^- + K e, \quad P^+ = (I - K H) P^- (I - K H)' + K R K',
    \quad \ell = \log N(e; 0, S),

    \textbf{smooth back:}\quad & G = P F' (P^-_{t+1})^{-1}, \quad
    \bar x^s = \bar x + G (\bar x^s_{t+1} - \bar x^-_{t+1}), \quad
    P^s = P + G (P^s_{t+1} - P^-_{t+1}) G',

the covariance correction in the Joseph form (symmetric positive definite to rounding, where
``(I - K H) P⁻`` can lose both) and symmetrised; the smoothed covariance likewise as the
equal sum ``(I - G F) P (I - G F)' + G (Q + P^s_{t+1}) G'``, where the difference loses every
digit of a small variance beside a large one (1e-10 beside 1e10). NaN components of ``y``
are missing: their rows of ``H`` and their innovations are zero and their rows and columns of
``S`` a unit's, so the update and ``ℓ`` use the observed components alone (a wholly missing
``y`` leaves the Gaussian unchanged, with ``ℓ = 0``).

Each function takes a batch (leading dimensions) and is a few lines, as dynamax's
``_predict`` and ``_condition_on``. :func:`condition_on` takes the innovation and a per-Gaussian
``H``, so the EKF is it with the measurement model's residual and Jacobian
(:func:`~vistrack.filters.ekf_update` calls it). The compiled kernels behind
:func:`~vistrack.filters.kf_predict`, :func:`~vistrack.filters.kf_update`,
:func:`~vistrack.filters.kalman_filter` and :func:`~vistrack.filters.rts_smooth`, and the box
tracker's per-axis filter (:mod:`vistrack.filters.axes`), compute the same equations in loops;
the tests check each against these functions, and these against filterpy and scipy.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

__all__ = ["predict", "condition_on", "kalman_update", "smooth_step"]

_LOG2PI = math.log(2.0 * math.pi)


def _t(a: np.ndarray) -> np.ndarray:
    return np.swapaxes(a, -1, -2)


def symmetric(P: np.ndarray) -> np.ndarray:
    """``(P + P') / 2`` over the last two axes."""
    return 0.5 * (P + _t(P))


def masked_innovation(
    e: np.ndarray, S: np.ndarray, obs: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Decouple missing components: a zero innovation, and a unit row and column in ``S``.

    Returns ``(e, S, L, loglik)`` with ``L`` the Cholesky factor of the masked ``S`` and the
    log-density of the observed components' innovation. Raises ``ValueError`` if ``S`` is not
    positive definite on the observed components."""
    m = e.shape[-1]
    if not obs.all():
        both = obs[..., :, None] & obs[..., None, :]
        S = np.where(both, S, np.eye(m))
        e = np.where(obs, e, 0.0)
    try:
        L = np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        raise ValueError(
            "the innovation covariance is not positive definite for some Gaussian; R must be "
            "positive definite on the observed components"
        ) from None
    w = np.linalg.solve(L, e[..., None])[..., 0]
    logdet = np.log(np.diagonal(L, axis1=-2, axis2=-1)).sum(-1)
    ll = -0.5 * (w * w).sum(-1) - logdet - 0.5 * obs.sum(-1) * _LOG2PI
    return e, S, L, ll


def gain(C: np.ndarray, L: np.ndarray) -> np.ndarray:
    """``K = C S⁻¹`` for ``S = L L'``, by two triangular solves (``C (..., n, m)``)."""
    Z = np.linalg.solve(L, _t(C))  # L^-1 C'
    return _t(np.linalg.solve(_t(L), Z))


def predict(
    mean: ArrayLike, cov: ArrayLike, F: ArrayLike, Q: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    r"""The prediction ``N(F x̄, F P F' + Q)`` of a batch of Gaussians.

    Parameters
    ----------
    mean : (..., n) array_like
        Means.
    cov : (..., n, n) array_like
        Covariances.
    F, Q : (n, n) or (..., n, n) array_like
        Dynamics and process noise, shared or one per Gaussian.

    Returns
    -------
    mean : (..., n) ndarray
    cov : (..., n, n) ndarray
        Symmetrised.

    Examples
    --------
    >>> import numpy as np
    >>> m, P = predict([0.0, 1.0], np.eye(2), [[1.0, 1.0], [0.0, 1.0]], 0.1 * np.eye(2))
    >>> m, P
    (array([1., 1.]), array([[2.1, 1. ],
           [1. , 1.1]]))
    """
    x, P = np.asarray(mean, dtype=float), np.asarray(cov, dtype=float)
    F, Q = np.asarray(F, dtype=float), np.asarray(Q, dtype=float)
    return (F @ x[..., None])[..., 0], symmetric(F @ P @ _t(F) + Q)


def condition_on(
    mean: ArrayLike, cov: ArrayLike, H: ArrayLike, R: ArrayLike, innovation: ArrayLike,
    observed: ArrayLike | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r"""Correct a batch of Gaussians by the innovation ``e`` of a measurement ``y ≈ H x + v``.

    .. math::

        S = H P H' + R, \quad K = P H' S^{-1}, \quad \bar x^+ = \bar x + K e, \quad
        P^+ = (I - K H) P (I - K H)' + K R K', \quad \ell = \log N(e; 0, S),

    over the observed components: the rows of ``H`` and the components of ``e`` not observed
    are taken as zero and their rows and columns of ``S`` as a unit's.

    Parameters
    ----------
    mean : (..., n) array_like
        Predicted means.
    cov : (..., n, n) array_like
        Predicted covariances.
    H : (m, n) or (..., m, n) array_like
        Measurement matrix (or an EKF's Jacobian), shared or one per Gaussian.
    R : (m, m) array_like
        Measurement noise covariance.
    innovation : (..., m) array_like
        ``e = y - H x̄`` (or a model's residual, angles wrapped); entries not observed are
        ignored.
    observed : (..., m) array_like of bool, optional
        Which components were measured; all by default.

    Returns
    -------
    mean : (..., n) ndarray
    cov : (..., n, n) ndarray
        The corrected Gaussians.
    loglik : (...) ndarray
        ``log N(e; 0, S)`` over the observed components; 0 where none is.

    Raises
    ------
    ValueError
        If ``S`` is not positive definite on the observed components.

    Examples
    --------
    >>> import numpy as np
    >>> m, P, ll = condition_on([0.0, 1.0], np.eye(2), [[1.0, 0.0]], [[0.5]], [1.5])
    >>> m.round(3), P.round(3), ll.round(3)
    (array([1., 1.]), array([[0.333, 0.   ],
           [0.   , 1.   ]]), np.float64(-1.872))
    """
    x, P = np.asarray(mean, dtype=float), np.asarray(cov, dtype=float)
    R = np.asarray(R, dtype=float)
    e = np.asarray(innovation, dtype=float)
    obs = (np.ones(e.shape, dtype=bool) if observed is None
           else np.asarray(observed, dtype=bool))
    # missing components: zero rows (whatever H holds there: a Jacobian may be NaN)
    Hm = np.where(obs[..., :, None], np.asarray(H, dtype=float), 0.0)
    U = P @ _t(Hm)  # P H'
    e, S, L, ll = masked_innovation(e, Hm @ U + R, obs)
    K = gain(U, L)
    A = np.eye(x.shape[-1]) - K @ Hm
    Rm = np.where(obs[..., :, None] & obs[..., None, :], R, 0.0)
    return (x + (K @ e[..., None])[..., 0],
            symmetric(A @ P @ _t(A) + K @ Rm @ _t(K)), ll)


def kalman_update(
    mean: ArrayLike, cov: ArrayLike, y: ArrayLike, H: ArrayLike, R: ArrayLike
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    r""":func:`condition_on` with the linear innovation ``e = y - H x̄``; NaN in ``y`` is missing.

    Parameters
    ----------
    mean : (..., n) array_like
        Predicted means.
    cov : (..., n, n) array_like
        Predicted covariances.
    y : (..., m) array_like
        One measurement per Gaussian; NaN components are missing.
    H, R : (m, n) and (m, m) array_like
        Measurement matrix and noise covariance.

    Returns
    -------
    mean, cov, loglik : ndarray
        As :func:`condition_on`.

    Examples
    --------
    >>> import numpy as np
    >>> m, P, ll = kalman_update(np.zeros((2, 2)), np.tile(np.eye(2), (2, 1, 1)),
    ...                          [[1.0, np.nan], [np.nan, np.nan]], np.eye(2), 0.5 * np.eye(2))
    >>> m.round(3), ll.round(3)
    (array([[0.667, 0.   ],
           [0.   , 0.   ]]), array([-1.455, -0.   ]))
    """
    x = np.asarray(mean, dtype=float)
    y = np.asarray(y, dtype=float)
    H = np.asarray(H, dtype=float)
    obs = ~np.isnan(y)
    e = np.where(obs, y, 0.0) - (H @ x[..., None])[..., 0]
    return condition_on(x, cov, H, R, e, obs)


def smooth_step(
    mean: ArrayLike, cov: ArrayLike, next_smoothed_mean: ArrayLike, next_smoothed_cov: ArrayLike,
    F: ArrayLike, Q: ArrayLike,
) -> tuple[np.ndarray, np.ndarray]:
    r"""One Rauch-Tung-Striebel step back: ``p(x_t | y_0..T-1)`` from ``p(x_t | y_0..t)``.

    .. math::

        P^-_{t+1} = F P F' + Q, \quad G = P F' (P^-_{t+1})^{-1}, \quad
        \bar x^s = \bar x + G (\bar x^s_{t+1} - F \bar x), \quad
        P^s = P + G (P^s_{t+1} - P^-_{t+1}) G'
            = (I - G F) P (I - G F)' + G (Q + P^s_{t+1}) G',

    computed in the second form (see the module).

    Parameters
    ----------
    mean : (..., n) array_like
        Filtered mean at ``t``.
    cov : (..., n, n) array_like
        Filtered covariance at ``t``.
    next_smoothed_mean : (..., n) array_like
        Smoothed mean at ``t + 1``.
    next_smoothed_cov : (..., n, n) array_like
        Smoothed covariance at ``t + 1``.
    F, Q : (n, n) or (..., n, n) array_like
        Dynamics and process noise from ``t`` to ``t + 1``.

    Returns
    -------
    mean : (..., n) ndarray
    cov : (..., n, n) ndarray
        The smoothed Gaussian at ``t`` (covariance symmetrised).

    Raises
    ------
    numpy.linalg.LinAlgError
        If the prediction's covariance is singular.

    References
    ----------
    .. [1] H. E. Rauch, F. Tung and C. T. Striebel, "Maximum likelihood estimates of linear
       dynamic systems", *AIAA Journal* 3(8), 1965.

    Examples
    --------
    With nothing more learnt after ``t`` the smoothed Gaussian is the filtered one:

    >>> import numpy as np
    >>> F, Q = np.array([[1.0, 1.0], [0.0, 1.0]]), 0.1 * np.eye(2)
    >>> xp, Pp = predict([0.0, 1.0], np.eye(2), F, Q)
    >>> smooth_step([0.0, 1.0], np.eye(2), xp, Pp, F, Q)[0]
    array([0., 1.])
    """
    x, P = np.asarray(mean, dtype=float), np.asarray(cov, dtype=float)
    F = np.asarray(F, dtype=float)
    xp, Pp = predict(x, P, F, Q)
    G = _t(np.linalg.solve(Pp, F @ P))  # (Pp^-1 F P)' = P F' Pp^-1
    ms = x + (G @ (np.asarray(next_smoothed_mean, dtype=float) - xp)[..., None])[..., 0]
    # P + G (P_s - Pp) G' as a sum of positive semi-definite terms (see the module)
    A = np.eye(x.shape[-1]) - G @ F
    Ps = A @ P @ _t(A) + G @ (np.asarray(Q, dtype=float)
                              + np.asarray(next_smoothed_cov, dtype=float)) @ _t(G)
    return ms, symmetric(Ps)
