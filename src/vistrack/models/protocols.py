r"""What a model must provide, as :class:`typing.Protocol` classes: the types of the ``motion``
and ``measurement`` arguments of the filters, trackers and samplers.

- Linear models: :class:`MotionModel` (``F(dt)``, ``Q(dt)``, ``ndim_state``) and
  :class:`MeasurementModel` (``H(ndim_state)``, ``R()``, ``ndim_meas``), defined in
  :mod:`vistrack.models.motion` and :mod:`vistrack.models.measurement` and re-exported here;
  :class:`~vistrack.filters.KalmanFilter` takes them.
- Nonlinear models: :class:`NonlinearMotionModel` (``f(x, dt, t)``, ``jacobian(x, dt, t)``,
  ``Q(dt)``, ``ndim_state``) and :class:`NonlinearMeasurementModel` (``h(x)``,
  ``jacobian(x)``, ``R()``); the EKF, the UKF, the ensemble Kalman filter, the particle
  filter and :func:`vistrack.simulate.simulate` take them, and the linear ones too.

Any object with the methods and attributes is a model: nothing needs to subclass these. They
are checkable at run time with ``isinstance``, which looks for the names only, not their
signatures. A model with both ``F`` and ``jacobian`` is taken as nonlinear: the filters look
for ``jacobian`` to tell the two apart.

Optionally, for speed, a nonlinear model may also give its functions for one state as
module-level numba functions: ``jit_f(x, dt, t, params, out)`` and
``jit_jacobian(x, dt, t, params, out)`` for motion, ``jit_h(x, params, out)`` and
``jit_jacobian(x, params, out)`` for measurement, with ``jit_params`` (see
:mod:`vistrack.models.nonlinear`, whose models have them). The particle filter, and the
filters of the EKF and the UKF, then run a whole sequence in one compiled call, where the
compiled functions are the model's own (not inherited by a subclass that overrides ``f`` or
``h``) and the measurement model's ``ndim_state`` is the motion model's. Compiled code does
not check its indices: ``jit_params`` must give every value the compiled functions read.

Examples
--------
>>> from vistrack.models import ConstantVelocity, CoordinatedTurn, Position, RangeBearing
>>> isinstance(CoordinatedTurn(), NonlinearMotionModel)
True
>>> isinstance(ConstantVelocity(dim=2), NonlinearMotionModel)   # no jacobian: linear
False
>>> isinstance(RangeBearing(), NonlinearMeasurementModel), isinstance(Position(), MeasurementModel)
(True, True)
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from .measurement import MeasurementModel
from .motion import MotionModel

__all__ = ["MotionModel", "MeasurementModel", "NonlinearMotionModel", "NonlinearMeasurementModel"]


@runtime_checkable
class NonlinearMotionModel(Protocol):
    r"""What a nonlinear motion model provides: ``f(x, dt, t)``, ``jacobian(x, dt, t)``,
    ``Q(dt)`` and ``ndim_state``.

    .. math:: x_t = f(x_{t-1}, \Delta t, t) + w_t, \qquad w_t \sim N(0, Q(\Delta t)).

    The filters call the three methods with positional arguments, on a batch of states
    ``x (..., n)`` (a state, the sigma points, the members of an ensemble or the particles),
    with ``dt`` a float and ``t`` the time of the predicted state.
    :class:`~vistrack.models.NonlinearMotion` makes one from plain functions;
    :class:`~vistrack.models.CoordinatedTurn` and :class:`~vistrack.models.GrowthMotion` are
    others.

    See Also
    --------
    MotionModel : The linear motion model, ``F(dt)`` and ``Q(dt)``.

    Examples
    --------
    A model of one's own: exponential decay at an uncertain rate.

    >>> class Decay:
    ...     ndim_state = 1
    ...     def f(self, x, dt, t):
    ...         return x * np.exp(-dt)
    ...     def jacobian(self, x, dt, t):
    ...         return np.full(x.shape + (1,), np.exp(-dt))
    ...     def Q(self, dt):
    ...         return np.array([[0.1 * dt]])
    >>> isinstance(Decay(), NonlinearMotionModel)
    True
    >>> from vistrack.filters import ExtendedKalmanFilter
    >>> from vistrack.models import Position
    >>> res = ExtendedKalmanFilter(Decay(), Position(dim=1)).filter(
    ...     [[1.0], [0.4], [0.1]], x0=[1.0], P0=[[1.0]])
    >>> res.means.shape
    (3, 1)
    """

    @property
    def ndim_state(self) -> int:
        """Size ``n`` of the state, at least 1 (an attribute or a property)."""
        ...

    def f(self, x: np.ndarray, dt: float, t: float, /) -> np.ndarray:
        """The mean transition: the states ``x`` moved on by ``dt``, without noise.

        Parameters
        ----------
        x : (..., n) ndarray
            States, one per row.
        dt : float
            Time step.
        t : float
            Time of the predicted state (for time-varying models).

        Returns
        -------
        (..., n) ndarray
            ``f(x, dt, t)``, one predicted state per row of ``x``.

        Examples
        --------
        >>> from vistrack.models import CoordinatedTurn
        >>> CoordinatedTurn().f(np.array([0.0, 0.0, 1.0, 0.0, 0.0]), 2.0, 0.0)
        array([2., 0., 1., 0., 0.])
        """
        ...

    def jacobian(self, x: np.ndarray, dt: float, t: float, /) -> np.ndarray:
        """The Jacobian ``∂f/∂x`` at each state.

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
        >>> from vistrack.models import GrowthMotion
        >>> GrowthMotion().jacobian(np.array([1.0]), 1.0, 0.0)
        array([[0.5]])
        """
        ...

    def Q(self, dt: float, /) -> np.ndarray:
        """Process-noise covariance over a time step.

        Parameters
        ----------
        dt : float
            Time step.

        Returns
        -------
        (n, n) ndarray
            ``Q(dt)``, symmetric positive semi-definite.

        Examples
        --------
        >>> from vistrack.models import GrowthMotion
        >>> GrowthMotion(q=10.0).Q(1.0)
        array([[10.]])
        """
        ...


@runtime_checkable
class NonlinearMeasurementModel(Protocol):
    r"""What a nonlinear measurement model provides: ``h(x)``, ``jacobian(x)`` and ``R()``.

    .. math:: y_t = h(x_t) + v_t, \qquad v_t \sim N(0, R).

    The filters call ``h`` and ``jacobian`` with a batch of states ``x (..., n)`` as the one
    positional argument; the size ``m`` of a measurement is the size of ``R()``.
    :class:`~vistrack.models.NonlinearMeasurement` makes one from plain functions;
    :class:`~vistrack.models.RangeBearing` and :class:`~vistrack.models.GrowthMeasurement` are
    others.

    See Also
    --------
    MeasurementModel : The linear measurement model, ``H(ndim_state)`` and ``R()``.

    Notes
    -----
    The filters use these too when a model has them, and do without otherwise:

    - ``residual(a, b)``: differences of measurements (default ``a - b``);
    - ``mean(z, w)``: the weighted mean of measurements ``z (..., N, m)`` with weights
      ``w (N,)`` (default the weighted sum);
    - ``angles``: the indices of the components that are angles, in radians.

    :class:`~vistrack.models.AngleAwareMeasurement` gives all three; the models of
    :mod:`vistrack.models.nonlinear` also have ``ndim_meas`` and ``ndim_state``.

    Examples
    --------
    A model of one's own: the distance from the origin of a 2-D position.

    >>> class Distance:
    ...     def h(self, x):
    ...         return np.linalg.norm(x[..., :2], axis=-1, keepdims=True)
    ...     def jacobian(self, x):
    ...         return (x[..., :2] / self.h(x))[..., None, :]
    ...     def R(self):
    ...         return np.array([[0.01]])
    >>> isinstance(Distance(), NonlinearMeasurementModel)
    True
    >>> from vistrack.filters import ExtendedKalmanFilter
    >>> from vistrack.models import ConstantPosition
    >>> res = ExtendedKalmanFilter(ConstantPosition(dim=2), Distance()).filter(
    ...     [[5.0], [5.1]], x0=[3.0, 4.0], P0=np.eye(2))
    >>> res.means.shape
    (2, 2)
    """

    def h(self, x: np.ndarray, /) -> np.ndarray:
        """The mean measurement of each state.

        Parameters
        ----------
        x : (..., n) ndarray
            States.

        Returns
        -------
        (..., m) ndarray
            ``h(x)``, one measurement per state.

        Examples
        --------
        >>> from vistrack.models import RangeBearing
        >>> RangeBearing().h(np.array([3.0, 4.0, 0.0, 0.0])).round(4)
        array([5.    , 0.9273])
        """
        ...

    def jacobian(self, x: np.ndarray, /) -> np.ndarray:
        """The Jacobian ``∂h/∂x`` at each state.

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
        >>> from vistrack.models import GrowthMeasurement
        >>> GrowthMeasurement().jacobian(np.array([2.0]))
        array([[0.2]])
        """
        ...

    def R(self) -> np.ndarray:
        """Measurement-noise covariance.

        Returns
        -------
        (m, m) ndarray
            ``R``, symmetric positive definite.

        Examples
        --------
        >>> from vistrack.models import GrowthMeasurement
        >>> GrowthMeasurement(r=2.0).R()
        array([[2.]])
        """
        ...
