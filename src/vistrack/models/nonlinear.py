r"""Nonlinear motion and measurement models, for the EKF, the UKF, ensemble and particle filters.

A nonlinear motion model gives the mean transition and its Jacobian,

.. math:: x_t = f(x_{t-1}, \Delta t, t) + w_t, \quad w_t \sim N(0, Q(\Delta t)),
   \qquad G_t = \partial f / \partial x \,|_{x_{t-1}},

and a nonlinear measurement model

.. math:: y_t = h(x_t) + v_t, \quad v_t \sim N(0, R), \qquad H_t = \partial h / \partial x,

the seeds' EKF (seed 004, "Extended Kalman Filter": Jacobians ``G`` and ``H`` at the current
estimate). Every function takes a batch ``x (..., n)``. ``t`` is the time of the predicted state
(the step index when ``dt = 1``); only time-varying models use it.

Measurement models also give ``residual(a, b)`` (``a - b`` with angles wrapped to ``(-π, π]``)
and ``mean(z, w)`` (a weighted mean with a circular mean for angles), which the UKF uses so that
bearings near ±π average correctly.

User models: :class:`NonlinearMotion` and :class:`NonlinearMeasurement` wrap plain functions; a
missing Jacobian falls back to :func:`numerical_jacobian` (central differences).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit

from .._validate import as_float_array, check_matrix_stack, check_psd
from .motion import _as_dt, _check_q

__all__ = [
    "AngleAwareMeasurement",
    "CoordinatedTurn",
    "RangeBearing",
    "GrowthMotion",
    "GrowthMeasurement",
    "growth_model",
    "NonlinearMotion",
    "NonlinearMeasurement",
    "numerical_jacobian",
    "wrap_angle",
]


def wrap_angle(a: np.ndarray) -> np.ndarray:
    """Angles wrapped to ``(-π, π]``."""
    return np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi)


def numerical_jacobian(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray,
                       eps: float = 1e-6) -> np.ndarray:
    r"""Central-difference Jacobian of ``fun`` at a batch ``x (..., n)``: ``(..., k, n)``.

    The step for entry ``i`` is ``eps * max(1, |x_i|)``; the error is O(step²) for smooth
    ``fun``. ``fun`` must accept a batch ``(..., n)`` and return ``(..., k)``.

    Examples
    --------
    >>> numerical_jacobian(lambda x: x**2, np.array([3.0])).round(6)
    array([[6.]])
    """
    x = np.asarray(x, dtype=float)
    n = x.shape[-1]
    h = eps * np.maximum(1.0, np.abs(x))  # (..., n)
    eye = np.eye(n)
    # all 2n evaluations in one batched call: (2n, ..., n)
    steps = eye.reshape((n,) + (1,) * (x.ndim - 1) + (n,)) * h  # (n, ..., n)
    pts = np.concatenate([x + steps, x - steps], axis=0)
    vals = np.asarray(fun(pts), dtype=float)
    diff = (vals[:n] - vals[n:]) / (2.0 * np.moveaxis(h, -1, 0)[..., None])  # (n, ..., k)
    return np.moveaxis(diff, 0, -1)


class NonlinearMotion:
    r"""A user-given motion model ``x_t = f(x, dt, t) + N(0, Q(dt))``.

    Parameters
    ----------
    f : callable ``f(x, dt, t)`` on a batch ``x (..., n)``
    Q : ``(n, n)`` array, or a callable ``Q(dt)``
    ndim_state : int
    jacobian : callable ``jacobian(x, dt, t) -> (..., n, n)``, optional
        Defaults to central differences of ``f``.
    """

    def __init__(self, f: Callable, Q: np.ndarray | Callable, ndim_state: int,
                 jacobian: Callable | None = None):
        if not callable(f):
            raise TypeError(f"f must be callable; got {type(f).__name__}")
        self.ndim_state = int(ndim_state)
        if callable(Q):
            self._Q = Q
        else:
            Qa = check_matrix_stack(Q, "Q", self.ndim_state, self.ndim_state)[0]
            check_psd(Qa, "Q")
            self._Q = lambda dt: Qa.copy()
        self._f = f
        self._jac = jacobian

    def __repr__(self) -> str:
        return f"NonlinearMotion(ndim_state={self.ndim_state})"

    def f(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        return self._f(x, dt, t)

    def jacobian(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        if self._jac is not None:
            return self._jac(x, dt, t)
        return numerical_jacobian(lambda z: self._f(z, dt, t), x)

    def Q(self, dt: float = 1.0) -> np.ndarray:
        return np.asarray(self._Q(dt), dtype=float)


class AngleAwareMeasurement:
    """The base of the nonlinear measurement models: ``R()``, ``residual(a, b)`` (differences,
    angles wrapped to ``(-π, π]``) and ``mean(z, w)`` (weighted sums, circular for angles) of a
    model with ``_R`` and ``angles``. The filters' compiled one-Gaussian kernels reproduce
    these two, so a model that keeps them (does not override them) takes the fast path."""

    _R: np.ndarray
    angles: tuple = ()

    def R(self) -> np.ndarray:
        return self._R.copy()

    def residual(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        return _residual(a, b, self.angles)

    def mean(self, z: np.ndarray, w: np.ndarray) -> np.ndarray:
        return _weighted_mean(z, w, self.angles)


class NonlinearMeasurement(AngleAwareMeasurement):
    r"""A user-given measurement model ``y = h(x) + N(0, R)``.

    Parameters
    ----------
    h : callable on a batch ``x (..., n)``, returning ``(..., m)``
    R : ``(m, m)`` array
    ndim_state : int
    jacobian : callable ``jacobian(x) -> (..., m, n)``, optional; central differences if absent
    angles : sequence of int, optional
        Components of ``y`` that are angles (in radians): their residuals are wrapped to
        ``(-π, π]`` and their means are circular.
    """

    def __init__(self, h: Callable, R: np.ndarray, ndim_state: int,
                 jacobian: Callable | None = None, angles: tuple[int, ...] = ()):
        if not callable(h):
            raise TypeError(f"h must be callable; got {type(h).__name__}")
        R_arr = as_float_array(R, "R", ndim=(2,))
        m = R_arr.shape[0]
        R_arr = check_matrix_stack(R_arr, "R", m, m)[0]
        check_psd(R_arr, "R", strict=True)
        self.ndim_meas, self.ndim_state = m, int(ndim_state)
        self._h, self._jac, self._R = h, jacobian, R_arr
        self.angles = tuple(int(a) for a in angles)
        for a in self.angles:
            if not 0 <= a < m:
                raise ValueError(f"angles must index components 0..{m - 1}; got {a}")

    def __repr__(self) -> str:
        return f"NonlinearMeasurement(ndim_meas={self.ndim_meas}, ndim_state={self.ndim_state})"

    def h(self, x: np.ndarray) -> np.ndarray:
        return self._h(x)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        if self._jac is not None:
            return self._jac(x)
        return numerical_jacobian(self._h, x)



def _residual(a, b, angles):
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if angles:
        d = d.copy()
        for k in angles:
            d[..., k] = wrap_angle(d[..., k])
    return d


def _weighted_mean(z, w, angles):
    """Weighted mean over axis -2 of ``z (..., N, m)`` with weights ``w (N,)`` (summing to
    one); angle components use the circular mean ``atan2(Σ w sin, Σ w cos)``."""
    out = np.einsum("...km,k->...m", z, w)
    for k in angles:
        out[..., k] = np.arctan2(np.einsum("...k,k->...", np.sin(z[..., k]), w),
                                 np.einsum("...k,k->...", np.cos(z[..., k]), w))
    return out


# ---------------------------------------------------------------- compiled one-state functions
# ``f(x (n,), dt, t, params, out (n,))`` and ``h(x (n,), params, out (m,))`` for one state: the
# particle filter's compiled path calls them per particle. Models expose them as ``jit_f`` /
# ``jit_h``, with ``jit_params``: for motion, ``jit_params(dts (T,), times (T,)) -> (T, p)``,
# each step's parameters at once; for measurement, ``jit_params() -> (p,)``. User models may
# provide their own, defined at module level.
@njit(cache=True, error_model="numpy", inline="always")
def _ct_f(x, dt, t, params, out):
    w = x[4]
    a = w * dt
    sa, ca = math.sin(a), math.cos(a)
    if abs(a) < 1e-4:
        s, c = dt * (1 - a * a / 6), dt * (a / 2 - a**3 / 24)
    else:
        s, c = sa / w, (1 - ca) / w
    out[0] = x[0] + s * x[2] - c * x[3]
    out[1] = x[1] + c * x[2] + s * x[3]
    out[2] = ca * x[2] - sa * x[3]
    out[3] = sa * x[2] + ca * x[3]
    out[4] = w


@njit(cache=True, error_model="numpy", inline="always")
def _range_bearing_h(x, params, out):
    dx, dy = x[0] - params[0], x[1] - params[1]
    out[0] = math.sqrt(dx * dx + dy * dy)
    out[1] = math.atan2(dy, dx)


@njit(cache=True, error_model="numpy", inline="always")
def _growth_f(x, dt, t, params, out):
    v = x[0]
    out[0] = v / 2 + 25 * v / (1 + v * v) + params[0]  # params[0] = 8 cos(1.2 t), once a step


@njit(cache=True, error_model="numpy", inline="always")
def _square_h(x, params, out):
    out[0] = x[0] * x[0] / 20


_NO_PARAMS = np.zeros(0)


class CoordinatedTurn:
    r"""The coordinated-turn model in 2-D: constant speed, constant turn rate ``ω``.

    State ``[x, y, vx, vy, ω]`` (derivative-major, like the kinematic models). Over ``dt`` the
    velocity turns by ``ω dt``:

    .. math::
        p' = p + \begin{bmatrix} \frac{\sin ωΔ}{ω} & -\frac{1 - \cos ωΔ}{ω} \\
                                 \frac{1 - \cos ωΔ}{ω} & \frac{\sin ωΔ}{ω} \end{bmatrix} v,
        \qquad v' = \begin{bmatrix} \cos ωΔ & -\sin ωΔ \\ \sin ωΔ & \cos ωΔ \end{bmatrix} v,
        \qquad ω' = ω,

    with the limit ``ω → 0`` (constant velocity) taken by series. Process noise: white
    acceleration of spectral density ``q`` on position and velocity (as
    :class:`~vistrack.models.ConstantVelocity`), and a random walk of density ``q_turn`` on
    ``ω``. Reference: Bar-Shalom, Li and Kirubarajan, *Estimation with Applications to Tracking
    and Navigation* (2001), §11.7.

    Examples
    --------
    >>> ct = CoordinatedTurn(q=0.1, q_turn=0.01)
    >>> ct.f(np.array([0.0, 0.0, 1.0, 0.0, np.pi / 2]), dt=1.0).round(3)
    array([0.637, 0.637, 0.   , 1.   , 1.571])
    """

    ndim_state = 5
    jit_f = staticmethod(_ct_f)

    def jit_params(self, dt: np.ndarray, t: np.ndarray) -> np.ndarray:
        return np.zeros((len(t), 0))

    def __init__(self, q: float = 1.0, q_turn: float = 0.01):
        self.q = _check_q(q)
        self.q_turn = _check_q(q_turn)

    def __repr__(self) -> str:
        return f"CoordinatedTurn(q={self.q}, q_turn={self.q_turn})"

    @staticmethod
    def _coeffs(w, dt, derivatives=True):
        """``s = sin(wΔ)/w``, ``c = (1 - cos wΔ)/w`` and (if asked) their derivatives in
        ``w``, with the series near ``w = 0``."""
        a = w * dt
        small = np.abs(a) < 1e-4
        safe = np.where(small, 1.0, w)
        sa, ca = np.sin(a), np.cos(a)
        s = np.where(small, dt * (1 - a * a / 6), sa / safe)
        c = np.where(small, dt * (a / 2 - a**3 / 24), (1 - ca) / safe)
        if not derivatives:
            return sa, ca, s, c, None, None
        ds = np.where(small, dt * dt * (-a / 3 + a**3 / 30), (dt * ca - sa / safe) / safe)
        dc = np.where(small, dt * dt * (0.5 - a * a / 8), (dt * sa - (1 - ca) / safe) / safe)
        return sa, ca, s, c, ds, dc

    def f(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        px, py, vx, vy, w = np.moveaxis(x, -1, 0)
        sa, ca, s, c, _, _ = self._coeffs(w, dt, derivatives=False)
        return np.stack([px + s * vx - c * vy, py + c * vx + s * vy,
                         ca * vx - sa * vy, sa * vx + ca * vy, w], axis=-1)

    def jacobian(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        _, _, vx, vy, w = np.moveaxis(x, -1, 0)
        sa, ca, s, c, ds, dc = self._coeffs(w, dt)
        J = np.zeros(x.shape[:-1] + (5, 5))
        J[..., 0, 0] = J[..., 1, 1] = J[..., 4, 4] = 1.0
        J[..., 0, 2], J[..., 0, 3], J[..., 0, 4] = s, -c, ds * vx - dc * vy
        J[..., 1, 2], J[..., 1, 3], J[..., 1, 4] = c, s, dc * vx + ds * vy
        J[..., 2, 2], J[..., 2, 3], J[..., 2, 4] = ca, -sa, -dt * (sa * vx + ca * vy)
        J[..., 3, 2], J[..., 3, 3], J[..., 3, 4] = sa, ca, dt * (ca * vx - sa * vy)
        return J

    def Q(self, dt: float = 1.0) -> np.ndarray:
        d = float(_as_dt(dt))
        Q = np.zeros((5, 5))
        for i in range(2):
            Q[i, i] = self.q * d**3 / 3
            Q[i, i + 2] = Q[i + 2, i] = self.q * d**2 / 2
            Q[i + 2, i + 2] = self.q * d
        Q[4, 4] = self.q_turn * d
        return Q


class RangeBearing(AngleAwareMeasurement):
    r"""Range and bearing of a 2-D position from a sensor at ``sensor = (sx, sy)``.

    .. math:: h(x) = \left[\sqrt{(x - s_x)^2 + (y - s_y)^2},\;
                          \operatorname{atan2}(y - s_y, x - s_x)\right]

    The position is the first two state entries (``[x, y, ...]``). The bearing is an angle:
    residuals wrap to ``(-π, π]`` and means are circular.

    Parameters
    ----------
    r_range, r_bearing : float
        Measurement noise variances (range² and rad²).
    sensor : (2,) array
    ndim_state : int
        Size of the state (at least 2).

    Examples
    --------
    >>> RangeBearing(ndim_state=4).h(np.array([3.0, 4.0, 0.0, 0.0])).round(4)
    array([5.    , 0.9273])
    """

    angles = (1,)
    ndim_meas = 2
    jit_h = staticmethod(_range_bearing_h)

    def jit_params(self) -> np.ndarray:
        return self.sensor

    def __init__(self, r_range: float = 1.0, r_bearing: float = 1e-4, sensor=(0.0, 0.0),
                 ndim_state: int = 4):
        for name, v in (("r_range", r_range), ("r_bearing", r_bearing)):
            if not np.isfinite(v) or v <= 0:
                raise ValueError(f"{name} must be a finite variance > 0; got {v}")
        self._R = np.diag([float(r_range), float(r_bearing)])
        self.sensor = as_float_array(sensor, "sensor", ndim=(1,))
        if self.sensor.shape != (2,):
            raise ValueError(f"sensor must have shape (2,); got {self.sensor.shape}")
        if int(ndim_state) < 2:
            raise ValueError(f"ndim_state must be at least 2; got {ndim_state}")
        self.ndim_state = int(ndim_state)

    def __repr__(self) -> str:
        return f"RangeBearing(sensor={self.sensor.tolist()}, ndim_state={self.ndim_state})"

    def h(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        dx, dy = x[..., 0] - self.sensor[0], x[..., 1] - self.sensor[1]
        return np.stack([np.hypot(dx, dy), np.arctan2(dy, dx)], axis=-1)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        dx, dy = x[..., 0] - self.sensor[0], x[..., 1] - self.sensor[1]
        r2 = dx * dx + dy * dy
        r = np.sqrt(r2)
        J = np.zeros(x.shape[:-1] + (2, self.ndim_state))
        J[..., 0, 0], J[..., 0, 1] = dx / r, dy / r
        J[..., 1, 0], J[..., 1, 1] = -dy / r2, dx / r2
        return J



class GrowthMotion:
    r"""The univariate nonlinear growth model, the classic particle-filter benchmark:

    .. math:: x_t = \frac{x_{t-1}}{2} + \frac{25 x_{t-1}}{1 + x_{t-1}^2} + 8 \cos(1.2\, t) + w_t,
       \qquad w_t \sim N(0, q)

    with ``t`` the step index (``q = 10`` in the literature). Reference: Gordon, Salmond and
    Smith (1993), "Novel approach to nonlinear/non-Gaussian Bayesian state estimation";
    Kitagawa (1996).
    """

    ndim_state = 1
    jit_f = staticmethod(_growth_f)

    def jit_params(self, dt: np.ndarray, t: np.ndarray) -> np.ndarray:
        return 8 * np.cos(1.2 * np.asarray(t, dtype=float))[:, None]

    def __init__(self, q: float = 10.0):
        self.q = _check_q(q)

    def __repr__(self) -> str:
        return f"GrowthMotion(q={self.q})"

    def f(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        return x / 2 + 25 * x / (1 + x * x) + 8 * np.cos(1.2 * np.asarray(t))[..., None]

    def jacobian(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        x = np.asarray(x, dtype=float)
        return (0.5 + 25 * (1 - x * x) / (1 + x * x) ** 2)[..., None]

    def Q(self, dt: float = 1.0) -> np.ndarray:
        return np.array([[self.q]])


class GrowthMeasurement(AngleAwareMeasurement):
    r"""The growth model's measurement ``y_t = x_t^2 / 20 + v_t``, ``v_t ~ N(0, r)`` (``r = 1``
    in the literature). Its sign ambiguity makes the posterior bimodal."""

    ndim_meas, ndim_state, angles = 1, 1, ()
    jit_h = staticmethod(_square_h)

    def jit_params(self) -> np.ndarray:
        return _NO_PARAMS

    def __init__(self, r: float = 1.0):
        if not np.isfinite(r) or r <= 0:
            raise ValueError(f"r must be a finite variance > 0; got {r}")
        self._R = np.array([[float(r)]])

    def __repr__(self) -> str:
        return f"GrowthMeasurement(r={self._R[0, 0]})"

    def h(self, x: np.ndarray) -> np.ndarray:
        return np.asarray(x, dtype=float) ** 2 / 20

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        return (np.asarray(x, dtype=float) / 10)[..., None]



def growth_model(q: float = 10.0, r: float = 1.0) -> tuple[GrowthMotion, GrowthMeasurement]:
    """The growth model's motion and measurement, with the literature's ``q = 10``, ``r = 1``.

    Examples
    --------
    >>> motion, meas = growth_model()
    >>> float(motion.f(np.array([1.0]), t=0.0)[0]), float(meas.h(np.array([2.0]))[0])
    (21.0, 0.2)
    """
    return GrowthMotion(q), GrowthMeasurement(r)
