r"""The Kalman filter: batched kernels, a whole-sequence function and the seeds' scalar
equations (the class over models is :mod:`vistrack.filters.linear`).

Notation follows the seeds: the dynamics ``x_i ~ N(D x_{i-1}, Σd)`` are ``F``, ``Q`` here and the
measurements ``y_i ~ N(M x_i, Σm)`` are ``H``, ``R``. The prior ``x0, P0`` is the seeds'
``x̄0⁻, Σ0⁻``: the prediction *for the first step*, which the first measurement corrects.

Prediction:  ``x̄ᵢ⁻ = F x̄ᵢ₋₁⁺``,   ``Σᵢ⁻ = F Σᵢ₋₁⁺ F' + Q``

Correction:  ``K = Σᵢ⁻ H' (H Σᵢ⁻ H' + R)⁻¹``,  ``x̄ᵢ⁺ = x̄ᵢ⁻ + K (yᵢ - H x̄ᵢ⁻)``,
``Σᵢ⁺ = (I - K H) Σᵢ⁻ (I - K H)' + K R K'`` (Joseph form: equal to the seeds' ``(I - K H) Σᵢ⁻`` in
exact arithmetic, but an error in the gain changes it only to second order). It is kept exactly
symmetric; the tests run 10⁶ steps of a badly scaled model and find every covariance positive
definite.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._validate import (
    as_flag,
    as_float_array,
    as_measurement_series,
    check_finite,
    check_has_steps,
    check_linear_gaussian,
    check_not_infinite,
    check_psd,
    check_symmetric,
)
from ..types import Gaussian
from . import _codegen, _kernels

__all__ = [
    "FilterResult",
    "kalman_filter",
    "kf_predict",
    "kf_update",
    "kf_step",
    "kalman_filter_1d",
    "FilterResult1D",
]


@dataclass(frozen=True)
class FilterResult:
    """The output of :func:`kalman_filter` (and of the other filters' ``filter``).

    Arrays are read-only. ``(...)`` is ``()`` for one series and ``(B,)`` for a batch.

    Attributes
    ----------
    means : (..., T, n) ndarray
        Corrected means ``x̄ᵢ⁺``.
    covs : (..., T, n, n) ndarray or None
        Corrected covariances ``Σᵢ⁺``; None when ``store_covs=False``.
    pred_means : (..., T, n) ndarray or None
        Predicted means ``x̄ᵢ⁻`` (``pred_means[..., 0, :]`` is the prior ``x0``); None when
        ``store_covs=False``.
    pred_covs : (..., T, n, n) ndarray or None
        Predicted covariances ``Σᵢ⁻``; None when ``store_covs=False``.
    loglik : (...) ndarray
        ``log p(y_0, ..., y_{T-1})``, summed over the observed components.
    last : Gaussian
        The corrected estimate at the last step, batch shape ``(...)``.
    shared_covs : bool
        True when every series shared one covariance sequence (``covs`` is then a broadcast
        view).

    Examples
    --------
    >>> F, H = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    >>> ys = np.array([[0.1], [0.9], [np.nan], [3.2]])
    >>> res = kalman_filter(ys, F=F, Q=0.01 * np.eye(2), H=H, R=[[0.25]],
    ...                     x0=[0.0, 1.0], P0=np.eye(2))
    >>> res.last.mean.round(3), round(float(res.loglik), 3), res.means.flags.writeable
    (array([3.148, 1.05 ]), -3.579, False)
    """

    means: np.ndarray
    covs: np.ndarray | None
    pred_means: np.ndarray | None
    pred_covs: np.ndarray | None
    loglik: np.ndarray
    last: Gaussian
    shared_covs: bool = False


def _is_dask(x: object) -> bool:
    """A Dask collection (:mod:`vistrack.filters.chunked`), told without importing Dask."""
    return type(x).__module__.split(".", 1)[0] == "dask"


def _readonly(*arrays: np.ndarray | None) -> None:
    for a in arrays:
        if a is not None and a.flags.writeable:
            a.flags.writeable = False


def _prior(x0: ArrayLike, P0: ArrayLike, B: int,
           n_model: int | None = None) -> tuple[np.ndarray, np.ndarray]:
    """The prior, checked; ``n_model`` is the state size of ``F`` when known: an ``x0`` whose
    length disagrees with both ``P0`` and ``F`` is named (rather than ``P0``)."""
    x = as_float_array(x0, "x0", ndim=(1, 2))
    P = as_float_array(P0, "P0", ndim=(2, 3))
    n = x.shape[-1]
    n_P = P.shape[-1]
    if n != n_P and n_model == n_P and P.shape[-2] == n_P:
        raise ValueError(f"x0 must have shape ({n_P},) or (B={B}, {n_P}) to match P0 and F; "
                         f"got {x.shape}")
    if x.ndim == 2 and x.shape[0] not in (1, B):
        raise ValueError(f"x0 must have shape ({n},) or (B={B}, {n}); got {x.shape}")
    if P.shape[-2:] != (n, n) or (P.ndim == 3 and P.shape[0] not in (1, B)):
        raise ValueError(f"P0 must have shape ({n}, {n}) or (B={B}, {n}, {n}); got {P.shape}")
    check_finite(x, "x0")
    check_finite(P, "P0")
    check_psd(P, "P0")
    return x.reshape(-1, n), P.reshape(-1, n, n)


def _shared_gains(Pp: np.ndarray, H: np.ndarray,
                  R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The Kalman gains ``(T, n, m)`` and the Cholesky factors of ``S = H Pp H' + R``
    ``(T, m, m)`` of every fully measured step, from the predicted covariances ``Pp (T, n,
    n)``, ``H``, ``R`` stacks of 1 or ``T``: what :func:`_kernels.kf_means_shared` takes."""
    HP = H @ Pp
    S = HP @ np.swapaxes(H, -1, -2) + R
    S = (S + np.swapaxes(S, -1, -2)) / 2
    return (np.ascontiguousarray(np.swapaxes(np.linalg.solve(S, HP), -1, -2)),
            np.linalg.cholesky(S))


def _raise_not_pd(bad_t: int, series: int | None = None) -> None:
    if bad_t >= 0:
        where = f"step {bad_t}" + ("" if series is None else f" of series {series}")
        raise ValueError(
            f"the innovation covariance H P H' + R is not positive definite at {where}; "
            "R must be positive definite on the observed components (or P must make S so)"
        )


def _failing_series(y: np.ndarray, F: np.ndarray, Q: np.ndarray, H: np.ndarray,
                    R: np.ndarray, x0: np.ndarray, P0: np.ndarray, bad_t: int) -> int | None:
    """The first series of a batch whose innovation covariance is not positive definite at
    step ``bad_t`` (the batch kernels say the step alone), each run alone by the one-series
    kernel: on the error's path only."""
    B, T, _ = y.shape
    n, m = x0.shape[-1], y.shape[-1]
    for b in range(B):
        t, _ = _kernels.single_kernel(n, m)(
            y[b], F, Q, H, R, x0[b % len(x0)], P0[b % len(P0)], np.empty((T, n)),
            np.empty((1, n, n)), np.empty((1, n)), np.empty((1, n, n)), np.empty((n, n)),
            False,
        )
        if t == bad_t:
            return b
    return None


def kalman_filter(
    ys: ArrayLike,
    *,
    F: ArrayLike,
    Q: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    x0: ArrayLike,
    P0: ArrayLike,
    store_covs: bool = True,
) -> FilterResult:
    r"""Run the Kalman filter over one series or a batch of series.

    For ``t = 0, ..., T-1``, from the prior :math:`\bar x_0^- = x_0`, :math:`\Sigma_0^- =
    P_0`:

    .. math::

        \bar x_t^- = F_t \bar x_{t-1}^+, \quad \Sigma_t^- = F_t \Sigma_{t-1}^+ F_t' + Q_t
        \quad (t > 0),

        K_t = \Sigma_t^- H_t' (H_t \Sigma_t^- H_t' + R_t)^{-1}, \quad
        \bar x_t^+ = \bar x_t^- + K_t (y_t - H_t \bar x_t^-), \quad
        \Sigma_t^+ = (I - K_t H_t) \Sigma_t^- (I - K_t H_t)' + K_t R_t K_t',

    the correction over the observed components of :math:`y_t` (see the module).

    Parameters
    ----------
    ys : (T, m) or (B, T, m) array_like
        Measurements. A NaN component (or a masked entry of a numpy masked array, pykalman's
        convention) is missing: a row of NaN means no measurement at that step
        (predict only); NaN in some components updates with the others.
    F, Q : (n, n) or (T, n, n) array_like
        Dynamics and process noise, constant or per step (``F[t]`` predicts step ``t``; the
        first step has no prediction, so ``F[0]`` and ``Q[0]`` are not used).
    H, R : (m, n) and (m, m), or (T, m, n) and (T, m, m) array_like
        Measurement matrix and noise covariance, constant or per step.
    x0 : (n,) or (B, n) array_like
        Prior mean of the first step (the seeds' ``x̄0⁻``), corrected by ``ys[..., 0, :]``;
        one for all series or one per series.
    P0 : (n, n) or (B, n, n) array_like
        Prior covariance of the first step (the seeds' ``Σ0⁻``), symmetric positive
        semi-definite.
    store_covs : bool
        If False, only the corrected means, the log-likelihood and the last Gaussian are kept
        (``covs``, ``pred_means`` and ``pred_covs`` are None), which saves ``B T n (2 n + 1)``
        floats and most of the memory traffic on large batches.

    Returns
    -------
    FilterResult
        Means ``(..., T, n)``, covariances ``(..., T, n, n)``, predictions, the
        log-likelihood ``(...)`` and the last estimate; ``(...)`` is ``()`` for ``ys`` of
        shape ``(T, m)`` and ``(B,)`` for ``(B, T, m)``.

    Raises
    ------
    ValueError
        If ``ys`` has no step (``T = 0``), a shape disagrees (the message names the argument),
        a value is not finite, ``Q``, ``R`` or ``P0`` is not symmetric
        positive semi-definite, or an innovation covariance ``H P H' + R`` is not positive
        definite (the message names the step).
    TypeError
        If ``store_covs`` is not True or False.

    See Also
    --------
    KalmanFilter : The same from motion and measurement models.
    rts_smooth : Smoothing of the result.

    Notes
    -----
    As the seeds observe, the covariance does not depend on the measured values. Series that share
    ``P0`` and the pattern of missing components therefore share every covariance and gain: these
    are computed once, and each series then costs only its mean recursion. Other batches carry one
    covariance per series. Large ones (100,000 series-steps or more, state size up to 6,
    measurement size up to 3) run a kernel generated for the zeros and ones of ``F``, ``Q``,
    ``H``, ``R``; it compiles in a few seconds the first time a pattern is seen, and is then
    cached on disk (``$VISTRACK_CACHE_DIR``, by default ``~/.cache/vistrack/kernels``). With
    constant matrices and fully observed steps, the covariances converge to their steady state,
    after which only the means are computed.

    References
    ----------
    .. [1] R. E. Kalman, "A new approach to linear filtering and prediction problems",
       *Journal of Basic Engineering* 82(1), 1960.

    Examples
    --------
    >>> import numpy as np
    >>> from vistrack.filters import kalman_filter
    >>> F = np.array([[1.0, 1.0], [0.0, 1.0]]); H = np.array([[1.0, 0.0]])
    >>> ys = np.array([[0.1], [0.9], [np.nan], [3.2]])
    >>> res = kalman_filter(ys, F=F, Q=0.01 * np.eye(2), H=H, R=[[0.25]],
    ...                     x0=[0.0, 1.0], P0=np.eye(2))
    >>> res.means.shape, res.covs.shape, res.loglik.shape
    ((4, 2), (4, 2, 2), ())

    Two series with the same missing values share their covariances:

    >>> res = kalman_filter(np.stack([ys, ys + 1]), F=F, Q=0.01 * np.eye(2), H=H, R=[[0.25]],
    ...                     x0=[0.0, 1.0], P0=np.eye(2))
    >>> res.means.shape, res.loglik.shape, res.shared_covs
    ((2, 4, 2), (2,), True)
    """
    store_covs = as_flag(store_covs, "store_covs")  # ("no" was true)
    if _is_dask(ys):  # a batch larger than memory: filtered lazily, chunk by chunk
        from . import chunked

        return chunked.kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0,
                                     store_covs=store_covs)
    y, single = as_measurement_series(ys)
    check_has_steps(y[0] if single else y)
    B, T, m = y.shape
    f = _shape(F, "F")
    x0_, P0_ = _prior(x0, P0, B, f[-1] if len(f) >= 2 else None)
    n = x0_.shape[1]
    F_, Q_, H_, R_ = check_linear_gaussian(F, Q, H, R, n, m, T)

    means = np.empty((B, T, n))
    pmeans = np.empty((B, T, n)) if store_covs else np.empty((1, 1, n))
    loglik = np.empty(B)
    shared = False
    if B > 1 and P0_.shape[0] == 1:  # only then can the series share their covariances
        mask = np.isnan(y)
        shared = bool((mask == mask[0]).all())
    if shared and store_covs and not mask[0].any():
        # every step fully measured: the covariances once, by the one-series kernel (which
        # stops updating them once they reach their steady state), and the gains and the
        # Cholesky factors of S from its predicted covariances
        c4, pc4, last1 = np.empty((1, T, n, n)), np.empty((1, T, n, n)), np.empty((1, n, n))
        bad_t, _ = _kernels.single_kernel(n, m)(
            y[0], F_, Q_, H_, R_, x0_[0], P0_[0], np.empty((T, n)), c4[0], np.empty((T, n)),
            pc4[0], last1[0], True,
        )
        _raise_not_pd(bad_t)
        gains, chol = _shared_gains(pc4[0], H_, R_)
    elif shared:
        # covariances, gains and Cholesky factors once, from the first series
        gains = np.empty((T, n, m))
        chol = np.empty((T, m, m))
        c4 = np.empty((1, T, n, n)) if store_covs else np.empty((1, 1, 1, 1))
        pc4 = np.empty((1, T, n, n)) if store_covs else np.empty((1, 1, 1, 1))
        last1 = np.empty((1, n, n))
        bad_t = _kernels.kf_batch(
            y[:1], F_, Q_, H_, R_, x0_[:1], P0_, np.empty((1, T, n)), c4, np.empty((1, T, n)),
            pc4, np.empty(1), last1, gains, chol, store_covs,
        )
        _raise_not_pd(bad_t)
    if shared:
        _kernels.kf_means_shared(y, F_, H_, x0_, gains, chol, means, pmeans, loglik, store_covs)
        covs = np.broadcast_to(c4, (B, T, n, n)) if store_covs else None
        pcovs = np.broadcast_to(pc4, (B, T, n, n)) if store_covs else None
        last_P = np.broadcast_to(last1, (B, n, n))
    elif B == 1 and P0_.shape[0] == 1:
        # one series: the scalar kernel (the SoA kernel's loops would have length one)
        covs = np.empty((1, T, n, n)) if store_covs else np.empty((1, 1, n, n))
        pcovs = np.empty((1, T, n, n)) if store_covs else np.empty((1, 1, n, n))
        last_P = np.empty((1, n, n))
        bad_t, loglik[0] = _kernels.single_kernel(n, m)(
            y[0], F_, Q_, H_, R_, x0_[0], P0_[0], means[0], covs[0], pmeans[0], pcovs[0],
            last_P[0], store_covs,
        )
        _raise_not_pd(bad_t)
        if not store_covs:
            covs = pcovs = None
    else:
        covs = np.empty((B, T, n, n)) if store_covs else np.empty((1, 1, 1, 1))
        pcovs = np.empty((B, T, n, n)) if store_covs else np.empty((1, 1, 1, 1))
        last_P = np.empty((B, n, n))
        if _codegen.worth_it(n, m, B * T):
            # straight-line code for this model's zeros and ones, compiled once per machine
            codes = (_codegen.entry_codes(a) for a in (F_, Q_, H_, R_))
            bad_t = _codegen.batch_kernel(n, m, *codes)(
                y, F_, Q_, H_, R_, x0_, P0_, means, covs, pmeans, pcovs, loglik, last_P,
                store_covs,
            )
        else:
            bad_t = _kernels.kf_batch(
                y, F_, Q_, H_, R_, x0_, P0_, means, covs, pmeans, pcovs, loglik, last_P,
                np.empty((0, n, m)), np.empty((0, m, m)), store_covs,
            )
        if bad_t >= 0:  # (the kernels give the step; the series is found by running each alone)
            _raise_not_pd(bad_t, _failing_series(y, F_, Q_, H_, R_, x0_, P0_, bad_t))
        if not store_covs:
            covs = pcovs = None
    pred_means: np.ndarray | None = pmeans if store_covs else None
    if single:
        # loglik[0, ...]: a 0-d view, made read-only with the rest (a scalar, taken as a new
        # array, was writable)
        means, loglik, last_P = means[0], loglik[0, ...], last_P[0]
        pred_means, covs, pcovs = (None if a is None else a[0]
                                   for a in (pred_means, covs, pcovs))
    # a copy: a view made before the arrays are made read-only would stay writable, and a
    # tracker going on from `last` in place changed the results' last means under them
    last = Gaussian(means[..., -1, :].copy(), last_P)
    _readonly(means, covs, pred_means, pcovs, loglik)
    return FilterResult(means, covs, pred_means, pcovs, np.asarray(loglik), last, shared)


def _contiguous(a: np.ndarray) -> np.ndarray:
    return a if a.flags.c_contiguous else np.ascontiguousarray(a)


def _one_batch_axis(a: np.ndarray, tail: int) -> np.ndarray:
    """A contiguous ``a (..., *tail)`` whose batch axes, if more than one, are made one: the
    kernels are compiled (at install) for a single Gaussian and for a batch of one axis, and a
    batch of another rank would compile again on first use."""
    a = _contiguous(a)
    return a.reshape((-1,) + a.shape[a.ndim - tail:]) if a.ndim > tail + 1 else a


def _small_matrix(value: ArrayLike, name: str, rows: int, cols: int) -> np.ndarray:
    """A constant ``(rows, cols)`` float64 matrix, checked for shape here (the kernels check
    finiteness and symmetry, which costs less there)."""
    if type(value) is np.ndarray and value.dtype == np.float64 and value.flags.c_contiguous:
        arr = value
    else:
        arr = as_float_array(value, name)
    if not arr.flags.writeable:
        # the kernels are compiled (at install) for writable arrays: a read-only one (a model's
        # matrix kept with setflags(write=False)) would compile each again, for seconds
        arr = arr.copy()
    if arr.shape != (rows, cols):
        raise ValueError(f"{name} must have shape ({rows}, {cols}); got {arr.shape}")
    return arr


_KERNEL_ERRORS = {
    1: "{a} must be finite",
    2: "{b} must be finite",
    3: "{b} must be symmetric",
    4: "the innovation covariance H P H' + R is not positive definite for some Gaussian; "
    "R must be positive definite on the observed components (or P must make S so)",
    5: "H must be finite",
    6: "R must be finite",
    7: "R must be symmetric",
    8: "{b} must be positive semi-definite: a variance (diagonal entry) is negative, or a "
    "covariance is larger than the product of its two standard deviations",
    13: "g.mean must be finite",
    14: "g.cov must be finite",
    12: "R must be positive semi-definite: a variance (diagonal entry) is negative, or a "
    "covariance is larger than the product of its two standard deviations",
}


def _matrix_entry(code: int, a: str, b: str, mats: dict[str, ArrayLike]) -> None:
    """The entry a kernel's ``code`` is about, named from the matrices themselves (checked
    in Python only here, on the way to the error)."""
    name = {1: a, 2: b, 3: b, 8: b, 5: "H", 6: "R", 7: "R", 12: "R", 13: "g.mean",
            14: "g.cov"}.get(code)
    if name not in mats:
        return
    arr = np.asarray(mats[name], dtype=float)
    if code in (1, 2, 5, 6, 13, 14):
        check_finite(arr, name)
    elif code in (3, 7):
        check_symmetric(arr, name)
    elif code in (8, 12):
        # the compiled check's own tolerances (_kernels.check_matrices), so that the entry
        # named is the one it refused (-1e-20 beside 1 is a variance of 0 there)
        tol = 1e-8
        d = np.diagonal(arr)
        top = float(np.abs(d).max())
        if (d < -tol * top).any():
            i = int(np.argmax(d < -tol * top))
            raise ValueError(f"{name} must be positive semi-definite; {name}[{i}, {i}] = "
                             f"{d[i]:g}, a negative variance")
        over = np.triu(arr ** 2 > np.outer(d, d) * (1 + tol) + (tol * top) ** 2, 1)
        if over.any():
            i, k = (int(v) for v in np.argwhere(over)[0])
            if min(d[i], d[k]) < 0:  # (a variance below 0 within the tolerance: the product
                # of the two is then below 0, and the entry was named, beside a NaN)
                j = i if d[i] < 0 else k
                raise ValueError(f"{name} must be positive semi-definite; {name}[{j}, {j}] = "
                                 f"{d[j]:g}, a negative variance")
            raise ValueError(f"{name} must be positive semi-definite; {name}[{i}, {k}] = "
                             f"{arr[i, k]:g}, beyond the product of the two standard "
                             f"deviations, {np.sqrt(d[i] * d[k]):g}")


def _kernel_error(code: int, a: str, b: str, mats: dict[str, ArrayLike] | None = None) -> None:
    if mats:
        _matrix_entry(code, a, b, mats)
        if code in (13, 14) and "F" in mats and "H" in mats:
            # kf_step: g was finite, so its prediction overflowed (g.mean was blamed)
            raise ValueError("the prediction F m, F P F' + Q is not finite: it overflowed "
                             "(g, F or Q too large)")
    raise ValueError(_KERNEL_ERRORS[code].format(a=a, b=b))


def _with_measurement(g: Gaussian, y: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Check ``g`` and one measurement per Gaussian; contiguous ``mean, cov, y`` for a kernel."""
    if not isinstance(g, Gaussian):
        raise TypeError(f"g must be a vistrack.Gaussian; got {type(g).__name__}")
    mean = g.mean
    if not (type(y) is np.ndarray and y.dtype == np.float64):
        y = as_float_array(y, "y")
    if y.ndim != mean.ndim or y.shape[:-1] != mean.shape[:-1]:
        want = ", ".join(map(str, mean.shape[:-1] + ("m",)))  # (the tuple printed 'm' quoted)
        raise ValueError(f"y must have shape ({want}), a measurement of m values for each of "
                         f"g's {mean.shape[:-1]}; got {y.shape}")
    check_not_infinite(y)  # NaN is a missing value; an infinite one gave NaN means
    return _one_batch_axis(mean, 1), _one_batch_axis(g.cov, 2), _one_batch_axis(y, 1)


def kf_step(
    g: Gaussian, y: ArrayLike, F: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike
) -> Gaussian:
    r""":func:`kf_predict` then :func:`kf_update` in one call: the usual loop of one tracker.

    Equal to ``kf_update(kf_predict(g, F, Q), y, H, R)``, with the same checks:

    .. math:: \bar x^- = F \bar x, \qquad P^- = F P F' + Q,

    then the correction of :math:`(\bar x^-, P^-)` with ``y``.

    Parameters
    ----------
    g : Gaussian
        Estimates at the previous step, batch shape ``(...)``, state size ``n``.
    y : (..., m) array_like
        One measurement per Gaussian; NaN components are missing.
    F, Q : (n, n) array_like
        Dynamics and process noise.
    H, R : (m, n) and (m, m) array_like
        Measurement matrix and noise covariance.

    Returns
    -------
    Gaussian
        The corrected estimates, batch shape ``(...)``.

    Raises
    ------
    TypeError
        If ``g`` is not a :class:`~vistrack.types.Gaussian`.
    ValueError
        If a shape disagrees, ``y`` is infinite (NaN is a missing value), a matrix is not
        finite, ``Q`` or ``R`` is not symmetric or has a negative variance or a correlation
        beyond ±1, or an innovation covariance is not positive definite.

    Examples
    --------
    >>> import numpy as np
    >>> from vistrack import Gaussian
    >>> g = Gaussian(np.zeros(2), np.eye(2))
    >>> F, Q, H, R = [[1.0, 1.0], [0.0, 1.0]], 0.01 * np.eye(2), [[1.0, 0.0]], [[0.5]]
    >>> for y in ([1.0], [2.1], [2.9]):
    ...     g = kf_step(g, y, F, Q, H, R)
    >>> g.mean.round(2)
    array([2.82, 0.86])
    """
    given = np.shape(y)
    mean, cov, y = _with_measurement(g, y)
    n, m = mean.shape[-1], y.shape[-1]
    _check_y_fits(given, n, m, H, R)
    code, mean, cov, ll = _kernels.step_batch(
        mean, cov, y, _small_matrix(F, "F", n, n),
        _small_matrix(Q, "Q", n, n), _small_matrix(H, "H", m, n), _small_matrix(R, "R", m, m),
    )
    if code >= 0:
        _kernel_error(code, "F", "Q", {"F": F, "Q": Q, "H": H, "R": R, "g.mean": g.mean,
                                       "g.cov": g.cov})
    return Gaussian._trusted(mean.reshape(g.mean.shape), cov.reshape(g.cov.shape))


def kf_predict(g: Gaussian, F: ArrayLike, Q: ArrayLike) -> Gaussian:
    r"""Predict every Gaussian of a batch one step: ``N(F m, F P F' + Q)``.

    .. math:: \bar x^- = F \bar x, \qquad P^- = F P F' + Q

    Parameters
    ----------
    g : Gaussian
        Estimates, batch shape ``(...)``, state size ``n``.
    F, Q : (n, n) array_like
        Checked for shape, finiteness, the symmetry of ``Q`` and what semi-definiteness asks
        of each variance and pair (variances >= 0, correlations within ±1); the full test of
        definiteness would cost more than the prediction (:func:`kalman_filter` makes it).

    Returns
    -------
    Gaussian
        The predictions, batch shape ``(...)``.

    Raises
    ------
    TypeError
        If ``g`` is not a :class:`~vistrack.types.Gaussian`.
    ValueError
        If ``F`` or ``Q`` has the wrong shape or is not finite, or ``Q`` is not symmetric or
        has a negative variance or a correlation beyond ±1.

    Examples
    --------
    >>> import numpy as np
    >>> from vistrack import Gaussian
    >>> g = Gaussian(np.zeros((5, 2)), np.tile(np.eye(2), (5, 1, 1)))
    >>> kf_predict(g, [[1, 1], [0, 1]], 0.1 * np.eye(2)).cov[0]
    array([[2.1, 1. ],
           [1. , 1.1]])
    """
    if not isinstance(g, Gaussian):
        raise TypeError(f"g must be a vistrack.Gaussian; got {type(g).__name__}")
    n = g.mean.shape[-1]
    code, mean, cov = _kernels.predict_batch_py(
        _one_batch_axis(g.mean, 1), _one_batch_axis(g.cov, 2), _small_matrix(F, "F", n, n),
        _small_matrix(Q, "Q", n, n),
    )
    if code >= 0:
        _kernel_error(code, "F", "Q", {"F": F, "Q": Q, "g.mean": g.mean, "g.cov": g.cov})
    return Gaussian._trusted(mean.reshape(g.mean.shape), cov.reshape(g.cov.shape))


def kf_update(g: Gaussian, y: ArrayLike, H: ArrayLike, R: ArrayLike) -> Gaussian:
    r"""Correct every Gaussian of a batch with its measurement.

    .. math::

        S = H P H' + R, \quad K = P H' S^{-1}, \quad
        \bar x^+ = \bar x + K (y - H \bar x), \quad
        P^+ = (I - K H) P (I - K H)' + K R K',

    over the observed components of ``y`` (Joseph form, kept symmetric): compiled, and equal
    to :func:`vistrack.filters.reference.kalman_update` to rounding.
    :meth:`KalmanFilter.update <vistrack.filters.KalmanFilter.update>` also gives the
    log-likelihood :math:`\log N(y; H \bar x, S)`.

    Parameters
    ----------
    g : Gaussian
        Predictions, batch shape ``(...)``, state size ``n``.
    y : (..., m) array_like
        One measurement per Gaussian; NaN components are missing (an all-NaN row leaves that
        Gaussian unchanged).
    H, R : (m, n) and (m, m) array_like
        Checked for shape, finiteness, the symmetry of ``R`` and its variances (>= 0) and
        correlations (within ±1); a non-positive-definite innovation covariance raises
        ``ValueError``.

    Returns
    -------
    Gaussian
        The corrected estimates, batch shape ``(...)``.

    Raises
    ------
    TypeError
        If ``g`` is not a :class:`~vistrack.types.Gaussian`.
    ValueError
        If a shape disagrees, ``y`` is infinite (NaN is a missing value), ``H`` or ``R`` is
        not finite, ``R`` is not symmetric or has a negative variance or a correlation beyond
        ±1, or an innovation covariance is not positive definite.

    References
    ----------
    .. [1] R. E. Kalman, "A new approach to linear filtering and prediction problems",
       *Journal of Basic Engineering* 82(1), 1960.

    Examples
    --------
    >>> from vistrack import Gaussian
    >>> g = Gaussian(np.zeros((2, 2)), np.tile(np.eye(2), (2, 1, 1)))
    >>> y = np.array([[1.0, np.nan], [np.nan, np.nan]])    # the second: nothing observed
    >>> post = kf_update(g, y, np.eye(2), 0.5 * np.eye(2))
    >>> post.mean.round(3), post.cov[0].diagonal().round(3)
    (array([[0.667, 0.   ],
           [0.   , 0.   ]]), array([0.333, 1.   ]))
    """
    return _update(g, y, H, R)[0]


def _shape(value: ArrayLike, name: str) -> tuple[int, ...]:
    """``np.shape(value)``, or the error that names ``value`` where it has none (a ragged
    list: numpy's "setting an array element with a sequence" before)."""
    try:
        return np.shape(value)
    except ValueError:
        as_float_array(value, name)
        raise


def _check_y_fits(given: tuple[int, ...], n: int, m: int, H: ArrayLike, R: ArrayLike) -> None:
    """Name ``y`` when ``H`` fits the state and ``R`` fits ``H`` but ``y`` (of shape
    ``given``, ``m`` values) does not: the measurement is the one of the wrong size."""
    h, r = _shape(H, "H"), _shape(R, "R")
    if len(h) in (2, 3) and h[-1] == n and h[-2] != m and (len(r) < 2 or r[-2:] == (h[-2],) * 2):
        raise ValueError(f"y must have {h[-2]} value{'s' if h[-2] != 1 else ''} a Gaussian, "
                         f"one for each row of H "
                         f"{h}; got shape {given}")


def _update(g: Gaussian, y: ArrayLike, H: ArrayLike, R: ArrayLike) -> tuple[Gaussian, np.ndarray]:
    """:func:`kf_update` and ``log N(y; H m, H P H' + R)`` per Gaussian (0 where nothing is
    observed)."""
    given = np.shape(y)
    mean, cov, y = _with_measurement(g, y)
    n, m = mean.shape[-1], y.shape[-1]
    _check_y_fits(given, n, m, H, R)
    code, mean, cov, ll = _kernels.update_batch_py(
        mean, cov, y, _small_matrix(H, "H", m, n),
        _small_matrix(R, "R", m, m),
    )
    if code >= 0:
        _kernel_error(code, "H", "R", {"H": H, "R": R, "g.mean": g.mean, "g.cov": g.cov})
    batch = g.mean.shape[:-1]
    return (Gaussian._trusted(mean.reshape(g.mean.shape), cov.reshape(g.cov.shape)),
            ll.reshape(batch))


@dataclass(frozen=True)
class FilterResult1D:
    """The output of :func:`kalman_filter_1d`: the slides' scalar quantities, each ``(T,)``,
    read-only.

    Attributes
    ----------
    pred_mean, pred_std : (T,) ndarray
        The predictions :math:`\bar x_i^-` and :math:`\\sigma_i^-`.
    mean, std : (T,) ndarray
        The corrections :math:`\bar x_i^+` and :math:`\\sigma_i^+`.

    Examples
    --------
    >>> r = kalman_filter_1d([1.0], d=1.0, m=1.0, sigma_d=0.5, sigma_m=1.0, x0=0.0, sigma0=1.0)
    >>> float(r.mean[0]), r.mean.flags.writeable
    (0.5, False)
    """

    pred_mean: np.ndarray
    pred_std: np.ndarray
    mean: np.ndarray
    std: np.ndarray


# the largest number whose square a float holds
_SQRT_MAX = float(np.sqrt(np.finfo(float).max))


def _check_square(a: np.ndarray, name: str) -> None:
    """Name a value of ``kalman_filter_1d`` whose square (a variance, or a gain's factor)
    no float holds: Python's ``OverflowError`` named none."""
    if (np.abs(a) >= _SQRT_MAX).any():
        raise ValueError(f"{name} must be below {_SQRT_MAX:.4g} in size, its square a finite "
                         f"number; got {np.max(np.abs(a)):g}")


def _power_of_two(*values: float) -> float:
    """The power of two at or just above the largest of ``values``' magnitudes (1 where none
    is finite and above 0): dividing by it is exact, and leaves them at most 1."""
    top = max((abs(v) for v in values if math.isfinite(v)), default=0.0)
    return math.ldexp(1.0, math.frexp(top)[1]) if top > 0 else 1.0


def kalman_filter_1d(
    ys: ArrayLike,
    *,
    d: float | np.ndarray,
    m: float | np.ndarray,
    sigma_d: float | np.ndarray,
    sigma_m: float | np.ndarray,
    x0: float,
    sigma0: float,
) -> FilterResult1D:
    r"""The seeds' scalar Kalman filter, written exactly as on the slides.

    Model ``xᵢ ~ N(dᵢ xᵢ₋₁, σ_dᵢ²)``, ``yᵢ ~ N(mᵢ xᵢ, σ_mᵢ²)``; start ``x̄0⁻ = x0``,
    ``σ0⁻ = sigma0``.

    .. math::
        \bar x_i^- = d_i \bar x_{i-1}^+, \quad
        \sigma_i^- = \sqrt{\sigma_{d_i}^2 + (d_i \sigma_{i-1}^+)^2}, \quad
        \bar x_i^+ = \frac{\bar x_i^- \sigma_{m_i}^2 + m_i y_i (\sigma_i^-)^2}
                          {\sigma_{m_i}^2 + m_i^2 (\sigma_i^-)^2}, \quad
        \sigma_i^+ = \sqrt{\frac{\sigma_{m_i}^2 (\sigma_i^-)^2}
                                {\sigma_{m_i}^2 + m_i^2 (\sigma_i^-)^2}}

    A NaN in ``ys`` skips the correction at that step.

    Parameters
    ----------
    ys : (T,) array_like
        Measurements; NaN (or masked, in a numpy masked array) where missing.
    d, m : float or (T,) array_like
        Dynamics and measurement coefficients :math:`d_i`, :math:`m_i` (``d[0]`` unused).
    sigma_d, sigma_m : float or (T,) array_like
        Standard deviations (not variances) of the dynamics and measurement noise
        (``sigma_d[0]`` unused).
    x0 : float
        Prior mean of the first step, :math:`\bar x_0^-`.
    sigma0 : float
        Prior standard deviation of the first step, :math:`\sigma_0^-`.

    Returns
    -------
    FilterResult1D
        ``pred_mean``, ``pred_std`` (the predictions :math:`\bar x_i^-`,
        :math:`\sigma_i^-`) and ``mean``, ``std`` (the corrections :math:`\bar x_i^+`,
        :math:`\sigma_i^+`), each ``(T,)``.

    Raises
    ------
    ValueError
        If ``ys`` has no step, an array parameter does not have shape ``(T,)``, a parameter
        is not finite, ``ys`` holds an infinity (NaN is a missing step), a standard deviation
        is negative, or the
        innovation variance of an observed step is 0 (no measurement noise, and a state with
        no uncertainty or ``m = 0``), as the n-D filter refuses such a step.

    Examples
    --------
    >>> out = kalman_filter_1d([1.0, np.nan, 2.0], d=1.0, m=1.0, sigma_d=0.5, sigma_m=1.0,
    ...                        x0=0.0, sigma0=1.0)
    >>> out.mean.round(3), out.std.round(3)
    (array([0.5 , 0.5 , 1.25]), array([0.707, 0.866, 0.707]))
    """
    y = as_float_array(ys, "ys", ndim=(1,))
    check_not_infinite(y, "ys")
    T = y.shape[0]
    if T == 0:  # as the n-D filter refuses it (an empty result, before)
        raise ValueError("ys must have at least one step; got shape (0,)")
    par = {}
    for name, v in (("d", d), ("m", m), ("sigma_d", sigma_d), ("sigma_m", sigma_m)):
        a = as_float_array(v, name, ndim=(0, 1))
        if a.ndim == 1 and a.shape[0] != T:
            raise ValueError(f"{name} must be a scalar or have shape (T={T},); got {a.shape}")
        check_finite(a, name)
        if name.startswith("sigma") and (a < 0).any():
            raise ValueError(f"{name} must be standard deviations >= 0; got {a.min()}")
        _check_square(a, name)
        par[name] = np.broadcast_to(a, (T,))
    for name, v in (("x0", x0), ("sigma0", sigma0)):
        if v is None:  # (read as NaN: "x0 must be a finite number; got nan")
            raise ValueError(f"{name} must be a finite number; got None")
        x = float(as_float_array(v, name, ndim=(0,)))
        if not np.isfinite(x) or (name == "sigma0" and x < 0):
            raise ValueError(f"{name} must be a finite number{' >= 0' * (name == 'sigma0')}; "
                             f"got {x}")
        if name == "sigma0":
            _check_square(np.asarray(x), name)
    out = {k: np.empty(T) for k in ("pred_mean", "pred_std", "mean", "std")}
    xp, sp = float(x0), float(sigma0)
    for i in range(T):
        di, mi, sd, sm = (float(par[k][i]) for k in ("d", "m", "sigma_d", "sigma_m"))
        # the standard deviations over a power of two near the largest, k: the squares of
        # standard deviations from 1e77 overflowed (a std of inf, then NaN) and from 1e-77
        # underflowed (stds of 0, wrong means), well inside the 1.34e154 taken; a power of
        # two scales exactly, and the squares are products (correctly rounded: ** 2 went
        # through pow(), whose last bit is not always), so the results hold at any scale
        if i > 0:
            xp = di * out["mean"][i - 1]
            k = _power_of_two(sd, di * out["std"][i - 1])
            u, v = sd / k, di * (out["std"][i - 1] / k)
            sp = math.sqrt(u * u + v * v) * k
        out["pred_mean"][i], out["pred_std"][i] = xp, sp
        if np.isnan(y[i]):
            out["mean"][i], out["std"][i] = xp, sp
            continue
        k = _power_of_two(sm, mi * sp)
        sm2, sp2 = (sm / k) * (sm / k), (sp / k) * (sp / k)
        den = sm2 + mi * mi * sp2
        if not den > 0:  # as the n-D filter's innovation covariance (NaN, or 1/0, before)
            raise ValueError(f"the innovation variance sigma_m^2 + m^2 pred_std^2 is 0 at step "
                             f"{i}: a measurement without noise of a state without "
                             f"uncertainty, or that does not see it (m[{i}] = {mi:g})")
        out["mean"][i] = (xp * sm2 + mi * y[i] * sp2) / den
        out["std"][i] = math.sqrt(sm2 * sp2 / den) * k
    _readonly(*out.values())
    return FilterResult1D(**out)
