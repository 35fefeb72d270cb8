"""What the EKF, UKF and ensemble KF share: model adapters, the masked Gaussian correction, and
the loop over a sequence. Private; the public functions are in ekf.py, ukf.py and enkf.py."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, NamedTuple, Protocol, TypeVar, cast

import numpy as np
from numpy.typing import ArrayLike

from .._validate import (
    as_float_array,
    check_has_steps,
    check_not_infinite,
    check_prior,
    eps_of,
    masked_batch,
)
from ..models.adapters import MeasurementFunctions, MotionFunctions
from ..types import Gaussian
from ._codegen import Ref, jit_ref
from .kalman import FilterResult, _readonly


def check_y(y: ArrayLike, batch: tuple, m: int, prior: str = "g") -> np.ndarray:
    y = as_float_array(y, "y")
    if y.shape != batch + (m,):
        raise ValueError(f"y must have shape {batch + (m,)} to match {prior}; got {y.shape}")
    check_not_infinite(y)  # as kf_update: an infinite value gave NaN means
    return y


def check_gaussian(g: object) -> Gaussian:
    if not isinstance(g, Gaussian):
        raise TypeError(f"g must be a vistrack.Gaussian; got {type(g).__name__}")
    return g


def check_h_size(z: np.ndarray, m: int, x: np.ndarray) -> np.ndarray:
    """``z``, the measurement model's values ``h(x)`` for states ``x (..., n)``, or a
    ValueError where they are not ``(..., m)``, ``m`` values a state, the size of its ``R``
    (numpy's broadcast error named neither; the UKF's compiled step read the first ``m``
    values, without a word)."""
    if np.shape(z) != np.shape(x)[:-1] + (m,):
        raise ValueError(f"the measurement model's h(x) gives values of shape {np.shape(z)} "
                         f"for states of shape {np.shape(x)}; its R is {m} x {m}, so "
                         f"{np.shape(x)[:-1] + (m,)} was expected")
    return z


def check_model_values(z: np.ndarray, points: np.ndarray, what: str) -> None:
    """Name the sigma point or member (``what``) ``points[..., k, :]`` at which the
    measurement model's values ``z (..., K, m)`` hold NaN or infinity: a batch's estimates,
    or an ensemble's members, came out NaN without a word."""
    bad = ~np.isfinite(z).all(axis=-1)
    if bad.any():
        at = tuple(int(i) for i in np.argwhere(bad)[0])
        raise ValueError(f"the measurement model gave NaN or infinity at {what} "
                         f"[{', '.join(map(str, at))}]: "
                         f"h({np.array2string(points[at], precision=4)}) = "
                         f"{np.array2string(z[at], precision=4)}")


def step_times(dt: ArrayLike | None, times: ArrayLike | None,
               T: int) -> tuple[np.ndarray, np.ndarray]:
    """``dt`` (a scalar, the ``T-1`` intervals between steps, or ``(T,)`` with ``dt[t]`` the
    step from ``t-1`` to ``t``, ``dt[0]`` unused) as ``(T,)``, as ``KalmanFilter`` takes it,
    and the time of each step: ``times``, by default the cumulative ``dt`` from 0. ``dt``
    None is ``np.diff(times)`` where ``times`` is given, else 1; given both, they must agree
    (``times`` alone filtered with steps of 1, whatever it said: a gap of 4.9 s was
    predicted over 1 s, without a word)."""
    if dt is None and times is None:
        dt = 1.0
    # the rounding the times and steps came with (float32 times of 1/30 s differ from
    # float64 steps by 5e-9, within their own rounding)
    eps = max(eps_of(times), eps_of(dt))
    if times is not None:
        times = as_float_array(times, "times", ndim=(1,))
        if times.shape != (T,):
            raise ValueError(f"times must have shape ({T},); got {times.shape}")
        if not np.isfinite(times).all():  # a model of time (growth) gave NaN states
            k = int(np.flatnonzero(~np.isfinite(times))[0])
            raise ValueError(f"times must be finite; times[{k}] = {times[k]}")
        gaps = np.diff(times)
        if (gaps < 0).any():
            k = 1 + int(np.flatnonzero(gaps < 0)[0])
            raise ValueError(f"times must not decrease; times[{k}] = {times[k]} comes after "
                             f"times[{k - 1}] = {times[k - 1]}")
        if dt is None:
            dt = gaps
    # (True was a step of 1 here, where the models refuse it)
    d = as_float_array(dt, "dt", ndim=(0, 1), not_boolean="a number or an array of numbers")
    if d.ndim == 1 and d.shape == (T - 1,):  # np.diff(times), as the Kalman filter takes
        d = np.concatenate([d[:1] if T > 1 else [1.0], d])
    if d.ndim == 1 and d.shape != (T,):
        raise ValueError(f"dt must be a scalar, the T-1={T - 1} intervals between steps or "
                         f"T={T} values (dt[0] unused); got shape {d.shape}")
    dts = np.broadcast_to(d, (T,))
    ok = np.isfinite(dts[1:]) & (dts[1:] >= 0)
    if not ok.all():
        # (a user's model took it and gave NaN states, blamed on the model or on a lost
        # target; a negative step was refused by the model, after the particle filter had
        # drawn its first particles)
        k = 1 + int(np.flatnonzero(~ok)[0])
        raise ValueError(f"dt must be finite and >= 0 (dt[0], before the first step, aside); "
                         f"the step to step {k} is {dts[k]}")
    if times is None:
        return dts, np.concatenate([[0.0], np.cumsum(dts[1:])])
    # the steps the times say, within their rounding (times of 1.7e9 s, an epoch's, differ
    # from their steps' sum by a few 1e-7)
    slack = 1e-9 * np.abs(dts[1:]) + 64 * eps * np.abs(times).max()
    off = np.abs(dts[1:] - np.diff(times)) > slack
    if off.any():
        k = 1 + int(np.flatnonzero(off)[0])
        raise ValueError(f"dt and times disagree: the step to step {k} is {dts[k]} in dt and "
                         f"{times[k] - times[k - 1]} in times (times[{k}] - times[{k - 1}]); "
                         f"give one of them")
    return dts, times


class _Moments(Protocol):
    def moments(self) -> tuple[np.ndarray, np.ndarray]: ...


State = TypeVar("State", bound=Gaussian | _Moments)


def run_sequence(ys: ArrayLike, x0: ArrayLike | None, P0: ArrayLike | None, n: int, m: int,
                 dt: ArrayLike | None, times: ArrayLike | None,
                 predict: Callable[[State, float, float], State],
                 update: Callable[[State, np.ndarray], tuple[State, np.ndarray]],
                 state: State | None = None,
                 start: Callable[[], State] | None = None) -> FilterResult:
    """Filter ``ys (T, m)`` or ``(B, T, m)`` with ``predict(state, dt, t)`` and
    ``update(state, y) -> (state, loglik)``, where ``state`` starts as ``Gaussian(x0, P0)`` (or
    the given ``state``) and ``moments(state) -> (mean, cov)`` is ``state.mean, state.cov``.

    ``dt`` is a scalar or ``(T,)`` (``dt[t]`` is the step from ``t-1`` to ``t``); ``times``
    defaults to the cumulative sum of ``dt`` with ``times[0] = 0``. Given ``start`` instead
    of ``state``, the first state is ``start()``, made once ``ys``, ``dt`` and ``times`` are
    checked (an ensemble drawn first used up its generator's draws on a call refused)."""
    Y, single, dts, times = sequence_inputs(ys, m, dt, times)
    B, T, _ = Y.shape
    if start is not None:
        state = start()
    if state is None:
        mean0, cov0 = check_prior(x0, P0, n, series=B)
        if B == 1 and mean0.ndim == 1 and cov0.ndim == 2:
            # one series: the state is one Gaussian, which runs the compiled one-Gaussian paths
            state = cast(State, Gaussian(mean0.copy(), cov0.copy()))
            Y = Y[0]
        else:
            state = cast(State, Gaussian(np.broadcast_to(mean0, (B, n)).copy(),
                                         np.broadcast_to(cov0, (B, n, n)).copy()))
    means = np.empty((B, T, n))
    covs = np.empty((B, T, n, n))
    pmeans = np.empty((B, T, n))
    pcovs = np.empty((B, T, n, n))
    loglik = np.zeros(B)
    t, predicted = 0, 0  # the steps whose predictions are stored
    # once, not a step at a time (a few microseconds of each step's numpy calls, a tenth of
    # the EKF's step on one Gaussian): the steps as floats, the steps missing whole, and
    # views of the results by step, (T, n) for one series and (T, B, n) for a batch
    steps, at = dts.tolist(), times.tolist()
    gone = np.isnan(Y).all(-1)  # (T,) where Y is one series' (T, m), else (B, T)
    gone = (gone if gone.ndim == 1 else gone.all(0)).tolist()
    by_step = [a[0] if B == 1 else a.swapaxes(0, 1) for a in (pmeans, pcovs, means, covs)]
    pm_t, pc_t, m_t, c_t = by_step
    try:
        for t in range(T):
            if t > 0:
                state = predict(state, steps[t], at[t])
            pm, pc = _moments(state)
            pm_t[t], pc_t[t] = pm, pc
            predicted = t + 1
            if gone[t]:
                mean, cov = pm, pc
            else:
                state, ll = update(state, Y[..., t, :])
                loglik += ll
                mean, cov = _moments(state)
            m_t[t], c_t[t] = mean, cov
    except ValueError as e:  # a state the step could not take: where it went wrong first
        bad = _not_finite(pmeans[:, :predicted], pcovs[:, :predicted], means[:, :t],
                          covs[:, :t], B > 1)
        if bad:
            raise ValueError(bad) from e
        if type(e) is ValueError:
            raise ValueError(f"step {t}: {e}") from e
        raise  # the model's own error (numpy's LinAlgError, a user's class) as it was
    bad = _not_finite(pmeans, pcovs, means, covs, B > 1)
    if bad:
        raise ValueError(bad)
    return sequence_result(means, covs, pmeans, pcovs, loglik, single)


def sequence_inputs(ys: ArrayLike, m: int, dt: ArrayLike | None,
                    times: ArrayLike | None) -> tuple[np.ndarray, bool, np.ndarray, np.ndarray]:
    """:func:`run_sequence`'s measurements ``ys`` checked and as ``(B, T, m)``, whether they
    were one series, and each step's ``dt`` and time (:func:`step_times`)."""
    Y = as_float_array(masked_batch(ys), "ys", ndim=(2, 3))  # (a list of masked series too)
    check_has_steps(Y)
    if Y.shape[-1] != m:
        raise ValueError(f"ys must have {m} measurement components (last axis); got "
                         f"{Y.shape[-1]}")
    check_not_infinite(Y, "ys")  # here, to name the step in the series
    single = Y.ndim == 2
    if single:
        Y = Y[None]
    dts, times = step_times(dt, times, Y.shape[1])
    return Y, single, dts, times


class CompiledRun(NamedTuple):
    """What a filter's compiled run over a sequence takes (``inputs``: the priors ``(B, n)``
    and ``(B, n, n)``, the measurements ``(B, T, m)``, each step's ``dt`` and time, the
    models' parameters per step and fixed, ``Q`` per distinct step and each step's index
    into them, ``R``, and which components are angles) and fills (``outputs``: corrected and
    predicted means and covariances ``(B, T, ...)``, the log-likelihoods ``(B,)``), and
    whether the measurements were one series."""

    inputs: tuple[Any, ...]
    outputs: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    single: bool

    def result(self) -> FilterResult:
        """The :class:`FilterResult` of the filled outputs."""
        return sequence_result(*self.outputs, self.single)


def compiled_run(mo: MotionFunctions, me: MeasurementFunctions, ys: ArrayLike, x0: ArrayLike,
                 P0: ArrayLike, dt: ArrayLike | None, times: ArrayLike | None
                 ) -> CompiledRun | None:
    """The arrays of a compiled run (:class:`CompiledRun`) of a filter of models with
    compiled one-state functions (``jit_params``), checked as :func:`run_sequence` checks
    them; None where a model's ``Q`` or ``jit_params`` refuses a step, or the parameters
    are not one row a step (the steps from Python then run, and name what they refuse)."""
    n, m = mo.n, me.m
    Y, single, dts, ts = sequence_inputs(ys, m, dt, times)
    B, T, _ = Y.shape
    mean0, cov0 = check_prior(x0, P0, n, series=B)
    # dt[0], the step before the first measurement, is not used (as from Python): the model
    # is not evaluated at it; Q once per distinct step
    dts = np.array(dts, dtype=float)
    dts[0] = dts[1] if T > 1 else 1.0
    ts = np.array(ts, dtype=float)
    # Q of each step predicted (none for one step), and the models' parameters; what the
    # model refuses is refused by the steps from Python, at the step it names
    steps, qi = np.unique(dts[1:], return_inverse=True)
    try:
        Qs = np.array([mo.Q(float(v)) for v in steps]).reshape(len(steps), n, n)
        fp = np.array(cast(Any, mo.model).jit_params(dts, ts), dtype=float)
        hp = np.array(cast(Any, me.model).jit_params(), dtype=float).ravel()
    except Exception:  # (the steps from Python raise it again, as they did)
        return None
    if fp.ndim != 2 or len(fp) != T:  # (the steps from Python do not read them)
        return None
    if not len(steps):
        Qs = np.zeros((1, n, n))
    qi = np.concatenate([[0], qi.ravel()]).astype(np.int64)
    # (writeable C-ordered copies, the types the kernels are built for ahead of time: np.array
    # of a broadcast view may come out Fortran-ordered, np.ascontiguousarray read-only, and
    # a caller's read-only times compiled the kernel again, seconds)
    inputs = (np.array(np.broadcast_to(mean0, (B, n)), dtype=float, order="C"),
              np.array(np.broadcast_to(cov0, (B, n, n)), dtype=float, order="C"),
              np.array(Y, order="C"), dts, ts, np.ascontiguousarray(fp), hp, Qs, qi,
              np.array(me.Rm, dtype=float), np.array(me.angle_mask, dtype=np.bool_))
    outputs = (np.empty((B, T, n)), np.empty((B, T, n, n)), np.empty((B, T, n)),
               np.empty((B, T, n, n)), np.zeros(B))
    return CompiledRun(inputs, outputs, single)


_PYTHON_OF = {"jit_f": "f", "jit_h": "h", "jit_jacobian": "jacobian"}


def compiled_stands_for(model: object, names: tuple[str, ...]) -> bool:
    """Whether ``model``'s compiled one-state functions ``names`` (``jit_f``, ...) stand for
    its Python ones (``f``, ...): each, its Python twin and ``jit_params`` defined by one
    class of its type's, none set on the instance. A subclass of a shipped model that
    overrides ``f`` inherits ``jit_f``, which is not its ``f``: the compiled filters gave
    the base model's estimates, without a word."""
    wanted = {*names, *(_PYTHON_OF[n] for n in names), "jit_params"}
    if wanted & set(getattr(model, "__dict__", {})):
        return False
    owners = {next((k for k in type(model).__mro__ if n in vars(k)), None) for n in wanted}
    return len(owners) == 1 and None not in owners


def compiled_functions(mo: MotionFunctions, me: MeasurementFunctions,
                       motion_names: tuple[str, ...],
                       measurement_names: tuple[str, ...]) -> tuple[Ref, ...] | None:
    """The module and name of each compiled one-state function ``motion_names`` of the motion
    model and ``measurement_names`` of the measurement model (``jit_f``, ``jit_jacobian``,
    ...; each model with ``jit_params``), for a generated kernel to import; or None, and the
    steps run from Python: a model without them, or whose Python functions are not theirs
    (:func:`compiled_stands_for`), a measurement model of another state's size (its compiled
    functions would read past the state), or a measurement residual or mean of its own (a
    compiled filter takes differences, angles wrapped)."""
    motion, meas = mo.model, me.model
    if not (me.standard and getattr(meas, "ndim_state", None) == mo.n
            and compiled_stands_for(motion, motion_names)
            and compiled_stands_for(meas, measurement_names)):
        return None
    refs = tuple(jit_ref(getattr(model, name, None))
                 for model, names in ((motion, motion_names), (meas, measurement_names))
                 for name in names)
    return None if any(r is None for r in refs) else cast(tuple[Ref, ...], refs)


def own_steps(f: object, originals: tuple[Callable, Callable]) -> bool:
    """Whether ``f``'s ``predict`` and ``update`` are its class's ``originals``: not a
    subclass's, not set on the instance, not patched on the class."""
    return (type(f).predict is originals[0]  # type: ignore[attr-defined]
            and type(f).update is originals[1]  # type: ignore[attr-defined]
            and "predict" not in vars(f) and "update" not in vars(f))


def sequence_result(means: np.ndarray, covs: np.ndarray, pmeans: np.ndarray,
                    pcovs: np.ndarray, loglik: np.ndarray, single: bool) -> FilterResult:
    """The :class:`FilterResult` of a filter's ``(B, T, ...)`` outputs, one series' without
    its batch axis, its arrays read-only."""
    # copies, not views of the results (which are made read-only below; a view made before
    # would stay writable, and changing `last` in place changed them)
    last = Gaussian(means[:, -1].copy(), covs[:, -1].copy())
    if single:
        means, covs, pmeans, pcovs = means[0], covs[0], pmeans[0], pcovs[0]
        loglik = loglik[0]
        last = Gaussian(last.mean[0], last.cov[0])
    loglik = np.asarray(loglik)
    # (the log-likelihood was left writable, where FilterResult says its arrays are not)
    _readonly(means, covs, pmeans, pcovs, loglik)
    return FilterResult(means, covs, pmeans, pcovs, loglik, last, False)


def _not_finite(pmeans: np.ndarray, pcovs: np.ndarray, means: np.ndarray, covs: np.ndarray,
                batch: bool) -> str | None:
    """The first step whose prediction or correction ``(B, T, ...)`` is not finite, said (a
    model that gave NaN or infinity, which every step after would carry), or None. The
    corrections may stop a step before the predictions."""
    ok_p = np.isfinite(pmeans).all(-1) & np.isfinite(pcovs).all((-2, -1))
    ok_c = np.ones_like(ok_p)
    T = means.shape[1]
    ok_c[:, :T] = np.isfinite(means).all(-1) & np.isfinite(covs).all((-2, -1))
    bad = ~(ok_p & ok_c)
    if not bad.any():
        return None
    t = int(np.flatnonzero(bad.any(axis=0))[0])
    b = int(np.flatnonzero(bad[:, t])[0])
    series = f" of series {b}" if batch else ""
    if not ok_p[b, t]:
        m, P = pmeans[b, t], pcovs[b, t]
        what, model = f"the prediction to step {t}{series}", "the motion model"
    else:
        m, P = means[b, t], covs[b, t]
        what, model = f"the correction at step {t}{series}", "the measurement model"
    return (f"{what} is not finite (mean {np.array2string(m, precision=4)}, variances "
            f"{np.array2string(np.diagonal(P), precision=4)}): {model} gave NaN or infinity "
            "there")


def _moments(state: Gaussian | _Moments) -> tuple[np.ndarray, np.ndarray]:
    if isinstance(state, Gaussian):
        return state.mean, state.cov
    return state.moments()
