r"""The probabilistic data association filter's correction: every track corrected with all
the detections, weighted by their association probabilities
(:func:`vistrack.association.pda_weights`, :func:`~vistrack.association.jpda_weights`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

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
        The tracks' predictions, batch shape ``(T,)``, state size ``n``.
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
    m, P = g.mean, g.cov
    H = np.asarray(H, dtype=float)
    R = np.asarray(R, dtype=float)
    Z = np.asarray(Z, dtype=float).reshape(-1, H.shape[0])
    zp = m @ H.T
    S = H @ P @ H.T + R
    K = np.swapaxes(np.linalg.solve(S, H @ P), 1, 2)  # P H' S^-1
    nu_j = Z[None, :, :] - zp[:, None, :]  # (T, D, m)
    nu = np.einsum("td,tdm->tm", beta, nu_j)
    spread = np.einsum("td,tdm,tdn->tmn", beta, nu_j, nu_j) - nu[:, :, None] * nu[:, None, :]
    mean = m + np.einsum("tnm,tm->tn", K, nu)
    KSK = K @ S @ np.swapaxes(K, 1, 2)
    cov = P - (1.0 - beta0)[:, None, None] * KSK + K @ spread @ np.swapaxes(K, 1, 2)
    return Gaussian(mean, 0.5 * (cov + np.swapaxes(cov, 1, 2)))
