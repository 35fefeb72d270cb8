r"""Motion models: the physics of how a state moves between two measurements.

Every model gives the discrete-time transition ``F(dt)`` and process-noise covariance ``Q(dt)`` of

.. math:: x_t = F(\Delta t)\, x_{t-1} + w_t, \qquad w_t \sim N(0, Q(\Delta t)),

the seeds' :math:`x_i \sim N(D_{i-1} x_{i-1}; \Sigma_{d_i})`. ``dt`` may be a scalar, giving
``(n, n)`` matrices, or an array of shape ``(K,)``, giving stacks ``(K, n, n)``: this is how
variable time steps (dropped frames, irregular sampling) are handled.

State layout for the kinematic models in ``dim`` spatial dimensions is derivative-major:
``[p_1..p_dim, v_1..v_dim, a_1..a_dim]``, so in 2-D constant velocity the state is
``[x, y, vx, vy]`` as in the seeds' 2-D example, and a position measurement picks the first
``dim`` entries.
"""

from __future__ import annotations

from collections.abc import Callable
from math import factorial
from typing import Any, Literal, Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from .._validate import (
    as_float_array,
    as_number,
    check_matrix_stack,
    check_psd,
    is_whole,
)

__all__ = [
    "MotionModel",
    "ConstantPosition",
    "ConstantVelocity",
    "ConstantAcceleration",
    "Periodic",
    "LinearMotion",
]

Discretisation = Literal["exact", "euler"]


@runtime_checkable
class MotionModel(Protocol):
    """What a linear motion model provides: ``F(dt)``, ``Q(dt)`` and ``ndim_state``.

    Any object with these is a motion model for :class:`~vistrack.filters.KalmanFilter` and
    the other filters; the protocol is checkable at run time with ``isinstance`` (which looks
    for the names only, not their signatures).

    Attributes
    ----------
    ndim_state : int
        Size ``n`` of the state.

    Examples
    --------
    >>> isinstance(ConstantVelocity(dim=2), MotionModel)
    True
    """

    ndim_state: int

    def F(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """Transition matrix over a time step.

        Parameters
        ----------
        dt : float or (K,) array_like
            Time step, or several.

        Returns
        -------
        (n, n) or (K, n, n) ndarray
            ``F(dt)``, one per time step when ``dt`` is an array.

        Examples
        --------
        >>> ConstantVelocity(dim=1).F(2.0)
        array([[1., 2.],
               [0., 1.]])
        """
        ...

    def Q(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """Process-noise covariance over a time step.

        Parameters
        ----------
        dt : float or (K,) array_like
            Time step, or several.

        Returns
        -------
        (n, n) or (K, n, n) ndarray
            ``Q(dt)``, symmetric positive semi-definite, shaped like :meth:`F`.

        Examples
        --------
        >>> ConstantPosition(dim=1, q=0.5).Q(2.0)
        array([[1.]])
        """
        ...


def _as_dt(dt: float | np.ndarray) -> np.ndarray:
    # (True, "0.5" and b"1" were read as steps; None was said as "got nan")
    if dt is None:
        raise TypeError("dt must be a number or an array of numbers; got None")
    d = as_float_array(dt, "dt", ndim=(0, 1), not_boolean="a number or an array of numbers")
    if not np.all(np.isfinite(d)) or np.any(d < 0):
        bad = d[~(np.isfinite(d) & (d >= 0))].ravel()[0]
        raise ValueError(f"dt must be finite and >= 0; got {bad}")
    return d


def _powered(c: float, dt: np.ndarray, p: int) -> np.ndarray:
    """``c dt^p`` multiplied a factor at a time, so that no power overflows where the product
    does not (``dt^3`` of 1e103 is past the largest float; times 1e-21 it is not), and 0
    where ``c`` is (``0 × inf`` was NaN)."""
    out = np.full(dt.shape, c)
    for _ in range(p):
        out = out * dt
    return out


def _finite(entries: Callable[..., np.ndarray], dt: np.ndarray, name: str,
            model: object) -> np.ndarray:
    """``entries(dt)``, a kinematic model's ``F`` or ``Q`` block; where an entry overflows
    (``dt^p`` past the largest float), again a factor at a time (``entries(dt, True)``),
    and a ValueError naming the step and ``q`` where an entry itself is past it (a constant
    velocity's ``Q`` at ``dt`` 1e155 was inf, and reached the filters). The entries of
    ordinary steps are computed as before, to the bit."""
    with np.errstate(over="ignore", invalid="ignore"):
        out = entries(dt)
        if not np.isfinite(out).all():
            out = entries(dt, True)
    return _in_range(out, name, model, dt)


def _in_range(out: np.ndarray, name: str, model: Any, dt: np.ndarray) -> np.ndarray:
    """``out``, a model's ``F`` or ``Q`` over ``dt``, or a ValueError naming the step and
    the model's ``q`` where an entry is past the largest float."""
    if not np.isfinite(out).all():
        raise ValueError(f"{type(model).__name__}'s {name}(dt) is past the largest float at "
                         f"dt={float(np.max(dt)):g}, q={model.q:g}: too long a step or too "
                         "large a noise for this model")
    return out


def _apply(F: np.ndarray, x: ArrayLike) -> np.ndarray:
    """``F x`` for states ``x (..., n)``: one ``F (n, n)`` for all, or a stack ``(K, n, n)``
    (a ``dt`` for each of ``K`` states, or ``K`` time steps of one state)."""
    x = np.asarray(x)
    if F.ndim == 2:
        if x.shape[-1:] != F.shape[-1:]:  # (matmul's mismatch named no argument)
            raise ValueError(f"x must be states of size {F.shape[-1]}, shape (..., "
                             f"{F.shape[-1]}); got shape {x.shape}")
        return x @ F.T
    try:
        return np.einsum("...ij,...j->...i", F, x)
    except ValueError:
        raise ValueError(f"x must have one state for each of the {len(F)} time steps in dt, "
                         f"shape ({len(F)}, {F.shape[-1]}), or be one state; got shape "
                         f"{x.shape}") from None


_SIN_TERMS = 12  # of the series below; for u < 2 the first term left out, u^24/25!, is < 1.1e-18


def _sin_series(u2: np.ndarray, first: int) -> np.ndarray:
    r"""``sum_k (-1)^k u^(2k) / (2k + first)!`` for ``u2 = u²``, by Horner's rule:
    ``sin(u) / u`` for ``first=1``, ``(u - sin u) / u³`` for ``first=3``, accurate to rounding
    for ``|u| < 2``, where the closed forms cancel (``u - sin u`` loses half its digits at
    ``u = 1e-4``, all of them below ``u = 4e-8``).

    >>> float(_sin_series(np.array(1e-20), 3)), float(_sin_series(np.array(0.0), 1))
    (0.16666666666666666, 1.0)
    """
    out = np.zeros_like(u2)
    for k in reversed(range(_SIN_TERMS)):
        out = (-1) ** k / factorial(2 * k + first) + u2 * out
    return out


def _check_q(q: float, name: str = "q") -> float:
    q = as_number(q, name)
    if not np.isfinite(q) or q < 0:
        raise ValueError(f"{name} must be a finite number >= 0; got {q}")
    return q


def _check_dim(dim: int) -> int:
    if not (is_whole(dim, 1) and dim <= 3):
        raise ValueError(f"dim must be 1, 2 or 3; got {dim!r}")
    return int(dim)


class _Kinematic:
    """A chain of ``order`` integrators per spatial axis, driven by white noise.

    The continuous model is ``d^{order+1} p / dt^{order+1} = w(t)`` with ``E[w w'] = q δ(t)``
    per axis. ``F`` is the exact discretisation ``exp(A dt)``, whose entries are
    ``dt^(j-i) / (j-i)!``, and ``Q`` is the exact integral
    ``q ∫_0^dt exp(A s) G G' exp(A s)' ds``, whose entries are
    ``q dt^(2k+1-i-j) / ((2k+1-i-j) (k-i)! (k-j)!)`` for ``k = order``.
    """

    order: int

    def __init__(self, dim: int = 2, q: float = 1.0, discretisation: Discretisation = "exact"):
        self.dim = _check_dim(dim)
        self.q = _check_q(q)
        if discretisation not in ("exact", "euler"):
            raise ValueError(f"discretisation must be 'exact' or 'euler'; got {discretisation!r}")
        self.discretisation = discretisation
        self.ndim_state = self.dim * (self.order + 1)

    def __repr__(self) -> str:
        extra = "" if self.discretisation == "exact" else ", discretisation='euler'"
        return f"{type(self).__name__}(dim={self.dim}, q={self.q}{extra})"

    def _F1(self, dt: np.ndarray, stepwise: bool = False) -> np.ndarray:
        k = self.order + 1
        out = np.zeros(dt.shape + (k, k))
        for i in range(k):
            for j in range(i, k):
                if self.discretisation == "euler" and j - i > 1:
                    continue  # forward Euler: I + A dt keeps only the first super-diagonal
                out[..., i, j] = (_powered(1.0 / factorial(j - i), dt, j - i) if stepwise
                                  else dt ** (j - i) / factorial(j - i))
        return out

    def _Q1(self, dt: np.ndarray, stepwise: bool = False) -> np.ndarray:
        k = self.order
        out = np.zeros(dt.shape + (k + 1, k + 1))
        if self.discretisation == "euler":
            out[..., k, k] = self.q * dt  # Euler-Maruyama: noise enters the last derivative only
            return out
        for i in range(k + 1):
            for j in range(k + 1):
                p = 2 * k + 1 - i - j
                out[..., i, j] = (
                    _powered(self.q / (p * factorial(k - i) * factorial(k - j)), dt, p)
                    if stepwise else self.q * dt**p / (p * factorial(k - i) * factorial(k - j)))
        return out

    def F(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """Transition matrix over ``dt``: ``dt^(j-i) / (j-i)!`` per axis (see the class).

        Parameters
        ----------
        dt : float or (K,) array_like
            Time step(s), finite and >= 0.

        Returns
        -------
        (n, n) or (K, n, n) ndarray
            ``(n, n)`` for a scalar ``dt``, one matrix per step for ``dt`` of shape ``(K,)``.

        Examples
        --------
        >>> ConstantVelocity(dim=1).F([1.0, 2.0]).shape
        (2, 2, 2)
        """
        d = _as_dt(dt)
        return np.kron(_finite(self._F1, d, "F", self), np.eye(self.dim))

    def Q(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """Process-noise covariance over ``dt`` (see the class), shaped like :meth:`F`.

        Parameters
        ----------
        dt : float or (K,) array_like
            Time step(s), finite and >= 0.

        Returns
        -------
        (n, n) or (K, n, n) ndarray
            Symmetric positive semi-definite; zero for ``dt = 0``.

        Examples
        --------
        >>> ConstantVelocity(dim=1, q=1.0).Q(1.0).round(3).tolist()
        [[0.333, 0.5], [0.5, 1.0]]
        """
        d = _as_dt(dt)
        return np.kron(_finite(self._Q1, d, "Q", self), np.eye(self.dim))

    def f(self, x: np.ndarray, dt: float = 1.0) -> np.ndarray:
        """Propagate states by ``dt`` without noise: ``x F(dt)'``.

        Parameters
        ----------
        x : (..., n) array_like
            States, one per row.
        dt : float or (K,) array_like
            Time step; or one for each of ``K`` states ``x (K, n)`` (or ``K`` steps of one
            state ``x (n,)``).

        Returns
        -------
        (..., n) ndarray
            The predicted states ``F(dt) x``.

        Examples
        --------
        >>> ConstantVelocity(dim=1).f(np.array([0.0, 2.0]), dt=0.5)
        array([1., 2.])
        """
        return _apply(self.F(dt), x)


class ConstantPosition(_Kinematic):
    r"""Drifting points: :math:`D = I`, the position is the old one plus noise.

    ``Q(dt) = q dt I`` (a random walk whose variance grows by ``q`` per unit time):

    .. math:: x_t = x_{t-1} + w_t, \qquad w_t \sim N(0, q\, \Delta t\, I).

    Parameters
    ----------
    dim : {1, 2, 3}
        Spatial dimension; the state is the position, ``n = dim``.
    q : float
        Diffusion rate: variance added per unit time, per axis (finite, >= 0).

    Raises
    ------
    ValueError
        If ``dim`` is not 1, 2 or 3, or ``q`` is negative or not finite.

    Examples
    --------
    >>> ConstantPosition(dim=2, q=0.5).Q(2.0)
    array([[1., 0.],
           [0., 1.]])
    """

    order = 0

    def __init__(self, dim: int = 2, q: float = 1.0):
        super().__init__(dim, q, "exact")


class ConstantVelocity(_Kinematic):
    r"""Constant velocity, driven by white-noise acceleration.

    Per axis, state ``(p, v)`` with ``F = [[1, dt], [0, 1]]`` (the seeds' matrix; forward Euler
    and the exact discretisation agree here) and

    .. math:: Q = q \begin{pmatrix} dt^3/3 & dt^2/2 \\ dt^2/2 & dt \end{pmatrix},

    where ``q`` is the power spectral density of the acceleration noise (units of
    position² / time³). With ``discretisation='euler'``, ``Q = q dt`` on the velocity only.

    Parameters
    ----------
    dim : {1, 2, 3}
        Spatial dimension; the state is ``[p_1..p_dim, v_1..v_dim]``, ``n = 2 dim``.
    q : float
        Spectral density of the white-noise acceleration, per axis (finite, >= 0).
    discretisation : {'exact', 'euler'}
        ``'exact'``: ``F = exp(A dt)`` and the exact noise integral; ``'euler'``: the forward
        Euler step ``I + A dt`` (the same ``F`` here) and noise ``q dt`` on the velocity.

    Raises
    ------
    ValueError
        If ``dim`` is not 1, 2 or 3, ``q`` is negative or not finite, or ``discretisation``
        is not one of the two names.

    References
    ----------
    .. [1] Y. Bar-Shalom, X. R. Li and T. Kirubarajan, *Estimation with Applications to
       Tracking and Navigation*, Wiley, 2001, ch. 6 (kinematic models).

    Examples
    --------
    >>> ConstantVelocity(dim=1).F(0.5)
    array([[1. , 0.5],
           [0. , 1. ]])
    """

    order = 1


class ConstantAcceleration(_Kinematic):
    r"""Constant acceleration, driven by white-noise jerk.

    Per axis, state ``(p, v, a)`` with the standard kinematic transition

    .. math:: F = \begin{pmatrix} 1 & dt & dt^2/2 \\ 0 & 1 & dt \\ 0 & 0 & 1 \end{pmatrix}.

    The seeds write ``F = [[1, dt, 0], [0, 1, dt], [0, 0, 1]]``, without the ``dt²/2`` term:
    that is the forward-Euler step ``I + A dt`` of ``dp/dt = v, dv/dt = a``, which lets
    acceleration reach the position only one step late. It is available as
    ``discretisation='euler'``; the default is the exact one. ``Q`` is the exact white-noise-jerk
    covariance with jerk spectral density ``q``:
    ``q [[dt⁵/20, dt⁴/8, dt³/6], [dt⁴/8, dt³/3, dt²/2], [dt³/6, dt²/2, dt]]``.

    Parameters
    ----------
    dim : {1, 2, 3}
        Spatial dimension; the state is ``[p_1..p_dim, v_1..v_dim, a_1..a_dim]``,
        ``n = 3 dim``.
    q : float
        Spectral density of the white-noise jerk, per axis (finite, >= 0).
    discretisation : {'exact', 'euler'}
        ``'exact'``: ``F = exp(A dt)`` and the exact noise integral; ``'euler'``: the seeds'
        ``F = I + A dt`` and noise ``q dt`` on the acceleration only.

    Raises
    ------
    ValueError
        If ``dim`` is not 1, 2 or 3, ``q`` is negative or not finite, or ``discretisation``
        is not one of the two names.

    References
    ----------
    .. [1] Y. Bar-Shalom, X. R. Li and T. Kirubarajan, *Estimation with Applications to
       Tracking and Navigation*, Wiley, 2001, ch. 6 (kinematic models).

    Examples
    --------
    >>> ConstantAcceleration(dim=1).F(2.0)
    array([[1., 2., 2.],
           [0., 1., 2.],
           [0., 0., 1.]])
    >>> ConstantAcceleration(dim=1, discretisation="euler").F(2.0)
    array([[1., 2., 0.],
           [0., 1., 2.],
           [0., 0., 1.]])
    """

    order = 2


def _phase(omega: float, dt: np.ndarray) -> np.ndarray:
    """``ω dt``, or a ValueError where it is past the largest float (the sines of it were
    NaN, and reached the filters)."""
    with np.errstate(over="ignore"):
        wd = omega * dt
    if not np.isfinite(wd).all():
        raise ValueError(f"Periodic's phase omega dt is past the largest float at "
                         f"omega={omega:g}, dt={float(np.max(dt)):g}")
    return wd


class Periodic:
    r"""Periodic motion ``d²p/dt² = -ω² p`` (the seeds use ``ω = 1``), per spatial axis.

    State per axis ``u = (p, v)`` with ``du/dt = S u``, ``S = [[0, 1], [-ω², 0]]``.

    - ``discretisation='exact'``:
      ``F = exp(S dt) = [[cos ωdt, sin(ωdt)/ω], [-ω sin ωdt, cos ωdt]]``, which keeps the
      energy of the oscillation;
    - ``discretisation='euler'``: the seeds' forward Euler step
      ``F = I + S dt = [[1, dt], [-ω² dt, 1]]``, whose amplitude grows by
      ``sqrt(1 + ω² dt²)`` every step.

    ``Q`` is the exact covariance of white-noise acceleration of density ``q``:
    ``Q11 = q/ω² (dt/2 - sin(2ωdt)/(4ω))``, ``Q12 = q sin²(ωdt)/(2ω²)``,
    ``Q22 = q (dt/2 + sin(2ωdt)/(4ω))`` (Euler: ``q dt`` on the velocity). For
    ``u = 2ωdt < 1`` the same are computed as ``Q11 = 2 q dt³ (u - sin u)/u³``,
    ``Q12 = q dt² (sin(ωdt)/(ωdt))² / 2``, ``Q22 = q dt (1 + sin(u)/u) / 2`` with the
    series of these ratios, since ``dt/2 - sin(2ωdt)/(4ω)`` cancels (to zero, and ``Q`` to
    a matrix that is not positive semi-definite, at ``ω dt = 1e-8``); as ``ω → 0`` ``Q``
    tends to :class:`ConstantVelocity`'s, ``q [[dt³/3, dt²/2], [dt²/2, dt]]``.

    Parameters
    ----------
    dim : {1, 2, 3}
        Spatial dimension; the state is ``[p_1..p_dim, v_1..v_dim]``, ``n = 2 dim``.
    omega : float
        Angular frequency ``ω`` (finite, > 0); the period is ``2π / ω``.
    q : float
        Spectral density of the white-noise acceleration, per axis (finite, >= 0).
    discretisation : {'exact', 'euler'}
        See above.

    Raises
    ------
    ValueError
        If ``dim`` is not 1, 2 or 3, ``omega`` is not a finite number > 0, ``q`` is negative
        or not finite, or ``discretisation`` is not one of the two names.

    Examples
    --------
    A quarter period moves position into velocity:

    >>> Periodic(omega=2.0).F(np.pi / 4).round(12)
    array([[ 0. ,  0.5],
           [-2. ,  0. ]])
    >>> Periodic(omega=2.0, discretisation="euler").F(0.5)
    array([[ 1. ,  0.5],
           [-2. ,  1. ]])
    """

    def __init__(
        self,
        dim: int = 1,
        omega: float = 1.0,
        q: float = 1.0,
        discretisation: Discretisation = "exact",
    ):
        self.dim = _check_dim(dim)
        self.omega = as_number(omega, "omega")
        if not np.isfinite(self.omega) or self.omega <= 0:
            raise ValueError(f"omega must be a finite number > 0; got {omega}")
        self.q = _check_q(q)
        if discretisation not in ("exact", "euler"):
            raise ValueError(f"discretisation must be 'exact' or 'euler'; got {discretisation!r}")
        self.discretisation = discretisation
        self.ndim_state = 2 * self.dim

    def __repr__(self) -> str:
        return (
            f"Periodic(dim={self.dim}, omega={self.omega}, q={self.q}, "
            f"discretisation={self.discretisation!r})"
        )

    def F(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """Transition matrix over ``dt`` (see the class).

        Parameters
        ----------
        dt : float or (K,) array_like
            Time step(s), finite and >= 0.

        Returns
        -------
        (n, n) or (K, n, n) ndarray
            One matrix per step for ``dt`` of shape ``(K,)``.

        Examples
        --------
        >>> Periodic(omega=1.0).F(np.pi).round(12)
        array([[-1.,  0.],
               [-0., -1.]])
        """
        d = _as_dt(dt)
        w = self.omega
        out = np.empty(d.shape + (2, 2))
        if self.discretisation == "euler":
            out[..., 0, 0] = 1.0
            out[..., 0, 1] = d
            with np.errstate(over="ignore"):  # (w**2 of a Python float raised OverflowError)
                out[..., 1, 0] = -np.float64(w) * w * d
            if not np.isfinite(out[..., 1, 0]).all():
                raise ValueError(f"Periodic's Euler step overflows: omega² dt is past the "
                                 f"largest float at omega={w}, dt={d.max()}")
            out[..., 1, 1] = 1.0
        else:
            wd = _phase(w, d)
            c, s = np.cos(wd), np.sin(wd)
            # sin(ωdt)/ω as dt sin(u)/u, by the series below u = 1: a subnormal ω dt rounds
            # (to 0 at ω = 5e-324), and sin(ωdt)/ω with it, where the limit is dt
            small = wd < 1.0
            sinc = np.where(small, _sin_series(np.where(small, wd, 0.0) ** 2, 1),
                            s / np.where(small, 1.0, wd))
            out[..., 0, 0] = c
            out[..., 0, 1] = d * sinc
            out[..., 1, 0] = -w * s
            out[..., 1, 1] = c
        return np.kron(out, np.eye(self.dim))

    def Q(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """Process-noise covariance over ``dt`` (see the class), shaped like :meth:`F`.

        Parameters
        ----------
        dt : float or (K,) array_like
            Time step(s), finite and >= 0.

        Returns
        -------
        (n, n) or (K, n, n) ndarray
            Symmetric positive semi-definite.

        Examples
        --------
        Over a whole period the position and velocity noise have the same energy:

        >>> Periodic(omega=1.0, q=1.0).Q(2 * np.pi).round(6)
        array([[3.141593, 0.      ],
               [0.      , 3.141593]])
        """
        d = _as_dt(dt)
        w, q = self.omega, self.q
        with np.errstate(over="ignore", invalid="ignore"):  # (checked below)
            out = np.zeros(d.shape + (2, 2))
            if self.discretisation == "euler":
                out[..., 1, 1] = q * d
            else:
                dd = d.reshape(-1)
                q11, q12, q22 = np.empty_like(dd), np.empty_like(dd), np.empty_like(dd)
                # the closed forms cancel: the series (see the class); the phase is checked
                small = 2 * w * dd < 1.0
                ds = dd[small]
                u2 = (2 * w * ds) ** 2
                q11[small] = 2 * q * ds**3 * _sin_series(u2, 3)
                q12[small] = q / 2 * (ds * _sin_series(u2 / 4, 1)) ** 2
                q22[small] = q * ds * (1 + _sin_series(u2, 1)) / 2
                if not small.all():
                    db = dd[~small]
                    wd = _phase(w, db)
                    two = 2 * wd
                    # sin(2 ω dt) / 4ω; where 2 ω dt alone is past the largest float (ω 1e308
                    # at dt 1: NaN), as sin(ω dt) cos(ω dt) / 2ω
                    fin = np.isfinite(two)
                    sin = np.sin(wd)
                    s2 = np.where(fin, np.sin(np.where(fin, two, 0.0)),
                                  2 * sin * np.cos(wd)) / (4 * w)
                    # (w**2 of a Python float past 1.3e154 raised OverflowError: divided twice)
                    q11[~small] = q / w / w * (db / 2 - s2)
                    q12[~small] = q * sin ** 2 / 2 / w / w
                    q22[~small] = q * (db / 2 + s2)
                out[..., 0, 0] = q11.reshape(d.shape)
                out[..., 0, 1] = out[..., 1, 0] = q12.reshape(d.shape)
                out[..., 1, 1] = q22.reshape(d.shape)
        # (q 1e308 at dt 10 gave inf, as the kinematic Q did)
        return np.kron(_in_range(out, "Q", self, d), np.eye(self.dim))

    def f(self, x: np.ndarray, dt: float = 1.0) -> np.ndarray:
        """Propagate states by ``dt`` without noise: ``x F(dt)'``.

        Parameters
        ----------
        x : (..., n) array_like
            States, one per row.
        dt : float or (K,) array_like
            Time step; or one for each of ``K`` states ``x (K, n)`` (or ``K`` steps of one
            state ``x (n,)``).

        Returns
        -------
        (..., n) ndarray
            The predicted states.

        Examples
        --------
        >>> Periodic(omega=1.0).f(np.array([1.0, 0.0]), dt=np.pi).round(12)
        array([-1., -0.])
        """
        return _apply(self.F(dt), x)


class LinearMotion:
    r"""A user-given discrete-time motion model ``x_t = D_t x_{t-1} + N(0, Σd_t)``.

    .. math:: x_t = F_t x_{t-1} + w_t, \qquad w_t \sim N(0, Q_t).

    Parameters
    ----------
    F : (n, n) or (T, n, n) array_like
        Transition matrix ``D``, constant or one per step (``F[t]`` maps step ``t-1`` to ``t``;
        ``F[0]`` is never used, since the first step has no prediction).
    Q : (n, n) or (T, n, n) array_like
        Process-noise covariance ``Σd``, symmetric positive semi-definite; constant or one per
        step (with as many steps as ``F`` when both are per step).

    Attributes
    ----------
    ndim_state : int
        Size ``n`` of the state.
    n_steps : int or None
        The number of per-step matrices, None when both are constant.

    Raises
    ------
    ValueError
        If a matrix is not finite or square of size ``n`` (at least 1), a stack holds no
        matrix, the two disagree on the number of steps, or ``Q`` is not symmetric positive
        semi-definite.

    Notes
    -----
    A discrete-time model has no time step: ``F(dt)`` and ``Q(dt)`` accept only ``dt = 1``.

    Examples
    --------
    >>> m = LinearMotion([[1.0, 1.0], [0.0, 1.0]], 0.1 * np.eye(2))
    >>> m.f(np.array([0.0, 2.0])), m.n_steps
    (array([2., 2.]), None)
    """

    def __init__(self, F: np.ndarray, Q: np.ndarray):
        F_arr = as_float_array(F, "F", ndim=(2, 3))
        n = F_arr.shape[-1]
        if n == 0:  # (numpy's "zero-size array to reduction operation" in the Q check)
            raise ValueError(f"F must be at least 1 x 1 (a state of one value or more); got "
                             f"shape {F_arr.shape}")
        # a stack of one matrix is the constant, as kalman_filter takes it
        T = F_arr.shape[0] if F_arr.ndim == 3 and F_arr.shape[0] != 1 else None
        self._F = check_matrix_stack(F_arr, "F", n, n, T)
        Q_arr = as_float_array(Q, "Q", ndim=(2, 3))
        T = T if T is not None else (Q_arr.shape[0] if Q_arr.ndim == 3 and Q_arr.shape[0] != 1
                                     else None)
        self._Q = check_matrix_stack(Q_arr, "Q", n, n, T)
        check_psd(self._Q, "Q")
        # its own copies, and copies given out (read-only arrays would be new argument types
        # for the compiled filters): the caller's arrays were kept, so a Q changed after the
        # check (or through the view Q() returned) was used as it was, unchecked
        self._F, self._Q = self._F.copy(), self._Q.copy()
        self.ndim_state = n
        self.n_steps = T

    def __repr__(self) -> str:
        return f"LinearMotion(n={self.ndim_state}, steps={self.n_steps or 'constant'})"

    @staticmethod
    def _check_dt(dt: float | np.ndarray) -> None:
        d = _as_dt(dt)  # (True and "1" were taken as a step of 1)
        if not np.all(d == 1.0):
            raise ValueError(
                "LinearMotion is a discrete-time model whose F and Q do not depend on dt; "
                "pass dt=1 (or a per-step F/Q stack), or use a continuous model such as "
                f"ConstantVelocity for variable time steps; got dt={dt!r}"
            )

    def F(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """The transition matrix or matrices.

        Parameters
        ----------
        dt : float or array_like
            Must be 1 (every entry, for an array): the model is discrete-time.

        Returns
        -------
        (n, n), (T, n, n) or (1, n, n) ndarray
            The constant matrix when neither ``F`` nor ``Q`` is per step; otherwise the stored
            stack: ``(T, n, n)`` if ``F`` was given per step, ``(1, n, n)`` if it was constant.

        Raises
        ------
        ValueError
            If ``dt`` is not 1.

        Examples
        --------
        >>> LinearMotion(np.eye(2), np.eye(2)).F().shape
        (2, 2)
        """
        self._check_dt(dt)
        return (self._F[0] if self.n_steps is None else self._F).copy()

    def Q(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """The process-noise covariance or covariances.

        Parameters
        ----------
        dt : float or array_like
            Must be 1 (every entry, for an array): the model is discrete-time.

        Returns
        -------
        (n, n), (T, n, n) or (1, n, n) ndarray
            The constant matrix when neither ``F`` nor ``Q`` is per step; otherwise the stored
            stack: ``(T, n, n)`` if ``Q`` was given per step, ``(1, n, n)`` if it was constant.

        Raises
        ------
        ValueError
            If ``dt`` is not 1.

        Examples
        --------
        >>> LinearMotion(np.eye(2), 0.5 * np.eye(2)).Q()
        array([[0.5, 0. ],
               [0. , 0.5]])
        """
        self._check_dt(dt)
        return (self._Q[0] if self.n_steps is None else self._Q).copy()

    def f(self, x: np.ndarray, dt: float = 1.0) -> np.ndarray:
        """Propagate states one step without noise: ``x F'``.

        Parameters
        ----------
        x : (..., n) array_like
            States, one per row.
        dt : float
            Must be 1.

        Returns
        -------
        (..., n) ndarray
            The predicted states.

        Raises
        ------
        ValueError
            If the model has one ``F`` per step (there is no single ``F`` to apply), or ``dt``
            is not 1.

        Examples
        --------
        >>> LinearMotion([[0.0, 1.0], [1.0, 0.0]], np.eye(2)).f(np.array([1.0, 2.0]))
        array([2., 1.])
        """
        if self._F.shape[0] > 1:  # (a Q per step alone leaves one F to apply)
            raise ValueError("f(x) needs a constant F; this LinearMotion has one F per step")
        self._check_dt(dt)
        return _apply(self._F[0], x)  # (matmul's mismatch named no argument)
