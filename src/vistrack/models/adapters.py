"""Any motion or measurement model seen as the functions the nonlinear filters and the
simulator call: :class:`MotionFunctions` (``f``, ``jacobian``, ``Q``) and
:class:`MeasurementFunctions` (``h``, ``jacobian``, ``R``, ``residual``, ``mean``), for linear
and nonlinear models alike, and :func:`psd_sqrt`, the square root the samplers draw noise
with."""

from __future__ import annotations

import copy
import threading
from collections.abc import Callable
from functools import partial
from typing import cast

import numpy as np

from .._validate import as_float_array, check_finite, check_psd, correlation
from .nonlinear import AngleAwareMeasurement, _offset_mean, _residual, _weighted_mean
from .protocols import (
    MeasurementModel,
    MotionModel,
    NonlinearMeasurementModel,
    NonlinearMotionModel,
)

__all__ = ["MotionFunctions", "MeasurementFunctions", "psd_sqrt"]


def check_not_box_motion(model: object, name: str = "motion") -> None:
    """Refuse :class:`~vistrack.models.BoxMotion` as a filter's motion model: its noise,
    ``Q(boxes, dt)``, scales with the boxes' sizes (the box trackers' own), and a filter took
    it and failed at its first step on "boxes must have shape (K, 4)", an argument the caller
    never gave."""
    from .box import BoxMotion

    if isinstance(model, BoxMotion):
        raise TypeError(f"{name} is a BoxMotion, whose noise Q(boxes, dt) follows the boxes' "
                        "sizes (the box trackers' model); give a filter a motion model whose "
                        "Q(dt) takes the time step alone (ConstantVelocity(dim=4), say)")


def psd_sqrt(S: np.ndarray, name: str = "S") -> np.ndarray:
    """The principal square root ``A`` (symmetric, ``A A' = A A = S``) of each of a stack of
    positive semi-definite matrices, from the eigendecomposition (singular matrices allowed:
    process noise often acts on some states only).

    It is unique, so noise drawn as ``eps @ A.T`` is the same on every machine to rounding.
    The eigenvectors alone are not: where eigenvalues repeat (``4 I``; the x and y blocks of
    a constant-velocity model's ``Q``), LAPACK may return any orthonormal basis of their
    space, and ``V diag(sqrt(w))``, the root this returned before, changed the draws of a
    seeded simulation from one processor to another.

    Where the variances span so many orders that the eigenvalues' rounding (relative to the
    largest) swallows real noise (a constant-acceleration ``Q`` at ``dt`` 1e-4: its least
    eigenvalue, 1/36 of the position's variance, fell under the cut, and the root gave the
    position 35/36 of its variance; at 1e-5 a variance 4.7 times too large), the root is
    taken of the correlation matrix instead, ``A = D C^{1/2}`` with ``D = diag(S)^{1/2}``
    and ``C = D^{-1} S D^{-1}``: not symmetric, still unique, ``A A' = S`` to rounding.

    Parameters
    ----------
    S : (..., n, n) array_like
        Symmetric positive semi-definite matrices.
    name : str
        What the caller calls ``S``, for the errors.

    Returns
    -------
    (..., n, n) ndarray
        ``A`` with ``A A' = S`` (eigenvalues within rounding of 0, or negative from
        rounding, taken as 0).

    Raises
    ------
    ValueError
        If ``S`` is not a stack of square matrices, or one is not finite, not symmetric (to
        1e-8 of its largest entry), or has an eigenvalue below -1e-10 of its largest entry
        (:func:`~vistrack._validate.check_psd`, whose words these are): ``diag(1, -1)`` gave
        the root of ``diag(1, 0)``, and a triangular matrix the root of the symmetric matrix
        of its lower triangle, without a word.

    Examples
    --------
    >>> import numpy as np
    >>> S = np.array([[4.0, 0.0], [0.0, 0.0]])
    >>> A = psd_sqrt(S)
    >>> bool(np.allclose(A @ A.T, S))
    True
    >>> psd_sqrt(np.array([[1.0, 2.0], [2.0, 1.0]]))
    Traceback (most recent call last):
    ...
    ValueError: S must be positive semi-definite; its smallest eigenvalue is -1
    """
    S = as_float_array(S, name)
    if S.ndim < 2 or S.shape[-1] != S.shape[-2]:
        raise ValueError(f"{name} must be square matrices (..., n, n); got shape {S.shape}")
    check_finite(S, name)
    check_psd(S, name)
    if S.shape[-1] == 0:  # the root of a matrix of no entries is one (numpy's words before)
        return S.copy()
    w, V = np.linalg.eigh(S)
    A = _principal_root(w, V)
    d = np.diagonal(S, axis1=-2, axis2=-1)
    # each variance as the root gives it, against S's own: within rounding where the scales
    # are near one another, off by a share where they span more than the eigenvalues hold
    got = (A * A).sum(axis=-1)
    tol = np.where(d > 0, 1e-8 * d, w.shape[-1] * np.finfo(float).eps
                   * np.abs(w).max(axis=-1, keepdims=True))
    off = (np.abs(got - d) > tol).any(axis=-1)
    if off.any():
        C, s = correlation(S[off])  # (a zero variance: its row and column are 0)
        A[off] = np.where(s > 0, s, 1.0)[..., :, None] * _principal_root(*np.linalg.eigh(C))
    return A


def _principal_root(w: np.ndarray, V: np.ndarray) -> np.ndarray:
    """:func:`psd_sqrt` from the eigendecomposition ``w, V`` (``np.linalg.eigh``'s), for a
    caller that has it already (to check the eigenvalues first)."""
    # eigenvalues within rounding of 0 (n eps of the largest) are 0: the square root of a
    # rounding error (1e-8 of the scale) would carry its sign and size, which vary by processor
    tiny = w.shape[-1] * np.finfo(float).eps * np.abs(w).max(axis=-1, keepdims=True)
    w = np.where(w > tiny, w, 0.0)
    return (V * np.sqrt(w)[..., None, :]) @ np.swapaxes(V, -1, -2)


class MotionFunctions:
    """A linear or nonlinear motion model seen as functions: ``f(x, dt, t)``,
    ``jacobian(x, dt, t)``, ``Q(dt)`` and ``Q_sqrt(dt)``.

    For a linear model (``F(dt)``, :class:`~vistrack.models.protocols.MotionModel`),
    ``f(x) = F x`` and the Jacobian is ``F``; a nonlinear one
    (:class:`~vistrack.models.protocols.NonlinearMotionModel`) is used as it is. ``Q`` and its
    square root are computed once per distinct ``dt``. It is itself a nonlinear motion model,
    which is how the EKF, UKF, ensemble and particle filters and
    :func:`vistrack.simulate.simulate` see every model.

    Parameters
    ----------
    model : MotionModel or NonlinearMotionModel
        The model.

    Attributes
    ----------
    model
        The model given.
    n : int
        The state's size (also ``ndim_state``).
    linear : bool
        Whether the model is linear (has ``F`` and no ``jacobian``).

    Raises
    ------
    TypeError
        If ``model`` is neither kind of motion model, or its ``ndim_state`` is below 1.

    Examples
    --------
    >>> import numpy as np
    >>> from vistrack.models import ConstantVelocity
    >>> mo = MotionFunctions(ConstantVelocity(dim=1, q=0.1))
    >>> mo.f(np.array([[0.0, 2.0]]), 0.5, 0.0), mo.linear, mo.ndim_state
    (array([[1., 2.]]), True, 2)
    """

    def __init__(self, model: MotionModel | NonlinearMotionModel):
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
        check_not_box_motion(model)
        steps = getattr(model, "n_steps", None)
        if self.linear and steps is not None:
            # F (T, n, n) per step: f and jacobian took the stack for one matrix (a state of
            # (1, n) came back (1, 1, n))
            raise ValueError(f"motion has per-step matrices ({steps} steps), which the "
                             "nonlinear filters do not take; give one F and Q (kalman_filter "
                             "takes per-step ones)")
        self._Q: dict = {}
        self._Q_sqrt: dict = {}
        self._seen: tuple = ()

    @classmethod
    def of(cls, motion: MotionModel | NonlinearMotionModel | MotionFunctions
           ) -> MotionFunctions:
        """The functions of ``motion``: a model's, or functions already made, as they are
        (their kept ``Q`` kept).

        >>> from vistrack.models import ConstantVelocity
        >>> mo = MotionFunctions.of(ConstantVelocity(dim=1, q=0.1))
        >>> MotionFunctions.of(mo) is mo
        True
        """
        return motion if isinstance(motion, MotionFunctions) else cls(motion)

    @property
    def ndim_state(self) -> int:
        """The state's size, as a motion model gives it."""
        return self.n

    def f(self, x: np.ndarray, dt: float, t: float) -> np.ndarray:
        """``x_t = f(x, dt, t)`` for states ``x (..., n)``."""
        if self.linear:
            F = cast(MotionModel, self.model).F(dt)
            # a dt per state gives F (K, n, n): .T reversed all three axes (wrong states,
            # of the wrong shape, without a word)
            return x @ F.T if F.ndim == 2 else (F @ x[..., None])[..., 0]
        out = cast(NonlinearMotionModel, self.model).f(x, dt, t)
        if np.shape(out) != np.shape(x):
            # (the ensemble filter kept members of the wrong size and the unscented filter
            # read zeros past them, without a word; the EKF named its Gaussian's shapes)
            raise ValueError(f"the motion model's f(x, dt, t) gives values of shape "
                             f"{np.shape(out)} for states of shape {np.shape(x)}; its "
                             f"ndim_state is {self.n}, so {np.shape(x)} was expected")
        return out

    def jacobian(self, x: np.ndarray, dt: float, t: float) -> np.ndarray:
        """``∂f/∂x (..., n, n)`` at states ``x (..., n)``."""
        if self.linear:
            return np.broadcast_to(cast(MotionModel, self.model).F(dt), x.shape + (self.n,))
        return cast(NonlinearMotionModel, self.model).jacobian(x, dt, t)

    def _current(self) -> None:
        """Forget the kept ``Q`` where a model's setting was set since (as
        ``KalmanFilter.fit`` sets its copies' ``q``): kept under ``dt`` alone, the old
        ``Q`` was used. A setting is compared by identity, and an array setting by its
        values too (against a copy), so an array changed in place is seen as well."""
        state = getattr(self.model, "__dict__", None)
        values = () if state is None else tuple(state.values())
        seen = self._seen
        if len(values) != len(seen) or any(
                a is not b or (c is not None and not np.array_equal(a, c))
                for a, (b, c) in zip(values, seen)):
            self._Q.clear()
            self._Q_sqrt.clear()
            # (each value held, so no identity is reused; arrays copied as they were)
            self._seen = tuple((v, v.copy() if isinstance(v, np.ndarray) else None)
                               for v in values)

    def Q(self, dt: float) -> np.ndarray:
        """``Q(dt)``, computed once per ``dt`` among the last few distinct ones while the
        model's settings stay as they are (timestamps that never repeat a step keep no more
        than those)."""
        self._current()
        key = float(dt)  # (a 0-d array is not hashable)
        Q = self._Q.get(key)
        if Q is None:
            Q = np.asarray(self.model.Q(dt), dtype=float)
            # checked once for each dt, as kept: the EKF took a Q with a negative eigenvalue
            # and gave covariances with one too, without a word (the particle filter's square
            # root clipped it; Q = -I was named as R)
            _check_noise_matrix(Q, self.n, f"motion.Q({key:g})")
            Q = _remember(self._Q, key, Q)
        return Q

    def Q_sqrt(self, dt: float) -> np.ndarray:
        """:func:`psd_sqrt` of ``Q(dt)``, as :meth:`Q` keeps it: noise = eps @ Q_sqrt.T."""
        self._current()
        key = float(dt)  # (a 0-d array is not hashable)
        A = self._Q_sqrt.get(key)
        if A is None:
            A = _remember(self._Q_sqrt, key, np.ascontiguousarray(psd_sqrt(self.Q(dt))))
        return A


_KEPT = 16
"""How many distinct time steps' ``Q`` a model's functions keep."""

_CHECKED: dict[tuple, None] = {}
_CHECKED_LOCK = threading.Lock()


def _check_noise_matrix(Q: np.ndarray, n: int, name: str, size: str = "the state's") -> None:
    """A model's ``Q`` checked (shape ``(n, n)``, finite, symmetric positive semi-definite),
    or found among the last few matrices that passed, by their values: the filters' steps
    called one at a time (``ekf_predict``, ``ukf_predict``) make a model's functions afresh
    each call, and its eigenvalues cost a step half its time again."""
    if Q.shape != (n, n):
        raise ValueError(f"{name} must have shape ({n}, {n}), {size}; got {Q.shape}")
    key = (n, Q.tobytes())
    if key in _CHECKED:
        return
    check_finite(Q, name)
    check_psd(Q, name)
    with _CHECKED_LOCK:  # (threads filtering at once)
        while len(_CHECKED) >= 64:
            del _CHECKED[next(iter(_CHECKED))]
        _CHECKED[key] = None


def _remember(cache: dict, key: float, value: np.ndarray) -> np.ndarray:
    """``value`` kept under ``key``, the oldest entry dropped past :data:`_KEPT`."""
    if len(cache) >= _KEPT:
        del cache[next(iter(cache))]
    cache[key] = value
    return value


def _plain_residual(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    return a - b


def _plain_mean(z: np.ndarray, w: np.ndarray) -> np.ndarray:
    return _offset_mean(z, w)


class MeasurementFunctions:
    """A linear or nonlinear measurement model seen as functions: ``h(x)``, ``jacobian(x)``,
    ``R()``, ``residual(a, b)`` and ``mean(z, w)``.

    For a linear model (``H``, ``R``) ``h(x) = H x``; residuals are differences (a model's own
    ``residual`` and ``mean``, such as those of angle-aware models, are used when it has them)
    unless given here. It is itself a nonlinear measurement model.

    Parameters
    ----------
    model : MeasurementModel or NonlinearMeasurementModel
        The model.
    n : int
        The state's size (for a linear model's ``H(n)``).
    residual, mean : callable, optional
        ``residual(a, b)`` and ``mean(z, w)`` overriding the model's.

    Attributes
    ----------
    model
        The model given.
    m : int
        The measurement's size.
    Rm : (m, m) ndarray
        The noise covariance (also ``R()``).
    linear : bool
        Whether the model is linear.
    standard : bool
        Whether residuals are differences (angles wrapped) and means weighted sums (circular
        for angles), the model's own neither: then the UKF (its compiled one-Gaussian
        kernel and its batch alike) averages about the central sigma point, angles'
        differences wrapped.
    angle_mask : (m,) ndarray of bool
        The components that are angles.

    Raises
    ------
    TypeError
        If ``model`` is neither kind of measurement model.

    Examples
    --------
    >>> import numpy as np
    >>> from vistrack.models import Position
    >>> me = MeasurementFunctions(Position(dim=1, r=0.5), 2)
    >>> me.h(np.array([[3.0, 1.0]])), me.R(), me.m
    (array([[3.]]), array([[0.5]]), 1)
    """

    def __init__(self, model: MeasurementModel | NonlinearMeasurementModel, n: int,
                 residual: Callable | None = None, mean: Callable | None = None):
        self.model = model
        self.linear = hasattr(model, "H") and not hasattr(model, "jacobian")
        if self.linear:
            steps = getattr(model, "n_steps", None)
            if steps is not None:
                # H (T, m, n) or R (T, m, m) per step: h failed in matmul, R was taken for one
                # covariance
                raise ValueError(f"measurement has per-step matrices ({steps} steps), "
                                 "which the nonlinear filters do not take; give one H and R "
                                 "(kalman_filter takes per-step ones)")
            self.H = np.asarray(cast(MeasurementModel, model).H(n), dtype=float)
        elif not (callable(getattr(model, "h", None))
                  and callable(getattr(model, "jacobian", None))):
            raise TypeError(
                f"measurement must be a measurement model with H and R, or h(x), jacobian(x) "
                f"and R(); got {type(model).__name__}"
            )
        self.Rm = np.asarray(model.R(), dtype=float)
        self.m = self.Rm.shape[-1] if self.Rm.ndim else 1
        # checked as Q is: a negative variance gave posteriors with one too, an asymmetric R
        # was read by its lower triangle in the UKF and whole in the EKF
        _check_noise_matrix(self.Rm, self.m, "measurement.R()", "the measurement's")
        angles = tuple(int(k) for k in getattr(model, "angles", ()))
        # a model with angles but no residual or mean of its own: its angles wrapped and
        # averaged on the circle all the same (the ensemble KF's mean; the UKF, compiled or
        # not, averages them about its central sigma point: angle_mask)
        self.residual = residual or getattr(model, "residual", None) or (
            partial(_residual, angles=angles) if angles else _plain_residual)
        self.mean = mean or getattr(model, "mean", None) or (
            partial(_weighted_mean, angles=angles) if angles else _plain_mean)
        # "standard": residuals are differences (angles wrapped) and means weighted sums
        # (circular for angles), which the UKF replaces by its sums about the central sigma
        # point (compiled for one Gaussian, numpy for a batch); a model,
        # linear or not, with a residual or mean of its own is not (a linear sensor of a
        # heading wraps its residual)
        own = type(model)
        self.standard = residual is None and mean is None and (
            (getattr(own, "residual", None) is AngleAwareMeasurement.residual
             and getattr(own, "mean", None) is AngleAwareMeasurement.mean)
            or not (hasattr(model, "residual") or hasattr(model, "mean")))
        self.angle_mask = np.zeros(self.m, dtype=np.bool_)
        self.angle_mask[list(getattr(model, "angles", ()))] = True

    @classmethod
    def of(cls, measurement: MeasurementModel | NonlinearMeasurementModel | MeasurementFunctions,
           n: int, residual: Callable | None = None,
           mean: Callable | None = None) -> MeasurementFunctions:
        """The functions of ``measurement``, a model or functions already made, with
        ``residual`` and ``mean`` in place of its own where given (functions already made
        kept theirs, and the ones given were not used).

        Examples
        --------
        >>> from vistrack.models import Position
        >>> me = MeasurementFunctions(Position(dim=1, r=0.5), 2)
        >>> MeasurementFunctions.of(me, 2) is me
        True
        >>> flip = MeasurementFunctions.of(me, 2, residual=lambda a, b: b - a)
        >>> flip.residual(np.array([1.0]), np.array([3.0])), flip.standard
        (array([2.]), False)
        """
        if not isinstance(measurement, MeasurementFunctions):
            return cls(measurement, n, residual, mean)
        if residual is None and mean is None:
            return measurement
        out = copy.copy(measurement)
        out.residual = residual or measurement.residual
        out.mean = mean or measurement.mean
        out.standard = False
        return out

    def R(self) -> np.ndarray:
        """The noise covariance ``(m, m)``, as a measurement model gives it."""
        return self.Rm

    def h(self, x: np.ndarray) -> np.ndarray:
        """The noise-free measurement ``h(x) (..., m)`` of states ``x (..., n)``."""
        return x @ self.H.T if self.linear else cast(NonlinearMeasurementModel, self.model).h(x)

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """``∂h/∂x (..., m, n)`` at states ``x (..., n)``."""
        if self.linear:
            return np.broadcast_to(self.H, x.shape[:-1] + self.H.shape)
        return cast(NonlinearMeasurementModel, self.model).jacobian(x)
