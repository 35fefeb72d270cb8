r"""Measurement models: how a state gives rise to a measurement.

.. math:: y_t = H x_t + v_t, \qquad v_t \sim N(0, R),

the seeds' :math:`y_i \sim N(M_i x_i; \Sigma_{m_i})`. ``H(ndim_state)`` builds the measurement
matrix for a state of the given size, so one measurement model serves every motion model.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from .._validate import as_float_array, check_matrix_stack, check_psd

__all__ = ["MeasurementModel", "Position", "LinearMeasurement"]


@runtime_checkable
class MeasurementModel(Protocol):
    """What a linear measurement model provides."""

    ndim_meas: int

    def H(self, ndim_state: int) -> np.ndarray: ...

    def R(self) -> np.ndarray: ...


class Position:
    """Measure the position: the first ``dim`` entries of a derivative-major kinematic state.

    Parameters
    ----------
    dim : {1, 2, 3}
        Number of measured coordinates.
    r : float or array of shape (dim, dim)
        Measurement-noise variance per coordinate (a float gives ``r I``), or the full covariance.

    Examples
    --------
    >>> Position(dim=2, r=4.0).H(4)
    array([[1., 0., 0., 0.],
           [0., 1., 0., 0.]])
    """

    def __init__(self, dim: int = 2, r: float | np.ndarray = 1.0):
        if int(dim) != dim or not 1 <= dim <= 3:
            raise ValueError(f"dim must be 1, 2 or 3; got {dim}")
        self.ndim_meas = int(dim)
        r_arr = as_float_array(r, "r", ndim=(0, 2))
        if r_arr.ndim == 0:
            if not np.isfinite(r_arr) or r_arr <= 0:
                raise ValueError(f"r must be a finite variance > 0; got {float(r_arr)}")
            r_arr = float(r_arr) * np.eye(self.ndim_meas)
        r_arr = check_matrix_stack(r_arr, "r", self.ndim_meas, self.ndim_meas)[0]
        check_psd(r_arr, "r", strict=True)
        self._R = r_arr

    def __repr__(self) -> str:
        return f"Position(dim={self.ndim_meas})"

    def H(self, ndim_state: int) -> np.ndarray:
        if ndim_state < self.ndim_meas:
            raise ValueError(
                f"Position(dim={self.ndim_meas}) needs a state of at least {self.ndim_meas} "
                f"entries; got ndim_state={ndim_state}"
            )
        return np.eye(self.ndim_meas, ndim_state)

    def R(self) -> np.ndarray:
        return self._R.copy()


class LinearMeasurement:
    """A user-given linear measurement ``y = H x + N(0, R)``, constant or one per step.

    Parameters
    ----------
    H : array, shape (m, n) or (T, m, n)
    R : array, shape (m, m) or (T, m, m), symmetric positive semi-definite
    """

    def __init__(self, H: np.ndarray, R: np.ndarray):
        H_arr = as_float_array(H, "H", ndim=(2, 3))
        m, n = H_arr.shape[-2:]
        T = H_arr.shape[0] if H_arr.ndim == 3 else None
        self._H = check_matrix_stack(H_arr, "H", m, n, T)
        R_arr = as_float_array(R, "R", ndim=(2, 3))
        T = T if T is not None else (R_arr.shape[0] if R_arr.ndim == 3 else None)
        self._R = check_matrix_stack(R_arr, "R", m, m, T)
        check_psd(self._R, "R")
        self.ndim_meas = m
        self.ndim_state = n
        self.n_steps = T

    def __repr__(self) -> str:
        return f"LinearMeasurement(m={self.ndim_meas}, n={self.ndim_state})"

    def H(self, ndim_state: int | None = None) -> np.ndarray:
        if ndim_state is not None and ndim_state != self.ndim_state:
            raise ValueError(
                f"this LinearMeasurement's H has {self.ndim_state} columns; "
                f"the motion model's state has {ndim_state}"
            )
        return self._H[0] if self._H.shape[0] == 1 else self._H

    def R(self) -> np.ndarray:
        return self._R[0] if self._R.shape[0] == 1 else self._R
