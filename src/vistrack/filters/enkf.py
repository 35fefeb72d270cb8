r"""The ensemble Kalman filter (seed 004: "represents the distribution of the system state using
a collection (an ensemble) of state vectors ... replace the covariance matrix by the sample
covariance from the ensemble").

Prediction moves every member through the dynamics with sampled process noise,
:math:`x_i^- = f(x_i^+) + w_i`, :math:`w_i \sim N(0, Q)`. The correction is the stochastic
(perturbed-observation) EnKF of Burgers, van Leeuwen and Evensen (1998): with the ensemble's
cross-covariance :math:`C = \operatorname{cov}(x^-, h(x^-))` and
:math:`S = \operatorname{cov}(h(x^-)) + R`,

.. math:: K = C S^{-1}, \qquad x_i^+ = x_i^- + K\, r(y + v_i, h(x_i^-)), \quad v_i \sim N(0, R).

The perturbations make the ensemble's covariance match the Kalman posterior in expectation; as
the ensemble grows, the EnKF tends to the Kalman filter on linear models.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Literal, overload

import numpy as np

from .._validate import as_rng
from ._nonlinear import (
    Measurement,
    Motion,
    check_y,
    gain,
    masked_innovation,
    psd_sqrt,
    run_sequence,
)
from .kalman import FilterResult

__all__ = ["Ensemble", "enkf_predict", "enkf_update", "EnsembleKalmanFilter"]


@dataclass(frozen=True)
class Ensemble:
    """A batch of ensembles: ``members (..., N, n)``, N members of state size n."""

    members: np.ndarray

    def __post_init__(self) -> None:
        m = np.asarray(self.members, dtype=np.float64)
        if m.ndim < 2 or m.shape[-2] < 2:
            raise ValueError(f"members must have shape (..., N, n) with N >= 2; got {m.shape}")
        object.__setattr__(self, "members", m)

    @classmethod
    def sample(cls, mean: Any, cov: Any, n_members: int,
               rng: np.random.Generator | int | None = None) -> Ensemble:
        """``n_members`` draws from ``N(mean, cov)`` (a batch: ``mean (..., n)``)."""
        rng = as_rng(rng)
        mean = np.asarray(mean, dtype=float)
        try:
            L = np.linalg.cholesky(np.asarray(cov, dtype=float))
        except np.linalg.LinAlgError:
            raise ValueError("cov must be positive definite to sample an ensemble") from None
        z = rng.standard_normal(mean.shape[:-1] + (int(n_members), mean.shape[-1]))
        return cls(mean[..., None, :] + z @ np.swapaxes(L, -1, -2))

    def moments(self) -> tuple[np.ndarray, np.ndarray]:
        """Sample mean ``(..., n)`` and covariance ``(..., n, n)`` (divisor N - 1)."""
        mean = self.members.mean(-2)
        d = self.members - mean[..., None, :]
        return mean, np.swapaxes(d, -1, -2) @ d / (self.members.shape[-2] - 1)


def _noise(rng, shape, A):
    """Draws of ``N(0, A A')``; none when ``A`` is zero (no noise)."""
    if not np.any(A):
        return np.zeros(shape)
    return rng.standard_normal(shape) @ A.T


def enkf_predict(ens: Ensemble, motion: Any, dt: float = 1.0, t: float = 0.0, *,
                 rng: np.random.Generator | int | None = None) -> Ensemble:
    """Move every member through ``motion`` by ``dt`` and add sampled process noise."""
    mo = motion if isinstance(motion, Motion) else Motion(motion)
    x = np.asarray(mo.f(ens.members, dt, t), dtype=float)
    return Ensemble(x + _noise(as_rng(rng), x.shape, mo.Q_sqrt(dt)))


@overload
def enkf_update(ens: Ensemble, y: Any, measurement: Any, *,
                rng: np.random.Generator | int | None = None, residual: Callable | None = None,
                return_loglik: Literal[False] = ...) -> Ensemble: ...
@overload
def enkf_update(ens: Ensemble, y: Any, measurement: Any, *,
                rng: np.random.Generator | int | None = None, residual: Callable | None = None,
                return_loglik: Literal[True]) -> tuple[Ensemble, np.ndarray]: ...
@overload
def enkf_update(ens: Ensemble, y: Any, measurement: Any, *,
                rng: np.random.Generator | int | None = None, residual: Callable | None = None,
                return_loglik: bool) -> Ensemble | tuple[Ensemble, np.ndarray]: ...
def enkf_update(ens: Ensemble, y: Any, measurement: Any, *,
                rng: np.random.Generator | int | None = None, residual: Callable | None = None,
                return_loglik: bool = False) -> Ensemble | tuple[Ensemble, np.ndarray]:
    """Perturbed-observation update of a batch of ensembles with ``y (..., m)`` (NaN = missing).

    With ``return_loglik``, also returns the Gaussian log-density of the innovation
    ``N(r(y, mean h), S)`` under the ensemble's moments.
    """
    X = ens.members
    N, n = X.shape[-2:]
    me = measurement if isinstance(measurement, Measurement) else Measurement(
        measurement, n, residual)
    y = check_y(y, X.shape[:-2], me.m)
    obs = ~np.isnan(y)
    Z = np.asarray(me.h(X), dtype=float)  # (..., N, m)
    zbar = Z.mean(-2)
    dZ = me.residual(Z, zbar[..., None, :]) * obs[..., None, :]
    dX = X - X.mean(-2)[..., None, :]
    C = np.swapaxes(dX, -1, -2) @ dZ / (N - 1)
    e, S, L, ll = masked_innovation(me.residual(np.where(obs, y, 0.0), zbar),
                                    np.swapaxes(dZ, -1, -2) @ dZ / (N - 1) + me.R, obs)
    K = gain(C, L)
    v = _noise(as_rng(rng), Z.shape, psd_sqrt(me.R))
    innov = me.residual(np.where(obs, y, 0.0)[..., None, :] + v, Z) * obs[..., None, :]
    out = Ensemble(X + innov @ np.swapaxes(K, -1, -2))
    return (out, ll) if return_loglik else out


class EnsembleKalmanFilter:
    """The stochastic EnKF over a sequence.

    Parameters
    ----------
    motion, measurement
        Nonlinear or linear models.
    n_members : int
        Ensemble size.
    rng : numpy Generator, int seed or None
    residual : callable, optional
        Measurement residual, overriding the model's.

    Notes
    -----
    The result's ``means`` and ``covs`` are the ensemble's sample moments.
    """

    def __init__(self, motion: Any, measurement: Any, n_members: int = 100, *,
                 rng: np.random.Generator | int | None = None, residual: Callable | None = None):
        if int(n_members) != n_members or n_members < 2:
            raise ValueError(f"n_members must be an integer >= 2; got {n_members}")
        self.motion = Motion(motion)
        self.measurement = Measurement(measurement, self.motion.n, residual)
        self.n_members = int(n_members)
        self.rng = as_rng(rng)

    def filter(self, ys: Any, *, x0: Any, P0: Any, dt: Any = 1.0,
               times: Any = None) -> FilterResult:
        """Filter ``ys (T, m)`` or ``(B, T, m)``; the first ensemble is drawn from ``N(x0, P0)``."""
        n = self.motion.n
        ys_arr = np.asarray(ys, dtype=float)
        B = 1 if ys_arr.ndim == 2 else ys_arr.shape[0]
        x0 = np.broadcast_to(np.asarray(x0, dtype=float), (B, n))
        P0 = np.broadcast_to(np.asarray(P0, dtype=float), (B, n, n))
        ens = Ensemble.sample(x0, P0, self.n_members, self.rng)
        return run_sequence(
            ys, None, None, n, self.measurement.m, dt, times,
            lambda e, dt, t: enkf_predict(e, self.motion, dt, t, rng=self.rng),
            lambda e, y: enkf_update(e, y, self.measurement, rng=self.rng, return_loglik=True),
            state=ens,
        )
