r"""A complete linear-Gaussian state-space model with user-given matrices."""

from __future__ import annotations

import numpy as np

from .measurement import LinearMeasurement
from .motion import LinearMotion

__all__ = ["LinearGaussian"]


class LinearGaussian:
    r"""The seeds' linear dynamic model, with every matrix given by the user.

    .. math::
        x_i \sim N(D_{i-1} x_{i-1}; \Sigma_{d_i}), \qquad y_i \sim N(M_i x_i; \Sigma_{m_i})

    Parameters
    ----------
    F, Q : (n, n) or (T, n, n) array_like
        Dynamics ``D`` and its noise covariance ``Σd``; per step when 3-D (``F[t]`` predicts
        step ``t`` from ``t-1``; ``F[0]`` is unused).
    H, R : (m, n) and (m, m), or (T, m, n) and (T, m, m) array_like
        Measurement matrix ``M`` and its noise covariance ``Σm``.

    Attributes
    ----------
    motion : LinearMotion
        The dynamics ``F``, ``Q``.
    measurement : LinearMeasurement
        The measurement ``H``, ``R``.
    ndim_state, ndim_meas : int
        Sizes ``n`` and ``m``.
    n_steps : int or None
        The number of per-step matrices, None when all four are constant.

    Raises
    ------
    ValueError
        If a matrix is invalid (see :class:`LinearMotion` and :class:`LinearMeasurement`),
        ``H`` does not have ``n`` columns, or per-step matrices disagree on the number of
        steps.

    See Also
    --------
    vistrack.filters.KalmanFilter : Filters and smooths with ``model.motion`` and
        ``model.measurement``.

    Examples
    --------
    The seeds' 2-D constant-velocity example (from Kevin Murphy's toolbox):

    >>> import numpy as np
    >>> F = np.array([[1, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    >>> model = LinearGaussian(F, 0.1 * np.eye(4), np.eye(2, 4), np.eye(2))
    >>> model.ndim_state, model.ndim_meas
    (4, 2)
    >>> from vistrack.filters import KalmanFilter
    >>> kf = KalmanFilter(model.motion, model.measurement)
    >>> kf.filter(np.zeros((6, 2))).means.shape
    (6, 4)
    """

    def __init__(self, F: np.ndarray, Q: np.ndarray, H: np.ndarray, R: np.ndarray):
        self.motion = LinearMotion(F, Q)
        self.measurement = LinearMeasurement(H, R)
        if self.measurement.ndim_state != self.motion.ndim_state:
            raise ValueError(
                f"H has {self.measurement.ndim_state} columns but F is "
                f"{self.motion.ndim_state}x{self.motion.ndim_state}"
            )
        steps = {s for s in (self.motion.n_steps, self.measurement.n_steps) if s is not None}
        if len(steps) > 1:
            raise ValueError(f"per-step matrices disagree on the number of steps: {sorted(steps)}")
        self.ndim_state = self.motion.ndim_state
        self.ndim_meas = self.measurement.ndim_meas
        self.n_steps = steps.pop() if steps else None

    def __repr__(self) -> str:
        return (
            f"LinearGaussian(n={self.ndim_state}, m={self.ndim_meas}, "
            f"steps={self.n_steps or 'constant'})"
        )

    @property
    def F(self) -> np.ndarray:
        """Transition matrix ``D``: ``(n, n)`` when neither ``F`` nor ``Q`` is per step,
        ``(T, n, n)`` when ``F`` is, and ``(1, n, n)`` when ``F`` is constant beside a
        per-step ``Q``, as :meth:`LinearMotion.F` gives it.

        Examples
        --------
        >>> LinearGaussian(np.eye(2), np.eye(2), [[1.0, 0.0]], [[1.0]]).F.shape
        (2, 2)
        """
        return self.motion.F()

    @property
    def Q(self) -> np.ndarray:
        """Process-noise covariance ``Σd``: ``(n, n)`` when neither ``F`` nor ``Q`` is per
        step, ``(T, n, n)`` when ``Q`` is, and ``(1, n, n)`` when ``Q`` is constant beside a
        per-step ``F``, as :meth:`LinearMotion.Q` gives it.

        Examples
        --------
        >>> LinearGaussian(np.eye(2), np.eye(2), [[1.0, 0.0]], [[1.0]]).Q.shape
        (2, 2)
        """
        return self.motion.Q()

    @property
    def H(self) -> np.ndarray:
        """Measurement matrix ``M``, ``(m, n) or (T, m, n)``.

        As :meth:`LinearMeasurement.H` gives it.

        Examples
        --------
        >>> LinearGaussian(np.eye(2), np.eye(2), [[1.0, 0.0]], [[1.0]]).H.shape
        (1, 2)
        """
        return self.measurement.H()

    @property
    def R(self) -> np.ndarray:
        """Measurement-noise covariance ``Σm``, ``(m, m) or (T, m, m)``.

        As :meth:`LinearMeasurement.R` gives it.

        Examples
        --------
        >>> LinearGaussian(np.eye(2), np.eye(2), [[1.0, 0.0]], [[1.0]]).R.shape
        (1, 1)
        """
        return self.measurement.R()
