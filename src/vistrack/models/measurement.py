r"""Measurement models: how a state gives rise to a measurement.

.. math:: y_t = H x_t + v_t, \qquad v_t \sim N(0, R),

the seeds' :math:`y_i \sim N(M_i x_i; \Sigma_{m_i})`. ``H(ndim_state)`` builds the measurement
matrix for a state of the given size, so one measurement model serves every motion model.
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

import numpy as np

from .._validate import as_float_array, check_matrix_stack, check_psd, is_whole

__all__ = ["MeasurementModel", "Position", "LinearMeasurement"]


@runtime_checkable
class MeasurementModel(Protocol):
    """What a linear measurement model provides: ``H(ndim_state)``, ``R()`` and ``ndim_meas``.

    Any object with these is a measurement model for :class:`~vistrack.filters.KalmanFilter`
    and the other filters; the protocol is checkable at run time with ``isinstance`` (which
    looks for the names only, not their signatures).

    Attributes
    ----------
    ndim_meas : int
        Size ``m`` of a measurement.

    Examples
    --------
    >>> isinstance(Position(dim=2), MeasurementModel)
    True
    """

    ndim_meas: int

    def H(self, ndim_state: int) -> np.ndarray:
        """Measurement matrix for a state of ``ndim_state`` entries.

        Parameters
        ----------
        ndim_state : int
            Size ``n`` of the motion model's state.

        Returns
        -------
        (m, n) or (T, m, n) ndarray
            ``H``, constant or one per step.

        Examples
        --------
        >>> Position(dim=1).H(2)
        array([[1., 0.]])
        """
        ...

    def R(self) -> np.ndarray:
        """Measurement-noise covariance.

        Returns
        -------
        (m, m) or (T, m, m) ndarray
            ``R``, symmetric positive (semi-)definite, constant or one per step.

        Examples
        --------
        >>> Position(dim=1, r=2.0).R()
        array([[2.]])
        """
        ...


class Position:
    r"""Measure the position: the first ``dim`` entries of a derivative-major kinematic state.

    .. math:: y = \begin{pmatrix} I_{dim} & 0 \end{pmatrix} x + v, \qquad v \sim N(0, R).

    Parameters
    ----------
    dim : {1, 2, 3}
        Number of measured coordinates.
    r : float or (dim, dim) array_like
        Measurement-noise variance per coordinate (a float gives ``r I``, ``r > 0``), or the
        full covariance (symmetric positive definite).

    Attributes
    ----------
    ndim_meas : int
        ``dim``.

    Raises
    ------
    ValueError
        If ``dim`` is not 1, 2 or 3, or ``r`` is not a finite variance > 0 or a symmetric
        positive definite ``(dim, dim)`` matrix.

    Examples
    --------
    >>> Position(dim=2, r=4.0).H(4)
    array([[1., 0., 0., 0.],
           [0., 1., 0., 0.]])
    """

    def __init__(self, dim: int = 2, r: float | np.ndarray = 1.0):
        if not (is_whole(dim, 1) and dim <= 3):
            raise ValueError(f"dim must be 1, 2 or 3; got {dim!r}")
        self.ndim_meas = int(dim)
        r_arr = as_float_array(r, "r", ndim=(0, 2), not_boolean="a variance or a covariance "
                               "matrix")  # (True was a variance of 1)
        if r_arr.ndim == 0:
            if not np.isfinite(r_arr) or r_arr <= 0:
                raise ValueError(f"r must be a finite variance > 0; got {float(r_arr)}")
            r_arr = float(r_arr) * np.eye(self.ndim_meas)
        r_arr = check_matrix_stack(r_arr, "r", self.ndim_meas, self.ndim_meas)[0]
        check_psd(r_arr, "r", strict=True)
        self._R = r_arr.copy()  # (a view of the caller's array was kept, and used unchecked)

    def __repr__(self) -> str:
        return f"Position(dim={self.ndim_meas})"

    def H(self, ndim_state: int) -> np.ndarray:
        """The matrix that picks the first ``dim`` entries of the state.

        Parameters
        ----------
        ndim_state : int
            Size ``n`` of the state, at least ``dim``.

        Returns
        -------
        (dim, n) ndarray
            ``[I 0]``.

        Raises
        ------
        ValueError
            If ``ndim_state < dim``.

        Examples
        --------
        >>> Position(dim=1).H(3)
        array([[1., 0., 0.]])
        """
        if not is_whole(ndim_state) or ndim_state < self.ndim_meas:
            # (2.5 met numpy's "'float' object cannot be interpreted as an integer")
            raise ValueError(
                f"Position(dim={self.ndim_meas}) needs a state of at least {self.ndim_meas} "
                f"entries, a whole number; got ndim_state={ndim_state!r}"
            )
        return np.eye(self.ndim_meas, int(ndim_state))

    def R(self) -> np.ndarray:
        """The measurement-noise covariance.

        Returns
        -------
        (dim, dim) ndarray
            A copy of ``R``.

        Examples
        --------
        >>> Position(dim=2, r=4.0).R()
        array([[4., 0.],
               [0., 4.]])
        """
        return self._R.copy()


class LinearMeasurement:
    r"""A user-given linear measurement ``y = H x + N(0, R)``, constant or one per step.

    .. math:: y_t = H_t x_t + v_t, \qquad v_t \sim N(0, R_t).

    Parameters
    ----------
    H : (m, n) or (T, m, n) array_like
        Measurement matrix ``M``, constant or one per step.
    R : (m, m) or (T, m, m) array_like
        Measurement-noise covariance ``Σm``, symmetric positive semi-definite, constant or one
        per step (with as many steps as ``H`` when both are per step).

    Attributes
    ----------
    ndim_meas, ndim_state : int
        Sizes ``m`` and ``n``.
    n_steps : int or None
        The number of per-step matrices, None when both are constant.

    Raises
    ------
    ValueError
        If a matrix is not finite or has the wrong shape, the two disagree on the number of
        steps, or ``R`` is not symmetric positive semi-definite.

    Examples
    --------
    >>> meas = LinearMeasurement([[1.0, 1.0]], [[0.5]])
    >>> meas.ndim_meas, meas.ndim_state, meas.H(2)
    (1, 2, array([[1., 1.]]))
    """

    def __init__(self, H: np.ndarray, R: np.ndarray):
        H_arr = as_float_array(H, "H", ndim=(2, 3))
        m, n = H_arr.shape[-2:]
        # a stack of one matrix is the constant, as kalman_filter takes it
        T = H_arr.shape[0] if H_arr.ndim == 3 and H_arr.shape[0] != 1 else None
        self._H = check_matrix_stack(H_arr, "H", m, n, T)
        R_arr = as_float_array(R, "R", ndim=(2, 3))
        T = T if T is not None else (R_arr.shape[0] if R_arr.ndim == 3 and R_arr.shape[0] != 1
                                     else None)
        self._R = check_matrix_stack(R_arr, "R", m, m, T)
        check_psd(self._R, "R")
        # its own copies, and copies given out, as LinearMotion's: the caller's arrays were
        # kept, so an R changed after the check (or through the array R() returned) was used
        # unchecked (a variance of -3)
        self._H, self._R = self._H.copy(), self._R.copy()
        self.ndim_meas = m
        self.ndim_state = n
        self.n_steps = T

    def __repr__(self) -> str:
        return f"LinearMeasurement(m={self.ndim_meas}, n={self.ndim_state})"

    def H(self, ndim_state: int | None = None) -> np.ndarray:
        """The measurement matrix or matrices.

        Parameters
        ----------
        ndim_state : int, optional
            Size of the motion model's state, checked against the columns of ``H``.

        Returns
        -------
        (m, n) or (T, m, n) ndarray
            The constant matrix (also when it was given as a stack of one), or the per-step
            stack.

        Raises
        ------
        ValueError
            If ``ndim_state`` is given and is not ``n``.

        Examples
        --------
        >>> LinearMeasurement(np.ones((5, 1, 2)), [[1.0]]).H().shape
        (5, 1, 2)
        """
        if ndim_state is not None and ndim_state != self.ndim_state:
            raise ValueError(
                f"this LinearMeasurement's H has {self.ndim_state} columns; "
                f"the motion model's state has {ndim_state}"
            )
        return (self._H[0] if self._H.shape[0] == 1 else self._H).copy()

    def R(self) -> np.ndarray:
        """The measurement-noise covariance or covariances.

        Returns
        -------
        (m, m) or (T, m, m) ndarray
            The constant matrix (also when it was given as a stack of one), or the per-step
            stack.

        Examples
        --------
        >>> LinearMeasurement([[1.0, 0.0]], [[0.5]]).R()
        array([[0.5]])
        """
        return (self._R[0] if self._R.shape[0] == 1 else self._R).copy()
