r"""Multiple-model filtering: the interacting multiple model (IMM) filter.

The seeds' multiple-model filter (seed 000, "Multiple model filters", after Welch and Bishop):
"test several models of assumed dynamics, use the best" — run one filter per model, weigh each
by how well it predicts the measurements, and report the probability-weighted estimate, which
has "no lag" when the target moves and is "smooth when still". With a Markov switching matrix
``Π`` (``Π[i, j] = P(model j at t | model i at t-1)``) the filters also exchange their estimates
before each prediction, which is the IMM of Blom and Bar-Shalom (1988). With ``Π = I`` there is
no exchange and this is exactly the seed's filter.

One IMM cycle for mode probabilities :math:`\mu_i`:

.. math::
    \bar c_j = \sum_i \Pi_{ij} \mu_i, \quad \mu_{i|j} = \Pi_{ij} \mu_i / \bar c_j, \quad
    x^{0}_j = \sum_i \mu_{i|j} x_i, \quad
    P^{0}_j = \sum_i \mu_{i|j} \left(P_i + (x_i - x^0_j)(x_i - x^0_j)^T\right),

then each filter predicts from :math:`(x^0_j, P^0_j)` and corrects, giving the log-likelihood
:math:`\ell_j` of the measurement, and :math:`\log \mu_j = \log \bar c_j + \ell_j - \log \sum_k
\bar c_k e^{\ell_k}`. Everything is done with log-probabilities, so a measurement that every
model finds very unlikely does not underflow to 0/0 (FilterPy's IMM does, filterpy #70).

Members may have different state sizes when each smaller state is a leading part of the larger
ones (derivative-major layouts give this: ``[x, y]`` in ``[x, y, vx, vy]`` in
``[x, y, vx, vy, ω]``). An estimate moves to a larger space by taking the missing components,
and their covariance, from the receiving model's own estimate; to a smaller one by dropping
them. Members may be any filter with ``predict(g, dt, t)`` and ``update(g, y) -> (g, loglik)``:
:class:`~vistrack.filters.ExtendedKalmanFilter` (exact for linear models),
:class:`~vistrack.filters.UnscentedKalmanFilter`, or one's own.

Where every member is a Kalman filter of linear models (a
:class:`~vistrack.filters.KalmanFilter`, or an
:class:`~vistrack.filters.ExtendedKalmanFilter` of linear models, as
:meth:`IMMFilter.from_system` makes), :meth:`IMMFilter.filter` runs the whole sequence in one
compiled call, each member's steps by the Kalman filter's own one-Gaussian kernels: a few
microseconds a step, against some hundreds for the steps from Python (and FilterPy's
``IMMEstimator``). What that call cannot take (a matrix not finite, an innovation covariance
not positive definite, a measurement every model gives zero likelihood) is filtered again
from Python, which names it.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, cast, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from .._jit import njit
from .._prebuilt import kernel
from .._validate import (
    as_float_array,
    as_markov_chain,
    as_rng,
    check_has_steps,
    check_not_infinite,
    check_prior,
    masked_batch,
)
from ..models.protocols import MotionModel, NonlinearMotionModel
from ..models.switching import SwitchingLinearSystem
from ..types import Gaussian
from ._kernels import check_matrices, one_scratch, predict_one, update_one
from ._nonlinear import own_steps, step_times
from .kalman import _readonly, _update, kf_predict
from .particle import RESAMPLERS, _ess, check_particle_options, resample_now

__all__ = ["GaussianFilter", "IMMFilter", "IMMResult", "SwitchingParticleFilter", "SwitchingResult"]


@runtime_checkable
class GaussianFilter(Protocol):
    """What a filter class gives :class:`IMMFilter`: one step of its own model at a time.

    :class:`~vistrack.filters.KalmanFilter`, :class:`~vistrack.filters.ExtendedKalmanFilter`
    and :class:`~vistrack.filters.UnscentedKalmanFilter` are such filters (see the API
    conventions: every filter class has ``predict`` and ``update``).

    Examples
    --------
    >>> import vistrack as vt
    >>> kf = vt.filters.KalmanFilter(vt.models.ConstantVelocity(dim=1), vt.models.Position(dim=1))
    >>> isinstance(kf, GaussianFilter)
    True
    """

    @property
    def motion(self) -> MotionModel | NonlinearMotionModel:
        """The motion model (its ``ndim_state`` is the size of the filter's state)."""
        ...

    def predict(self, g: Gaussian, dt: float = 1.0, t: float = 0.0, /) -> Gaussian:
        """The prediction of ``g`` by ``dt`` to time ``t``."""
        ...

    def update(self, g: Gaussian, y: ArrayLike, /) -> tuple[Gaussian, np.ndarray]:
        """The correction of ``g`` by ``y`` and the innovation's log-density."""
        ...


@dataclass(frozen=True)
class IMMResult:
    """The output of :meth:`IMMFilter.filter`. Arrays are read-only.

    ``(...)`` is ``()`` for one series and ``(B,)`` for a batch.

    Attributes
    ----------
    means : (..., T, n) ndarray
        The probability-weighted (moment-matched) mean, in the state space of the largest
        member.
    covs : (..., T, n, n) ndarray
        Its covariance (the members' covariances plus the spread of their means).
    mode_probs : (..., T, M) ndarray
        Posterior model probabilities after each correction.
    member_means : list of (..., T, n_i) ndarray
        Each member's corrected mean.
    loglik : (...) ndarray
        ``log p(y_0, ..., y_{T-1})`` under the switching model.

    Examples
    --------
    >>> import vistrack as vt
    >>> from vistrack.models import SwitchingLinearSystem
    >>> slds = SwitchingLinearSystem(
    ...     [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=4.0)],
    ...     vt.Position(dim=1, r=0.5), [[0.95, 0.05], [0.2, 0.8]])
    >>> zs, xs, ys = slds.sample(100, x0=[0.0, 1.0], rng=0)
    >>> res = IMMFilter.from_system(slds).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    >>> res.means.shape, res.covs.shape, res.mode_probs.shape, len(res.member_means)
    ((100, 2), (100, 2, 2), (100, 2), 2)
    """

    means: np.ndarray
    covs: np.ndarray
    mode_probs: np.ndarray
    member_means: list
    loglik: np.ndarray


def _convert(g: Gaussian, ref: Gaussian) -> tuple[np.ndarray, np.ndarray]:
    """``g`` in the state space of ``ref``: truncated, or completed from ``ref``."""
    ni, nj = g.mean.shape[-1], ref.mean.shape[-1]
    if ni >= nj:
        return g.mean[..., :nj], g.cov[..., :nj, :nj]
    x = np.concatenate([g.mean, ref.mean[..., ni:]], axis=-1)
    P = np.zeros(ref.cov.shape)
    P[..., :ni, :ni] = g.cov
    P[..., ni:, ni:] = ref.cov[..., ni:, ni:]
    return x, P


def _mix(gs: Sequence[Gaussian], w: np.ndarray, ref: Gaussian) -> Gaussian:
    """Moment-matched mixture ``Σ_i w_i g_i`` (weights ``w (..., M)``) in ``ref``'s space."""
    xs, Ps = zip(*(_convert(g, ref) for g in gs))
    X, P = np.stack(xs, -2), np.stack(Ps, -3)  # (..., M, n), (..., M, n, n)
    mean = np.einsum("...i,...in->...n", w, X)
    d = X - mean[..., None, :]
    cov = np.einsum("...i,...inm->...nm", w, P + d[..., :, None] * d[..., None, :])
    return Gaussian(mean, 0.5 * (cov + np.swapaxes(cov, -1, -2)))


def _logsumexp(a: np.ndarray, axis: int) -> np.ndarray:
    m = np.max(a, axis=axis, keepdims=True)
    m = np.where(np.isfinite(m), m, 0.0)
    with np.errstate(divide="ignore"):  # all -inf: log 0 = -inf, reported by the caller
        return np.squeeze(m, axis) + np.log(np.exp(a - m).sum(axis))




class IMMFilter:
    r"""Interacting multiple models over a sequence.

    Parameters
    ----------
    filters : sequence of filters
        Each with ``predict(g, dt, t) -> Gaussian``, ``update(g, y) -> (Gaussian, loglik)``
        and ``motion.ndim_state`` (its state size):
        :class:`~vistrack.filters.ExtendedKalmanFilter`,
        :class:`~vistrack.filters.UnscentedKalmanFilter`.
    transition : (M, M) array
        ``transition[i, j]``: probability of switching from model ``i`` to model ``j`` in one
        step; rows sum to one (to 1e-9, or to the rounding of the array's own floating type
        where that is coarser: a float32 matrix's rows are then scaled to sum to one). The
        identity gives the seed's multiple-model filter.
    mode_probs : (M,) array, optional
        Prior model probabilities (default uniform); as ``transition``'s rows.

    Attributes
    ----------
    filters : list
        The members.
    sizes : list of int
        Their state sizes.
    ref : int
        Index of the member with the largest state, whose space the estimates are in.
    log_transition, log_mu0 : ndarray
        Logarithms of ``transition`` and ``mode_probs``.

    Raises
    ------
    TypeError
        If a member lacks ``predict``, ``update`` or a motion model (``motion``), or is an
        :class:`~vistrack.filters.EnsembleKalmanFilter` (its steps take ensembles).
    ValueError
        If there are no members, ``transition`` is not a finite non-negative ``(M, M)``
        matrix with rows summing to one, or ``mode_probs`` is not ``M`` finite non-negative
        numbers summing to one (a NaN or infinite entry is named).

    Notes
    -----
    One cycle mixes the members' estimates (see the module), predicts and corrects each, and
    updates the mode probabilities with the members' log-likelihoods :math:`\ell_j`:

    .. math::

        \log \mu_j = \log \bar c_j + \ell_j - \log \sum_k \bar c_k e^{\ell_k}, \qquad
        \bar x = \sum_j \mu_j x_j, \quad
        P = \sum_j \mu_j \big(P_j + (x_j - \bar x)(x_j - \bar x)'\big).

    References
    ----------
    .. [1] H. A. P. Blom and Y. Bar-Shalom, "The interacting multiple model algorithm for
       systems with Markovian switching coefficients", *IEEE Transactions on Automatic
       Control* 33(8), 1988.

    Examples
    --------
    >>> import vistrack as vt
    >>> still = vt.filters.ExtendedKalmanFilter(vt.ConstantPosition(dim=1, q=0.01),
    ...                                         vt.Position(dim=1, r=0.1))
    >>> moving = vt.filters.ExtendedKalmanFilter(vt.ConstantVelocity(dim=1, q=0.01),
    ...                                          vt.Position(dim=1, r=0.1))
    >>> imm = IMMFilter([still, moving], [[0.95, 0.05], [0.05, 0.95]])
    >>> ys = np.r_[np.zeros(10), np.arange(1.0, 11.0)][:, None]
    >>> res = imm.filter(ys, x0=[0.0, 0.0], P0=np.eye(2))
    >>> res.mode_probs[[9, -1]].round(2)  # still, then moving
    array([[0.83, 0.17],
           [0.  , 1.  ]])
    """

    @classmethod
    def from_system(cls, system: SwitchingLinearSystem) -> IMMFilter:
        """The IMM of a :class:`~vistrack.models.SwitchingLinearSystem`.

        One exact Kalman member (an :class:`~vistrack.filters.ExtendedKalmanFilter` of a
        linear model) per motion, with the system's switching matrix and first-mode
        distribution.

        Parameters
        ----------
        system : SwitchingLinearSystem
            The models, the switching matrix and the first mode's distribution.

        Returns
        -------
        IMMFilter
            One member per motion model.

        Examples
        --------
        >>> import vistrack as vt
        >>> from vistrack.models import SwitchingLinearSystem
        >>> slds = SwitchingLinearSystem(
        ...     [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=4.0)],
        ...     vt.Position(dim=1, r=0.5), [[0.95, 0.05], [0.2, 0.8]])
        >>> zs, xs, ys = slds.sample(100, x0=[0.0, 1.0], rng=0)
        >>> imm = IMMFilter.from_system(slds)
        >>> len(imm.filters), imm.sizes
        (2, [2, 2])
        """
        from .ekf import ExtendedKalmanFilter

        return cls([ExtendedKalmanFilter(m, system.measurement) for m in system.motions],
                   system.transition, mode_probs=system.mode_probs)

    def __init__(self, filters: Sequence[GaussianFilter], transition: ArrayLike, *,
                 mode_probs: ArrayLike | None = None):
        from .enkf import EnsembleKalmanFilter

        self.filters = list(filters)
        M = len(self.filters)
        if M < 1:
            raise ValueError("filters must hold at least one filter")
        for k, f in enumerate(self.filters):
            if not (callable(getattr(f, "predict", None)) and callable(getattr(f, "update", None))
                    and hasattr(getattr(f, "motion", None), "ndim_state")):
                # (one without a motion model failed on the attribute, after every check)
                raise TypeError(f"filters[{k}] must have predict(g, dt, t), update(g, y) and a "
                                f"motion model (.motion.ndim_state); got {type(f).__name__}")
            if isinstance(f, EnsembleKalmanFilter):
                # (taken, and refused in filter() as "ens must be a vistrack.filters.Ensemble",
                # an argument the caller never gave)
                raise TypeError(f"filters[{k}] is an EnsembleKalmanFilter, whose steps take "
                                "and give ensembles; IMMFilter mixes Gaussians: give its modes "
                                "as KalmanFilter, ExtendedKalmanFilter or "
                                "UnscentedKalmanFilter")
        Pi, mu = as_markov_chain(transition, mode_probs, M)
        with np.errstate(divide="ignore"):
            self.log_transition, self.log_mu0 = np.log(Pi), np.log(mu)
        self.sizes = [int(f.motion.ndim_state) for f in self.filters]
        self.ref = int(np.argmax(self.sizes))

    def filter(self, ys: ArrayLike, *, x0: ArrayLike, P0: ArrayLike,
               dt: ArrayLike | None = None, times: ArrayLike | None = None) -> IMMResult:
        """Filter a sequence, or a batch of them.

        Parameters
        ----------
        ys : (T, m) or (B, T, m) array_like
            Measurements; NaN components (or the masked entries of a numpy masked array) are
            missing, and a step whose measurement is all NaN is predicted only (the mode
            probabilities are then only mixed).
        x0 : (n,) or (B, n) array_like
            Prior mean of the first step in the largest member's state space (each member
            takes its leading part).
        P0 : (n, n) or (B, n, n) array_like
            Prior covariance of the first step.
        dt : float or (T,) array_like, optional
            Time step: a scalar, the ``T-1`` intervals between steps (``np.diff(times)``),
            or ``T`` values, ``dt[t]`` the step from ``t-1`` to ``t`` (``dt[0]`` unused);
            default ``np.diff(times)`` where ``times`` is given, else 1.
        times : (T,) array_like, optional
            Time of each step, not decreasing; default the cumulative ``dt`` from 0. Given
            with ``dt``, the two must agree.

        Returns
        -------
        IMMResult
            Combined means ``(..., T, n)`` and covariances ``(..., T, n, n)``, mode
            probabilities ``(..., T, M)``, the members' means and the log-likelihood ``(...)``.

        Raises
        ------
        ValueError
            If ``x0`` or ``P0`` is not in the largest member's space, or every model gives a
            measurement zero likelihood (the message names the series and step).

        Examples
        --------
        >>> import vistrack as vt
        >>> from vistrack.models import SwitchingLinearSystem
        >>> slds = SwitchingLinearSystem(
        ...     [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=4.0)],
        ...     vt.Position(dim=1, r=0.5), [[0.95, 0.05], [0.2, 0.8]])
        >>> zs, xs, ys = slds.sample(100, x0=[0.0, 1.0], rng=0)
        >>> res = IMMFilter.from_system(slds).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
        >>> rmse = lambda est: float(np.sqrt(np.mean((est - xs[:, 0]) ** 2)))
        >>> rmse(res.means[:, 0]) < rmse(ys[:, 0])       # better than the measurements
        True
        """
        ys = as_float_array(masked_batch(ys), "ys", ndim=(2, 3))
        check_has_steps(ys)
        meas = getattr(self.filters[self.ref], "measurement", None)
        # a measurement model's size, or a nonlinear member's measurement functions' (m)
        m = getattr(meas, "ndim_meas", None) or getattr(meas, "m", None) or ys.shape[-1]
        if ys.shape[-1] != m:
            raise ValueError(f"ys must have {m} measurement components (last axis), as "
                             f"{getattr(meas, 'model', meas)!r} measures; got {ys.shape[-1]}")
        check_not_infinite(ys, "ys")
        single = ys.ndim == 2
        if single:
            ys = ys[None]
        B, T, _ = ys.shape
        n = self.sizes[self.ref]
        x0, P0 = check_prior(x0, P0, n, space=" (the largest member's state)", series=B)
        x0 = np.broadcast_to(x0, (B, n))
        P0 = np.broadcast_to(P0, (B, n, n))
        dts, times = step_times(dt, times, T)
        linear = _linear_members(self.filters)
        if linear is not None:
            # Kalman members of linear models: the whole filter in one compiled call; what
            # it cannot take (a matrix not finite, an innovation covariance not positive
            # definite, every model giving a measurement zero likelihood) is filtered again
            # below, which names it as before
            done = self._filter_linear(linear, ys, single, x0, P0, dts)
            if done is not None:
                return done
        gs = [Gaussian(x0[:, :k].copy(), P0[:, :k, :k].copy()) for k in self.sizes]
        M = len(self.filters)
        log_mu = np.broadcast_to(self.log_mu0, (B, M)).copy()
        means, covs = np.empty((B, T, n)), np.empty((B, T, n, n))
        probs = np.empty((B, T, M))
        member_means = [np.empty((B, T, k)) for k in self.sizes]
        loglik = np.zeros(B)
        for t in range(T):
            if t > 0:
                # mixing: a[b, i, j] = log Π_ij + log μ_i; c̄_j = Σ_i exp(a); μ_{i|j}
                a = self.log_transition[None] + log_mu[:, :, None]
                log_c = _logsumexp(a, 1)  # (B, M)
                with np.errstate(invalid="ignore"):
                    w = np.exp(a - log_c[:, None, :])  # (B, i, j)
                # a model with c̄_j = 0 has no mass to mix: it keeps its own estimate (mixed
                # from nothing it was reset to a zero mean and covariance, its member means
                # meaningless while its probability stayed 0)
                w = np.nan_to_num(w)
                empty = ~np.isfinite(log_c)  # (B, M)
                if empty.any():
                    series, model = np.nonzero(empty)
                    w[series, :, model] = 0.0
                    w[series, model, model] = 1.0
                gs = [_mix(gs, w[:, :, j], gs[j]) for j in range(M)]
                gs = [f.predict(g, float(dts[t]), float(times[t]))
                      for f, g in zip(self.filters, gs)]
            else:
                log_c = log_mu
            y = ys[:, t]
            if np.isnan(y).all():
                log_mu = log_c
            else:
                lls = []
                for j, f in enumerate(self.filters):
                    gs[j], ll = f.update(gs[j], y)
                    lls.append(np.broadcast_to(ll, (B,)))
                joint = log_c + np.stack(lls, -1)
                nan = np.isnan(joint)
                if nan.any():  # (one member's NaN read as "every model gives zero")
                    b, j = (int(v) for v in np.argwhere(nan)[0])
                    raise ValueError(f"filters[{j}] gave a log-likelihood of NaN for the "
                                     f"measurement of series {b} at step {t}")
                norm = _logsumexp(joint, 1)
                if not np.all(np.isfinite(norm)):
                    b = int(np.argmin(np.isfinite(norm)))
                    raise ValueError(f"every model gives zero likelihood to the measurement of "
                                     f"series {b} at step {t}")
                loglik += norm
                log_mu = joint - norm[:, None]
            mu = np.exp(log_mu)
            probs[:, t] = mu
            out = _mix(gs, mu, gs[self.ref])
            means[:, t], covs[:, t] = out.mean, out.cov
            for j, g in enumerate(gs):
                member_means[j][:, t] = g.mean
        return _result(means, covs, probs, member_means, loglik, single)

    def _filter_linear(self, linear: list, Y: np.ndarray, single: bool, x0: np.ndarray,
                       P0: np.ndarray, dts: np.ndarray) -> IMMResult | None:
        """:meth:`filter` of Kalman members of linear models (``linear``: each member's
        ``F(dt)``, ``Q(dt)``, ``H`` and ``R``, :func:`_linear_members`) in one compiled
        call, given what :meth:`filter` checked (``Y (B, T, m)``, the priors ``(B, n)`` and
        ``(B, n, n)``, each step's ``dt``); or None where the call met what it cannot take
        (filtered again from Python, which names it)."""
        B, T, m = Y.shape
        n, M = self.sizes[self.ref], len(linear)
        # each member's H and R of the measurement's size and its state's, as its steps take
        # them (else named from Python: broadcast here, they gave estimates without a word)
        if any(np.shape(H) != (m, k) or np.shape(R) != (m, m)
               for (_, _, H, R), k in zip(linear, self.sizes)):
            return None
        steps, qi = np.unique(dts[1:], return_inverse=True)
        U = max(len(steps), 1)
        Fs, Qs = np.zeros((M, U, n, n)), np.zeros((M, U, n, n))
        Hs, Rs = np.zeros((M, 1, m, n)), np.zeros((M, 1, m, m))
        try:
            for j, (F, Q, H, R) in enumerate(linear):
                k = self.sizes[j]
                for u, d in enumerate(steps.tolist()):
                    Fd, Qd = np.asarray(F(d), dtype=float), np.asarray(Q(d), dtype=float)
                    if Fd.shape != (k, k) or Qd.shape != (k, k):
                        return None  # (the steps from Python name the shape)
                    Fs[j, u, :k, :k], Qs[j, u, :k, :k] = Fd, Qd
                Hs[j, 0, :, :k], Rs[j, 0] = H, R
        except Exception:  # (the steps from Python raise it again, at their step)
            return None
        gone = np.isnan(Y).all(axis=(0, 2))  # a step no series measured: mixed only
        means, covs = np.empty((B, T, n)), np.empty((B, T, n, n))
        probs, loglik = np.empty((B, T, M)), np.zeros(B)
        member = np.empty((M, B, T, n))
        bad = _imm_linear(np.array(x0, dtype=float, order="C"),
                          np.array(P0, dtype=float, order="C"),
                          np.array(Y, order="C"), gone, np.asarray(self.sizes, np.int64),
                          np.ascontiguousarray(self.log_transition, dtype=float),
                          np.ascontiguousarray(self.log_mu0, dtype=float), self.ref, Fs, Qs,
                          np.concatenate([[0], qi.ravel()]).astype(np.int64), Hs, Rs, means,
                          covs, probs, member, loglik)
        if bad >= 0:
            return None
        return _result(means, covs, probs, [np.ascontiguousarray(member[j, :, :, :k])
                                            for j, k in enumerate(self.sizes)], loglik, single)


def _linear_members(filters: list) -> list | None:
    """What each member's steps use, where every member is a
    :class:`~vistrack.filters.KalmanFilter` or an
    :class:`~vistrack.filters.ExtendedKalmanFilter` of linear models with its own steps
    (not a subclass's, nor patched on the class or the instance), its measurement residual
    a plain difference and its matrices one for every step: ``(F, Q, H, R)``, ``F(dt)`` and
    ``Q(dt)`` functions and ``H (m, n)``, ``R (m, m)`` as those steps take them (an EKF's
    ``Q`` checked and ``H``, ``R`` kept when it was made, a Kalman filter's asked of its
    models). Else None: the members' steps from Python."""
    from . import ekf, linear

    out = []
    for f in filters:
        kind = type(f)
        if kind is ekf.ExtendedKalmanFilter and own_steps(f, ekf._OWN_STEPS):
            fo, fe = f.motion, f.measurement
            if not (fo.linear and fe.linear and fe.standard and not fe.angle_mask.any()):
                return None
            mo, me = fo.model, fe.model
            parts = (cast(MotionModel, mo).F, fo.Q, fe.H, fe.Rm)
        elif kind is linear.KalmanFilter and own_steps(f, linear._OWN_STEPS):
            mo, me = f.motion, f.measurement
            if hasattr(mo, "jacobian") or hasattr(me, "jacobian") or len(
                    getattr(me, "angles", ())):
                return None
            k = mo.ndim_state
            parts = (mo.F, mo.Q, me.H(k), me.R())
        else:
            return None
        if getattr(mo, "n_steps", None) is not None or getattr(me, "n_steps", None) is not None:
            return None
        out.append(parts)
    return out


def _result(means: np.ndarray, covs: np.ndarray, probs: np.ndarray, member_means: list,
            loglik: np.ndarray, single: bool) -> IMMResult:
    """The :class:`IMMResult` of ``(B, T, ...)`` arrays, one series' without its batch axis,
    read-only."""
    if single:
        means, covs, probs, loglik = means[0], covs[0], probs[0], loglik[0]
        member_means = [m[0] for m in member_means]
    loglik = np.asarray(loglik)  # (read-only as the rest, as the docstring says)
    _readonly(means, covs, probs, loglik, *member_means)
    return IMMResult(means, covs, probs, member_means, loglik)


@njit(cache=True)
def _logsumexp_col(a, j, M):
    """``log Σ_i exp(a[i, j])``, as :func:`_logsumexp` (its largest term taken out; -inf
    where every term is)."""
    top = -np.inf
    for i in range(M):
        top = max(top, a[i, j])
    if not abs(top) < np.inf:
        top = 0.0
    s = 0.0
    for i in range(M):
        s += np.exp(a[i, j] - top)
    return top + np.log(s)


@njit(cache=True)
def _mix_into(X, P, w, sz, into, xm, Pm, xc, Pc):
    """The moment-matched mixture ``Σ_i w[i] g_i`` of the members' ``X (M, n)``,
    ``P (M, n, n)`` (member ``i``'s first ``sz[i]`` entries) in the space of member ``into``,
    a smaller member's missing entries (and their covariance) taken from ``into``'s own
    estimate, as :func:`_mix` does; into ``xm``, ``Pm`` (``xc``, ``Pc``: scratch)."""
    M = X.shape[0]
    k = sz[into]
    for a in range(k):
        xm[a] = 0.0
        for b in range(k):
            Pm[a, b] = 0.0
    for i in range(M):
        ni = sz[i]
        for a in range(k):
            xc[i, a] = X[i, a] if a < ni else X[into, a]
        for a in range(k):
            xm[a] += w[i] * xc[i, a]
    for i in range(M):
        ni = sz[i]
        for a in range(k):
            for b in range(k):
                if a < ni and b < ni:
                    v = P[i, a, b]
                elif a >= ni and b >= ni:
                    v = P[into, a, b]
                else:
                    v = 0.0
                Pc[a, b] = v + (xc[i, a] - xm[a]) * (xc[i, b] - xm[b])
        for a in range(k):
            for b in range(k):
                Pm[a, b] += w[i] * Pc[a, b]
    for a in range(k):
        for b in range(a + 1, k):
            v = 0.5 * (Pm[a, b] + Pm[b, a])
            Pm[a, b] = v
            Pm[b, a] = v


@kernel
@njit(cache=True)
def _imm_linear(x0, P0, ys, gone, sz, logPi, logmu0, ref, Fs, Qs, qi, Hs, Rs, means, covs,
                probs, member, loglik):
    """The IMM of Kalman members over every series, one compiled call: the cycle of
    :meth:`IMMFilter.filter` (mixing, each member's prediction and correction by the
    Kalman filter's one-Gaussian kernels, the mode probabilities in logarithms, the
    moment-matched output). Returns -1, or the first series at which a matrix, a state or a
    likelihood is not what the steps take (filtered again from Python, which names it)."""
    B, T, m = ys.shape
    M, n = Fs.shape[0], Fs.shape[2]
    for j in range(M):
        for u in range(Fs.shape[1]):
            if check_matrices(Fs[j, u:u + 1], Qs[j, u:u + 1], 1e-8):
                return 0
        if check_matrices(Hs[j], Rs[j], 1e-8):
            return 0
    X = np.empty((M, n))
    P = np.empty((M, n, n))
    X0 = np.empty((M, n))
    P0m = np.empty((M, n, n))
    xc = np.empty((M, n))
    Pc = np.empty((n, n))
    FP = np.empty((n, n))
    xp = np.empty(n)
    Pp = np.empty((n, n))
    a = np.empty((M, M))
    w = np.empty(M)
    log_mu = np.empty(M)
    log_c = np.empty(M)
    joint = np.empty(M)
    idx, e, Ut, KT, S, L, AP, W, _ = one_scratch(n, m)
    for b in range(B):
        for j in range(M):
            k = sz[j]
            for r in range(k):
                X[j, r] = x0[b, r]
                for c in range(k):
                    P[j, r, c] = P0[b, r, c]
            log_mu[j] = logmu0[j]
        total = 0.0
        for t in range(T):
            if t > 0:
                for i in range(M):
                    for j in range(M):
                        a[i, j] = logPi[i, j] + log_mu[i]
                for j in range(M):
                    log_c[j] = _logsumexp_col(a, j, M)
                for j in range(M):
                    if abs(log_c[j]) < np.inf:
                        for i in range(M):
                            v = np.exp(a[i, j] - log_c[j])
                            w[i] = v if v == v else 0.0
                    else:  # no mass to mix: the model keeps its own estimate
                        for i in range(M):
                            w[i] = 1.0 if i == j else 0.0
                    _mix_into(X, P, w, sz, j, X0[j], P0m[j], xc, Pc)
                for j in range(M):
                    k = sz[j]
                    predict_one(Fs[j], Qs[j], qi[t], qi[t], X0[j], P0m[j], xp, Pp, FP, k)
                    for r in range(k):
                        X[j, r] = xp[r]
                        for c in range(k):
                            P[j, r, c] = Pp[r, c]
            else:
                for j in range(M):
                    log_c[j] = log_mu[j]
            if gone[t]:
                for j in range(M):
                    log_mu[j] = log_c[j]
            else:
                for j in range(M):
                    k = sz[j]
                    ok, ll = update_one(Hs[j], Rs[j], 0, 0, ys[b, t], X[j], P[j], xp, Pp, idx,
                                        e, Ut, KT, S, L, AP, W, k, m)
                    if not ok:
                        return b
                    for r in range(k):
                        X[j, r] = xp[r]
                        for c in range(k):
                            P[j, r, c] = Pp[r, c]
                    joint[j] = log_c[j] + ll
                    if joint[j] != joint[j]:
                        return b
                top = -np.inf
                for j in range(M):
                    top = max(top, joint[j])
                if not abs(top) < np.inf:
                    return b
                s = 0.0
                for j in range(M):
                    s += np.exp(joint[j] - top)
                norm = top + np.log(s)
                total += norm
                for j in range(M):
                    log_mu[j] = joint[j] - norm
            for j in range(M):
                w[j] = np.exp(log_mu[j])
                probs[b, t, j] = w[j]
            _mix_into(X, P, w, sz, ref, xp, Pp, xc, Pc)
            for r in range(n):
                means[b, t, r] = xp[r]
                if not abs(xp[r]) < np.inf:
                    return b
                for c in range(n):
                    covs[b, t, r, c] = Pp[r, c]
                    if not abs(Pp[r, c]) < np.inf:
                        return b
            for j in range(M):
                for r in range(sz[j]):
                    member[j, b, t, r] = X[j, r]
        loglik[b] = total
    return -1


@dataclass(frozen=True)
class SwitchingResult:
    """The output of :meth:`SwitchingParticleFilter.filter`. Arrays are read-only.

    Attributes
    ----------
    means : (T, n) ndarray
        Posterior mean (of the mixture of the particles' Kalman estimates).
    covs : (T, n, n) ndarray
        Posterior covariance of the mixture.
    mode_probs : (T, k) ndarray
        Posterior probability of each mode.
    ess : (T,) ndarray
        Effective sample size after each correction, before any resampling.
    loglik : float
        Estimate of ``log p(y_0, ..., y_{T-1})``.

    Examples
    --------
    >>> import vistrack as vt
    >>> from vistrack.models import SwitchingLinearSystem
    >>> slds = SwitchingLinearSystem(
    ...     [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=4.0)],
    ...     vt.Position(dim=1, r=0.5), [[0.95, 0.05], [0.2, 0.8]])
    >>> zs, xs, ys = slds.sample(100, x0=[0.0, 1.0], rng=0)
    >>> res = SwitchingParticleFilter(slds, n_particles=300, rng=1).filter(
    ...     ys, x0=[0.0, 1.0], P0=np.eye(2))
    >>> res.means.shape, res.mode_probs.shape, res.ess.shape, res.means.flags.writeable
    ((100, 2), (100, 2), (100,), False)
    """

    means: np.ndarray
    covs: np.ndarray
    mode_probs: np.ndarray
    ess: np.ndarray
    loglik: float


class SwitchingParticleFilter:
    r"""Rao-Blackwellised particle filter for a switching linear dynamic system.

    Each particle carries a mode sequence and, given it, the exact Kalman posterior of the
    state: the mode is sampled from the switching matrix, the Gaussian is predicted with that
    mode's model and corrected, and the particle is weighted by the Kalman predictive
    likelihood :math:`p(y_t \mid z_{0:t}, y_{<t})`. The continuous state is never sampled, so
    far fewer particles are needed than for a plain particle filter (Doucet, de Freitas, Murphy
    and Russell, 2000, "Rao-Blackwellised particle filtering for dynamic Bayesian networks").

    .. math::

        z_t^{(i)} \sim \Pi_{z_{t-1}^{(i)}, \cdot}, \qquad
        w_t^{(i)} \propto w_{t-1}^{(i)}\, N\big(y_t; H \bar x_t^{(i)-}, H P_t^{(i)-} H' + R\big)

    with :math:`(\bar x_t^{(i)-}, P_t^{(i)-})` the Kalman prediction of particle :math:`i`
    under mode :math:`z_t^{(i)}`.

    Parameters
    ----------
    system : vistrack.models.SwitchingLinearSystem
        The models, switching matrix and first-mode distribution (constant ``H``, ``R``).
    n_particles : int
        Number of particles, >= 1.
    resampling : str
        A name in :data:`~vistrack.filters.RESAMPLERS`.
    ess_threshold : float
        In [0, 1]: resample when the effective sample size falls below
        ``ess_threshold * n_particles`` (1 resamples every step, 0 never), as
        :class:`~vistrack.filters.ParticleFilter`.
    rng : numpy.random.Generator, int or None
        Random generator or seed.

    Raises
    ------
    ValueError
        If ``n_particles``, ``resampling`` or ``ess_threshold`` is invalid.
    TypeError
        If ``n_particles`` or ``ess_threshold`` is no number (a string).

    See Also
    --------
    IMMFilter : The deterministic approximation, :meth:`IMMFilter.from_system`.

    References
    ----------
    .. [1] A. Doucet, N. de Freitas, K. Murphy and S. Russell, "Rao-Blackwellised particle
       filtering for dynamic Bayesian networks", UAI 2000.

    Examples
    --------
    Beside the IMM on the same data, which merges its Gaussians into one a mode at every step
    (an approximation; with 3,000 or 20,000 particles the particle filter's log-likelihood
    stays within 0.2 of this one):

    >>> import vistrack as vt
    >>> from vistrack.models import SwitchingLinearSystem
    >>> slds = SwitchingLinearSystem(
    ...     [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=4.0)],
    ...     vt.Position(dim=1, r=0.5), [[0.95, 0.05], [0.2, 0.8]])
    >>> zs, xs, ys = slds.sample(100, x0=[0.0, 1.0], rng=0)
    >>> rbpf = SwitchingParticleFilter(slds, n_particles=300, rng=1)
    >>> res = rbpf.filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    >>> imm = IMMFilter.from_system(slds).filter(ys, x0=[0.0, 1.0], P0=np.eye(2))
    >>> round(res.loglik, 1), round(float(imm.loglik), 1)
    (-181.5, -183.8)
    """

    def __init__(self, system: SwitchingLinearSystem, n_particles: int = 500, *,
                 resampling: str = "systematic", ess_threshold: float = 0.5,
                 rng: np.random.Generator | int | None = None):
        self.n_particles, self.ess_threshold = check_particle_options(
            n_particles, resampling, ess_threshold)
        self.system, self.resample, self.rng = system, RESAMPLERS[resampling], as_rng(rng)

    def filter(self, ys: ArrayLike, *, x0: ArrayLike, P0: ArrayLike,
               dt: float = 1.0) -> SwitchingResult:
        """Filter one sequence.

        Every particle starts at ``N(x0, P0)``, the prior of the first step, with a mode
        drawn from the system's ``mode_probs``; a step whose measurement is all NaN is
        predicted only.

        Parameters
        ----------
        ys : (T, m) array_like
            Measurements; NaN components (or the masked entries of a numpy masked array) are
            missing.
        x0 : (n,) array_like
            Prior mean of the first step.
        P0 : (n, n) array_like
            Prior covariance of the first step.
        dt : float
            Time step of the motion models (one for every step).

        Returns
        -------
        SwitchingResult
            Means ``(T, n)``, covariances ``(T, n, n)``, mode probabilities ``(T, k)``, the
            effective sample sizes ``(T,)`` and the log-likelihood.

        Raises
        ------
        ValueError
            If ``x0`` or ``P0`` has the wrong shape, ``ys`` is not ``(T, m)`` for the
            system's measurement or holds an infinity, ``dt`` is not one number, or every
            particle gives a measurement zero likelihood (naming the step).

        Examples
        --------
        >>> import vistrack as vt
        >>> from vistrack.models import SwitchingLinearSystem
        >>> slds = SwitchingLinearSystem(
        ...     [vt.ConstantVelocity(dim=1, q=0.01), vt.ConstantVelocity(dim=1, q=4.0)],
        ...     vt.Position(dim=1, r=0.5), [[0.95, 0.05], [0.2, 0.8]])
        >>> zs, xs, ys = slds.sample(100, x0=[0.0, 1.0], rng=0)
        >>> res = SwitchingParticleFilter(slds, n_particles=300, rng=1).filter(
        ...     ys, x0=[0.0, 1.0], P0=np.eye(2))
        >>> bool(np.allclose(res.mode_probs.sum(1), 1.0))
        True
        """
        sysm, N, rng = self.system, self.n_particles, self.rng
        ys = as_float_array(ys, "ys", ndim=(2,))
        check_has_steps(ys)
        T, n, k = ys.shape[0], sysm.ndim_state, len(sysm.motions)
        H, R = sysm.measurement.H(n), sysm.measurement.R()
        if ys.shape[1] != len(R):
            raise ValueError(f"ys must have shape (T, {len(R)}): {len(R)} values a step, as "
                             f"the system's measurement model measures; got {ys.shape}")
        check_not_infinite(ys, "ys")
        if np.ndim(dt) != 0:
            raise ValueError(f"dt must be one time step, the same for every step; got shape "
                             f"{np.shape(dt)}")
        Fs = [m.F(dt) for m in sysm.motions]
        Qs = [m.Q(dt) for m in sysm.motions]
        # cumulative rows divided by their ends, which are then exactly 1: a uniform below 1
        # never passes the end, so no mode of probability 0 after the last is drawn (a row's
        # sum may round below 1, and the draw was then taken to mode k - 1)
        cum = np.cumsum(sysm.transition, axis=1)
        cum /= cum[:, -1:]
        first = np.cumsum(sysm.mode_probs)
        first /= first[-1]
        x0, P0 = check_prior(x0, P0, n, batch=False)
        mean = np.broadcast_to(x0, (N, n)).copy()
        cov = np.broadcast_to(P0, (N, n, n)).copy()
        z = np.searchsorted(first, rng.random(N), "right")
        logw = np.full(N, -np.log(N))
        means, covs = np.empty((T, n)), np.empty((T, n, n))
        probs, ess = np.empty((T, k)), np.empty(T)
        total = 0.0
        for t in range(T):
            if t > 0:
                u = rng.random(N)
                z = (u[:, None] >= cum[z]).sum(1)
                for j in range(k):
                    idx = np.flatnonzero(z == j)
                    if len(idx):
                        g = kf_predict(Gaussian(mean[idx], cov[idx]), Fs[j], Qs[j])
                        mean[idx], cov[idx] = g.mean, g.cov
            if not np.isnan(ys[t]).all():
                g, ll = _update(Gaussian(mean, cov), np.broadcast_to(ys[t], (N, len(R))), H, R)
                mean, cov = g.mean.copy(), g.cov.copy()
                a = logw + ll
                norm = float(_logsumexp(a[None], 1)[0])
                if not np.isfinite(norm):  # (the weights would be NaN from here on)
                    raise ValueError(f"every particle gives zero likelihood to the "
                                     f"measurement at step {t}")
                total += norm
                logw = a - norm
            w = np.exp(logw)
            w /= w.sum()
            means[t] = w @ mean
            d = mean - means[t]
            covs[t] = np.einsum("i,ijk->jk", w, cov + d[:, :, None] * d[:, None, :])
            probs[t] = np.bincount(z, weights=w, minlength=k)
            ess[t] = _ess(w)
            if resample_now(ess[t], self.ess_threshold, N):
                idx = self.resample(w, N, rng)
                mean, cov, z = mean[idx], cov[idx], z[idx]
                logw = np.full(N, -np.log(N))
        _readonly(means, covs, probs, ess)
        return SwitchingResult(means, covs, probs, ess, total)
