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

from math import factorial
from typing import Literal, Protocol, runtime_checkable

import numpy as np

from .._validate import as_float_array, check_matrix_stack, check_psd

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
    """What a linear motion model provides."""

    ndim_state: int

    def F(self, dt: float | np.ndarray = 1.0) -> np.ndarray: ...

    def Q(self, dt: float | np.ndarray = 1.0) -> np.ndarray: ...


def _as_dt(dt: float | np.ndarray) -> np.ndarray:
    d = as_float_array(dt, "dt", ndim=(0, 1))
    if not np.all(np.isfinite(d)) or np.any(d < 0):
        bad = d[~(np.isfinite(d) & (d >= 0))].ravel()[0]
        raise ValueError(f"dt must be finite and >= 0; got {bad}")
    return d


def _check_q(q: float) -> float:
    q = float(q)
    if not np.isfinite(q) or q < 0:
        raise ValueError(f"q must be a finite number >= 0; got {q}")
    return q


def _check_dim(dim: int) -> int:
    if int(dim) != dim or not 1 <= dim <= 3:
        raise ValueError(f"dim must be 1, 2 or 3; got {dim}")
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

    def _F1(self, dt: np.ndarray) -> np.ndarray:
        k = self.order + 1
        out = np.zeros(dt.shape + (k, k))
        for i in range(k):
            for j in range(i, k):
                if self.discretisation == "euler" and j - i > 1:
                    continue  # forward Euler: I + A dt keeps only the first super-diagonal
                out[..., i, j] = dt ** (j - i) / factorial(j - i)
        return out

    def _Q1(self, dt: np.ndarray) -> np.ndarray:
        k = self.order
        out = np.zeros(dt.shape + (k + 1, k + 1))
        if self.discretisation == "euler":
            out[..., k, k] = self.q * dt  # Euler-Maruyama: noise enters the last derivative only
            return out
        for i in range(k + 1):
            for j in range(k + 1):
                p = 2 * k + 1 - i - j
                out[..., i, j] = self.q * dt**p / (p * factorial(k - i) * factorial(k - j))
        return out

    def F(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """Transition matrix, ``(n, n)`` for scalar ``dt`` or ``(K, n, n)`` for ``dt`` of
        ``(K,)``."""
        return np.kron(self._F1(_as_dt(dt)), np.eye(self.dim))

    def Q(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        """Process-noise covariance, shaped like :meth:`F`."""
        return np.kron(self._Q1(_as_dt(dt)), np.eye(self.dim))

    def f(self, x: np.ndarray, dt: float = 1.0) -> np.ndarray:
        """Propagate states ``x`` of shape ``(..., n)`` by ``dt`` without noise."""
        return np.asarray(x) @ self.F(dt).T


class ConstantPosition(_Kinematic):
    r"""Drifting points: :math:`D = I`, the position is the old one plus noise.

    ``Q(dt) = q dt I`` (a random walk whose variance grows by ``q`` per unit time).

    Parameters
    ----------
    dim : {1, 2, 3}
        Spatial dimension; the state is the position, ``n = dim``.
    q : float
        Diffusion rate: variance added per unit time, per axis.

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
    ``Q22 = q (dt/2 + sin(2ωdt)/(4ω))`` (Euler: ``q dt`` on the velocity).
    """

    def __init__(
        self,
        dim: int = 1,
        omega: float = 1.0,
        q: float = 1.0,
        discretisation: Discretisation = "exact",
    ):
        self.dim = _check_dim(dim)
        self.omega = float(omega)
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
        d = _as_dt(dt)
        w = self.omega
        out = np.empty(d.shape + (2, 2))
        if self.discretisation == "euler":
            out[..., 0, 0] = 1.0
            out[..., 0, 1] = d
            out[..., 1, 0] = -(w**2) * d
            out[..., 1, 1] = 1.0
        else:
            c, s = np.cos(w * d), np.sin(w * d)
            out[..., 0, 0] = c
            out[..., 0, 1] = s / w
            out[..., 1, 0] = -w * s
            out[..., 1, 1] = c
        return np.kron(out, np.eye(self.dim))

    def Q(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        d = _as_dt(dt)
        w, q = self.omega, self.q
        out = np.zeros(d.shape + (2, 2))
        if self.discretisation == "euler":
            out[..., 1, 1] = q * d
        else:
            s2 = np.sin(2 * w * d) / (4 * w)
            out[..., 0, 0] = q / w**2 * (d / 2 - s2)
            out[..., 0, 1] = out[..., 1, 0] = q * np.sin(w * d) ** 2 / (2 * w**2)
            out[..., 1, 1] = q * (d / 2 + s2)
        return np.kron(out, np.eye(self.dim))

    def f(self, x: np.ndarray, dt: float = 1.0) -> np.ndarray:
        return np.asarray(x) @ self.F(dt).T


class LinearMotion:
    r"""A user-given discrete-time motion model ``x_t = D_t x_{t-1} + N(0, Σd_t)``.

    Parameters
    ----------
    F : array, shape (n, n) or (T, n, n)
        Transition matrix ``D``, constant or one per step (``F[t]`` maps step ``t-1`` to ``t``;
        ``F[0]`` is never used, since the first step has no prediction).
    Q : array, shape (n, n) or (T, n, n)
        Process-noise covariance ``Σd``, symmetric positive semi-definite.

    Notes
    -----
    A discrete-time model has no time step: ``F(dt)`` and ``Q(dt)`` accept only ``dt = 1``.
    """

    def __init__(self, F: np.ndarray, Q: np.ndarray):
        F_arr = as_float_array(F, "F", ndim=(2, 3))
        n = F_arr.shape[-1]
        T = F_arr.shape[0] if F_arr.ndim == 3 else None
        self._F = check_matrix_stack(F_arr, "F", n, n, T)
        Q_arr = as_float_array(Q, "Q", ndim=(2, 3))
        T = T if T is not None else (Q_arr.shape[0] if Q_arr.ndim == 3 else None)
        self._Q = check_matrix_stack(Q_arr, "Q", n, n, T)
        check_psd(self._Q, "Q")
        self.ndim_state = n
        self.n_steps = T

    def __repr__(self) -> str:
        return f"LinearMotion(n={self.ndim_state}, steps={self.n_steps or 'constant'})"

    @staticmethod
    def _check_dt(dt: float | np.ndarray) -> None:
        d = np.asarray(dt, dtype=float)
        if not np.all(d == 1.0):
            raise ValueError(
                "LinearMotion is a discrete-time model whose F and Q do not depend on dt; "
                "pass dt=1 (or a per-step F/Q stack), or use a continuous model such as "
                f"ConstantVelocity for variable time steps; got dt={dt!r}"
            )

    def F(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        self._check_dt(dt)
        return self._F[0] if self.n_steps is None else self._F

    def Q(self, dt: float | np.ndarray = 1.0) -> np.ndarray:
        self._check_dt(dt)
        return self._Q[0] if self.n_steps is None else self._Q

    def f(self, x: np.ndarray, dt: float = 1.0) -> np.ndarray:
        if self.n_steps is not None:
            raise ValueError("f(x) needs a constant F; this LinearMotion has one F per step")
        return np.asarray(x) @ self.F(dt).T
