r"""Association costs between tracks and detections, vectorised over both: ``(T, D)`` arrays.

- :func:`iou` and :func:`giou` of boxes ``x0, y0, x1, y1`` (generalised IoU: Rezatofighi et
  al., 2019, :math:`\text{GIoU} = \text{IoU} - |C \setminus (A \cup B)| / |C|` with ``C`` the
  smallest enclosing box; it stays informative for boxes that do not overlap);
- :func:`euclidean` distances between points;
- :func:`mahalanobis`: the squared distance :math:`d^2 = (z - \hat z)' S^{-1} (z - \hat z)` of
  each detection from each track's predicted measurement, with the innovation covariance
  ``S = H P H' + R`` of the track (seed 003, "Mahalanobis distance", validation gates).
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["iou", "giou", "euclidean", "mahalanobis"]


def _boxes(b: Any, name: str) -> np.ndarray:
    a = np.asarray(b, dtype=float)
    if a.size == 0:
        return a.reshape(0, 4)
    if a.ndim != 2 or a.shape[1] != 4:
        raise ValueError(f"{name} must have shape (N, 4) (x0, y0, x1, y1); got {a.shape}")
    return a


def _overlap(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    iw = np.clip(np.minimum(a[:, None, 2], b[None, :, 2]) - np.maximum(a[:, None, 0], b[None, :, 0]),
                 0, None)
    ih = np.clip(np.minimum(a[:, None, 3], b[None, :, 3]) - np.maximum(a[:, None, 1], b[None, :, 1]),
                 0, None)
    inter = iw * ih
    area_a = (a[:, 2] - a[:, 0]) * (a[:, 3] - a[:, 1])
    area_b = (b[:, 2] - b[:, 0]) * (b[:, 3] - b[:, 1])
    return inter, area_a[:, None] + area_b[None, :] - inter


def iou(a: Any, b: Any) -> np.ndarray:
    """Intersection over union of boxes ``a (N, 4)`` and ``b (M, 4)``: ``(N, M)``, 0 where both
    boxes are empty.

    Examples
    --------
    >>> iou([[0, 0, 2, 2]], [[1, 0, 3, 2], [5, 5, 6, 6]]).round(3).tolist()
    [[0.333, 0.0]]
    """
    a, b = _boxes(a, "a"), _boxes(b, "b")
    inter, union = _overlap(a, b)
    return np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)


def giou(a: Any, b: Any) -> np.ndarray:
    """Generalised IoU of boxes ``a (N, 4)`` and ``b (M, 4)``, in [-1, 1].

    Examples
    --------
    >>> giou([[0, 0, 1, 1]], [[2, 0, 3, 1]]).tolist()   # apart by one width: 0 - 1/3
    [[-0.3333333333333333]]
    """
    a, b = _boxes(a, "a"), _boxes(b, "b")
    inter, union = _overlap(a, b)
    cw = np.maximum(a[:, None, 2], b[None, :, 2]) - np.minimum(a[:, None, 0], b[None, :, 0])
    ch = np.maximum(a[:, None, 3], b[None, :, 3]) - np.minimum(a[:, None, 1], b[None, :, 1])
    hull = cw * ch
    i = np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)
    return i - np.divide(hull - union, hull, out=np.zeros_like(hull), where=hull > 0)


def euclidean(a: Any, b: Any) -> np.ndarray:
    """Distances between points ``a (N, d)`` and ``b (M, d)``: ``(N, M)``."""
    a, b = np.atleast_2d(np.asarray(a, dtype=float)), np.atleast_2d(np.asarray(b, dtype=float))
    if a.shape[1] != b.shape[1]:
        raise ValueError(f"a and b must have the same point size; got {a.shape} and {b.shape}")
    return np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1))


def mahalanobis(z_pred: Any, S: Any, z: Any) -> np.ndarray:
    """Squared Mahalanobis distances ``(T, D)`` of detections ``z (D, m)`` from predicted
    measurements ``z_pred (T, m)`` with innovation covariances ``S (T, m, m)``, by one
    Cholesky factorisation per track.

    Examples
    --------
    >>> mahalanobis([[0.0, 0.0]], [np.diag([4.0, 1.0])], [[2.0, 0.0], [0.0, 2.0]]).tolist()
    [[1.0, 4.0]]
    """
    zp = np.atleast_2d(np.asarray(z_pred, dtype=float))
    S = np.asarray(S, dtype=float)
    z = np.atleast_2d(np.asarray(z, dtype=float))
    T, m = zp.shape
    if S.shape != (T, m, m):
        raise ValueError(f"S must have shape ({T}, {m}, {m}); got {S.shape}")
    if z.shape[1:] != (m,) and z.size:
        raise ValueError(f"z must have shape (D, {m}); got {z.shape}")
    if T == 0 or z.size == 0:
        return np.zeros((T, len(z) if z.size else 0))
    try:
        L = np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        raise ValueError("S must be positive definite for every track") from None
    r = z[None, :, :] - zp[:, None, :]  # (T, D, m)
    w = np.linalg.solve(L, np.swapaxes(r, 1, 2))  # L w = r' : (T, m, D)
    return (w * w).sum(1)
