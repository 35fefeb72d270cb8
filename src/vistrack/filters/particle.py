r"""Particle filtering: sequential importance resampling (SIR), the seeds' CONDENSATION.

The posterior is a weighted set of samples (seed 004, "factored sampling"): each step moves
every particle through the dynamics with sampled noise (predict, spread), weights it by the
likelihood of the measurement, :math:`w_i \propto w_i\, p(y_t \mid x_i)` (weight), and resamples
when the effective sample size :math:`N_\text{eff} = 1 / \sum w_i^2` falls below a fraction of
``N``. Weights are kept as logarithms, normalised by log-sum-exp, so that likelihoods far below
the smallest double do not underflow to an all-zero set.

Resampling schemes, chosen by name (:data:`RESAMPLERS`): ``multinomial``, ``stratified``,
``systematic`` and ``residual``. All run in linear time: sorted uniforms merged with the
cumulative weights (Douc, Cappé and Moulines, 2005, "Comparison of resampling schemes for
particle filtering"; Hol, Schön and Gustafsson, 2006).

Estimates from a cloud: the weighted mean and covariance, and the **mode**, the seeds' "mean of
the tallest peak", found by a weighted Gaussian-kernel mean-shift, with the share of the weight
in that peak as its confidence.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from .._jit import njit
from .._prebuilt import Kernel, kernel
from .._registry import Registry
from .._validate import (
    as_finite,
    as_flag,
    as_float_array,
    as_rng,
    as_whole,
    check_finite,
    check_has_steps,
    check_not_boolean,
    check_not_infinite,
    check_prior,
    sum_tolerance,
)
from ..models.adapters import MeasurementFunctions, MotionFunctions, psd_sqrt
from ..models.protocols import (
    MeasurementModel,
    MotionModel,
    NonlinearMeasurementModel,
    NonlinearMotionModel,
)
from . import _codegen, _jitmath, _random
from ._codegen import Ref
from ._nonlinear import check_h_size, compiled_stands_for, step_times
from ._random import last_drawable, last_positive
from .kalman import _readonly

__all__ = [
    "RESAMPLERS",
    "resample",
    "effective_sample_size",
    "ParticleDegeneracyError",
    "weighted_mean",
    "weighted_cov",
    "particle_mode",
    "ParticleFilter",
    "ParticleResult",
]


class ParticleDegeneracyError(RuntimeError):
    """Every particle has zero likelihood: the cloud has lost the target.

    Raised by :meth:`ParticleFilter.filter` rather than silently resetting the weights, which
    would hide the failure; the message names the step and the measurement.

    Examples
    --------
    >>> from vistrack.models import ConstantPosition
    >>> never = lambda y, x: np.full(len(x), -np.inf)     # log-likelihood of every particle
    >>> pf = ParticleFilter(ConstantPosition(dim=1), never, n_particles=10, rng=0)
    >>> try:  # doctest: +ELLIPSIS
    ...     pf.filter(np.zeros((3, 1)), x0=[0.0], P0=[[1.0]])
    ... except ParticleDegeneracyError as e:
    ...     print(e)
    every particle has zero likelihood at step 0 (measurement [0.0]); the filter has lost ...
    """


def _user_loglik(ll: object, N: int, t: int, y: np.ndarray) -> np.ndarray:
    """The values a user's log-likelihood callable returned at step ``t``, checked: ``N`` of
    them, none NaN or ``+inf`` (``-inf`` is an impossible particle; NaN is a bug in the
    callable, and so is ``+inf``, which read as every particle having zero likelihood)."""
    try:  # (text failed in numpy's words: "could not convert string to float")
        check_not_boolean(ll, "likelihood's values", "log-likelihoods, numbers")
        a = np.asarray(ll, dtype=float)
    except (TypeError, ValueError):
        raise TypeError(f"likelihood must return (N,) = ({N},) log-likelihoods, numbers; got "
                        f"{ll!r:.80} at step {t}") from None
    if a.shape != (N,):
        raise ValueError(f"likelihood must return (N,) = ({N},) log-likelihoods, one per "
                         f"particle; got shape {a.shape} at step {t}")
    for bad, what in ((np.isnan(a), "NaN"), (a == np.inf, "+inf")):
        if bad.any():
            raise ValueError(f"likelihood returned {what} for {int(bad.sum())} of {N} particles "
                             f"at step {t} (measurement {y.tolist()}); it must return "
                             "log p(y | x) for each particle, finite or -inf where y is "
                             "impossible")
    return a


def _user_particles(x: object, N: int, n: int, t: int) -> np.ndarray:
    """The particles a user's ``propagate`` callable returned at step ``t``, checked: shape
    ``(N, n)`` (an ``(N, 1)`` for a 2-D state was broadcast into the estimates), finite. A
    float array is returned as it is."""
    a = x if isinstance(x, np.ndarray) and x.dtype.kind == "f" else np.asarray(x, dtype=float)
    if a.shape != (N, n):
        raise ValueError(f"motion (a propagate callable) must return particles of shape "
                         f"(N, n) = ({N}, {n}); got shape {a.shape} at step {t}")
    bad = ~np.isfinite(a).all(axis=1)
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"motion (a propagate callable) returned non-finite particles at step "
                         f"{t} ({int(bad.sum())} of {N}); particles[{i}] = {a[i].tolist()}")
    return a


def _degenerate(t: int, y: np.ndarray) -> ParticleDegeneracyError:
    return ParticleDegeneracyError(f"every particle has zero likelihood at step {t} (measurement "
                                   f"{y.tolist()}); the filter has lost the target")


# ---------------------------------------------------------------- resampling
@kernel
@njit(cache=True)
def _merge(cw, u, out):
    """``out[k]`` = the first ``i`` with ``u[k] < cw[i]``, for sorted ``u`` (linear time); a
    ``u[k]`` at or past the end (a uniform rounded up to 1) takes the first ``i`` at the end,
    the last of positive weight (the last index, of weight 0, was drawn)."""
    last = last_drawable(cw)
    i = 0
    for k in range(u.shape[0]):
        while i < last and cw[i] <= u[k]:
            i += 1
        out[k] = i
    return out


def _finite_scale(w: np.ndarray, total: float | None = None) -> np.ndarray:
    """Weights of any positive scale as they are, or over their largest where their sum
    (``total``, where the caller has it) overflows (three weights of 1e308 summed to inf,
    and each scheme drew from a cumulative sum of inf: particle 1 alone, or 0 alone)."""
    return w if np.isfinite(w.sum() if total is None else total) else w / w.max()


def _cumulative(w: np.ndarray) -> np.ndarray:
    cw = np.cumsum(w)
    if not np.isfinite(cw[-1]):  # (the sum overflowed: _finite_scale)
        cw = np.cumsum(_finite_scale(w, cw[-1]))
    cw /= cw[-1]  # exactly 1 at the end, whatever the rounding of the sum
    return cw


def _multinomial(w: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    # sorted uniforms in linear time: normalised cumulative sums of exponentials
    e = np.cumsum(rng.standard_exponential(n + 1))
    return _merge(_cumulative(w), e[:-1] / e[-1], np.empty(n, np.int64))


def _stratified(w: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    u = (np.arange(n) + rng.random(n)) / n
    return _merge(_cumulative(w), u, np.empty(n, np.int64))


@njit(cache=True, error_model="numpy")
def _systematic_kernel(w, u0, out):
    # u_k = (k + u0) / n; index i is drawn for every u_k below the cumulative weight c_i,
    # that is for k < ceil(n c_i - u0): one pass, no search
    n = out.shape[0]
    total = 0.0
    for i in range(w.shape[0]):
        total += w[i]
    c, k = 0.0, 0
    for i in range(w.shape[0]):
        c += w[i]
        edge = min(math.ceil(n * (c / total) - u0), n)
        while k < edge:
            out[k] = i
            k += 1
    if k < n:  # rounding of the last edge (u0 within n/2 ulp of 1): the last of weight > 0
        out[k:] = last_positive(w)
    return out


_systematic_kernel_py = kernel(_systematic_kernel)
""":func:`_systematic_kernel` for calls from Python (compiled code calls the numba function)."""


def _systematic(w: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    return _systematic_kernel_py(_finite_scale(w), rng.random(), np.empty(n, np.int64))


def _residual(w: np.ndarray, n: int, rng: np.random.Generator) -> np.ndarray:
    # weights of any positive scale, as the other schemes (floor(n w) of (2, 1, 1) was 16
    # copies of 4); a sum within rounding of 1 is taken as it is, so that normalised weights
    # give the same draws as before
    s = w.sum()
    if not np.isfinite(s):
        w = _finite_scale(w, s)
        s = w.sum()
    if abs(s - 1.0) > 1e-9 * max(1, len(w)) ** 0.5:
        w = w / s
    nw = n * w
    copies = _whole_copies(nw, n)
    idx = np.repeat(np.arange(len(w)), copies)
    rest = n - len(idx)
    if rest == 0:
        return idx
    r = np.maximum(nw - copies, 0.0)
    return np.sort(np.concatenate([idx, _multinomial(r / r.sum(), rest, rng)]))


def _whole_copies(nw: np.ndarray, n: int) -> np.ndarray:
    """The residual scheme's deterministic copies, ``floor(n w_i)``, of ``nw = n w`` whose
    rounding is forgiven: ``n w_i`` that is a whole number in exact arithmetic (n equal
    weights: 1 each) may round below it, and its floor then lost the copy, drawing the whole
    set at random (1,000 equal weights kept 651 distinct particles). A value within
    ``4 N`` ulp below a whole number counts as it; were the copies more than ``n`` for that,
    the plain floor."""
    copies = np.floor(nw * (1.0 + 4.0 * len(nw) * np.finfo(float).eps)).astype(np.int64)
    if copies.sum() > n:
        copies = np.floor(nw).astype(np.int64)
    return copies


RESAMPLERS: Registry[Callable[[np.ndarray, int, np.random.Generator], np.ndarray]] = Registry(
    "resampler", {
    "multinomial": _multinomial,
    "stratified": _stratified,
    "systematic": _systematic,
    "residual": _residual,
})
"""Resampling schemes by name: ``f(weights, n, rng) -> indices (n,)``, sorted; the weights
need not sum to 1 (any positive scale)."""


def _check_weights(weights: ArrayLike) -> np.ndarray:
    # (a mask was taken as weights)
    w = as_float_array(weights, "weights", ndim=(1, 2), not_boolean="numbers >= 0")
    if w.shape[-1] == 0:
        raise ValueError("weights must not be empty")
    if not np.all(np.isfinite(w)) or np.any(w < 0):
        bad = w[~(np.isfinite(w) & (w >= 0))][0]
        raise ValueError(f"weights must be finite and >= 0; got {bad}")
    s = w.sum(-1)
    # (weights normalised in float32 or float16 are off by up to N of its ulp: 8e-9 for ten
    # float32 weights was refused)
    tol = max(1e-9 * max(1, w.shape[-1]) ** 0.5, sum_tolerance(weights, w.shape[-1]))
    off = np.abs(s - 1.0) > tol
    if off.any():
        k = np.flatnonzero(np.ravel(off))[0]
        where = f"row {k} sums" if w.ndim == 2 else "they sum"
        raise ValueError(f"weights must sum to 1; {where} to {float(np.ravel(s)[k])!r}")
    return w


@kernel
@njit(cache=True)
def _systematic_rows(w, u0, out):
    for t in range(w.shape[0]):
        _systematic_kernel(w[t], u0[t], out[t])
    return out


def resample(weights: ArrayLike, method: str = "systematic", *, n: int | None = None,
             rng: np.random.Generator | int | None = None) -> np.ndarray:
    r"""Indices of ``n`` (default ``len(weights)``) particles drawn by ``method``.

    Each index ``i`` is drawn ``N w_i`` times in expectation (unbiased); the schemes differ in
    variance: multinomial > residual, stratified > systematic (usually).

    Parameters
    ----------
    weights : (N,) or (B, N) array_like
        Normalised weights of one particle set, or of ``B`` sets (each row sums to 1, within
        ``1e-9 √N``, or ``N`` ulp of a float32 or float16 array), which are resampled
        independently in one call.
    method : {'systematic', 'stratified', 'residual', 'multinomial'}
        A name of :data:`RESAMPLERS`.
    n : int, optional
        How many to draw (per set), an integer >= 1 (a float with an integral value, such as
        ``3.0``, is taken; ``2.7`` is refused).
    rng : numpy.random.Generator, int or None
        Random generator or seed.

    Returns
    -------
    (n,) or (B, n) ndarray of int64
        Indices into each set, sorted.

    Raises
    ------
    ValueError
        If ``method`` is unknown, the weights are empty, negative, not finite or do not sum
        to one, or ``n`` is not an integer >= 1.

    References
    ----------
    .. [1] R. Douc, O. Cappé and E. Moulines, "Comparison of resampling schemes for particle
       filtering", ISPA 2005.
    .. [2] J. D. Hol, T. B. Schön and F. Gustafsson, "On resampling algorithms for particle
       filters", Nonlinear Statistical Signal Processing Workshop, 2006.

    Examples
    --------
    >>> resample([0.1, 0.2, 0.7], "systematic", n=10, rng=0)
    array([0, 1, 1, 2, 2, 2, 2, 2, 2, 2])
    >>> resample([[0.5, 0.5], [0.0, 1.0]], rng=0)
    array([[0, 1],
           [1, 1]])
    """
    if not isinstance(method, str) or method not in RESAMPLERS:  # (a list: "unhashable type")
        raise ValueError(f"method must be one of {sorted(RESAMPLERS)}; got {method!r}")
    w = _check_weights(weights)
    n = w.shape[-1] if n is None else as_whole(n, "n", 1)
    gen = as_rng(rng)
    if w.ndim == 1:
        return RESAMPLERS[method](w, n, gen)
    if method == "systematic":  # one draw a row, all rows in one compiled call
        return _systematic_rows(w, gen.random(w.shape[0]), np.empty((w.shape[0], n), np.int64))
    return np.stack([RESAMPLERS[method](row, n, gen) for row in w]) if len(w) else \
        np.empty((0, n), np.int64)


def effective_sample_size(weights: ArrayLike) -> float:
    r"""Effective sample size of weights, :math:`N_\text{eff} = (\sum_i w_i)^2 / \sum_i w_i^2`:
    :math:`1 / \sum_i w_i^2` for normalised ones.

    ``N`` for equal weights, 1 when one particle has all the weight.

    Parameters
    ----------
    weights : (N,) array_like
        Weights, finite and >= 0, not all 0 (normalised or not).

    Returns
    -------
    float
        In ``[1, N]``.

    Raises
    ------
    ValueError
        If ``weights`` is not 1-D, is empty, or a weight is negative or not finite, or all are
        0 (naming the first bad one).

    Examples
    --------
    >>> effective_sample_size([0.25, 0.25, 0.25, 0.25]), effective_sample_size([1.0, 0.0])
    (4.0, 1.0)
    >>> effective_sample_size([3.0, 1.0])  # the same as (0.75, 0.25)
    1.6
    """
    w = as_float_array(weights, "weights", ndim=(1,), not_boolean="numbers >= 0")
    if w.size == 0:
        raise ValueError("weights is empty: no particles")
    top = _some_weight(w)
    w = w / top  # first by the largest: the sum of 1e308 and 1e308 overflowed
    return _ess(w / w.sum())


def _some_weight(w: np.ndarray) -> float:
    """The largest of the weights ``w`` (1-D, not empty), checked: each finite and >= 0, and
    not all 0; each error names the first bad one."""
    bad = ~np.isfinite(w) | (w < 0)
    if bad.any():
        i = int(np.argmax(bad))
        raise ValueError(f"weights[{i}] is {w[i]}: weights must be finite and >= 0")
    top = float(w.max())
    if top == 0:
        raise ValueError(f"weights are all 0 (of {w.size} particles)")
    return top


def _normalised(w: np.ndarray) -> np.ndarray:
    """The weights ``w`` (1-D, not empty) checked as :func:`_some_weight` does and divided by
    their sum (first by the largest, so that large weights do not overflow)."""
    w = w / _some_weight(w)
    return w / w.sum()


def _ess(w: np.ndarray) -> float:
    # effective_sample_size of normalised weights, unchecked: the filters' own
    return float(1.0 / np.dot(w, w))


# ---------------------------------------------------------------- estimates
def _particles_and_weights(particles: ArrayLike,
                           weights: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    x = as_float_array(particles, "particles", ndim=(2,))
    w = as_float_array(weights, "weights", ndim=(1,), not_boolean="numbers >= 0")
    if w.shape != x.shape[:1]:
        raise ValueError(f"weights must have shape ({x.shape[0]},), one per particle (row of "
                         f"particles); got {w.shape}")
    # (a cloud of none failed in numpy's "zero-size array"; a NaN particle, even of weight
    # 0, made the mean NaN without a word)
    if x.shape[0] == 0:
        raise ValueError(f"particles must hold at least one particle; got shape {x.shape}")
    check_finite(x, "particles")
    return x, w


def _wmean(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    return w @ x


def _wcov(x: np.ndarray, w: np.ndarray) -> np.ndarray:
    d = x - _wmean(x, w)
    return (d * w[:, None]).T @ d


def weighted_mean(particles: ArrayLike, weights: ArrayLike) -> np.ndarray:
    r"""Weighted mean of a particle cloud, :math:`\sum_i w_i x_i`.

    Parameters
    ----------
    particles : (N, n) array_like
        The particles.
    weights : (N,) array_like
        Weights, finite and >= 0, not all 0; divided by their sum (likelihoods may be given
        as they are, as to numpy's ``average``).

    Returns
    -------
    (n,) ndarray
        The mean.

    Raises
    ------
    ValueError
        If ``particles`` is not 2-D, empty or not finite, ``weights`` is not one weight per
        particle, or a weight is negative or not finite, or all are 0 (naming the first bad
        one).

    Examples
    --------
    >>> weighted_mean([[0.0], [2.0]], [0.25, 0.75]), weighted_mean([[0.0], [2.0]], [1, 3])
    (array([1.5]), array([1.5]))
    """
    x, w = _particles_and_weights(particles, weights)
    return _wmean(x, _normalised(w))


def weighted_cov(particles: ArrayLike, weights: ArrayLike) -> np.ndarray:
    r"""Weighted covariance of a particle cloud, :math:`\sum_i w_i (x_i - m)(x_i - m)'`.

    The population covariance (no bias correction), with ``m`` the :func:`weighted_mean`.

    Parameters
    ----------
    particles : (N, n) array_like
        The particles.
    weights : (N,) array_like
        Weights, finite and >= 0, not all 0; divided by their sum.

    Returns
    -------
    (n, n) ndarray
        The covariance.

    Raises
    ------
    ValueError
        If ``particles`` is not 2-D, empty or not finite, ``weights`` is not one weight per
        particle, or a weight is negative or not finite, or all are 0 (naming the first bad
        one).

    Examples
    --------
    >>> weighted_cov([[0.0], [2.0]], [0.25, 0.75])
    array([[0.75]])
    """
    x, w = _particles_and_weights(particles, weights)
    return _wcov(x, _normalised(w))


def particle_mode(particles: ArrayLike, weights: ArrayLike, *, bandwidth: ArrayLike | None = None,
                  n_starts: int = 8, max_iter: int = 500,
                  max_points: int = 5000) -> tuple[np.ndarray, float]:
    r"""The mode of a weighted cloud, "the mean of the tallest peak", and its confidence.

    A mean-shift with a Gaussian kernel of covariance ``bandwidth²`` (per dimension; default
    Silverman's rule on the weighted covariance) runs from the weighted mean and from
    ``n_starts - 1`` particles drawn by weight, so that every sizeable peak gets a start. End
    points closer than one bandwidth are one peak, and so are two with no real valley between
    them (the density along the segment never a quarter below the lower end's: a start
    still climbing a broad peak, or stopped on a bump of a few particles); the peak with the
    highest kernel density wins. Its confidence is the share of the weight of the particles
    nearer to it than to any other peak found. Clouds larger than ``max_points`` are
    subsampled by systematic resampling for the search (the confidence uses every particle).
    The search draws from a generator of its own, so the estimate does not change the
    filter's random draws.

    Each mean-shift step moves a point :math:`p` to the kernel-weighted mean of the
    particles,

    .. math::

        p \leftarrow \frac{\sum_i w_i K(x_i - p)\, x_i}{\sum_i w_i K(x_i - p)}, \qquad
        K(d) = \exp\left(-\tfrac12 \textstyle\sum_k d_k^2 / h_k^2\right),

    with Silverman's bandwidth :math:`h_k = \sigma_k \big(4 / ((n + 2) N_\text{eff})
    \big)^{1/(n+4)}` by default. A dimension in which every particle has the same value
    (within rounding of it: a state the prior or the motion leaves fixed) has no spread to
    scale by; its bandwidth is then the value's own size (1 at 0), so that it counts for
    nothing in the search (a bandwidth of about 1e-150 made its last bits outweigh every
    real distance, and gave the weighted mean as the mode, with confidence 1).

    Parameters
    ----------
    particles : (N, n) array_like
        The particles.
    weights : (N,) array_like
        Weights, finite and >= 0, not all 0, divided by their sum (zero weights are
        particles that count for nothing).
    bandwidth : float or (n,) array_like, optional
        Kernel standard deviation per dimension; default Silverman's rule.
    n_starts : int
        Number of mean-shift starts (the weighted mean and ``n_starts - 1`` particles).
    max_iter : int
        Largest number of mean-shift steps; the search stops before once no start moves
        by 1e-6 bandwidths in a step (a skewed peak's climb takes a few hundred).
    max_points : int
        Clouds larger than this are subsampled for the search.

    Returns
    -------
    mode : (n,) ndarray
        The mode.
    confidence : float
        Share of the weight in the mode's peak, in [0, 1].

    Raises
    ------
    ValueError
        If ``particles`` is not 2-D, empty or not finite, ``weights`` is not one finite
        weight >= 0 per particle or all are 0, ``bandwidth`` is not finite and > 0 (one, or
        one per dimension), or ``n_starts`` or ``max_points`` is not an integer >= 1 or
        ``max_iter`` one >= 0.

    References
    ----------
    .. [1] D. Comaniciu and P. Meer, "Mean shift: a robust approach toward feature space
       analysis", *IEEE Transactions on Pattern Analysis and Machine Intelligence* 24(5),
       2002.
    .. [2] B. W. Silverman, *Density Estimation for Statistics and Data Analysis*, Chapman
       and Hall, 1986.

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> x = np.concatenate([rng.normal(-5, 1, (300, 1)), rng.normal(4, 1, (700, 1))])
    >>> mode, conf = particle_mode(x, np.full(1000, 1e-3))
    >>> round(float(mode[0])), round(conf, 1)
    (4, 0.7)
    """
    x, w = _particles_and_weights(particles, weights)
    N, n = x.shape
    w = _normalised(w)
    n_starts = as_whole(n_starts, "n_starts", 1)
    max_iter = as_whole(max_iter, "max_iter", 0)
    max_points = as_whole(max_points, "max_points", 1)
    if bandwidth is None:
        sd = np.sqrt(np.maximum(np.diagonal(_wcov(x, w)), 0.0))
        neff = _ess(w)
        h = sd * (4.0 / ((n + 2) * neff)) ** (1.0 / (n + 4))
        # a dimension of one value (to rounding): its own size, 1 at 0 (see above)
        size = np.abs(x).max(0)
        flat = sd <= 64 * np.finfo(float).eps * size
        h = np.where(flat, np.where(size > 0, size, 1.0), h)
    else:
        hb = as_float_array(bandwidth, "bandwidth", ndim=(0, 1),
                            not_boolean="one number > 0 or one per dimension")
        if hb.size not in (1, n):
            raise ValueError(f"bandwidth must be a number or ({n},), one per dimension; got "
                             f"shape {hb.shape}")
        if not (np.isfinite(hb).all() and (hb > 0).all()):
            raise ValueError(f"bandwidth must be finite and > 0; got {hb.tolist()}")
        h = np.broadcast_to(hb, (n,))
    search = np.random.default_rng(0)  # the estimate must not consume the filter's randomness
    if N > max_points:
        xs, ws = x[_systematic(w, max_points, search)], np.full(max_points, 1.0 / max_points)
    else:
        xs, ws = x, w
    z = xs / h
    # (one start was two: the mean and a particle, as the docstring's n_starts - 1 says not)
    picks = _systematic(ws, n_starts - 1, search) if n_starts > 1 else np.zeros(0, np.intp)
    starts = np.concatenate([[_wmean(xs, ws)], xs[picks]]) / h
    # the kernel is scaled by its largest term over the particles of positive weight (those
    # of zero weight are infinitely far): scaled by the nearest particle, one of zero weight
    # underflowed every other term to 0, and the step to 0/0, when the weighted ones were
    # more than ~38 bandwidths away
    zero = None if ws.min() > 0 else ws == 0
    for _ in range(max_iter):
        d2 = ((starts[:, None, :] - z[None]) ** 2).sum(-1)  # (S, N)
        if zero is not None:
            d2 = np.where(zero, np.inf, d2)
        k = ws * np.exp(-0.5 * (d2 - d2.min(1, keepdims=True)))
        new = (k @ z) / k.sum(1, keepdims=True)
        done = np.max(np.abs(new - starts)) < 1e-6
        starts = new
        if done:
            break
    peaks: list[np.ndarray] = []
    for p in starts:
        if all(((p - q) ** 2).sum() > 1.0 for q in peaks):
            peaks.append(p)
    P = np.array(peaks)

    def density(points: np.ndarray) -> np.ndarray:
        return (ws * np.exp(-0.5 * ((points[:, None, :] - z[None]) ** 2).sum(-1))).sum(1)

    dens = density(P)
    if len(P) > 1:
        # a start from a far tail climbs a broad peak by a small fraction of its distance a
        # step (h²/(σ² + h²) on a Gaussian) and may not have arrived, or stops on a bump of
        # the kernel estimate (a few particles in a tail): two end points are one peak where
        # the density along the segment between them stays within a quarter of the lower of
        # the two (no real valley: two equal normals 3σ apart dip 36 % between them, 2.6σ
        # apart 17 %), and the peak is the higher end. On 20,000 particles of a normal, the
        # tail starts counted as peaks of their own gave confidence 0.17 in 1-D, 0.25 in 4-D.
        t = np.linspace(0.1, 0.9, 9)[:, None]

        def one_peak(i: int, j: int) -> bool:
            low = density(P[i] + t * (P[j] - P[i])).min()
            return bool(low >= 0.75 * min(dens[i], dens[j]))

        # from the highest: each end point joins the first peak kept (higher) it has no valley
        # with, checked against that peak itself, so that a point between two peaks (a
        # middle bump, a start stuck in the valley) does not join them to each other
        keep: list[int] = []
        for i in np.argsort(-dens, kind="stable"):
            if not any(one_peak(int(i), k) for k in keep):
                keep.append(int(i))
        P, dens = P[keep], dens[keep]
    best = int(np.argmax(dens))
    nearest = np.argmin(((x[:, None, :] / h - P[None]) ** 2).sum(-1), axis=1)
    return P[best] * h, min(1.0, float(w[nearest == best].sum()))


# ---------------------------------------------------------------- the compiled path
_FUSED = """
# depends on: {depends}
import math
import numpy as np
from numba import njit
from vistrack.filters._jitmath import exp_weight, wrap_angle
from vistrack.filters._random import normal, resample_into
from {fmod} import {fname} as f
from {hmod} import {hname} as h


@njit(cache=True, error_model="numpy", fastmath={{"contract", "arcp", "nsz"}})
def run(x, xb, ys, obs, nobs, Linv, c, angles, dts, times, fp, hp, S, scheme, threshold, s,
        logw, w, idx, cw, means, covs, ess, resampled):
    # The whole filter in one call. Each step is one pass over the cloud that moves every
    # particle (x <- f(x) + S e, e ~ N(0, I), reading the resampled index straight from idx),
    # weighs it (log w += c - |Linv r|^2 / 2 over the observed components) and keeps the
    # largest log weight; then a pass for the normalised weights and the mean, one for the
    # covariance, and resampling into idx when the ESS is low. Returns (the step at which
    # every weight was zero or -1, the log-likelihood).
    T, N = ys.shape[0], x.shape[0]
    n, m = {n}, {m}  # literal sizes: the per-particle loops unroll
    xn = np.empty(n)
    e = np.empty(n)
    z = np.empty(m)
    r = np.empty(m)
    o = np.empty(n)
    d1 = np.empty(n)
    d2 = np.empty((n, n))
    uniform = -math.log(N)  # the log weight after resampling
    loglik = 0.0
    st = (s[0], s[1], s[2], s[3])  # the generator's state, in registers
    moved = False  # idx holds the last resampling, not yet applied to x
    for t in range(T):
        no = nobs[t]
        top = -np.inf
        bad = False  # a particle, or its h, not finite: the model's fault, named by the caller
        for i in range(N):
            j = idx[i] if moved else i
            if t > 0:
                f(x[j], dts[t], times[t], fp[t], xn)
                for l in range(n):
                    e[l], st = normal(st)
                for k in range(n):
                    v = xn[k]
                    for l in range(n):
                        v += S[t, k, l] * e[l]
                    xb[i, k] = v
                    if not abs(v) < np.inf:
                        bad = True
            else:
                for k in range(n):
                    xb[i, k] = x[j, k]
            q = 0.0
            if no > 0:
                h(xb[i], hp, z)
                for a in range(no):
                    k = obs[t, a]
                    if not abs(z[k]) < np.inf:
                        bad = True
                    d = ys[t, k] - z[k]
                    if angles[k]:
                        d = wrap_angle(d)
                    r[a] = d
                for a in range(no):
                    v = 0.0
                    for b in range(a + 1):
                        v += Linv[t, a, b] * r[b]
                    q += v * v
            v = (uniform if moved else logw[i]) + c[t] - 0.5 * q
            logw[i] = v
            top = max(top, v)
        x, xb = xb, x
        moved = False
        if bad or not top > -np.inf:
            s[0], s[1], s[2], s[3] = st
            return t, loglik, x
        for i in range(N):  # vectorised
            w[i] = exp_weight(logw[i] - top)
        # sums of the weights, their squares, and the weighted first and second moments about
        # a particle of the largest weight (shifted sums: no cancellation for far-off clouds)
        ref = 0
        for i in range(N):
            if w[i] == 1.0:
                ref = i
                break
        for k in range(n):
            o[k] = x[ref, k]
            d1[k] = 0.0
            for l in range(n):
                d2[k, l] = 0.0
        total, sq = 0.0, 0.0
        for i in range(N):
            wi = w[i]
            total += wi
            sq += wi * wi
            for k in range(n):
                dk = x[i, k] - o[k]
                d1[k] += wi * dk
                for l in range(k + 1):
                    d2[k, l] += wi * dk * (x[i, l] - o[l])
        norm = top + math.log(total)
        if not abs(norm) < np.inf:
            s[0], s[1], s[2], s[3] = st
            return t, loglik, x
        if no > 0:
            loglik += norm
        for k in range(n):
            d1[k] /= total
            means[t, k] = o[k] + d1[k]
        for k in range(n):
            for l in range(k + 1):
                v = d2[k, l] / total - d1[k] * d1[l]
                covs[t, k, l] = v
                covs[t, l, k] = v
        ess[t] = total * total / sq
        if ess[t] < threshold * N or threshold == 1.0:
            st = resample_into(w, scheme, st, cw, idx)
            resampled[t] = True
            moved = True
        else:
            for i in range(N):
                logw[i] -= norm
    if moved:  # the last resampling
        for i in range(N):
            for k in range(n):
                xb[i, k] = x[idx[i], k]
            logw[i] = uniform
        x = xb
    s[0], s[1], s[2], s[3] = st
    return -1, loglik, x
"""


def _fused_kernel(fref: Ref, href: Ref, n: int, m: int) -> Kernel:
    """The fused filter of these functions and sizes for calls from Python (and for
    compiling it ahead of time, see :mod:`vistrack._prebuilt`), of their modules' current
    source."""
    return _codegen.generated_kernel(
        _FUSED, "vistrack_pf", f"{__name__}:_fused_kernel({fref!r}, {href!r}, {n!r}, {m!r})",
        (fref[0], href[0], _random.__name__, _jitmath.__name__),
        fmod=fref[0], fname=fref[1], hmod=href[0], hname=href[1], n=n, m=m)


@njit(cache=True, error_model="numpy", inline="always")
def _linear_f(x, dt, t, params, out):
    # out = F x, params = F (n, n) flattened
    n = out.shape[0]
    for k in range(n):
        v = 0.0
        for l in range(n):
            v += params[k * n + l] * x[l]
        out[k] = v


@njit(cache=True, error_model="numpy", inline="always")
def _linear_h(x, params, out):
    # out = H x, params = H (m, n) flattened
    m, n = out.shape[0], x.shape[0]
    for k in range(m):
        v = 0.0
        for l in range(n):
            v += params[k * n + l] * x[l]
        out[k] = v


def _compiled_parts(mo: MotionFunctions, me: MeasurementFunctions):
    """What the compiled path needs of the models: the module-level compiled one-state ``f``
    and ``h`` and their parameters (``params(dt, t)`` per step, and a fixed array), from the
    models' ``jit_f``/``jit_h`` or, for linear models, ``F x`` and ``H x``. None when a model
    has neither (a user model in Python runs on the numpy path) or its Python functions are
    not theirs (a subclass's own ``f``: :func:`~._nonlinear.compiled_stands_for`), the
    measurement model's state is of another size, or the measurement's residual is its own
    (the compiled path takes differences, angles wrapped)."""
    motion, meas = mo.model, me.model
    if not me.standard:
        return None
    fref = _codegen.jit_ref(getattr(motion, "jit_f", None))
    if fref is not None and compiled_stands_for(motion, ("jit_f",)):
        fparams = cast(Any, motion).jit_params
    elif mo.linear and np.ndim(cast(MotionModel, motion).F(1.0)) == 2:
        # a constant F; one per step runs in numpy
        def fparams(dts, times):
            d, inv = np.unique(dts, return_inverse=True)
            return np.array([np.ravel(motion.F(float(v))) for v in d])[inv]

        fref = _codegen.jit_ref(_linear_f)
    else:
        return None
    href = _codegen.jit_ref(getattr(meas, "jit_h", None))
    if (href is not None and compiled_stands_for(meas, ("jit_h",))
            and getattr(meas, "ndim_state", None) == mo.n):
        hparams = cast(Any, meas).jit_params()
    elif me.linear:
        href, hparams = _codegen.jit_ref(_linear_h), me.H
    else:
        return None
    return fref, fparams, href, np.asarray(hparams, dtype=float).ravel(), mo, me


# what the compiled path needs of the models (see _compiled_parts): f's module and name, its
# parameters per step, h's module and name, h's parameters, and the two models
_FusedParts = tuple[tuple[str, str], Callable[..., Any], tuple[str, str], np.ndarray,
                    MotionFunctions, MeasurementFunctions]


def _whitening(R: np.ndarray, o: np.ndarray) -> tuple[np.ndarray, float]:
    """For the observed components ``o`` of the noise ``R = L L'``: ``L^-1`` (a Gaussian's
    exponent is ``-|L^-1 r|^2 / 2``) and its constant ``-log det L - k/2 log 2π``."""
    try:
        L = np.linalg.cholesky(R[np.ix_(o, o)])
    except np.linalg.LinAlgError:  # (numpy's message names neither R nor the components)
        raise ValueError(f"the measurement model's R must be positive definite on the observed "
                         f"components; on components {o.tolist()} it is not "
                         f"({R[np.ix_(o, o)].tolist()})") from None
    return np.linalg.inv(L), float(-np.log(np.diagonal(L)).sum()
                                   - 0.5 * len(o) * math.log(2 * math.pi))


# ---------------------------------------------------------------- the filter
@dataclass(frozen=True)
class ParticleResult:
    """The output of :meth:`ParticleFilter.filter`. Arrays are read-only.

    Attributes
    ----------
    means : (T, n) ndarray
        Weighted mean of the cloud after each correction.
    covs : (T, n, n) ndarray
        Weighted covariance of the cloud after each correction.
    modes : (T, n) ndarray or None
        :func:`particle_mode` of each step's cloud (when asked for), else None.
    mode_confidence : (T,) ndarray or None
        The modes' confidences, else None.
    ess : (T,) ndarray
        Effective sample size after each correction, before any resampling.
    resampled : (T,) ndarray of bool
        Whether the step resampled.
    loglik : float
        ``Σ_t log p(y_t | y_{<t})``, each term ``log Σ w_i p(y_t | x_i)``.
    particles : (N, n) ndarray
        The last cloud.
    weights : (N,) ndarray
        Its normalised weights.

    Examples
    --------
    >>> import vistrack as vt
    >>> pf = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1), 500, rng=0)
    >>> res = pf.filter(np.arange(5.0)[:, None], x0=[0.0, 1.0], P0=np.eye(2))
    >>> res.means.shape, res.particles.shape, bool(np.isclose(res.weights.sum(), 1.0))
    ((5, 2), (500, 2), True)
    >>> res.means.flags.writeable, res.particles.flags.writeable
    (False, False)
    """

    means: np.ndarray
    covs: np.ndarray
    modes: np.ndarray | None
    mode_confidence: np.ndarray | None
    ess: np.ndarray
    resampled: np.ndarray
    loglik: float
    particles: np.ndarray
    weights: np.ndarray


def _result(means: np.ndarray, covs: np.ndarray, modes: np.ndarray | None,
            mode_confidence: np.ndarray | None, ess: np.ndarray, resampled: np.ndarray,
            loglik: float, particles: np.ndarray, weights: np.ndarray) -> ParticleResult:
    """A :class:`ParticleResult` whose arrays are made read-only, as the other filters'."""
    _readonly(means, covs, modes, mode_confidence, ess, resampled, particles, weights)
    return ParticleResult(means, covs, modes, mode_confidence, ess, resampled, loglik,
                          particles, weights)


def check_particle_options(n_particles: float, resampling: str,
                           ess_threshold: float) -> tuple[int, float]:
    """Check a particle filter's size, resampling scheme and ESS threshold, by the package's
    rules for whole and bounded numbers: a ``TypeError`` naming the argument for what is no
    number (a string), a ``ValueError`` for any other bad value (a bool is no count here)."""
    n = as_whole(n_particles, "n_particles", 1)
    if not isinstance(resampling, str) or resampling not in RESAMPLERS:
        raise ValueError(f"resampling must be one of {sorted(RESAMPLERS)}; got {resampling!r}")
    return n, as_finite(ess_threshold, "ess_threshold", 0.0, high=1.0)


def resample_now(ess: float, threshold: float, n: int) -> bool:
    """Whether a particle filter of ``n`` particles resamples at an effective sample size
    ``ess``: below ``threshold * n``, or always at ``threshold`` 1 (equal weights give
    ``ess == n``, which is not below)."""
    return ess < threshold * n or threshold == 1.0


class ParticleFilter:
    r"""A bootstrap (SIR / CONDENSATION) particle filter.

    Each step moves the particles through the dynamics, weighs them by the measurement's
    likelihood and resamples when the effective sample size is low:

    .. math::

        x_t^{(i)} = f(x_{t-1}^{(i)}, \Delta t, t) + w^{(i)}, \quad w^{(i)} \sim N(0, Q),
        \qquad \log w_t^{(i)} = \log w_{t-1}^{(i)} + \log p(y_t \mid x_t^{(i)}) - c_t,

    with :math:`c_t` the log-sum-exp that normalises the weights, and :math:`\sum_t c_t` the
    log-likelihood of the measurements.

    Parameters
    ----------
    motion
        A motion model (``f`` and ``Q``, or ``F`` and ``Q``); particles move by ``f`` plus
        Gaussian noise of covariance ``Q(dt)``. Or a callable
        ``propagate(particles (N, n), dt, t, rng) -> (N, n)`` for any other dynamics (its
        output is checked at each step: shape ``(N, n)``, finite).
    likelihood
        A measurement model (``h``, ``R``: a Gaussian likelihood with the model's residual),
        or a callable ``log_likelihood(y, particles (N, n)) -> (N,)`` returning
        ``log p(y | x_i)`` (image likelihoods plug in here): finite, or ``-inf`` where ``y``
        is impossible.
    n_particles : int
        Number ``N`` of particles, >= 1.
    resampling : str
        A name in :data:`RESAMPLERS`.
    ess_threshold : float
        In [0, 1]: resample when ``N_eff < ess_threshold * N`` (1 resamples every step, 0
        never).
    rng : numpy.random.Generator, int or None
        Random generator or seed.
    ndim_state : int, optional
        Needed when ``motion`` is a callable.
    compiled : bool
        Run the whole filter as one compiled call when the models allow it: linear models
        (constant ``F``, ``H``), and models that provide compiled one-state functions
        (``jit_f``, ``jit_h`` with ``jit_params``: the growth model, the coordinated turn,
        range-bearing). Each step is then one pass over the cloud that moves, weighs and keeps
        the largest log weight, a vectorised pass for the weights, one for the moments, and
        resampling in place. Its randomness comes from a xoshiro256++ generator seeded from
        ``rng`` (reproducible from the seed, but not the same draws as the numpy path, which
        runs otherwise and when ``modes=True``).

    Raises
    ------
    ValueError
        If ``n_particles``, ``resampling`` or ``ess_threshold`` is invalid, or ``motion`` is
        a callable and ``ndim_state`` is missing.
    TypeError
        If ``motion`` or ``likelihood`` is neither a model nor a callable, or
        ``n_particles`` or ``ess_threshold`` is no number (a string).

    References
    ----------
    .. [1] N. J. Gordon, D. J. Salmond and A. F. M. Smith, "Novel approach to
       nonlinear/non-Gaussian Bayesian state estimation", *IEE Proceedings F* 140(2), 1993.
    .. [2] M. Isard and A. Blake, "CONDENSATION: conditional density propagation for visual
       tracking", *International Journal of Computer Vision* 29(1), 1998.

    Examples
    --------
    >>> import vistrack as vt
    >>> motion, meas = vt.models.growth_model()
    >>> xs, ys = vt.simulate.simulate(motion, meas, 50, x0=[0.1], rng=1)
    >>> pf = ParticleFilter(motion, meas, n_particles=2000, rng=2)
    >>> res = pf.filter(ys, x0=[0.0], P0=[[5.0]])
    >>> res.means.shape, res.ess.shape, bool(res.resampled.any())
    ((50, 1), (50,), True)
    """

    def __init__(self, motion: MotionModel | NonlinearMotionModel | Callable[..., np.ndarray],
                 likelihood: (MeasurementModel | NonlinearMeasurementModel
                              | Callable[[np.ndarray, np.ndarray], np.ndarray]),
                 n_particles: int = 1000, *,
                 resampling: str = "systematic", ess_threshold: float = 0.5,
                 rng: np.random.Generator | int | None = None, ndim_state: int | None = None,
                 compiled: bool = True):
        self.n_particles, self.ess_threshold = check_particle_options(
            n_particles, resampling, ess_threshold)
        self.resampling, self.rng = resampling, as_rng(rng)
        self._user_motion = False  # a propagate callable, whose output is checked each step
        compiled = as_flag(compiled, "compiled")  # ("no" was true)
        if hasattr(motion, "Q"):
            mo = MotionFunctions(cast(MotionModel | NonlinearMotionModel, motion))
            if ndim_state is not None and as_whole(ndim_state, "ndim_state", 1) != mo.n:
                # (dropped without a word: the model's own size was used)
                raise ValueError(f"ndim_state is {ndim_state}, where the motion model's states "
                                 f"have {mo.n} values: give it only with a callable motion")
            self.ndim_state = mo.n
            self._propagate = self._model_propagate(mo)
        elif callable(motion):
            if ndim_state is None:
                raise ValueError("ndim_state is needed when motion is a callable")
            self.ndim_state, self._propagate = as_whole(ndim_state, "ndim_state", 1), motion
            self._user_motion = True
        else:
            raise TypeError(f"motion must be a motion model or a callable; got "
                            f"{type(motion).__name__}")
        self._fused: _FusedParts | None = None
        self._whiten: dict[bytes, tuple[np.ndarray, float]] = {}
        self._m: int | None = None  # a measurement model's components (None: a callable's)
        if hasattr(likelihood, "R"):
            me = MeasurementFunctions(
                cast(MeasurementModel | NonlinearMeasurementModel, likelihood), self.ndim_state)
            self._m = me.m
            gauss = self._gaussian_loglik(me)
            self._loglik = lambda y, x, t: np.asarray(gauss(y, x), dtype=float)
            if compiled and hasattr(motion, "Q") and resampling in _random.SCHEMES:
                self._fused = _compiled_parts(mo, me)
        elif callable(likelihood):
            N = self.n_particles
            self._loglik = lambda y, x, t: _user_loglik(likelihood(y, x), N, t, y)
        else:
            raise TypeError(f"likelihood must be a measurement model or a callable; got "
                            f"{type(likelihood).__name__}")

    @staticmethod
    def _model_propagate(mo: MotionFunctions):
        def propagate(x, dt, t, rng):
            out = np.asarray(mo.f(x, dt, t), dtype=float)
            return out + rng.standard_normal(out.shape) @ mo.Q_sqrt(dt).T

        return propagate

    @staticmethod
    def _gaussian_loglik(me: MeasurementFunctions):
        whiten: dict = {}  # per pattern of observed components

        def loglik(y, x):
            obs = ~np.isnan(y)
            key = obs.tobytes()
            if key not in whiten:
                whiten[key] = _whitening(me.Rm, np.flatnonzero(obs))
            Linv, c = whiten[key]
            hx = check_h_size(np.asarray(me.h(x), dtype=float), me.m, x)
            r = me.residual(np.where(obs, y, 0.0), hx)[:, obs]
            z = r * Linv[0, 0] if r.shape[1] == 1 else r @ Linv.T
            ll = c - 0.5 * (z * z).sum(1)
            # a particle whose h is infinite: NaN, the model's fault (its weight was 0, and
            # every particle's such read as a lost target); named by the filter
            return np.where(np.isfinite(hx[:, obs]).all(axis=1), ll, np.nan)

        return loglik

    def filter(self, ys: ArrayLike, *, x0: ArrayLike | None = None, P0: ArrayLike | None = None,
               particles: ArrayLike | None = None, dt: ArrayLike | None = None,
               times: ArrayLike | None = None, modes: bool = False) -> ParticleResult:
        """Filter one sequence.

        The first cloud is ``particles`` or ``N`` draws from ``N(x0, P0)``, the prior of the
        first step (which is corrected with no prediction before it, as in the Kalman
        filters).

        Parameters
        ----------
        ys : (T, m) array_like
            Measurements; a row of NaN is predicted only (NaN in some components: the
            Gaussian likelihood uses the others); masked entries of a numpy masked array are
            NaN.
        x0 : (n,) array_like, optional
            Prior mean of the first step (when ``particles`` is not given).
        P0 : (n, n) array_like, optional
            Prior covariance of the first step.
        particles : (N, n) array_like, optional
            The first cloud, instead of draws from ``N(x0, P0)``.
        dt : float or (T,) array_like, optional
            Time step: a scalar, the ``T-1`` intervals between steps (``np.diff(times)``),
            or ``T`` values, ``dt[t]`` the step from ``t-1`` to ``t`` (``dt[0]`` unused);
            default ``np.diff(times)`` where ``times`` is given, else 1.
        times : (T,) array_like, optional
            Time of each step, not decreasing; default the cumulative ``dt`` from 0. Given
            with ``dt``, the two must agree.
        modes : bool
            Also compute :func:`particle_mode` at every step (on the numpy path).

        Returns
        -------
        ParticleResult
            Means ``(T, n)``, covariances ``(T, n, n)``, effective sample sizes ``(T,)``,
            the log-likelihood and the last cloud.

        Raises
        ------
        ParticleDegeneracyError
            If every particle gets zero likelihood (the message names the step).
        ValueError
            If ``ys`` has no step or holds an infinity (NaN is missing), the prior or
            ``particles`` has the wrong shape or is not finite, a ``likelihood`` callable
            returns other than ``N`` values, a NaN or ``+inf``, or a ``propagate`` callable
            returns other than ``(N, n)`` finite particles, or a motion or measurement model
            gives NaN or infinity for some particle (not a lost target), or a ``dt`` after
            the first is not finite (the message names the step).

        Examples
        --------
        >>> import vistrack as vt
        >>> pf = ParticleFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=1.0),
        ...                     n_particles=2000, rng=0)
        >>> ys = np.array([[0.0], [1.1], [np.nan], [2.9], [4.2]])
        >>> res = pf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2), modes=True)
        >>> res.modes.shape
        (5, 2)

        The model is linear-Gaussian, so the Kalman filter's means are the exact posterior's;
        2,000 particles come within 0.1 of them (0.02 here):

        >>> kf = vt.KalmanFilter(vt.ConstantVelocity(dim=1, q=0.1), vt.Position(dim=1, r=1.0))
        >>> exact = kf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
        >>> exact.means[:, 0].round(2), bool(np.abs(res.means - exact.means).max() < 0.1)
        (array([0.  , 1.06, 2.1 , 2.94, 4.09]), True)
        """
        modes = as_flag(modes, "modes")  # ("no" was true: the modes were searched)
        ys = as_float_array(ys, "ys", ndim=(2,))
        check_has_steps(ys)
        if self._m is not None and ys.shape[1] != self._m:  # both paths, before any step
            raise ValueError(f"ys must have {self._m} measurement components; got "
                             f"{ys.shape[1]}")
        check_not_infinite(ys, "ys")  # every particle's likelihood 0: not a lost target
        T = ys.shape[0]
        n, N, rng = self.ndim_state, self.n_particles, self.rng
        # checked before the first particles are drawn (a bad dt used up the generator's
        # draws, and the next call's particles were other ones)
        dts, ts = step_times(dt, times, T)
        if self._fused is not None and not modes:
            x = self._initial(particles, x0, P0)
            return self._filter_fused(ys, x, dt, times)
        x = self._initial(particles, x0, P0)
        times = ts
        logw = np.full(N, -math.log(N))
        means, covs = np.empty((T, n)), np.empty((T, n, n))
        mode_arr = np.empty((T, n)) if modes else None
        conf = np.empty(T) if modes else None
        ess, resampled, total = np.empty(T), np.zeros(T, bool), 0.0
        for t in range(T):
            if t > 0:
                x = self._propagate(x, float(dts[t]), float(times[t]), rng)
                if self._user_motion:
                    x = _user_particles(x, N, n, t)
                elif not np.isfinite(x).all():  # (an infinite particle: NaN means, unsaid)
                    raise self._failure(t, ys[t], x)
            if not np.isnan(ys[t]).all():
                a = logw + self._loglik(ys[t], x, t)
                top = np.max(a)
                if not np.isfinite(top):
                    raise self._failure(t, ys[t], x)
                w = np.exp(a - top)  # log-sum-exp: the largest weight is exp(0)
                s = w.sum()
                total += top + math.log(s)
                w /= s
                logw = a - (top + math.log(s))
            else:
                w = np.exp(logw)
                w /= w.sum()
            means[t], covs[t] = _wmean(x, w), _wcov(x, w)
            if modes:
                assert mode_arr is not None and conf is not None  # allocated when modes
                mode_arr[t], conf[t] = particle_mode(x, w)
            ess[t] = _ess(w)
            if resample_now(ess[t], self.ess_threshold, N):
                x = x[RESAMPLERS[self.resampling](w, N, rng)]
                logw = np.full(N, -math.log(N))
                resampled[t] = True
        w = np.exp(logw)
        return _result(means, covs, mode_arr, conf, ess, resampled, total, x, w / w.sum())

    def _failure(self, t: int, y: np.ndarray, x: np.ndarray) -> Exception:
        """What no particle's weight being finite at step ``t`` means: a motion or a
        measurement model that gave NaN or infinity (a ``ValueError`` naming it: one NaN
        log-weight made the largest NaN, and a model's error read as a lost target), or
        every particle's likelihood 0 (:class:`ParticleDegeneracyError`)."""
        bad = ~np.isfinite(x).all(axis=1)
        if bad.any():
            i = int(np.flatnonzero(bad)[0])
            return ValueError(f"the motion model gave NaN or infinity for {int(bad.sum())} of "
                              f"{len(x)} particles at step {t}; particles[{i}] = "
                              f"{x[i].tolist()}")
        with np.errstate(all="ignore"):
            ll = np.asarray(self._loglik(y, x, t), dtype=float)
        if np.isnan(ll).any():
            i = int(np.flatnonzero(np.isnan(ll))[0])
            return ValueError(f"the measurement model gave NaN or infinity for "
                              f"{int(np.isnan(ll).sum())} of {len(x)} particles at step {t} "
                              f"(measurement {y.tolist()}); particles[{i}] = {x[i].tolist()}")
        return _degenerate(t, y)

    def _initial(self, particles: ArrayLike | None, x0: ArrayLike | None,
                 P0: ArrayLike | None) -> np.ndarray:
        n, N = self.ndim_state, self.n_particles
        if particles is not None and (x0 is not None or P0 is not None):
            # (x0 and P0 were dropped without a word)
            given = " and ".join(k for k, v in (("x0", x0), ("P0", P0)) if v is not None)
            raise ValueError(f"give particles or x0 and P0, not both; got particles and "
                             f"{given}")
        if particles is not None:
            x = as_float_array(particles, "particles", ndim=(2,))
            if x.shape != (N, n):
                raise ValueError(f"particles must have shape ({N}, {n}); got {x.shape}")
            if not np.isfinite(x).all():  # it read as every particle's likelihood being 0
                i = int(np.flatnonzero(~np.isfinite(x).all(axis=1))[0])
                raise ValueError(f"particles must be finite; particles[{i}] = {x[i].tolist()}")
            return x.copy()
        for name, value in (("x0", x0), ("P0", P0)):
            if value is not None:  # NaN read as every particle's likelihood being 0, too
                check_finite(as_float_array(value, name), name)
        m0, C0 = check_prior(x0, P0, n, batch=False)
        # the principal root: the same particles on every machine (psd_sqrt)
        return m0 + self.rng.standard_normal((N, n)) @ psd_sqrt(C0).T

    def _filter_fused(self, ys: np.ndarray, x: np.ndarray, dt: ArrayLike | None,
                      times: ArrayLike | None) -> ParticleResult:
        assert self._fused is not None  # filter calls this only with the compiled parts
        fref, fparams, href, hp, mo, me = self._fused
        T, m = ys.shape
        n, N = self.ndim_state, self.n_particles
        R = me.Rm
        assert R.shape == (m, m)  # filter checked ys against the measurement model
        run = _fused_kernel(fref, href, n, m)
        dts, times = step_times(dt, times, T)
        # per step: the observed components, the whitening of their noise, the model's
        # parameters and the square root of Q
        seen = ~np.isnan(ys)
        if seen.all():  # the common case, without the sort of unique rows
            patterns, which = seen[:1], np.zeros(T, np.intp)
        else:
            patterns, which = np.unique(seen, axis=0, return_inverse=True)
        obs, Linv, c = (np.zeros((len(patterns), m), np.int64),
                        np.zeros((len(patterns), m, m)), np.zeros(len(patterns)))
        for p, key in enumerate(patterns):
            o = np.flatnonzero(key)
            if len(o):
                obs[p, :len(o)] = o
                key = o.tobytes()
                if key not in self._whiten:
                    self._whiten[key] = _whitening(R, o)
                Linv[p, :len(o), :len(o)], c[p] = self._whiten[key]
        which = which.ravel()
        obs, Linv, c, nobs = obs[which], Linv[which], c[which], seen.sum(1)
        # dt[0], the step before the first measurement, is not used (as on the numpy path):
        # the model is not evaluated at it (np.diff(times, prepend=np.nan) gives NaN there)
        dts = np.array(dts, dtype=float)
        dts[0] = dts[1] if T > 1 else 1.0
        times = np.ascontiguousarray(times, dtype=float)
        fp = np.asarray(fparams(dts, times), dtype=float).reshape(T, -1)
        # the square root of Q of each distinct step, gathered into a C array (T, n, n) even
        # where every step is the same: a broadcast view there, read-only and of no fixed
        # layout, was another type to numba, so each model's kernel was compiled twice
        d, inv = np.unique(dts, return_inverse=True)
        S = np.array([mo.Q_sqrt(float(v)) for v in d])[inv.ravel()]
        means, covs = np.empty((T, n)), np.empty((T, n, n))
        ess, resampled = np.empty(T), np.zeros(T, bool)
        logw, w = np.full(N, -math.log(N)), np.empty(N)
        fail, loglik, x = run(
            np.ascontiguousarray(x, dtype=float), np.empty((N, n)), np.where(seen, ys, 0.0),
            obs, nobs, Linv, c, me.angle_mask, dts, times, fp, hp, S,
            _random.SCHEMES.index(self.resampling), self.ess_threshold,
            _random.seed(self.rng), logw, w, np.zeros(N, np.int64), np.empty(N),
            means, covs, ess, resampled)
        if fail >= 0:
            raise self._failure(int(fail), ys[fail], x)
        w = np.exp(logw - logw.max())
        return _result(means, covs, None, None, ess, resampled, float(loglik), x, w / w.sum())
