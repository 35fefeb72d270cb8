r"""The unscented Kalman filter (seed 004: "propagate just a few sample points ('sigma points')
around the mean exactly, then recover the covariance from them").

Sigma points :math:`\chi_0 = x`, :math:`\chi_{\pm i} = x \pm (\sqrt{(n + \lambda) P})_i`
(columns of the Cholesky factor; of a singular covariance, which may have none, a root
from its eigendecomposition), with mean weights ``Wm`` and covariance weights ``Wc``:

- :class:`MerweScaledSigmaPoints` (van der Merwe's scaled points, parameters α, β, κ):
  :math:`\lambda = \alpha^2 (n + \kappa) - n`, :math:`W^m_0 = \lambda / (n + \lambda)`,
  :math:`W^c_0 = W^m_0 + 1 - \alpha^2 + \beta`, :math:`W_i = 1 / (2 (n + \lambda))`;
- :class:`JulierSigmaPoints` (Julier and Uhlmann's points, parameter κ): :math:`\lambda = \kappa`.

Prediction: :math:`x^- = \sum W^m_i f(\chi_i)`,
:math:`P^- = \sum W^c_i (f(\chi_i) - x^-)(f(\chi_i) - x^-)^T + Q`. Correction with sigma
points :math:`\gamma_i` drawn afresh from :math:`(x^-, P^-)`, so that they carry ``Q`` too
(on a linear model this makes the UKF the Kalman filter): with
:math:`d_i = r(h(\gamma_i), h(\gamma_0))`, the differences from the central point (``r`` the
measurement model's residual, angles wrapped), and :math:`m = \sum W^m_i d_i`,
:math:`\hat z = h(\gamma_0) + m`, :math:`S = \sum W^c_i (d_i - m)(d_i - m)^T + R`,
:math:`C = \sum W^c_i (\gamma_i - x^-)(d_i - m)^T`, :math:`K = C S^{-1}`,
:math:`x^+ = x^- + K\, r(y, \hat z)`, :math:`P^+ = P^- - K S K^T`, the last evaluated as
:math:`P^- - V V^T` with :math:`V = C L^{-T}`, :math:`S = L L^T`, so that it is symmetric by
construction. On plain components these are the usual sums; an angle is averaged about the
central point rather than on the circle (``atan2(Σ W sin, Σ W cos)``, which with the scaled
points' first weight of about -10^6 turns by π once the angle's spread passes about √2), and
with every residual about the same :math:`m` the covariances stay positive semi-definite. These
are the equations of FilterPy's ``UnscentedKalmanFilter`` given that mean (its ``z_mean_fn``),
which the tests check to 1e-8.

:meth:`UnscentedKalmanFilter.filter` runs the whole sequence in one compiled call where both
models provide compiled one-state functions (``jit_f``, ``jit_h`` with ``jit_params``: the
coordinated turn, range-bearing, the growth model) and the state has no mean or residual of
its own: a few microseconds a step, against some hundred for the steps from Python, with the
same one-Gaussian kernels. Other models run the steps from Python.

References: Julier and Uhlmann (1997), "A new extension of the Kalman filter to nonlinear
systems"; Wan and van der Merwe (2000), "The unscented Kalman filter for nonlinear estimation".
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._jit import njit
from .._prebuilt import Kernel, kernel
from .._validate import (
    as_float_array,
    as_whole,
    check_finite,
    check_one_step,
    check_psd,
    check_symmetric,
)
from ..models.adapters import MeasurementFunctions, MotionFunctions, psd_sqrt
from ..models.nonlinear import _offset_mean
from ..models.protocols import (
    MeasurementModel,
    MotionModel,
    NonlinearMeasurementModel,
    NonlinearMotionModel,
)
from ..types import Gaussian
from . import _codegen, _jitmath, _kernels
from ._codegen import Ref
from ._jitmath import wrap_angle
from ._kernels import back_solve, chol_factor, forward_solve, symmetric_within
from ._nonlinear import (
    check_gaussian,
    check_h_size,
    check_model_values,
    check_y,
    compiled_functions,
    compiled_run,
    own_steps,
    run_sequence,
)
from .kalman import FilterResult
from .reference import masked_innovation, symmetric

_chol_factor = kernel(chol_factor)
""":func:`chol_factor` for calls from Python (built at install: a batch with a singular member
does not compile it with numba)."""

__all__ = [
    "MerweScaledSigmaPoints",
    "JulierSigmaPoints",
    "ukf_predict",
    "ukf_update",
    "UnscentedKalmanFilter",
]


def _sqrt(P: np.ndarray, scale: float, name: str) -> np.ndarray:
    """Square roots ``L L' = scale P`` of a stack of covariances: LAPACK's Cholesky factors, or
    where one has none, :func:`_root_semidefinite`'s."""
    try:
        return np.linalg.cholesky(scale * P)
    except np.linalg.LinAlgError:
        return _root_semidefinite(P, scale, name)


def _root_semidefinite(P: np.ndarray, scale: float, name: str, *,
                       compiled: bool = True) -> np.ndarray:
    """Square roots ``L L' = scale P`` of a stack of covariances of which some have no Cholesky
    factor by LAPACK, or none by :func:`chol_factor` (the one-Gaussian path's).

    A state known exactly along a direction (``[[1, 1], [1, 1]]``: two states equal; a zero
    variance) makes a covariance singular, and its sigma points are still well defined, at
    the mean along that direction. Each matrix takes LAPACK's factor if it has one (so that a
    series' points do not depend on the others of its batch), else :func:`chol_factor`'s (a
    singular matrix may have one by rounding where LAPACK finds none: the one-Gaussian path
    then gives the same points), else a root from its eigendecomposition (the eigenvectors
    scaled by the square roots of their eigenvalues), after the check the filters give a prior
    (finite, symmetric, no eigenvalue below -1e-10 of its largest entry), the error naming
    ``name`` and the matrix's index in the stack. ``compiled=False``: the caller's
    :func:`chol_factor` already found none."""
    P = np.asarray(P)
    check_finite(P, name)  # (LAPACK's factor of NaN is NaN, without an error)
    n, lead = P.shape[-1], P.shape[:-2]
    flat = P.reshape(-1, n, n)
    out = np.empty(flat.shape, np.result_type(flat.dtype, np.float32))
    for b, p in enumerate(flat):
        a = scale * p
        try:
            out[b] = np.linalg.cholesky(a)
            continue
        except np.linalg.LinAlgError:
            pass
        L = np.zeros((n, n))
        if compiled and _chol_factor(L, np.ascontiguousarray(a, dtype=np.float64), n):
            out[b] = L
            continue
        check_psd(p, name + str(list(map(int, np.unravel_index(b, lead)))) if lead else name)
        out[b] = psd_sqrt(a)
    return out.reshape(P.shape)


def _settled(P: np.ndarray, prior: np.ndarray) -> np.ndarray:
    """The corrected covariances ``P (..., n, n)``, each with the eigenvalues that rounding
    took below zero, by no more than 1e-10 of its ``prior``'s largest entry, raised to 0.

    ``P = prior - V'V`` cancels where a measurement pins a large prior down along some
    directions: from a prior of rank 2 with entries near 2e6, measured to 1, the rounding
    (about 1e-16 of the prior's entries) left eigenvalues of -1e-10 where the exact ones are
    0, which is past the check of 1e-10 of the result's own largest entry (about 1), and the
    next prediction refused its own prior as not positive semi-definite (23 of 200 random
    such priors, at step 1). A matrix with a Cholesky factor, or whose smallest eigenvalue
    passes that check, is returned as it is, bit for bit; one whose eigenvalues lie further
    below is left for the check to name."""
    n = P.shape[-1]
    if P.ndim == 2 and _chol_factor(np.empty((n, n)), np.ascontiguousarray(P, np.float64), n):
        return P  # (one Gaussian, the common case: one compiled call)
    flat, before = P.reshape(-1, n, n), prior.reshape(-1, n, n)
    if len(flat) > 1:
        try:
            np.linalg.cholesky(flat)  # (a batch: each matrix's factor, in one call)
            return P
        except np.linalg.LinAlgError:
            pass
    out = None
    for b, p in enumerate(flat):
        L = np.zeros((n, n))
        if _chol_factor(L, np.ascontiguousarray(p, dtype=np.float64), n):
            continue
        w, V = np.linalg.eigh(p)
        own = 1e-10 * np.abs(p).max()
        if not -1e-10 * np.abs(before[b]).max() <= w[0] < -own:
            continue
        if out is None:
            out = flat.copy()
        out[b] = symmetric((V * np.maximum(w, 0.0)) @ V.T)
    return P if out is None else out.reshape(P.shape)


# ---------------------------------------------------------------- compiled, one Gaussian
# For one Gaussian (the common case of a track) the sigma-point algebra is a few dozen numpy
# calls on 5x5 matrices, whose overhead is most of the time; these kernels do it in three
# compiled calls a step, with the Kalman kernels' Cholesky factor and triangular solves. The
# model's f and h still run as numpy on all points at once.
@kernel
@njit(cache=True, error_model="numpy")
def _points_one(x, P, scale, out):
    """0 with the points in ``out``; 1 where ``P`` has no Cholesky factor; 2 where ``P`` is
    not symmetric to 1e-8 of its largest entry, as :func:`check_symmetric` judges (its lower
    triangle alone was read, where the other filters read it whole)."""
    n = x.shape[0]
    if not symmetric_within(P, 1e-8):
        return 2
    L = np.zeros((n, n))  # (the upper triangle stays zero)
    if not chol_factor(L, scale * P, n):
        return 1
    for k in range(n):
        out[0, k] = x[k]
    for i in range(n):
        for k in range(n):
            out[1 + i, k] = x[k] + L[k, i]
            out[1 + n + i, k] = x[k] - L[k, i]
    return 0


@kernel
@njit(cache=True, error_model="numpy")
def _state_moments_one(Y, Wm, Wc, Q, mean, cov):
    K, n = Y.shape
    for k in range(n):
        # about the first point, as _offset_mean: W_0 is about -10^6
        v = 0.0
        for i in range(1, K):
            v += Wm[i] * (Y[i, k] - Y[0, k])
        mean[k] = Y[0, k] + v
    for a in range(n):
        for b in range(a + 1):
            v = Q[a, b]
            for i in range(K):
                v += Wc[i] * (Y[i, a] - mean[a]) * (Y[i, b] - mean[b])
            cov[a, b] = v
            cov[b, a] = v


@kernel
@njit(cache=True, error_model="numpy")
def _update_one(G, Z, Wm, Wc, R, y, angles, x, P, xo, Po):
    """Unscented correction of one Gaussian from its sigma points ``G`` and their
    measurements ``Z`` (the equations of :func:`ukf_update`: differences from the central
    point, angles wrapped, and residuals about their unwrapped weighted sum; NaN components
    of ``y`` missing). Returns ``(ok, loglik)``."""
    K, n = G.shape
    m = Z.shape[1]
    zhat = np.empty(m)
    for k in range(m):
        # the differences from the central point (an angle's wrapped), summed: W_0 is about
        # -10^6 (as _offset_mean); the residuals are about the mean they give, unwrapped
        # (_central_transform)
        v = 0.0
        for i in range(1, K):
            d = Z[i, k] - Z[0, k]
            v += Wm[i] * (wrap_angle(d) if angles[k] else d)
        zhat[k] = v
    rz = np.empty((K, m))
    e = np.empty(m)
    nobs = 0
    for k in range(m):
        obs = not math.isnan(y[k])
        nobs += obs
        d = y[k] - (Z[0, k] + zhat[k]) if obs else 0.0
        e[k] = wrap_angle(d) if angles[k] else d
        for i in range(K):
            d = Z[i, k] - Z[0, k]
            rz[i, k] = ((wrap_angle(d) if angles[k] else d) - zhat[k]) if obs else 0.0
    S = np.empty((m, m))
    for a in range(m):
        for b in range(a + 1):
            if math.isnan(y[a]) or math.isnan(y[b]):
                v = 1.0 if a == b else 0.0
            else:
                v = R[a, b]
                for i in range(K):
                    v += Wc[i] * rz[i, a] * rz[i, b]
            S[a, b] = v
            S[b, a] = v
    C = np.zeros((n, m))
    for i in range(K):
        for a in range(n):
            dx = Wc[i] * (G[i, a] - x[a])
            for b in range(m):
                C[a, b] += dx * rz[i, b]
    L = np.empty((m, m))
    if not chol_factor(L, S, m):
        return False, 0.0
    # Vt = L^-1 C' (m x n); K' = L'^-1 Vt; whitened innovation w = L^-1 e
    Vt = np.ascontiguousarray(C.T)
    forward_solve(L, Vt, m, n)
    Kt = Vt.copy()
    back_solve(L, Kt, m, n)
    w = np.empty((m, 1))
    for a in range(m):  # a loop: see _kernels.copy_vec
        w[a, 0] = e[a]
    forward_solve(L, w, m, 1)
    ll = -0.5 * nobs * math.log(2.0 * math.pi)
    for b in range(m):
        ll -= 0.5 * w[b, 0] * w[b, 0] + math.log(L[b, b])
    for a in range(n):
        v = x[a]
        for b in range(m):
            v += Kt[b, a] * e[b]
        xo[a] = v
    for a in range(n):
        for c in range(a + 1):
            v = P[a, c]
            for b in range(m):
                v -= Vt[b, a] * Vt[b, c]
            Po[a, c] = v
            Po[c, a] = v
    return True, ll


class _SigmaPoints:
    lam: float

    def _lam(self, n: int) -> float:
        raise NotImplementedError

    def weights(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        raise NotImplementedError

    def points_one(self, x: np.ndarray, P: np.ndarray) -> np.ndarray:
        r"""Sigma points of one Gaussian, by a compiled kernel.

        The same points as :meth:`points`: :math:`\chi_0 = x`, then
        :math:`x + (\sqrt{(n + \lambda) P})_i` for each column ``i`` of the Cholesky factor
        (of a singular ``P``, which may have none, a root from its eigendecomposition), then
        :math:`x - (\sqrt{(n + \lambda) P})_i`.

        Parameters
        ----------
        x : (n,) ndarray
            Mean.
        P : (n, n) ndarray
            Covariance, positive semi-definite.

        Returns
        -------
        (2n + 1, n) ndarray
            The points, one a row.

        Raises
        ------
        ValueError
            If ``P`` is not positive semi-definite, or the points' parameters give
            :math:`n + \lambda \le 0`.

        Examples
        --------
        >>> JulierSigmaPoints(kappa=1.0).points_one(np.zeros(2), np.eye(2)).round(3)
        array([[ 0.   ,  0.   ],
               [ 1.732,  0.   ],
               [ 0.   ,  1.732],
               [-1.732,  0.   ],
               [ 0.   , -1.732]])
        """
        x = as_float_array(x, "x", ndim=(1,))
        P = as_float_array(P, "P", ndim=(2,))
        self._check_pair(x, P)
        return self._one(x, P, "P")

    @staticmethod
    def _check_pair(x: np.ndarray, P: np.ndarray) -> None:
        """``P`` of ``x``'s size, both finite, ``P`` symmetric (a larger ``P`` was cut to its
        top-left block by ``points_one``, and by ``points`` met numpy's broadcast error)."""
        n = x.shape[-1]
        if P.shape[-2:] != (n, n):
            raise ValueError(f"P must be (..., {n}, {n}), the size of x's {n} values; got "
                             f"shape {P.shape}")
        try:  # (numpy's broadcast error named neither: x (2,) with P (3, 2, 2) is 3 points)
            np.broadcast_shapes(x.shape[:-1], P.shape[:-2])
        except ValueError:
            raise ValueError(f"x and P must have batch shapes that broadcast; got x "
                             f"{x.shape} and P {P.shape}") from None
        check_finite(x, "x")
        check_symmetric(P, "P")

    @staticmethod
    def _finite(x: np.ndarray, P: np.ndarray, name: str) -> None:
        """The mean and covariance ``name`` finite (LAPACK's factor of a NaN matrix is NaN,
        without an error: the batch's points were NaN, and its update blamed ``h``)."""
        check_finite(x, name.replace("cov", "mean") if "cov" in name else "x")
        check_finite(P, name)

    def _one(self, x: np.ndarray, P: np.ndarray, name: str) -> np.ndarray:
        self._finite(x, P, name)
        n = x.shape[0]
        out = np.empty((2 * n + 1, n))
        scale = float(n + self._lam(n))
        code = _points_one(x, P, scale, out)
        if code == 2:
            check_symmetric(P, name)
        if code:  # no Cholesky factor: see _root_semidefinite
            Lt = _root_semidefinite(P, scale, name, compiled=False).T
            out[0], out[1:n + 1], out[n + 1:] = x, x + Lt, x - Lt
        return out

    def points(self, x: np.ndarray, P: np.ndarray) -> np.ndarray:
        r"""Sigma points of a batch of Gaussians.

        :math:`\chi_0 = x`, then :math:`x + (\sqrt{(n + \lambda) P})_i` for each column ``i``
        of the Cholesky factor (of a singular ``P``, which may have none, a root from its
        eigendecomposition), then :math:`x - (\sqrt{(n + \lambda) P})_i`.

        Parameters
        ----------
        x : (..., n) ndarray
            Means; the leading dimensions index the batch.
        P : (..., n, n) ndarray
            Covariances, positive semi-definite.

        Returns
        -------
        (..., 2n + 1, n) ndarray
            The points of each Gaussian, one a row.

        Raises
        ------
        ValueError
            If a covariance is not positive semi-definite, or the points' parameters give
            :math:`n + \lambda \le 0`.

        Examples
        --------
        >>> pts = MerweScaledSigmaPoints(alpha=0.5).points(np.zeros((3, 2)), np.eye(2))
        >>> pts.shape, pts[0, :, 0].round(3).tolist()
        ((3, 5, 2), [0.0, 0.707, 0.0, -0.707, 0.0])
        """
        x = as_float_array(x, "x", ndim=None)
        P = as_float_array(P, "P", ndim=None)
        if x.ndim < 1 or P.ndim < 2:
            raise ValueError(f"x must be (..., n) and P (..., n, n); got shapes {x.shape} and "
                             f"{P.shape}")
        self._check_pair(x, P)
        return self._many(x, P, "P")

    def _many(self, x: np.ndarray, P: np.ndarray, name: str) -> np.ndarray:
        self._finite(x, P, name)
        n = x.shape[-1]
        check_symmetric(P, name)  # (LAPACK's factor reads the lower triangle alone)
        L = _sqrt(P, n + self._lam(n), name)
        Lt = np.swapaxes(L, -1, -2)  # row i = column i of L
        xb = x[..., None, :]
        if xb.shape[:-2] != Lt.shape[:-2]:  # (a mean for many covariances, or the reverse)
            batch = np.broadcast_shapes(xb.shape[:-2], Lt.shape[:-2])
            xb = np.broadcast_to(xb, batch + xb.shape[-2:])
            Lt = np.broadcast_to(Lt, batch + Lt.shape[-2:])
        return np.concatenate([xb, xb + Lt, xb - Lt], axis=-2)


def _points_or_default(points: Any) -> _SigmaPoints:
    """``points``, the package's sigma points, or Van der Merwe's by default (None): a falsy
    value (0) was taken as the default, and text or another library's points failed at the
    first step on an attribute."""
    if points is None:
        return MerweScaledSigmaPoints()
    if not isinstance(points, _SigmaPoints):
        raise TypeError(f"points must be MerweScaledSigmaPoints or JulierSigmaPoints; got "
                        f"{type(points).__name__}")
    return points


class MerweScaledSigmaPoints(_SigmaPoints):
    r"""Van der Merwe's scaled sigma points: ``2n + 1`` points with parameters α (spread, small
    positive), β (2 is optimal for Gaussians) and κ (usually 0 or 3 - n).

    Parameters
    ----------
    alpha : float
        Spread of the points around the mean, > 0.
    beta : float
        Prior knowledge of the distribution, added to the mean's covariance weight (2 is
        optimal for Gaussians).
    kappa : float
        Secondary scaling.

    Raises
    ------
    ValueError
        If ``alpha`` is not a finite number > 0, ``beta`` or ``kappa`` not a finite number
        (and, when points or weights are asked for a state size ``n``, if
        :math:`\alpha^2 (n + \kappa) \le 0`).

    Notes
    -----
    For a state of size ``n``,

    .. math::

        \lambda = \alpha^2 (n + \kappa) - n, \qquad
        W^m_0 = \frac{\lambda}{n + \lambda}, \qquad
        W^c_0 = W^m_0 + 1 - \alpha^2 + \beta, \qquad
        W^m_i = W^c_i = \frac{1}{2 (n + \lambda)} \quad (i = 1 \dots 2n),

    and the points are :math:`x` and :math:`x \pm (\sqrt{(n + \lambda) P})_i`.

    References
    ----------
    .. [1] E. A. Wan and R. van der Merwe, "The unscented Kalman filter for nonlinear
       estimation", *Proceedings of the IEEE Adaptive Systems for Signal Processing,
       Communications, and Control Symposium*, 2000.

    Examples
    --------
    >>> pts = MerweScaledSigmaPoints(alpha=1.0, beta=2.0, kappa=1.0)
    >>> Wm, Wc = pts.weights(2)
    >>> Wm.round(3).tolist(), Wc.round(3).tolist()
    ([0.333, 0.167, 0.167, 0.167, 0.167], [2.333, 0.167, 0.167, 0.167, 0.167])
    """

    def __init__(self, alpha: float = 1e-3, beta: float = 2.0, kappa: float = 0.0):
        from .._validate import as_finite

        # a NaN beta or an infinite kappa was taken, and the filter then blamed R or the
        # covariance
        self.alpha = as_finite(alpha, "alpha", 0.0, above=True)
        self.beta, self.kappa = as_finite(beta, "beta"), as_finite(kappa, "kappa")

    def __repr__(self) -> str:
        return f"MerweScaledSigmaPoints(alpha={self.alpha}, beta={self.beta}, kappa={self.kappa})"

    def _lam(self, n: int) -> float:
        try:  # (alpha 1e155: float's OverflowError, unnamed)
            lam = self.alpha**2 * (n + self.kappa) - n
        except OverflowError:
            lam = math.inf
        if not n + lam < math.inf:  # (kappa 1e308 gave weights of NaN, and NaN estimates)
            raise ValueError(f"alpha**2 * (n + kappa) must be finite; got alpha {self.alpha}, "
                             f"kappa {self.kappa} for n={n}")
        if n + lam <= 0:
            raise ValueError(f"alpha**2 * (n + kappa) must be > 0; got {n + lam} for n={n}")
        return lam

    def weights(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        r"""The mean and covariance weights of the ``2n + 1`` points (see the class).

        Parameters
        ----------
        n : int
            State size.

        Returns
        -------
        Wm : (2n + 1,) ndarray
            Mean weights; they sum to 1.
        Wc : (2n + 1,) ndarray
            Covariance weights: ``Wm`` but for the first, :math:`W^m_0 + 1 - \alpha^2 + \beta`.

        Raises
        ------
        ValueError
            If :math:`\alpha^2 (n + \kappa) \le 0`.

        Examples
        --------
        >>> Wm, Wc = MerweScaledSigmaPoints(alpha=1.0, kappa=1.0).weights(2)
        >>> round(float(Wm.sum()), 12), round(float(Wc[0] - Wm[0]), 12)
        (1.0, 2.0)
        """
        n = as_whole(n, "n", 1)  # (-1 and 2.5 failed in numpy's words)
        lam = self._lam(n)
        Wm = np.full(2 * n + 1, 0.5 / (n + lam))
        Wc = Wm.copy()
        Wm[0] = lam / (n + lam)
        Wc[0] = Wm[0] + 1.0 - self.alpha**2 + self.beta
        return Wm, Wc


class JulierSigmaPoints(_SigmaPoints):
    r"""Julier and Uhlmann's sigma points: ``2n + 1`` points, weight ``κ / (n + κ)`` on the mean.

    Parameters
    ----------
    kappa : float
        Scaling: :math:`\lambda = \kappa`; ``n + κ`` must be > 0 for a state of size ``n``.

    Notes
    -----
    The points are :math:`x` and :math:`x \pm (\sqrt{(n + \kappa) P})_i`, with the same
    weights for the mean and the covariance,

    .. math::

        W_0 = \frac{\kappa}{n + \kappa}, \qquad
        W_i = \frac{1}{2 (n + \kappa)} \quad (i = 1 \dots 2n).

    References
    ----------
    .. [1] S. J. Julier and J. K. Uhlmann, "A new extension of the Kalman filter to nonlinear
       systems", *Proceedings of SPIE* 3068 (Signal Processing, Sensor Fusion, and Target
       Recognition VI), 1997.

    Examples
    --------
    >>> Wm, Wc = JulierSigmaPoints(kappa=1.0).weights(2)
    >>> Wm.round(3).tolist(), bool((Wm == Wc).all())
    ([0.333, 0.167, 0.167, 0.167, 0.167], True)
    """

    def __init__(self, kappa: float = 0.0):
        from .._validate import as_finite

        self.kappa = as_finite(kappa, "kappa")

    def __repr__(self) -> str:
        return f"JulierSigmaPoints(kappa={self.kappa})"

    def _lam(self, n: int) -> float:
        if n + self.kappa <= 0:
            raise ValueError(f"n + kappa must be > 0; got {n + self.kappa}")
        return self.kappa

    def weights(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The mean and covariance weights of the ``2n + 1`` points (see the class).

        Parameters
        ----------
        n : int
            State size; ``n + kappa`` must be > 0.

        Returns
        -------
        Wm : (2n + 1,) ndarray
            Mean weights; they sum to 1.
        Wc : (2n + 1,) ndarray
            Covariance weights, equal to ``Wm``.

        Raises
        ------
        ValueError
            If ``n + kappa <= 0``.

        Examples
        --------
        >>> JulierSigmaPoints(kappa=0.0).weights(1)[0].tolist()
        [0.0, 0.5, 0.5]
        """
        n = as_whole(n, "n", 1)  # (-1 and 2.5 failed in numpy's words)
        if not n + self.kappa > 0:
            raise ValueError(f"n + kappa must be > 0; got {n + self.kappa} for n={n}")
        W = np.full(2 * n + 1, 0.5 / (n + self.kappa))
        W[0] = self.kappa / (n + self.kappa)
        return W, W.copy()


def _transform(pts: np.ndarray, Wm: np.ndarray, Wc: np.ndarray, mean_fn: Callable,
               residual: Callable) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Unscented mean and covariance of points ``(..., k, d)``; also the residuals."""
    mean = mean_fn(pts, Wm)
    r = residual(pts, mean[..., None, :])
    cov = np.einsum("...ki,k,...kj->...ij", r, Wc, r)
    return mean, cov, r


def _central_transform(pts: np.ndarray, Wm: np.ndarray, Wc: np.ndarray,
                       residual: Callable) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`_transform` of sigma points ``(..., k, d)`` (the first the central one) for a
    residual that is a difference, angles wrapped: the points' residuals from the central
    one ``d_i``, their weighted sum ``m`` (the mean ``pts_0 + m``, left unwrapped), and the
    covariance of ``d_i - m``. The circular mean of an angle, ``atan2(Σ W sin, Σ W cos)`` (the
    model's ``mean``, right for an ensemble), is not the transform's: with scaled points
    (α small, the first weight about -1/α²) ``Σ W cos`` is ``1 - σ²/2`` to second order, σ
    the angle's spread, and past σ ≈ √2 it turns the mean by π; and residuals about a mean
    wrapped back from beyond ±π of the central point leave a covariance that need not be
    positive semi-definite. With every residual about the same ``m`` the covariance is
    ``Σ_{i≥1} W_i d_i d_i' + (Σ W^c - 2) m m'``, positive semi-definite for van der Merwe's
    points with β ≥ α², and for any points whose weights are all at least 0."""
    d = residual(pts, pts[..., :1, :])
    m = np.einsum("...km,k->...m", d, Wm)
    r = d - m[..., None, :]
    return pts[..., 0, :] + m, np.einsum("...ki,k,...kj->...ij", r, Wc, r), r


def ukf_predict(g: Gaussian, motion: MotionModel | NonlinearMotionModel, dt: float = 1.0,
                t: float = 0.0, *,
                points: _SigmaPoints | None = None, state_mean: Callable | None = None,
                state_residual: Callable | None = None) -> Gaussian:
    r"""UKF prediction of a batch of Gaussians through the dynamics.

    With sigma points :math:`\chi_i` of ``g`` and weights :math:`W^m_i`, :math:`W^c_i`,

    .. math::

        x^- = \sum_i W^m_i f(\chi_i), \qquad
        P^- = \sum_i W^c_i \big(f(\chi_i) - x^-\big)\big(f(\chi_i) - x^-\big)' + Q(\Delta t)

    (the mean and the differences are ``state_mean`` and ``state_residual`` when given).

    Parameters
    ----------
    g : Gaussian
        Mean ``(..., n)`` and covariance ``(..., n, n)``, positive semi-definite; the leading
        dimensions index the batch.
    motion : motion model
        Nonlinear (``f``, ``jacobian``, ``Q``; :mod:`vistrack.models.nonlinear`) or linear
        (``F``, ``Q``).
    dt : float
        Time step.
    t : float
        Time of the predicted state (for time-varying models).
    points : MerweScaledSigmaPoints or JulierSigmaPoints, optional
        The sigma points; default ``MerweScaledSigmaPoints()``.
    state_mean : callable, optional
        ``state_mean(points, w)``: the weighted mean of points ``(..., k, n)`` with weights
        ``(k,)``, overriding the weighted sum (for states with angles).
    state_residual : callable, optional
        ``state_residual(a, b)``, overriding ``a - b`` (for states with angles).

    Returns
    -------
    Gaussian
        The predicted mean ``(..., n)`` and covariance ``(..., n, n)``.

    Raises
    ------
    TypeError
        If ``g`` is not a :class:`~vistrack.types.Gaussian`, or ``motion`` is not a motion
        model.
    ValueError
        If a covariance is not positive semi-definite (no sigma points).

    References
    ----------
    .. [1] S. J. Julier and J. K. Uhlmann, "A new extension of the Kalman filter to nonlinear
       systems", *Proceedings of SPIE* 3068 (Signal Processing, Sensor Fusion, and Target
       Recognition VI), 1997.
    .. [2] E. A. Wan and R. van der Merwe, "The unscented Kalman filter for nonlinear
       estimation", *Proceedings of the IEEE Adaptive Systems for Signal Processing,
       Communications, and Control Symposium*, 2000.

    Examples
    --------
    >>> from vistrack.models import CoordinatedTurn
    >>> g = Gaussian(np.array([0.0, 0.0, 1.0, 0.0, 0.1]), np.eye(5) * 0.01)
    >>> ukf_predict(g, CoordinatedTurn(q=0.1), dt=1.0).mean.round(3)  # EKF: 0.998 0.05 0.995 0.1
    array([0.997, 0.05 , 0.99 , 0.099, 0.1  ])
    """
    g = check_gaussian(g)
    check_one_step(dt)
    mo = MotionFunctions.of(motion)
    points = _points_or_default(points)
    n = g.mean.shape[-1]
    if n != mo.n:  # (numpy's matmul error, naming neither)
        raise ValueError(f"g must have a state of {mo.n} values, the motion model's; got {n}")
    Wm, Wc = points.weights(n)
    if g.mean.ndim == 1 and state_mean is None and state_residual is None:
        gamma = np.asarray(mo.f(points._one(g.mean, g.cov, "g.cov"), dt, t), dtype=float)
        mean, cov = np.empty(n), np.empty((n, n))
        _state_moments_one(gamma, Wm, Wc, np.asarray(mo.Q(dt), dtype=float), mean, cov)
        return Gaussian(mean, cov)
    chi = points._many(g.mean, g.cov, "g.cov")
    gamma = np.asarray(mo.f(chi, dt, t), dtype=float)
    mean, cov, _ = _transform(gamma, Wm, Wc, state_mean or _wmean, state_residual or _sub)
    return Gaussian(mean, symmetric(cov + mo.Q(dt)))


def _wmean(z: np.ndarray, w: np.ndarray) -> np.ndarray:
    return _offset_mean(z, w)


def _sub(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a - b


def ukf_update(g: Gaussian, y: ArrayLike,
               measurement: MeasurementModel | NonlinearMeasurementModel, *,
               points: _SigmaPoints | None = None,
               residual: Callable | None = None, mean: Callable | None = None,
               state_residual: Callable | None = None) -> Gaussian:
    r"""UKF correction of a batch of Gaussians with a measurement each (NaN = missing).

    The sigma points :math:`\gamma_i` are drawn from ``g`` (so that they carry the process
    noise of the prediction too). With residuals :math:`r_i` (below), over the observed
    components,

    .. math::

        \hat z = h(\gamma_0) + m, \quad m = \sum_i W^m_i d_i, \qquad
        S = \sum_i W^c_i r_i r_i' + R, \qquad
        C = \sum_i W^c_i (\gamma_i - x) r_i',

        K = C S^{-1}, \qquad x^+ = x + K\, r(y, \hat z), \qquad
        P^+ = P - V V', \quad V = C L^{-T}, \quad S = L L',

    the last form symmetric by construction, where :math:`d_i = r(h(\gamma_i), h(\gamma_0))`
    are the differences from the central sigma point and :math:`r_i = d_i - m`, ``r`` the
    measurement model's residual (differences, angles wrapped): an angle is averaged about
    the central point, not on the circle (whose mean, with the scaled points' first weight of
    about -10^6, turns by π once the angle's spread passes about √2). A model with a
    residual or mean of its own (or ``residual``, ``mean`` given) uses them instead:
    :math:`\hat z` its mean of the :math:`h(\gamma_i)` and :math:`r_i = r(h(\gamma_i), \hat z)`.
    On a linear model this is the Kalman update.

    Parameters
    ----------
    g : Gaussian
        The prior: mean ``(..., n)`` and covariance ``(..., n, n)``, positive semi-definite.
    y : (..., m) array_like
        One measurement per Gaussian; NaN components are missing (they neither correct the
        state nor count in the log-likelihood).
    measurement : measurement model
        Nonlinear (``h``, ``jacobian``, ``R``; :mod:`vistrack.models.nonlinear`) or linear
        (``H``, ``R``).
    points : MerweScaledSigmaPoints or JulierSigmaPoints, optional
        The sigma points; default ``MerweScaledSigmaPoints()``.
    residual : callable, optional
        ``residual(a, b)`` of measurements, overriding the model's.
    mean : callable, optional
        ``mean(z, w)``: the weighted mean of measurements ``(..., k, m)`` with weights
        ``(k,)``, overriding the model's.
    state_residual : callable, optional
        ``state_residual(a, b)`` of states, overriding ``a - b`` in :math:`C` (for states with
        angles).

    Returns
    -------
    Gaussian
        The corrected mean ``(..., n)`` and covariance ``(..., n, n)``.
        :meth:`UnscentedKalmanFilter.update` also gives the log-density of the innovation,
        :math:`\log N(r(y, \hat z); 0, S)`, over the observed components.

    Raises
    ------
    TypeError
        If ``g`` is not a :class:`~vistrack.types.Gaussian`, or ``measurement`` is not a
        measurement model.
    ValueError
        If ``y`` does not have shape ``(..., m)`` matching ``g``, a covariance is not
        positive semi-definite, or the innovation covariance is not (``R`` must be positive
        definite on the observed components).

    References
    ----------
    .. [1] S. J. Julier and J. K. Uhlmann, "A new extension of the Kalman filter to nonlinear
       systems", *Proceedings of SPIE* 3068 (Signal Processing, Sensor Fusion, and Target
       Recognition VI), 1997.
    .. [2] E. A. Wan and R. van der Merwe, "The unscented Kalman filter for nonlinear
       estimation", *Proceedings of the IEEE Adaptive Systems for Signal Processing,
       Communications, and Control Symposium*, 2000.

    Examples
    --------
    On a linear model, the Kalman update (:func:`~vistrack.filters.kf_update` gives the
    same numbers):

    >>> from vistrack.models import ConstantVelocity, Position
    >>> g = ukf_predict(Gaussian(np.array([0.0, 1.0]), np.eye(2)), ConstantVelocity(dim=1, q=0.1))
    >>> ukf_update(g, [1.5], Position(dim=1, r=0.5)).mean.round(3)
    array([1.401, 1.207])

    A batch of three, the second measurement missing:

    >>> gb = Gaussian(np.zeros((3, 2)), np.broadcast_to(np.eye(2), (3, 2, 2)))
    >>> ukf_update(gb, [[1.0], [np.nan], [2.0]], Position(dim=1, r=0.5)).mean[:, 0].round(3)
    array([0.667, 0.   , 1.333])
    """
    return _ukf_update(g, y, measurement, points, residual, mean, state_residual)[0]


def _ukf_update(g: Gaussian, y: ArrayLike,
                measurement: MeasurementModel | NonlinearMeasurementModel,
                points: _SigmaPoints | None,
                residual: Callable | None, mean: Callable | None,
                state_residual: Callable | None) -> tuple[Gaussian, np.ndarray]:
    g = check_gaussian(g)
    n = g.mean.shape[-1]
    me = MeasurementFunctions.of(measurement, n, residual, mean)
    y = check_y(y, g.mean.shape[:-1], me.m)
    points = _points_or_default(points)
    Wm, Wc = points.weights(n)
    if g.mean.ndim == 1 and me.standard and state_residual is None:
        gamma = points._one(g.mean, g.cov, "g.cov")
        xo, Po = np.empty(n), np.empty((n, n))
        z = check_h_size(np.asarray(me.h(gamma), dtype=float), me.m, gamma)
        ok, ll1 = _update_one(gamma, z, Wm, Wc, me.Rm, y, me.angle_mask, g.mean, g.cov, xo, Po)
        if not ok:
            zo = z[:, ~np.isnan(y)]  # (a missing component's value is not used)
            if not np.isfinite(zo).all():
                k = int(np.flatnonzero(~np.isfinite(zo).all(axis=-1))[0])
                raise ValueError(f"the measurement model gave NaN or infinity at sigma point "
                                 f"{k}: h({np.array2string(gamma[k], precision=4)}) = "
                                 f"{np.array2string(z[k], precision=4)}")
            raise ValueError("the innovation covariance is not positive definite; R must be "
                             "positive definite on the observed components")
        out = Gaussian(xo, _settled(Po, g.cov))
        return out, np.asarray(ll1)
    gamma = points._many(g.mean, g.cov, "g.cov")
    obs = ~np.isnan(y)
    # a missing component's value is not used: 0, not NaN, where h has none there (NaN times
    # the mask's 0 below is NaN, and made every estimate of the batch NaN)
    hz = check_h_size(np.asarray(me.h(gamma), dtype=float), me.m, gamma)
    zs = np.where(obs[..., None, :], hz, 0.0)
    check_model_values(zs, gamma, "sigma point")
    zhat, Pzz, rz = (_central_transform(zs, Wm, Wc, me.residual) if me.standard
                     else _transform(zs, Wm, Wc, me.mean, me.residual))
    rz = rz * obs[..., None, :]  # missing components: no cross-covariance
    dx = (state_residual or _sub)(gamma, g.mean[..., None, :])
    C = np.einsum("...ki,k,...kj->...ij", dx, Wc, rz)
    e = me.residual(np.where(obs, y, 0.0), zhat)
    e, S, L, ll = masked_innovation(e, Pzz + me.Rm, obs)
    Vt = np.linalg.solve(L, np.swapaxes(C, -1, -2))  # (C L^-T)'
    K = np.swapaxes(np.linalg.solve(np.swapaxes(L, -1, -2), Vt), -1, -2)  # C S^-1 = V L^-1
    out = Gaussian(g.mean + (K @ e[..., None])[..., 0],
                   _settled(symmetric(g.cov - np.swapaxes(Vt, -1, -2) @ Vt), g.cov))
    return out, ll


class UnscentedKalmanFilter:
    """The UKF over a sequence, from a motion and a measurement model: :func:`ukf_predict`
    and :func:`ukf_update` per step.

    Parameters
    ----------
    motion, measurement
        Nonlinear models (:mod:`vistrack.models.nonlinear`) or linear ones.
    points : MerweScaledSigmaPoints or JulierSigmaPoints, optional
        Default ``MerweScaledSigmaPoints()`` (α = 1e-3, β = 2, κ = 0).
    residual, mean : callable, optional
        Measurement residual ``r(a, b)`` and mean ``mean(z, w)``, overriding the model's.
    state_residual, state_mean : callable, optional
        The same for the state (for states with angles).

    Raises
    ------
    TypeError
        If a model lacks what a motion or measurement model provides.

    References
    ----------
    .. [1] S. J. Julier and J. K. Uhlmann, "A new extension of the Kalman filter to nonlinear
       systems", *Proceedings of SPIE* 3068 (Signal Processing, Sensor Fusion, and Target
       Recognition VI), 1997.
    .. [2] E. A. Wan and R. van der Merwe, "The unscented Kalman filter for nonlinear
       estimation", *Proceedings of the IEEE Adaptive Systems for Signal Processing,
       Communications, and Control Symposium*, 2000.

    Examples
    --------
    >>> import vistrack as vt
    >>> motion, meas = vt.models.CoordinatedTurn(q=0.01), vt.models.RangeBearing(ndim_state=5)
    >>> ys = np.array([[10.0, 0.0], [10.5, 0.1], [np.nan, np.nan], [11.0, 0.3]])
    >>> res = UnscentedKalmanFilter(motion, meas).filter(
    ...     ys, x0=[10.0, 0.0, 0.0, 1.0, 0.0], P0=np.diag([1.0, 1.0, 1.0, 1.0, 0.01]))
    >>> res.means.shape, res.covs.shape
    ((4, 5), (4, 5, 5))
    """

    def __init__(self, motion: MotionModel | NonlinearMotionModel,
                 measurement: MeasurementModel | NonlinearMeasurementModel, *,
                 points: _SigmaPoints | None = None,
                 residual: Callable | None = None, mean: Callable | None = None,
                 state_residual: Callable | None = None, state_mean: Callable | None = None):
        self.motion = MotionFunctions(motion)
        self.measurement = MeasurementFunctions(measurement, self.motion.n, residual, mean)
        self.points = _points_or_default(points)
        self.state_residual, self.state_mean = state_residual, state_mean

    def filter(self, ys: ArrayLike, *, x0: ArrayLike, P0: ArrayLike,
               dt: ArrayLike | None = None, times: ArrayLike | None = None) -> FilterResult:
        """Filter a sequence, or a batch of them; arguments as
        :meth:`ExtendedKalmanFilter.filter <vistrack.filters.ExtendedKalmanFilter.filter>`.

        Each step predicts (but the first) and corrects with its measurement; a step whose
        measurement is all NaN is predicted only.

        Parameters
        ----------
        ys : (T, m) or (B, T, m) array_like
            Measurements; NaN components (or masked entries of a numpy masked array) are
            missing.
        x0 : (n,) or (B, n) array_like
            Prior mean of the first step.
        P0 : (n, n) or (B, n, n) array_like
            Prior covariance of the first step, positive semi-definite (a state known exactly
            along a direction has its sigma points there at the mean).
        dt : float or (T,) array_like, optional
            Time step: a scalar, the ``T-1`` intervals between steps (``np.diff(times)``),
            or ``T`` values, ``dt[t]`` the step from ``t-1`` to ``t`` (``dt[0]`` unused);
            default ``np.diff(times)`` where ``times`` is given, else 1.
        times : (T,) array_like, optional
            Time of each step, not decreasing, passed to the model; default the cumulative
            ``dt`` from 0. Given with ``dt``, the two must agree.

        Returns
        -------
        FilterResult
            Corrected means ``(..., T, n)`` and covariances ``(..., T, n, n)``, the
            predictions, and the log-likelihood ``(...)``.

        Raises
        ------
        ValueError
            If the shapes disagree with the models, a covariance is not positive
            semi-definite, or a model gives NaN or infinity (the error names the first step,
            and series, whose prediction or correction it made so).

        Examples
        --------
        Two series at once, on a linear model:

        >>> from vistrack.models import ConstantVelocity, Position
        >>> ukf = UnscentedKalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1))
        >>> ys = np.stack([np.arange(5.0), -np.arange(5.0)])[..., None]
        >>> res = ukf.filter(ys, x0=[0.0, 0.0], P0=np.eye(2))
        >>> res.means.shape, res.loglik.shape
        ((2, 5, 2), (2,))
        """
        if (own_steps(self, _OWN_STEPS) and self.state_mean is None
                and self.state_residual is None):
            # models with compiled functions: the whole filter in one compiled call; what it
            # cannot take (a covariance without a Cholesky factor, a value not finite) is
            # filtered again below, which takes or names it as before
            parts = compiled_functions(self.motion, self.measurement, ("jit_f",), ("jit_h",))
            if parts is not None:
                done = _filter_compiled(parts, self, ys, x0, P0, dt, times)
                if done is not None:
                    return done
        return run_sequence(ys, x0, P0, self.motion.n, self.measurement.m, dt, times,
                            self.predict, self.update)

    def predict(self, g: Gaussian, dt: float = 1.0, t: float = 0.0) -> Gaussian:
        """One prediction (:func:`ukf_predict` with this filter's model and points).

        Parameters
        ----------
        g : Gaussian
            Mean ``(..., n)`` and covariance ``(..., n, n)``.
        dt : float
            Time step.
        t : float
            Time of the predicted state.

        Returns
        -------
        Gaussian
            The prediction, ``(..., n)`` and ``(..., n, n)``.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> ukf = UnscentedKalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1))
        >>> ukf.predict(Gaussian(np.array([0.0, 1.0]), np.eye(2))).mean
        array([1., 1.])
        """
        return ukf_predict(g, self.motion, dt, t, points=self.points,
                           state_mean=self.state_mean, state_residual=self.state_residual)

    def update(self, g: Gaussian, y: ArrayLike) -> tuple[Gaussian, np.ndarray]:
        """One correction and its innovation log-density (:func:`ukf_update`).

        Parameters
        ----------
        g : Gaussian
            The prior: mean ``(..., n)`` and covariance ``(..., n, n)``.
        y : (..., m) array_like
            The measurement; NaN components are missing.

        Returns
        -------
        posterior : Gaussian
            The corrected mean and covariance.
        loglik : (...) ndarray
            The Gaussian log-density of the innovation.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> ukf = UnscentedKalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1, r=1.0))
        >>> post, ll = ukf.update(Gaussian(np.array([0.0, 1.0]), np.eye(2)), [1.0])
        >>> post.mean, round(float(ll), 3)
        (array([0.5, 1. ]), -1.516)
        """
        return _ukf_update(g, y, self.measurement, self.points, None, None,
                           self.state_residual)


_OWN_STEPS = (UnscentedKalmanFilter.predict, UnscentedKalmanFilter.update)


# ---------------------------------------------------------------- the compiled path
_FUSED = """
# depends on: {depends}
import math
import numpy as np
from numba import njit
from vistrack.filters import ukf as _ukf
from vistrack.filters._kernels import chol_factor, keep_state, load_state, observed
from {fmod} import {fname} as f
from {hmod} import {hname} as h

points_one = _ukf._points_one.jit
state_moments_one = _ukf._state_moments_one.jit
update_one = _ukf._update_one.jit


@njit(cache=True, error_model="numpy")
def run(x0, P0, ys, dts, times, fp, hp, Qs, qi, R, angles, Wm, Wc, scale, means, covs,
        pmeans, pcovs, loglik):
    # The UKF over every series, one compiled call, with the kernels of its one-Gaussian
    # steps from Python: sigma points, f or h at each, the moments or the correction. Returns
    # (-1, -1), or the series and step of the first covariance without a Cholesky factor or
    # value not finite, which the caller filters again from Python (a singular covariance's
    # points from its eigendecomposition; a correction that rounding took below zero settled;
    # anything else named).
    B, T = ys.shape[0], ys.shape[1]
    n, m = {n}, {m}  # literal sizes: the loops unroll
    K = 2 * n + 1
    x = np.empty(n)
    P = np.empty((n, n))
    xo = np.empty(n)
    Po = np.empty((n, n))
    L = np.zeros((n, n))
    pts = np.empty((K, n))
    gam = np.empty((K, n))
    z = np.empty((K, m))
    for b in range(B):
        load_state(x0, P0, b, x, P)
        total = 0.0
        for t in range(T):
            if t > 0:
                if points_one(x, P, scale, pts) != 0:
                    return b, t
                for i in range(K):
                    f(pts[i], dts[t], times[t], fp[t], gam[i])
                state_moments_one(gam, Wm, Wc, Qs[qi[t]], x, P)
            if not keep_state(x, P, pmeans, pcovs, b, t):
                return b, t
            if observed(ys[b, t]) > 0:
                if points_one(x, P, scale, pts) != 0:
                    return b, t
                for i in range(K):
                    h(pts[i], hp, z[i])
                    for k in range(m):
                        if not math.isnan(ys[b, t, k]) and not abs(z[i, k]) < np.inf:
                            return b, t
                good, ll = update_one(pts, z, Wm, Wc, R, ys[b, t], angles, x, P, xo, Po)
                if not good or not chol_factor(L, Po, n):
                    return b, t
                total += ll
                for i in range(n):
                    x[i] = xo[i]
                    for k in range(n):
                        P[i, k] = Po[i, k]
            if not keep_state(x, P, means, covs, b, t):
                return b, t
        loglik[b] = total
    return -1, -1
"""


def _fused_kernel(fref: Ref, href: Ref, n: int, m: int) -> Kernel:
    """The compiled filter of these functions and sizes for calls from Python (and for
    compiling it ahead of time, see :mod:`vistrack._prebuilt`), of their modules' current
    source."""
    return _codegen.generated_kernel(
        _FUSED, "vistrack_ukf", f"{__name__}:_fused_kernel({fref!r}, {href!r}, {n!r}, {m!r})",
        (*sorted({fref[0], href[0]}), __name__, _jitmath.__name__, _kernels.__name__),
        fmod=fref[0], fname=fref[1], hmod=href[0], hname=href[1], n=n, m=m)


def _filter_compiled(parts: tuple[Ref, ...], flt: UnscentedKalmanFilter, ys: ArrayLike,
                     x0: ArrayLike, P0: ArrayLike, dt: ArrayLike | None,
                     times: ArrayLike | None) -> FilterResult | None:
    """:meth:`UnscentedKalmanFilter.filter` in one compiled call, or None where the call met
    what it cannot take (filtered again from Python)."""
    mo, me = flt.motion, flt.measurement
    n = mo.n
    try:  # (points whose n + λ is not positive: named by the steps from Python)
        Wm, Wc = flt.points.weights(n)
        scale = float(n + flt.points._lam(n))
    except ValueError:
        return None
    c = compiled_run(mo, me, ys, x0, P0, dt, times)
    if c is None:
        return None
    f, h = parts
    b, _ = _fused_kernel(f, h, n, me.m)(
        *c.inputs, np.ascontiguousarray(Wm, dtype=float), np.ascontiguousarray(Wc, dtype=float),
        scale, *c.outputs)
    return None if b >= 0 else c.result()
