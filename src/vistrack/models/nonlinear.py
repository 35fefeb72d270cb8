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
and ``mean(z, w)`` (a weighted mean with a circular mean for angles), which the ensemble KF uses
so that bearings near ±π average correctly; the UKF averages such a model's angles about its
central sigma point instead (:mod:`vistrack.filters.ukf`).

User models: :class:`NonlinearMotion` and :class:`NonlinearMeasurement` wrap plain functions; a
missing Jacobian falls back to :func:`numerical_jacobian` (central differences).
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .._jit import njit
from .._validate import (
    as_finite,
    as_float_array,
    as_whole,
    check_finite,
    check_matrix_stack,
    check_psd,
)
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
    r"""Angles wrapped to ``(-π, π]``: :math:`\pi - ((\pi - a) \bmod 2\pi)`.

    Parameters
    ----------
    a : array_like
        Angles in radians, any shape.

    Returns
    -------
    ndarray
        The angles plus a multiple of ``2π``, in ``(-π, π]``, shaped like ``a``.

    Examples
    --------
    >>> wrap_angle([np.pi, -np.pi, 1.5 * np.pi, 0.25]).round(4)
    array([ 3.1416,  3.1416, -1.5708,  0.25  ])
    """
    w = np.pi - np.mod(np.pi - np.asarray(a, dtype=float), 2.0 * np.pi)
    # np.mod of a hair below 0 rounds up to 2π: a hair above π came out as -π, outside the
    # range (and a residual at the boundary flipped by 2π)
    return np.where(w <= -np.pi, w + 2.0 * np.pi, w)


def _one_dt(dt: float) -> float:
    """``dt`` as one finite time step >= 0, or an error naming ``dt`` (a NaN or negative step
    moved the states backwards or to NaN without a word)."""
    if type(dt) is float and dt >= 0.0 and dt != math.inf:  # (the filters' own: no array)
        return dt
    d = _as_dt(dt)
    if d.ndim:
        raise ValueError(f"dt must be one value; got shape {d.shape}")
    return float(d)


def _states(x: ArrayLike, n: int, model: str) -> np.ndarray:
    """``x`` as float states ``(..., n)``, or ``ValueError`` naming ``x`` and the model (a
    state of another size was unpacked into numpy's "not enough values to unpack", or taken
    as it came)."""
    a = np.asarray(x, dtype=float)
    if a.ndim == 0 or a.shape[-1] != n:
        raise ValueError(f"x must be {model} states of {n} entr{'y' if n == 1 else 'ies'} "
                         f"(last axis); got shape {a.shape}")
    return a


def numerical_jacobian(fun: Callable[[np.ndarray], np.ndarray], x: np.ndarray,
                       eps: float = 1e-6, angles: tuple = ()) -> np.ndarray:
    r"""Central-difference Jacobian of ``fun`` at a batch of points.

    .. math:: J_{ki} = \frac{f_k(x + h_i e_i) - f_k(x - h_i e_i)}{2 h_i}, \qquad
              h_i = \varepsilon \max(1, |x_i|).

    The error is O(h²) for smooth ``fun``. All ``2 n`` evaluations are made in one call.

    Parameters
    ----------
    fun : callable
        ``fun(x (..., n)) -> (..., k)``, on a batch; it is called once, on points of shape
        ``(2 n, ..., n)``.
    x : (..., n) array_like
        Points at which to differentiate.
    eps : float
        Relative step.
    angles : tuple of int
        The output components that are angles: their differences are wrapped to
        ``(-π, π]`` (a bearing near ±π otherwise jumps by 2π between the two points).

    Returns
    -------
    (..., k, n) ndarray
        The Jacobian at each point.

    Examples
    --------
    >>> numerical_jacobian(lambda x: x**2, np.array([3.0])).round(6)
    array([[6.]])
    >>> f = lambda x: np.stack([x[..., 0] * x[..., 1], np.sin(x[..., 0])], axis=-1)
    >>> numerical_jacobian(f, np.array([2.0, 3.0])).round(6)
    array([[ 3.      ,  2.      ],
           [-0.416147,  0.      ]])
    """
    x = as_float_array(x, "x")
    if x.ndim == 0:  # (an IndexError from x.shape[-1])
        raise ValueError(f"x must be points of shape (..., n), one value as shape (1,); got "
                         f"the scalar {float(x)!r}")
    # (0 divided by 0 into NaN Jacobians, with a RuntimeWarning alone)
    eps = as_finite(eps, "eps", 0.0, above=True, what="step")
    n = x.shape[-1]
    h = eps * np.maximum(1.0, np.abs(x))  # (..., n)
    eye = np.eye(n)
    # all 2n evaluations in one batched call: (2n, ..., n)
    steps = eye.reshape((n,) + (1,) * (x.ndim - 1) + (n,)) * h  # (n, ..., n)
    pts = np.concatenate([x + steps, x - steps], axis=0)
    vals = np.asarray(fun(pts), dtype=float)
    diff = _residual(vals[:n], vals[n:], angles) / (2.0 * np.moveaxis(h, -1, 0)[..., None])
    return np.moveaxis(diff, 0, -1)


class NonlinearMotion:
    r"""A user-given motion model ``x_t = f(x, dt, t) + N(0, Q(dt))``.

    .. math:: x_t = f(x_{t-1}, \Delta t, t) + w_t, \qquad w_t \sim N(0, Q(\Delta t)).

    Parameters
    ----------
    f : callable
        ``f(x, dt, t) -> (..., n)`` on a batch ``x (..., n)``; ``t`` is the time of the
        predicted state.
    Q : (n, n) array_like or callable
        The process-noise covariance (constant, symmetric positive semi-definite), or a
        callable ``Q(dt) -> (n, n)``.
    ndim_state : int
        Size ``n`` of the state.
    jacobian : callable, optional
        ``jacobian(x, dt, t) -> (..., n, n)``; central differences of ``f``
        (:func:`numerical_jacobian`) if absent.

    Raises
    ------
    TypeError
        If ``f`` is not callable.
    ValueError
        If a constant ``Q`` is not ``(n, n)``, finite, symmetric positive semi-definite.

    Examples
    --------
    >>> m = NonlinearMotion(lambda x, dt, t: x + dt * np.sin(x), 0.1 * np.eye(1), ndim_state=1)
    >>> m.f(np.array([0.5]), dt=2.0).round(4), m.jacobian(np.array([0.0])).round(6)
    (array([1.4589]), array([[2.]]))
    """

    def __init__(self, f: Callable, Q: np.ndarray | Callable, ndim_state: int,
                 jacobian: Callable | None = None):
        if not callable(f):
            raise TypeError(f"f must be callable; got {type(f).__name__}")
        # (2.5 was cut to 2, and 0 failed in a reduction, naming nothing)
        self.ndim_state = as_whole(ndim_state, "ndim_state", 1)
        if callable(Q):
            self._Q = Q
        else:
            Qa = check_matrix_stack(Q, "Q", self.ndim_state, self.ndim_state)[0]
            check_psd(Qa, "Q")
            # a bound method, not a lambda: the model (and a filter holding it) pickles; a
            # copy (a view of the caller's array was kept, and Q() gave it changed, unchecked)
            self._Q_const = Qa.copy()
            self._Q = self._constant_Q
        self._f = f
        self._jac = jacobian

    def __repr__(self) -> str:
        return f"NonlinearMotion(ndim_state={self.ndim_state})"

    def _constant_Q(self, dt: float) -> np.ndarray:
        return self._Q_const.copy()

    def f(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        """The mean transition: the given ``f(x, dt, t)``.

        Parameters
        ----------
        x : (..., n) ndarray
            States.
        dt : float
            Time step.
        t : float
            Time of the predicted state.

        Returns
        -------
        (..., n) ndarray
            What ``f`` returns.

        Examples
        --------
        >>> NonlinearMotion(lambda x, dt, t: 2 * x, np.eye(1), 1).f(np.array([[1.0], [3.0]]))
        array([[2.],
               [6.]])
        """
        return self._f(x, dt, t)

    def jacobian(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        """The Jacobian ``∂f/∂x``: the given one, or central differences of ``f``.

        Parameters
        ----------
        x : (..., n) ndarray
            States at which to differentiate.
        dt : float
            Time step.
        t : float
            Time of the predicted state.

        Returns
        -------
        (..., n, n) ndarray
            One Jacobian per state.

        Examples
        --------
        >>> NonlinearMotion(lambda x, dt, t: x**3, np.eye(1), 1).jacobian(np.array([2.0]))
        array([[12.]])
        """
        if self._jac is not None:
            return self._jac(x, dt, t)
        return numerical_jacobian(lambda z: self._f(z, dt, t), x)

    def Q(self, dt: float = 1.0) -> np.ndarray:
        """The process-noise covariance over ``dt``.

        Parameters
        ----------
        dt : float
            Time step (a constant ``Q`` ignores it).

        Returns
        -------
        (n, n) ndarray
            ``Q`` (a copy of the constant one), or the callable's value as float.

        Examples
        --------
        >>> NonlinearMotion(lambda x, dt, t: x, lambda dt: [[dt]], 1).Q(0.5)
        array([[0.5]])
        """
        return np.asarray(self._Q(dt), dtype=float)


class AngleAwareMeasurement:
    r"""The base of the nonlinear measurement models: noise, residuals and means with angles.

    It gives ``R()``, ``residual(a, b)`` (differences, angles wrapped to ``(-π, π]``) and
    ``mean(z, w)`` (weighted sums, circular for angles) of a model with ``_R`` (the noise
    covariance) and ``angles`` (the indices of the components that are angles). The filters'
    compiled one-Gaussian kernels reproduce these two, so a model that keeps them (does not
    override them) takes the fast path.

    Attributes
    ----------
    angles : tuple of int
        The measurement components that are angles (radians); empty by default.

    Examples
    --------
    >>> rb = RangeBearing()
    >>> rb.residual(np.array([1.0, 3.0]), np.array([0.0, -3.0])).round(4)  # across ±π
    array([ 1.    , -0.2832])
    """

    _R: np.ndarray
    angles: tuple = ()

    def R(self) -> np.ndarray:
        """The measurement-noise covariance.

        Returns
        -------
        (m, m) ndarray
            A copy of ``R``.

        Examples
        --------
        >>> RangeBearing(r_range=4.0, r_bearing=0.01).R()
        array([[4.  , 0.  ],
               [0.  , 0.01]])
        """
        return self._R.copy()

    def residual(self, a: np.ndarray, b: np.ndarray) -> np.ndarray:
        """Differences ``a - b`` of measurements, the angle components wrapped to ``(-π, π]``.

        Parameters
        ----------
        a, b : (..., m) array_like
            Measurements (broadcast against each other).

        Returns
        -------
        (..., m) ndarray
            ``a - b``, with :func:`wrap_angle` applied to the components in ``angles``.

        Examples
        --------
        >>> RangeBearing().residual(np.array([5.0, -3.1]), np.array([4.0, 3.1])).round(4)
        array([1.    , 0.0832])
        """
        return _residual(a, b, self.angles)

    def mean(self, z: np.ndarray, w: np.ndarray) -> np.ndarray:
        r"""Weighted mean of measurements, circular for angles.

        .. math::

            \bar z_k = \sum_i w_i z_{ik}, \qquad
            \bar z_a = \operatorname{atan2}\Big(\sum_i w_i \sin z_{ia},
            \sum_i w_i \cos z_{ia}\Big) \text{ for an angle } a.

        Parameters
        ----------
        z : (..., N, m) ndarray
            ``N`` measurements (ensemble members; the UKF's sigma points only for a model
            that overrides this) per batch entry.
        w : (N,) ndarray
            Weights, summing to one (the plain components use them as given, so the
            unscented transform's negative weights are allowed).

        Returns
        -------
        (..., m) ndarray
            The weighted means.

        Examples
        --------
        >>> z = np.array([[10.0, 3.0], [20.0, -3.0]])   # bearings either side of π
        >>> RangeBearing().mean(z, np.array([0.5, 0.5])).round(4)
        array([15.    ,  3.1416])
        """
        return _weighted_mean(z, w, self.angles)


class NonlinearMeasurement(AngleAwareMeasurement):
    r"""A user-given measurement model ``y = h(x) + N(0, R)``.

    .. math:: y_t = h(x_t) + v_t, \qquad v_t \sim N(0, R).

    Parameters
    ----------
    h : callable
        ``h(x) -> (..., m)`` on a batch ``x (..., n)``.
    R : (m, m) array_like
        Measurement-noise covariance, symmetric positive definite.
    ndim_state : int
        Size ``n`` of the state.
    jacobian : callable, optional
        ``jacobian(x) -> (..., m, n)``; central differences of ``h``
        (:func:`numerical_jacobian`) if absent.
    angles : sequence of int, optional
        Components of ``y`` that are angles (in radians): their residuals are wrapped to
        ``(-π, π]`` and their means are circular.

    Raises
    ------
    TypeError
        If ``h`` is not callable.
    ValueError
        If ``R`` is not a finite, symmetric positive definite square matrix, or an angle index
        is outside ``0 .. m-1``.

    Examples
    --------
    A bearing-only sensor at the origin:

    >>> bearing = NonlinearMeasurement(lambda x: np.arctan2(x[..., 1:2], x[..., 0:1]),
    ...                                [[0.01]], ndim_state=2, angles=(0,))
    >>> bearing.h(np.array([0.0, 1.0])).round(4), bearing.jacobian(np.array([1.0, 1.0])).round(6)
    (array([1.5708]), array([[-0.5,  0.5]]))
    """

    def __init__(self, h: Callable, R: np.ndarray, ndim_state: int,
                 jacobian: Callable | None = None, angles: tuple[int, ...] = ()):
        if not callable(h):
            raise TypeError(f"h must be callable; got {type(h).__name__}")
        R_arr = as_float_array(R, "R", ndim=(2,))
        m = R_arr.shape[0]
        R_arr = check_matrix_stack(R_arr, "R", m, m)[0]
        check_psd(R_arr, "R", strict=True)
        self.ndim_meas, self.ndim_state = m, as_whole(ndim_state, "ndim_state", 1)
        self._h, self._jac, self._R = h, jacobian, R_arr.copy()  # (not the caller's array)
        self.angles = tuple(as_whole(a, "angles", 0) for a in angles)  # (0.5 was taken as 0)
        for a in self.angles:
            if not 0 <= a < m:
                raise ValueError(f"angles must index components 0..{m - 1}; got {a}")

    def __repr__(self) -> str:
        return f"NonlinearMeasurement(ndim_meas={self.ndim_meas}, ndim_state={self.ndim_state})"

    def h(self, x: np.ndarray) -> np.ndarray:
        """The mean measurement: the given ``h(x)``.

        Parameters
        ----------
        x : (..., n) ndarray
            States.

        Returns
        -------
        (..., m) ndarray
            What ``h`` returns.

        Examples
        --------
        >>> NonlinearMeasurement(lambda x: x[..., :1] ** 2, [[1.0]], 2).h(np.array([3.0, 0.0]))
        array([9.])
        """
        return self._h(x)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """The Jacobian ``∂h/∂x``: the given one, or central differences of ``h`` (those of
        the ``angles`` wrapped).

        Parameters
        ----------
        x : (..., n) ndarray
            States at which to differentiate.

        Returns
        -------
        (..., m, n) ndarray
            One Jacobian per state.

        Examples
        --------
        >>> meas = NonlinearMeasurement(lambda x: x[..., :1] ** 2, [[1.0]], 2)
        >>> meas.jacobian(np.array([3.0, 0.0])).round(6)
        array([[6., 0.]])
        """
        if self._jac is not None:
            return self._jac(x)
        return numerical_jacobian(self._h, x, angles=self.angles)



def _residual(a, b, angles):
    d = np.asarray(a, dtype=float) - np.asarray(b, dtype=float)
    if angles:
        d = d.copy()
        for k in angles:
            d[..., k] = wrap_angle(d[..., k])
    return d


def _offset_mean(z, w):
    """``Σ_k w_k z_k`` over axis -2 of ``z (..., N, m)`` for weights ``w`` summing to one,
    summed about the first point: ``z_0 + Σ_k w_k (z_k - z_0)``. The unscented transform's
    first weight is about -10^6 (α = 10^-3): summed as it stands (or with ``Σ w``, which
    rounds to 1 ± 10^-10), points 10^8 from the origin lost their last 8 digits to
    cancellation (a mean 8e-3 off on a state of unit variance)."""
    z0 = z[..., 0, :]
    return z0 + np.einsum("...km,k->...m", z - z0[..., None, :], w)


def _weighted_mean(z, w, angles):
    """Weighted mean over axis -2 of ``z (..., N, m)`` with weights ``w (N,)`` (summing to
    one; :func:`_offset_mean`); angle components use the circular mean
    ``atan2(Σ w sin, Σ w cos)``."""
    out = _offset_mean(z, w)
    for k in angles:
        out[..., k] = np.arctan2(np.einsum("...k,k->...", np.sin(z[..., k]), w),
                                 np.einsum("...k,k->...", np.cos(z[..., k]), w))
    return out


# ---------------------------------------------------------------- compiled one-state functions
# ``f(x (n,), dt, t, params, out (n,))`` and ``h(x (n,), params, out (m,))`` for one state: the
# particle filter's compiled path calls them per particle. Models expose them as ``jit_f`` /
# ``jit_h``, with ``jit_params``: for motion, ``jit_params(dts (T,), times (T,)) -> (T, p)``,
# each step's parameters at once; for measurement, ``jit_params() -> (p,)``. Their Jacobians,
# ``jit_jacobian``, take the same arguments and write ``out (n, n)`` or ``(m, n)``: the EKF's
# compiled path calls them once a step. User models may provide their own, defined at module
# level.
@njit(cache=True, error_model="numpy", inline="always")
def _ct_coeffs(w, dt):
    """For one turn rate ``w``: ``sin(wΔ)``, ``cos(wΔ)``, ``s = sin(wΔ)/w``,
    ``c = (1 - cos wΔ)/w`` and their derivatives in ``w``, with the series near ``w = 0``
    (:meth:`CoordinatedTurn._coeffs` for one state, compiled)."""
    a = w * dt
    sa, ca = math.sin(a), math.cos(a)
    if abs(a) < 1e-4:
        return (sa, ca, dt * (1 - a * a / 6), dt * (a / 2 - a**3 / 24),
                dt * dt * (-a / 3 + a**3 / 30), dt * dt * (0.5 - a * a / 8))
    s, c = sa / w, (1 - ca) / w
    return sa, ca, s, c, (dt * ca - s) / w, (dt * sa - c) / w


@njit(cache=True, error_model="numpy", inline="always")
def _ct_f(x, dt, t, params, out):
    """The coordinated turn's ``f`` for one state, compiled: writes ``f(x, dt)`` into ``out``.

    Parameters
    ----------
    x : (5,) ndarray
        The state ``[x, y, vx, vy, ω]``.
    dt : float
        Time step.
    t : float
        Unused.
    params : (0,) ndarray
        Unused (a row of :meth:`CoordinatedTurn.jit_params`).
    out : (5,) ndarray
        Receives the predicted state; nothing is returned.

    Examples
    --------
    >>> out = np.empty(5)
    >>> CoordinatedTurn.jit_f(np.array([0.0, 0.0, 1.0, 0.0, np.pi / 2]), 1.0, 0.0,
    ...                       np.zeros(0), out)
    >>> out.round(3)
    array([0.637, 0.637, 0.   , 1.   , 1.571])
    """
    w = x[4]
    sa, ca, s, c, _, _ = _ct_coeffs(w, dt)
    out[0] = x[0] + s * x[2] - c * x[3]
    out[1] = x[1] + c * x[2] + s * x[3]
    out[2] = ca * x[2] - sa * x[3]
    out[3] = sa * x[2] + ca * x[3]
    out[4] = w


@njit(cache=True, error_model="numpy", inline="always")
def _range_bearing_h(x, params, out):
    """Range-bearing ``h`` for one state, compiled: writes ``[range, bearing]`` into ``out``.

    Parameters
    ----------
    x : (n,) ndarray
        The state; its first two entries are the position.
    params : (2,) ndarray
        The sensor's position (:meth:`RangeBearing.jit_params`).
    out : (2,) ndarray
        Receives ``[range, bearing]``; nothing is returned.

    Examples
    --------
    >>> out = np.empty(2)
    >>> RangeBearing.jit_h(np.array([3.0, 4.0, 0.0, 0.0]), np.zeros(2), out)
    >>> out.round(4)
    array([5.    , 0.9273])
    """
    dx, dy = x[0] - params[0], x[1] - params[1]
    out[0] = math.sqrt(dx * dx + dy * dy)
    b = math.atan2(dy, dx)
    out[1] = b + 2.0 * math.pi if b <= -math.pi else b  # (-π, π], as h: atan2(-0.0, -1) = -π


@njit(cache=True, error_model="numpy", inline="always")
def _growth_f(x, dt, t, params, out):
    """The growth model's ``f`` for one state, compiled: ``x/2 + 25 x/(1 + x²) + params[0]``.

    Parameters
    ----------
    x : (1,) ndarray
        The state.
    dt, t : float
        Unused: the forcing comes in ``params``.
    params : (1,) ndarray
        ``8 cos(1.2 t)``, a row of :meth:`GrowthMotion.jit_params`.
    out : (1,) ndarray
        Receives the predicted state; nothing is returned.

    Examples
    --------
    >>> out = np.empty(1)
    >>> GrowthMotion.jit_f(np.array([1.0]), 1.0, 0.0, np.array([8.0]), out)
    >>> out
    array([21.])
    """
    v = x[0]
    out[0] = v / 2 + 25 * v / (1 + v * v) + params[0]  # params[0] = 8 cos(1.2 t), once a step


@njit(cache=True, error_model="numpy", inline="always")
def _square_h(x, params, out):
    """The growth model's measurement ``x² / 20`` for one state, compiled.

    Parameters
    ----------
    x : (1,) ndarray
        The state.
    params : (0,) ndarray
        Unused (:meth:`GrowthMeasurement.jit_params`).
    out : (1,) ndarray
        Receives ``x² / 20``; nothing is returned.

    Examples
    --------
    >>> out = np.empty(1)
    >>> GrowthMeasurement.jit_h(np.array([2.0]), np.zeros(0), out)
    >>> out
    array([0.2])
    """
    out[0] = x[0] * x[0] / 20


@njit(cache=True, error_model="numpy", inline="always")
def _ct_jacobian(x, dt, t, params, out):
    """The coordinated turn's Jacobian ``∂f/∂x`` at one state, compiled: written into ``out``.

    The same terms as :meth:`CoordinatedTurn.jacobian` (its ``ω → 0`` limit by series).

    Parameters
    ----------
    x : (5,) ndarray
        The state ``[x, y, vx, vy, ω]``.
    dt : float
        Time step.
    t : float
        Unused.
    params : (0,) ndarray
        Unused (a row of :meth:`CoordinatedTurn.jit_params`).
    out : (5, 5) ndarray
        Receives the Jacobian; nothing is returned.

    Examples
    --------
    >>> out = np.empty((5, 5))
    >>> CoordinatedTurn.jit_jacobian(np.array([0.0, 0.0, 1.0, 0.0, 0.0]), 1.0, 0.0,
    ...                              np.zeros(0), out)
    >>> out[:, 2:] + 0.0   # (+ 0.0: no negative zeros)
    array([[1. , 0. , 0. ],
           [0. , 1. , 0.5],
           [1. , 0. , 0. ],
           [0. , 1. , 1. ],
           [0. , 0. , 1. ]])
    """
    vx, vy = x[2], x[3]
    sa, ca, s, c, ds, dc = _ct_coeffs(x[4], dt)
    for i in range(5):
        for k in range(5):
            out[i, k] = 0.0
    out[0, 0] = out[1, 1] = out[4, 4] = 1.0
    out[0, 2], out[0, 3], out[0, 4] = s, -c, ds * vx - dc * vy
    out[1, 2], out[1, 3], out[1, 4] = c, s, dc * vx + ds * vy
    out[2, 2], out[2, 3], out[2, 4] = ca, -sa, -dt * (sa * vx + ca * vy)
    out[3, 2], out[3, 3], out[3, 4] = sa, ca, dt * (ca * vx - sa * vy)


@njit(cache=True, error_model="numpy", inline="always")
def _range_bearing_jacobian(x, params, out):
    """Range-bearing's Jacobian ``∂h/∂x`` at one state, compiled: written into ``out``, as
    :meth:`RangeBearing.jacobian` gives it.

    Parameters
    ----------
    x : (n,) ndarray
        The state; its first two entries are the position.
    params : (2,) ndarray
        The sensor's position (:meth:`RangeBearing.jit_params`).
    out : (2, n) ndarray
        Receives the Jacobian; nothing is returned.

    Examples
    --------
    >>> out = np.empty((2, 4))
    >>> RangeBearing.jit_jacobian(np.array([4.0, 5.0, 0.0, 0.0]), np.array([1.0, 1.0]), out)
    >>> out.round(3)
    array([[ 0.6 ,  0.8 ,  0.  ,  0.  ],
           [-0.16,  0.12,  0.  ,  0.  ]])
    """
    dx, dy = x[0] - params[0], x[1] - params[1]
    r2 = dx * dx + dy * dy
    r = math.sqrt(r2)
    for k in range(out.shape[1]):
        out[0, k] = 0.0
        out[1, k] = 0.0
    out[0, 0], out[0, 1] = dx / r, dy / r
    out[1, 0], out[1, 1] = -dy / r2, dx / r2


@njit(cache=True, error_model="numpy", inline="always")
def _growth_jacobian(x, dt, t, params, out):
    """The growth model's derivative ``1/2 + 25 (1 - x²) / (1 + x²)²`` at one state,
    compiled, into ``out (1, 1)`` (``dt``, ``t``, ``params`` unused: the forcing does not
    depend on the state).

    Examples
    --------
    >>> out = np.empty((1, 1))
    >>> GrowthMotion.jit_jacobian(np.array([1.0]), 1.0, 0.0, np.array([8.0]), out)
    >>> out
    array([[0.5]])
    """
    v = x[0]
    out[0, 0] = 0.5 + 25 * (1 - v * v) / (1 + v * v) ** 2


@njit(cache=True, error_model="numpy", inline="always")
def _square_jacobian(x, params, out):
    """The derivative ``x / 10`` of the growth model's measurement at one state, compiled,
    into ``out (1, 1)``.

    Examples
    --------
    >>> out = np.empty((1, 1))
    >>> GrowthMeasurement.jit_jacobian(np.array([2.0]), np.zeros(0), out)
    >>> out
    array([[0.2]])
    """
    out[0, 0] = x[0] / 10


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
    ``ω``:

    .. math::

        Q = \begin{pmatrix} q\,Δ^3/3\; I_2 & q\,Δ^2/2\; I_2 & 0 \\
                            q\,Δ^2/2\; I_2 & q\,Δ\; I_2 & 0 \\
                            0 & 0 & q_\text{turn} Δ \end{pmatrix}.

    Parameters
    ----------
    q : float
        Spectral density of the white-noise acceleration (finite, >= 0).
    q_turn : float
        Spectral density of the turn rate's random walk (finite, >= 0).

    Attributes
    ----------
    ndim_state : int
        Size of the state: 5.
    jit_f : numba function
        ``f`` for one state, compiled, for the particle filter's compiled path.
    jit_jacobian : numba function
        Its Jacobian at one state, compiled, for the extended Kalman filter's compiled path.

    Raises
    ------
    ValueError
        If ``q`` or ``q_turn`` is negative or not finite.

    References
    ----------
    .. [1] Y. Bar-Shalom, X. R. Li and T. Kirubarajan, *Estimation with Applications to
       Tracking and Navigation*, Wiley, 2001, §11.7.

    Examples
    --------
    >>> ct = CoordinatedTurn(q=0.1, q_turn=0.01)
    >>> ct.f(np.array([0.0, 0.0, 1.0, 0.0, np.pi / 2]), dt=1.0).round(3)
    array([0.637, 0.637, 0.   , 1.   , 1.571])
    """

    ndim_state = 5
    jit_f = staticmethod(_ct_f)
    jit_jacobian = staticmethod(_ct_jacobian)

    def jit_params(self, dt: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The parameters of :attr:`jit_f` for each step: none.

        Parameters
        ----------
        dt, t : (T,) ndarray
            Time steps and times of the steps.

        Returns
        -------
        (T, 0) ndarray
            Empty rows.

        Examples
        --------
        >>> CoordinatedTurn().jit_params(np.ones(3), np.arange(3.0)).shape
        (3, 0)
        """
        return np.zeros((len(t), 0))

    def __init__(self, q: float = 1.0, q_turn: float = 0.01):
        self.q = _check_q(q)
        self.q_turn = _check_q(q_turn, "q_turn")

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
        """Move states by ``dt`` along their turns (see the class), without noise.

        Parameters
        ----------
        x : (..., 5) array_like
            States ``[x, y, vx, vy, ω]``.
        dt : float
            Time step.
        t : float
            Unused (the model does not depend on time).

        Returns
        -------
        (..., 5) ndarray
            The predicted states.

        Examples
        --------
        A quarter turn at unit speed:

        >>> CoordinatedTurn().f(np.array([0.0, 0.0, 1.0, 0.0, np.pi / 2])).round(3)
        array([0.637, 0.637, 0.   , 1.   , 1.571])
        """
        x = _states(x, 5, "CoordinatedTurn")
        px, py, vx, vy, w = np.moveaxis(x, -1, 0)
        sa, ca, s, c, _, _ = self._coeffs(w, _one_dt(dt), derivatives=False)
        return np.stack([px + s * vx - c * vy, py + c * vx + s * vy,
                         ca * vx - sa * vy, sa * vx + ca * vy, w], axis=-1)

    def jacobian(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        """The Jacobian ``∂f/∂x``, analytic, with its ``ω → 0`` limit by series.

        Parameters
        ----------
        x : (..., 5) array_like
            States ``[x, y, vx, vy, ω]``.
        dt : float
            Time step.
        t : float
            Unused.

        Returns
        -------
        (..., 5, 5) ndarray
            One Jacobian per state.

        Examples
        --------
        At ``ω = 0`` it is the constant-velocity transition, plus the turn's first effect:

        >>> J = CoordinatedTurn().jacobian(np.array([0.0, 0.0, 1.0, 0.0, 0.0]))
        >>> J[:, 2:].round(3) + 0.0   # (+ 0.0: no negative zeros)
        array([[1. , 0. , 0. ],
               [0. , 1. , 0.5],
               [1. , 0. , 0. ],
               [0. , 1. , 1. ],
               [0. , 0. , 1. ]])
        """
        x = _states(x, 5, "CoordinatedTurn")
        _, _, vx, vy, w = np.moveaxis(x, -1, 0)
        dt = _one_dt(dt)
        sa, ca, s, c, ds, dc = self._coeffs(w, dt)
        J = np.zeros(x.shape[:-1] + (5, 5))
        J[..., 0, 0] = J[..., 1, 1] = J[..., 4, 4] = 1.0
        J[..., 0, 2], J[..., 0, 3], J[..., 0, 4] = s, -c, ds * vx - dc * vy
        J[..., 1, 2], J[..., 1, 3], J[..., 1, 4] = c, s, dc * vx + ds * vy
        J[..., 2, 2], J[..., 2, 3], J[..., 2, 4] = ca, -sa, -dt * (sa * vx + ca * vy)
        J[..., 3, 2], J[..., 3, 3], J[..., 3, 4] = sa, ca, dt * (ca * vx - sa * vy)
        return J

    def Q(self, dt: float = 1.0) -> np.ndarray:
        """Process-noise covariance over ``dt`` (see the class).

        Parameters
        ----------
        dt : float
            Time step, finite and >= 0 (one value).

        Returns
        -------
        (5, 5) ndarray
            Symmetric positive semi-definite.

        Examples
        --------
        >>> CoordinatedTurn(q=0.1, q_turn=0.01).Q(2.0).diagonal().round(3)
        array([0.267, 0.267, 0.2  , 0.2  , 0.02 ])
        """
        d = _one_dt(dt)
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
        Measurement noise variances (range² and rad²), finite and > 0.
    sensor : (2,) array_like
        Position ``(sx, sy)`` of the sensor.
    ndim_state : int
        Size of the state (at least 2).

    Attributes
    ----------
    angles : tuple of int
        ``(1,)``: the bearing.
    ndim_meas : int
        Size of a measurement: 2.
    sensor : (2,) ndarray
        The sensor's position.
    jit_h : numba function
        ``h`` for one state, compiled, for the particle filter's compiled path.
    jit_jacobian : numba function
        Its Jacobian at one state, compiled, for the extended Kalman filter's compiled path.

    Raises
    ------
    ValueError
        If a variance is not a finite number > 0, ``sensor`` does not have two finite
        entries, or ``ndim_state < 2``.

    Examples
    --------
    >>> RangeBearing(ndim_state=4).h(np.array([3.0, 4.0, 0.0, 0.0])).round(4)
    array([5.    , 0.9273])
    """

    angles = (1,)
    ndim_meas = 2
    jit_h = staticmethod(_range_bearing_h)
    jit_jacobian = staticmethod(_range_bearing_jacobian)

    def jit_params(self) -> np.ndarray:
        """The parameters of :attr:`jit_h`: the sensor's position.

        Returns
        -------
        (2,) ndarray
            ``sensor``.

        Examples
        --------
        >>> RangeBearing(sensor=(1.0, 2.0)).jit_params()
        array([1., 2.])
        """
        return self.sensor

    def __init__(self, r_range: float = 1.0, r_bearing: float = 1e-4, sensor=(0.0, 0.0),
                 ndim_state: int = 4):
        from .._validate import as_finite, as_whole

        self._R = np.diag([as_finite(r_range, "r_range", 0.0, above=True, what="variance"),
                           as_finite(r_bearing, "r_bearing", 0.0, above=True,
                                     what="variance")])
        # a copy: a view of the caller's array was kept, and changed after the check
        self.sensor = as_float_array(sensor, "sensor", ndim=(1,)).copy()
        if self.sensor.shape != (2,):
            raise ValueError(f"sensor must have shape (2,); got {self.sensor.shape}")
        check_finite(self.sensor, "sensor")  # (a NaN gave NaN ranges, without a word)
        self.ndim_state = as_whole(ndim_state, "ndim_state", 2)  # 2.5 was cut to 2

    def __repr__(self) -> str:
        return f"RangeBearing(sensor={self.sensor.tolist()}, ndim_state={self.ndim_state})"

    def h(self, x: np.ndarray) -> np.ndarray:
        """Range and bearing of each state's position from the sensor (see the class).

        Parameters
        ----------
        x : (..., n) array_like
            States whose first two entries are the position.

        Returns
        -------
        (..., 2) ndarray
            ``[range, bearing]``, the bearing in ``(-π, π]``.

        Examples
        --------
        >>> RangeBearing(sensor=(1.0, 1.0)).h(np.array([4.0, 5.0, 0.0, 0.0])).round(4)
        array([5.    , 0.9273])
        """
        x = _states(x, self.ndim_state, "RangeBearing")
        dx, dy = x[..., 0] - self.sensor[0], x[..., 1] - self.sensor[1]
        # (arctan2(-0.0, -1) is -π: the bearing is wrapped into (-π, π] as documented)
        return np.stack([np.hypot(dx, dy), wrap_angle(np.arctan2(dy, dx))], axis=-1)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        r"""The Jacobian ``∂h/∂x``: with :math:`(d_x, d_y)` the position relative to the sensor
        and :math:`r` its length, rows :math:`(d_x, d_y)/r` and :math:`(-d_y, d_x)/r^2` in the
        position columns, zero elsewhere.

        Parameters
        ----------
        x : (..., n) array_like
            States (not at the sensor, where the Jacobian is undefined).

        Returns
        -------
        (..., 2, n) ndarray
            One Jacobian per state.

        Examples
        --------
        >>> RangeBearing(sensor=(1.0, 1.0)).jacobian(np.array([4.0, 5.0, 0.0, 0.0])).round(3)
        array([[ 0.6 ,  0.8 ,  0.  ,  0.  ],
               [-0.16,  0.12,  0.  ,  0.  ]])
        """
        x = _states(x, self.ndim_state, "RangeBearing")
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

    with ``t`` the step index (``q = 10`` in the literature); see :func:`growth_model` for it
    with its measurement.

    Parameters
    ----------
    q : float
        Process-noise variance (finite, >= 0).

    Attributes
    ----------
    ndim_state : int
        Size of the state: 1.
    jit_f : numba function
        ``f`` for one state, compiled, for the particle filter's compiled path.
    jit_jacobian : numba function
        Its Jacobian at one state, compiled, for the extended Kalman filter's compiled path.

    Raises
    ------
    ValueError
        If ``q`` is negative or not finite.

    References
    ----------
    .. [1] N. J. Gordon, D. J. Salmond and A. F. M. Smith, "Novel approach to
       nonlinear/non-Gaussian Bayesian state estimation", *IEE Proceedings F* 140(2), 1993.
    .. [2] G. Kitagawa, "Monte Carlo filter and smoother for non-Gaussian nonlinear state
       space models", *Journal of Computational and Graphical Statistics* 5(1), 1996.

    Examples
    --------
    >>> GrowthMotion().f(np.array([[1.0], [2.0]]), t=0.0)
    array([[21.],
           [19.]])
    """

    ndim_state = 1
    jit_f = staticmethod(_growth_f)
    jit_jacobian = staticmethod(_growth_jacobian)

    def jit_params(self, dt: np.ndarray, t: np.ndarray) -> np.ndarray:
        """The parameters of :attr:`jit_f` for each step: the forcing ``8 cos(1.2 t)``.

        Parameters
        ----------
        dt, t : (T,) ndarray
            Time steps (unused) and times of the steps.

        Returns
        -------
        (T, 1) ndarray
            ``8 cos(1.2 t)``.

        Examples
        --------
        >>> GrowthMotion().jit_params(np.ones(2), np.array([0.0, 1.0])).round(4)
        array([[8.    ],
               [2.8989]])
        """
        return 8 * np.cos(1.2 * np.asarray(t, dtype=float))[:, None]

    def __init__(self, q: float = 10.0):
        self.q = _check_q(q)

    def __repr__(self) -> str:
        return f"GrowthMotion(q={self.q})"

    def f(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        """The mean transition ``x/2 + 25 x/(1 + x²) + 8 cos(1.2 t)``.

        Parameters
        ----------
        x : (..., 1) array_like
            States.
        dt : float
            Unused (the model is discrete-time).
        t : float
            The step index of the predicted state.

        Returns
        -------
        (..., 1) ndarray
            The predicted states.

        Examples
        --------
        >>> GrowthMotion().f(np.array([0.0]), t=0.0)
        array([8.])
        """
        x = _states(x, 1, "GrowthMotion")  # ((2,) against t (2,) broadcast to (2, 2))
        return x / 2 + 25 * x / (1 + x * x) + 8 * np.cos(1.2 * np.asarray(t))[..., None]

    def jacobian(self, x: np.ndarray, dt: float = 1.0, t: float = 0.0) -> np.ndarray:
        """The derivative ``1/2 + 25 (1 - x²) / (1 + x²)²``.

        Parameters
        ----------
        x : (..., 1) array_like
            States.
        dt, t : float
            Unused.

        Returns
        -------
        (..., 1, 1) ndarray
            One Jacobian per state.

        Examples
        --------
        >>> GrowthMotion().jacobian(np.array([1.0]))
        array([[0.5]])
        """
        x = _states(x, 1, "GrowthMotion")
        return (0.5 + 25 * (1 - x * x) / (1 + x * x) ** 2)[..., None]

    def Q(self, dt: float = 1.0) -> np.ndarray:
        """The process-noise variance as a matrix.

        Parameters
        ----------
        dt : float
            Unused.

        Returns
        -------
        (1, 1) ndarray
            ``[[q]]``.

        Examples
        --------
        >>> GrowthMotion(q=10.0).Q()
        array([[10.]])
        """
        return np.array([[self.q]])


class GrowthMeasurement(AngleAwareMeasurement):
    r"""The growth model's measurement ``y_t = x_t^2 / 20 + v_t``, ``v_t ~ N(0, r)``.

    .. math:: y_t = \frac{x_t^2}{20} + v_t, \qquad v_t \sim N(0, r)

    (``r = 1`` in the literature). Its sign ambiguity makes the posterior bimodal.

    Parameters
    ----------
    r : float
        Measurement-noise variance, finite and > 0.

    Attributes
    ----------
    ndim_meas, ndim_state : int
        Sizes of a measurement and of the state: 1 and 1.
    jit_h : numba function
        ``h`` for one state, compiled, for the particle filter's compiled path.
    jit_jacobian : numba function
        Its Jacobian at one state, compiled, for the extended Kalman filter's compiled path.

    Raises
    ------
    ValueError
        If ``r`` is not a finite number > 0.

    References
    ----------
    .. [1] N. J. Gordon, D. J. Salmond and A. F. M. Smith, "Novel approach to
       nonlinear/non-Gaussian Bayesian state estimation", *IEE Proceedings F* 140(2), 1993.

    Examples
    --------
    >>> meas = GrowthMeasurement()
    >>> meas.h(np.array([[-2.0], [2.0]]))   # the same for x and -x
    array([[0.2],
           [0.2]])
    """

    ndim_meas, ndim_state, angles = 1, 1, ()
    jit_h = staticmethod(_square_h)
    jit_jacobian = staticmethod(_square_jacobian)

    def jit_params(self) -> np.ndarray:
        """The parameters of :attr:`jit_h`: none.

        Returns
        -------
        (0,) ndarray
            Empty.

        Examples
        --------
        >>> GrowthMeasurement().jit_params().shape
        (0,)
        """
        return _NO_PARAMS

    def __init__(self, r: float = 1.0):
        # ("a" failed in isfinite, naming nothing; True was taken as 1)
        self._R = np.array([[as_finite(r, "r", 0.0, above=True, what="variance")]])

    def __repr__(self) -> str:
        return f"GrowthMeasurement(r={self._R[0, 0]})"

    def h(self, x: np.ndarray) -> np.ndarray:
        """The mean measurement ``x² / 20``.

        Parameters
        ----------
        x : (..., 1) array_like
            States.

        Returns
        -------
        (..., 1) ndarray
            ``x² / 20``.

        Examples
        --------
        >>> GrowthMeasurement().h(np.array([10.0]))
        array([5.])
        """
        return _states(x, 1, "GrowthMeasurement") ** 2 / 20

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """The derivative ``x / 10``.

        Parameters
        ----------
        x : (..., 1) array_like
            States.

        Returns
        -------
        (..., 1, 1) ndarray
            One Jacobian per state.

        Examples
        --------
        >>> GrowthMeasurement().jacobian(np.array([2.0]))
        array([[0.2]])
        """
        return (_states(x, 1, "GrowthMeasurement") / 10)[..., None]



def growth_model(q: float = 10.0, r: float = 1.0) -> tuple[GrowthMotion, GrowthMeasurement]:
    r"""The growth model's motion and measurement, with the literature's ``q = 10``, ``r = 1``.

    .. math::

        x_t = \frac{x_{t-1}}{2} + \frac{25 x_{t-1}}{1 + x_{t-1}^2} + 8 \cos(1.2\, t) + w_t,
        \quad w_t \sim N(0, q), \qquad y_t = \frac{x_t^2}{20} + v_t, \quad v_t \sim N(0, r).

    Parameters
    ----------
    q : float
        Process-noise variance.
    r : float
        Measurement-noise variance.

    Returns
    -------
    motion : GrowthMotion
        The dynamics.
    measurement : GrowthMeasurement
        The measurement.

    References
    ----------
    .. [1] N. J. Gordon, D. J. Salmond and A. F. M. Smith, "Novel approach to
       nonlinear/non-Gaussian Bayesian state estimation", *IEE Proceedings F* 140(2), 1993.
    .. [2] G. Kitagawa, "Monte Carlo filter and smoother for non-Gaussian nonlinear state
       space models", *Journal of Computational and Graphical Statistics* 5(1), 1996.

    Examples
    --------
    >>> motion, meas = growth_model()
    >>> float(motion.f(np.array([1.0]), t=0.0)[0]), float(meas.h(np.array([2.0]))[0])
    (21.0, 0.2)
    """
    return GrowthMotion(q), GrowthMeasurement(r)
