"""What a detections file tells of the detector that wrote it, and what a run says of it.

Read from the rows alone, before any tracking: the detector's stride (:func:`detection_stride`:
a detector run on every k-th frame), the frames it did not deliver
(:func:`undelivered_frames`: none amid frames with many), copies of one object
(:func:`duplicate_share`: a detector without non-maximum suppression), and the warnings
:func:`vistrack.pipeline.track_sequence` and :func:`vistrack.pipeline.track_video` give of
such a file (boxes without area or outside the image, several classes, a long run of frames
without rows). The
pipeline decides what to do about them; this module only looks.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ._validate import is_real, ordinal
from .association import overlapping_pairs
from .evaluation.mot import _lines_of
from .io.motchallenge import MOTTable, _csv_detection_line

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["detection_stride", "detector_grid", "undelivered_frames", "duplicate_share",
           "DUPLICATE_IOU", "UNDELIVERED_AROUND"]


def row_line(path: str | Path, frame: int, box: list[float] | None = None,
             columns: dict[str, str] | None = None) -> int | None:
    """The line of the detections file ``path`` of its first row of ``frame`` (and ``box``,
    as read), for a message: a MOTChallenge text file's found by its values, a CSV file's
    with a header by reading it again with its columns named by ``columns`` (they may lie in
    any order); None where it is not found."""
    lines = _lines_of(str(path), lambda row: row[0] == frame
                      and (box is None or row[2:6] == box))
    if lines:
        return lines[0]
    if Path(path).suffix.lower() == ".csv":
        # (a CSV file's row was named by its frame alone)
        return _csv_detection_line(path, columns, frame, box)
    return None


def row_place(path: str | Path, frame: int, box: list[float] | None = None,
              columns: dict[str, str] | None = None) -> str:
    """``"PATH, line N"`` for :func:`row_line`'s line, or ``"PATH, frame F"`` where there is
    none."""
    line = row_line(path, frame, box, columns)
    return f"{path}, line {line}" if line is not None else f"{path}, frame {frame}"


def first_box(dets: MOTTable, k: int, path: str | Path,
              columns: dict[str, str] | None = None) -> tuple[str, str]:
    """Where row ``k`` of a detections file is, for a message (``"PATH, line N"``, or its
    frame where the line is not found), and its box as written there (``"1241, 185.448, 0,
    188.552"``); a CSV file's columns named by ``columns``."""
    f, box = int(dets.frames[k]), dets.boxes[k].tolist()
    return row_place(path, f, box, columns), ", ".join(f"{v:g}" for v in box)


def warn_no_area(dets: MOTTable, path: Path, stacklevel: int,
                 columns: dict[str, str] | None = None) -> None:
    """Warn of a detections file's boxes of zero width or height, naming the first one's line
    (its frame, where the line is not found; a CSV file's columns named by ``columns``): a
    box with no area overlaps no other, so no track can follow it from frame to frame."""
    flat = (dets.boxes[:, 2] == 0) | (dets.boxes[:, 3] == 0)
    if not flat.any():
        return
    k = int(np.argmax(flat))
    where, box = first_box(dets, k, path, columns)
    more = int(flat.sum()) - 1
    zero = "width" if dets.boxes[k, 2] == 0 else "height"
    warnings.warn(f"{where}: a box of zero {zero} ({box})"
                  + (f" and {more} more of zero width or height" if more else "")
                  + ": a box with no area overlaps no other, so no track can follow it from "
                  "frame to frame", RuntimeWarning, stacklevel=stacklevel + 1)


OUTSIDE_SHARE = 0.05
"""The share of a detections file's boxes lying wholly outside the image from which
:func:`warn_outside` names them."""


def warn_outside(dets: MOTTable, path: str | Path, size: tuple[int, int],
                 stacklevel: int, columns: dict[str, str] | None = None) -> None:
    """Warn of a detections file of which a twentieth of the boxes or more lie wholly
    outside the ``(width, height)`` image, naming the first one's line (its frame, where the
    line is not found) and how many there are: such boxes are tracked as any other, but no
    object of the image is there (boxes in the pixels of another image size, or shifted). A
    few are not named: a detector that extrapolates people leaving the image puts 0.2-0.6 %
    of its boxes just past its edge (FairMOT's on MOT16)."""
    if not len(dets) or size[0] <= 0 or size[1] <= 0:
        return
    b = dets.boxes
    out = (b[:, 0] >= size[0]) | (b[:, 1] >= size[1]) | (b[:, 0] + b[:, 2] <= 0) \
        | (b[:, 1] + b[:, 3] <= 0)
    if out.sum() < OUTSIDE_SHARE * len(b):
        return
    where, box = first_box(dets, int(np.argmax(out)), path, columns)
    n = int(out.sum())
    warnings.warn(f"{where}: a box ({box}) wholly outside the "
                  f"{size[0]}x{size[1]} image" + (f", and {n - 1} more of {len(b)}" if n > 1
                                                  else "")
                  + ": tracked as the others, though nothing of the image is there (boxes in "
                  "the pixels of another image size?)", RuntimeWarning, stacklevel=stacklevel + 1)


def warn_long_silence(dets: MOTTable, path: Path, frame_rate: float,
                      stacklevel: int, columns: dict[str, str] | None = None) -> None:
    """Warn of a detections file (tracked without a sequence's length) whose frames with rows
    leave a run of frames without any longer than an hour and than ten times the frames that
    have rows: the tracker steps through every frame up to the last (some thousands a
    second), so a mistyped frame number, or a timestamp where the frame should be, makes a
    short file a run of minutes. The warning names the line of the first row after the run."""
    have = np.unique(dets.frames)
    if not len(have):
        return
    gaps = np.diff(np.r_[0, have]) - 1  # the frames without rows before each with rows
    k = int(np.argmax(gaps))
    if gaps[k] <= max(3600 * frame_rate, 10 * len(have)):
        return
    f = int(have[k])
    where = row_place(path, f, columns=columns)
    start = int(have[k - 1]) + 1 if k else 1
    warnings.warn(f"{where}: frame {f:,}'s rows come after frames {start:,}-{f - 1:,} without "
                  f"any ({int(gaps[k]):,} frames, {gaps[k] / frame_rate / 3600:,.1f} hours at "
                  f"{frame_rate:g} frames/s), where {len(have):,} frames have rows: the "
                  f"tracker steps through all {int(have[-1]):,} frames up to the last (a "
                  "mistyped frame number, or a timestamp where the frame should be?)",
                  UserWarning, stacklevel=stacklevel + 1)


DUPLICATE_IOU = 0.7
"""The IoU at which :func:`duplicate_share` counts two detections of a frame as one
object's (a detector's own non-maximum suppression leaves hardly any pair above it)."""


def duplicate_share(dets: MOTTable, min_iou: float = DUPLICATE_IOU) -> float:
    """The share of a detections file's rows that overlap another row of their frame and
    class at IoU ``min_iou`` or more: below 0.03 on every sequence of the shared data (its
    detectors apply non-maximum suppression), 0.96 where each detection has a copy moved by
    5 % of its size.

    Examples
    --------
    >>> t = MOTTable.from_rows([(1, -1, 0, 0, 10, 10, 0.9), (1, -1, 1, 0, 10, 10, 0.8),
    ...                         (1, -1, 50, 0, 10, 10, 0.7), (2, -1, 1, 0, 10, 10, 0.8)])
    >>> duplicate_share(t)
    0.5

    Raises
    ------
    ValueError
        If ``min_iou`` is not a number in (0, 1] (NaN and 2 gave 0.0, -1 gave 1.0).
    """
    if not (is_real(min_iou) and 0.0 < float(min_iou) <= 1.0):
        raise ValueError(f"min_iou must be a number in (0, 1]; got {min_iou!r}")
    n = 0
    xyxy = np.c_[dets.boxes[:, :2], dets.boxes[:, :2] + dets.boxes[:, 2:]]
    # the frames that have rows (sorted by frame), not every frame up to the last
    _, start, count = np.unique(dets.frames, return_index=True, return_counts=True)
    for a, m in zip(start[count > 1].tolist(), count[count > 1].tolist()):
        r, _ = overlapping_pairs(xyxy[a:a + m], dets.classes[a:a + m], min_iou)
        n += len(np.unique(r))
    return n / max(len(dets), 1)


def warn_duplicates(dets: MOTTable, path: Path, stacklevel: int) -> None:
    """Warn of a detections file where one row in five or more overlaps another of its frame
    and class at IoU 0.7 or more (:func:`duplicate_share`): a detector without non-maximum
    suppression, whose copies of one object each start a track."""
    share = duplicate_share(dets)
    if share < 0.2:
        return
    warnings.warn(f"{path}: {share:.0%} of the detections overlap another of their frame and "
                  f"class at IoU {DUPLICATE_IOU:g} or more (at most 3 % in detectors that apply "
                  "non-maximum suppression): copies of one object, each of which starts a "
                  f"track of its own; --nms-iou {DUPLICATE_IOU:g} (nms_iou under [tracker] in a "
                  "--config file) keeps the most confident of each", UserWarning,
                  stacklevel=stacklevel + 1)


def warn_classes(dets: MOTTable, path: Path, stacklevel: int,
                 classless: Path | None = None) -> None:
    """Warn that a detections file holds more than one class (the eighth value of a
    MOTChallenge file's rows, a CSV file's ``class``): each is tracked apart (with
    calibrated scores, each class's calibrated on their own); and where the results go to
    ``classless``, a MOTChallenge text file, which has no class column, that it will not say
    which class a track is (a CSV or Parquet results file and a video's ``tracks.csv`` do)."""
    kinds = np.unique(dets.classes)
    if len(kinds) < 2:
        return
    shown = ", ".join(str(k) for k in kinds[:8]) + (", ..." if len(kinds) > 8 else "")
    lost = ("" if classless is None else
            f"; {classless}, MOTChallenge's text, has no class column (a .csv or .parquet "
            "results file has one)")
    warnings.warn(f"{path}: detections of {len(kinds)} classes ({shown}): each class is "
                  f"tracked apart, no track taking another's detections{lost}", UserWarning,
                  stacklevel=stacklevel + 1)


def detector_grid(frames: np.ndarray) -> tuple[int, int]:
    """``(first, stride)``: the frames a detections file's detector ran on, every
    ``stride``-th from ``first`` (:func:`detection_stride`; ``(1, 1)``: every frame)."""
    stride = detection_stride(frames)
    return ((int(frames.min()) - 1) % stride + 1 if stride > 1 else 1), stride


UNDELIVERED_AROUND = 5
"""The fewest rows on each side of a run of frames without any for :func:`undelivered_frames`
to take the run as frames the detector did not deliver: where a detector finds 5 objects a
frame on average, it finds none in a frame it ran on with a chance below 1 % (e^-5)."""


def _frame_numbers(frames: ArrayLike) -> np.ndarray:
    """``frames`` as int64, each a whole number within int64 (NaN became -2^63 and 3.9
    became 3 by the cast, and frames that were never there were reported)."""
    f = np.asarray(frames).reshape(-1)
    if f.dtype.kind == "i" or f.dtype.kind == "u" and (not len(f) or f.max() < 2 ** 63):
        return f.astype(np.int64, copy=False)
    try:
        g = f.astype(np.float64)
    except (TypeError, ValueError):
        raise ValueError(f"frames must be whole numbers below 2^63; got {frames!r:.60}") from None
    bad = ~(np.isfinite(g) & (g == np.round(g)) & (np.abs(g) < 2.0 ** 63))
    if bad.any():
        i = int(np.flatnonzero(bad)[0])
        raise ValueError(f"frames must be whole numbers below 2^63; frames[{i}] = "
                         f"{float(g[i])!r}")
    return g.astype(np.int64)


def undelivered_frames(frames: ArrayLike, first: int = 1, stride: int = 1,
                       max_run: int | None = None,
                       around: int = UNDELIVERED_AROUND) -> np.ndarray:
    """The frames of a detector's grid (every ``stride``-th from ``first``) that have no rows
    while the grid frames on either side of their run have ``around`` rows or more each:
    frames the detector did not deliver (dropped while it was busy, a camera's glitch), not
    frames where it found nothing.

    Parameters
    ----------
    frames : (N,) array_like of int
        The rows' frame numbers.
    first, stride : int
        The detector's grid (:func:`detection_stride`).
    max_run : int, optional
        Runs of more grid frames than this are left as frames where nothing was found.
    around : int
        The fewest rows in each of the frames either side of a run.

    Returns
    -------
    (M,) int64 ndarray
        Sorted frame numbers.

    Raises
    ------
    ValueError
        If ``stride`` or ``around`` is not an integer >= 1, ``max_run`` one >= 0, ``first``
        not an integer, or a frame not a whole number.

    Examples
    --------
    Six boxes a frame, none in frames 4 and 7 (and none after frame 9):

    >>> f = np.repeat([1, 2, 3, 5, 6, 8, 9], 6)
    >>> undelivered_frames(f).tolist()
    [4, 7]
    >>> undelivered_frames(np.r_[f, 10]).tolist()  # frame 10's single box: frames 1-9 as before
    [4, 7]
    >>> undelivered_frames(np.repeat([1, 2, 3, 5, 6], [6, 6, 2, 6, 6])).tolist()  # 2 before 4
    []
    """
    for name, v, least in (("stride", stride, 1), ("around", around, 1),
                           ("max_run", 0 if max_run is None else max_run, 0)):
        # (a stride of 0 divided by zero, -1 gave frames out of order)
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < least:
            raise ValueError(f"{name} must be an integer >= {least}; got {v!r}")
    if isinstance(first, bool) or not isinstance(first, (int, np.integer)):
        raise ValueError(f"first must be an integer; got {first!r}")
    f = _frame_numbers(frames)
    if len(f) == 0:
        return np.zeros(0, np.int64)
    first = int(first)
    grid = (f - first) // stride  # the grid frames' numbers from 0
    on = (f - first) % stride == 0
    # the grid frames with rows and their counts (not a count for every frame up to the last,
    # which a stray frame number of 10^11 made 745 GiB)
    have, count = np.unique(grid[on], return_counts=True)
    gap = np.diff(have)
    k = np.flatnonzero((gap > 1) & (count[:-1] >= around) & (count[1:] >= around)
                       & (gap - 1 <= (np.inf if max_run is None else max_run)))
    runs = [np.arange(have[i] + 1, have[i + 1]) for i in k]
    return first + stride * (np.concatenate(runs) if runs else np.zeros(0, np.int64))


def detection_stride(frames: ArrayLike, min_frames: int = 10) -> int:
    """The detector's stride in a detections file: ``k`` where every row lies on one frame in
    ``k`` (the detector ran on every ``k``-th frame), 1 where rows lie on consecutive frames.

    The stride is the greatest common divisor of the gaps between the frames that have rows,
    taken only over ``min_frames`` such frames or more: a detector that runs on every frame
    gives rows on two consecutive frames somewhere, unless it finds almost nothing, and fewer
    frames could share a divisor by chance.

    Parameters
    ----------
    frames : (N,) array_like of int
        The rows' frame numbers.
    min_frames : int
        The fewest frames with rows to find a stride in.

    Returns
    -------
    int

    Raises
    ------
    ValueError
        If a frame is not a whole number (NaN, 3.9).

    Examples
    --------
    >>> detection_stride([1, 1, 4, 7, 10, 13, 16, 19, 22, 25, 28, 31])
    3
    >>> detection_stride([1, 4, 7, 8, 10, 13, 16, 19, 22, 25, 28])
    1
    >>> detection_stride([5, 10, 15])  # too few frames to tell
    1
    """
    f = np.unique(_frame_numbers(frames))
    if len(f) < min_frames:
        return 1
    return max(1, int(np.gcd.reduce(np.diff(f))))


def stride_warning(path: str | Path, first: int, stride: int, rate: float,
                   offline: bool) -> str:
    """What a run says of a detector run on every ``stride``-th frame alone."""
    return (f"{path}: detections on every {ordinal(stride)} frame only (frames "
            f"{first}, {first + stride}, {first + 2 * stride}, ...): tracked as a sequence of "
            "those frames "
            f"at {rate:.4g} frames/s; the frames between "
            + ("are filled on the line between the smoothed boxes" if offline else
               "have the tracks' predicted boxes") + " (score 0)")


def undelivered_text(skip: np.ndarray | tuple) -> str:
    """How many frames are without detections amid frames with many."""
    return (f"{len(skip)} frame{'s' if len(skip) > 1 else ''} without detections amid frames "
            f"with {UNDELIVERED_AROUND} or more each")


def undelivered_warning(path: str | Path, skip: np.ndarray, offline: bool) -> str:
    """What a run says of frames without detections amid frames with many."""
    shown = ", ".join(map(str, skip[:5].tolist())) + (", ..." if len(skip) > 5 else "")
    return (f"{path}: {undelivered_text(skip)} (frame"
            f"{'s' if len(skip) > 1 else ''} {shown}): taken as frames the detector did not "
            "deliver; the tracks are carried across them, and "
            + ("filled on the line between the smoothed boxes there" if offline else
               "given their predicted boxes there") + " (score 0)")
