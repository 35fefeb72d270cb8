r"""The ensemble Kalman filter (seed 004: "represents the distribution of the system state using
a collection (an ensemble) of state vectors ... replace the covariance matrix by the sample
covariance from the ensemble").

Prediction moves every member through the dynamics with sampled process noise,
:math:`x_i^- = f(x_i^+) + w_i`, :math:`w_i \sim N(0, Q)`. The correction is the stochastic
(perturbed-observation) EnKF of Burgers, van Leeuwen and Evensen (1998): with the ensemble's
cross-covariance :math:`C = \operatorname{cov}(x^-, h(x^-))` and
:math:`S = \operatorname{cov}(h(x^-)) + R`,

.. math:: K = C S^{-1}, \qquad x_i^+ = x_i^- + K\, r(y + v_i, h(x_i^-)), \quad v_i \sim N(0, R).

The perturbations make the ensemble's covariance match the Kalman posterior in expectation; as
the ensemble grows, the EnKF tends to the Kalman filter on linear models.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._validate import (
    as_float_array,
    as_rng,
    as_whole,
    check_finite,
    check_has_steps,
    check_not_masked,
    check_one_step,
    check_prior,
    check_psd,
    is_whole,
    masked_batch,
)
from ..models.adapters import (
    MeasurementFunctions,
    MotionFunctions,
    _plain_mean,
    psd_sqrt,
)
from ..models.protocols import (
    MeasurementModel,
    MotionModel,
    NonlinearMeasurementModel,
    NonlinearMotionModel,
)
from ._nonlinear import (
    check_h_size,
    check_model_values,
    check_y,
    run_sequence,
)
from .kalman import FilterResult
from .reference import gain, masked_innovation

__all__ = ["Ensemble", "enkf_predict", "enkf_update", "EnsembleKalmanFilter"]


@dataclass(frozen=True)
class Ensemble:
    """A batch of ensembles: ``N`` state vectors of size ``n`` per batch entry.

    Parameters
    ----------
    members : (..., N, n) array_like
        The members, ``N >= 2``; the leading dimensions index the batch. Stored as float64.

    Raises
    ------
    ValueError
        If ``members`` has fewer than 2 dimensions or fewer than 2 members, or is a numpy
        masked array with an entry masked.
    TypeError
        If ``members`` are not real numbers (complex values, text).

    Examples
    --------
    >>> ens = Ensemble([[0.0, 1.0], [2.0, 3.0]])
    >>> ens.moments()
    (array([1., 2.]), array([[2., 2.],
           [2., 2.]]))
    """

    members: np.ndarray

    def __post_init__(self) -> None:
        # (np.asarray read the values under a mask as members and took complex ones' real
        # parts with a warning alone)
        check_not_masked(self.members, "members", "an ensemble has no missing member")
        m = as_float_array(self.members, "members")
        if m.ndim < 2 or m.shape[-2] < 2:
            raise ValueError(f"members must have shape (..., N, n) with N >= 2; got {m.shape}")
        object.__setattr__(self, "members", m)

    @classmethod
    def sample(cls, mean: ArrayLike, cov: ArrayLike, n_members: int,
               rng: np.random.Generator | int | None = None) -> Ensemble:
        """An ensemble of ``n_members`` draws from ``N(mean, cov)``, or a batch of them.

        Parameters
        ----------
        mean : (..., n) array_like
            Means; the leading dimensions index the batch.
        cov : (n, n) or (..., n, n) array_like
            Covariances, positive semi-definite (a singular one draws on its subspace).
        n_members : int
            Members per ensemble.
        rng : numpy.random.Generator, int or None
            Random generator or seed.

        Returns
        -------
        Ensemble
            Members ``(..., n_members, n)``.

        Raises
        ------
        ValueError
            If ``mean`` or ``cov`` has a NaN or an infinite entry, their sizes disagree,
            ``cov`` is not symmetric positive semi-definite, ``n_members`` is not a whole
            number >= 2, or either is a numpy masked array with an entry masked.
        TypeError
            If ``mean`` or ``cov`` are not real numbers (complex values, text).

        Examples
        --------
        >>> Ensemble.sample(np.zeros((3, 2)), np.eye(2), 100, rng=0).members.shape
        (3, 100, 2)
        """
        rng = as_rng(rng)
        # (np.asarray drew about the values under a mask, and took complex values' real
        # parts with a warning alone)
        check_not_masked(mean, "mean", "a distribution has no missing value")
        check_not_masked(cov, "cov", "a distribution has no missing value")
        mean = as_float_array(mean, "mean")
        cov = as_float_array(cov, "cov")
        # (a NaN covariance passed Cholesky's factorisation and drew NaN members)
        check_finite(mean, "mean")
        check_finite(cov, "cov")
        n = mean.shape[-1] if mean.ndim else 0
        if mean.ndim < 1 or cov.ndim < 2 or cov.shape[-2:] != (n, n):
            raise ValueError(f"cov must have shape (n, n) or (..., n, n) with n = {n}, the size "
                             f"of mean {mean.shape}; got {cov.shape}")
        try:  # (numpy's broadcast error at the draw named neither)
            np.broadcast_shapes(mean.shape[:-1], cov.shape[:-2])
        except ValueError:
            raise ValueError(f"mean and cov must have batch shapes that broadcast; got mean "
                             f"{mean.shape} and cov {cov.shape}") from None
        # (Cholesky reads the lower triangle alone: another matrix's draws)
        check_psd(cov, "cov")
        n_members = as_whole(n_members, "n_members", 2)
        try:
            L = np.linalg.cholesky(cov)
        except np.linalg.LinAlgError:
            # singular (a state known exactly along some direction; semi-definite, as
            # check_psd found above): the principal root, unique, so the draws are the same on
            # every machine, or where the scales lie far apart the correlation matrix's (the
            # principal root alone gave a constant-acceleration prior at dt 1e-4 35/36 of its
            # position's variance)
            L = psd_sqrt(0.5 * (cov + np.swapaxes(cov, -1, -2)))
        # one draw per ensemble of the batch, mean's or cov's (a batch of cov beside one
        # mean drew one set and scaled it for every ensemble: their members correlated 1)
        batch = np.broadcast_shapes(mean.shape[:-1], cov.shape[:-2])
        shape = batch + (int(n_members), mean.shape[-1])
        try:
            z = rng.standard_normal(shape)
        except (ValueError, MemoryError):  # (numpy's words named neither: "Maximum allowed
            # dimension exceeded", "Unable to allocate 14.6 TiB")
            raise ValueError(f"n_members {n_members} makes an ensemble of {math.prod(shape):.3g} "
                             "values, more than memory holds") from None
        return cls(mean[..., None, :] + z @ np.swapaxes(L, -1, -2))

    def moments(self) -> tuple[np.ndarray, np.ndarray]:
        r"""Sample mean and covariance of each ensemble.

        .. math:: \bar x = \frac1N \sum_i x_i, \qquad
                  P = \frac{1}{N - 1} \sum_i (x_i - \bar x)(x_i - \bar x)'

        Returns
        -------
        mean : (..., n) ndarray
            Sample means.
        cov : (..., n, n) ndarray
            Sample covariances (divisor ``N - 1``).

        Examples
        --------
        >>> mean, cov = Ensemble.sample([0.0, 1.0], np.eye(2), 5000, rng=0).moments()
        >>> mean.round(1) + 0.0, cov.round(1) + 0.0
        (array([0., 1.]), array([[1., 0.],
               [0., 1.]]))
        """
        mean = self.members.mean(-2)
        d = self.members - mean[..., None, :]
        return mean, np.swapaxes(d, -1, -2) @ d / (self.members.shape[-2] - 1)


def _noise(rng, shape, A):
    """Draws of ``N(0, A A')``; none when ``A`` is zero (no noise)."""
    if not np.any(A):
        return np.zeros(shape)
    return rng.standard_normal(shape) @ A.T


def check_ensemble(ens: object) -> Ensemble:
    """``ens``, or a TypeError where it is no :class:`Ensemble` (a ``Gaussian`` given to an
    ensemble step failed in Python's words: no attribute ``members``)."""
    if not isinstance(ens, Ensemble):
        raise TypeError(f"ens must be a vistrack.filters.Ensemble (Ensemble.sample draws one "
                        f"from a mean and covariance); got {type(ens).__name__}")
    return ens


def enkf_predict(ens: Ensemble, motion: MotionModel | NonlinearMotionModel, dt: float = 1.0,
                 t: float = 0.0, *,
                 rng: np.random.Generator | int | None = None) -> Ensemble:
    r"""Move every member through the dynamics and add sampled process noise.

    .. math:: x_i^- = f(x_i, \Delta t, t) + w_i, \qquad w_i \sim N(0, Q(\Delta t))

    (:math:`f(x) = F x` for a linear model).

    Parameters
    ----------
    ens : Ensemble
        Members ``(..., N, n)``.
    motion : motion model
        Linear (``F``, ``Q``) or nonlinear (``f``, ``jacobian``, ``Q``).
    dt : float
        Time step.
    t : float
        Time of the predicted state (for time-varying models).
    rng : numpy.random.Generator, int or None
        Random generator or seed.

    Returns
    -------
    Ensemble
        The predicted members ``(..., N, n)``.

    Raises
    ------
    TypeError
        If ``ens`` is no :class:`Ensemble`.
    ValueError
        If the members are not of the motion model's size, or ``dt`` is not one step.

    References
    ----------
    .. [1] G. Evensen, "Sequential data assimilation with a nonlinear quasi-geostrophic model
       using Monte Carlo methods to forecast error statistics", *Journal of Geophysical
       Research* 99(C5), 1994.
    .. [2] G. Burgers, P. J. van Leeuwen and G. Evensen, "Analysis scheme in the ensemble
       Kalman filter", *Monthly Weather Review* 126(6), 1998.

    Examples
    --------
    >>> from vistrack.models import ConstantVelocity
    >>> ens = Ensemble.sample([0.0, 1.0], np.eye(2), 5000, rng=0)
    >>> enkf_predict(ens, ConstantVelocity(dim=1, q=0.1), dt=1.0, rng=1).moments()[0].round(1)
    array([1., 1.])
    """
    check_one_step(dt, "every ensemble of ens")
    check_ensemble(ens)
    mo = MotionFunctions.of(motion)
    if ens.members.shape[-1] != mo.n:  # (numpy's matmul error, naming neither)
        raise ValueError(f"ens must have members of {mo.n} values, the motion model's; got "
                         f"{ens.members.shape[-1]}")
    x = np.asarray(mo.f(ens.members, dt, t), dtype=float)
    return Ensemble(x + _noise(as_rng(rng), x.shape, mo.Q_sqrt(dt)))


def enkf_update(ens: Ensemble, y: ArrayLike,
                measurement: MeasurementModel | NonlinearMeasurementModel, *,
                rng: np.random.Generator | int | None = None,
                residual: Callable | None = None) -> Ensemble:
    r"""Perturbed-observation update of a batch of ensembles with a measurement each.

    With the ensemble's cross-covariance :math:`C = \operatorname{cov}(x, h(x))` and
    :math:`S = \operatorname{cov}(h(x)) + R`, over the observed components,

    .. math:: K = C S^{-1}, \qquad x_i^+ = x_i + K\, r(y + v_i, h(x_i)),
              \quad v_i \sim N(0, R),

    with :math:`r` the measurement residual (differences, angles wrapped).

    Parameters
    ----------
    ens : Ensemble
        Members ``(..., N, n)``.
    y : (..., m) array_like
        One measurement per ensemble; NaN components are missing.
    measurement : measurement model
        Linear (``H``, ``R``) or nonlinear (``h``, ``jacobian``, ``R``).
    rng : numpy.random.Generator, int or None
        Random generator or seed.
    residual : callable, optional
        ``residual(a, b)``, overriding the model's.

    Returns
    -------
    Ensemble
        The corrected members ``(..., N, n)``. :meth:`EnsembleKalmanFilter.update` also gives
        the Gaussian log-density of the innovation,
        :math:`\log N(r(y, \overline{h(x)}); 0, S)`, under the ensemble's moments.

    Raises
    ------
    TypeError
        If ``ens`` is no :class:`Ensemble`.
    ValueError
        If a member of ``ens`` is not finite (named), or ``y`` does not fit the measurement.

    References
    ----------
    .. [1] G. Evensen, "Sequential data assimilation with a nonlinear quasi-geostrophic model
       using Monte Carlo methods to forecast error statistics", *Journal of Geophysical
       Research* 99(C5), 1994.
    .. [2] G. Burgers, P. J. van Leeuwen and G. Evensen, "Analysis scheme in the ensemble
       Kalman filter", *Monthly Weather Review* 126(6), 1998.

    Examples
    --------
    Close to the Kalman update (mean ``[1.40, 1.21]``, variance 0.40) with many members:

    >>> from vistrack.models import ConstantVelocity, Position
    >>> ens = enkf_predict(Ensemble.sample([0.0, 1.0], np.eye(2), 5000, rng=0),
    ...                    ConstantVelocity(dim=1, q=0.1), rng=1)
    >>> post = enkf_update(ens, [1.5], Position(dim=1, r=0.5), rng=2)
    >>> mean, cov = post.moments()
    >>> mean.round(2), round(float(cov[0, 0]), 1)
    (array([1.4 , 1.19]), 0.4)
    """
    return _enkf_update(ens, y, measurement, rng, residual)[0]


def _enkf_update(ens: Ensemble, y: ArrayLike,
                 measurement: MeasurementModel | NonlinearMeasurementModel,
                 rng: np.random.Generator | int | None,
                 residual: Callable | None) -> tuple[Ensemble, np.ndarray]:
    X = check_ensemble(ens).members
    # (one member that is not finite made every member NaN, and the log-likelihood, without
    # a word; the filter names a prediction that is not finite before it gets here)
    check_finite(X, "ens.members")
    N, n = X.shape[-2:]
    me = MeasurementFunctions.of(measurement, n, residual)
    y = check_y(y, X.shape[:-2], me.m, "ens")
    obs = ~np.isnan(y)
    # (..., N, m); a missing component's value is not used: 0, not NaN, where h has none
    # there (NaN times the mask's 0 below is NaN, and made every member NaN)
    # (an h of one value too few was broadcast over the measurement, without a word)
    Z = np.where(obs[..., None, :], check_h_size(np.asarray(me.h(X), dtype=float), me.m, X),
                 0.0)
    check_model_values(Z, X, "member")  # (every member came out NaN, without a word)
    # the members' mean measurement: circular for angles (bearings either side of π average
    # to π, not 0), as the model's mean gives it
    zbar = Z.mean(-2) if me.mean is _plain_mean else me.mean(Z, np.full(N, 1.0 / N))
    dZ = me.residual(Z, zbar[..., None, :]) * obs[..., None, :]
    dX = X - X.mean(-2)[..., None, :]
    C = np.swapaxes(dX, -1, -2) @ dZ / (N - 1)
    e, S, L, ll = masked_innovation(me.residual(np.where(obs, y, 0.0), zbar),
                                    np.swapaxes(dZ, -1, -2) @ dZ / (N - 1) + me.Rm, obs)
    K = gain(C, L)
    v = _noise(as_rng(rng), Z.shape, psd_sqrt(me.Rm))
    innov = me.residual(np.where(obs, y, 0.0)[..., None, :] + v, Z) * obs[..., None, :]
    out = Ensemble(X + innov @ np.swapaxes(K, -1, -2))
    return out, ll


class EnsembleKalmanFilter:
    """The stochastic EnKF over a sequence: :func:`enkf_predict` and :func:`enkf_update` per
    step.

    Parameters
    ----------
    motion, measurement
        Nonlinear or linear models.
    n_members : int
        Ensemble size, at least 2.
    rng : numpy.random.Generator, int or None
        Random generator or seed, used for the first ensemble and every step.
    residual : callable, optional
        Measurement residual, overriding the model's.

    Raises
    ------
    ValueError
        If ``n_members`` is not an integer >= 2.
    TypeError
        If a model lacks what a motion or measurement model provides.

    Notes
    -----
    The result's ``means`` and ``covs`` are the ensemble's sample moments.

    References
    ----------
    .. [1] G. Evensen, "Sequential data assimilation with a nonlinear quasi-geostrophic model
       using Monte Carlo methods to forecast error statistics", *Journal of Geophysical
       Research* 99(C5), 1994.
    .. [2] G. Burgers, P. J. van Leeuwen and G. Evensen, "Analysis scheme in the ensemble
       Kalman filter", *Monthly Weather Review* 126(6), 1998.

    Examples
    --------
    >>> from vistrack.models import ConstantVelocity, Position
    >>> enkf = EnsembleKalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1, r=1.0),
    ...                             n_members=500, rng=0)
    >>> res = enkf.filter(np.arange(10.0)[:, None], x0=[0.0, 1.0], P0=np.eye(2))
    >>> res.means.shape, res.covs.shape, res.means[-1].round(1)
    ((10, 2), (10, 2, 2), array([9., 1.]))
    """

    def __init__(self, motion: MotionModel | NonlinearMotionModel,
                 measurement: MeasurementModel | NonlinearMeasurementModel, n_members: int = 100, *,
                 rng: np.random.Generator | int | None = None, residual: Callable | None = None):
        if not is_whole(n_members, 2):
            raise ValueError(f"n_members must be an integer >= 2; got {n_members!r}")
        self.motion = MotionFunctions(motion)
        self.measurement = MeasurementFunctions(measurement, self.motion.n, residual)
        self.n_members = int(n_members)
        self.rng = as_rng(rng)

    def filter(self, ys: ArrayLike, *, x0: ArrayLike, P0: ArrayLike,
               dt: ArrayLike | None = None, times: ArrayLike | None = None) -> FilterResult:
        """Filter a sequence, or a batch of them.

        The first ensemble is drawn from ``N(x0, P0)``, the prior of the first step, which
        the first measurement corrects; a step whose measurement is all NaN is predicted only.

        Parameters
        ----------
        ys : (T, m) or (B, T, m) array_like
            Measurements; NaN components (or masked entries of a numpy masked array) are
            missing.
        x0 : (n,) or (B, n) array_like
            Prior mean of the first step.
        P0 : (n, n) or (B, n, n) array_like
            Prior covariance of the first step, positive semi-definite (a singular one draws
            the ensemble on its subspace).
        dt : float or (T,) array_like, optional
            Time step: a scalar, the ``T-1`` intervals between steps (``np.diff(times)``),
            or ``T`` values, ``dt[t]`` the step from ``t-1`` to ``t`` (``dt[0]`` unused);
            default ``np.diff(times)`` where ``times`` is given, else 1.
        times : (T,) array_like, optional
            Time of each step, not decreasing; default the cumulative ``dt`` from 0. Given
            with ``dt``, the two must agree.

        Returns
        -------
        FilterResult
            The ensembles' sample means ``(..., T, n)`` and covariances ``(..., T, n, n)``,
            their predictions, and the log-likelihood ``(...)``.

        Raises
        ------
        ValueError
            If the shapes disagree with the models, ``P0`` is not positive semi-definite, or a
            model gives NaN or infinity (the error names the first step, and series, whose
            prediction or correction it made so).

        Examples
        --------
        Two series at once:

        >>> from vistrack.models import ConstantVelocity, Position
        >>> enkf = EnsembleKalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1),
        ...                             n_members=200, rng=0)
        >>> ys = np.stack([np.arange(5.0), -np.arange(5.0)])[..., None]
        >>> res = enkf.filter(ys, x0=[0.0, 0.0], P0=np.eye(2))
        >>> res.means.shape, res.loglik.shape
        ((2, 5, 2), (2,))
        """
        n = self.motion.n
        ys_arr = as_float_array(masked_batch(ys), "ys", ndim=(2, 3))
        check_has_steps(ys_arr)
        B = 1 if ys_arr.ndim == 2 else ys_arr.shape[0]
        x0, P0 = check_prior(x0, P0, n, series=B)
        x0 = np.broadcast_to(x0, (B, n))
        P0 = np.broadcast_to(P0, (B, n, n))
        return run_sequence(
            ys_arr, None, None, n, self.measurement.m, dt, times, self.predict, self.update,
            start=lambda: Ensemble.sample(x0, P0, self.n_members, self.rng),
        )

    def predict(self, ens: Ensemble, dt: float = 1.0, t: float = 0.0) -> Ensemble:
        """One prediction (:func:`enkf_predict` with this filter's motion model and generator).

        Parameters
        ----------
        ens : Ensemble
            Members ``(..., N, n)``.
        dt : float
            Time step.
        t : float
            Time of the predicted state.

        Returns
        -------
        Ensemble
            The predicted members.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> enkf = EnsembleKalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1), rng=0)
        >>> ens = Ensemble.sample([0.0, 1.0], np.eye(2), 2000, rng=1)
        >>> enkf.predict(ens).moments()[0].round(1)
        array([1., 1.])
        """
        return enkf_predict(ens, self.motion, dt, t, rng=self.rng)

    def update(self, ens: Ensemble, y: ArrayLike) -> tuple[Ensemble, np.ndarray]:
        r"""One correction (:func:`enkf_update`) and the innovation's log-density.

        Parameters
        ----------
        ens : Ensemble
            Members ``(..., N, n)``.
        y : (..., m) array_like
            One measurement per ensemble; NaN components are missing.

        Returns
        -------
        posterior : Ensemble
            The corrected members.
        loglik : (...) ndarray
            :math:`\log N(r(y, \overline{h(x)}); 0, S)` under the ensemble's moments, over
            the observed components.

        Examples
        --------
        >>> from vistrack.models import ConstantVelocity, Position
        >>> enkf = EnsembleKalmanFilter(ConstantVelocity(dim=1, q=0.1), Position(dim=1), rng=0)
        >>> post, ll = enkf.update(Ensemble.sample([0.0, 1.0], np.eye(2), 2000, rng=1), [1.0])
        >>> post.moments()[0].round(1), ll.shape
        (array([0.5, 1. ]), ())
        """
        n = self.motion.n
        # (numpy's matmul error, naming neither; as predict)
        if check_ensemble(ens).members.shape[-1] != n:
            raise ValueError(f"ens must have members of {n} values, the motion model's; got "
                             f"{ens.members.shape[-1]}")
        return _enkf_update(ens, y, self.measurement, self.rng, None)
