r"""Accuracy and consistency of state estimates: RMSE, NEES, NIS and chi-square bands.

A filter is *consistent* when its errors are as large as its covariances say. For a consistent
filter the normalised estimation error squared ``NEES = e' P⁻¹ e`` (``e`` = truth − estimate) is
chi-square with ``n`` degrees of freedom, and the normalised innovation squared
``NIS = ν' S⁻¹ ν`` is chi-square with ``m`` (Bar-Shalom, Li & Kirubarajan, *Estimation with
Applications to Tracking and Navigation*, §5.4). Averaged over ``N`` independent runs,
``N · mean`` is chi-square with ``N n`` degrees of freedom, which gives :func:`chi2_band`.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .._validate import as_float_array, as_measurement_series, check_psd, is_real, is_whole

if TYPE_CHECKING:  # the filters import numba; scoring needs none of it
    from ..filters.kalman import FilterResult

__all__ = ["rmse", "nees", "nis", "chi2_band"]


def rmse(estimates: ArrayLike, truth: ArrayLike, *,
         axis: int | tuple[int, ...] | None = None) -> np.ndarray:
    r"""Root-mean-square error of estimates against the truth.

    .. math:: \text{RMSE} = \sqrt{\operatorname{mean}\big((\hat x - x)^2\big)}

    Parameters
    ----------
    estimates, truth : array_like
        Arrays of one shape.
    axis : int or tuple of int, optional
        Axes to average over; all by default.

    Returns
    -------
    ndarray or numpy.float64
        The RMSE, with the ``axis`` dimensions removed (a scalar when averaging over
        everything).

    Raises
    ------
    ValueError
        If the shapes differ.

    Examples
    --------
    >>> round(float(rmse([1.0, 2.0, 3.0], [1.0, 2.0, 5.0])), 4)
    1.1547
    >>> rmse(np.array([[1.0, 1.0], [3.0, 3.0]]), np.zeros((2, 2)), axis=0).round(4)
    array([2.2361, 2.2361])
    """
    est = as_float_array(estimates, "estimates")
    tru = as_float_array(truth, "truth")
    if est.shape != tru.shape:
        raise ValueError(f"estimates and truth must have the same shape; got {est.shape} and "
                         f"{tru.shape}")
    if est.size == 0:  # the mean of nothing was NaN, with numpy's warning
        raise ValueError("estimates and truth are empty: no error to measure")
    return np.sqrt(np.mean((est - tru) ** 2, axis=axis))


def _quadratic(e: np.ndarray, S: np.ndarray, name: Callable[[tuple], str]) -> np.ndarray:
    """``e' S^-1 e`` for each of a stack, or a LinAlgError naming the first ``S`` that is
    not positive definite by ``name(index)`` (numpy's said "Matrix is not positive definite"
    alone, of one step among thousands)."""
    try:
        L = np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        for i in np.ndindex(S.shape[:-2]):
            try:
                np.linalg.cholesky(S[i])
            except np.linalg.LinAlgError:
                raise np.linalg.LinAlgError(f"{name(i)} is not positive definite") from None
        raise
    w = np.linalg.solve(L, e[..., None])[..., 0]
    return np.sum(w * w, axis=-1)


def nees(truth: ArrayLike, means: ArrayLike, covs: ArrayLike) -> np.ndarray:
    r"""Normalised estimation error squared of each estimate.

    .. math:: \text{NEES} = (x - \hat x)' P^{-1} (x - \hat x),

    chi-square with ``n`` degrees of freedom for a consistent filter (see the module).

    Parameters
    ----------
    truth : (..., n) array_like
        True states.
    means : (..., n) array_like
        Estimates.
    covs : (..., n, n) array_like
        Their covariances, positive definite.

    Returns
    -------
    (...) ndarray
        One NEES per estimate.

    Raises
    ------
    ValueError
        If the shapes disagree.
    numpy.linalg.LinAlgError
        If a covariance is not positive definite (the first such is named,
        ``covs[57] is not positive definite``).

    References
    ----------
    .. [1] Y. Bar-Shalom, X. R. Li and T. Kirubarajan, *Estimation with Applications to
       Tracking and Navigation*, Wiley, 2001, §5.4.

    Examples
    --------
    >>> round(float(nees([1.0, 0.0], [0.0, 0.0], 0.5 * np.eye(2))), 6)
    2.0
    """
    x = as_float_array(truth, "truth")
    m = as_float_array(means, "means")
    P = as_float_array(covs, "covs")
    if m.ndim == 0 or x.shape != m.shape or P.shape != m.shape + m.shape[-1:]:
        raise ValueError(
            f"truth and means must have the same shape (..., n) and covs (..., n, n); "
            f"got {x.shape}, {m.shape}, {P.shape}"
        )
    check_psd(P, "covs")  # symmetric: its lower triangle alone was read
    return _quadratic(x - m, P, lambda i: f"covs[{', '.join(map(str, i))}]" if i else "covs")


def nis(ys: ArrayLike, result: FilterResult, *, H: ArrayLike,
        R: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    r"""Normalised innovation squared of each step, over its observed components.

    .. math:: \text{NIS}_t = \nu_t' S_t^{-1} \nu_t, \qquad \nu_t = y_t - H \bar x_t^-,
              \quad S_t = H \Sigma_t^- H' + R,

    chi-square with as many degrees of freedom as observed components for a consistent
    filter (see the module).

    Parameters
    ----------
    ys : (T, m) or (B, T, m) array_like
        The measurements the filter ran on (NaN: missing).
    result : FilterResult
        From :func:`vistrack.filters.kalman_filter` (or a filter's ``filter``) with
        ``store_covs=True``: its predictions are used.
    H : (m, n) or (T, m, n) array_like
        Measurement matrix.
    R : (m, m) or (T, m, m) array_like
        Measurement-noise covariance.

    Returns
    -------
    nis : (..., T) ndarray
        ``ν' S⁻¹ ν`` over the observed components; 0 where nothing was observed.
    dof : (..., T) ndarray of int
        Number of observed components (the chi-square degrees of freedom).

    Raises
    ------
    ValueError
        If the result has no predictions (``store_covs=False``) or does not cover ``ys``, or
        ``R`` is not symmetric positive semi-definite.
    numpy.linalg.LinAlgError
        If an innovation covariance ``S`` is not positive definite (the first such named).

    References
    ----------
    .. [1] Y. Bar-Shalom, X. R. Li and T. Kirubarajan, *Estimation with Applications to
       Tracking and Navigation*, Wiley, 2001, §5.4.

    Examples
    --------
    >>> from vistrack.filters import kalman_filter
    >>> F, H = np.array([[1.0, 1.0], [0.0, 1.0]]), np.array([[1.0, 0.0]])
    >>> ys = np.array([[0.1], [0.9], [np.nan], [3.2]])
    >>> res = kalman_filter(ys, F=F, Q=0.01 * np.eye(2), H=H, R=[[0.25]],
    ...                     x0=[0.0, 1.0], P0=np.eye(2))
    >>> v, dof = nis(ys, res, H=H, R=[[0.25]])
    >>> v.round(3), dof
    (array([0.008, 0.022, 0.   , 0.108]), array([1, 1, 0, 1]))
    """
    y, single = as_measurement_series(ys)
    if result.pred_covs is None:
        raise ValueError("result has no covariances: run the filter with store_covs=True")
    if result.pred_means is None:
        raise ValueError("result has no predicted means: run the filter with store_covs=True")
    pm = result.pred_means if not single else result.pred_means[None]
    pP = result.pred_covs if not single else result.pred_covs[None]
    H_ = as_float_array(H, "H", ndim=(2, 3))
    R_ = as_float_array(R, "R", ndim=(2, 3))
    if y.shape[:2] != pm.shape[:2]:
        if single:  # (the batch's shapes, (1, T, m), were given for a series of its own)
            raise ValueError(f"ys has {y.shape[1]} steps (shape {y.shape[1:]}) but the result "
                             f"covers {pm.shape[1]}")
        raise ValueError(f"ys has shape {y.shape} but the result covers {pm.shape[:2]}")
    m, n, T = y.shape[-1], pm.shape[-1], y.shape[1]
    # named here: a (1, 1) R was added to every entry of S, a (1, n) H broadcast over m rows
    for name, arr, want in (("H", H_, (m, n)), ("R", R_, (m, m))):
        if arr.shape[-2:] != want or (arr.ndim == 3 and arr.shape[0] != T):
            raise ValueError(f"{name} must be {want} or ({T}, {want[0]}, {want[1]}) for ys of "
                             f"{m} values and states of {n}; got {arr.shape}")
    # as the filters check it: S's lower triangle alone was read, so an R not symmetric gave
    # a NIS that depended on which triangle held the slip, without a word
    check_psd(R_, "R")
    Ht = np.swapaxes(H_, -1, -2)
    nu = y - pm @ Ht if H_.ndim == 2 else y - np.einsum("tmn,btn->btm", H_, pm)
    S = H_ @ pP @ Ht + R_
    obs = ~np.isnan(y)
    both = obs[..., :, None] & obs[..., None, :]
    S = np.where(both, S, np.eye(m))
    val = _quadratic(np.where(obs, nu, 0.0), S,
                     lambda i: f"S = H P H' + R at step {i[1]}" + ("" if single
                                                                   else f" of series {i[0]}"))
    dof = obs.sum(axis=-1)
    if single:
        return val[0], dof[0]
    return val, dof


def chi2_band(dof: int, *, n_runs: int = 1, level: float = 0.95) -> tuple[float, float]:
    r"""Two-sided ``level`` band for the mean of ``n_runs`` chi-square(``dof``) statistics.

    The sum of ``N`` independent chi-square(``dof``) values is chi-square(``N dof``), so the
    band of their mean is

    .. math:: \left[\frac{\chi^2_{N\,dof}\big(\tfrac{1 - level}{2}\big)}{N},\;
              \frac{\chi^2_{N\,dof}\big(\tfrac{1 + level}{2}\big)}{N}\right].

    Parameters
    ----------
    dof : int
        Degrees of freedom of each statistic (``n`` for NEES, ``m`` for NIS), >= 1.
    n_runs : int
        Number ``N`` of independent runs averaged, >= 1.
    level : float
        Probability of the band, in (0, 1).

    Returns
    -------
    lo, hi : float
        The band's ends.

    Raises
    ------
    ValueError
        If an argument is out of range.

    References
    ----------
    .. [1] Y. Bar-Shalom, X. R. Li and T. Kirubarajan, *Estimation with Applications to
       Tracking and Navigation*, Wiley, 2001, §5.4.

    Examples
    --------
    >>> lo, hi = chi2_band(4, n_runs=50)
    >>> round(lo, 2), round(hi, 2)
    (3.25, 4.82)
    """
    from scipy import stats  # imported here: scipy.stats costs ~60 MB and 0.8 s at import

    # written so that NaN fails too (it passed, and gave a band of NaN); each named alone
    for name, value in (("dof", dof), ("n_runs", n_runs)):
        if not is_whole(value, 1):
            raise ValueError(f"{name} must be a whole number >= 1; got {value!r}")
    if not (is_real(level) and 0 < level < 1):  # (a string met a bare comparison error)
        raise ValueError(f"level must be a probability in (0, 1); got {level!r}")
    a = (1 - level) / 2
    k = dof * n_runs
    return float(stats.chi2.ppf(a, k) / n_runs), float(stats.chi2.ppf(1 - a, k) / n_runs)
