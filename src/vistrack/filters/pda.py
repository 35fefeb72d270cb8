r"""The probabilistic data association filter's correction: every track corrected with all
the detections, weighted by their association probabilities
(:func:`vistrack.association.pda_weights`, :func:`~vistrack.association.jpda_weights`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._validate import check_finite, check_psd, correlation
from ..types import Gaussian

__all__ = ["pda_update"]


def pda_update(g: Gaussian, Z: ArrayLike, H: ArrayLike, R: ArrayLike, beta: np.ndarray,
               beta0: np.ndarray) -> Gaussian:
    r"""Correct every track with all the detections, weighted by their association probabilities.

    With the gain :math:`K = P^- H' S^{-1}`, :math:`S = H P^- H' + R`, the innovations
    :math:`\nu_j = z_j - H \bar x^-` and their combination :math:`\nu = \sum_j \beta_j
    \nu_j`,

    .. math::

        \bar x = \bar x^- + K \nu, \qquad
        P = P^- - (1 - \beta_0) K S K' + K \Big(\sum_j \beta_j \nu_j \nu_j' - \nu \nu'\Big) K'.

    The last term, the spread of the innovations, widens the covariance when the detections
    disagree.

    Parameters
    ----------
    g : Gaussian
        The tracks' predictions, batch shape ``(T,)``, state size ``n``. Their covariances
        are checked to be finite but taken as positive semi-definite, as
        :func:`vistrack.filters.kf_update` takes them (checking it would add a third to the
        call, measured on 500 tracks of 4 states).
    Z : (D, m) array_like
        Detections.
    H : (m, n) array_like
        Measurement matrix.
    R : (m, m) array_like
        Measurement-noise covariance.
    beta : (T, D) ndarray
        Association probabilities (:func:`pda_weights`, :func:`jpda_weights`).
    beta0 : (T,) ndarray
        Probability that no detection is the track's.

    Returns
    -------
    Gaussian
        The corrected tracks, batch shape ``(T,)``.

    Raises
    ------
    ValueError
        If a shape does not agree with the others (each named), ``g``, ``H`` or ``R`` has an
        entry that is not finite, ``R`` is not symmetric positive semi-definite, a track's
        innovation covariance ``S`` is singular (naming the track), the weights of a track are
        not probabilities (each in [0, 1], ``beta0`` and the track's row of ``beta`` adding
        up to 1 within 1e-6: other weights give a covariance that is not one), or a
        detection that is not finite has a weight above 0 (one outside every gate, of weight
        0, adds nothing).

    References
    ----------
    .. [1] Y. Bar-Shalom and E. Tse, "Tracking in a cluttered environment with probabilistic
       data association", *Automatica* 11(5), 1975.

    Examples
    --------
    Two detections either side of a track: the mean stays, the spread widens ``P`` along them:

    >>> from vistrack.association import likelihoods, pda_weights
    >>> g = Gaussian(np.zeros((1, 2)), np.eye(2)[None])
    >>> Z, H, R = np.array([[1.0, 0.0], [-1.0, 0.0]]), np.eye(2), np.eye(2)
    >>> b, b0 = pda_weights(likelihoods(np.zeros((1, 2)), 2 * np.eye(2)[None], Z),
    ...                     np.ones((1, 2), bool), clutter_density=0.01)
    >>> post = pda_update(g, Z, H, R, b, b0)
    >>> post.mean.round(3) + 0.0, post.cov[0].diagonal().round(3)
    (array([[0., 0.]]), array([0.752, 0.505]))
    """
    if not isinstance(g, Gaussian):  # (a tuple failed on "has no attribute 'mean'")
        raise TypeError(f"g must be a vistrack.Gaussian; got {type(g).__name__}")
    m, P = g.mean, g.cov
    if m.ndim != 2:
        raise ValueError(f"g must be a batch of tracks, batch shape (T,); got batch shape "
                         f"{m.shape[:-1]}")
    T, n = m.shape
    check_finite(m, "g.mean")
    check_finite(P, "g.cov")
    H = np.asarray(H, dtype=float)
    if H.ndim != 2 or H.shape[1] != n:
        raise ValueError(f"H must have shape (m, {n}); got {H.shape}")
    check_finite(H, "H")
    k = H.shape[0]
    R = np.asarray(R, dtype=float)
    if R.shape != (k, k):
        raise ValueError(f"R must have shape ({k}, {k}), as H has {k} rows; got {R.shape}")
    check_finite(R, "R")
    check_psd(R, "R")
    Z = np.asarray(Z, dtype=float)
    if Z.size == 0:
        Z = Z.reshape(0, k)
    if Z.ndim != 2 or Z.shape[1] != k:
        raise ValueError(f"Z must have shape (D, {k}); got {Z.shape}")
    beta, beta0 = np.asarray(beta, dtype=float), np.asarray(beta0, dtype=float)
    if beta.shape != (T, len(Z)):
        raise ValueError(f"beta must have shape ({T}, {len(Z)}), tracks by detections; got "
                         f"{beta.shape}")
    if beta0.shape != (T,):
        raise ValueError(f"beta0 must have shape ({T},); got {beta0.shape}")
    _check_weights(beta, beta0)
    used = beta > 0
    bad = used & ~np.isfinite(Z).all(1)[None, :]
    if bad.any():
        t, j = (int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"Z[{j}] is not finite but has weight beta[{t}, {j}] = {beta[t, j]}")
    zp = m @ H.T
    S = H @ P @ H.T + R
    # positive definite: its correlation matrix's smallest eigenvalue above 1e-12, so that
    # axes of other units (S = diag(1e4, 1e-7)) are no matter (the solve below refused only
    # an exactly zero pivot: a rank-1 S whose pivot rounds to 1e-17 passed, and the
    # covariance grew where the prior had none)
    corr, sd = correlation(S)
    low = np.asarray(~(sd > 0).all(axis=1))
    low[~low] = np.linalg.eigvalsh(corr[~low])[:, 0] <= 1e-12
    bad = int(np.flatnonzero(low)[0]) if low.any() else None
    if bad is not None:
        raise ValueError(f"the innovation covariance S = H P H' + R of track {bad} is "
                         f"singular: g.cov[{bad}] and R leave a measured direction without "
                         "noise")
    K = np.swapaxes(np.linalg.solve(S, H @ P), 1, 2)  # P H' S^-1
    # the pairs of weight above 0 only (a detection of weight 0 adds nothing, a NaN one
    # outside the gate too): a track's sums over its own, not over every detection
    rows, cols = np.nonzero(used)
    w = beta[rows, cols]
    nu_p = Z[cols] - zp[rows]  # (P, k)
    nu = np.stack([np.bincount(rows, w * nu_p[:, i], T) for i in range(k)], axis=-1)
    outer = (w[:, None, None] * nu_p[:, :, None] * nu_p[:, None, :]).reshape(-1, k * k)
    spread = (np.stack([np.bincount(rows, outer[:, i], T) for i in range(k * k)], axis=-1)
              .reshape(T, k, k) - nu[:, :, None] * nu[:, None, :])
    mean = m + np.einsum("tnm,tm->tn", K, nu)
    KSK = K @ S @ np.swapaxes(K, 1, 2)
    cov = P - (1.0 - beta0)[:, None, None] * KSK + K @ spread @ np.swapaxes(K, 1, 2)
    return Gaussian(mean, 0.5 * (cov + np.swapaxes(cov, 1, 2)))


def _check_weights(beta: np.ndarray, beta0: np.ndarray) -> None:
    """Raise a ValueError naming the first track whose weights are not probabilities: each
    in [0, 1] and the track's ``beta0`` and ``beta`` row adding up to 1 (within 1e-6)."""
    inside = lambda a: np.isfinite(a) & (a >= 0) & (a <= 1)  # noqa: E731
    bad = ~inside(beta)
    if bad.any():
        t, j = (int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"beta must hold probabilities in [0, 1]; beta[{t}, {j}] = "
                         f"{beta[t, j]}")
    if not inside(beta0).all():
        t = int(np.flatnonzero(~inside(beta0))[0])
        raise ValueError(f"beta0 must hold probabilities in [0, 1]; beta0[{t}] = {beta0[t]}")
    total = beta0 + beta.sum(axis=1)
    off = np.abs(total - 1.0) > 1e-6
    if off.any():
        t = int(np.flatnonzero(off)[0])
        raise ValueError(f"beta0 and beta of a track must add up to 1 (one of its events "
                         f"happens); track {t}'s add up to {total[t]:.9g}")
