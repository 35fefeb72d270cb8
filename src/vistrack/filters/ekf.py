r"""The extended Kalman filter (seed 004, "Extended Kalman Filter").

Prediction through the nonlinear dynamics and their Jacobian ``G`` at the current estimate,

.. math:: x_t^- = f(x_{t-1}^+), \qquad \Sigma_t^- = G_t \Sigma_{t-1}^+ G_t^T + \Sigma_{d_t},

correction with the measurement Jacobian ``H`` at the prediction,

.. math:: K_t = \Sigma_t^- H_t^T (H_t \Sigma_t^- H_t^T + \Sigma_{m_t})^{-1}, \quad
   x_t^+ = x_t^- + K_t\, r(y_t, h(x_t^-)), \quad
   \Sigma_t^+ = (I - K_t H_t) \Sigma_t^- (I - K_t H_t)^T + K_t \Sigma_{m_t} K_t^T,

in the Joseph form (which keeps ``Σ⁺`` symmetric positive definite, where the slides'
``(I - K H) Σ⁻`` can lose both to rounding), with the residual ``r`` of the measurement model
(angles wrap). As the seed says, the EKF is in general not an optimal estimator; on a linear
model it is exactly the Kalman filter.

:meth:`ExtendedKalmanFilter.filter` runs the whole sequence in one compiled call where both
models provide compiled one-state functions and Jacobians (``jit_f`` and ``jit_jacobian``,
``jit_h`` and ``jit_jacobian``, with ``jit_params``: the coordinated turn, range-bearing, the
growth model; see :mod:`vistrack.models.nonlinear`): about a microsecond a step, against
some hundred for the steps from Python. Other models run the steps from Python.
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np
from numpy.typing import ArrayLike

from .._prebuilt import Kernel
from .._validate import check_finite, check_one_step, check_psd, check_symmetric
from ..models.adapters import MeasurementFunctions, MotionFunctions
from ..models.protocols import (
    MeasurementModel,
    MotionModel,
    NonlinearMeasurementModel,
    NonlinearMotionModel,
)
from ..types import Gaussian
from . import _codegen, _jitmath, _kernels
from ._codegen import Ref
from ._kernels import update_batch_py
from ._nonlinear import (
    check_gaussian,
    check_h_size,
    check_y,
    compiled_functions,
    compiled_run,
    own_steps,
    run_sequence,
)
from .kalman import FilterResult
from .reference import condition_on, symmetric

__all__ = ["ekf_predict", "ekf_update", "ExtendedKalmanFilter"]


def ekf_predict(g: Gaussian, motion: MotionModel | NonlinearMotionModel, dt: float = 1.0,
                t: float = 0.0) -> Gaussian:
    r"""EKF prediction of a batch of Gaussians ``g`` (mean ``(..., n)``) by ``dt`` to time ``t``.

    ``motion`` is a nonlinear motion model (``f``, ``jacobian``, ``Q``; see
    :mod:`vistrack.models.nonlinear`) or a linear one (``F``, ``Q``).

    Examples
    --------
    >>> from vistrack.models import CoordinatedTurn
    >>> g = Gaussian(np.array([0.0, 0.0, 1.0, 0.0, 0.1]), np.eye(5) * 0.01)
    >>> ekf_predict(g, CoordinatedTurn(q=0.1), dt=1.0).mean.round(3)
    array([0.998, 0.05 , 0.995, 0.1  , 0.1  ])
    """
    g = _checked(g)
    check_one_step(dt)
    return _predict(MotionFunctions.of(motion), g, dt, t)


def _predict(mo: MotionFunctions, g: Gaussian, dt: float, t: float) -> Gaussian:
    """:func:`ekf_predict` of a checked Gaussian and step."""
    if g.mean.shape[-1] != mo.n:  # (numpy's broadcast error, naming neither; as ukf_predict)
        raise ValueError(f"g must have a state of {mo.n} values, the motion model's; got "
                         f"{g.mean.shape[-1]}")
    G = mo.jacobian(g.mean, dt, t)
    cov = symmetric(G @ g.cov @ np.swapaxes(G, -1, -2) + mo.Q(dt))
    return Gaussian(np.asarray(mo.f(g.mean, dt, t), dtype=float), cov)


def _checked(g: object) -> Gaussian:
    """``g``, a Gaussian whose mean and covariance are finite and whose covariance is
    symmetric positive semi-definite, as the UKF takes it (a covariance of a negative
    variance, or not symmetric, gave estimates with negative variances, without a word)."""
    g = check_gaussian(g)
    check_finite(g.mean, "g.mean")
    check_finite(g.cov, "g.cov")
    try:  # positive definite, the usual case: a Cholesky factor, cheap (its eigenvalues
        # every step made the filter half as slow again)
        np.linalg.cholesky(g.cov)
        check_symmetric(g.cov, "g.cov")
    except np.linalg.LinAlgError:  # singular, or not semi-definite: judged as the UKF does
        check_psd(g.cov, "g.cov")
    return g


def ekf_update(g: Gaussian, y: ArrayLike,
               measurement: MeasurementModel | NonlinearMeasurementModel, *,
               residual: Callable | None = None) -> Gaussian:
    r"""EKF correction of a batch of Gaussians ``g`` with measurements ``y (..., m)``.

    NaN components of ``y`` are missing: the update uses the others (a NaN row leaves ``g``
    unchanged). ``residual(a, b)`` overrides the model's (default ``a - b``, with angles
    wrapped for models that declare them). This is
    :func:`vistrack.filters.reference.condition_on` with the measurement model's Jacobian
    and residual; :meth:`ExtendedKalmanFilter.update` also gives the log-density of the
    innovation.
    """
    return _ekf_update(g, y, measurement, residual)[0]


def _ekf_update(g: Gaussian, y: ArrayLike,
                measurement: MeasurementModel | NonlinearMeasurementModel,
                residual: Callable | None, *, trusted: bool = False
                ) -> tuple[Gaussian, np.ndarray]:
    """:func:`ekf_update` and the innovation's log-density; ``trusted``: ``g`` is the
    filter's own (its prior checked, every state since made by these steps: symmetric and
    semi-definite by their form; a NaN one a model gave is named by the filter's loop)."""
    if not trusted:
        g = _checked(g)
    n = g.mean.shape[-1]
    me = MeasurementFunctions.of(measurement, n, residual)
    y = check_y(y, g.mean.shape[:-1], me.m)
    obs = ~np.isnan(y)
    x = g.mean
    e = me.residual(np.where(obs, y, 0.0), check_h_size(me.h(x), me.m, x))
    H = me.jacobian(x)
    if np.shape(H)[-2:] != (me.m, n):  # (numpy's matmul error, or numba's reshape's)
        raise ValueError(f"the measurement model's jacobian(x) gives shape {np.shape(H)} for "
                         f"states of shape {x.shape}; (..., {me.m}, {n}) was expected (its R "
                         f"is {me.m} x {me.m})")
    if x.ndim == 1 and np.ndim(H) == 2 and np.isfinite(e[obs]).all():
        # one Gaussian: the correction in one compiled call (the Kalman filter's own, which
        # forms the innovation as y - H x: given e for y and a zero mean, it gives the step
        # K e, the same Joseph form and log-density), where numpy's some thirty calls cost
        # more than the model's f and h (the filter ran at 0.25 ms a step, FilterPy's 0.13)
        # (writeable C-ordered copies: the argument types the kernel was built for ahead of
        # time; a model's read-only R, or a Jacobian in Fortran order, compiled it again at
        # the first call, seconds)
        H = np.ascontiguousarray(np.where(obs[:, None], np.asarray(H, dtype=float), 0.0))
        code, step, cov, ll = update_batch_py(np.zeros(n),
                                              np.array(g.cov, dtype=float, order="C"),
                                              np.where(obs, e, np.nan), H,
                                              np.array(me.Rm, dtype=float, order="C"))
        if code < 0:
            return Gaussian._trusted(x + step, cov), ll
        # (anything else, not finite or not positive definite: as numpy's path words it; an
        # innovation h made NaN is not a missing component, which the kernel reads NaN as)
    mean, cov, ll = condition_on(x, g.cov, H, me.Rm, e, obs)
    return Gaussian(mean, cov), ll


class ExtendedKalmanFilter:
    """The EKF over a sequence, from a motion and a measurement model.

    Parameters
    ----------
    motion, measurement
        Nonlinear models (:mod:`vistrack.models.nonlinear`) or linear ones.
    residual : callable, optional
        ``residual(a, b)`` for measurements, overriding the model's (the steps then run from
        Python).

    Notes
    -----
    With models that provide compiled one-state functions and their Jacobians (module
    level numba functions ``jit_f``, ``jit_h`` and each model's ``jit_jacobian``, with
    ``jit_params``), :meth:`filter` runs in one compiled call. A value that call cannot
    take (a state or a model's value not finite, an innovation covariance not positive
    definite) makes it filter again from Python, which names it.

    Examples
    --------
    >>> import vistrack as vt
    >>> motion, meas = vt.models.CoordinatedTurn(q=0.01), vt.models.RangeBearing(ndim_state=5)
    >>> ys = np.array([[10.0, 0.0], [10.5, 0.1], [np.nan, np.nan], [11.0, 0.3]])
    >>> res = ExtendedKalmanFilter(motion, meas).filter(
    ...     ys, x0=[10.0, 0.0, 0.0, 1.0, 0.0], P0=np.diag([1.0, 1.0, 1.0, 1.0, 0.01]))
    >>> res.means.shape, res.covs.shape
    ((4, 5), (4, 5, 5))
    """

    def __init__(self, motion: MotionModel | NonlinearMotionModel,
                 measurement: MeasurementModel | NonlinearMeasurementModel, *,
                 residual: Callable | None = None):
        self.motion = MotionFunctions(motion)
        self.measurement = MeasurementFunctions(measurement, self.motion.n, residual)

    def filter(self, ys: ArrayLike, *, x0: ArrayLike, P0: ArrayLike,
               dt: ArrayLike | None = None, times: ArrayLike | None = None) -> FilterResult:
        """Filter ``ys (T, m)`` or ``(B, T, m)`` (NaN = missing). ``x0, P0`` are the prior of the
        first step, as in :func:`~vistrack.filters.kalman_filter`. ``dt`` is a scalar, the
        ``T-1`` intervals between steps or one per step (``dt[0]`` unused), by default
        ``np.diff(times)`` where ``times`` is given, else 1; ``times`` (not decreasing;
        default: the cumulative ``dt``, from 0) is passed to the model, and must agree with
        ``dt`` where both are given. A model that gives
        NaN or infinity mid-run is a ValueError naming the first step (and series) whose
        prediction or correction it made so."""
        predict: Callable[[Gaussian, float, float], Gaussian] = self.predict
        update: Callable[[Gaussian, np.ndarray], tuple[Gaussian, np.ndarray]] = self.update
        if own_steps(self, _OWN_STEPS):
            # models with compiled functions and Jacobians: the whole filter in one compiled
            # call; anything it cannot take (a state or a model's value not finite, an
            # innovation covariance not positive definite) is filtered again below, which
            # names it as before
            parts = compiled_functions(self.motion, self.measurement, ("jit_f", "jit_jacobian"),
                                       ("jit_h", "jit_jacobian"))
            if parts is not None:
                done = _filter_compiled(parts, self.motion, self.measurement, ys, x0, P0, dt,
                                        times)
                if done is not None:
                    return done
            # the prior checked by run_sequence, the states since the filter's own: the steps
            # without the checks of a Gaussian given, a third of their time (a predict or
            # update of a subclass's, the instance's or a patch's is called as it is, and
            # each Gaussian checked: a subclass's prediction of a negative variance was
            # corrected without a word)
            predict = partial(_predict, self.motion)
            update = partial(_ekf_update, measurement=self.measurement, residual=None,
                             trusted=True)
        return run_sequence(ys, x0, P0, self.motion.n, self.measurement.m, dt, times,
                            predict, update)

    def predict(self, g: Gaussian, dt: float = 1.0, t: float = 0.0) -> Gaussian:
        """One prediction (:func:`ekf_predict` with this filter's motion model)."""
        return ekf_predict(g, self.motion, dt, t)

    def update(self, g: Gaussian, y: ArrayLike) -> tuple[Gaussian, np.ndarray]:
        """One correction and its innovation log-density (:func:`ekf_update`)."""
        return _ekf_update(g, y, self.measurement, None)


_OWN_STEPS = (ExtendedKalmanFilter.predict, ExtendedKalmanFilter.update)


# ---------------------------------------------------------------- the compiled path
_FUSED = """
# depends on: {depends}
import math
import numpy as np
from numba import njit
from vistrack.filters._jitmath import wrap_angle
from vistrack.filters._kernels import (keep_state, load_state, observed, one_scratch,
                                       predict_one, update_one)
from {fmod} import {fname} as f
from {jfmod} import {jfname} as jf
from {hmod} import {hname} as h
from {jhmod} import {jhname} as jh


@njit(cache=True, error_model="numpy", fastmath={{"nsz"}})
def run(x0, P0, ys, dts, times, fp, hp, Qs, qi, R, angles, means, covs, pmeans, pcovs,
        loglik):
    # The EKF over every series, one compiled call: per step the prediction
    # (f, G P G' + Q) and the correction of the Kalman filter's one-Gaussian
    # update_one, given the residual y - h(x) (angles wrapped) for y and a zero mean, with
    # the Jacobian of h for H, as the filter's steps from Python do. Returns (-1, -1), or the
    # series and step of the first value not finite or innovation covariance not positive
    # definite, which the caller filters again from Python to name.
    B, T = ys.shape[0], ys.shape[1]
    n, m = {n}, {m}  # literal sizes: the loops unroll
    x = np.empty(n)
    xn = np.empty(n)
    step = np.empty(n)
    zero = np.zeros(n)
    P = np.empty((n, n))
    A = np.empty((n, n))
    G = np.empty((1, n, n))
    GP = np.empty((n, n))
    z = np.empty(m)
    e = np.empty(m)
    H = np.empty((1, m, n))
    R3 = R.reshape((1, m, m))
    idx, ee, Ut, KT, S, L, AP, W, _ = one_scratch(n, m)
    for b in range(B):
        load_state(x0, P0, b, x, P)
        total = 0.0
        for t in range(T):
            if t > 0:
                # G P G' + Q by the Kalman filter's own prediction, G for F (its mean, G x,
                # is not the EKF's: f(x) replaces it)
                f(x, dts[t], times[t], fp[t], xn)
                jf(x, dts[t], times[t], fp[t], G[0])
                predict_one(G, Qs, 0, qi[t], x, P, step, A, GP, n)
                for i in range(n):
                    x[i] = xn[i]
                    for k in range(n):
                        P[i, k] = A[i, k]
            if not keep_state(x, P, pmeans, pcovs, b, t):
                return b, t
            if observed(ys[b, t]) > 0:
                h(x, hp, z)
                fine = True
                jh(x, hp, H[0])
                for k in range(m):
                    y = ys[b, t, k]
                    if math.isnan(y):
                        e[k] = np.nan
                        continue
                    d = y - z[k]
                    e[k] = wrap_angle(d) if angles[k] else d
                    fine = fine and abs(z[k]) < np.inf
                    for l in range(n):
                        fine = fine and abs(H[0, k, l]) < np.inf
                if not fine:
                    return b, t
                good, ll = update_one(H, R3, 0, 0, e, zero, P, step, A, idx, ee, Ut, KT, S,
                                      L, AP, W, n, m)
                if not good:
                    return b, t
                total += ll
                for i in range(n):
                    x[i] += step[i]
                    for k in range(n):
                        P[i, k] = A[i, k]
            if not keep_state(x, P, means, covs, b, t):
                return b, t
        loglik[b] = total
    return -1, -1
"""


def _fused_kernel(fref: Ref, jfref: Ref, href: Ref, jhref: Ref, n: int, m: int) -> Kernel:
    """The compiled filter of these functions and sizes for calls from Python (and for
    compiling it ahead of time, see :mod:`vistrack._prebuilt`), of their modules' current
    source."""
    return _codegen.generated_kernel(
        _FUSED, "vistrack_ekf",
        f"{__name__}:_fused_kernel({fref!r}, {jfref!r}, {href!r}, {jhref!r}, {n!r}, {m!r})",
        (*sorted({fref[0], jfref[0], href[0], jhref[0]}), _jitmath.__name__,
         _kernels.__name__),
        fmod=fref[0], fname=fref[1], jfmod=jfref[0], jfname=jfref[1], hmod=href[0],
        hname=href[1], jhmod=jhref[0], jhname=jhref[1], n=n, m=m)


def _filter_compiled(parts: tuple[Ref, ...], mo: MotionFunctions,
                     me: MeasurementFunctions, ys: ArrayLike, x0: ArrayLike, P0: ArrayLike,
                     dt: ArrayLike | None, times: ArrayLike | None) -> FilterResult | None:
    """:meth:`ExtendedKalmanFilter.filter` in one compiled call, or None where the call met
    a value it cannot take (filtered again from Python, which names it)."""
    c = compiled_run(mo, me, ys, x0, P0, dt, times)
    if c is None:
        return None
    f, jf, h, jh = parts
    b, _ = _fused_kernel(f, jf, h, jh, mo.n, me.m)(*c.inputs, *c.outputs)
    return None if b >= 0 else c.result()
