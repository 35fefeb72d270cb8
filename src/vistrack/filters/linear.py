"""The linear-Gaussian filter as an object: a motion and a measurement model in; whole
sequences filtered or smoothed, or one target followed a measurement at a time, out. The
equations are :mod:`vistrack.filters.kalman`'s and :mod:`vistrack.filters.smoothers`'."""

from __future__ import annotations

import copy
from dataclasses import replace
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validate import (
    as_finite,
    as_float_array,
    as_measurement_series,
    check_has_steps,
    check_matrix_stack,
    check_one_step,
    check_psd,
    is_real,
)
from ..models.adapters import check_not_box_motion
from ..models.measurement import LinearMeasurement, MeasurementModel, Position
from ..models.motion import MotionModel
from ..types import Gaussian
from . import _kernels
from .kalman import FilterResult, _kernel_error, _prior, _update, kalman_filter, kf_predict
from .learn import FitResult, _names, _state_size, em, mle
from .smoothers import SmoothResult, rts_smooth

__all__ = ["KalmanFilter", "OnlineFilter"]


def dt_steps(dt: ArrayLike, T: int) -> np.ndarray | float:
    """``dt`` for ``T`` steps: a scalar as a float, else ``(T,)`` with ``dt[t]`` the step from
    ``t-1`` to ``t``. Step 0 has no prediction, so ``dt[0]`` is unused: given the first
    interval's value (1 for one step), whether the ``T-1`` intervals were given or ``T``
    values, so that a model that checks its steps (``LinearMotion`` takes 1 alone) sees none
    it would refuse (a 0 the user never gave, or the NaN of ``np.diff(times,
    prepend=np.nan)``)."""
    # (True was a step of 1 here, where the models refuse it; None was "got nan")
    if dt is None:
        raise ValueError("dt must be a number or an array of numbers; got None")
    d = as_float_array(dt, "dt", ndim=(0, 1), not_boolean="a number or an array of numbers")
    if d.ndim == 0:
        return float(d)
    if d.shape[0] == T - 1:
        d = np.concatenate([[np.nan], d])
    if d.shape[0] != T:
        raise ValueError(
            f"dt must be a scalar, the T-1={T - 1} intervals between steps or T={T} values "
            f"(dt[0] unused); got shape {d.shape}"
        )
    d = d.copy()
    d[0] = d[1] if T > 1 else 1.0
    return d


class KalmanFilter:
    """A Kalman filter built from a motion model and a measurement model.

    Parameters
    ----------
    motion : MotionModel
        Gives ``F(dt)``, ``Q(dt)`` (e.g. :class:`vistrack.models.ConstantVelocity`).
    measurement : MeasurementModel
        Gives ``H(n)``, ``R()`` (e.g. :class:`vistrack.models.Position`).

    Attributes
    ----------
    motion, measurement
        The models.

    Raises
    ------
    TypeError
        If a model lacks one of the attributes it must provide (``F``, ``Q``, ``ndim_state``;
        ``H``, ``R``, ``ndim_meas``).

    See Also
    --------
    kalman_filter : The filter on matrices.
    rts_smooth : The smoother.

    Examples
    --------
    >>> import numpy as np
    >>> from vistrack.models import ConstantVelocity, Position
    >>> kf = KalmanFilter(ConstantVelocity(dim=2, q=0.1), Position(dim=2, r=1.0))
    >>> ys = np.c_[np.arange(10.0), 2 * np.arange(10.0)]
    >>> smoothed = kf.smooth(ys)
    >>> smoothed.means.shape
    (10, 4)
    """

    def __init__(self, motion: MotionModel, measurement: MeasurementModel):
        for name, obj, attrs in (
            ("motion", motion, ("F", "Q", "ndim_state")),
            ("measurement", measurement, ("H", "R", "ndim_meas")),
        ):
            missing = [a for a in attrs if not hasattr(obj, a)]
            if missing:
                raise TypeError(f"{name} must provide {', '.join(attrs)}; "
                                f"{type(obj).__name__} lacks {', '.join(missing)}")
        check_not_box_motion(motion)
        # a position measured in more dimensions than the motion has would read its rates as
        # positions (Position(dim=3) of a 2-D constant velocity: x, y and vx)
        from ..models.measurement import Position

        if isinstance(measurement, Position) and isinstance(getattr(motion, "dim", None), int) \
                and measurement.ndim_meas > motion.dim:  # type: ignore[attr-defined]
            raise ValueError(f"measurement {measurement!r} measures {measurement.ndim_meas} "
                             f"position components, but motion {motion!r} moves in "
                             f"{motion.dim}")  # type: ignore[attr-defined]
        self.motion = motion
        self.measurement = measurement

    def __repr__(self) -> str:
        return f"KalmanFilter({self.motion!r}, {self.measurement!r})"

    def _check_ys(self, ys: ArrayLike) -> None:
        """Refuse a series whose last axis is not the measurement's size, naming both (numpy
        would say it as a matrix product's mismatch)."""
        shape = np.shape(ys)
        m = self.measurement.ndim_meas
        if len(shape) in (2, 3) and shape[-1] != m:
            raise ValueError(f"ys must have shape (T, {m}) or (B, T, {m}): {m} values a step, "
                             f"as {self.measurement!r} measures; got {shape}")

    def matrices(self, T: int, dt: ArrayLike = 1.0) -> dict[str, np.ndarray]:
        """The matrices ``F, Q, H, R`` of the models for ``T`` steps with time step(s) ``dt``.

        Parameters
        ----------
        T : int
            Number of steps.
        dt : float or array_like
            A scalar, the ``T-1`` intervals between steps, or ``T`` values (``dt[0]``
            unused).

        Returns
        -------
        dict of str to ndarray
            ``F`` and ``Q``: ``(n, n)`` for a scalar ``dt``, else ``(T, n, n)``; ``H`` and
            ``R`` as the measurement model gives them. The keyword arguments of
            :func:`kalman_filter`.

        Raises
        ------
        ValueError
            If ``dt`` has another length, or a model rejects it.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> kf = KalmanFilter(ConstantVelocity(dim=1), Position(dim=1))
        >>> {k: v.shape for k, v in kf.matrices(3, dt=[0.5, 2.0]).items()}
        {'F': (3, 2, 2), 'Q': (3, 2, 2), 'H': (1, 2), 'R': (1, 1)}
        """
        n = self.motion.ndim_state
        d = dt_steps(dt, T)
        return {
            "F": self.motion.F(d),
            "Q": self.motion.Q(d),
            "H": self.measurement.H(n),
            "R": self.measurement.R(),
        }

    def predict(self, g: Gaussian, dt: float = 1.0, t: float = 0.0) -> Gaussian:
        """One prediction of a batch by the motion model: :func:`kf_predict` with ``F(dt)``,
        ``Q(dt)``.

        Parameters
        ----------
        g : Gaussian
            Estimates, batch shape ``(...)``.
        dt : float
            Time step.
        t : float
            Time of the predicted state (unused by linear models; there for the signature
            every filter class shares).

        Returns
        -------
        Gaussian
            The predictions.

        Examples
        --------
        >>> from vistrack import Gaussian
        >>> from vistrack.models import ConstantVelocity, Position
        >>> kf = KalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1, r=0.5))
        >>> kf.predict(Gaussian(np.array([0.0, 1.0]), np.eye(2)), dt=2.0).mean
        array([2., 1.])
        """
        check_one_step(dt)
        self._check_state(g)
        return kf_predict(g, self.motion.F(dt), self.motion.Q(dt))

    def _check_state(self, g: Gaussian) -> None:
        """Name ``g`` whose state size is not the motion model's (the model's ``F`` or
        ``H`` was named instead: matrices the caller never gave)."""
        n = self.motion.ndim_state
        if isinstance(g, Gaussian) and g.mean.shape[-1] != n:
            raise ValueError(f"g must have a state of {n} values, the motion model's "
                             f"({type(self.motion).__name__}); got {g.mean.shape[-1]} "
                             f"(g.mean of shape {g.mean.shape})")

    def update(self, g: Gaussian, y: ArrayLike) -> tuple[Gaussian, np.ndarray]:
        """One correction by the measurement model (:func:`kf_update`) and its log-likelihood.

        Parameters
        ----------
        g : Gaussian
            Predictions, batch shape ``(...)``.
        y : (..., m) array_like
            One measurement per Gaussian; NaN components are missing.

        Returns
        -------
        posterior : Gaussian
            The corrected estimates.
        loglik : (...) ndarray
            ``log N(y; H m, H P H' + R)`` over the observed components; 0 where none is.

        Examples
        --------
        >>> from vistrack import Gaussian
        >>> from vistrack.models import ConstantVelocity, Position
        >>> kf = KalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1, r=0.5))
        >>> post, ll = kf.update(Gaussian(np.array([0.0, 1.0]), np.eye(2)), [1.5])
        >>> post.mean.round(3), round(float(ll), 3)
        (array([1., 1.]), -1.872)
        """
        n = self.motion.ndim_state
        self._check_state(g)
        return _update(g, y, self.measurement.H(n), self.measurement.R())

    def default_prior(self, ys: ArrayLike, *,
                      scale: float = 1e3) -> tuple[np.ndarray, np.ndarray]:
        r"""A weak prior from the first measurement of each series.

        ``x0`` is the least-squares state ``H⁺ y`` of the first non-missing value of each
        component (0 where a component is never observed), and ``P0`` is ``R`` on the measured
        subspace and ``scale² · max(diag R)`` on the rest of the state:

        .. math::

            x_0 = H^+ y_\text{first}, \qquad
            P_0 = H^+ R H^{+\prime} + s^2 \max_i R_{ii} \, (I - H^+ H).

        Per-step ``H`` and ``R`` use their first step.

        Parameters
        ----------
        ys : (T, m) or (B, T, m) array_like
            Measurements, NaN (or masked, in a numpy masked array) where missing.
        scale : float
            The prior's standard deviation on the unmeasured part of the state, in units of
            the largest measurement standard deviation: a finite number >= 0.

        Returns
        -------
        x0 : (n,) or (B, n) ndarray
            One prior mean per series.
        P0 : (n, n) ndarray
            One prior covariance for all series.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> kf = KalmanFilter(ConstantVelocity(dim=1), Position(dim=1, r=1.0))
        >>> x0, P0 = kf.default_prior(np.array([[np.nan], [2.0], [3.0]]))
        >>> x0, P0.diagonal()
        (array([2., 0.]), array([1.e+00, 1.e+06]))
        """
        self._check_ys(ys)
        # (NaN gave a prior of NaN, a string numpy's words, and -2 was taken as 2; 0, a
        # prior of no variance off the measured part, is one)
        scale = as_finite(scale, "scale", 0.0)
        y, single = as_measurement_series(ys)
        check_has_steps(y[0] if single else y)
        n = self.motion.ndim_state
        H = np.asarray(self.measurement.H(n), dtype=float)
        R = np.asarray(self.measurement.R(), dtype=float)
        H0, R0 = (H[0] if H.ndim == 3 else H), (R[0] if R.ndim == 3 else R)
        ok = ~np.isnan(y)
        first = np.where(ok.any(axis=1), np.argmax(ok, axis=1), 0)  # (B, m)
        y_first = np.take_along_axis(y, first[:, None, :], axis=1)[:, 0]
        y_first = np.nan_to_num(y_first)
        Hp = np.linalg.pinv(H0)
        x0 = y_first @ Hp.T
        proj = Hp @ H0
        P0 = Hp @ R0 @ Hp.T + scale**2 * np.max(np.diag(R0)) * (np.eye(n) - proj)
        P0 = 0.5 * (P0 + P0.T)
        return (x0[0] if np.ndim(ys) == 2 else x0), P0

    def filter(
        self,
        ys: ArrayLike,
        *,
        dt: ArrayLike = 1.0,
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        store_covs: bool = True,
    ) -> FilterResult:
        """Filter a sequence, or a batch of them; see :func:`kalman_filter` for the equations.

        Parameters
        ----------
        ys : (T, m) or (B, T, m) array_like
            Measurements; NaN components (or masked entries of a numpy masked array) are
            missing.
        dt : float or array_like
            A scalar, the ``T-1`` intervals between steps, or ``T`` values with ``dt[0]``
            unused.
        x0 : (n,) or (B, n) array_like, optional
            Prior mean of the first step; from :meth:`default_prior` if None.
        P0 : (n, n) or (B, n, n) array_like, optional
            Prior covariance of the first step; from :meth:`default_prior` if None.
        store_covs : bool
            Keep the covariances and predictions (see :func:`kalman_filter`).

        Returns
        -------
        FilterResult
            Means ``(..., T, n)``, covariances ``(..., T, n, n)``, the log-likelihood and the
            last estimate; ``(...)`` is ``()`` or ``(B,)``.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> kf = KalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1, r=1.0))
        >>> kf.filter(np.arange(5.0)[:, None]).means[-1].round(3)
        array([4., 1.])
        """
        self._check_ys(ys)
        T = np.shape(ys)[-2] if np.ndim(ys) >= 2 else 0
        if x0 is None or P0 is None:
            dx0, dP0 = self.default_prior(ys)
            x0 = dx0 if x0 is None else x0
            P0 = dP0 if P0 is None else P0
        _prior_of(self.motion, x0, P0)
        return kalman_filter(ys, **self.matrices(T, dt), x0=x0, P0=P0, store_covs=store_covs)

    def online(self, x0: ArrayLike, P0: ArrayLike, *, dt: float = 1.0) -> OnlineFilter:
        """A filter for one target that is fed one measurement at a time.

        ``x0, P0`` are the prior of the first measurement (as in :func:`kalman_filter`): correct
        them with :meth:`OnlineFilter.update`, then :meth:`OnlineFilter.step` for each later one.

        Parameters
        ----------
        x0 : (n,) array_like
            Prior mean.
        P0 : (n, n) array_like
            Prior covariance, symmetric positive semi-definite.
        dt : float
            The default time step of :meth:`OnlineFilter.predict` and
            :meth:`OnlineFilter.step`.

        Returns
        -------
        OnlineFilter
            The filter, at the prior.

        Raises
        ------
        ValueError
            If the prior has the wrong shape or is invalid, or the measurement model is not
            constant.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> f = KalmanFilter(ConstantVelocity(dim=1, q=0.01), Position(dim=1, r=0.5)).online(
        ...     x0=[0.0, 1.0], P0=np.eye(2))
        >>> _ = f.update([0.1])
        >>> for y in ([1.0], [2.1], [2.9]):
        ...     _ = f.step(y)
        >>> f.mean.round(2)
        array([2.96, 0.96])
        """
        return OnlineFilter(self, x0, P0, dt=dt)

    def smooth(
        self, ys: ArrayLike, *, dt: ArrayLike = 1.0, x0: ArrayLike | None = None,
        P0: ArrayLike | None = None
    ) -> SmoothResult:
        """Filter, then RTS-smooth; see :func:`vistrack.filters.rts_smooth`.

        Parameters
        ----------
        ys : (T, m) or (B, T, m) array_like
            Measurements; NaN components (or masked entries of a numpy masked array) are
            missing.
        dt : float or array_like
            As in :meth:`filter`.
        x0, P0 : array_like, optional
            The prior, as in :meth:`filter`.

        Returns
        -------
        SmoothResult
            Smoothed means ``(..., T, n)`` and covariances ``(..., T, n, n)``, and the forward
            :class:`FilterResult`.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> kf = KalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1, r=1.0))
        >>> sm = kf.smooth(np.arange(5.0)[:, None])
        >>> sm.means.shape, sm.covs.shape, sm.filtered.means.shape
        ((5, 2), (5, 2, 2), (5, 2))
        """
        res = self.filter(ys, dt=dt, x0=x0, P0=P0)  # checks ys
        mats = self.matrices(np.shape(ys)[-2], dt)
        return rts_smooth(res, F=mats["F"], Q=mats["Q"])

    def fit(
        self,
        ys: ArrayLike,
        *,
        dt: ArrayLike = 1.0,
        learn: tuple[str, ...] | list[str] = ("q", "R"),
        method: str = "mle",
        R_form: str = "diag",
        x0: ArrayLike | None = None,
        P0: ArrayLike | None = None,
        **options: Any,
    ) -> tuple[KalmanFilter, FitResult]:
        """Learn the motion model's noise ``q`` and the measurement noise ``R`` from
        measurements (one series, or a batch pooled), the rest of the models as they are.

        ``Q(dt)`` is learned as a factor of the motion model's (its ``q`` for any time steps,
        as the model discretises it), and ``R`` by its diagonal (``R_form="diag"``), a factor
        (``"scaled"``) or, by EM, every entry (``"full"``).

        Parameters
        ----------
        ys : (T, m) or (B, T, m) array_like
            Measurements; NaN components (or masked entries of a numpy masked array) are
            missing.
        dt : float or array_like
            As in :meth:`filter`.
        learn : sequence of {"q", "R"}
            What to learn.
        method : {"mle", "em"}
            Maximum likelihood by L-BFGS with the exact gradient
            (:func:`~vistrack.filters.mle`), or expectation-maximisation
            (:func:`~vistrack.filters.em`); both reach the same maximum.
        R_form : {"diag", "scaled", "full"}
            ``R``'s structure (``"full"`` with ``method="em"`` only).
        x0, P0 : array_like, optional
            The prior, held fixed. By default ``x0`` from the first measurement
            (:meth:`default_prior`) and ``P0`` wide, ``100 I`` times the largest variance of
            a series' steps from one measurement to the next, so that the values learned do
            not depend on the noise they start from; filter with the same prior to get
            ``fit.loglik[-1]`` back.
        **options
            Passed to the method (``max_iter``, ``tol`` for EM, ``xtol`` for L-BFGS).

        Returns
        -------
        KalmanFilter
            A new filter: a copy of the motion model with the learned ``q``, and the
            measurement model with the learned ``R`` (a :class:`~vistrack.models.Position`
            or :class:`~vistrack.models.LinearMeasurement` as given).
        FitResult
            The fit: its log-likelihood trace, iterations and, by maximum likelihood, standard
            errors; ``q`` and ``stderr["q"]`` in the motion model's units, ``r`` R's
            diagonal (``"diag"``) or its factor relative to the measurement model's R
            (``"scaled"``).

        Raises
        ------
        TypeError
            If ``q`` is learned and the motion model has no ``q`` that scales its ``Q``
            linearly, or ``R`` is learned of a measurement model that is not a ``Position``
            or ``LinearMeasurement``.
        ValueError
            If ``learn``, ``method`` or ``R_form`` is unknown, or as the method raises.

        Examples
        --------
        A constant-velocity target with q = 0.5 and R = 4 I, learned from a start of q = 1
        and R = I:

        >>> from vistrack.models import ConstantVelocity, Position
        >>> from vistrack.simulate import simulate
        >>> truth = KalmanFilter(ConstantVelocity(dim=2, q=0.5), Position(dim=2, r=4.0))
        >>> _, ys = simulate(truth.motion, truth.measurement, 2000, x0=np.zeros(4), rng=0)
        >>> kf, fit = KalmanFilter(ConstantVelocity(dim=2), Position(dim=2)).fit(ys)
        >>> round(kf.motion.q, 2), kf.measurement.R().diagonal().round(2), fit.converged
        (0.52, array([4.05, 3.92]), True)
        """
        learned = _names(learn, ("q", "R"))
        if method not in ("mle", "em"):
            raise ValueError(f"method must be 'mle' or 'em'; got {method!r}")
        motion, meas = self.motion, self.measurement
        if "q" in learned:
            q0 = getattr(motion, "q", None)
            doubled = copy.copy(motion)
            if isinstance(q0, float) and q0 > 0:
                doubled.q = 2 * q0  # type: ignore[attr-defined]
            d = np.linspace(0.5, 2.0, 4)
            if not (isinstance(q0, float) and q0 > 0
                    and np.allclose(doubled.Q(d), 2 * np.asarray(motion.Q(d)), rtol=1e-12)):
                raise TypeError(f"learning q needs a motion model with a q > 0 whose Q is q "
                                f"times a matrix; {motion!r} has no such q")
        if "R" in learned and not isinstance(meas, (Position, LinearMeasurement)):
            raise TypeError(f"learning R needs a Position or LinearMeasurement model; got "
                            f"{type(meas).__name__}")
        self._check_ys(ys)
        y, _ = as_measurement_series(ys)
        T = y.shape[1]
        if x0 is None or P0 is None:
            # the first measurement, and every part of the state with a standard deviation of
            # 10 times the spread of the measurements' steps: learned values that do not
            # depend on the noise they start from (default_prior's P0 takes R from it)
            dx0, dP0 = self.default_prior(y)
            x0 = dx0 if x0 is None else x0
            steps = np.diff(y, axis=1)
            spread = float(np.nanmax(np.nanvar(steps, axis=1))) if np.isfinite(
                steps).any() else 1.0
            P0 = 100.0 * max(spread, 1e-12) * np.eye(len(dP0)) if P0 is None else P0
        mats = self.matrices(T, dt)
        what = tuple({"q": "Q", "R": "R"}[k] for k in learned)
        F, Q, H, R = mats["F"], mats["Q"], mats["H"], mats["R"]
        if method == "mle":
            fit = mle(y, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0, learn=what, R_form=R_form,
                      **options)
        else:
            fit = em(y, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0, learn=what, Q_form="scaled",
                     R_form=R_form, **options)
        if "q" in learned:
            # q, and its standard error, in the motion model's units
            q0 = float(getattr(self.motion, "q"))  # noqa: B009
            motion = copy.copy(motion)
            setattr(motion, "q", q0 * float(fit.q))  # noqa: B010
            stderr = dict(fit.stderr)
            if "q" in stderr:
                stderr["q"] = q0 * stderr["q"]
            fit = replace(fit, q=q0 * float(fit.q), stderr=stderr)
        if "R" in learned:
            meas = (Position(dim=meas.ndim_meas, r=fit.R) if isinstance(meas, Position)
                    else LinearMeasurement(meas.H(self.motion.ndim_state), fit.R))
        return KalmanFilter(motion, meas), fit


_OWN_STEPS = (KalmanFilter.predict, KalmanFilter.update)
"""The class's own steps, as imported (a patch made later is told apart from them)."""


class OnlineFilter:
    """One target's Gaussian, predicted and corrected in place, one measurement at a time.

    Made by :meth:`KalmanFilter.online`. The model's matrices for the default time step are
    checked once, here, so a call costs little more than the arithmetic: this is the loop of a
    single-object tracker. For many targets, :func:`kf_predict` / :func:`kf_update` on a batch
    of Gaussians cost less per target. The equations are those of :func:`kf_predict` and
    :func:`kf_update`.

    Parameters
    ----------
    kf : KalmanFilter
        The models; the measurement model must be constant (``H``, ``R`` 2-D).
    x0 : (n,) array_like
        Prior mean of the first measurement.
    P0 : (n, n) array_like
        Prior covariance, symmetric positive semi-definite.
    dt : float
        The default time step.

    Attributes
    ----------
    mean : (n,) ndarray
        Read-only view of the current mean (it changes with the next call; copy to keep).
    cov : (n, n) ndarray
        Read-only view of the current covariance.

    Raises
    ------
    ValueError
        If the prior has the wrong shape or is invalid, or the measurement model is not
        constant, or its ``R`` is not symmetric positive semi-definite.

    Examples
    --------
    >>> from vistrack.models import ConstantVelocity, Position
    >>> kf = KalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1, r=1.0))
    >>> f = OnlineFilter(kf, [0.0, 1.0], np.eye(2))
    >>> f.predict()
    >>> f.mean, f.cov.round(3)
    (array([1., 1.]), array([[2.033, 1.05 ],
           [1.05 , 1.1  ]]))
    >>> round(f.update([1.2]), 3), f.mean.round(3)
    (-1.48, array([1.134, 1.069]))
    """

    __slots__ = ("_kf", "_n", "_m", "_dt0", "_dt", "_buf", "_off", "_idx", "_kernel", "_no_y")

    def __init__(self, kf: KalmanFilter, x0: ArrayLike, P0: ArrayLike, *, dt: float = 1.0):
        n = kf.motion.ndim_state
        x, P = _prior(x0, P0, 1, n)
        if x.shape != (1, n) or P.shape[0] != 1:
            raise ValueError(f"x0 must have shape ({n},) and P0 ({n}, {n}); got {np.shape(x0)}, "
                             f"{np.shape(P0)}")
        H = np.asarray(kf.measurement.H(n), dtype=np.float64)
        R = np.asarray(kf.measurement.R(), dtype=np.float64)
        if H.ndim != 2 or R.ndim != 2:
            raise ValueError("an online filter needs a constant measurement model (H, R 2-D)")
        m = H.shape[0]
        H = check_matrix_stack(H, "H", m, n, 1)
        R = check_matrix_stack(R, "R", m, m, 1)
        check_psd(R, "R")
        self._kf, self._n, self._m = kf, n, m
        # state, model and work space in one buffer: few arguments make the kernel call cheap
        self._off, size = _kernels.online_layout(n, m)
        self._buf = np.zeros(size)
        self._put("x", x[0])
        self._put("P", P[0])
        self._put("H", H)
        self._put("R", R)
        self._idx = np.empty(m, dtype=np.int64)
        self._kernel = _kernels.online_kernel(n, m)
        # (text was taken as a step and True as 1 here, where predict refuses them; None and
        # arrays failed in float()'s words)
        if not is_real(dt):
            raise ValueError(f"dt must be a number; got {dt!r}")
        self._dt0 = float(dt)  # the default time step; F, Q are kept for the last one used
        self._dt: float | None = None
        self._set_dt(self._dt0)
        self._no_y = np.full(m, np.nan)  # the measurement argument of a prediction

    def _put(self, name: str, value: np.ndarray) -> None:
        o = self._off[name]
        self._buf[o:o + value.size] = value.ravel()

    def _set_dt(self, dt: float) -> None:
        n = self._n
        F = check_matrix_stack(self._kf.motion.F(dt), "F", n, n, 1)
        Q = check_matrix_stack(self._kf.motion.Q(dt), "Q", n, n, 1)
        check_psd(Q, "Q")
        self._put("F", F)
        self._put("Q", Q)
        self._dt = dt

    def __repr__(self) -> str:
        return f"OnlineFilter(mean={np.array2string(self.mean, precision=3)})"

    @property
    def mean(self) -> np.ndarray:
        """The current mean ``(n,)``: a read-only view that the next call changes.

        Examples
        --------
        >>> from vistrack.models import ConstantPosition, Position
        >>> f = KalmanFilter(ConstantPosition(dim=2), Position(dim=2)).online([1.0, 2.0],
        ...                                                                  np.eye(2))
        >>> f.mean, f.mean.flags.writeable
        (array([1., 2.]), False)
        """
        o = self._off["x"]
        v = self._buf[o:o + self._n]
        v.flags.writeable = False
        return v

    @property
    def cov(self) -> np.ndarray:
        """The current covariance ``(n, n)``: a read-only view that the next call changes.

        Examples
        --------
        >>> from vistrack.models import ConstantPosition, Position
        >>> f = KalmanFilter(ConstantPosition(dim=1), Position(dim=1)).online([0.0], np.eye(1))
        >>> _ = f.update([1.0])
        >>> f.cov
        array([[0.5]])
        """
        n, o = self._n, self._off["P"]
        v = self._buf[o:o + n * n].reshape(n, n)
        v.flags.writeable = False
        return v

    @property
    def gaussian(self) -> Gaussian:
        """A copy of the current estimate: a :class:`~vistrack.types.Gaussian`, batch shape ``()``.

        Examples
        --------
        >>> from vistrack.models import ConstantPosition, Position
        >>> kf = KalmanFilter(ConstantPosition(dim=2), Position(dim=2))
        >>> g = kf.online([1.0, 2.0], np.eye(2)).gaussian
        >>> g.mean, g.batch_shape
        (array([1., 2.]), ())
        """
        return Gaussian(self.mean.copy(), self.cov.copy())

    def _run(self, y: ArrayLike | None, predict: bool, update: bool, dt: float | None) -> float:
        if predict:
            # (text was read as a step: "0.5" moved the mean by half a step)
            if dt is not None and not is_real(dt):
                raise ValueError(f"dt must be a number; got {dt!r}")
            d = self._dt0 if dt is None else float(dt)
            if d != self._dt:
                self._set_dt(d)
        if update:
            if not (type(y) is np.ndarray and y.dtype == np.float64 and y.flags.c_contiguous):
                y = as_float_array(y, "y")
            if y.shape != (self._m,):
                raise ValueError(f"y must have shape ({self._m},); got {y.shape}")
        else:
            y = self._no_y
        code, ll = self._kernel(self._buf, y, self._idx, predict, update)
        if code >= 0:
            if code == 8:
                raise ValueError(f"y must be finite or NaN (missing); got {y}")
            _kernel_error(code, "F", "Q")
        return ll

    def predict(self, *, dt: float | None = None) -> None:
        r"""Predict one step: :math:`\bar x \leftarrow F \bar x`, :math:`P \leftarrow F P F' + Q`.

        Parameters
        ----------
        dt : float, optional
            Time step; default the ``dt`` the filter was made with. ``F(dt)`` and ``Q(dt)``
            are computed (and checked) when ``dt`` changes.

        Raises
        ------
        ValueError
            If the model's ``F`` or ``Q`` for ``dt`` is invalid.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> f = KalmanFilter(ConstantVelocity(dim=1), Position(dim=1)).online([0.0, 1.0],
        ...                                                                  np.eye(2))
        >>> f.predict(dt=3.0)
        >>> f.mean
        array([3., 1.])
        """
        self._run(None, True, False, dt)

    def update(self, y: ArrayLike) -> float:
        """Correct with a measurement (the equations of :func:`kf_update`).

        Parameters
        ----------
        y : (m,) array_like
            The measurement; NaN components are missing (all NaN: no correction).

        Returns
        -------
        float
            ``log N(y; H m, S)`` over the observed components (0 if none).

        Raises
        ------
        ValueError
            If ``y`` has the wrong shape or an infinite value, or the innovation covariance
            is not positive definite.

        Examples
        --------
        >>> from vistrack.models import ConstantPosition, Position
        >>> f = KalmanFilter(ConstantPosition(dim=1), Position(dim=1, r=1.0)).online([0.0],
        ...                                                                         np.eye(1))
        >>> round(f.update([2.0]), 3), f.mean, f.cov
        (-2.266, array([1.]), array([[0.5]]))
        """
        return self._run(y, False, True, None)

    def step(self, y: ArrayLike, *, dt: float | None = None) -> float:
        """:meth:`predict` then :meth:`update`: the loop of a tracker.

        Parameters
        ----------
        y : (m,) array_like
            The measurement; NaN components are missing.
        dt : float, optional
            Time step; default the ``dt`` the filter was made with.

        Returns
        -------
        float
            The log-likelihood of ``y`` under the prediction.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> f = KalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1)).online(
        ...     [0.0, 1.0], np.eye(2))
        >>> for y in ([1.1], [1.9], [3.2]):
        ...     ll = f.step(y)
        >>> f.mean.round(2), round(ll, 3)
        (array([3.1 , 1.04]), -1.458)
        """
        return self._run(y, True, True, dt)


def _prior_of(motion: Any, x0: Any, P0: Any) -> None:
    """Raise a ValueError naming ``x0`` when ``x0`` and ``P0`` agree on a state size that is
    not the motion model's (the filter of the model's matrices named ``F``, which the user
    never gave); a prior that disagrees with itself, or that numpy cannot read, is left to
    the filter's own checks, which name it."""
    n = int(motion.ndim_state)
    if _state_size(n, x0, P0) != n:  # the size x0 and P0 agree on, where they do
        raise ValueError(f"x0 must have shape ({n},) or (B, {n}), as the motion model "
                         f"{motion!r} has {n} states; got {np.shape(x0)} (and P0 "
                         f"{np.shape(P0)})")
