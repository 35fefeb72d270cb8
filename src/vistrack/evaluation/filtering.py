r"""Accuracy and consistency of state estimates: RMSE, NEES, NIS and chi-square bands.

A filter is *consistent* when its errors are as large as its covariances say. For a consistent
filter the normalised estimation error squared ``NEES = e' P⁻¹ e`` (``e`` = truth − estimate) is
chi-square with ``n`` degrees of freedom, and the normalised innovation squared
``NIS = ν' S⁻¹ ν`` is chi-square with ``m`` (Bar-Shalom, Li & Kirubarajan, *Estimation with
Applications to Tracking and Navigation*, §5.4). Averaged over ``N`` independent runs,
``N · mean`` is chi-square with ``N n`` degrees of freedom, which gives :func:`chi2_band`.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .._validate import as_float_array, as_measurement_series
from ..filters.kalman import FilterResult

__all__ = ["rmse", "nees", "nis", "chi2_band"]


def rmse(estimates: Any, truth: Any, *, axis: int | tuple[int, ...] | None = None) -> np.ndarray:
    """Root-mean-square error ``sqrt(mean((estimates - truth)²))`` over ``axis`` (all by
    default)."""
    est = as_float_array(estimates, "estimates")
    tru = as_float_array(truth, "truth")
    if est.shape != tru.shape:
        raise ValueError(f"estimates and truth must have the same shape; got {est.shape} and "
                         f"{tru.shape}")
    return np.sqrt(np.mean((est - tru) ** 2, axis=axis))


def _quadratic(e: np.ndarray, S: np.ndarray) -> np.ndarray:
    L = np.linalg.cholesky(S)
    w = np.linalg.solve(L, e[..., None])[..., 0]
    return np.sum(w * w, axis=-1)


def nees(truth: Any, means: Any, covs: Any) -> np.ndarray:
    """``(x - m)' P⁻¹ (x - m)`` per estimate: ``truth, means (..., n)``, ``covs (..., n, n)``."""
    x = as_float_array(truth, "truth")
    m = as_float_array(means, "means")
    P = as_float_array(covs, "covs")
    if x.shape != m.shape or P.shape != m.shape + m.shape[-1:]:
        raise ValueError(
            f"truth and means must have the same shape (..., n) and covs (..., n, n); "
            f"got {x.shape}, {m.shape}, {P.shape}"
        )
    return _quadratic(x - m, P)


def nis(ys: Any, result: FilterResult, *, H: Any, R: Any) -> tuple[np.ndarray, np.ndarray]:
    """Normalised innovation squared of each step, over its observed components.

    Returns
    -------
    nis : ndarray, shape (..., T)
        ``ν' S⁻¹ ν`` with ``ν = y - H x̄⁻`` and ``S = H Σ⁻ H' + R``; 0 where nothing was observed.
    dof : ndarray of int, shape (..., T)
        Number of observed components (the chi-square degrees of freedom).
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
        raise ValueError(f"ys has shape {y.shape} but the result covers {pm.shape[:2]}")
    m = y.shape[-1]
    Ht = np.swapaxes(H_, -1, -2)
    nu = y - pm @ Ht if H_.ndim == 2 else y - np.einsum("tmn,btn->btm", H_, pm)
    S = H_ @ pP @ Ht + R_
    obs = ~np.isnan(y)
    both = obs[..., :, None] & obs[..., None, :]
    S = np.where(both, S, np.eye(m))
    val = _quadratic(np.where(obs, nu, 0.0), S)
    dof = obs.sum(axis=-1)
    if single:
        return val[0], dof[0]
    return val, dof


def chi2_band(dof: int, *, n_runs: int = 1, level: float = 0.95) -> tuple[float, float]:
    """Two-sided ``level`` band for the mean of ``n_runs`` chi-square(``dof``) statistics.

    Examples
    --------
    >>> lo, hi = chi2_band(4, n_runs=50)
    >>> round(lo, 2), round(hi, 2)
    (3.25, 4.82)
    """
    from scipy import stats  # imported here: scipy.stats costs ~60 MB and 0.8 s at import

    if dof < 1 or n_runs < 1 or not 0 < level < 1:
        raise ValueError(f"need dof >= 1, n_runs >= 1, 0 < level < 1; got {dof}, {n_runs}, {level}")
    a = (1 - level) / 2
    k = dof * n_runs
    return float(stats.chi2.ppf(a, k) / n_runs), float(stats.chi2.ppf(1 - a, k) / n_runs)
