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

import numpy as np
from numpy.typing import ArrayLike

from .._jit import njit
from .._prebuilt import kernel
from .._validate import as_finite, as_float_array, check_symmetric

__all__ = ["iou", "paired_iou", "iou_pairs", "iou_pairs_same_class", "overlapping_pairs",
           "non_maximum", "giou", "euclidean", "mahalanobis"]


def _boxes(b: ArrayLike, name: str) -> np.ndarray:
    a = as_float_array(b, name)  # (complex boxes lost their imaginary parts)
    # none: (0, 4), or a bare [] (a (3, 0) array was taken for none, its 3 rows dropped)
    if a.size == 0 and (a.ndim == 1 or (a.ndim == 2 and (len(a) == 0 or a.shape[1] == 4))):
        return a.reshape(0, 4)
    if a.ndim != 2 or a.shape[1] != 4:
        raise ValueError(f"{name} must have shape (N, 4) (x0, y0, x1, y1); got {a.shape}")
    if not np.isfinite(a).all():  # (a NaN box overlapped nothing: IoU 0, GIoU 0, unsaid)
        k = int(np.flatnonzero(~np.isfinite(a).all(axis=1))[0])
        raise ValueError(f"{name} must be finite boxes; {name}[{k}] = {a[k].tolist()}")
    # (a far corner before the near one overlapped nothing, itself included: IoU 0, and two
    # such boxes, the same, both survived non_maximum)
    inverted = (a[:, 2] < a[:, 0]) | (a[:, 3] < a[:, 1])
    if inverted.any():
        k = int(np.flatnonzero(inverted)[0])
        raise ValueError(f"{name}[{k}] = {a[k].tolist()} is not a box x0, y0, x1, y1 with "
                         "x0 <= x1 and y0 <= y1")
    # (a box of side 1e160 has an area of inf, one of 1e-170 an area of 0: two such boxes,
    # the same, overlapped at IoU 0, and both survived non_maximum)
    w, h = a[:, 2] - a[:, 0], a[:, 3] - a[:, 1]
    with np.errstate(over="ignore", under="ignore"):
        area = w * h
    # (an area below the smallest normal float kept a few digits or one: two boxes of side
    # 2.3e-162 overlapping by half had IoU 1, and non_maximum dropped the second)
    lost = np.isinf(w) | np.isinf(h) | np.isinf(area) | (
        (area < np.finfo(float).tiny) & (w > 0) & (h > 0))
    if lost.any():
        k = int(np.flatnonzero(lost)[0])
        raise ValueError(f"{name}[{k}] = {a[k].tolist()} is a box whose area a float cannot "
                         f"hold ({w[k]:g} x {h[k]:g}); scale the boxes")
    return a


def _overlap(a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    # intersection and union of boxes (..., 4) that broadcast against each other
    iw = np.clip(np.minimum(a[..., 2], b[..., 2]) - np.maximum(a[..., 0], b[..., 0]), 0, None)
    ih = np.clip(np.minimum(a[..., 3], b[..., 3]) - np.maximum(a[..., 1], b[..., 1]), 0, None)
    inter = iw * ih
    area_a = (a[..., 2] - a[..., 0]) * (a[..., 3] - a[..., 1])
    area_b = (b[..., 2] - b[..., 0]) * (b[..., 3] - b[..., 1])
    return inter, area_a + area_b - inter


def _ratio(inter: np.ndarray, union: np.ndarray) -> np.ndarray:
    return np.divide(inter, union, out=np.zeros_like(inter), where=union > 0)


def iou(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    r"""Intersection over union of every box of ``a`` with every box of ``b``.

    .. math:: \text{IoU}(A, B) = \frac{|A \cap B|}{|A \cup B|}

    Parameters
    ----------
    a : (N, 4) array_like
        Boxes ``x0, y0, x1, y1``.
    b : (M, 4) array_like
        Boxes ``x0, y0, x1, y1``.

    Returns
    -------
    (N, M) ndarray
        IoU in [0, 1]; 0 where the union is empty (both boxes empty).

    Raises
    ------
    ValueError
        If ``a`` or ``b`` is not empty and not of shape ``(., 4)``, or holds a box that is
        not finite, inverted, or of an area a float cannot hold (each named).

    See Also
    --------
    iou_pairs : The overlapping pairs only, for many boxes.
    paired_iou : IoU of boxes paired by index.

    Examples
    --------
    >>> iou([[0, 0, 2, 2]], [[1, 0, 3, 2], [5, 5, 6, 6]]).round(3).tolist()
    [[0.333, 0.0]]
    """
    a, b = _boxes(a, "a"), _boxes(b, "b")
    return _ratio(*_overlap(a[:, None], b[None, :]))


def paired_iou(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Intersection over union of boxes paired by index: ``a[k]`` with ``b[k]``.

    Parameters
    ----------
    a, b : (N, 4) array_like
        Boxes ``x0, y0, x1, y1``.

    Returns
    -------
    (N,) ndarray
        IoU in [0, 1]; 0 where the union is empty.

    Raises
    ------
    ValueError
        If ``a`` and ``b`` do not have the same shape ``(N, 4)``, or a box is not finite.

    Examples
    --------
    >>> paired_iou([[0, 0, 2, 2], [0, 0, 1, 1]], [[1, 0, 3, 2], [5, 5, 6, 6]]).round(3).tolist()
    [0.333, 0.0]
    """
    a, b = _boxes(a, "a"), _boxes(b, "b")
    if a.shape != b.shape:
        raise ValueError(f"a and b must have the same shape; got {a.shape} and {b.shape}")
    return _ratio(*_overlap(a, b))


def giou(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    r"""Generalised IoU of every box of ``a`` with every box of ``b``.

    .. math:: \text{GIoU}(A, B) = \text{IoU}(A, B) - \frac{|C \setminus (A \cup B)|}{|C|}

    with ``C`` the smallest box that encloses both: unlike the IoU, it still tells how far
    apart boxes that do not overlap are.

    Parameters
    ----------
    a : (N, 4) array_like
        Boxes ``x0, y0, x1, y1``.
    b : (M, 4) array_like
        Boxes ``x0, y0, x1, y1``.

    Returns
    -------
    (N, M) ndarray
        GIoU in [-1, 1].

    Raises
    ------
    ValueError
        If ``a`` or ``b`` is not empty and not of shape ``(., 4)``, or holds a box that is
        not finite, or whose ``x1 < x0`` or ``y1 < y0`` (its negative area and hull gave
        values far outside [-1, 1]).

    References
    ----------
    .. [1] H. Rezatofighi, N. Tsoi, J. Gwak, A. Sadeghian, I. Reid and S. Savarese,
       "Generalized intersection over union: a metric and a loss for bounding box
       regression", CVPR 2019.

    Examples
    --------
    >>> giou([[0, 0, 1, 1]], [[2, 0, 3, 1]]).tolist()   # apart by one width: 0 - 1/3
    [[-0.3333333333333333]]
    """
    a, b = _boxes(a, "a"), _boxes(b, "b")
    inter, union = _overlap(a[:, None], b[None, :])
    cw = np.maximum(a[:, None, 2], b[None, :, 2]) - np.minimum(a[:, None, 0], b[None, :, 0])
    ch = np.maximum(a[:, None, 3], b[None, :, 3]) - np.minimum(a[:, None, 1], b[None, :, 1])
    with np.errstate(over="ignore"):
        hull = cw * ch
    far = np.isinf(hull)  # boxes far apart, whose hull a float cannot hold: its limit,
    # 1 - union / hull (inf - union over inf was NaN)
    out = _ratio(inter, union) - _ratio(hull - union, np.where(far, 1.0, hull))
    if far.any():
        out[far] = _ratio(inter, union)[far] - 1.0
    return out


def euclidean(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """Euclidean distances between every point of ``a`` and every point of ``b``.

    Parameters
    ----------
    a : (N, d) array_like
        Points (one point may be given as ``(d,)``).
    b : (M, d) array_like
        Points (one point may be given as ``(d,)``).

    Returns
    -------
    (N, M) ndarray
        ``|a_i - b_j|``.

    Raises
    ------
    ValueError
        If ``a`` or ``b`` is not 1-D or 2-D, or their points differ in size.

    Examples
    --------
    >>> euclidean([[0, 0], [3, 4]], [[0, 0], [6, 8]])
    array([[ 0., 10.],
           [ 5.,  5.]])
    """
    pa, pb = _points(a, "a"), _points(b, "b")
    if pa is None or pb is None:  # none (a bare []): as iou's, of the other's count
        return np.zeros((0 if pa is None else len(pa), 0 if pb is None else len(pb)))
    if pa.shape[1] != pb.shape[1]:
        raise ValueError(f"a and b must have the same point size; got {pa.shape} and "
                         f"{pb.shape}")
    diff = pa[:, None, :] - pb[None, :, :]
    with np.errstate(over="ignore", under="ignore"):
        d = np.sqrt((diff * diff).sum(-1))
    # squares past the largest float (3e200 apart), or below the smallest normal one (1e-154
    # apart: points 3e-170 and 1e-170 from the origin were both 0 from it, and the nearest
    # taken was the farther): each such pair scaled by its largest coordinate, as math.hypot
    # does
    scale = (np.isinf(d) | (d < 1e-150)) & np.isfinite(diff).all(-1) & (d >= 0)
    if scale.any():
        big = np.abs(diff[scale]).max(-1, keepdims=True)
        safe = np.where(big > 0, big, 1.0)
        with np.errstate(over="ignore"):
            d[scale] = big[:, 0] * np.sqrt(((diff[scale] / safe) ** 2).sum(-1))
    return d


def _points(value: ArrayLike, name: str) -> np.ndarray | None:
    """Points ``(N, d)`` (one given as ``(d,)``), or None for none given as a bare ``[]``
    (as ``atleast_2d`` read it: one point of no coordinates, distance 0 from every other,
    and a phantom pair)."""
    x = as_float_array(value, name)  # (complex values lost their imaginary parts)
    if x.ndim == 1 and x.size == 0:
        return None
    x = np.atleast_2d(x)
    if x.ndim != 2:
        raise ValueError(f"{name} must be points, (N, d) or one (d,); got shape {x.shape}")
    return x


def _innovations(z_pred: ArrayLike, S: ArrayLike, z: ArrayLike, z_name: str = "z"
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    # predicted measurements (T, m), innovation covariances (T, m, m), detections (D, m)
    # (complex values lost their imaginary parts)
    zp = as_float_array(z_pred, "z_pred")
    S = as_float_array(S, "S")
    z = np.atleast_2d(as_float_array(z, z_name))
    if zp.shape == (0,):  # no tracks, a bare [] (or an array of none): read as one track
        # of no measurement, and S, as bare, refused as not (1, 0, 0)
        none = z.size == 0 and z.shape == (1, 0)  # (a bare [] of detections: atleast_2d's)
        zp = np.zeros((0, 0 if none else z.shape[1]))
        if S.shape == (0,):
            S = np.zeros((0, zp.shape[1], zp.shape[1]))
    zp = np.atleast_2d(zp)
    if zp.ndim != 2:  # (Python's "too many values to unpack")
        raise ValueError(f"z_pred must have shape (T, m); got {zp.shape}")
    T, m = zp.shape
    if S.shape != (T, m, m):
        raise ValueError(f"S must have shape ({T}, {m}, {m}); got {S.shape}")
    # (none: a bare [] or (0, m); a (5, 0) array was taken for none, its rows dropped)
    if z.shape[1:] != (m,) and not (z.size == 0 and z.shape in ((1, 0), (0, m))):
        raise ValueError(f"{z_name} must have shape (D, {m}); got {z.shape}")
    if T == 0:  # no tracks: nothing to check in S or z_pred (the checks below reduced over
        # no entry, in numpy's words, where there were no detections either)
        return zp, S, z
    finite = np.isfinite(S).all(axis=(1, 2))
    if not finite.all():  # numpy's Cholesky factor of NaN is NaN, without an error
        raise ValueError(f"S must be finite and positive definite for every track; S["
                         f"{int(np.flatnonzero(~finite)[0])}] is not finite")
    # (a track whose prediction is not finite would be outside every gate, and so dropped
    # without a word)
    ok = np.isfinite(zp).all(axis=1)
    if not ok.all():
        t = int(np.flatnonzero(~ok)[0])
        raise ValueError(f"z_pred must be finite; z_pred[{t}] = {zp[t].tolist()}")
    # numpy's Cholesky reads the lower triangle alone: an S that is not symmetric would be
    # taken for another
    check_symmetric(S, "S")
    return zp, S, z


def cholesky_innovations(S: np.ndarray) -> np.ndarray:
    """The Cholesky factors ``L`` (``S_t = L_t L_t'``) of innovation covariances ``(T, m, m)``.

    Raises a ValueError naming the first track whose ``S_t`` is not positive definite, rather
    than numpy's LinAlgError."""
    try:
        return np.linalg.cholesky(S)
    except np.linalg.LinAlgError:
        for t in range(len(S)):
            try:
                np.linalg.cholesky(S[t])
            except np.linalg.LinAlgError:
                raise ValueError(f"S must be positive definite for every track; S[{t}] is "
                                 f"not") from None
        raise ValueError("S must be positive definite for every track") from None


def mahalanobis(z_pred: ArrayLike, S: ArrayLike, z: ArrayLike) -> np.ndarray:
    r"""Squared Mahalanobis distances of detections from tracks' predicted measurements.

    .. math:: d^2_{tj} = (z_j - \hat z_t)' S_t^{-1} (z_j - \hat z_t),

    by one Cholesky factorisation per track. For a consistent filter, :math:`d^2` of the
    track's own detection is chi-square with ``m`` degrees of freedom
    (:func:`~vistrack.association.chi2_gate`).

    Parameters
    ----------
    z_pred : (T, m) array_like
        Predicted measurements :math:`\hat z_t = H \bar x_t^-`.
    S : (T, m, m) array_like
        Innovation covariances :math:`S_t = H P_t^- H' + R`, positive definite.
    z : (D, m) array_like
        Detections.

    Returns
    -------
    (T, D) ndarray
        The squared distances.

    Raises
    ------
    ValueError
        If the shapes disagree, an ``S_t`` is not symmetric and positive definite, or a
        ``z_pred`` is not finite (each named).

    Examples
    --------
    >>> mahalanobis([[0.0, 0.0]], [np.diag([4.0, 1.0])], [[2.0, 0.0], [0.0, 2.0]]).tolist()
    [[1.0, 4.0]]
    """
    zp, S, z = _innovations(z_pred, S, z)
    T, m = zp.shape
    if T == 0 or z.size == 0:
        return np.zeros((T, len(z) if z.size else 0))
    L = cholesky_innovations(S)
    r = z[None, :, :] - zp[:, None, :]  # (T, D, m)
    w = np.linalg.solve(L, np.swapaxes(r, 1, 2))  # L w = r' : (T, m, D)
    return (w * w).sum(1)


def mahalanobis_pairs(z_pred: ArrayLike, S: ArrayLike, z: ArrayLike,
                      threshold: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pairs of tracks and detections whose squared Mahalanobis distance is at most
    ``threshold``, without the dense ``(T, D)`` matrix: ``(rows, cols, d2)``.

    A detection within the gate of track ``t`` lies within Euclidean distance
    ``√(threshold · λ_max(S_t))`` of its prediction, so a k-d tree over the detections gives
    the candidates, and only those are measured.

    Examples
    --------
    >>> r, c, d2 = mahalanobis_pairs([[0.0, 0.0]], [np.diag([4.0, 1.0])],
    ...                              [[2.0, 0.0], [0.0, 2.0], [9.0, 9.0]], threshold=2.0)
    >>> r.tolist(), c.tolist(), d2.tolist()
    ([0], [0], [1.0])
    """
    from scipy.spatial import cKDTree

    from .._validate import as_number

    # (NaN or -1 gave no pair, without a word; inf is no gate, as before)
    if not as_number(threshold, "threshold") >= 0:
        raise ValueError(f"threshold must be a squared distance >= 0 (inf: no gate); got "
                         f"{threshold!r}")
    zp, S, z = _innovations(z_pred, S, z)
    T = len(zp)
    if T == 0 or z.size == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    try:
        Sinv = np.linalg.inv(S)
        eig = np.linalg.eigvalsh(S)
    except np.linalg.LinAlgError:
        raise ValueError("S must be positive definite for every track") from None
    if not (eig[:, 0] > 0).all():  # the smallest: an indefinite S gave negative distances
        raise ValueError(f"S must be positive definite for every track; S["
                         f"{int(np.flatnonzero(eig[:, 0] <= 0)[0])}] is not")
    lam = eig[:, -1]
    finite = np.isfinite(z).all(axis=1)
    if not finite.all():  # (scipy's k-d tree: "data must be finite", naming no argument)
        j = int(np.flatnonzero(~finite)[0])
        raise ValueError(f"z must be finite; z[{j}] = {z[j].tolist()}")
    near = cKDTree(z).query_ball_point(zp, np.sqrt(threshold * lam) * (1 + 1e-9))
    counts = np.fromiter((len(x) for x in near), np.int64, T)
    rows = np.repeat(np.arange(T), counts)
    cols = np.fromiter((j for x in near for j in x), np.int64, int(counts.sum()))
    r = z[cols] - zp[rows]
    d2 = np.einsum("pi,pij,pj->p", r, Sinv[rows], r)
    ok = d2 <= threshold
    return rows[ok], cols[ok], d2[ok]


@njit(cache=True)
def _finite(boxes):
    # every value of the (N, 4) boxes finite
    for j in range(boxes.shape[0]):
        for k in range(4):
            if not np.isfinite(boxes[j, k]):
                return False
    return True


@njit(cache=True, error_model="numpy")
def _grid_pairs(a, b, min_iou):
    # b bucketed by the grid cell of its corner (x0, y0), cells as large as b's largest box
    # (coarser when b is spread so far that the grid would be much larger than b): a box of b
    # can only overlap box a if its corner lies in the cells from (a.x0 - cw, a.y0 - ch) to
    # (a.x1, a.y1). Returns (rows, cols, iou, ok); ok is False for a non-finite box.
    cw, ch = 1e-9, 1e-9
    x_hi, y_hi = -np.inf, -np.inf
    # one call each rather than a loop over (a, b): numba iterates over a tuple only of one
    # type, and a read-only array is of another type than a writable one
    if not _finite(a) or not _finite(b):
        return (np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0), False)
    for j in range(b.shape[0]):
        cw = max(cw, b[j, 2] - b[j, 0])
        ch = max(ch, b[j, 3] - b[j, 1])
        x_hi, y_hi = max(x_hi, b[j, 0]), max(y_hi, b[j, 1])
    x_min, y_min = b[:, 0].min(), b[:, 1].min()
    # at most `limit` cells in all: both axes coarsened alike, but an axis that would then
    # have less than one cell kept as it is and the other coarsened further (boxes spread
    # along a line, or one box far from the rest), so that neither axis' count overflows;
    # one cell when the spread is beyond floating point
    sx, sy = (x_hi - x_min) / cw + 1.0, (y_hi - y_min) / ch + 1.0
    limit = 4.0 * b.shape[0] + 1024
    if sx * sy > limit:
        grow = np.sqrt(sx * sy / limit)
        if sy < grow:
            cw = cw * (sx * sy / limit)
        elif sx < grow:
            ch = ch * (sx * sy / limit)
        else:
            cw, ch = cw * grow, ch * grow
    one_cell = not (np.isfinite(sx * sy) and np.isfinite(cw) and np.isfinite(ch))
    gx = np.zeros(b.shape[0], np.int64)
    gy = np.zeros(b.shape[0], np.int64)
    if not one_cell:
        for j in range(b.shape[0]):
            gx[j] = np.int64((b[j, 0] - x_min) / cw)
            gy[j] = np.int64((b[j, 1] - y_min) / ch)
    nx, ny = gx.max() + 1, gy.max() + 1
    counts = np.zeros(nx * ny + 1, np.int64)
    for j in range(b.shape[0]):
        counts[gy[j] * nx + gx[j] + 1] += 1
    starts = np.cumsum(counts)
    fill = starts[:-1].copy()
    order = np.empty(b.shape[0], np.int64)
    for j in range(b.shape[0]):
        k = gy[j] * nx + gx[j]
        order[fill[k]] = j
        fill[k] += 1
    cap = 8 * a.shape[0] + 16
    rows = np.empty(cap, np.int64)
    cols = np.empty(cap, np.int64)
    vals = np.empty(cap)
    n = 0
    for i in range(a.shape[0]):
        ax0, ay0, ax1, ay1 = a[i, 0], a[i, 1], a[i, 2], a[i, 3]
        area_a = (ax1 - ax0) * (ay1 - ay0)
        x_lo, x_hi, y_lo, y_hi = 0, 0, 0, 0
        if not one_cell:
            # clipped as floats first: a box far from every one of b would overflow the cast
            x_lo = np.int64(min(max(np.floor((ax0 - cw - x_min) / cw), 0.0), float(nx)))
            x_hi = np.int64(min(max(np.floor((ax1 - x_min) / cw), -1.0), nx - 1.0))
            y_lo = np.int64(min(max(np.floor((ay0 - ch - y_min) / ch), 0.0), float(ny)))
            y_hi = np.int64(min(max(np.floor((ay1 - y_min) / ch), -1.0), ny - 1.0))
        for cy in range(y_lo, y_hi + 1):
            for cx in range(x_lo, x_hi + 1):
                k = cy * nx + cx
                for q in range(starts[k], starts[k + 1]):
                    j = order[q]
                    iw = min(ax1, b[j, 2]) - max(ax0, b[j, 0])
                    ih = min(ay1, b[j, 3]) - max(ay0, b[j, 1])
                    if iw <= 0.0 or ih <= 0.0:
                        continue
                    inter = iw * ih
                    v = inter / (area_a + (b[j, 2] - b[j, 0]) * (b[j, 3] - b[j, 1]) - inter)
                    if not (v >= min_iou and v > 0.0):  # NaN too: areas beyond floating point
                        continue
                    if n == cap:
                        cap *= 2
                        rows2, cols2, vals2 = np.empty(cap, np.int64), np.empty(cap, np.int64), \
                            np.empty(cap)
                        for q2 in range(n):  # a loop: see filters._kernels.copy_vec
                            rows2[q2], cols2[q2], vals2[q2] = rows[q2], cols[q2], vals[q2]
                        rows, cols, vals = rows2, cols2, vals2
                    rows[n], cols[n], vals[n] = i, j, v
                    n += 1
    return rows[:n], cols[:n], vals[:n], True


@njit(cache=True)
def iou_pairs_same_class(a, a_cls, b, b_cls, min_iou):
    """:func:`iou_pairs` over the pairs of one class, compiled, for compiled callers too.

    Trackers never give two classes one identity, so only boxes of the same class are paired.

    Parameters
    ----------
    a : (N, 4) ndarray of float64
        Boxes ``x0, y0, x1, y1``.
    a_cls : (N,) ndarray of int64
        Their classes.
    b : (M, 4) ndarray of float64
        Boxes ``x0, y0, x1, y1``.
    b_cls : (M,) ndarray of int64
        Their classes.
    min_iou : float
        The least IoU of a pair kept (pairs must overlap too).

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The pairs ``(a[rows[k]], b[cols[k]])`` of one class whose IoU is at least ``min_iou``
        and > 0, by row.
    iou : (K,) ndarray
        Their IoU.
    ok : bool
        False, and the pairs empty, when a box is not finite.

    Raises
    ------
    ValueError
        If ``a_cls`` or ``b_cls`` does not hold one class per box (the classes would be read
        past their end).

    Examples
    --------
    >>> import numpy as np
    >>> a, b = np.array([[0, 0, 2, 2.0]]), np.array([[1, 0, 3, 2.0], [0, 0, 2, 2.0]])
    >>> r, c, v, ok = iou_pairs_same_class(a, np.array([1]), b, np.array([2, 1]), 0.1)
    >>> c.tolist(), v.tolist(), ok
    ([1], [1.0], True)
    """
    if a_cls.shape[0] != a.shape[0]:
        raise ValueError("a_cls must hold one class per box of a")
    if b_cls.shape[0] != b.shape[0]:
        raise ValueError("b_cls must hold one class per box of b")
    rows, cols, vals, ok = _grid_pairs(a, b, min_iou)
    same = a_cls[rows] == b_cls[cols]
    return rows[same], cols[same], vals[same], ok


_grid_pairs_py = kernel(_grid_pairs)
""":func:`_grid_pairs` for calls from Python (compiled code calls the numba function)."""


def iou_pairs(a: ArrayLike, b: ArrayLike,
              min_iou: float = 0.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The pairs of boxes whose IoU is at least ``min_iou``, without the dense matrix.

    The boxes of ``b`` are bucketed in a grid whose cells are as large as the largest box, so
    each box of ``a`` is compared with the boxes of a few cells only: 10,000 × 10,000 boxes
    spread over an image cost milliseconds.

    Parameters
    ----------
    a : (N, 4) array_like
        Boxes ``x0, y0, x1, y1``.
    b : (M, 4) array_like
        Boxes ``x0, y0, x1, y1``.
    min_iou : float
        The least IoU of a pair kept; pairs must overlap (IoU > 0) in any case.

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The pairs ``(a[rows[k]], b[cols[k]])``, by row.
    iou : (K,) ndarray
        Their IoU, as :func:`iou` gives it.

    Raises
    ------
    ValueError
        If a box is not finite, or ``a`` or ``b`` is not of shape ``(., 4)``.

    Examples
    --------
    >>> r, c, v = iou_pairs([[0, 0, 2, 2], [10, 10, 12, 12]], [[1, 0, 3, 2], [50, 50, 51, 51]])
    >>> r.tolist(), c.tolist(), v.round(3).tolist()
    ([0], [0], [0.333])
    """
    a, b = _boxes(a, "a"), _boxes(b, "b")
    # (NaN gave no pair, and turned non_maximum off; True was 1; "0.1" was taken)
    min_iou = as_finite(min_iou, "min_iou")
    if len(a) == 0 or len(b) == 0:
        return np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
    # (its finiteness flag is for compiled callers: _boxes has named a box that is not)
    rows, cols, vals, _ = _grid_pairs_py(np.ascontiguousarray(a), np.ascontiguousarray(b),
                                         min_iou)
    return rows, cols, vals


def overlapping_pairs(boxes: ArrayLike, classes: ArrayLike | None = None,
                      min_iou: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    """The pairs of two different boxes of one set, of one class, whose IoU is at least
    ``min_iou``, in both orders (:func:`iou_pairs` of the set with itself): one frame's
    detections that overlap, as duplicates of one object do.

    Parameters
    ----------
    boxes : (N, 4) array_like
        Boxes ``x0, y0, x1, y1``.
    classes : (N,) array_like of int, optional
        Their classes (default one class): boxes of two classes are never paired.
    min_iou : float
        The least IoU of a pair kept; pairs must overlap in any case.

    Returns
    -------
    rows, cols : (K,) ndarray of int64
        The pairs ``(boxes[rows[k]], boxes[cols[k]])``, ``rows[k] != cols[k]``.

    Examples
    --------
    >>> r, c = overlapping_pairs([[0, 0, 10, 10], [1, 0, 11, 10], [2, 0, 12, 10]], [0, 0, 1],
    ...                          min_iou=0.5)
    >>> r.tolist(), c.tolist()
    ([0, 1], [1, 0])
    """
    b = _boxes(boxes, "boxes")
    if classes is not None:
        cl = np.asarray(classes).reshape(-1)
        if len(cl) != len(b):
            raise ValueError(f"classes must have one value a box ({len(b)}); got {len(cl)}")
        # NaN equals no class, its own included: such boxes were never paired, and
        # non_maximum suppressed nothing among them (in an array of objects too)
        nan = np.array([v != v for v in cl.tolist()], bool) if cl.dtype.kind == "O" else (
            np.isnan(cl) if cl.dtype.kind in "fc" else np.zeros(len(cl), bool))
        if nan.any():
            raise ValueError(f"classes must be numbers; classes[{int(nan.argmax())}] is NaN")
    r, c, _ = iou_pairs(b, b, min_iou)
    keep = r != c
    if classes is not None:
        keep &= cl[r] == cl[c]
    return r[keep], c[keep]


def non_maximum(boxes: ArrayLike, scores: ArrayLike, classes: ArrayLike | None = None,
                min_iou: float = 0.7) -> np.ndarray:
    """Greedy non-maximum suppression: which boxes are kept when, from the most confident
    down, each box kept drops every less confident one of its class that overlaps it at IoU
    ``min_iou`` or more (ties in score by order).

    Parameters
    ----------
    boxes : (N, 4) array_like
        Boxes ``x0, y0, x1, y1``.
    scores : (N,) array_like
        Their scores (any scale: only their order counts).
    classes : (N,) array_like of int, optional
        Their classes (default one class): boxes of two classes never suppress each other.
    min_iou : float
        The IoU at which the less confident of two boxes is dropped. Boxes that do not
        overlap never suppress each other: at 0, any two that overlap at all (IoU > 0).

    Returns
    -------
    (N,) bool ndarray
        True for the boxes kept.

    Examples
    --------
    >>> non_maximum([[0, 0, 10, 10], [1, 0, 11, 10], [20, 0, 30, 10]], [0.8, 0.9, 0.5]).tolist()
    [False, True, True]
    >>> non_maximum([[0, 0, 10, 10], [1, 0, 11, 10]], [0.8, 0.9], classes=[0, 1]).tolist()
    [True, True]
    """
    b = _boxes(boxes, "boxes")  # (reshaped to (-1, 4): (2, 8) boxes were cut into four)
    # (text and booleans were read as numbers; complex ones lost their imaginary parts)
    s = as_float_array(scores, "scores", not_boolean="numbers").reshape(-1)
    if len(s) != len(b):
        raise ValueError(f"scores must have one value a box ({len(b)}); got {len(s)}")
    if np.isnan(s).any():  # (no place in the order: sorted last, as the least confident)
        raise ValueError(f"scores must be numbers; scores[{int(np.flatnonzero(np.isnan(s))[0])}]"
                         " is NaN")
    keep = np.ones(len(b), bool)
    if len(b) < 2:
        return keep
    r, k = overlapping_pairs(b, classes, min_iou)
    if not len(r):
        return keep
    order = np.lexsort((np.arange(len(b)), -s))  # most confident first, then by order
    rank = np.empty(len(b), np.int64)
    rank[order] = np.arange(len(b))
    weaker = rank[k] > rank[r]
    r, k = r[weaker], k[weaker]  # (stronger, weaker) pairs
    by = np.argsort(rank[r], kind="stable")
    r, k = r[by], k[by]
    for i, j in zip(r.tolist(), k.tolist()):
        if keep[i]:
            keep[j] = False
    return keep
