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
    F, Q : array, shape (n, n) or (T, n, n)
        Dynamics ``D`` and its noise covariance ``Σd``; per step when 3-D (``F[t]`` predicts
        step ``t`` from ``t-1``; ``F[0]`` is unused).
    H, R : array, shape (m, n) / (m, m) or (T, m, n) / (T, m, m)
        Measurement matrix ``M`` and its noise covariance ``Σm``.

    Examples
    --------
    The seeds' 2-D constant-velocity example (from Kevin Murphy's toolbox):

    >>> import numpy as np
    >>> F = np.array([[1, 0, 1, 0], [0, 1, 0, 1], [0, 0, 1, 0], [0, 0, 0, 1.0]])
    >>> model = LinearGaussian(F, 0.1 * np.eye(4), np.eye(2, 4), np.eye(2))
    >>> model.ndim_state, model.ndim_meas
    (4, 2)
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
        return self.motion.F()

    @property
    def Q(self) -> np.ndarray:
        return self.motion.Q()

    @property
    def H(self) -> np.ndarray:
        return self.measurement.H()

    @property
    def R(self) -> np.ndarray:
        return self.measurement.R()
