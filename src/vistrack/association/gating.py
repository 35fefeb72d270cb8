"""Gates: which track-detection pairs may be associated at all.

A chi-square gate keeps detections whose squared Mahalanobis distance is below the ``p``
quantile of the chi-square distribution with ``m`` degrees of freedom: the region where a true
detection falls with probability ``p`` (seed 003, "validation gate").
"""

from __future__ import annotations

import numpy as np
from scipy.stats import chi2

__all__ = ["chi2_gate", "chi2_threshold"]


def chi2_threshold(m: int, p: float = 0.99) -> float:
    """The ``p`` quantile of chi-square with ``m`` degrees of freedom."""
    if not 0.0 < p < 1.0:
        raise ValueError(f"p must be in (0, 1); got {p}")
    return float(chi2.ppf(p, int(m)))


def chi2_gate(d2: np.ndarray, m: int, p: float = 0.99) -> np.ndarray:
    """Boolean ``(T, D)``: ``d2 <= chi2_threshold(m, p)``."""
    return np.asarray(d2) <= chi2_threshold(m, p)
