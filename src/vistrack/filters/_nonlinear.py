"""What the EKF, UKF and ensemble KF share: model adapters, the masked Gaussian correction, and
the loop over a sequence. Private; the public functions are in ekf.py, ukf.py and enkf.py."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from .._validate import as_float_array
from ..models.nonlinear import AngleAwareMeasurement
from ..types import Gaussian
from .kalman import FilterResult, _readonly


def psd_sqrt(S: np.ndarray) -> np.ndarray:
    """A square root ``A`` with ``A A' = S`` for a stack of PSD matrices (singular allowed:
    process noise often acts on some states only), from the eigendecomposition."""
    w, V = np.linalg.eigh(S)
    return V * np.sqrt(np.clip(w, 0.0, None))[..., None, :]


class Motion:
    """A motion model seen through ``f(x, dt, t)``, ``jacobian(x, dt, t)`` and ``Q(dt)``.

    Linear models (with ``F(dt)``) and nonlinear ones (with ``f`` and ``jacobian``) both fit.
    """

    def __init__(self, model: Any):
        self.model = model
        self.n = int(getattr(model, "ndim_state", 0))
        self.linear = hasattr(model, "F") and not hasattr(model, "jacobian")
        if not (self.linear or (callable(getattr(model, "f", None))
                                and callable(getattr(model, "jacobian", None)))):
            raise TypeError(
                f"motion must be a motion model with F(dt) and Q(dt), or f(x, dt, t), "
                f"jacobian(x, dt, t) and Q(dt); got {type(model).__name__}"
            )
        if self.n < 1:
            raise TypeError(f"motion must have ndim_state >= 1; got {type(model).__name__}")
        self._Q: dict = {}
        self._Q_sqrt: dict = {}

    def f(self, x: np.ndarray, dt: float, t: float) -> np.ndarray:
        if self.linear:
            return x @ self.model.F(dt).T
        return self.model.f(x, dt, t)

    def jacobian(self, x: np.ndarray, dt: float, t: float) -> np.ndarray:
        if self.linear:
            return np.broadcast_to(self.model.F(dt), x.shape + (self.n,))
        return self.model.jacobian(x, dt, t)

    def Q(self, dt: float) -> np.ndarray:
        """``Q(dt)``, computed once per distinct ``dt`` (models are immutable)."""
        Q = self._Q.get(dt)
        if Q is None:
            Q = self._Q[dt] = np.asarray(self.model.Q(dt), dtype=float)
        return Q

    def Q_sqrt(self, dt: float) -> np.ndarray:
        """:func:`psd_sqrt` of ``Q(dt)``, once per distinct ``dt``: noise = eps @ Q_sqrt.T."""
        A = self._Q_sqrt.get(dt)
        if A is None:
            A = self._Q_sqrt[dt] = np.ascontiguousarray(psd_sqrt(self.Q(dt)))
        return A


def _plain_residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a - b


def _plain_mean(z: np.ndarray, w: np.ndarray) -> np.ndarray:
    return np.einsum("...km,k->...m", z, w)


class Measurement:
    """A measurement model seen through ``h(x)``, ``jacobian(x)``, ``R()``, ``residual(a, b)``
    and ``mean(z, w)``; linear models (``H``, ``R``) fit too."""

    def __init__(self, model: Any, n: int, residual: Callable | None = None,
                 mean: Callable | None = None):
        self.model = model
        self.linear = hasattr(model, "H") and not hasattr(model, "jacobian")
        if self.linear:
            self.H = np.asarray(model.H(n), dtype=float)
        elif not (callable(getattr(model, "h", None))
                  and callable(getattr(model, "jacobian", None))):
            raise TypeError(
                f"measurement must be a measurement model with H and R, or h(x), jacobian(x) "
                f"and R(); got {type(model).__name__}"
            )
        self.R = np.asarray(model.R(), dtype=float)
        self.m = self.R.shape[-1]
        self.residual = residual or getattr(model, "residual", None) or _plain_residual
        self.mean = mean or getattr(model, "mean", None) or _plain_mean
        # "standard": residuals are differences (angles wrapped) and means weighted sums
        # (circular for angles), which the compiled one-Gaussian kernels reproduce
        own = type(model)
        self.standard = residual is None and mean is None and (
            self.linear
            or (getattr(own, "residual", None) is AngleAwareMeasurement.residual
                and getattr(own, "mean", None) is AngleAwareMeasurement.mean)
            or not (hasattr(model, "residual") or hasattr(model, "mean")))
        self.angle_mask = np.zeros(self.m, dtype=np.bool_)
        self.angle_mask[list(getattr(model, "angles", ()))] = True

    def h(self, x: np.ndarray) -> np.ndarray:
        return x @ self.H.T if self.linear else self.model.h(x)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        if self.linear:
            return np.broadcast_to(self.H, x.shape[:-1] + self.H.shape)
        return self.model.jacobian(x)


def check_y(y: Any, batch: tuple, m: int) -> np.ndarray:
    y = as_float_array(y, "y")
    if y.shape != batch + (m,):
        raise ValueError(f"y must have shape {batch + (m,)} to match g; got {y.shape}")
    return y


def check_gaussian(g: Any) -> Gaussian:
    if not isinstance(g, Gaussian):
        raise TypeError(f"g must be a vistrack.Gaussian; got {type(g).__name__}")
    return g


def step_times(dt: Any, times: Any, T: int) -> tuple[np.ndarray, np.ndarray]:
    """``dt`` (a scalar or ``(T,)``, ``dt[t]`` the step from ``t-1`` to ``t``) as ``(T,)``, and
    the time of each step: ``times``, by default the cumulative ``dt`` from 0."""
    d = as_float_array(dt, "dt", ndim=(0, 1))
    if d.ndim == 1 and d.shape != (T,):
        raise ValueError(f"dt must be a scalar or have shape ({T},); got {d.shape}")
    dts = np.broadcast_to(d, (T,))
    if times is None:
        return dts, np.concatenate([[0.0], np.cumsum(dts[1:])])
    times = as_float_array(times, "times", ndim=(1,))
    if times.shape != (T,):
        raise ValueError(f"times must have shape ({T},); got {times.shape}")
    return dts, times


def run_sequence(ys: Any, x0: Any, P0: Any, n: int, m: int, dt: Any, times: Any,
                 predict: Callable, update: Callable, state: Any = None) -> FilterResult:
    """Filter ``ys (T, m)`` or ``(B, T, m)`` with ``predict(state, dt, t)`` and
    ``update(state, y) -> (state, loglik)``, where ``state`` starts as ``Gaussian(x0, P0)`` (or
    the given ``state``) and ``moments(state) -> (mean, cov)`` is ``state.mean, state.cov``.

    ``dt`` is a scalar or ``(T,)`` (``dt[t]`` is the step from ``t-1`` to ``t``); ``times``
    defaults to the cumulative sum of ``dt`` with ``times[0] = 0``."""
    ys = as_float_array(ys, "ys", ndim=(2, 3))
    single = ys.ndim == 2
    if single:
        ys = ys[None]
    B, T, mm = ys.shape
    if mm != m:
        raise ValueError(f"ys must have {m} measurement components (last axis); got {mm}")
    dts, times = step_times(dt, times, T)
    if state is None:
        x0 = as_float_array(x0, "x0", ndim=(1, 2))
        P0 = as_float_array(P0, "P0", ndim=(2, 3))
        if x0.shape[-1] != n or P0.shape[-2:] != (n, n):
            raise ValueError(f"x0 and P0 must have shapes (…, {n}) and (…, {n}, {n}); "
                             f"got {x0.shape} and {P0.shape}")
        if B == 1 and x0.ndim == 1 and P0.ndim == 2:
            # one series: the state is one Gaussian, which runs the compiled one-Gaussian paths
            state = Gaussian(x0.copy(), P0.copy())
            ys = ys[0]
        else:
            state = Gaussian(np.broadcast_to(x0, (B, n)).copy(),
                             np.broadcast_to(P0, (B, n, n)).copy())
    means = np.empty((B, T, n))
    covs = np.empty((B, T, n, n))
    pmeans = np.empty((B, T, n))
    pcovs = np.empty((B, T, n, n))
    loglik = np.zeros(B)
    for t in range(T):
        if t > 0:
            state = predict(state, float(dts[t]), float(times[t]))
        pm, pc = _moments(state)
        pmeans[:, t], pcovs[:, t] = pm, pc
        y = ys[..., t, :]
        if np.isnan(y).all():
            mean, cov = pm, pc
        else:
            state, ll = update(state, y)
            loglik += ll
            mean, cov = _moments(state)
        means[:, t], covs[:, t] = mean, cov
    last = Gaussian(means[:, -1], covs[:, -1])
    if single:
        means, covs, pmeans, pcovs = means[0], covs[0], pmeans[0], pcovs[0]
        loglik = loglik[0]
        last = Gaussian(last.mean[0], last.cov[0])
    _readonly(means, covs, pmeans, pcovs)
    return FilterResult(means, covs, pmeans, pcovs, np.asarray(loglik), last, False)


def _moments(state: Any) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(state, Gaussian):
        return state.mean, state.cov
    return state.moments()
