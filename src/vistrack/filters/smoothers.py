r"""Fixed-interval smoothers: Rauch-Tung-Striebel and the seeds' two-filter (forward-backward) form.

Both give ``p(x_t | y_0, ..., y_{T-1})`` for a linear-Gaussian model and agree to rounding; the
tests check one against the other.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from .._jit import njit
from .._prebuilt import kernel
from .._validate import (
    as_measurement_series,
    check_finite,
    check_has_steps,
    check_linear_gaussian,
    check_matrix_stack,
    check_psd,
    correlation,
)
from ._kernels import chol_solve, copy_mat, copy_vec, predict_one
from .kalman import FilterResult, _is_dask, _readonly, kalman_filter

__all__ = ["SmoothResult", "rts_smooth", "two_filter_smooth"]


@dataclass(frozen=True)
class SmoothResult:
    """The output of :func:`rts_smooth` and :func:`two_filter_smooth`; arrays are read-only.

    ``(...)`` is ``()`` for one series and ``(B,)`` for a batch.

    Attributes
    ----------
    means : (..., T, n) ndarray
        Smoothed means, ``E[x_t | y_0, ..., y_{T-1}]``.
    covs : (..., T, n, n) ndarray
        Smoothed covariances.
    filtered : FilterResult
        The forward :class:`FilterResult` the smoother started from.
    backward_info : (..., T, n, n) ndarray or None
        Two-filter smoother only: the backward filter's prediction in information form,
        ``Λ_t = cov⁻¹``, of the density of ``y_{t+1}, ..., y_{T-1}`` given ``x_t`` (``Λ``
        may be singular near the end; it is zero at the last step).
    backward_info_vec : (..., T, n) ndarray or None
        Two-filter smoother only: ``η_t = Λ_t · mean``.

    Examples
    --------
    >>> F, H = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    >>> model = dict(F=F, Q=0.01 * np.eye(2), H=H, R=[[0.25]])
    >>> ys = np.array([[0.1], [0.9], [np.nan], [3.2]])
    >>> sm = two_filter_smooth(ys, **model, x0=[0.0, 1.0], P0=np.eye(2))
    >>> sm.means.shape, sm.backward_info.shape, sm.filtered.means.shape
    ((4, 2), (4, 2, 2), (4, 2))
    """

    means: np.ndarray
    covs: np.ndarray
    filtered: FilterResult
    backward_info: np.ndarray | None = None
    backward_info_vec: np.ndarray | None = None


@functools.cache
def _rts_kernel(n):
    """The RTS backward pass for state size ``n``, compiled with ``n`` as a constant (see
    :func:`vistrack.filters._kernels.single_kernel`). The kernel returns the first failing
    step or -1."""

    @njit(cache=True)
    def rts(means, covs, F, Q, s_means, s_covs):
        B, T = means.shape[0], means.shape[1]
        xp = np.empty(n)
        Pp = np.empty((n, n))
        FP = np.empty((n, n))
        L = np.empty((n, n))
        G = np.empty((n, n))  # holds G' = Pp^-1 F P
        A = np.empty((n, n))
        AP = np.empty((n, n))
        M = np.empty((n, n))
        GM = np.empty((n, n))
        for b in range(B):
            copy_vec(s_means[b, T - 1], means[b, T - 1])
            copy_mat(s_covs[b, T - 1], covs[b, T - 1])
            for t in range(T - 2, -1, -1):
                fi = t + 1 if F.shape[0] > 1 else 0
                qi = t + 1 if Q.shape[0] > 1 else 0
                # the filter's prediction of t+1: xp = F m_t, FP = F P_t, Pp = F P_t F' + Q
                predict_one(F, Q, fi, qi, means[b, t], covs[b, t], xp, Pp, FP, n)
                # G' = Pp^-1 (F P_t)  (P_t symmetric, so F P_t = (P_t F')')
                copy_mat(G, FP)
                if not chol_solve(L, Pp, G, n, n):
                    return t
                # m_s = m + G (m_s(t+1) - F m)
                for i in range(n):
                    s = means[b, t, i]
                    for l in range(n):
                        s += G[l, i] * (s_means[b, t + 1, l] - xp[l])
                    s_means[b, t, i] = s
                # P_s = (I - G F) P (I - G F)' + G (Q + P_s(t+1)) G', equal to
                # P + G (P_s(t+1) - Pp) G' but a sum of positive semi-definite terms: the
                # difference lost every digit where the variances span many orders (1e10
                # beside 1e-10 gave variances of 0 and below)
                for i in range(n):
                    for k in range(n):
                        s = 1.0 if i == k else 0.0
                        for l in range(n):
                            s -= G[l, i] * F[fi, l, k]
                        A[i, k] = s
                        M[i, k] = Q[qi, i, k] + s_covs[b, t + 1, i, k]
                for i in range(n):
                    for k in range(n):
                        s = 0.0
                        s2 = 0.0
                        for l in range(n):
                            s += A[i, l] * covs[b, t, l, k]
                            s2 += G[l, i] * M[l, k]
                        AP[i, k] = s
                        GM[i, k] = s2
                for i in range(n):
                    for k in range(i, n):
                        s = 0.0
                        s2 = 0.0
                        for l in range(n):
                            s += AP[i, l] * A[k, l] + GM[i, l] * G[l, k]
                            s2 += AP[k, l] * A[i, l] + GM[k, l] * G[l, i]
                        v = 0.5 * (s + s2)
                        s_covs[b, t, i, k] = v
                        s_covs[b, t, k, i] = v
        return -1

    return kernel(rts, f"{__name__}:_rts_kernel({n!r})")


def _filtered_arrays(result: FilterResult) -> tuple[np.ndarray, np.ndarray, bool]:
    if not isinstance(result, FilterResult):
        raise TypeError(f"result must be a FilterResult; got {type(result).__name__}")
    if result.covs is None:
        raise ValueError("result has no covariances: run kalman_filter with store_covs=True")
    # a FilterResult may be made by hand: the compiled smoother indexes covs by means' shape
    means = np.asarray(result.means, dtype=float)
    covs = np.asarray(result.covs, dtype=float)
    if means.ndim not in (2, 3):
        raise ValueError(f"result.means must have shape (T, n) or (B, T, n); got "
                         f"{means.shape}")
    if covs.shape != means.shape + means.shape[-1:]:
        raise ValueError(f"result.covs must have shape {means.shape + means.shape[-1:]} (the "
                         f"steps and states of result.means {means.shape}); got {covs.shape}")
    check_finite(means, "result.means")
    check_finite(covs, "result.covs")
    single = means.ndim == 2
    means = np.ascontiguousarray(means if not single else means[None])
    covs = np.ascontiguousarray(covs if not single else covs[None])
    return means, covs, single


def rts_smooth(result: FilterResult, *, F: ArrayLike, Q: ArrayLike) -> SmoothResult:
    r"""Rauch-Tung-Striebel smoother over a filtered sequence (one series or a batch).

    .. math::
        G_t = P_t F' (F P_t F' + Q)^{-1}, \quad
        m^s_t = m_t + G_t (m^s_{t+1} - F m_t), \quad
        P^s_t = P_t + G_t (P^s_{t+1} - F P_t F' - Q) G_t'

    with ``F = F[t+1]``, ``Q = Q[t+1]`` for per-step matrices, backwards from
    :math:`m^s_{T-1} = m_{T-1}`, :math:`P^s_{T-1} = P_{T-1}`. The gain comes from a Cholesky
    solve with the predicted covariance. The covariance is computed in the equal form
    :math:`(I - G_t F) P_t (I - G_t F)' + G_t (Q + P^s_{t+1}) G_t'`, a sum of positive
    semi-definite terms: the difference above loses every digit where the variances span
    many orders of magnitude (``1e10`` beside ``1e-10``).

    Parameters
    ----------
    result : FilterResult
        From :func:`vistrack.filters.kalman_filter` with ``store_covs=True``: means
        ``(..., T, n)``, covariances ``(..., T, n, n)``.
    F, Q : (n, n) or (T, n, n) array_like
        The model the filter ran with.

    Returns
    -------
    SmoothResult
        Smoothed means ``(..., T, n)`` and covariances ``(..., T, n, n)``; ``filtered`` is
        ``result``.

    Raises
    ------
    TypeError
        If ``result`` is not a :class:`FilterResult`.
    ValueError
        If ``result`` has no covariances, its ``covs`` do not match its ``means`` in shape or
        either has an entry that is not finite, ``F`` or ``Q`` has the wrong shape or is
        invalid, or a predicted covariance ``F P F' + Q`` is not positive definite.

    See Also
    --------
    two_filter_smooth : The seeds' forward-backward form, equal to rounding.

    References
    ----------
    .. [1] H. E. Rauch, F. Tung and C. T. Striebel, "Maximum likelihood estimates of linear
       dynamic systems", *AIAA Journal* 3(8), 1965.

    Examples
    --------
    The missing measurement at step 2 is better estimated from both sides:

    >>> F, H = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    >>> model = dict(F=F, Q=0.01 * np.eye(2), H=H, R=[[0.25]])
    >>> ys = np.array([[0.1], [0.9], [np.nan], [3.2]])
    >>> res = kalman_filter(ys, **model, x0=[0.0, 1.0], P0=np.eye(2))
    >>> sm = rts_smooth(res, F=F, Q=model["Q"])
    >>> res.means[2].round(3), sm.means[2].round(3)
    (array([1.808, 0.877]), array([2.096, 1.05 ]))
    >>> np.sqrt([res.covs[2, 0, 0], sm.covs[2, 0, 0]]).round(3)
    array([0.941, 0.337])
    """
    if isinstance(result, FilterResult) and _is_dask(result.means):
        from . import chunked  # a filtered batch larger than memory: chunk by chunk, lazily

        return chunked.rts_smooth(result, F=F, Q=Q)
    means, covs, single = _filtered_arrays(result)
    check_has_steps(result.means, "result.means")
    B, T, n = means.shape
    F_ = check_matrix_stack(F, "F", n, n, T)
    Q_ = check_matrix_stack(Q, "Q", n, n, T)
    check_psd(Q_, "Q")
    s_means = np.empty_like(means)
    s_covs = np.empty_like(covs)
    bad = _rts_kernel(n)(means, covs, F_, Q_, s_means, s_covs)
    if bad >= 0:
        raise ValueError(
            f"the predicted covariance F P F' + Q from step {bad} to {bad + 1} is not positive "
            "definite, so the RTS gain is undefined; make Q positive definite (P, the filtered "
            f"covariance result.covs at step {bad}, must be positive semi-definite)"
        )
    if single:
        s_means, s_covs = s_means[0], s_covs[0]
    _readonly(s_means, s_covs)
    return SmoothResult(s_means, s_covs, result)


def _too_far_apart(t: int, what: str) -> ValueError:
    """The error of a two-filter step whose ``what`` numpy found singular: nonsingular in
    exact arithmetic (P and Λ are positive semi-definite), singular in rounding where
    variances lie too far apart (1e10 beside 1e-10)."""
    return ValueError(f"step {t}: {what} is singular to working precision (the model's "
                      "variances lie too far apart for the information form, such as 1e10 "
                      "beside 1e-10); rts_smooth smooths such a model")


def two_filter_smooth(
    ys: ArrayLike, *, F: ArrayLike, Q: ArrayLike, H: ArrayLike, R: ArrayLike, x0: ArrayLike,
    P0: ArrayLike
) -> SmoothResult:
    r"""The seeds' forward-backward smoother: run two filters and combine them.

    "The crucial point here is that we can obtain a smoothed estimate by viewing the backward
    filter's prediction as yet another measurement for the forward filter." The forward pass is
    :func:`kalman_filter`. The backward filter runs from the last step to the first with no prior
    (a diffuse start), so it is kept in information form ``(Λ, η)``:

    - correction at ``t``: ``Λ ← Λ + H' R⁻¹ H``, ``η ← η + H' R⁻¹ y_t`` (observed components);
    - prediction from ``t+1`` to ``t``: ``Λ_t = F' (I + Λ Q)⁻¹ Λ F``, ``η_t = F' (I + Λ Q)⁻¹ η``.

    The backward prediction ``N(Λ_t⁻¹ η_t, Λ_t⁻¹)`` is then a measurement of ``x_t`` with ``H = I``
    for the forward estimate ``N(m_t, P_t)``; in a form that stays defined while ``Λ_t`` is
    singular: ``P^s = (I + P Λ)⁻¹ P``, ``m^s = (I + P Λ)⁻¹ (m + P η)``.

    Parameters
    ----------
    ys : (T, m) or (B, T, m) array_like
        Measurements; NaN components (or masked entries of a numpy masked array) are
        missing.
    F, Q : (n, n) or (T, n, n) array_like
        Dynamics and process noise, constant or per step.
    H, R : (m, n) and (m, m), or (T, m, n) and (T, m, m) array_like
        Measurement matrix and noise covariance, constant or per step.
    x0 : (n,) or (B, n) array_like
        Prior mean of the first step.
    P0 : (n, n) or (B, n, n) array_like
        Prior covariance of the first step.

    Returns
    -------
    SmoothResult
        Smoothed means ``(..., T, n)`` and covariances ``(..., T, n, n)``, the forward
        :class:`FilterResult`, and in ``backward_info`` / ``backward_info_vec`` the backward
        predictions ``Λ_t`` ``(..., T, n, n)`` and ``η_t`` ``(..., T, n)``.

    Raises
    ------
    ValueError
        As :func:`kalman_filter` raises; or if ``R`` is singular on the components observed
        at a step (an exact measurement, which :func:`rts_smooth` smooths), naming the step;
        or if the information form is singular to rounding at a step (variances 1e10 beside
        1e-10, which :func:`rts_smooth` smooths), naming the step.

    See Also
    --------
    rts_smooth : The Rauch-Tung-Striebel form, from a filtered result.

    References
    ----------
    .. [1] D. C. Fraser and J. E. Potter, "The optimum linear smoother as a combination of two
       optimum linear filters", *IEEE Transactions on Automatic Control* 14(4), 1969.

    Examples
    --------
    >>> F, H = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    >>> model = dict(F=F, Q=0.01 * np.eye(2), H=H, R=[[0.25]])
    >>> ys = np.array([[0.1], [0.9], [np.nan], [3.2]])
    >>> tf = two_filter_smooth(ys, **model, x0=[0.0, 1.0], P0=np.eye(2))
    >>> rts = rts_smooth(kalman_filter(ys, **model, x0=[0.0, 1.0], P0=np.eye(2)),
    ...                  F=F, Q=model["Q"])
    >>> np.allclose(tf.means, rts.means), np.allclose(tf.covs, rts.covs)
    (True, True)
    """

    fwd = kalman_filter(ys, F=F, Q=Q, H=H, R=R, x0=x0, P0=P0)
    y, single = as_measurement_series(ys)
    B, T, m = y.shape
    n = fwd.means.shape[-1]
    F_, Q_, H_, R_ = check_linear_gaussian(F, Q, H, R, n, m, T)
    fm, fP, _ = _filtered_arrays(fwd)
    eye = np.eye(n)
    Lam = np.zeros((B, n, n))
    eta = np.zeros((B, n))
    lam_pred = np.empty((B, T, n, n))
    eta_pred = np.empty((B, T, n))
    s_means = np.empty((B, T, n))
    s_covs = np.empty((B, T, n, n))
    for t in range(T - 1, -1, -1):
        if t < T - 1:
            # backward prediction from t+1 to t
            Ft, Qt = F_[t + 1 if F_.shape[0] > 1 else 0], Q_[t + 1 if Q_.shape[0] > 1 else 0]
            try:
                C = np.linalg.solve(eye + Lam @ Qt,
                                    np.concatenate([Lam, eta[..., None]], axis=-1))
            except np.linalg.LinAlgError:
                raise _too_far_apart(t + 1, "I + Λ Q") from None
            Lam = Ft.T @ C[..., :n] @ Ft
            Lam = 0.5 * (Lam + np.swapaxes(Lam, -1, -2))
            eta = (Ft.T @ C[..., n:])[..., 0]
        lam_pred[:, t], eta_pred[:, t] = Lam, eta
        # combine: the backward prediction as a measurement of x_t for the forward estimate
        P = fP[:, t]
        Mx = eye + P @ Lam
        rhs = (fm[:, t] + (P @ eta[..., None])[..., 0])[..., None]
        try:
            sol = np.linalg.solve(Mx, np.concatenate([P, rhs], axis=-1))
        except np.linalg.LinAlgError:
            raise _too_far_apart(t, "I + P Λ") from None
        Ps = sol[..., :n]
        s_covs[:, t] = 0.5 * (Ps + np.swapaxes(Ps, -1, -2))
        s_means[:, t] = sol[..., n]
        # backward correction with y_t (observed components only)
        Ht, Rt = H_[t if H_.shape[0] > 1 else 0], R_[t if R_.shape[0] > 1 else 0]
        obs = ~np.isnan(y[:, t])  # (B, m)
        both = obs[:, :, None] & obs[:, None, :]
        # missing components decoupled, on the observed ones' scale (so that the rank test
        # below is relative to the observed block)
        diag = np.diagonal(Rt)
        scale = np.where(obs, np.abs(diag), 0.0).max(axis=-1, initial=0.0)
        scale = np.where(scale > 0, scale, 1.0)
        Rm = np.where(both, Rt, np.eye(m) * scale[:, None, None])
        # singular to rounding: numerical rank below m (numpy's matrix_rank tolerance), where
        # solve may still return a finite, wrong inverse; of the correlation matrix, so that
        # components of other units (variances 1e4 and 1e-13) are not taken for singular
        C, sd = correlation(Rm)
        ev = np.linalg.eigvalsh(C)
        singular = bool((sd <= 0).any() or (ev[:, 0] <= ev[:, -1] * m * np.finfo(float).eps)
                        .any())
        try:
            if singular:
                raise np.linalg.LinAlgError
            W = np.linalg.solve(Rm, np.eye(m)) * both  # R_oo^-1 embedded, zero on missing
        except np.linalg.LinAlgError:
            raise ValueError(
                f"R at step {t} is singular on the observed components: the backward filter "
                "adds the information H' R^-1 H, which an exact measurement makes infinite "
                "(rts_smooth of kalman_filter's result smooths it)") from None
        yt = np.where(obs, y[:, t], 0.0)
        HtW = Ht.T @ W  # (B, n, m)
        Lam = Lam + HtW @ Ht
        Lam = 0.5 * (Lam + np.swapaxes(Lam, -1, -2))
        eta = eta + (HtW @ yt[..., None])[..., 0]
    if single:
        s_means, s_covs, lam_pred, eta_pred = s_means[0], s_covs[0], lam_pred[0], eta_pred[0]
    _readonly(s_means, s_covs, lam_pred, eta_pred)
    return SmoothResult(s_means, s_covs, fwd, lam_pred, eta_pred)
