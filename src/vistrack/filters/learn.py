r"""Learning a linear-Gaussian model from its measurements: expectation-maximisation and
maximum likelihood by gradient.

The Kalman filter needs the model, ``F``, ``Q``, ``H``, ``R`` and the prior ``x0``, ``P0``;
users rarely know the noise. :func:`em` learns any subset of them from one series or a batch,
the rest held fixed (Shumway and Stoffer [1]_); :func:`mle` learns the structured noise (the
factor ``q`` of ``Q``, ``R``'s diagonal or factor) by L-BFGS with the exact gradient, which
comes from the same smoothed sums (Fisher's identity), with standard errors.
:meth:`vistrack.filters.KalmanFilter.fit` does either for a filter built from models.

Each iteration of EM runs the filter and the Rauch-Tung-Striebel smoother (the E-step) and sets
the parameters learned to the maximum of the expected complete-data log-likelihood (the
M-step), which never lowers the likelihood of the measurements (but once, on the first
iteration, where the start lies outside the family learned: a per-step ``Q`` or ``R`` learned
as one matrix, or a correlated one learned as ``"diag"``). A learned covariance keeps the
null space of its start (EM's M-step sets it from expectations under the start, which lie
in it): a zero ``Q``, ``R`` or ``P0`` stays zero, and is refused; a singular one, such as
the Euler ``Q`` of a constant-velocity model, stays singular, so start from one of full
rank where the truth may be. With smoothed means
:math:`m_t`, covariances :math:`P_t`, the lag-one cross-covariances
:math:`C_t = \operatorname{cov}(x_t, x_{t-1} \mid y) = P_t G_{t-1}'` (the smoother's
gain :math:`G_{t-1} = P^+_{t-1} F_t' (P^-_t)^{-1}`) and the sums over the ``N``
transitions of the batch (``B (T-1)``, less those after a series' last measured step: the
steps that pad a shorter series tell nothing, and their terms, the current ``Q``'s and ``F``'s
own, would only hold each M-step back toward them),

.. math::

    S_{11} = \sum P_t + m_t m_t', \quad S_{10} = \sum C_t + m_t m_{t-1}', \quad
    S_{00} = \sum P_{t-1} + m_{t-1} m_{t-1}',

    F = S_{10} S_{00}^{-1}, \qquad
    Q = \frac{1}{N} \sum E[w_t w_t'] = \frac{1}{N} \sum S_{11,t} - F S_{10,t}' - S_{10,t} F'
    + F S_{00,t} F',

``H`` row by row from the steps where its component is measured, :math:`H_i = (\sum y_{ti}
m_t') (\sum P_t + m_t m_t')^{-1}`, and ``R`` the mean of :math:`E[v_t v_t']`,
:math:`v_t = y_t - H x_t`, over the steps that measured something (a step missed whole says
nothing of ``R``): for a measured component its residual's square and :math:`H P_t H'`, for
a missing one of a step measured in part what the current ``R`` expects given the measured
ones (the conditional Gaussian of ``v``). ``H`` is learned before ``R``, ``F`` before ``Q``
and ``x0`` before ``P0``, each with the other's new value, as in pykalman, which the tests
check this against step by step. ``E[w_t w_t']`` is summed term by term, :math:`(m_t - F
m_{t-1})(m_t - F m_{t-1})' + P_t - F C_t' - C_t F' + F P_{t-1} F'`, rather than from the
:math:`S` above, whose terms grow with the state's distance from the origin and cancel. When
the series of a batch share their covariances (the same prior, the same steps missing:
``FilterResult.shared_covs``), the smoother's covariances and gains are computed once for all
of them; when, moreover, the matrices are constant, every step is measured in full or not at
all, the last step is measured (no padding) and neither ``F`` nor ``H`` is learned, the whole
E-step is one compiled pass
(:mod:`vistrack.filters._estep`), which also stops computing the covariances at their steady
state; :func:`mle` uses the same E-step.

Structured noise: ``"diag"`` keeps the diagonal of the full estimate; ``"scaled"`` learns one
factor of the matrix given, ``Q_t = q Q^{(0)}_t``, :math:`q = \sum \operatorname{tr}(Q^{(0)+}_t
E[w_t w_t']) / \sum \operatorname{rank} Q^{(0)}_t` (the white-noise acceleration's ``q``, for
any time steps; the same for ``R``).

References
----------
.. [1] R. H. Shumway and D. S. Stoffer, "An approach to time series smoothing and forecasting
   using the EM algorithm", *Journal of Time Series Analysis* 3(4), 1982.
"""

from __future__ import annotations

import numbers
import warnings
from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING, Any, TextIO

import numpy as np

from .._jit import njit
from .._prebuilt import kernel
from .._validate import (
    as_flag,
    as_float_array,
    as_measurement_series,
    check_has_steps,
    check_linear_gaussian,
    check_prior,
)
from ._estep import WORK_TOO_SMALL, work_layout
from ._estep import estep_shared as _estep_shared
from .kalman import FilterResult, _is_dask, kalman_filter
from .smoothers import rts_smooth

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["FitResult", "em", "mle", "LEARNABLE", "NOISE_FORMS"]

LEARNABLE = ("F", "Q", "H", "R", "x0", "P0")
"""The parameters :func:`em` can learn."""

NOISE_FORMS = ("full", "diag", "scaled")
"""How ``Q`` and ``R`` are learned: every entry, the diagonal only, or one factor of the
matrix given."""


@dataclass(frozen=True)
class FitResult:
    """The output of :func:`em` and :func:`mle`: the model, learned and fixed parameters
    alike, and the log-likelihood at each iteration.

    From ``em(..., pooled=False)`` every attribute has a leading batch axis ``(B,)``, one fit
    per series, and ``loglik`` is padded with NaN after a series' last iteration.

    Attributes
    ----------
    F, Q, H, R : ndarray
        The model (a fixed parameter exactly as given; a learned one constant over the steps,
        or for ``"scaled"`` noise the matrix given times ``q`` or ``r``).
    x0, P0 : ndarray
        The prior of the first step.
    q, r : float or ndarray
        The factors learned for ``"scaled"`` noise (1.0 otherwise); from :func:`mle` with
        ``R_form="diag"``, ``r`` is ``R``'s diagonal.
    loglik : (iterations + 1,) ndarray
        ``log p(y)`` under the parameters at the start, after each iteration; the last is that
        of the parameters returned.
    iterations : int
        M-steps taken (:func:`em`), or L-BFGS and Newton iterations (:func:`mle`).
    converged : bool
        :func:`em`: the last iteration changed the log-likelihood by ``tol`` or less, and
        no learned ``Q`` or ``R`` fell to zero (constant data, whose likelihood has no
        maximum: warned);
        :func:`mle`: a Newton step from where L-BFGS stopped would change no parameter by
        more than ``xtol`` (relative).
    stderr : dict of str to float or ndarray
        :func:`mle` only (empty otherwise): standard errors of the learned ``"q"`` and ``"r"``
        (R's diagonal, or its factor), from the curvature of the log-likelihood at the
        maximum (the inverse of the observed information, by differences of the exact
        gradient).
    """

    F: np.ndarray
    Q: np.ndarray
    H: np.ndarray
    R: np.ndarray
    x0: np.ndarray
    P0: np.ndarray
    q: float | np.ndarray
    r: float | np.ndarray
    loglik: np.ndarray
    iterations: int | np.ndarray
    converged: bool | np.ndarray
    stderr: dict[str, Any] = field(default_factory=dict)


def em(
    ys: ArrayLike,
    *,
    F: ArrayLike,
    Q: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    x0: ArrayLike,
    P0: ArrayLike,
    learn: tuple[str, ...] | list[str] = ("Q", "R"),
    Q_form: str = "full",
    R_form: str = "full",
    pooled: bool = True,
    tol: float = 1e-6,
    max_iter: int = 100,
    progress: TextIO | None = None,
) -> FitResult:
    r"""Learn the parameters ``learn`` of a linear-Gaussian model from measurements by
    expectation-maximisation (see the module), the others fixed.

    Parameters
    ----------
    ys : (T, m) or (B, T, m) array_like, or (B, T, m) Dask array
        Measurements, NaN where missing (a whole step or some components; the masked entries
        of a numpy masked array, pykalman's convention, are missing too), as for
        :func:`kalman_filter`. Series of unequal length are padded with NaN after their
        last step: the padding tells nothing, and its transitions are left out of the
        M-steps of ``F`` and ``Q`` (they held each step back toward the current values: a
        batch of 19 random walks of 50 steps and one of 1,000 took 914 iterations where it
        now takes 114, to the same maximum). A Dask array chunked along the batch axis is
        fitted chunk by chunk where its chunks are (:func:`vistrack.filters.chunked.em`):
        pooled, the chunks' sums added at each iteration (numpy parameters returned, equal
        to the in-memory fit to rounding); with ``pooled=False``, lazily (a result of Dask
        arrays, equal to the in-memory fits).
    F, Q, H, R, x0, P0 : array_like
        The model to start from, as for :func:`kalman_filter` (constant or per-step matrices;
        a prior for all series or one per series). A learned ``F``, ``H``, or ``Q`` / ``R`` of
        form ``"full"`` or ``"diag"``, is constant over the steps; ``"scaled"`` keeps the
        per-step matrices given and learns their factor.
    learn : sequence of str
        Which of :data:`LEARNABLE` to learn.
    Q_form, R_form : {"full", "diag", "scaled"}
        How ``Q`` and ``R`` are learned (:data:`NOISE_FORMS`).
    pooled : bool
        One estimate from every series of a batch (the sums of the M-step over all of them),
        or one fit per series (``False``; the result then has a batch axis).
    tol : float
        Stop when an iteration changes the log-likelihood by ``tol`` nats or less (``-inf``:
        run ``max_iter`` iterations).
    max_iter : int
        The most iterations (M-steps).
    progress : stream, optional
        Where to write each iteration's log-likelihood.

    Returns
    -------
    FitResult
        The model and the log-likelihood trace.

    Raises
    ------
    ValueError
        If ``learn`` is a string, is empty or names something unknown, a form is unknown,
        ``tol`` is not a number or ``max_iter`` not a positive integer, ``ys`` measures
        nothing, a prior is given for another number of series, ``Q`` or ``F`` is learned
        from series of one step, ``F`` (``H``) is learned with a ``Q`` (``R``) that stays
        one per step, ``H`` where some steps miss some components and ``R`` is not diagonal,
        or for a component never measured, a learned ``Q``, ``R`` or ``P0`` is zero, or the
        model's arguments are invalid (as :func:`kalman_filter` says).
    TypeError
        If ``pooled`` is not True or False, or ``progress`` has no ``write``.

    Warns
    -----
    RuntimeWarning
        If a learned ``Q`` or ``R`` falls to zero (every variance below the smallest normal
        float, 2.2e-308: constant data, whose likelihood grows without bound as the noise
        falls): the iterations stop there, at the last parameters whose likelihood was
        computed, and the fit is not converged.

    Examples
    --------
    A random walk seen in noise, its two variances learned from a start ten times off:

    >>> from vistrack.simulate import simulate_lgssm
    >>> model = dict(F=[[1.0]], H=[[1.0]], x0=[0.0], P0=[[1.0]])
    >>> _, ys = simulate_lgssm(2000, Q=[[0.5]], R=[[4.0]], rng=1, **model)
    >>> fit = em(ys, Q=[[5.0]], R=[[0.4]], **model, tol=1e-8, max_iter=500)
    >>> round(float(fit.Q[0, 0]), 2), round(float(fit.R[0, 0]), 2), bool(fit.converged)
    (0.5, 4.03, True)
    >>> bool(np.all(np.diff(fit.loglik) >= -1e-9))  # EM never lowers the likelihood
    True
    """
    learned = _names(learn, LEARNABLE)
    pooled = as_flag(pooled, "pooled")  # ("no" was true: pooled)
    if progress is not None and not callable(getattr(progress, "write", None)):
        # (True failed at the first iteration: "'bool' object has no attribute 'write'")
        raise TypeError(f"progress must be a stream with write() (e.g. sys.stderr) or None; "
                        f"got {progress!r}")
    for name, form in (("Q_form", Q_form), ("R_form", R_form)):
        if form not in NOISE_FORMS:
            raise ValueError(f"{name} must be one of {list(NOISE_FORMS)}; got {form!r}")
    if isinstance(tol, bool) or not isinstance(tol, numbers.Real) or np.isnan(tol):
        raise ValueError(f"tol must be a number (-inf: never stop before max_iter); got {tol!r}")
    if _is_dask(ys):  # a batch larger than memory: the E-step's sums added chunk to chunk
        from . import chunked

        _check_max_iter(max_iter)
        return chunked.em(ys, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0, learn=learned, Q_form=Q_form,
                          R_form=R_form, pooled=pooled, tol=float(tol),
                          max_iter=int(max_iter), progress=progress)
    y, params, single = _problem(ys, F, Q, H, R, x0, P0, learned, max_iter)
    o = _Observed(y)
    _check_em(o.measured, o.has_partial, params, learned, Q_form, R_form)
    if pooled or single:  # a batch of one, unpooled, keeps its batch axis
        return _fit_in_memory(y, params, learned, Q_form, R_form, float(tol), int(max_iter),
                              progress, o=o)
    return _fit_each(y, params, learned, Q_form, R_form, float(tol), int(max_iter), progress)


def _fit_in_memory(y: np.ndarray, p: dict[str, np.ndarray], learn: tuple[str, ...],
                   Q_form: str, R_form: str, tol: float, max_iter: int,
                   progress: TextIO | None, label: str = "", *,
                   o: _Observed | None = None) -> FitResult:
    """:func:`_fit` on the series ``y (B, T, m)`` in memory, pooled (``o``: ``y``'s
    :class:`_Observed`, if already made)."""
    obs = _Observed(y) if o is None else o
    shared = _shares_covariances(obs, p, learn)
    return _fit(lambda params, _: _estep(obs, params, shared), y.shape[1], p,
                learn, Q_form, R_form, tol, max_iter, progress, label)


def _fit_each(y: np.ndarray, params: dict[str, np.ndarray], learn: tuple[str, ...],
              Q_form: str, R_form: str, tol: float, max_iter: int,
              progress: TextIO | None, first: int = 0) -> FitResult:
    """One fit per series of ``y (B, T, m)``, stacked along a batch axis (``loglik`` padded
    with NaN after each series' last iteration); ``first``: the first series' index in the
    whole batch, for messages. Each series is checked as :func:`em` checks a batch (a
    component one series never measures leaves its row of ``H`` unknown, though another
    series measures it), the error naming the series."""
    B = y.shape[0]
    fits = []
    for b in range(B):
        p = dict(params)
        if p["x0"].ndim == 2:
            p["x0"] = p["x0"][b]
        if p["P0"].ndim == 3:
            p["P0"] = p["P0"][b]
        o = _Observed(y[b:b + 1])
        if not np.isfinite(y[b]).any():  # (it came back "converged" at its start, unsaid)
            raise ValueError(f"series {first + b} of ys (pooled=False): it has no "
                             "measurement: every value is NaN")
        try:
            _check_em(o.measured, o.has_partial, p, learn, Q_form, R_form)
        except ValueError as e:
            raise ValueError(f"series {first + b} of ys (pooled=False): {e}") from None
        fits.append(_fit_in_memory(y[b:b + 1], p, learn, Q_form, R_form, tol, max_iter,
                                   progress, f"series {first + b}: ", o=o))
    K = max(len(f.loglik) for f in fits)
    ll = np.full((B, K), np.nan)
    for b, f in enumerate(fits):
        ll[b, :len(f.loglik)] = f.loglik
    def stack(name: str) -> np.ndarray:
        return np.stack([getattr(f, name) for f in fits])

    return FitResult(F=stack("F"), Q=stack("Q"), H=stack("H"), R=stack("R"), x0=stack("x0"),
                     P0=stack("P0"), q=stack("q"), r=stack("r"), loglik=ll,
                     iterations=stack("iterations"), converged=stack("converged"))


def _problem(ys: ArrayLike, F: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike,
             x0: ArrayLike, P0: ArrayLike, learn: tuple[str, ...],
             max_iter: Any) -> tuple[np.ndarray, dict[str, np.ndarray], bool]:
    """The measurements as ``(B, T, m)``, the model as float arrays, checked as far as the
    filter's first run does not check them, and whether ``ys`` was one series ``(T, m)``."""
    _check_max_iter(max_iter)
    y, single = as_measurement_series(ys)
    check_has_steps(y)
    _check_steps(y.shape[1], learn)
    # the model before the prior, as kalman_filter checks it: a malformed F is named, not
    # the x0 that disagrees with it
    F_ = as_float_array(F, "F", ndim=(2, 3))
    n = _state_size(F_.shape[-1], x0, P0)
    check_linear_gaussian(F, Q, H, R, n, y.shape[2], y.shape[1])
    x0_, P0_ = check_prior(x0, P0, n, series=y.shape[0])
    x0_ = x0_[0] if x0_.ndim == 2 and x0_.shape[0] == 1 else x0_
    P0_ = P0_[0] if P0_.ndim == 3 and P0_.shape[0] == 1 else P0_
    if not np.isfinite(y).any():
        raise ValueError("ys has no measurement: every value is NaN")
    return y, {k: np.asarray(v, dtype=np.float64)
               for k, v in (("F", F), ("Q", Q), ("H", H), ("R", R), ("x0", x0_),
                            ("P0", P0_))}, single


def _state_size(n_F: int, x0: Any, P0: Any) -> int:
    """The state size to check the model against: the prior's where ``x0`` and ``P0`` agree
    on one (then an ``F``, ``Q`` or ``H`` of another is the argument named, as by
    :func:`kalman_filter`), else ``F``'s ``n_F`` (and the prior is named)."""
    try:
        sx, sP = np.shape(x0), np.shape(P0)
    except ValueError:  # ragged: check_prior names it
        return n_F
    if len(sx) in (1, 2) and len(sP) in (2, 3) and sP[-2:] == (sx[-1], sx[-1]):
        return int(sx[-1])
    return n_F


def _check_max_iter(max_iter: Any) -> None:
    if isinstance(max_iter, bool) or not isinstance(max_iter, (int, np.integer)) or max_iter < 1:
        raise ValueError(f"max_iter must be an integer >= 1; got {max_iter!r}")


def _check_steps(T: int, learn: tuple[str, ...]) -> None:
    if T < 2 and ({"F", "Q"} & set(learn)):
        raise ValueError(f"learning F or Q needs series of at least 2 steps; got T={T}")


def _names(learn: Any, allowed: tuple[str, ...]) -> tuple[str, ...]:
    """``learn`` as a tuple of names, each one of ``allowed``."""
    if isinstance(learn, str):
        raise ValueError(f"learn must be a sequence of names (e.g. ({learn!r},)), not a string")
    try:
        names = tuple(learn)
    except TypeError:  # (None was "'NoneType' object is not iterable")
        raise TypeError(f"learn must be a sequence of names, some of {list(allowed)}; got "
                        f"{learn!r}") from None
    if not names:  # (nothing to learn ran an iteration and returned the model as given)
        raise ValueError(f"learn must name at least one of {list(allowed)}; got {learn!r}")
    for name in names:
        if name not in allowed:
            raise ValueError(f"learn must name some of {list(allowed)}; got {name!r}")
    return names


def _check_measured(measured: np.ndarray, what: str) -> None:
    """Raise ValueError naming the first component never measured (``measured (m,)``, of the
    whole batch): of ``what`` nothing can be learned."""
    never = np.flatnonzero(~measured)
    if len(never):
        raise ValueError(f"component {int(never[0])} of ys is never measured: {what} cannot "
                         "be learned")


def _check_em(measured: np.ndarray, partial: bool, p: dict[str, np.ndarray],
              learn: tuple[str, ...], Q_form: str, R_form: str) -> None:
    """Refuse what :func:`em`'s M-steps do not cover, naming why; ``measured (m,)``: which
    components of the measurements are measured at some step of some series, ``partial``:
    whether some step measures some of its components but not all."""
    for name, form, M in (("Q", Q_form, p["Q"]), ("R", R_form, p["R"])):
        if name in learn and form == "scaled" and not np.any(M):
            raise ValueError(f"{name} must not be zero to learn its factor ({name}_form="
                             "'scaled')")
    # a zero start is a fixed point of EM whatever the form: "converged" at it, far from the
    # maximum (the expected noise under a zero noise is zero)
    for name in ("Q", "R", "P0"):
        if name in learn and not np.any(p[name]):
            raise ValueError(f"{name} must not be zero to learn it: EM keeps a zero {name} "
                             "zero (start from one of full rank, e.g. the identity)")
    # F and H are learned unweighted by the noise: exact where that noise, after the M-step,
    # is one matrix for all steps (a per-step one would weigh each step by its inverse)
    for name, noise, form in (("F", "Q", Q_form), ("H", "R", R_form)):
        per_step = p[noise].ndim == 3 and (noise not in learn or form == "scaled")
        if name in learn and per_step:
            raise ValueError(f"learning {name} needs one {noise} for all steps, given or "
                             f"learned as 'full' or 'diag' (its M-step would otherwise weigh "
                             f"each step by its {noise}); got a {noise} per step")
    if "H" in learn:
        _check_measured(measured, "H's row for it")
        R_diagonal = ("R" in learn and R_form == "diag") or (
            not ("R" in learn and R_form == "full")
            and not np.any(p["R"] - np.eye(p["R"].shape[-1]) * np.diagonal(
                p["R"], axis1=-2, axis2=-1)[..., None, :]))
        if partial and len(measured) > 1 and not R_diagonal:
            raise ValueError("learning H where some steps miss some of their components needs "
                             "a diagonal R (R_form='diag', or a diagonal R not learned as "
                             "'full'): with a correlated R the rows of H are coupled")


def mle(
    ys: ArrayLike,
    *,
    F: ArrayLike,
    Q: ArrayLike,
    H: ArrayLike,
    R: ArrayLike,
    x0: ArrayLike,
    P0: ArrayLike,
    learn: tuple[str, ...] | list[str] = ("Q", "R"),
    R_form: str = "diag",
    xtol: float = 1e-4,
    max_iter: int = 200,
) -> FitResult:
    r"""Learn the noise of a linear-Gaussian model by maximum likelihood: L-BFGS over the
    logarithms of its structured parameters, with the exact gradient.

    The parameters: ``q`` with ``Q_t = q Q^{(0)}_t`` (``Q`` as given, constant or per step:
    the white-noise acceleration's ``q`` for any time steps), and ``R``'s diagonal
    (``R_form="diag"``, ``R`` diagonal) or its factor ``r`` (``"scaled"``, ``R_t = r
    R^{(0)}_t``). The gradient of ``log p(y)`` is the expected gradient of the complete-data
    log-likelihood given the measurements (Fisher's identity), from the same smoothed sums
    as :func:`em`'s M-step:

    .. math::

        \frac{\partial \log p(y)}{\partial \log q} = -\tfrac12 \sum_t \operatorname{rank}
        Q^{(0)}_t + \frac{1}{2q} \sum_t \operatorname{tr}\big(Q^{(0)+}_t E[w_t w_t' \mid
        y]\big), \qquad \frac{\partial \log p(y)}{\partial \log r_i} = -\tfrac{N}{2} +
        \frac{1}{2 r_i} \sum_t E[v_{ti}^2 \mid y]

    over the transitions of every series up to its last measured step (those after it, a
    shorter series' padding, add nothing to either term) and the ``N`` steps that measured
    something. Where
    EM creeps towards the maximum, this reaches it in a few dozen evaluations of the filter
    and the smoother; both find the same maximum.

    Parameters
    ----------
    ys : (T, m) or (B, T, m) array_like
        Measurements, NaN (or masked, in a numpy masked array) where missing; a batch is
        pooled (one ``q`` and ``R`` for all).
    F, Q, H, R, x0, P0 : array_like
        The model, as for :func:`kalman_filter`; ``Q`` and ``R`` are the start and the
        shapes of their structure (``R`` diagonal for ``"diag"``: its off-diagonal entries
        are dropped). Each factor is searched within ``e^±20`` (about 5e8) of its start, so
        that the filter stays finite; a fit that ends on that bound is warned of (start
        nearer the data's scale, or learn by :func:`em`, which has no bound).
    learn : sequence of {"Q", "R"}
        Which noise to learn; the rest stays as given.
    R_form : {"diag", "scaled"}
        ``R``'s structure.
    xtol : float
        Converged when a Newton step would change no parameter by a factor of more than
        ``1 + xtol``. L-BFGS runs first, then Newton's method with the observed information
        (the central differences of the exact gradient), which also gives the standard
        errors.
    max_iter : int
        The most L-BFGS iterations, and the most Newton steps after them.

    Returns
    -------
    FitResult
        The model at the maximum, ``q`` and ``r`` (R's diagonal for ``"diag"``),
        ``loglik`` at the start and after each iteration, and ``stderr``.

    Raises
    ------
    ValueError
        If ``learn`` is empty or names something else than ``"Q"`` and ``"R"``, ``R_form``
        is unknown, ``xtol`` is not > 0, ``max_iter`` is not a positive integer, ``ys``
        measures nothing, the noise learned is zero (or ``R``'s diagonal is not > 0, or a
        component is never measured, for ``"diag"``), or the model is invalid (as
        :func:`kalman_filter` says).

    Examples
    --------
    The random walk of :func:`em`, its two variances by maximum likelihood:

    >>> from vistrack.simulate import simulate_lgssm
    >>> model = dict(F=[[1.0]], H=[[1.0]], x0=[0.0], P0=[[1.0]])
    >>> _, ys = simulate_lgssm(2000, Q=[[0.5]], R=[[4.0]], rng=1, **model)
    >>> fit = mle(ys, Q=[[1.0]], R=[[1.0]], **model)  # Q = q [[1]], R = diag(r)
    >>> round(fit.q, 2), fit.r.round(2), bool(fit.converged)
    (0.5, array([4.03]), True)
    >>> round(fit.stderr["q"], 2), fit.stderr["r"].round(2)  # their standard errors
    (0.06, array([0.16]))
    """
    from scipy.optimize import minimize

    learned = _names(learn, ("Q", "R"))
    if R_form not in ("diag", "scaled"):
        raise ValueError(f"R_form must be 'diag' or 'scaled'; got {R_form!r}")
    if isinstance(xtol, bool) or not isinstance(xtol, numbers.Real) or not xtol > 0:
        raise ValueError(f"xtol must be a number > 0; got {xtol!r}")
    y, p, _ = _problem(ys, F, Q, H, R, x0, P0, learned, max_iter)
    lik = _Structured(y, p, learned, R_form)
    value_and_grad, model, nq, nr = lik.value_and_grad, lik.model, lik.nq, lik.nr
    theta0 = lik.start()
    lls = [value_and_grad(theta0)[0]]
    it = [0]

    def negative(theta: np.ndarray) -> tuple[float, np.ndarray]:
        ll, g = value_and_grad(theta)
        return -ll, -g

    def record(xk: np.ndarray) -> None:  # after each iteration, at its point (computed)
        lls.append(value_and_grad(xk)[0])
        it[0] += 1

    k = nq + nr
    if k == 0:
        return FitResult(F=p["F"], Q=p["Q"], H=p["H"], R=p["R"], x0=p["x0"], P0=p["P0"], q=1.0,
                         r=1.0, loglik=np.array(lls), iterations=0, converged=True)
    # each factor within e^±20 of its start: the filter stays finite
    bounds = [(t - 20.0, t + 20.0) for t in theta0]
    opt = minimize(negative, theta0, jac=True, method="L-BFGS-B", callback=record,
                   bounds=bounds, options={"gtol": 1e-9 * y.shape[0] * y.shape[1],
                                           "maxiter": int(max_iter), "ftol": 1e-13})
    # then Newton's method with the observed information (central differences of the exact
    # gradient), halving a step that does not raise the likelihood: L-BFGS stops where its
    # line search finds no rise, which is not always the maximum
    theta, (ll, g) = opt.x, value_and_grad(opt.x)
    converged = False
    for _ in range(int(max_iter)):
        info = _information(value_and_grad, theta)
        try:
            step = np.linalg.solve(info, g)
        except np.linalg.LinAlgError:
            break
        if not np.all(np.linalg.eigvalsh(info) > 0):
            step = g / max(1.0, float(np.max(np.diag(info))))  # not concave here: ascend
        elif np.max(np.abs(step)) <= xtol:
            converged = True
            break
        for _ in range(30):
            trial = np.clip(theta + step, [b[0] for b in bounds], [b[1] for b in bounds])
            ll_new, g_new = value_and_grad(trial)
            if ll_new >= ll:
                break
            step = step / 2
        else:
            break
        if ll_new == ll and np.array_equal(trial, theta):
            break
        theta, ll, g = trial, ll_new, g_new
        lls.append(ll)
        it[0] += 1
    else:
        info = _information(value_and_grad, theta)
    best = model(theta)
    lo, hi = np.array([b[0] for b in bounds]), np.array([b[1] for b in bounds])
    edge = np.flatnonzero((theta <= lo) | (theta >= hi))
    if len(edge):
        # (a random walk scaled by 1e5, from Q = R = 1, stopped at q = r = 4.85e8, unsaid)
        names = ["q"] * nq + (["r"] if R_form != "diag" else [f"r[{i}]" for i in range(nr)])
        which = ", ".join(names[i] for i in edge)
        warnings.warn(f"mle: {which} reached e^±20 times its start, the bound of the search: "
                      "the fit is not the maximum; start Q and R nearer the data's scale, or "
                      "learn them by em", RuntimeWarning, stacklevel=2)
    q = float(np.exp(theta[0])) if nq else 1.0
    r: float | np.ndarray = (np.exp(theta[nq:]) if R_form == "diag" else float(
        np.exp(theta[nq]))) if nr else 1.0
    # the standard errors by the delta method
    try:
        var = np.diag(np.linalg.inv(info))
    except np.linalg.LinAlgError:
        var = np.full(k, np.inf)
    se = np.sqrt(np.where(var > 0, var, np.inf)) * np.exp(theta)
    errors: dict[str, Any] = {}
    if nq:
        errors["q"] = float(se[0])
    if nr:
        errors["r"] = se[nq:] if R_form == "diag" else float(se[nq])
    return FitResult(F=best["F"], Q=best["Q"], H=best["H"], R=best["R"], x0=best["x0"],
                     P0=best["P0"], q=q, r=r, loglik=np.array(lls), iterations=it[0],
                     converged=converged, stderr=errors)


def _information(value_and_grad: Any, theta: np.ndarray, h: float = 1e-4) -> np.ndarray:
    """The observed information (minus the Hessian of the log-likelihood) at ``theta``, by
    central differences of the exact gradient, symmetrised."""
    k = len(theta)
    info = np.empty((k, k))
    for j in range(k):
        d = np.zeros(k)
        d[j] = h
        info[:, j] = (value_and_grad(theta - d)[1] - value_and_grad(theta + d)[1]) / (2 * h)
    return (info + info.T) / 2


class _Structured:
    """``log p(y)`` and its gradient over the logarithms of the structured noise parameters
    of :func:`mle`: ``theta = [log q] + [log r_i ...]`` (or ``[log r]``)."""

    def __init__(self, y: np.ndarray, p: dict[str, np.ndarray], learn: tuple[str, ...],
                 R_form: str) -> None:
        _, T, m = y.shape
        diag = R_form == "diag" and "R" in learn
        if diag and p["R"].ndim != 2:
            raise ValueError("R_form='diag' needs one R (m, m) for all steps; got "
                             f"{p['R'].shape}")
        self.y, self.p, self.R_form = y, p, R_form
        self.o = _Observed(y)
        self.shared = _shares_covariances(self.o, p, learn)
        self.R0 = np.diag(np.diag(p["R"])) if diag else p["R"]  # R as given, if not learned
        if "Q" in learn and not np.any(p["Q"]):
            raise ValueError("Q must not be zero to learn its factor q")
        if "R" in learn and not np.any(p["R"]):
            raise ValueError("R must not be zero to learn it")
        if diag:
            if not np.all(np.diag(p["R"]) > 0):
                raise ValueError(f"R's diagonal must be > 0 to learn it; got {np.diag(p['R'])}")
            _check_measured(self.o.measured, "its variance in R")
        self.nq = 1 if "Q" in learn else 0
        self.nr = (m if R_form == "diag" else 1) if "R" in learn else 0
        n_meas = self.o.count  # series that measured something, per step
        self.n_meas = int(n_meas.sum())
        if self.nq:
            self.Q_scaled = _Scaled(p["Q"], T - 1)
            # (the transitions the E-step's sums keep: none after a series' last measured step)
            self.Q_dof = self.Q_scaled.dof(self.o.move_count)
        if self.nr and R_form == "scaled":
            self.R_scaled = _Scaled(self.R0, T)
            self.R_dof = self.R_scaled.dof(n_meas)
        self._memo: dict[bytes, tuple[float, np.ndarray]] = {}

    def start(self) -> np.ndarray:
        """``theta`` of the model given."""
        if not self.nr:
            return np.zeros(self.nq)
        logr = np.log(np.diag(self.R0)) if self.R_form == "diag" else np.zeros(1)
        return np.r_[np.zeros(self.nq), logr]

    def model(self, theta: np.ndarray) -> dict[str, np.ndarray]:
        out = dict(self.p, R=self.R0)
        if self.nq:
            out["Q"] = np.exp(theta[0]) * self.p["Q"]
        if self.nr:
            e = np.exp(theta[self.nq:])
            out["R"] = np.diag(e) if self.R_form == "diag" else e[0] * self.R0
        return out

    def value_and_grad(self, theta: np.ndarray) -> tuple[float, np.ndarray]:
        """``log p(y)`` and its gradient at ``theta``; a point asked for again (L-BFGS's
        start, its last point, the iterations' log) is not computed again."""
        key = np.asarray(theta, dtype=np.float64).tobytes()
        if key in self._memo:
            return self._memo[key]
        y, nq, nr = self.y, self.nq, self.nr
        T = y.shape[1]
        mp = self.model(theta)
        e = _estep(self.o, mp, self.shared)
        ll = e.ll
        g = np.empty(nq + nr)
        if nq:
            tr = self.Q_scaled.trace(e.process_noise_sums(_transitions(mp["F"], T)))
            g[0] = -0.5 * self.Q_dof + 0.5 * tr / np.exp(theta[0])
        if nr:
            V = e.vv(mp["H"])
            if self.R_form == "diag":
                g[nq:] = (-0.5 * self.n_meas
                          + 0.5 * np.diagonal(V.sum(axis=0)) / np.exp(theta[nq:]))
            else:
                g[nq] = -0.5 * self.R_dof + 0.5 * self.R_scaled.trace(V) / np.exp(theta[nq])
        if len(self._memo) > 256:
            self._memo.clear()
        self._memo[key] = ll, g
        return ll, g


class _Scaled:
    """A noise learned as a factor of the matrices given (``shape``, one for all steps or one
    per step), over the last ``K`` steps of ``T`` (the ``T - 1`` transitions of ``Q``, the
    ``T`` steps of ``R``): their pseudo-inverses and ranks, computed once for EM's M-step of
    the factor, ``trace / dof``, and for the score of :func:`mle`."""

    def __init__(self, shape: np.ndarray, K: int) -> None:
        S = _steps(shape, K)
        S = S[-K:] if S.shape[0] > 1 else S
        self.pinv, self.rank = np.linalg.pinv(S), np.linalg.matrix_rank(S)

    def trace(self, E: np.ndarray) -> float:
        """``sum_k tr(pinv_k E_k)`` of the expected outer products ``E (K, d, d)``."""
        if len(self.pinv) == 1:
            return float(np.trace(self.pinv[0] @ E.sum(axis=0)))
        return float(np.einsum("kij,kji->", self.pinv, E))

    def dof(self, count: np.ndarray) -> int:
        """``sum_k rank_k count_k``: the dimensions the ``count (K,)`` series measure."""
        if len(self.rank) == 1:
            return int(np.sum(count)) * int(self.rank[0])
        return int(np.sum(count * self.rank))


def _fit(estep: Any, T: int, p: dict[str, np.ndarray], learn: tuple[str, ...],
         Q_form: str, R_form: str, tol: float, max_iter: int, progress: TextIO | None,
         label: str = "") -> FitResult:
    """EM pooled over a batch of series of ``T`` steps; ``estep(p, learn)`` runs the
    E-step under the model ``p`` and returns an object with the log-likelihood ``ll`` and the
    M-step's sums (:class:`_EStep` for a batch in memory, one whose sums are added chunk to
    chunk for a Dask array)."""
    Q0, R0 = p["Q"], p["R"]  # the shapes of "scaled" noise
    Q_scaled = _Scaled(Q0, T - 1) if "Q" in learn and Q_form == "scaled" else None
    R_scaled = _Scaled(R0, T) if "R" in learn and R_form == "scaled" else None
    q = r = 1.0
    lls: list[float] = []
    converged = False
    for k in range(max_iter + 1):
        e = estep(p, learn if k < max_iter else ())
        ll = e.ll
        lls.append(ll)
        if progress is not None:
            progress.write(f"{label}EM iteration {k}: log-likelihood {ll:.6f}\n")
        if k > 0 and _fell_to_zero(p, learn):
            # a learned noise fell to zero (constant data: said below); its variances below
            # the smallest normal float, the E-steps after it underflow to 0 and to a
            # covariance that is not positive definite
            break
        # a change of tol or less either way (a fall larger than that, as from a per-step
        # start outside the constant family learned, goes on)
        if k > 0 and abs(ll - lls[-2]) <= tol:
            converged = True
            break
        if k == max_iter:
            break
        new = dict(p)
        if {"F", "Q"} & set(learn):
            if "F" in learn and e.Q_count().any():  # (else nothing depends on F: kept)
                S11, S10, S00 = e.transition_sums()
                new["F"] = np.linalg.solve(S00.sum(axis=0).T, S10.sum(axis=0).T).T
            if "Q" in learn:
                A = e.process_noise_sums(_transitions(new["F"], T))
                new["Q"], q_new = _noise(A, e.Q_count(), Q0, Q_form, Q_scaled)
                q = q_new if Q_form == "scaled" else 1.0
        if "H" in learn:
            new["H"] = _H_rows(*e.H_sums())
        if "R" in learn:
            new["R"], r_new = _noise(e.vv(new["H"]), e.R_count(), R0, R_form, R_scaled)
            r = r_new if R_form == "scaled" else 1.0
        if {"x0", "P0"} & set(learn):
            new["x0"], new["P0"] = e.prior(learn)
        for name in ("Q", "R", "P0"):  # symmetric to the last bit, and not below zero
            if name in learn:
                new[name] = _psd((new[name] + np.swapaxes(new[name], -1, -2)) / 2)
        p = new
    for name in _fell_to_zero(p, learn):
        # (constant data: EM went on until the variances were subnormal, 1e-323, and said it
        # had converged there)
        d = np.diagonal(p[name], axis1=-2, axis2=-1)
        warnings.warn(f"{label}{name} fell to zero (its largest variance {d.max():.3g}): "
                      f"the measurements fit the model without that noise, and the "
                      f"likelihood grows without bound as it falls; the fit is not "
                      f"converged. Keep {name} fixed, or learn from data with noise",
                      RuntimeWarning, stacklevel=4)
        converged = False
    return FitResult(F=p["F"], Q=p["Q"], H=p["H"], R=p["R"], x0=p["x0"], P0=p["P0"], q=q, r=r,
                    loglik=np.array(lls), iterations=len(lls) - 1, converged=converged)


class _Observed:
    """What every E-step needs of the measurements ``y (B, T, m)`` (NaN: missing), worked out
    once for all iterations: ``obs`` (True where measured), ``y0`` (``y`` with 0 where
    missing), ``measured`` ``(m,)`` (each component measured at some step of some series), per
    series and step (``(B, T)``) ``full`` (every component measured) and ``partial`` (some but
    not all), ``has_partial`` (any such step), ``count`` ``(T,)``, how many series
    measured something at each step, ``moves`` ``(B, T - 1)``, True for each transition up
    to the series' last measured step (the M-steps of ``F`` and ``Q`` leave the others out),
    ``move_count`` ``(T - 1,)`` their number per transition, ``all_move`` (every one), and
    ``seen`` ``(B,)``, each series measured at some step (the prior's M-steps leave the
    others out)."""

    def __init__(self, y: np.ndarray) -> None:
        self.y = y = np.ascontiguousarray(y, dtype=np.float64)
        self.obs = ~np.isnan(y)
        self.y0 = np.where(self.obs, y, 0.0)
        self.measured = self.obs.any(axis=(0, 1))
        self.full = self.obs.all(axis=-1)
        some = self.obs.any(axis=-1)
        self.partial = some & ~self.full
        self.has_partial = bool(self.partial.any())
        self.count = some.sum(axis=0)
        B, T = some.shape
        last = np.where(some.any(axis=1), T - 1 - np.argmax(some[:, ::-1], axis=1), -1)
        self.moves = np.arange(1, T)[None, :] <= last[:, None]
        self.move_count = self.moves.sum(axis=0)
        self.all_move = bool(self.moves.all())
        self.seen = last >= 0
        self._yt: np.ndarray | None = None
        self._work: np.ndarray | None = None

    @property
    def yt(self) -> np.ndarray:
        """``y`` as ``(T, m, B)``, the series last (contiguous), made when first asked for."""
        if self._yt is None:
            self._yt = np.ascontiguousarray(self.y.transpose(1, 2, 0))
        return self._yt

    def work(self, n: int) -> np.ndarray:
        """The work space of :func:`._estep.estep_shared` for ``n`` states, made when first
        asked for and the same for every iteration after."""
        B, T, m = self.y.shape
        size = work_layout.py_func(T, n, m, B)[0]
        if self._work is None or self._work.shape[0] < size:
            self._work = np.empty(size)
        return self._work


class _EStep:
    """The E-step over measurements ``o.y (B, T, m)`` (see :class:`_Observed`) in memory
    under the model ``p``: the filter's log-likelihood at once, the smoother and each of the
    M-step's sums when first asked for."""

    def __init__(self, o: _Observed, p: dict[str, np.ndarray]) -> None:
        self.o, self.p = o, p
        self.res = kalman_filter(o.y, F=p["F"], Q=p["Q"], H=p["H"], R=p["R"], x0=p["x0"],
                                 P0=p["P0"])
        self.ll = float(np.sum(self.res.loglik))
        self._smoothed: tuple[np.ndarray, np.ndarray, np.ndarray, int] | None = None

    @property
    def smoothed(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
        """:func:`_smoothed` of this E-step's filter run."""
        if self._smoothed is None:
            self._smoothed = _smoothed(self.res, self.p["F"], self.p["Q"])
        return self._smoothed

    def transition_sums(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return _transition_sums(*self.smoothed, moves=None if self.o.all_move else self.o)

    def process_noise_sums(self, Fn: np.ndarray) -> np.ndarray:
        """``E[w_t w_t']`` summed over the batch, per transition ``(T - 1, n, n)``, ``w_t = x_t
        - F_t x_{t-1}`` under the transitions ``Fn`` (:func:`_transitions`), term by term:
        ``d_t d_t'`` of the smoothed means' ``d_t = m_t - F_t m_{t-1}``, and ``Ps_t - F_t C_t'
        - C_t F_t' + F_t Ps_{t-1} F_t'`` with the lag-one covariance ``C_t = Ps_t X_{t-1}``.
        (``S11 - F S10' - S10 F' + F S00 F'`` from :meth:`transition_sums` is the same sum, but
        its terms grow with the state's size and cancel: far from the origin, digits lost.)"""
        ms, Ps, X, mult = self.smoothed
        Ft = np.swapaxes(Fn, -1, -2)
        Fx = ms[:, :-1] @ Ft if Fn.ndim == 2 else np.einsum("tij,btj->bti", Fn, ms[:, :-1])
        d = ms[:, 1:] - Fx
        FC = Fn @ np.swapaxes(Ps[:, 1:] @ X, -1, -2)
        cov = Ps[:, 1:] - FC - np.swapaxes(FC, -1, -2) + Fn @ Ps[:, :-1] @ Ft
        if self.o.all_move:
            return _outer_sum(d, d) + mult * cov.sum(axis=0)
        return _outer_sum(d * self.o.moves[..., None], d) + _over_moves(cov, self.o)

    def Q_count(self) -> np.ndarray:
        """How many series enter each transition's sum ``(T - 1,)``: those measured at it
        or after."""
        return self.o.move_count

    def H_sums(self) -> tuple[np.ndarray, np.ndarray]:
        ms, Ps, _, mult = self.smoothed
        return _H_sums(self.o, ms, Ps, mult)

    def vv(self, H: np.ndarray) -> np.ndarray:
        ms, Ps, _, mult = self.smoothed
        return _expected_vv(self.o, ms, Ps, mult, H, self.p["R"])

    def R_count(self) -> np.ndarray:
        """How many series measured something at each step ``(T,)``."""
        return self.o.count

    def prior(self, learn: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
        """The prior ``x0``, ``P0`` after the M-step (those not in ``learn`` as they were)."""
        ms, Ps, _, _ = self.smoothed
        return _prior_step(ms[:, 0], Ps[:, 0], self.p["x0"], self.p["P0"], learn, self.o.seen)


def _prior_step(ms0: np.ndarray, Ps0: np.ndarray, x0: np.ndarray, P0: np.ndarray,
                learn: tuple[str, ...], seen: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The M-step of the prior from the first step's smoothed means ``ms0 (B, n)`` and
    covariances ``Ps0 (B or 1, n, n)``: ``x0`` and ``P0`` if in ``learn``, else as given.
    A series never measured (``seen (B,)`` False) says nothing of the prior: its smoothed
    first state is the prior itself, which held each M-step back toward the current values;
    it is left out (its own ``x0`` or ``P0``, given per series, kept)."""
    if not seen.any():  # (em refuses measurements with no value; a guard)
        return x0, P0
    if "x0" in learn:
        if x0.ndim == 2:
            x0 = np.where(seen[:, None], ms0, x0)
        elif P0.ndim == 3:  # one x0 for priors of different covariances: weighted
            x0 = _shared_x0(*_shared_x0_sums(P0[seen], ms0[seen]), x0)
        else:
            x0 = ms0[seen].mean(axis=0)
    if "P0" in learn:
        d = ms0 - (x0 if x0.ndim == 2 else x0[None])
        D = Ps0 + d[:, :, None] * d[:, None, :]  # Ps0 broadcast when shared
        P0 = np.where(seen[:, None, None], D, P0) if P0.ndim == 3 else D[seen].mean(axis=0)
    return x0, P0


def _shared_x0_sums(P0: np.ndarray, ms0: np.ndarray) -> tuple[np.ndarray, np.ndarray,
                                                                np.ndarray]:
    """The sums that give one ``x0`` for the priors ``P0 (B, n, n)`` of the series whose first
    smoothed means are ``ms0 (B, n)``: ``sum W_b``, ``sum W_b ms0_b`` with ``W_b`` the
    (pseudo-)inverse of ``P0_b``, and the sum of the projectors onto the directions a
    singular ``P0_b`` holds exactly (0 where none is singular)."""
    n = P0.shape[-1]
    w, V = np.linalg.eigh(P0)
    low = w <= n * np.finfo(float).eps * np.maximum(w[:, -1:], np.finfo(float).tiny)
    if not low.any():
        W = np.linalg.inv(P0)
        fixed = np.zeros((n, n))
    else:
        W = (V / np.where(low, np.inf, w)[:, None, :]) @ np.swapaxes(V, -1, -2)
        N = V * low[:, None, :]
        fixed = (N @ np.swapaxes(N, -1, -2)).sum(axis=0)
    return W.sum(axis=0), np.einsum("bij,bj->i", W, ms0), fixed


def _shared_x0(W: np.ndarray, Wm: np.ndarray, fixed: np.ndarray, x0: np.ndarray) -> np.ndarray:
    """The M-step of one ``x0`` from :func:`_shared_x0_sums` (added over the series) and the
    current ``x0``: ``(sum W_b)^-1 sum W_b ms0_b``. Along a direction a singular prior holds
    exactly, the first state equals ``x0`` with certainty, and the expected log-likelihood is
    finite only there: ``x0`` stays as it is along those, and the rest is the weighted mean
    over the others."""
    if not fixed.any():
        return np.linalg.solve(W, Wm)
    w, V = np.linalg.eigh(fixed)
    free = V[:, w <= len(w) * np.finfo(float).eps * max(w[-1], 1.0)]
    if free.shape[1] == 0:
        return x0
    z = np.linalg.solve(free.T @ W @ free, free.T @ (Wm - W @ x0))
    return x0 + free @ z


_SHARED_LEARNABLE = frozenset({"Q", "R", "x0", "P0"})


def _shares_covariances(o: _Observed, p: dict[str, np.ndarray], learn: tuple[str, ...]) -> bool:
    """Whether :class:`_SharedEStep` applies: constant ``F``, ``Q``, ``H``, ``R``, one prior
    covariance, steps measured in full or not at all and the same in every series, the last
    step measured (the compiled pass sums every transition), and neither ``F`` nor ``H``
    learned (their M-steps need sums this E-step does not keep)."""
    return (all(p[k].ndim == 2 for k in ("F", "Q", "H", "R", "P0"))
            and not o.has_partial and o.all_move and bool((o.full == o.full[:1]).all())
            and set(learn) <= _SHARED_LEARNABLE)


class _SharedEStep:
    """The E-step of :class:`_EStep` in one compiled pass (:func:`._estep.estep_shared`) for
    series that share their covariances (:func:`_shares_covariances`): the M-step's sums are
    totals over the steps, ``(1, d, d)``, which is all its noises' forms need when the
    matrices are constant."""

    def __init__(self, o: _Observed, p: dict[str, np.ndarray]) -> None:
        self.o, self.p = o, p
        out = np.empty(2)
        self.A, self.V, self.ms0, self.Ps0 = out_arrays = _shared_outputs(o.y, p)
        F, Q, H, R, P0 = (np.ascontiguousarray(p[k], dtype=np.float64)
                          for k in ("F", "Q", "H", "R", "P0"))
        x0 = np.ascontiguousarray(p["x0"], dtype=np.float64).reshape(-1, F.shape[0])
        _estep_shared(o.yt, F, Q, H, R, x0, P0, *out_arrays, o.work(F.shape[0]), out)
        if out[1] == WORK_TOO_SMALL:  # pragma: no cover - work() sizes it
            raise RuntimeError("the shared E-step's work space is too small")
        self.ll = float(out[0])
        self.done = out[1] == -1.0  # else the general E-step says what went wrong

    def process_noise_sums(self, Fn: np.ndarray) -> np.ndarray:
        """As :meth:`_EStep.process_noise_sums`, summed over the transitions as well, under
        this model's ``F`` (never learned here: ``Fn`` is it)."""
        return self.A[None]

    def vv(self, H: np.ndarray) -> np.ndarray:
        return self.V[None]

    def R_count(self) -> np.ndarray:
        return self.o.count

    def Q_count(self) -> np.ndarray:
        return self.o.move_count  # (every series' every transition: all_move)

    def prior(self, learn: tuple[str, ...]) -> tuple[np.ndarray, np.ndarray]:
        return _prior_step(self.ms0, self.Ps0[None], self.p["x0"], self.p["P0"], learn,
                           self.o.seen)


def _shared_outputs(y: np.ndarray, p: dict[str, np.ndarray]) -> tuple[np.ndarray, ...]:
    """The arrays :func:`._estep.estep_shared` writes: ``A``, ``V``, ``ms0``, ``Ps0``."""
    B, _, m = y.shape
    n = p["F"].shape[0]
    return np.empty((n, n)), np.empty((m, m)), np.empty((B, n)), np.empty((n, n))


def _estep(o: _Observed, p: dict[str, np.ndarray], shared: bool) -> _EStep | _SharedEStep:
    """The E-step under the model ``p``: in one compiled pass where the series share their
    covariances (``shared``, from :func:`_shares_covariances`), else :class:`_EStep`, which
    also says where an innovation covariance is not positive definite."""
    if shared:
        e = _SharedEStep(o, p)
        if e.done:
            return e
    return _EStep(o, p)


def _fell_to_zero(p: dict[str, np.ndarray], learn: tuple[str, ...]) -> list[str]:
    """The learned noises of ``p`` (``Q``, ``R``) whose every variance lies below the
    smallest normal float: fallen to zero, as on constant data."""
    return [name for name in ("Q", "R") if name in learn and (
        np.diagonal(p[name], axis1=-2, axis2=-1) < np.finfo(float).tiny).all()]


def _psd(M: np.ndarray) -> np.ndarray:
    """A symmetric matrix (or stack) with its eigenvalues below zero, which rounding leaves
    in the sums of a singular noise, lifted to zero; unchanged when there are none beyond
    the eigen solver's own rounding, ``n eps`` of the largest in magnitude (its estimate of an
    eigenvalue of 0). The negative part alone is taken away, ``M - sum w v v'`` over those
    ``w < 0``, so that the rest of ``M`` keeps its digits: rebuilding ``M`` from all its
    eigenvectors put that rounding into every entry, 1e-16 on a noise that is exactly 0."""
    w, V = np.linalg.eigh(M)
    n = M.shape[-1]
    tol = n * np.finfo(float).eps * np.abs(w).max(axis=-1, keepdims=True)
    neg = np.where(w < -tol, w, 0.0)
    if not neg.any():
        return M
    out = M - (V * neg[..., None, :]) @ np.swapaxes(V, -1, -2)
    return (out + np.swapaxes(out, -1, -2)) / 2


def _smoothed(res: FilterResult, F: np.ndarray,
              Q: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """The smoothed means ``(B, T, n)`` and covariances, the transposed smoother gains ``X_t =
    G_t' = (P^-_{t+1})^{-1} F_{t+1} P_t`` ``(T - 1, n, n)`` and how many series each
    covariance stands for: when the series share one covariance sequence (the same prior and
    the same steps missing) the covariances are those of one series ``(1, T, ...)``, computed
    once, and stand for all ``B``; otherwise ``(B, T, ...)``, each for 1."""
    means = res.means if res.means.ndim == 3 else res.means[None]
    B, T, n = means.shape
    Pf, Pp = res.covs, res.pred_covs
    assert Pf is not None and Pp is not None and res.pred_means is not None  # store_covs
    if Pf.ndim == 3:
        Pf, Pp = Pf[None], Pp[None]
    shared = B == 1 or res.shared_covs
    one = replace(res, means=means[:1], covs=Pf[:1], pred_means=None, pred_covs=None,
                  loglik=res.loglik) if shared else res
    sm = rts_smooth(one, F=F, Q=Q)
    Ps = sm.covs if sm.covs.ndim == 4 else sm.covs[None]
    Pf, Pp = (Pf[:1], Pp[:1]) if shared else (Pf, Pp)
    X = np.linalg.solve(Pp[:, 1:], _transitions(F, T) @ Pf[:, :-1])
    if not shared or B == 1:
        ms = sm.means if sm.means.ndim == 3 else sm.means[None]
        return ms, Ps, X, 1
    # every series' smoothed means with the shared gains, backwards over the steps
    ms = np.empty_like(means)
    _shared_gain_means(np.ascontiguousarray(means), np.ascontiguousarray(res.pred_means),
                       np.ascontiguousarray(X[0]), ms)
    return ms, Ps, X, B


@njit(cache=True)
def _shared_gain_means_jit(means, pred_means, X, ms):  # pragma: no cover - compiled
    """The RTS smoother's means of every series ``(B, T, n)`` given one sequence of
    transposed gains ``X (T - 1, n, n)``: ``ms_t = m_t + (ms_{t+1} - pm_{t+1}) X_t``,
    backwards, into ``ms``."""
    B, T, n = means.shape
    for b in range(B):
        for i in range(n):
            ms[b, T - 1, i] = means[b, T - 1, i]
        for t in range(T - 2, -1, -1):
            for i in range(n):
                s = means[b, t, i]
                for k in range(n):
                    s += (ms[b, t + 1, k] - pred_means[b, t + 1, k]) * X[t, k, i]
                ms[b, t, i] = s


_shared_gain_means = kernel(_shared_gain_means_jit)


def _transition_sums(ms: np.ndarray, Ps: np.ndarray, X: np.ndarray, mult: int, *,
                     moves: _Observed | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per transition, summed over the batch ``(T - 1, n, n)``: ``E[x_t x_t']``, ``E[x_t
    x_{t-1}']``, ``E[x_{t-1} x_{t-1}']``, with the lag-one cross-covariance ``C_t = Ps_t
    G_{t-1}' = Ps_t X_{t-1}`` (see :func:`_smoothed`); given ``moves`` (an
    :class:`_Observed`), over the series that move at each transition only."""
    if moves is not None:
        w = moves.moves[..., None]
        return (_outer_sum(ms[:, 1:] * w, ms[:, 1:]) + _over_moves(Ps[:, 1:], moves),
                _outer_sum(ms[:, 1:] * w, ms[:, :-1]) + _over_moves(Ps[:, 1:] @ X, moves),
                _outer_sum(ms[:, :-1] * w, ms[:, :-1]) + _over_moves(Ps[:, :-1], moves))
    M = _outer_sum(ms, ms)  # sum_b m_t m_t' of every step, for both S11 and S00
    S11 = mult * Ps[:, 1:].sum(axis=0) + M[1:]
    S10 = mult * (Ps[:, 1:] @ X).sum(axis=0) + _outer_sum(ms[:, 1:], ms[:, :-1])
    S00 = mult * Ps[:, :-1].sum(axis=0) + M[:-1]
    return S11, S10, S00


def _over_moves(cov: np.ndarray, o: _Observed) -> np.ndarray:
    """The per-transition covariance terms ``cov (B or 1, T - 1, n, n)`` summed over the
    series that move at each transition (``o.moves``): one sequence for every series (shared
    covariances, or a batch of one) counts ``o.move_count`` times at each."""
    if cov.shape[0] == 1:
        return cov[0] * o.move_count[:, None, None]
    return (cov * o.moves[..., None, None]).sum(axis=0)


def _outer_sum(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``sum_b a[b, t] b[b, t]'`` for each ``t``: ``(B, T, i), (B, T, j) -> (T, i, j)`` (a
    matrix product per step, which numpy hands to BLAS; einsum would loop)."""
    return np.transpose(a, (1, 2, 0)) @ np.transpose(b, (1, 0, 2))


def _transitions(F: np.ndarray, T: int) -> np.ndarray:
    """``F`` of each of the ``T - 1`` transitions: ``(n, n)`` if constant, else
    ``(T - 1, n, n)``."""
    Ft = _steps(F, T)
    return Ft[1:] if Ft.shape[0] > 1 else Ft[0]


def _steps(M: np.ndarray, T: int) -> np.ndarray:
    """A constant or per-step matrix as a stack ``(1, ...)`` or ``(T, ...)``."""
    return M[None] if M.ndim == 2 else M


def _noise(E: np.ndarray, count: np.ndarray, shape: np.ndarray, form: str,
           scaled: _Scaled | None) -> tuple[np.ndarray, float]:
    """The noise covariance from the expected outer products ``E (K, d, d)`` of each step,
    summed over the ``count (K,)`` series that enter it: their mean (``"full"``), its
    diagonal (``"diag"``), or the factor of ``shape`` (constant or per step, ``scaled``) that
    maximises the likelihood (``"scaled"``); and that factor."""
    total = int(np.sum(count))
    if total == 0:
        return shape, 1.0  # nothing measured: the likelihood does not depend on it
    if form == "scaled":
        assert scaled is not None
        factor = scaled.trace(E) / scaled.dof(count)
        return factor * shape, factor
    mean = E.sum(axis=0) / total
    if form == "diag":
        mean = np.diag(np.diag(mean))
    return mean, 1.0


def _H_sums(o: _Observed, ms: np.ndarray, Ps: np.ndarray,
            mult: int) -> tuple[np.ndarray, np.ndarray]:
    """The sums that give ``H`` row by row (:func:`_H_rows`), over the steps that measured its
    component: ``sum y_ti m_t'`` ``(m, n)`` and ``sum P_t + m_t m_t'`` ``(m, n, n)`` (see
    :func:`_check_em` for when that is the M-step)."""
    nums, dens = [], []
    for i in range(o.y.shape[-1]):
        w = o.obs[..., i].astype(np.float64)
        nums.append(np.einsum("bt,bti->i", o.y0[..., i], ms))
        den = np.einsum("bt,bti,btj->ij", w, ms, ms)
        if mult > 1:  # one covariance sequence for every series
            den += np.einsum("t,tij->ij", w.sum(axis=0), Ps[0])
        else:
            den += np.einsum("bt,btij->ij", w, Ps)
        dens.append(den)
    return np.array(nums), np.array(dens)


def _H_rows(num: np.ndarray, den: np.ndarray) -> np.ndarray:
    """``H``, each row ``i`` solving ``den_i h = num_i`` (:func:`_H_sums`)."""
    return np.array([np.linalg.solve(d.T, v) for v, d in zip(num, den)])


def _expected_vv(o: _Observed, ms: np.ndarray, Ps: np.ndarray, mult: int, H: np.ndarray,
                 R_old: np.ndarray) -> np.ndarray:
    """``E[v_t v_t' | y]`` for ``v_t = y_t - H x_t``, summed over the series that measured
    something at step ``t`` ``(T, m, m)``: measured components from the smoothed state, missing
    ones given the measured ones under the current ``R``."""
    B, T, m = o.y.shape
    Ht = _steps(H, T)
    Hb = np.broadcast_to(Ht, (T,) + Ht.shape[1:]) if Ht.shape[0] == 1 else Ht
    # H x_t of every series and step: one matrix product when H is constant
    Hx = ms @ Ht[0].T if Ht.shape[0] == 1 else np.einsum("tij,btj->bti", Ht, ms)
    e = o.y0 - Hx
    HPH = Hb @ Ps @ np.swapaxes(Hb, -1, -2)  # (1 or B, T, m, m)
    fw = o.full.astype(np.float64)
    V = _outer_sum(fw[..., None] * e, e)
    V += (np.einsum("t,tij->tij", fw.sum(axis=0), HPH[0]) if mult > 1
          else np.einsum("bt,btij->tij", fw, HPH))
    if not o.has_partial:
        return V
    Rt = _steps(R_old, T)
    Rb = np.broadcast_to(Rt, (T, m, m)) if Rt.shape[0] == 1 else Rt
    idx = np.argwhere(o.partial)
    patterns, which = np.unique(o.obs[o.partial], axis=0, return_inverse=True)
    for k, seen in enumerate(patterns):
        b, t = idx[which.ravel() == k].T
        Rk = Rb[t]
        oi, mi = np.flatnonzero(seen), np.flatnonzero(~seen)
        ee = e[b, t][:, oi][:, :, None] * e[b, t][:, oi][:, None, :]
        Eoo = ee + HPH[0 if mult > 1 else b, t][:, oi[:, None], oi]
        Roo = Rk[:, oi[:, None], oi]
        Rmo = Rk[:, mi[:, None], oi]
        try:
            K = np.swapaxes(np.linalg.solve(Roo, np.swapaxes(Rmo, -1, -2)), -1, -2)  # Rmo Roo^-1
        except np.linalg.LinAlgError:
            # a noiseless component measured (R = diag(0, 1), the filter takes it): the
            # conditional of a degenerate Gaussian, by the pseudo-inverse
            K = Rmo @ np.linalg.pinv(Roo, hermitian=True)
        Vk = np.empty((len(b), m, m))
        Vk[:, oi[:, None], oi] = Eoo
        KE = K @ Eoo
        Vk[:, mi[:, None], oi] = KE
        Vk[:, oi[:, None], mi] = np.swapaxes(KE, -1, -2)
        Vk[:, mi[:, None], mi] = (KE @ np.swapaxes(K, -1, -2) + Rk[:, mi[:, None], mi]
                                  - K @ np.swapaxes(Rmo, -1, -2))
        np.add.at(V, t, Vk)
    return V
