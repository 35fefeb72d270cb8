"""Sample states and measurements from linear-Gaussian and nonlinear models, with a seeded
``rng``."""

from __future__ import annotations

from typing import TYPE_CHECKING, cast

import numpy as np
from numpy.typing import ArrayLike

from ._validate import (
    as_float_array,
    as_rng,
    as_whole,
    check_finite,
    check_linear_gaussian,
    check_psd,
    is_whole,
)
from .filters.linear import KalmanFilter, dt_steps
from .models.adapters import psd_sqrt

if TYPE_CHECKING:
    from .models.protocols import (
        MeasurementModel,
        MotionModel,
        NonlinearMeasurementModel,
        NonlinearMotionModel,
    )

__all__ = ["simulate_lgssm", "simulate"]


def simulate_lgssm(
    T: int,
    *,
    F: ArrayLike,
    Q: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    x0: ArrayLike,
    P0: ArrayLike | None = None,
    n_series: int | None = None,
    rng: np.random.Generator | int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Sample states and measurements of a linear-Gaussian state-space model.

    .. math::

        x_0 \sim N(\bar x_0, P_0), \qquad
        x_t = F_t x_{t-1} + w_t, \quad w_t \sim N(0, Q_t), \qquad
        y_t = H_t x_t + v_t, \quad v_t \sim N(0, R_t),

    for ``t = 0, ..., T-1`` (the seeds' :math:`x_i \sim N(D x_{i-1}, \Sigma_d)`,
    :math:`y_i \sim N(M x_i, \Sigma_m)`).

    Parameters
    ----------
    T : int
        Number of steps, at least 1.
    F, Q : (n, n) or (T, n, n) array_like
        Dynamics and process-noise covariance, constant or per step, as in
        :func:`vistrack.filters.kalman_filter` (``F[t]`` moves step ``t-1`` to ``t``; ``F[0]``
        and ``Q[0]`` are unused). ``Q`` is symmetric positive semi-definite.
    H, R : (m, n) and (m, m), or (T, m, n) and (T, m, m) array_like
        Measurement matrix and noise covariance, constant or per step.
    x0 : (n,) array_like
        Mean :math:`\bar x_0` of the first state.
    P0 : (n, n) array_like, optional
        Covariance of the first state; the first state is exactly ``x0`` if None.
    n_series : int, optional
        Draw this many independent series: the outputs gain a leading axis.
    rng : numpy.random.Generator, int or None
        Random generator or seed.

    Returns
    -------
    xs : ([n_series,] T, n) ndarray
        States.
    ys : ([n_series,] T, m) ndarray
        Measurements.

    Raises
    ------
    ValueError
        If ``T`` is not a positive integer, a matrix has the wrong shape or is not finite,
        ``Q``, ``R`` or ``P0`` is not symmetric positive semi-definite, or ``n_series < 1``.

    See Also
    --------
    simulate : The same from motion and measurement models, linear or not.

    Examples
    --------
    >>> import numpy as np
    >>> xs, ys = simulate_lgssm(5, F=np.eye(1), Q=[[1.0]], H=[[1.0]], R=[[0.1]], x0=[0.0], rng=0)
    >>> xs.shape, ys.shape
    ((5, 1), (5, 1))
    """
    if not is_whole(T, 1):
        raise ValueError(f"T must be a positive integer; got {T!r}")
    T = int(T)
    gen = as_rng(rng)
    x0_ = as_float_array(x0, "x0", ndim=(1,))
    check_finite(x0_, "x0")
    n = x0_.shape[0]
    H_arr = as_float_array(H, "H", ndim=(2, 3))
    m = H_arr.shape[-2]
    F_, Q_, H_, R_ = check_linear_gaussian(F, Q, H_arr, R, n, m, T)
    B = _n_series(n_series)
    x = np.broadcast_to(x0_, (B, n)).copy()
    if P0 is not None:
        P0_ = as_float_array(P0, "P0", ndim=(2,))
        if P0_.shape != (n, n):
            raise ValueError(f"P0 must have shape ({n}, {n}); got {P0_.shape}")
        check_finite(P0_, "P0")  # a NaN passed the PSD check and made every state NaN
        check_psd(P0_, "P0")
        x += gen.standard_normal((B, n)) @ psd_sqrt(P0_).T
    sq, sr = psd_sqrt(Q_), psd_sqrt(R_)
    xs = np.empty((B, T, n))
    ys = np.empty((B, T, m))
    for t in range(T):
        if t > 0:
            Ft, St = F_[t if len(F_) > 1 else 0], sq[t if len(sq) > 1 else 0]
            x = x @ Ft.T + gen.standard_normal((B, n)) @ St.T
        Ht, Rt = H_[t if len(H_) > 1 else 0], sr[t if len(sr) > 1 else 0]
        xs[:, t] = x
        ys[:, t] = x @ Ht.T + gen.standard_normal((B, m)) @ Rt.T
    if n_series is None:
        return xs[0], ys[0]
    return xs, ys


def simulate(
    motion: MotionModel | NonlinearMotionModel,
    measurement: MeasurementModel | NonlinearMeasurementModel,
    T: int,
    *,
    x0: ArrayLike,
    P0: ArrayLike | None = None,
    dt: ArrayLike = 1.0,
    n_series: int | None = None,
    rng: np.random.Generator | int | None = None,
) -> tuple[np.ndarray, np.ndarray]:
    r"""Sample states and measurements from a motion model and a measurement model.

    Linear models (no ``jacobian``) are sampled by :func:`simulate_lgssm` with the matrices
    :meth:`vistrack.filters.KalmanFilter.matrices` gives. A nonlinear model (one with a
    ``jacobian``: :mod:`vistrack.models.nonlinear`) is sampled as

    .. math::

        x_t = f(x_{t-1}, \Delta t_t, \tau_t) + w_t, \quad w_t \sim N(0, Q(\Delta t_t)),
        \qquad y_t = h(x_t) + v_t, \quad v_t \sim N(0, R),

    with :math:`\tau_t` the time since the first step (the cumulative ``dt``), and the
    measurement components that the model lists in ``angles`` wrapped to ``(-π, π]``.

    Parameters
    ----------
    motion : motion model
        Linear (``F(dt)``, ``Q(dt)``, ``ndim_state``, as :mod:`vistrack.models.motion`) or
        nonlinear (``f``, ``jacobian``, ``Q``, as :mod:`vistrack.models.nonlinear`).
    measurement : measurement model
        Linear (``H(n)``, ``R()``) or nonlinear (``h``, ``jacobian``, ``R()``).
    T : int
        Number of steps.
    x0 : (n,) array_like
        Mean of the first state.
    P0 : (n, n) array_like, optional
        Covariance of the first state; the first state is exactly ``x0`` if None.
    dt : float or array_like
        Time step: a scalar, the ``T-1`` intervals between steps, or ``T`` values (``dt[0]``
        unused).
    n_series : int, optional
        Draw this many independent series: the outputs gain a leading axis.
    rng : numpy.random.Generator, int or None
        Random generator or seed.

    Returns
    -------
    xs : ([n_series,] T, n) ndarray
        States.
    ys : ([n_series,] T, m) ndarray
        Measurements.

    Raises
    ------
    ValueError
        If ``T`` is not a positive integer, ``n_series < 1``, ``x0`` is not finite, ``P0``
        is not symmetric positive semi-definite, ``dt`` is neither a scalar nor ``T-1`` or
        ``T`` values, or a model is invalid (:func:`simulate_lgssm` lists the checks of the
        linear path), with either kind of model.

    See Also
    --------
    simulate_lgssm : The linear-Gaussian sampler, from matrices.
    vistrack.models.SwitchingLinearSystem.sample : Sampling a switching linear system.

    Examples
    --------
    >>> from vistrack.models import ConstantVelocity, Position
    >>> xs, ys = simulate(ConstantVelocity(dim=2, q=0.1), Position(dim=2), 15,
    ...                   x0=[10, 10, 1, 0], rng=1)
    >>> xs.shape, ys.shape
    ((15, 4), (15, 2))

    A nonlinear model, 3 independent series:

    >>> from vistrack.models import growth_model
    >>> xs, ys = simulate(*growth_model(), 20, x0=[0.1], n_series=3, rng=0)
    >>> xs.shape, ys.shape
    ((3, 20, 1), (3, 20, 1))
    """
    # the checks of simulate_lgssm, made here for the nonlinear path too
    if not is_whole(T, 1):
        raise ValueError(f"T must be a positive integer; got {T!r}")
    nonlinear = hasattr(motion, "jacobian") or hasattr(measurement, "jacobian")
    if not nonlinear:
        # neither model has a jacobian: both are linear
        from .filters.linear import _prior_of

        # x0 one state of the motion's size (simulate takes no batch of them; the message
        # named a P0 built here, and offered a (B, n) that was then refused)
        n = int(getattr(motion, "ndim_state", 0))
        x0_ = as_float_array(x0, "x0", ndim=(1,))
        if n and x0_.shape != (n,):
            raise ValueError(f"x0 must have shape ({n},), the motion's state; got "
                             f"{x0_.shape}")
        if P0 is not None:
            _prior_of(motion, x0, P0)
        else:  # (the first state exactly x0)
            _prior_of(motion, x0, np.eye(np.shape(x0)[0]))
        mats = KalmanFilter(cast("MotionModel", motion),
                            cast("MeasurementModel", measurement)).matrices(int(T), dt)
        return simulate_lgssm(T, **mats, x0=x0, P0=P0, n_series=n_series, rng=rng)
    return _simulate_nonlinear(motion, measurement, int(T), x0, P0, dt, n_series, as_rng(rng))


def _n_series(n_series: int | None) -> int:
    """How many series: 1 for None, else a whole number >= 1 (2.7 was taken as 2)."""
    return 1 if n_series is None else as_whole(n_series, "n_series", 1)


def _simulate_nonlinear(motion, measurement, T, x0, P0, dt, n_series, gen):
    """``x_t = f(x_{t-1}, dt_t, t) + w_t``, ``y_t = h(x_t) + v_t`` (angles wrapped), with
    ``t`` the cumulative time from 0."""
    from .models.adapters import MeasurementFunctions, MotionFunctions
    from .models.nonlinear import wrap_angle

    mo = MotionFunctions(motion)
    me = MeasurementFunctions(measurement, mo.n)
    n, B = mo.n, _n_series(n_series)
    x0_ = as_float_array(x0, "x0", ndim=(1,))
    if x0_.shape != (n,):
        raise ValueError(f"x0 must have shape ({n},); got {x0_.shape}")
    check_finite(x0_, "x0")
    P0_ = None
    if P0 is not None:
        P0_ = as_float_array(P0, "P0", ndim=(2,))
        if P0_.shape != (n, n):
            raise ValueError(f"P0 must have shape ({n}, {n}); got {P0_.shape}")
        check_finite(P0_, "P0")
        check_psd(P0_, "P0")
    x = np.broadcast_to(x0_, (B, n)).copy()
    if P0_ is not None:
        x += gen.standard_normal((B, n)) @ psd_sqrt(P0_).T
    dts = np.broadcast_to(dt_steps(dt, T), (T,))
    if not (np.isfinite(dts[1:]) & (dts[1:] >= 0)).all():  # as the linear models refuse it
        bad = dts[1:][~(np.isfinite(dts[1:]) & (dts[1:] >= 0))][0]
        raise ValueError(f"dt must be finite and >= 0; got {bad}")
    times = np.concatenate([[0.0], np.cumsum(dts[1:])])
    Rs = psd_sqrt(me.Rm)
    xs, ys = np.empty((B, T, n)), np.empty((B, T, me.m))
    for t in range(T):
        if t > 0:
            Qs = mo.Q_sqrt(float(dts[t]))
            x = mo.f(x, float(dts[t]), float(times[t])) + gen.standard_normal((B, n)) @ Qs.T
        xs[:, t] = x
        ys[:, t] = me.h(x) + gen.standard_normal((B, me.m)) @ Rs.T
        for k in getattr(measurement, "angles", ()):
            ys[:, t, k] = wrap_angle(ys[:, t, k])
    if n_series is None:
        return xs[0], ys[0]
    return xs, ys
