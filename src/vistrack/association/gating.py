"""Gates: which track-detection pairs may be associated at all.

A chi-square gate keeps detections whose squared Mahalanobis distance is below the ``p``
quantile of the chi-square distribution with ``m`` degrees of freedom: the region where a true
detection falls with probability ``p`` (seed 003, "validation gate").
"""

from __future__ import annotations

import numpy as np

from .._validate import as_float_array, is_real, is_whole

__all__ = ["chi2_gate", "chi2_threshold"]


def chi2_threshold(m: int, p: float = 0.99) -> float:
    """The ``p`` quantile of chi-square with ``m`` degrees of freedom: the gate's threshold.

    Parameters
    ----------
    m : int
        Degrees of freedom: the size of a measurement.
    p : float
        Gate probability, in (0, 1).

    Returns
    -------
    float
        The threshold on the squared Mahalanobis distance.

    Raises
    ------
    ValueError
        If ``p`` is not a number in (0, 1), or ``m`` is not a whole number >= 1.

    Examples
    --------
    >>> round(chi2_threshold(2, 0.99), 3)
    9.21
    """
    # (a 0-d array was refused where m's was taken)
    if not (is_real(p) and 0.0 < float(p) < 1.0):
        raise ValueError(f"p must be a number in (0, 1); got {p!r}")
    # (10**400 failed in scipy's words, an OverflowError naming nothing)
    if not is_whole(m, 1) or m > 2**53:
        raise ValueError(f"m must be a whole number of degrees of freedom from 1 to 2**53, "
                         f"the size of a measurement; got {m!r}")
    from scipy.stats import chi2  # here: scipy.stats takes about 0.4 s to import

    return float(chi2.ppf(float(p), int(m)))


def chi2_gate(d2: np.ndarray, m: int, p: float = 0.99) -> np.ndarray:
    r"""The chi-square gate: which pairs are close enough to be associated.

    .. math:: d^2_{ij} \le \chi^2_m(p)

    Parameters
    ----------
    d2 : (T, D) array_like
        Squared Mahalanobis distances (:func:`~vistrack.association.mahalanobis`).
    m : int
        Size of a measurement (the degrees of freedom).
    p : float
        Gate probability, in (0, 1).

    Returns
    -------
    (T, D) ndarray of bool
        ``d2 <= chi2_threshold(m, p)`` (a NaN distance, of a detection that is not finite,
        is outside).

    Raises
    ------
    ValueError
        If ``d2`` has a negative entry (named), or as :func:`chi2_threshold` raises.

    Examples
    --------
    >>> chi2_gate(np.array([[1.0, 10.0]]), m=2)
    array([[ True, False]])
    """
    # (complex ones lost their imaginary parts)
    d2 = as_float_array(d2, "d2", not_boolean="squared distances, numbers >= 0")
    if (d2 < 0).any():  # (NaN, a detection that is not finite, is outside every gate)
        where = [int(i) for i in np.argwhere(d2 < 0)[0]]
        raise ValueError(f"d2 must hold squared distances, >= 0; d2{where} = "
                         f"{d2[tuple(where)]}")
    return d2 <= chi2_threshold(m, p)
