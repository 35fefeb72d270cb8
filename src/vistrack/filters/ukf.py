r"""The unscented Kalman filter (seed 004: "propagate just a few sample points ('sigma points')
around the mean exactly, then recover the covariance from them").

Sigma points :math:`\chi_0 = x`, :math:`\chi_{\pm i} = x \pm (\sqrt{(n + \lambda) P})_i`
(columns of the Cholesky factor), with mean weights ``Wm`` and covariance weights ``Wc``:

- :class:`MerweScaledSigmaPoints` (van der Merwe's scaled points, parameters α, β, κ):
  :math:`\lambda = \alpha^2 (n + \kappa) - n`, :math:`W^m_0 = \lambda / (n + \lambda)`,
  :math:`W^c_0 = W^m_0 + 1 - \alpha^2 + \beta`, :math:`W_i = 1 / (2 (n + \lambda))`;
- :class:`JulierSigmaPoints` (Julier and Uhlmann's points, parameter κ): :math:`\lambda = \kappa`.

Prediction: :math:`x^- = \sum W^m_i f(\chi_i)`,
:math:`P^- = \sum W^c_i (f(\chi_i) - x^-)(f(\chi_i) - x^-)^T + Q`. Correction with sigma
points :math:`\gamma_i` drawn afresh from :math:`(x^-, P^-)`, so that they carry ``Q`` too
(on a linear model this makes the UKF the Kalman filter):
:math:`\hat z = \sum W^m_i h(\gamma_i)`, :math:`S = \sum W^c_i r_i r_i^T + R`,
:math:`C = \sum W^c_i (\gamma_i - x^-) r_i^T`, :math:`K = C S^{-1}`,
:math:`x^+ = x^- + K\, r(y, \hat z)`, :math:`P^+ = P^- - K S K^T`, the last evaluated as
:math:`P^- - V V^T` with :math:`V = C L^{-T}`, :math:`S = L L^T`, so that it is symmetric by
construction. ``r`` is the measurement model's residual (angles wrap) and :math:`\hat z` its
mean (circular for angles). These are the equations of FilterPy's ``UnscentedKalmanFilter``,
which the tests check to 1e-8.

References: Julier and Uhlmann (1997), "A new extension of the Kalman filter to nonlinear
systems"; Wan and van der Merwe (2000), "The unscented Kalman filter for nonlinear estimation".
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Literal, overload

import numpy as np
from numba import njit

from ..types import Gaussian
from ._kernels import back_solve, chol_factor, forward_solve
from ._nonlinear import (
    Measurement,
    Motion,
    check_gaussian,
    check_y,
    masked_innovation,
    run_sequence,
    symmetric,
)
from .kalman import FilterResult

__all__ = [
    "MerweScaledSigmaPoints",
    "JulierSigmaPoints",
    "ukf_predict",
    "ukf_update",
    "UnscentedKalmanFilter",
]


def _sqrt(P: np.ndarray, scale: float) -> np.ndarray:
    try:
        return np.linalg.cholesky(scale * P)
    except np.linalg.LinAlgError:
        raise ValueError("g.cov must be positive definite to draw sigma points") from None


# ---------------------------------------------------------------- compiled, one Gaussian
# For one Gaussian (the common case of a track) the sigma-point algebra is a few dozen numpy
# calls on 5x5 matrices, whose overhead is most of the time; these kernels do it in three
# compiled calls a step, with the Kalman kernels' Cholesky factor and triangular solves. The
# model's f and h still run as numpy on all points at once.
@njit(cache=True, error_model="numpy")
def _points_one(x, P, scale, out):
    n = x.shape[0]
    L = np.zeros((n, n))  # (the upper triangle stays zero)
    if not chol_factor(L, scale * P, n):
        return False
    for k in range(n):
        out[0, k] = x[k]
    for i in range(n):
        for k in range(n):
            out[1 + i, k] = x[k] + L[k, i]
            out[1 + n + i, k] = x[k] - L[k, i]
    return True


@njit(cache=True, error_model="numpy")
def _state_moments_one(Y, Wm, Wc, Q, mean, cov):
    K, n = Y.shape
    for k in range(n):
        v = 0.0
        for i in range(K):
            v += Wm[i] * Y[i, k]
        mean[k] = v
    for a in range(n):
        for b in range(a + 1):
            v = Q[a, b]
            for i in range(K):
                v += Wc[i] * (Y[i, a] - mean[a]) * (Y[i, b] - mean[b])
            cov[a, b] = v
            cov[b, a] = v


@njit(cache=True, error_model="numpy")
def _wrap(d):
    return math.pi - ((math.pi - d) % (2.0 * math.pi))


@njit(cache=True, error_model="numpy")
def _update_one(G, Z, Wm, Wc, R, y, angles, x, P, xo, Po):
    """Unscented correction of one Gaussian from its sigma points ``G`` and their
    measurements ``Z`` (the equations of :func:`ukf_update`, angles wrapped and averaged on the
    circle, NaN components of ``y`` missing). Returns ``(ok, loglik)``."""
    K, n = G.shape
    m = Z.shape[1]
    zhat = np.empty(m)
    for k in range(m):
        if angles[k]:
            s, c = 0.0, 0.0
            for i in range(K):
                s += Wm[i] * math.sin(Z[i, k])
                c += Wm[i] * math.cos(Z[i, k])
            zhat[k] = math.atan2(s, c)
        else:
            v = 0.0
            for i in range(K):
                v += Wm[i] * Z[i, k]
            zhat[k] = v
    rz = np.empty((K, m))
    e = np.empty(m)
    nobs = 0
    for k in range(m):
        obs = not math.isnan(y[k])
        nobs += obs
        d = y[k] - zhat[k] if obs else 0.0
        e[k] = _wrap(d) if angles[k] else d
        for i in range(K):
            d = Z[i, k] - zhat[k]
            rz[i, k] = (_wrap(d) if angles[k] else d) if obs else 0.0
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
    w[:, 0] = e
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
        """Sigma points of one Gaussian, compiled: ``(2n + 1, n)``."""
        n = x.shape[0]
        out = np.empty((2 * n + 1, n))
        if not _points_one(x, P, float(n + self._lam(n)), out):
            raise ValueError("g.cov must be positive definite to draw sigma points")
        return out

    def points(self, x: np.ndarray, P: np.ndarray) -> np.ndarray:
        """Sigma points of a batch ``x (..., n)``, ``P (..., n, n)``: ``(..., 2n + 1, n)``."""
        n = x.shape[-1]
        L = _sqrt(P, n + self._lam(n))
        Lt = np.swapaxes(L, -1, -2)  # row i = column i of L
        return np.concatenate([x[..., None, :], x[..., None, :] + Lt, x[..., None, :] - Lt],
                              axis=-2)


class MerweScaledSigmaPoints(_SigmaPoints):
    """Van der Merwe's scaled sigma points: ``2n + 1`` points with parameters α (spread, small
    positive), β (2 is optimal for Gaussians) and κ (usually 0 or 3 - n)."""

    def __init__(self, alpha: float = 1e-3, beta: float = 2.0, kappa: float = 0.0):
        if not alpha > 0:
            raise ValueError(f"alpha must be > 0; got {alpha}")
        self.alpha, self.beta, self.kappa = float(alpha), float(beta), float(kappa)

    def __repr__(self) -> str:
        return f"MerweScaledSigmaPoints(alpha={self.alpha}, beta={self.beta}, kappa={self.kappa})"

    def _lam(self, n: int) -> float:
        lam = self.alpha**2 * (n + self.kappa) - n
        if n + lam <= 0:
            raise ValueError(f"alpha**2 * (n + kappa) must be > 0; got {n + lam} for n={n}")
        return lam

    def weights(self, n: int) -> tuple[np.ndarray, np.ndarray]:
        lam = self._lam(n)
        Wm = np.full(2 * n + 1, 0.5 / (n + lam))
        Wc = Wm.copy()
        Wm[0] = lam / (n + lam)
        Wc[0] = Wm[0] + 1.0 - self.alpha**2 + self.beta
        return Wm, Wc


class JulierSigmaPoints(_SigmaPoints):
    """Julier and Uhlmann's sigma points: ``2n + 1`` points, weight ``κ / (n + κ)`` on the mean."""

    def __init__(self, kappa: float = 0.0):
        self.kappa = float(kappa)

    def __repr__(self) -> str:
        return f"JulierSigmaPoints(kappa={self.kappa})"

    def _lam(self, n: int) -> float:
        if n + self.kappa <= 0:
            raise ValueError(f"n + kappa must be > 0; got {n + self.kappa}")
        return self.kappa

    def weights(self, n: int) -> tuple[np.ndarray, np.ndarray]:
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


def ukf_predict(g: Gaussian, motion: Any, dt: float = 1.0, t: float = 0.0, *,
                points: _SigmaPoints | None = None, state_mean: Callable | None = None,
                state_residual: Callable | None = None) -> Gaussian:
    r"""UKF prediction of a batch of Gaussians ``g`` (mean ``(..., n)``).

    ``points`` defaults to ``MerweScaledSigmaPoints()``. ``state_mean(points, w)`` and
    ``state_residual(a, b)`` override the weighted mean and ``a - b`` for states with angles.

    Examples
    --------
    >>> from vistrack.models import CoordinatedTurn
    >>> g = Gaussian(np.array([0.0, 0.0, 1.0, 0.0, 0.1]), np.eye(5) * 0.01)
    >>> ukf_predict(g, CoordinatedTurn(q=0.1), dt=1.0).mean.round(3)  # EKF: 0.998 0.05 0.995 0.1
    array([0.997, 0.05 , 0.99 , 0.099, 0.1  ])
    """
    g = check_gaussian(g)
    mo = motion if isinstance(motion, Motion) else Motion(motion)
    points = points or MerweScaledSigmaPoints()
    n = g.mean.shape[-1]
    Wm, Wc = points.weights(n)
    if g.mean.ndim == 1 and state_mean is None and state_residual is None:
        gamma = np.asarray(mo.f(points.points_one(g.mean, g.cov), dt, t), dtype=float)
        mean, cov = np.empty(n), np.empty((n, n))
        _state_moments_one(gamma, Wm, Wc, np.asarray(mo.Q(dt), dtype=float), mean, cov)
        return Gaussian(mean, cov)
    chi = points.points(g.mean, g.cov)
    gamma = np.asarray(mo.f(chi, dt, t), dtype=float)
    mean, cov, _ = _transform(gamma, Wm, Wc, state_mean or _wmean, state_residual or _sub)
    return Gaussian(mean, symmetric(cov + mo.Q(dt)))


def _wmean(z: np.ndarray, w: np.ndarray) -> np.ndarray:
    return np.einsum("...km,k->...m", z, w)


def _sub(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a - b


@overload
def ukf_update(g: Gaussian, y: Any, measurement: Any, *, points: _SigmaPoints | None = None,
               residual: Callable | None = None, mean: Callable | None = None,
               state_residual: Callable | None = None,
               return_loglik: Literal[False] = ...) -> Gaussian: ...
@overload
def ukf_update(g: Gaussian, y: Any, measurement: Any, *, points: _SigmaPoints | None = None,
               residual: Callable | None = None, mean: Callable | None = None,
               state_residual: Callable | None = None,
               return_loglik: Literal[True]) -> tuple[Gaussian, np.ndarray]: ...
@overload
def ukf_update(g: Gaussian, y: Any, measurement: Any, *, points: _SigmaPoints | None = None,
               residual: Callable | None = None, mean: Callable | None = None,
               state_residual: Callable | None = None,
               return_loglik: bool) -> Gaussian | tuple[Gaussian, np.ndarray]: ...
def ukf_update(g: Gaussian, y: Any, measurement: Any, *, points: _SigmaPoints | None = None,
               residual: Callable | None = None, mean: Callable | None = None,
               state_residual: Callable | None = None,
               return_loglik: bool = False) -> Gaussian | tuple[Gaussian, np.ndarray]:
    r"""UKF correction of a batch of Gaussians ``g`` with ``y (..., m)`` (NaN = missing).

    The sigma points are drawn from ``g``. ``residual(a, b)`` and ``mean(z, w)`` override the
    measurement model's (angles wrap; circular means).
    """
    g = check_gaussian(g)
    n = g.mean.shape[-1]
    me = measurement if isinstance(measurement, Measurement) else Measurement(
        measurement, n, residual, mean)
    y = check_y(y, g.mean.shape[:-1], me.m)
    points = points or MerweScaledSigmaPoints()
    Wm, Wc = points.weights(n)
    if g.mean.ndim == 1 and me.standard and state_residual is None:
        gamma = points.points_one(g.mean, g.cov)
        xo, Po = np.empty(n), np.empty((n, n))
        ok, ll1 = _update_one(gamma, np.asarray(me.h(gamma), dtype=float), Wm, Wc, me.R, y,
                              me.angle_mask, g.mean, g.cov, xo, Po)
        if not ok:
            raise ValueError("the innovation covariance is not positive definite; R must be "
                             "positive definite on the observed components")
        out = Gaussian(xo, Po)
        return (out, np.asarray(ll1)) if return_loglik else out
    gamma = points.points(g.mean, g.cov)
    obs = ~np.isnan(y)
    zs = np.asarray(me.h(gamma), dtype=float)
    zhat, Pzz, rz = _transform(zs, Wm, Wc, me.mean, me.residual)
    rz = rz * obs[..., None, :]  # missing components: no cross-covariance
    dx = (state_residual or _sub)(gamma, g.mean[..., None, :])
    C = np.einsum("...ki,k,...kj->...ij", dx, Wc, rz)
    e = me.residual(np.where(obs, y, 0.0), zhat)
    e, S, L, ll = masked_innovation(e, Pzz + me.R, obs)
    Vt = np.linalg.solve(L, np.swapaxes(C, -1, -2))  # (C L^-T)'
    K = np.swapaxes(np.linalg.solve(np.swapaxes(L, -1, -2), Vt), -1, -2)  # C S^-1 = V L^-1
    out = Gaussian(g.mean + (K @ e[..., None])[..., 0],
                   symmetric(g.cov - np.swapaxes(Vt, -1, -2) @ Vt))
    return (out, ll) if return_loglik else out


class UnscentedKalmanFilter:
    """The UKF over a sequence, from a motion and a measurement model.

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
    """

    def __init__(self, motion: Any, measurement: Any, *, points: _SigmaPoints | None = None,
                 residual: Callable | None = None, mean: Callable | None = None,
                 state_residual: Callable | None = None, state_mean: Callable | None = None):
        self.motion = Motion(motion)
        self.measurement = Measurement(measurement, self.motion.n, residual, mean)
        self.points = points or MerweScaledSigmaPoints()
        self.state_residual, self.state_mean = state_residual, state_mean

    def filter(self, ys: Any, *, x0: Any, P0: Any, dt: Any = 1.0,
               times: Any = None) -> FilterResult:
        """Filter ``ys (T, m)`` or ``(B, T, m)``; arguments as
        :meth:`ExtendedKalmanFilter.filter <vistrack.filters.ExtendedKalmanFilter.filter>`."""
        return run_sequence(ys, x0, P0, self.motion.n, self.measurement.m, dt, times,
                            self.predict, self.update)

    def predict(self, g: Gaussian, dt: float = 1.0, t: float = 0.0) -> Gaussian:
        """One prediction (:func:`ukf_predict` with this filter's model and points)."""
        return ukf_predict(g, self.motion, dt, t, points=self.points,
                           state_mean=self.state_mean, state_residual=self.state_residual)

    def update(self, g: Gaussian, y: Any) -> tuple[Gaussian, np.ndarray]:
        """One correction and its innovation log-density (:func:`ukf_update`)."""
        return ukf_update(g, y, self.measurement, points=self.points,
                          state_residual=self.state_residual, return_loglik=True)
