r"""Multi-object tracking scores: CLEAR MOT, identity (IDF1) and HOTA, as MOTChallenge computes
them.

The conventions are TrackEval's (Luiten and Hoffhues, 2020), the official MOTChallenge scorer,
and the numbers equal it on the same files (the tests compare every field):

- boxes match when their IoU is at least 0.5 (CLEAR, identity); HOTA averages over the IoU
  thresholds :math:`\alpha = 0.05, 0.10, \dots, 0.95`;
- **preprocessing** of MOT16/17/20 ground truth: predicted boxes matched (IoU ≥ 0.5, Hungarian)
  to a distractor (person on vehicle, static person, distractor, reflection; for MOT20 also
  non-MOT vehicle) are removed; then only pedestrians with the "consider" flag set are kept as
  ground truth. MOT15 ground truth has no classes (its class column is -1): nothing is removed
  but boxes flagged 0;
- **ID switches** (CLEAR): a ground-truth object matched to a different predicted id than at
  its last match, however long ago. The matching at each frame prefers the previous frame's
  pairs (Bernardin and Stiefelhagen, 2008), as TrackEval's. py-motmetrics prefers each
  object's last pair however many frames ago it was matched (a track gone for a frame and
  back within the threshold is taken again, where TrackEval may match another), and counts
  fewer switches on some sequences (12 against 24 on ADL-Rundle-6 with the tests' noisy
  predictions; IDF1 equal);
- **IDF1** from the one-to-one matching of whole ground-truth and predicted trajectories that
  maximises the matched detections (Ristani et al., 2016);
- **HOTA** :math:`= \sqrt{\text{DetA} \cdot \text{AssA}}` per threshold, averaged
  (Luiten et al., 2021, "HOTA: A Higher Order Metric for Evaluating Multi-Object Tracking").

Several sequences combine as MOTChallenge's COMBINED row: counts add up; AssA, AssRe, AssPr and
LocA are averaged weighted by each sequence's true positives.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validate import as_rows4, as_whole, decode_text, text_number
from ..io.motchallenge import (
    MOTTable,
    _row_cells,
    _shown,
    _text_lines,
    _text_without_header,
)

_LSA: list[Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]] = []


def linear_sum_assignment(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """scipy's ``linear_sum_assignment`` (TrackEval's), loaded at the first call
    (:func:`_scipy_lsa`)."""
    if not _LSA:
        _LSA.append(_scipy_lsa())
    return _LSA[0](cost)


def _scipy_lsa() -> Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """scipy's ``linear_sum_assignment``: the function of its extension module
    ``scipy.optimize._lsap``, loaded on its own where it can be, else the public import.

    ``import scipy.optimize`` takes about 0.3 s (its ``__init__`` imports the whole package),
    most of ``vistrack eval``'s time on a small file; the extension alone loads in about 10 ms.
    scipy's ``__init__`` exports that extension's function as it is; where its layout differs
    (another scipy version) the public import is used."""
    import sys

    public = sys.modules.get("scipy.optimize")
    if public is None:
        try:
            import importlib.machinery
            import importlib.util

            import scipy

            folder = Path(scipy.__file__).parent / "optimize"
            for suffix in importlib.machinery.EXTENSION_SUFFIXES:
                path = folder / f"_lsap{suffix}"
                if path.is_file():
                    loader = importlib.machinery.ExtensionFileLoader("scipy.optimize._lsap",
                                                                     str(path))
                    spec = importlib.util.spec_from_loader(loader.name, loader)
                    assert spec is not None
                    module = importlib.util.module_from_spec(spec)
                    loader.exec_module(module)
                    fn = module.linear_sum_assignment
                    if callable(fn):
                        return fn
        except Exception:  # noqa: BLE001 - any failure: the public import below
            pass
    from scipy.optimize import linear_sum_assignment as lsa

    return lsa

__all__ = ["MOTCounts", "evaluate_mot", "combine", "box_iou_xywh", "point_similarity", "ALPHAS",
           "Matches", "clear_matches", "SCORE_COLUMNS", "considered"]

SCORE_COLUMNS = (("HOTA", True), ("DetA", True), ("AssA", True), ("MOTA", True),
                 ("MOTP", True), ("IDF1", True), ("IDP", True), ("IDR", True), ("TP", False),
                 ("FP", False), ("FN", False), ("IDSW", False), ("Frag", False), ("MT", False),
                 ("PT", False), ("ML", False))
"""The columns of a score table (``vistrack eval``, ``vistrack report``): each key of
:meth:`MOTCounts.summary` and whether it is a fraction shown as a percentage."""

ALPHAS = np.arange(0.05, 0.99, 0.05)
"""HOTA's IoU thresholds: 0.05, 0.10, ..., 0.95."""

_EPS = np.finfo(float).eps
_DISTRACTORS = {"MOT16": (2, 7, 8, 12), "MOT17": (2, 7, 8, 12), "MOT20": (2, 6, 7, 8, 12)}


def box_iou_xywh(a: ArrayLike, b: ArrayLike) -> np.ndarray:
    """IoU of every box of ``a`` with every box of ``b``, boxes as ``left, top, width, height``.

    Any finite boxes give an IoU in [0, 1], however large their numbers: a pair with a value
    beyond 2**500, whose areas or right edges could overflow, is computed with each axis scaled
    by a power of two (which leaves the IoU as it is). As in any float sum, a right edge
    ``left + width`` is rounded: a width below the spacing of floats at ``left`` is lost.

    Parameters
    ----------
    a : (N, 4) array_like
        Boxes ``left, top, width, height`` (MOTChallenge files).
    b : (M, 4) array_like
        Boxes ``left, top, width, height``.

    Returns
    -------
    (N, M) ndarray
        IoU in [0, 1]; 0 where the union is empty (at most machine epsilon).

    Raises
    ------
    ValueError
        If ``a`` or ``b`` is not rows of 4 values (one row ``(4,)`` is taken as one box).

    See Also
    --------
    vistrack.association.iou : The same for boxes ``x0, y0, x1, y1``.

    Examples
    --------
    >>> box_iou_xywh([[0, 0, 10, 10]], [[5, 0, 10, 10], [0, 0, 10, 10]]).round(3)
    array([[0.333, 1.   ]])
    >>> box_iou_xywh([[0, 0, 1e300, 1e300]], [[0, 0, 1e300, 5e299]])
    array([[0.5]])
    """
    a, b = _rows4(a, "a"), _rows4(b, "b")
    big_a, big_b = (np.abs(a) > _BIG).any(1), (np.abs(b) > _BIG).any(1)
    if not (big_a.any() or big_b.any()):
        return _iou(a, b)
    with np.errstate(over="ignore", invalid="ignore"):
        out = _iou(a, b)
    i, j = np.nonzero(big_a[:, None] | big_b[None, :])
    out[i, j] = _iou_scaled(a[i], b[j])
    return out


_BIG = 2.0 ** 500  # below it, no sum or product of the IoU overflows


def _rows4(x: ArrayLike, name: str) -> np.ndarray:
    """``x`` as rows ``left, top, width, height`` (:func:`~vistrack._validate.as_rows4`: a
    VOT polygon's 8 values a row, or a transposed array, were read as other boxes)."""
    return as_rows4(x, name, "left, top, width, height")


def point_similarity(a: ArrayLike, b: ArrayLike, zero_distance: float) -> np.ndarray:
    """The similarity of every position of ``a`` with every position of ``b``,
    ``max(0, 1 - d / zero_distance)`` for ``d`` their Euclidean distance: TrackEval's for
    points (its ``_calculate_euclidean_similarity``), where a box's IoU would not do. A match
    (similarity 0.5 or more, as IoU 0.5 for boxes) lies within half of ``zero_distance``.

    Parameters
    ----------
    a : (N, 4) array_like
        Rows ``left, top, width, height``, each scored at its centre; a point is a row of
        width and height 0 at it.
    b : (M, 4) array_like
        The same.
    zero_distance : float
        The distance at which the similarity falls to 0 (finite, > 0).

    Returns
    -------
    (N, M) ndarray
        In [0, 1].

    Raises
    ------
    ValueError
        If ``a`` or ``b`` is not rows of 4 values, or ``zero_distance`` is not a finite
        number > 0.

    Examples
    --------
    >>> point_similarity([[0, 0, 0, 0]], [[3, 4, 0, 0], [1, 0, 0, 0], [0, 0, 2, 2]],
    ...                  zero_distance=10).round(3)
    array([[0.5  , 0.9  , 0.859]])
    """
    a, b = _rows4(a, "a"), _rows4(b, "b")
    # (0, negative or NaN gave similarities of 0, above 1 or NaN, with a RuntimeWarning at most)
    zero_distance = check_zero_distance(zero_distance)
    # the centres halved, which no finite row overflows (x + w / 2 near 1.7e308 was inf, and
    # inf - inf a NaN that SciPy's assignment refused, naming nothing): exact, a power of 2;
    # a distance past the largest float is inf, a similarity of 0
    ca, cb = a[:, :2] / 2 + a[:, 2:] / 4, b[:, :2] / 2 + b[:, 2:] / 4
    with np.errstate(over="ignore"):
        dist = 2 * np.linalg.norm(ca[:, np.newaxis] - cb[np.newaxis, :], axis=2)
        return np.maximum(0, 1 - dist / zero_distance)


def _similarity(gt: MOTTable, pred: MOTTable, zero_distance: float | None
                ) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """The similarity of a frame's rows: the boxes' IoU, or with ``zero_distance`` the
    positions' (:func:`point_similarity`). Points (rows of no width and height) without it
    are an error naming it: every IoU would be 0, every object missed."""
    if zero_distance is None:
        for table, what in ((gt, "ground truth"), (pred, "prediction")):
            if len(table) and not (table.boxes[:, 2:] > 0).any():
                raise ValueError(
                    f"{table.path or 'the ' + what}: every row is a point (no width or "
                    "height), which no IoU can score: score positions by distance, "
                    "zero_distance= (vistrack eval --zero-distance PX), the distance at which "
                    "a pair counts for nothing; a match lies within half of it")
        return box_iou_xywh
    zero = check_zero_distance(zero_distance)
    return lambda a, b: point_similarity(a, b, zero)


def check_zero_distance(zero_distance: Any) -> float:
    """``zero_distance`` as a float, or a ValueError naming it: a finite number > 0."""
    try:
        ok = not isinstance(zero_distance, bool) and math.isfinite(zero_distance) \
            and zero_distance > 0
    except TypeError:
        ok = False
    if not ok:
        raise ValueError(f"zero_distance must be a finite number > 0 (the distance at which a "
                         f"pair's similarity falls to 0); got {zero_distance!r}")
    return float(zero_distance)


def _iou(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    # TrackEval's operations, in its order (corners first, each area from its corners): a
    # pair whose IoU is 0.5 in exact arithmetic rounds to the same side of the threshold,
    # and two pairs equal in exact arithmetic rank the same way, as in its scores. (Areas as
    # w * h round differently in the last bits for decimals such as 813.27.)
    ax0, ay0, ax1, ay1 = a[:, 0:1], a[:, 1:2], a[:, 0:1] + a[:, 2:3], a[:, 1:2] + a[:, 3:4]
    bx0, by0, bx1, by1 = b[:, 0], b[:, 1], b[:, 0] + b[:, 2], b[:, 1] + b[:, 3]
    inter = (np.maximum(np.minimum(ax1, bx1) - np.maximum(ax0, bx0), 0)
             * np.maximum(np.minimum(ay1, by1) - np.maximum(ay0, by0), 0))
    area_a, area_b = (ax1 - ax0) * (ay1 - ay0), (bx1 - bx0) * (by1 - by0)
    union = area_a + area_b - inter
    inter[(area_a <= _EPS)[:, 0], :] = 0.0
    inter[:, area_b <= _EPS] = 0.0
    inter[union <= _EPS] = 0.0
    union[union <= _EPS] = 1.0
    return inter / union


def _iou_scaled(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The IoU of the pairs ``a[k]``, ``b[k]``, each axis scaled by the power of two that brings
    the pair's largest value on it below 1 (exact, unless a value becomes subnormal): no sum or
    product can overflow. Used for boxes with values beyond :data:`_BIG`."""
    cols = []
    for pos, size in ((0, 2), (1, 3)):  # the x axis, then the y axis
        v = np.stack([a[:, pos], a[:, size], b[:, pos], b[:, size]], axis=1)
        v = np.ldexp(v, -np.frexp(np.abs(v).max(1))[1][:, None])
        a1, b1 = v[:, 0] + v[:, 1], v[:, 2] + v[:, 3]  # as _iou: corners first
        lo = np.maximum(v[:, 0], v[:, 2])
        hi = np.minimum(a1, b1)
        cols.append((np.clip(hi - lo, 0, None), a1 - v[:, 0], b1 - v[:, 2]))
    (iw, aw, bw), (ih, ah, bh) = cols
    inter = iw * ih
    union = aw * ah + bw * bh - inter
    return np.where(union > 0, np.minimum(1.0, inter / np.where(union > 0, union, 1.0)), 0.0)


@dataclass
class _Sequence:
    gt_ids: list  # per frame with a row, contiguous ids 0 .. n_gt_ids - 1
    pred_ids: list
    sim: list  # per such frame (n_gt_t, n_pred_t) IoU
    n_gt_ids: int
    n_pred_ids: int
    frames: np.ndarray | None = None  # the frame of each entry above
    gt_labels: np.ndarray | None = None  # the files' ids of the contiguous ones
    pred_labels: np.ndarray | None = None


BENCHMARKS = ("auto", "MOT15", "MOT16", "MOT17", "MOT20")
"""The scoring conventions ``benchmark`` names (``auto``: MOT17's for a ground truth whose
column 8 holds MOT16/17/20 classes, 1-13, in every row, MOT15's otherwise). MOT20's classes
are MOT17's, so ``auto`` cannot tell its ground truth apart: name ``MOT20`` for it, whose
predictions on a non-motorised vehicle (class 6) TrackEval ignores and MOT17's rules count
as false positives."""


def _benchmark_of(gt: MOTTable, benchmark: str) -> str:
    if benchmark != "auto":
        if benchmark not in BENCHMARKS:
            raise ValueError(f"benchmark must be one of {', '.join(map(repr, BENCHMARKS))}; "
                             f"got {benchmark!r}")
        return benchmark
    # a column 8 of classes, whatever follows it: with 8 or 10 columns a distractor (class 7)
    # was scored as a person to find, where TrackEval reads column 8 as the class of any row
    # of 8 values or more (MOT15's 10 columns hold a world x there, read as no class)
    has_classes = gt.columns >= 8 and len(gt) and np.isin(gt.classes, np.arange(1, 14)).all()
    return "MOT17" if has_classes else "MOT15"


def considered(conf: np.ndarray) -> np.ndarray:
    """Which ground-truth rows are scored by their flag (column 7, ``conf``), as TrackEval
    reads it: the flag as an integer (truncated, ``int(0.5)`` is 0), other than 0. A row of
    0.5 was scored where TrackEval ignores it (MOTA 1.0 against its 0.0 on one such row).

    Examples
    --------
    >>> considered(np.array([1.0, 0.0, 0.5, -1.0, 1.5, -0.5])).tolist()
    [True, False, False, True, True, False]
    """
    return np.trunc(np.asarray(conf, dtype=np.float64)) != 0


def scored_truth(gt: MOTTable, benchmark: str = "auto") -> np.ndarray:
    """Which rows of the ground truth ``gt`` are scored, found or missed, under
    ``benchmark``'s convention (as :func:`evaluate_mot` takes it): a flag other than 0
    (:func:`considered`), and under MOT16/17/20's a pedestrian (class 1); the others are
    ignored, or distractors.

    Examples
    --------
    >>> gt = MOTTable.from_rows([(1, 1, 0, 0, 5, 9, 1, 1, 1.0), (1, 2, 9, 0, 5, 9, 0, 1, 1.0),
    ...                          (1, 3, 20, 0, 5, 9, 1, 7, 1.0)])
    >>> scored_truth(gt).tolist(), scored_truth(gt, "MOT15").tolist()
    ([True, False, False], [True, False, True])
    """
    keep = considered(gt.conf)
    if _benchmark_of(gt, benchmark) != "MOT15":
        keep &= gt.classes == 1
    return keep


def _lines_of(path: str, match: Callable[[list[float]], bool]) -> list[int]:
    """The lines (from 1) of the MOTChallenge file ``path`` whose row ``match`` accepts, for a
    message; empty for a table not read from a file (or a file no longer readable), and for
    a CSV or Parquet file with a header, whose columns need not start with frame and id (the
    message then names the file, the frame and the id): a ``.csv`` of MOTChallenge's text,
    without one, is read as text, and its lines are named as a ``.txt``'s."""
    suffix = Path(path).suffix.lower() if path else ""
    if not path or suffix == ".parquet" or (
            suffix == ".csv" and not _text_without_header(Path(path))):
        return []
    try:
        text = decode_text(Path(path).read_bytes(), path, "MOTChallenge", ValueError)
    except (OSError, ValueError):
        return []
    found = []
    for k, raw in enumerate(_text_lines(text), start=1):  # as read_mot counts lines
        try:  # a row's values as read_mot splits them (commas, or spaces and tabs); a blank
            # or comment line (np.loadtxt skips those) is not a row
            row = [text_number(c) for c in _row_cells(raw)]
        except ValueError:
            continue
        if len(row) >= 6 and match(row):
            found.append(k)
    return found


def _class_row(table: MOTTable, what: str, bad: Callable[[float], bool]
               ) -> tuple[str, float | None]:
    """Where the first row of ``table`` whose class (column 8) ``bad`` accepts is (``path,
    line 4, column 8 (class)``, or the file alone), and its class as written (3.5, 1e30;
    None when no line is found)."""
    seen: list[float] = []

    def first(row: list[float]) -> bool:
        if len(row) > 7 and bad(row[7]) and not seen:
            seen.append(row[7])
            return True
        return False

    lines = _lines_of(table.path, first)[:1]
    return (_where(table, what, lines) + (", column 8 (class)" if lines else ""),
            seen[0] if seen else None)


def _where(table: MOTTable, what: str, lines: list[int]) -> str:
    """``path, line 4`` / ``path, lines 4 and 9``, or the file (or ``what``) alone."""
    name = table.path or what
    if not lines:
        return name
    if len(lines) == 1:
        return f"{name}, line {lines[0]}"
    return f"{name}, lines {lines[0]} and {lines[1]}"


def _check_frames(table: MOTTable, what: str, n_frames: int) -> None:
    if len(table) and table.frames.min() < 1:
        first = int(table.frames.min())
        lines = _lines_of(table.path, lambda row: row[0] == first)[:1]
        raise ValueError(f"{_where(table, what, lines)}: frame {first} is before the "
                         "first (MOTChallenge frames count from 1)")
    if len(table) and table.frames.max() > n_frames:
        last = int(table.frames.max())
        lines = _lines_of(table.path, lambda row: row[0] == last)[:1]
        raise ValueError(f"{_where(table, what, lines)}: frame {last} is beyond the sequence's "
                         f"{n_frames} frames")


def _check_unique(table: MOTTable, what: str) -> None:
    if len(table) < 2:
        return
    # rows sorted by (frame, id): a repeated pair sits next to its twin
    order = np.lexsort((table.ids, table.frames))
    f, i = table.frames[order], table.ids[order]
    same = (f[1:] == f[:-1]) & (i[1:] == i[:-1])
    if not same.any():
        return
    twin = np.zeros(len(table), bool)
    twin[order[1:][same]] = twin[order[:-1][same]] = True
    k = int(np.argmax(twin))  # the first such row in the table's order
    frame, ident = int(table.frames[k]), int(table.ids[k])
    hint = ""
    if (table.ids == -1).all():
        hint = (f"; every id is -1: it looks like a detections file (det.txt), not "
                f"{'tracking results' if what == 'prediction' else what}")
    lines = _lines_of(table.path, lambda row: row[0] == frame and row[1] == ident)
    raise ValueError(f"{_where(table, what, lines)}: id {ident} appears more than once in "
                     f"frame {frame}{hint}")


def _check_table(table: Any, name: str) -> None:
    """A TypeError or ValueError naming ``name`` where ``table`` is not a MOTTable whose
    columns the scoring can read (a path, a DataFrame or a table built by hand with a NaN
    box failed inside numpy or SciPy's assignment, naming neither)."""
    if not isinstance(table, MOTTable):
        raise TypeError(f"{name} must be a MOTTable (vistrack.io.read_mot reads a file; "
                        "evaluate_files scores files); got "
                        f"{type(table).__name__}")
    n = len(table.frames) if getattr(table.frames, "ndim", 0) == 1 else -1
    for col in ("frames", "ids", "conf", "classes"):
        v = getattr(table, col)
        if not isinstance(v, np.ndarray) or v.shape != (n,):
            like = "" if col == "frames" else f" = ({n},), as frames"
            raise ValueError(f"{name}.{col} must be an array of shape (N,){like}; got "
                             f"{type(v).__name__} of shape {np.shape(v)}")
    if not isinstance(table.boxes, np.ndarray) or table.boxes.shape != (n, 4):
        raise ValueError(f"{name}.boxes must be an array of shape (N, 4) = ({n}, 4); got "
                         f"{type(table.boxes).__name__} of shape {np.shape(table.boxes)}")
    bad = ~np.isfinite(table.boxes).all(axis=1)
    if bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise ValueError(f"{name}.boxes[{k}] is not finite: {table.boxes[k].tolist()}")
    neg = (table.boxes[:, 2:] < 0).any(axis=1)
    if neg.any():  # (scored as IoU 0, a miss and a false positive, without a word)
        k = int(np.flatnonzero(neg)[0])
        raise ValueError(f"{name}.boxes[{k}] has a negative width or height: "
                         f"{table.boxes[k].tolist()} (x, y, w, h: a box of corners x1, y1, "
                         "x2, y2?)")
    # (frames before the first: _check_frames). An infinite frame was float()'s bare
    # OverflowError; a NaN id escaped the duplicate check (NaN != NaN) and was one object to
    # np.unique, an id of 1.5 a switch: as read_mot refuses them
    for col in ("frames", "ids"):
        v = getattr(table, col)
        if n and v.dtype.kind == "f":
            part = ~np.isfinite(v) | (v != np.floor(v))
            if part.any():
                k = int(np.flatnonzero(part)[0])
                raise ValueError(f"{name}.{col}[{k}] must be a whole number; got {v[k]}")


def _n_frames(gt: MOTTable, pred: MOTTable, n_frames: int | None) -> int:
    """The sequence's length: ``n_frames`` if given, else the last frame of either table."""
    _check_table(gt, "gt")
    _check_table(pred, "pred")
    if n_frames is None:
        return int(max(gt.frames.max() if len(gt) else 0, pred.frames.max() if len(pred) else 0))
    return as_whole(n_frames, "n_frames", 0)


def _prepare(gt: MOTTable, pred: MOTTable, n_frames: int, benchmark: str,
             zero_distance: float | None = None) -> _Sequence:
    bench = _benchmark_of(gt, benchmark)
    similarity = _similarity(gt, pred, zero_distance)
    for table, what in ((gt, "ground truth"), (pred, "prediction")):
        if len(table) > 1 and np.any(np.diff(table.frames) < 0):
            raise ValueError(f"{table.path or what}: rows must be sorted by frame (read_mot "
                             "sorts them)")
        _check_frames(table, what, n_frames)
        _check_unique(table, what)
    if bench != "MOT15" and len(gt):
        bad = ~np.isin(gt.classes, np.arange(1, 14))
        if bad.any():
            where, written = _class_row(gt, "ground truth", lambda c: c not in range(1, 14))
            value = _shown(written if written is not None else gt.classes[np.argmax(bad)])
            raise ValueError(f"{where}: class {value} is not a {bench} class (1-13)")
    if len(pred) and (pred.classes > 1).any():
        # TrackEval refuses such results ("only valid for pedestrian class"), under every
        # convention: a car of a tracker of many classes was counted as a pedestrian, a false
        # positive or a match (under MOT15's too; a world x there, MOT15's column 8 in
        # results, is read as no class)
        where, written = _class_row(pred, "prediction", lambda c: c > 1)
        first = written if written is not None else pred.classes[np.argmax(pred.classes > 1)]
        raise ValueError(f"{where}: class {_shown(first)}: {bench} scores pedestrians alone "
                         "(class 1, or -1 where the tracker gives none); give a pedestrian "
                         "tracker's "
                         "results, or those of class 1 alone")
    distractors = np.array(_DISTRACTORS.get(bench, ()), dtype=np.int64)
    # the frames with a row: a frame without any adds nothing to a count, and the sequence may
    # be long (its last frame, or seqinfo.ini's length, need not bound the work)
    frames = np.union1d(gt.frames, pred.frames)
    frames = frames[frames >= 1]
    gs = np.searchsorted(gt.frames, frames, "left"), np.searchsorted(gt.frames, frames, "right")
    ps = (np.searchsorted(pred.frames, frames, "left"),
          np.searchsorted(pred.frames, frames, "right"))
    # each row's part in it, once: whether a ground-truth row is scored and whether it is a
    # distractor (a prediction matched to one is removed)
    keep_gt = scored_truth(gt, bench)
    distractor = np.isin(gt.classes, distractors)
    gt_ids, pred_ids, sims = [], [], []
    for g0, g1, p0, p1 in zip(gs[0].tolist(), gs[1].tolist(), ps[0].tolist(), ps[1].tolist()):
        sim = similarity(gt.boxes[g0:g1], pred.boxes[p0:p1])
        keep_p = np.ones(p1 - p0, bool)
        if bench != "MOT15" and g1 > g0 and p1 > p0:
            score = np.where(sim < 0.5 - _EPS, 0.0, sim)
            r, c = linear_sum_assignment(-score)
            ok = score[r, c] > _EPS
            r, c = r[ok], c[ok]
            keep_p[c[distractor[g0:g1][r]]] = False
        keep_g = keep_gt[g0:g1]
        gt_ids.append(gt.ids[g0:g1][keep_g])
        pred_ids.append(pred.ids[p0:p1][keep_p])
        sims.append(sim[keep_g][:, keep_p])
    ug = np.unique(np.concatenate(gt_ids)) if gt_ids else np.zeros(0, np.int64)
    up = np.unique(np.concatenate(pred_ids)) if pred_ids else np.zeros(0, np.int64)
    return _Sequence([np.searchsorted(ug, i) for i in gt_ids],
                     [np.searchsorted(up, i) for i in pred_ids], sims, len(ug), len(up),
                     frames, ug, up)


def _same_fields(a: Any, b: Any) -> bool:
    """Whether two dataclasses of one type hold the same values, arrays compared whole (the
    generated ``==`` compared them as one value: numpy's "truth value of an array is
    ambiguous"); NaN in the same places is the same."""
    if type(a) is not type(b):
        return NotImplemented
    for f in fields(a):
        x, y = getattr(a, f.name), getattr(b, f.name)
        if isinstance(x, np.ndarray) or isinstance(y, np.ndarray):
            x, y = np.asarray(x), np.asarray(y)
            nan = x.dtype.kind in "fc" and y.dtype.kind in "fc"
            if not np.array_equal(x, y, equal_nan=nan):
                return False
        elif x != y:
            return False
    return True


def _assign(score: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r, c = linear_sum_assignment(-score)
    ok = score[r, c] > _EPS
    return r[ok], c[ok]


@dataclass
class MOTCounts:
    """The counts behind every score of one sequence, or of several combined (``+``).

    The scores are properties, as fractions in [0, 1] (MOTA can be negative). HOTA and its
    parts are averaged over :data:`ALPHAS`; ``*_alpha`` gives them per threshold. Adding two
    counts (``a + b``, :func:`combine`) adds the counts and averages ``AssA``, ``AssRe``,
    ``AssPr`` and ``LocA`` weighted by each one's HOTA true positives, as MOTChallenge's
    COMBINED row. ``sum(counts)`` gives the same as :func:`combine`.

    Attributes
    ----------
    frames, gt_dets, pred_dets, gt_ids, pred_ids : int
        Frames, ground-truth and predicted boxes (after preprocessing), and their identities.
    TP, FN, FP : int
        CLEAR MOT matches (IoU >= 0.5), missed ground truth and unmatched predictions.
    IDSW : int
        Identity switches: a ground-truth object matched to another predicted id than at its
        last match.
    Frag : int
        Fragmentations: times a ground-truth trajectory's matching resumes after a break, as
        TrackEval counts them: a frame with no prediction at all breaks nothing (an object
        matched in frames 1, 2 and 4 and missed in 3 is a fragmentation only where frame 3
        has a prediction; py-motmetrics counts it either way).
    MT, PT, ML : int
        Mostly tracked (matched in more than 80 % of its frames), partly tracked and mostly
        lost (under 20 %) ground-truth trajectories.
    MOTP_sum : float
        Sum of the IoU of the CLEAR MOT matches.
    IDTP, IDFN, IDFP : int
        Identity true positives, false negatives and false positives: detections matched, or
        not, under the best one-to-one matching of whole trajectories.
    HOTA_TP, HOTA_FN, HOTA_FP : (19,) ndarray
        HOTA's detection counts at each threshold of :data:`ALPHAS`.
    AssA_alpha, AssRe_alpha, AssPr_alpha, LocA_alpha : (19,) ndarray
        Association accuracy, recall and precision, and localisation accuracy, per threshold.
    combined : bool
        A sum of counts (``+``, :func:`combine`), not one sequence's: where no ground truth is
        counted, TrackEval gives a sequence's MOTA as 0 and a sum's by the formula
        (:attr:`MOTA`).

    References
    ----------
    .. [1] K. Bernardin and R. Stiefelhagen, "Evaluating multiple object tracking
       performance: the CLEAR MOT metrics", *EURASIP Journal on Image and Video Processing*,
       2008.
    .. [2] E. Ristani, F. Solera, R. Zou, R. Cucchiara and C. Tomasi, "Performance measures
       and a data set for multi-target, multi-camera tracking", ECCV Workshops, 2016.
    .. [3] J. Luiten, A. Ošep, P. Dendorfer, P. Torr, A. Geiger, L. Leal-Taixé and B. Leibe,
       "HOTA: a higher order metric for evaluating multi-object tracking", *International
       Journal of Computer Vision* 129, 2021.

    Examples
    --------
    One object, tracked throughout under two ids:

    >>> from vistrack.io import MOTTable
    >>> gt = MOTTable.from_rows([(f, 1, 10 * f, 0, 10, 10) for f in range(1, 5)])
    >>> pred = MOTTable.from_rows([(f, 7 if f < 3 else 8, 10 * f, 0, 10, 10)
    ...                            for f in range(1, 5)])
    >>> c = evaluate_mot(gt, pred)
    >>> c.TP, c.FN, c.FP, c.IDSW, c.MT
    (4, 0, 0, 1, 1)
    >>> round(c.MOTA, 3), c.MOTP, c.IDF1, round(c.HOTA, 3)
    (0.75, 1.0, 0.5, 0.707)
    >>> c.DetA, c.AssA, c.AssRe, c.AssPr
    (1.0, 0.5, 0.5, 1.0)
    >>> (c + c).TP, round(combine([c, c]).MOTA, 3), sum([c, c]).TP
    (8, 0.75, 8)
    """

    frames: int = 0
    gt_dets: int = 0
    pred_dets: int = 0
    gt_ids: int = 0
    pred_ids: int = 0
    # CLEAR MOT
    TP: int = 0
    FN: int = 0
    FP: int = 0
    IDSW: int = 0
    Frag: int = 0
    MT: int = 0
    PT: int = 0
    ML: int = 0
    MOTP_sum: float = 0.0
    # identity
    IDTP: int = 0
    IDFN: int = 0
    IDFP: int = 0
    # HOTA, per alpha
    HOTA_TP: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    HOTA_FN: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    HOTA_FP: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    AssA_alpha: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    AssRe_alpha: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    AssPr_alpha: np.ndarray = field(default_factory=lambda: np.zeros(len(ALPHAS)))
    LocA_alpha: np.ndarray = field(default_factory=lambda: np.ones(len(ALPHAS)))
    combined: bool = False

    def __eq__(self, other: object) -> bool:
        """Whether two counts are the same, their arrays compared whole.

        >>> from vistrack.io import MOTTable
        >>> g = MOTTable.from_rows([(1, 1, 0, 0, 10, 10), (2, 1, 1, 0, 10, 10)])
        >>> evaluate_mot(g, g) == evaluate_mot(g, g), evaluate_mot(g, g) == MOTCounts()
        (True, False)
        """
        return _same_fields(self, other)

    __hash__ = None  # type: ignore[assignment]  # (mutable, as the generated == made it)

    def __add__(self, other: MOTCounts) -> MOTCounts:
        if not isinstance(other, MOTCounts):
            return NotImplemented
        out = MOTCounts(combined=True)
        for f in fields(self):
            if f.name not in ("AssA_alpha", "AssRe_alpha", "AssPr_alpha", "LocA_alpha",
                              "combined"):
                setattr(out, f.name, getattr(self, f.name) + getattr(other, f.name))
        tp = out.HOTA_TP
        for name in ("AssA_alpha", "AssRe_alpha", "AssPr_alpha"):
            out.__dict__[name] = ((getattr(self, name) * self.HOTA_TP
                                   + getattr(other, name) * other.HOTA_TP) / np.maximum(1.0, tp))
        loc = self.LocA_alpha * self.HOTA_TP + other.LocA_alpha * other.HOTA_TP
        out.LocA_alpha = np.maximum(1e-10, loc) / np.maximum(1e-10, tp)
        return out

    def __radd__(self, other: int) -> MOTCounts:
        # sum() starts from 0: 0 + counts is the empty counts plus these, as in combine
        if isinstance(other, int) and not isinstance(other, bool) and other == 0:
            return MOTCounts() + self
        return NotImplemented

    # CLEAR MOT
    @property
    def MOTA(self) -> float:
        r"""CLEAR MOT accuracy, :math:`1 - (FN + FP + IDSW) / (TP + FN)`; can be negative.

        As TrackEval gives it: a sequence without ground truth to count (``TP + FN`` 0)
        scores 0, whatever it predicted; a sum of counts (:attr:`combined`), MOTChallenge's
        COMBINED, scores :math:`(TP - FP - IDSW) / \max(1, TP + FN)`, which is then ``-FP``.

        Examples
        --------
        >>> c = MOTCounts(TP=8, FN=2, FP=1, IDSW=1, MOTP_sum=6.0, IDTP=6, IDFP=3, IDFN=4)
        >>> c.MOTA
        0.6
        >>> none = MOTCounts(FP=5)  # no ground truth counted, five false positives
        >>> none.MOTA, combine([none]).MOTA
        (0.0, -5.0)
        """
        if self.TP + self.FN == 0 and not self.combined:
            return 0.0
        return (self.TP - self.FP - self.IDSW) / max(1, self.TP + self.FN)

    @property
    def MOTP(self) -> float:
        r"""CLEAR MOT precision: the mean IoU of the matches, :math:`\text{MOTP\_sum} / TP`.

        Examples
        --------
        >>> c = MOTCounts(TP=8, FN=2, FP=1, IDSW=1, MOTP_sum=6.0, IDTP=6, IDFP=3, IDFN=4)
        >>> c.MOTP
        0.75
        """
        return self.MOTP_sum / max(1, self.TP)

    # identity
    @property
    def IDF1(self) -> float:
        r"""Identity F1, :math:`IDTP / (IDTP + (IDFP + IDFN) / 2)`.

        Examples
        --------
        >>> c = MOTCounts(TP=8, FN=2, FP=1, IDSW=1, MOTP_sum=6.0, IDTP=6, IDFP=3, IDFN=4)
        >>> round(c.IDF1, 3)
        0.632
        """
        return self.IDTP / max(1.0, self.IDTP + 0.5 * self.IDFP + 0.5 * self.IDFN)

    @property
    def IDP(self) -> float:
        r"""Identity precision, :math:`IDTP / (IDTP + IDFP)`.

        Examples
        --------
        >>> c = MOTCounts(TP=8, FN=2, FP=1, IDSW=1, MOTP_sum=6.0, IDTP=6, IDFP=3, IDFN=4)
        >>> round(c.IDP, 3)
        0.667
        """
        return self.IDTP / max(1, self.IDTP + self.IDFP)

    @property
    def IDR(self) -> float:
        r"""Identity recall, :math:`IDTP / (IDTP + IDFN)`.

        Examples
        --------
        >>> c = MOTCounts(TP=8, FN=2, FP=1, IDSW=1, MOTP_sum=6.0, IDTP=6, IDFP=3, IDFN=4)
        >>> c.IDR
        0.6
        """
        return self.IDTP / max(1, self.IDTP + self.IDFN)

    # HOTA
    @property
    def DetA_alpha(self) -> np.ndarray:
        r"""Detection accuracy per threshold, :math:`TP_\alpha / (TP_\alpha + FN_\alpha +
        FP_\alpha)`: ``(19,)``.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> c.DetA_alpha[:3].round(3)
        array([0.667, 0.667, 0.667])
        """
        return self.HOTA_TP / np.maximum(1, self.HOTA_TP + self.HOTA_FN + self.HOTA_FP)

    @property
    def HOTA_alpha(self) -> np.ndarray:
        r"""HOTA per threshold, :math:`\sqrt{\text{DetA}_\alpha \, \text{AssA}_\alpha}`:
        ``(19,)``.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> c.HOTA_alpha.shape, round(float(c.HOTA_alpha[0]), 3)
        ((19,), 0.577)
        """
        return np.sqrt(self.DetA_alpha * self.AssA_alpha)

    @property
    def HOTA(self) -> float:
        """Higher order tracking accuracy: :attr:`HOTA_alpha` averaged over :data:`ALPHAS`.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> round(c.HOTA, 3)
        0.577
        """
        return float(self.HOTA_alpha.mean())

    @property
    def DetA(self) -> float:
        """Detection accuracy: :attr:`DetA_alpha` averaged over :data:`ALPHAS`.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> round(c.DetA, 3)
        0.667
        """
        return float(self.DetA_alpha.mean())

    @property
    def AssA(self) -> float:
        r"""Association accuracy averaged over :data:`ALPHAS`: per threshold, the mean over the
        matches :math:`c` of :math:`|TPA(c)| / (|TPA(c)| + |FNA(c)| + |FPA(c)|)`.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> c.AssA
        0.5
        """
        return float(self.AssA_alpha.mean())

    @property
    def LocA(self) -> float:
        """Localisation accuracy: the mean IoU of HOTA's matches, averaged over :data:`ALPHAS`.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> round(c.LocA, 3)
        0.9
        """
        return float(self.LocA_alpha.mean())

    @property
    def DetRe(self) -> float:
        r"""Detection recall, :math:`TP_\alpha / (TP_\alpha + FN_\alpha)` averaged over
        :data:`ALPHAS`.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> round(c.DetRe, 3)
        0.8
        """
        return float((self.HOTA_TP / np.maximum(1, self.HOTA_TP + self.HOTA_FN)).mean())

    @property
    def DetPr(self) -> float:
        r"""Detection precision, :math:`TP_\alpha / (TP_\alpha + FP_\alpha)` averaged over
        :data:`ALPHAS`.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> round(c.DetPr, 3)
        0.8
        """
        return float((self.HOTA_TP / np.maximum(1, self.HOTA_TP + self.HOTA_FP)).mean())

    @property
    def AssRe(self) -> float:
        r"""Association recall averaged over :data:`ALPHAS`: per threshold, the mean over the
        matches :math:`c` of :math:`|TPA(c)| / (|TPA(c)| + |FNA(c)|)`.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> round(c.AssRe, 3)
        0.6
        """
        return float(self.AssRe_alpha.mean())

    @property
    def AssPr(self) -> float:
        r"""Association precision averaged over :data:`ALPHAS`: per threshold, the mean over
        the matches :math:`c` of :math:`|TPA(c)| / (|TPA(c)| + |FPA(c)|)`.

        Examples
        --------
        >>> c = MOTCounts(HOTA_TP=np.full(19, 8.0), HOTA_FN=np.full(19, 2.0),
        ...           HOTA_FP=np.full(19, 2.0), AssA_alpha=np.full(19, 0.5),
        ...           AssRe_alpha=np.full(19, 0.6), AssPr_alpha=np.full(19, 0.7),
        ...           LocA_alpha=np.full(19, 0.9))
        >>> round(c.AssPr, 3)
        0.7
        """
        return float(self.AssPr_alpha.mean())

    def summary(self) -> dict:
        """Scores (fractions) and counts as a flat dict, for tables and JSON.

        Returns
        -------
        dict
            The 13 scores (``HOTA``, ``DetA``, ``AssA``, ``LocA``, ``DetRe``, ``DetPr``,
            ``AssRe``, ``AssPr``, ``MOTA``, ``MOTP``, ``IDF1``, ``IDP``, ``IDR``) as float,
            then 16 counts as int (``TP`` ... ``frames``).

        Examples
        --------
        >>> s = MOTCounts(frames=3, TP=2, FN=1).summary()
        >>> round(s["MOTA"], 3), s["TP"], len(s)
        (0.667, 2, 29)
        """
        keys = ("HOTA", "DetA", "AssA", "LocA", "DetRe", "DetPr", "AssRe", "AssPr", "MOTA",
                "MOTP", "IDF1", "IDP", "IDR")
        counts = ("TP", "FP", "FN", "IDSW", "Frag", "MT", "PT", "ML", "IDTP", "IDFP", "IDFN",
                  "gt_dets", "pred_dets", "gt_ids", "pred_ids", "frames")
        out = {k: float(getattr(self, k)) for k in keys}
        out.update({k: int(getattr(self, k)) for k in counts})
        return out


def _clear(seq: _Sequence, out: MOTCounts, record: list | None = None) -> None:
    """CLEAR MOT's counts into ``out``; with ``record``, each frame's objects, the predicted
    id matched to each (-1: missed) and whether that match switched identity appended to it
    (contiguous ids, one tuple a frame with objects)."""
    n_g = seq.n_gt_ids
    prev_any = np.full(n_g, -1)  # the predicted id of each object's last match
    prev_step = np.full(n_g, -1)  # ... at the previous frame, -1 if not matched there
    gt_count, matched_count, frag = np.zeros(n_g), np.zeros(n_g), np.zeros(n_g)
    for k, (g, p, sim) in enumerate(zip(seq.gt_ids, seq.pred_ids, seq.sim)):
        # (as in TrackEval, a frame without objects or without predictions leaves the
        # previous frame's pairs in place for the next)
        if len(g) == 0:
            out.FP += len(p)
            continue
        if len(p) == 0:
            out.FN += len(g)
            gt_count[g] += 1
            if record is not None:
                record.append((k, g, np.full(len(g), -1), np.zeros(len(g), bool)))
            continue
        score = 1000.0 * (p[None, :] == prev_step[g][:, None]) + sim
        score[sim < 0.5 - _EPS] = 0.0
        r, c = _assign(score)
        mg, mp = g[r], p[c]
        was = prev_any[mg]
        switched = (was >= 0) & (mp != was)
        out.IDSW += int(np.sum(switched))
        if record is not None:
            matched, switch = np.full(len(g), -1), np.zeros(len(g), bool)
            matched[r], switch[r] = mp, switched
            record.append((k, g, matched, switch))
        gt_count[g] += 1
        matched_count[mg] += 1
        not_tracked = prev_step < 0
        prev_any[mg] = mp
        prev_step[:] = -1
        prev_step[mg] = mp
        frag += not_tracked & (prev_step >= 0)
        out.TP += len(mg)
        out.FN += len(g) - len(mg)
        out.FP += len(p) - len(mg)
        out.MOTP_sum += float(sim[r, c].sum())
    ratio = matched_count[gt_count > 0] / gt_count[gt_count > 0]
    out.MT += int(np.sum(ratio > 0.8))
    out.PT += int(np.sum(ratio >= 0.2)) - int(np.sum(ratio > 0.8))
    out.ML += n_g - int(np.sum(ratio >= 0.2))
    out.Frag += int(np.sum(frag[frag > 0] - 1))


def _identity(seq: _Sequence, out: MOTCounts) -> None:
    keys = [np.zeros(0, np.int64)]
    n_gt = n_pred = 0
    for g, p, sim in zip(seq.gt_ids, seq.pred_ids, seq.sim):
        r, c = np.nonzero(sim >= 0.5)
        keys.append(g[r].astype(np.int64) * seq.n_pred_ids + p[c])
        n_gt += len(g)
        n_pred += len(p)
    idtp = most_matched(np.concatenate(keys), seq.n_pred_ids)
    out.IDTP += idtp
    out.IDFN += n_gt - idtp
    out.IDFP += n_pred - idtp


def most_matched(keys: np.ndarray, n_cols: int) -> int:
    """The most matched detections of a one-to-one matching of trajectories (IDF1's IDTP):
    ``keys`` holds one ``row * n_cols + col`` per detection matched in a frame (a
    ground-truth trajectory ``row``, a predicted one ``col``), and the matching maximises
    the detections of the pairs it keeps (the value of TrackEval's (G+P)^2 formulation,
    whose dummy rows and columns only pad it).

    Solved on the pairs that ever match alone, as a sparse assignment with a way out for
    every row (a dense matrix of every pair of identities took 4.7 GB for a tracker that
    gave 120,000 detections their own identity beside 2,420 people, and failed at 180,000).

    >>> # trajectory 0 matched to 0 twice and to 1 once, 1 to 1 once: (0, 0) and (1, 1)
    >>> most_matched(np.array([0 * 3 + 0, 0 * 3 + 0, 0 * 3 + 1, 1 * 3 + 1]), 3)
    3
    """
    from scipy.sparse import csr_matrix
    from scipy.sparse.csgraph import min_weight_full_bipartite_matching

    if not len(keys):
        return 0
    pair, count = np.unique(keys, return_counts=True)
    rows, r = np.unique(pair // n_cols, return_inverse=True)
    cols, c = np.unique(pair % n_cols, return_inverse=True)
    R, C = len(rows), len(cols)
    # each pair costs top - its detections, each row's own way out top: the least cost
    # keeps the most detections (whole numbers, exact in floats)
    top = int(count.max()) + 1
    cost = csr_matrix((np.r_[top - count, np.full(R, top)].astype(float),
                       (np.r_[r, np.arange(R)], np.r_[c, C + np.arange(R)])), shape=(R, C + R))
    i, j = min_weight_full_bipartite_matching(cost)
    real = j < C  # the rows matched to a pair, not to their way out: that pair's detections
    return int(count[np.searchsorted(pair, rows[i[real]] * n_cols + cols[j[real]])].sum())


def _hota(seq: _Sequence, out: MOTCounts) -> None:
    # the alignment of every pair of identities that ever overlap, kept for those pairs only
    # (a long sequence may hold thousands of each, which never meet): each frame's overlapping
    # pairs, their share of the frame's similarity, summed per pair in the order of the frames
    n_g, n_p = seq.n_gt_ids, seq.n_pred_ids
    g_count, p_count = np.zeros(n_g), np.zeros(n_p)
    keys, shares, cells = [], [], []
    for g, p, sim in zip(seq.gt_ids, seq.pred_ids, seq.sim):
        denom = sim.sum(0)[None, :] + sim.sum(1)[:, None] - sim
        share = np.zeros_like(sim)
        ok = denom > _EPS
        share[ok] = sim[ok] / denom[ok]
        r, c = np.nonzero(sim > 0)
        keys.append(g[r] * n_p + p[c])
        shares.append(share[r, c])
        cells.append((r, c))
        g_count[g] += 1
        p_count[p] += 1
    key = np.concatenate(keys) if keys else np.zeros(0, np.int64)
    pairs, pair_of = np.unique(key, return_inverse=True)
    pot = np.bincount(pair_of, weights=np.concatenate(shares) if shares else None,
                      minlength=len(pairs))
    gp, pp = g_count[pairs // max(n_p, 1)], p_count[pairs % max(n_p, 1)]
    align = pot / (gp + pp - pot)
    # each frame's one-to-one matching once; what each alpha keeps of it, for all alphas at
    # once: each match's similarity and its pair among the overlapping ones (-1 for a match
    # without overlap, which no alpha keeps)
    matched, ms = [], []
    n_gt = n_pred = 0
    o = 0
    for g, p, sim, (r, c) in zip(seq.gt_ids, seq.pred_ids, seq.sim, cells):
        n_gt += len(g)
        n_pred += len(p)
        if len(g) and len(p):
            here = pair_of[o:o + len(r)]
            score = np.zeros_like(sim)
            score[r, c] = align[here] * sim[r, c]
            pair_at = np.full(sim.shape, -1)
            pair_at[r, c] = here
            rr, cc = linear_sum_assignment(-score)
            matched.append(pair_at[rr, cc])
            ms.append(sim[rr, cc])
        o += len(r)
    s = np.concatenate(ms) if ms else np.zeros(0)
    pair = np.concatenate(matched) if matched else np.zeros(0, np.int64)
    A = len(ALPHAS)
    tp, loc = np.zeros(A), np.zeros(A)
    ass_a, ass_re, ass_pr = np.zeros(A), np.zeros(A), np.zeros(A)
    for a, alpha in enumerate(ALPHAS):
        ok = s >= alpha - _EPS
        tp[a], loc[a] = ok.sum(), s[ok].sum()
        m = np.bincount(pair[ok], minlength=len(pairs)).astype(np.float64)  # per pair
        k = max(1.0, tp[a])
        ass_a[a] = np.sum(m * m / np.maximum(1, gp + pp - m)) / k
        ass_re[a] = np.sum(m * m / np.maximum(1, gp)) / k
        ass_pr[a] = np.sum(m * m / np.maximum(1, pp)) / k
    fn, fp = n_gt - tp, n_pred - tp
    out.HOTA_TP, out.HOTA_FN, out.HOTA_FP = tp, fn, fp
    out.AssA_alpha, out.AssRe_alpha, out.AssPr_alpha = ass_a, ass_re, ass_pr
    out.LocA_alpha = np.maximum(1e-10, loc) / np.maximum(1e-10, tp)


def evaluate_mot(gt: MOTTable, pred: MOTTable, n_frames: int | None = None, *,
                 benchmark: str = "auto", zero_distance: float | None = None) -> MOTCounts:
    """CLEAR MOT, identity and HOTA counts of predicted tracks against ground truth.

    Parameters
    ----------
    gt, pred : MOTTable
        From :func:`vistrack.io.read_mot`.
    n_frames : int, optional
        The sequence length (``seqinfo.ini``'s ``seqLength``); default the last frame in
        either file.
    benchmark : {"auto", "MOT15", "MOT16", "MOT17", "MOT20"}
        Which preprocessing. "auto" is MOT17 for ground truth with a class column (8 values
        a row or more, every class 1-13), else MOT15 (whose rows end in three world
        coordinates).
    zero_distance : float, optional
        Score positions rather than boxes: each row at its centre (a point, a row of width
        and height 0, at itself), a pair's similarity ``max(0, 1 - d / zero_distance)`` in
        place of the IoU (:func:`point_similarity`, TrackEval's for points). CLEAR MOT and
        IDF1 match within half of it; HOTA's thresholds are on that similarity.

    Returns
    -------
    MOTCounts
        With ``.MOTA``, ``.IDF1``, ``.HOTA`` ...; add counts of several sequences with ``+``
        (or :func:`combine`) for the combined scores.

    Raises
    ------
    ValueError
        If ``benchmark`` is not one of the names, a file has rows beyond ``n_frames`` or
        before frame 1 (a table built in Python; ``read_mot`` refuses those) or an id twice in
        a frame, or MOT16/17/20 ground truth has a class outside 1-13; if ``zero_distance``
        is not a finite number > 0, or without it a table's rows are all points. The message
        names the table's file and, when it was read from one, the line(s) of the row:
        ``res.txt, lines 4 and 9: id 3 appears more than once in frame 2``.

    References
    ----------
    .. [1] K. Bernardin and R. Stiefelhagen, "Evaluating multiple object tracking
       performance: the CLEAR MOT metrics", *EURASIP Journal on Image and Video Processing*,
       2008.
    .. [2] E. Ristani, F. Solera, R. Zou, R. Cucchiara and C. Tomasi, "Performance measures
       and a data set for multi-target, multi-camera tracking", ECCV Workshops, 2016.
    .. [3] J. Luiten, A. Ošep, P. Dendorfer, P. Torr, A. Geiger, L. Leal-Taixé and B. Leibe,
       "HOTA: a higher order metric for evaluating multi-object tracking", *International
       Journal of Computer Vision* 129, 2021.

    Examples
    --------
    >>> from vistrack.io.motchallenge import MOTTable
    >>> import numpy as np
    >>> def table(ids, x):
    ...     n = len(ids)
    ...     return MOTTable(np.arange(1, n + 1), np.array(ids), np.c_[x, np.zeros(n),
    ...                     np.full(n, 10.0), np.full(n, 10.0)], np.ones(n), -np.ones(n, int),
    ...                     -np.ones(n))
    >>> gt = table([1, 1, 1, 1], [0, 1, 2, 3])
    >>> pred = table([7, 7, 8, 8], [0, 1, 2, 3])   # the right boxes, one id switch
    >>> c = evaluate_mot(gt, pred)
    >>> c.IDSW, round(c.MOTA, 2), round(c.IDF1, 2)
    (1, 0.75, 0.5)
    """
    n_frames = _n_frames(gt, pred, n_frames)
    seq = _prepare(gt, pred, n_frames, benchmark, zero_distance)
    out = MOTCounts(frames=n_frames, gt_dets=sum(len(g) for g in seq.gt_ids),
                    pred_dets=sum(len(p) for p in seq.pred_ids), gt_ids=seq.n_gt_ids,
                    pred_ids=seq.n_pred_ids)
    _clear(seq, out)
    _identity(seq, out)
    _hota(seq, out)
    return out


@dataclass(frozen=True)
class Matches:
    """Which predicted track covers each ground-truth object in each frame, as CLEAR MOT
    matches them (:func:`clear_matches`): one row per object per frame where it is scored.

    Attributes
    ----------
    frames, gt_ids : (N,) int ndarray
        The frame and the object's id in the ground truth, sorted by frame.
    pred_ids : (N,) int ndarray
        The predicted track's id matched to it there (any integer: a results file may number
        a track -1 or below), or -1 where it is missed.
    switches : (N,) bool ndarray
        True where the match's predicted id differs from the object's previous match's (an
        identity switch, as ``MOTCounts.IDSW`` counts them).
    matched : (N,) bool ndarray
        True where a predicted track covers the object (``TP``), False where it is missed
        (``FN``): what tells a track numbered -1 from a miss.
    """

    frames: np.ndarray
    gt_ids: np.ndarray
    pred_ids: np.ndarray
    switches: np.ndarray
    matched: np.ndarray

    def __eq__(self, other: object) -> bool:
        """Whether two matchings are the same, row by row (the generated ``==`` compared the
        arrays as one value: numpy's "ambiguous")."""
        return _same_fields(self, other)

    __hash__ = None  # type: ignore[assignment]  # (its arrays hold no hash)

    def __post_init__(self) -> None:
        # a Matches built by hand: one row per scored box in every field, or the timeline
        # would index one field by another's rows
        n = np.shape(self.frames)
        for name in ("frames", "gt_ids", "pred_ids", "switches", "matched"):
            shape = np.shape(getattr(self, name))
            if len(shape) != 1 or shape != n:
                raise ValueError(f"Matches.{name} must have shape (N,) as frames has, "
                                 f"one row per scored box; got {shape} against {n}")


def clear_matches(gt: MOTTable, pred: MOTTable, n_frames: int | None = None, *,
                  benchmark: str = "auto", zero_distance: float | None = None) -> Matches:
    """The matches behind :func:`evaluate_mot`'s CLEAR MOT counts, frame by frame: what a
    per-object timeline draws.

    Parameters and errors as :func:`evaluate_mot`; ``Matches`` has one row for each scored
    ground-truth box (a MOT16/17/20 box of another class, or of confidence 0, is not), so
    that the matched rows (``matched``) are ``TP``, the others ``FN``, and
    ``switches.sum()`` is ``IDSW``.

    Examples
    --------
    >>> from vistrack.io.motchallenge import MOTTable
    >>> def table(ids, x):
    ...     n = len(ids)
    ...     return MOTTable(np.arange(1, n + 1), np.array(ids), np.c_[x, np.zeros(n),
    ...                     np.full(n, 10.0), np.full(n, 10.0)], np.ones(n), -np.ones(n, int),
    ...                     -np.ones(n))
    >>> m = clear_matches(table([1, 1, 1], [0, 1, 2]), table([7, 8, 8], [0, 1, 9]))
    >>> m.frames.tolist(), m.pred_ids.tolist(), m.switches.tolist(), m.matched.tolist()
    ([1, 2, 3], [7, 8, -1], [False, True, False], [True, True, False])
    """
    seq = _prepare(gt, pred, _n_frames(gt, pred, n_frames), benchmark, zero_distance)
    record: list = []
    _clear(seq, MOTCounts(), record)
    assert seq.frames is not None and seq.gt_labels is not None and seq.pred_labels is not None
    if not record:
        empty = np.zeros(0, np.int64)
        return Matches(empty, empty, empty, np.zeros(0, bool), np.zeros(0, bool))
    k = np.concatenate([np.full(len(g), i) for i, g, _, _ in record])
    g = np.concatenate([g for _, g, _, _ in record])
    p = np.concatenate([p for _, _, p, _ in record])
    labels = seq.pred_labels
    return Matches(frames=seq.frames[k].astype(np.int64),
                   gt_ids=seq.gt_labels[g].astype(np.int64),
                   pred_ids=np.where(p >= 0, labels[np.maximum(p, 0)] if len(labels) else -1,
                                     -1).astype(np.int64),
                   switches=np.concatenate([s for _, _, _, s in record]), matched=p >= 0)


def combine(counts: Iterable[MOTCounts]) -> MOTCounts:
    """The combined counts of several sequences (MOTChallenge's COMBINED row).

    Parameters
    ----------
    counts : iterable of MOTCounts
        One per sequence.

    Returns
    -------
    MOTCounts
        Their sum (see :class:`MOTCounts`); empty counts for no sequences.

    Examples
    --------
    >>> total = combine([MOTCounts(frames=10, TP=8, FN=2), MOTCounts(frames=5, TP=3, FP=1)])
    >>> total.frames, total.TP, round(total.MOTA, 3)
    (15, 11, 0.769)
    """
    total = MOTCounts()
    for c in counts:
        total = total + c
    return total
