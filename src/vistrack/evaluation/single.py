"""Single-object tracking scores (OTB's measures) and ground-truth boxes of OTB and VOT.

- **success rate**: the fraction of frames whose IoU with the ground truth exceeds a threshold
  (0.5 by default); the **success curve** over thresholds 0, 0.05, ..., 1 and its mean, the
  area under it (AUC);
- **precision**: the fraction of frames whose centre error is at most 20 pixels.

Boxes are ``x, y, w, h`` (top-left corner and size), one per frame. Frames without a box are
scored as OTB's toolkit scores them (``calcSeqErrRobust``): a predicted box that is NaN or
of no size (a tracker that lost the object) stands for the last box before it, where the
ground truth has a box (a box with only some of its values NaN, or infinite, is a miss); a
frame whose ground truth is NaN or of no size (the object absent) counts as a failure for
success and as a hit for precision (an infinite true value is a box, and a miss, as OTB's
test takes it). (OTB also takes a true box whose ``x`` or ``y`` is 0 or
less, in its 1-based pixels, as absent; vistrack's boxes count from 0, and a box at the
image's edge is a box. OTB's toolkit also puts the ground truth's first box in place of the
tracker's, the frame it started from; vistrack scores the tracker's own first box, which may
come from a detection or be missing: with a NaN first box over four frames otherwise exact,
the AUC is 0.714 where OTB's toolkit gives 0.952.)
"""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike

from .._validate import as_finite, as_float_array, decode_text, text_number
from ..io.motchallenge import _text_lines
from ..io.tracks import write_boxes

__all__ = ["overlaps", "success_rate", "success_curve", "precision", "region_to_bbox",
           "read_boxes", "read_box_lines", "boxes_origin", "write_boxes"]


def _boxes(value: ArrayLike, name: str, k: int = 4) -> np.ndarray:
    """``(T, k)`` from ``(T, k)`` or one ``(k,)``; anything else named (a ``(4, T)`` array was
    read row by row as other boxes, and 5 values failed in numpy's reshape)."""
    # (booleans were boxes of 1s, complex values their real parts, text and ragged rows
    # numpy's words naming neither argument)
    a = as_float_array(value, name, not_boolean="x, y, w, h" if k == 4 else f"rows of {k} "
                       "numbers")
    if a.ndim == 1 and a.shape[0] == k:
        a = a[None]
    if a.ndim != 2 or a.shape[1] != k:
        raise ValueError(f"{name} must be (T, {k}), one row a frame, or one ({k},); got shape "
                         f"{a.shape}")
    return a


def _pair(pred: ArrayLike, gt: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    p, g = _boxes(pred, "pred"), _boxes(gt, "gt")
    if p.shape != g.shape:
        raise ValueError(f"pred and gt must have one box per frame; got {len(p)} and {len(g)}")
    if not len(p):
        raise ValueError("pred and gt have no boxes: nothing to score")
    return p, g


def _has_box(b: np.ndarray) -> np.ndarray:
    # absent: a NaN, or no size; an infinite value is a box (a miss), as OTB's test
    # (every value > 0 or not NaN) takes it, where it was an absent object, a hit
    return ~np.isnan(b).any(axis=1) & (b[:, 2] > 0) & (b[:, 3] > 0)


def _otb(pred: ArrayLike, gt: ArrayLike) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The boxes as OTB scores them (see the module): each predicted box that is wholly NaN
    or of no size replaced by the one before it where the truth has no NaN, and which frames'
    ground truth has a box. (OTB's test is MATLAB's ``if`` over the four values, true when
    all are: a box with some values NaN and a size is kept, and scores a miss.)"""
    p, g = _pair(pred, gt)
    p = p.copy()
    with np.errstate(invalid="ignore"):
        gone = np.isnan(p).all(axis=1) | (p[:, 2] <= 0) | (p[:, 3] <= 0)
    lost = gone & ~np.isnan(g).any(axis=1)
    for i in np.flatnonzero(lost):
        if i > 0:
            p[i] = p[i - 1]
    return p, g, _has_box(g)


def overlaps(pred: ArrayLike, gt: ArrayLike) -> np.ndarray:
    """IoU of each frame's predicted and true box.

    Parameters
    ----------
    pred, gt : (T, 4) array_like
        Boxes ``x, y, w, h``, one per frame.

    Returns
    -------
    (T,) ndarray
        IoU in [0, 1]; 0 where the union is empty.

    Examples
    --------
    >>> overlaps([[0, 0, 10, 10], [5, 0, 10, 10]], [[0, 0, 10, 10], [0, 0, 10, 10]]).round(3)
    array([1.   , 0.333])
    """
    p, g = _pair(pred, gt)
    return _iou(p, g)


def _iou(p: np.ndarray, g: np.ndarray) -> np.ndarray:
    iw = np.clip(np.minimum(p[:, 0] + p[:, 2], g[:, 0] + g[:, 2]) - np.maximum(p[:, 0], g[:, 0]),
                 0, None)
    ih = np.clip(np.minimum(p[:, 1] + p[:, 3], g[:, 1] + g[:, 3]) - np.maximum(p[:, 1], g[:, 1]),
                 0, None)
    inter = iw * ih
    union = p[:, 2] * p[:, 3] + g[:, 2] * g[:, 3] - inter
    # at most 1: a box and itself gave 1.0000000000000004 in 39 % of random float boxes,
    # which passed the success curve's last threshold (IoU > 1)
    return np.minimum(np.divide(inter, union, out=np.zeros_like(inter), where=union > 0), 1.0)


def success_rate(pred: ArrayLike, gt: ArrayLike, threshold: float = 0.5) -> float:
    """Success rate: the fraction of frames whose IoU with the ground truth exceeds a threshold.

    Parameters
    ----------
    pred, gt : (T, 4) array_like
        Boxes ``x, y, w, h``, one per frame.
    threshold : float
        The IoU to exceed (strictly).

    Returns
    -------
    float
        In [0, 1].

    Raises
    ------
    ValueError
        If ``pred`` or ``gt`` is not ``(T, 4)`` (or one box), they differ in length, or
        they hold no box; or ``threshold`` is not a number in [0, 1] (a TypeError for what
        is no number).

    References
    ----------
    .. [1] Y. Wu, J. Lim and M.-H. Yang, "Online object tracking: a benchmark", CVPR 2013.

    Examples
    --------
    >>> success_rate([[0, 0, 10, 10], [5, 0, 10, 10]], [[0, 0, 10, 10], [0, 0, 10, 10]])
    0.5
    """
    # (NaN scored 0 without a word, and an array was taken as a threshold per frame)
    threshold = as_finite(threshold, "threshold", 0, high=1, what="IoU")
    return float(np.mean(_otb_overlaps(pred, gt) > threshold))


def _otb_overlaps(pred: ArrayLike, gt: ArrayLike) -> np.ndarray:
    """Each frame's IoU as OTB scores it: -1 where the ground truth has no box."""
    p, g, has = _otb(pred, gt)
    with np.errstate(invalid="ignore"):
        return np.where(has, _iou(p, g), -1.0)


def success_curve(pred: ArrayLike, gt: ArrayLike) -> tuple[np.ndarray, np.ndarray, float]:
    """The success curve over IoU thresholds 0, 0.05, ..., 1, and the area under it (OTB).

    Parameters
    ----------
    pred, gt : (T, 4) array_like
        Boxes ``x, y, w, h``, one per frame.

    Returns
    -------
    thresholds : (21,) ndarray
        0, 0.05, ..., 1.
    rates : (21,) ndarray
        :func:`success_rate` at each threshold.
    auc : float
        The mean of ``rates``: OTB's area under the curve.

    Raises
    ------
    ValueError
        If ``pred`` or ``gt`` is not ``(T, 4)`` (or one box), they differ in length, or
        they hold no box.

    References
    ----------
    .. [1] Y. Wu, J. Lim and M.-H. Yang, "Online object tracking: a benchmark", CVPR 2013.

    Examples
    --------
    >>> th, rates, auc = success_curve([[0, 0, 10, 10], [5, 0, 10, 10]],
    ...                                [[0, 0, 10, 10], [0, 0, 10, 10]])
    >>> rates[[0, 6, 10, 20]], round(auc, 3)     # IoU 1 and 1/3
    (array([1. , 1. , 0.5, 0. ]), 0.643)
    """
    th = np.linspace(0, 1, 21)
    v = _otb_overlaps(pred, gt)
    rates = np.array([np.mean(v > t) for t in th])
    return th, rates, float(rates.mean())


def precision(pred: ArrayLike, gt: ArrayLike, threshold: float = 20.0) -> float:
    """Precision: the fraction of frames whose box centres are at most ``threshold`` apart.

    Parameters
    ----------
    pred, gt : (T, 4) array_like
        Boxes ``x, y, w, h``, one per frame.
    threshold : float
        The largest centre distance, in pixels (OTB: 20).

    Returns
    -------
    float
        In [0, 1].

    Raises
    ------
    ValueError
        If ``pred`` or ``gt`` is not ``(T, 4)`` (or one box), they differ in length, or
        they hold no box; or ``threshold`` is not a finite number >= 0 (a TypeError for what
        is no number).

    References
    ----------
    .. [1] Y. Wu, J. Lim and M.-H. Yang, "Online object tracking: a benchmark", CVPR 2013.

    Examples
    --------
    >>> precision([[0, 0, 10, 10], [30, 0, 10, 10]], [[0, 0, 10, 10], [0, 0, 10, 10]])
    0.5
    """
    threshold = as_finite(threshold, "threshold", 0, what="number of pixels")
    p, g, has = _otb(pred, gt)
    with np.errstate(invalid="ignore"):
        d = np.linalg.norm((p[:, :2] + p[:, 2:] / 2) - (g[:, :2] + g[:, 2:] / 2), axis=1)
    return float(np.mean(np.where(has, d <= threshold, True)))  # OTB: absent counts as a hit


def region_to_bbox(polygons: ArrayLike, rule: str = "area") -> np.ndarray:
    """Axis-aligned ``x, y, w, h`` boxes of VOT's rotated boxes (four corners).

    ``rule="area"``: the box centred on the corners' mean with the rotated box's area and the
    corners' aspect ratio (SiamFC's ``region_to_bbox``), whose width and height, as its,
    count pixels inclusively (``+ 1``); ``"minmax"``: the corners' bounding box (larger by up
    to twice for a box turned 45°), as VOT's toolkit converts a polygon to a rectangle. A
    polygon of no area (all corners on a point or one line: the object absent) is a box of no
    size, ``w = h = 0``, under either rule, which success and precision score as absent
    (SiamFC's gives NaN there; a 1 × 1 box was made of it, scored as a box).

    Parameters
    ----------
    polygons : (T, 8) array_like
        Corners ``x1, y1, ..., x4, y4`` of each frame's box, in order around it.
    rule : {'area', 'minmax'}
        How to make the box axis-aligned.

    Returns
    -------
    (T, 4) ndarray
        Boxes ``x, y, w, h``.

    Raises
    ------
    ValueError
        If ``rule`` is not one of the two names.

    Examples
    --------
    An upright 4 × 2 box: ``"area"`` adds the pixel to its width and height, ``"minmax"``
    keeps it.

    >>> region_to_bbox([[0, 0, 4, 0, 4, 2, 0, 2]]).tolist()
    [[-0.5, -0.5, 5.0, 3.0]]
    >>> region_to_bbox([[0, 0, 4, 0, 4, 2, 0, 2]], rule="minmax").tolist()
    [[0.0, 0.0, 4.0, 2.0]]
    """
    q = _boxes(polygons, "polygons", 8)
    xs, ys = q[:, 0::2], q[:, 1::2]
    x1, x2, y1, y2 = xs.min(1), xs.max(1), ys.min(1), ys.max(1)
    _check_rule(rule)
    if rule == "minmax":
        none = _no_area(xs, ys)
        return np.c_[x1, y1, np.where(none, 0.0, x2 - x1), np.where(none, 0.0, y2 - y1)]
    cx, cy = xs.mean(1), ys.mean(1)
    a1 = np.linalg.norm(q[:, 0:2] - q[:, 2:4], axis=1) * np.linalg.norm(q[:, 2:4] - q[:, 4:6],
                                                                         axis=1)
    a2 = (x2 - x1) * (y2 - y1)
    s = np.sqrt(np.divide(a1, a2, out=np.ones_like(a1), where=a2 > 0))
    w, h = s * (x2 - x1) + 1, s * (y2 - y1) + 1
    none = _no_area(xs, ys)
    w, h = np.where(none, 0.0, w), np.where(none, 0.0, h)
    return np.c_[np.where(none, cx, cx - w / 2), np.where(none, cy, cy - h / 2), w, h]


def _check_rule(rule: str) -> None:
    if rule not in ("area", "minmax"):
        raise ValueError(f"rule must be 'area' or 'minmax'; got {rule!r}")


def _no_area(xs: np.ndarray, ys: np.ndarray) -> np.ndarray:
    """Which polygons (corners ``xs, ys`` in order) enclose no area, their corners on a point
    or on any one line (the shoelace formula's zero, however the line runs, and not a
    crossed order's: a bow tie's halves cancel), or have a corner that is not finite: the
    object absent."""
    area = 0.5 * np.abs((xs * np.roll(ys, -1, axis=1) - np.roll(xs, -1, axis=1) * ys).sum(1))
    # a crossed order (a square's corners as a bow tie) sums to no area too, its corners on
    # no one line: not absent (it was, and an exact prediction scored 0 there)
    dx, dy = xs - xs[:, :1], ys - ys[:, :1]
    flat = (dx[:, :, None] * dy[:, None, :] == dy[:, :, None] * dx[:, None, :]).all((1, 2))
    return ~np.isfinite(area) | ((area == 0) & flat)


_OTB_NAME = re.compile(r"groundtruth_rect(\.\d+)?\.txt")


def read_boxes(path: str | Path, rule: str = "area", origin: int | None = None) -> np.ndarray:
    """Ground-truth or result boxes ``x, y, w, h`` from a text file.

    - OTB ``groundtruth_rect.txt`` (``groundtruth_rect.1.txt``, ``.2.txt`` for a sequence of
      two objects): ``x y w h`` (tabs, spaces or commas), 1-based pixels,
      returned 0-based;
    - VOT ``groundtruth.txt``: 8 values a line, converted by :func:`region_to_bbox`;
    - vistrack's ``boxes.txt``: ``frame,x,y,w,h``, whose frames must count up by one (the
      lines are taken in order: a file reversed, or with a frame left out, was scored
      against the wrong frames).

    Other files of 4 values a line are read as they are. Blank lines are skipped.

    Parameters
    ----------
    path : str or Path
        The file.
    rule : {'area', 'minmax'}
        For polygons: see :func:`region_to_bbox`.
    origin : {0, 1}, optional
        Where the pixels of ``x y w h`` lines count from: 1 (OTB's), returned 0-based, or 0.
        None: by the file's name, 1 for OTB's ``groundtruth_rect.txt`` (and ``.1.txt``,
        ``.2.txt``), 0 for any other name (a copy of OTB's file under another name is read
        from 0: :func:`boxes_origin` says which a file was read with).

    Returns
    -------
    (T, 4) ndarray
        One box per line.

    Raises
    ------
    ValueError
        If the file is not UTF-8 text, a line is not numbers, not 4, 5 or 8 of them, or not
        as many as the line before, or (``frame,x,y,w,h``) its frame is not a whole number or
        not the one after the line before's, or a blank line comes before a box of ``x y w
        h`` or polygon lines, which number their frames by line (blank lines at the end are
        left alone); the message names the file and line.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "groundtruth_rect.txt"
    >>> _ = path.write_text("11,21,30,40\\n12,21,30,40\\n")
    >>> read_boxes(path).tolist()                   # OTB: 1-based, returned 0-based
    [[10.0, 20.0, 30.0, 40.0], [11.0, 20.0, 30.0, 40.0]]
    """
    return read_box_lines(path, rule, origin)[0]


def read_box_lines(path: str | Path, rule: str = "area",
                   origin: int | None = None) -> tuple[np.ndarray, int]:
    """:func:`read_boxes`, and how many values the file's lines hold: 4 (``x y w h``, the
    only lines whose ``origin`` matters), 5 (``frame,x,y,w,h``) or 8 (a polygon); 0 for a
    file of no lines.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "boxes.txt"
    >>> _ = path.write_text("1,10,20,30,40\\n")
    >>> read_box_lines(path)
    (array([[10., 20., 30., 40.]]), 5)
    """
    return _read_box_rows(path, rule, origin)[:2]


def _read_box_rows(path: str | Path, rule: str = "area", origin: int | None = None
                   ) -> tuple[np.ndarray, int, int | None]:
    """:func:`read_box_lines`, and the first line's frame number for ``frame,x,y,w,h``
    lines (None for others, which number their frames by line)."""
    if not (origin is None or (isinstance(origin, (int, np.integer))
                               and not isinstance(origin, bool) and origin in (0, 1))):
        raise ValueError(f"origin must be 0, 1 or None (by the file's name); got {origin!r}")
    _check_rule(rule)  # (checked only where the file held polygons)
    path = Path(path)
    rows: list[list[float]] = []
    last = 0  # the line of rows[-1]
    # lines as editors count them, as the MOTChallenge reader does (str.splitlines also
    # breaks at a form feed, which made a box line two)
    # UTF-8 whatever the locale, a byte-order mark dropped, the file named where it is not text
    text = decode_text(path.read_bytes(), path, "boxes", ValueError)
    blank = 0  # the first blank line not yet followed by a box
    for n, line in enumerate(_text_lines(text), start=1):
        if not line.strip():
            blank = blank or n
            continue
        try:
            vals = [text_number(v) for v in line.replace(",", " ").replace("\t", " ").split()]
        except ValueError:
            raise ValueError(f"{path}:{n}: not numbers: {line.strip()!r}") from None
        if len(vals) not in (4, 5, 8):
            raise ValueError(f"{path}:{n}: expected 4 (x y w h), 5 (frame,x,y,w,h) or 8 "
                             f"(polygon) values; got {len(vals)}")
        if rows and len(vals) != len(rows[-1]):
            raise ValueError(f"{path}:{n}: {len(vals)} values after lines of {len(rows[-1])}")
        if blank and len(vals) != 5:
            # a line is a frame: skipped, it put every later box a frame early
            # (the advice gave 4 NaNs where the file's lines hold 8, a polygon's: following it
            # met "4 values after lines of 8")
            nans = ",".join(["NaN"] * len(vals))
            raise ValueError(f"{path}:{blank}: a blank line before the box of line {n}: each "
                             f"line is one frame's box ({nans} for a frame without one)")
        blank = 0
        if len(vals) == 5 and not float(vals[0]).is_integer():
            # (200.5, 201.5, ... counted up by one, and left the first frame unsaid: the
            # boxes were scored against the video's frames from 1, without a word)
            raise ValueError(f"{path}:{n}: frame {vals[0]:g} is not a whole number (the "
                             "first value of a frame,x,y,w,h line is a frame number)")
        if len(vals) == 5 and rows and vals[0] != rows[-1][0] + 1:
            raise ValueError(f"{path}:{n}: frame {vals[0]:g} after frame {rows[-1][0]:g} (line "
                             f"{last}): the frames of frame,x,y,w,h lines must count up "
                             "by one")
        rows.append(vals)
        last = n
    a = np.array(rows, dtype=float)
    if a.size == 0:
        return np.zeros((0, 4)), 0, None
    if a.shape[1] == 8:
        return region_to_bbox(a, rule), 8, None
    if a.shape[1] == 5:
        return a[:, 1:], 5, int(a[0, 0])
    if boxes_origin(path) if origin is None else origin:  # OTB: 1-based pixels
        a[:, :2] -= 1
    return a, 4, None


def boxes_origin(path: str | Path) -> int:
    """Where :func:`read_boxes` counts the pixels of a file of ``x y w h`` lines from, by its
    name: 1 for OTB's ``groundtruth_rect.txt`` (``groundtruth_rect.1.txt`` for a sequence's
    second object, as Jogging's), 0 for any other.

    Examples
    --------
    >>> boxes_origin("Crossing/groundtruth_rect.txt"), boxes_origin("crossing_gt.txt")
    (1, 0)
    """
    return 1 if _OTB_NAME.fullmatch(Path(path).name) else 0
