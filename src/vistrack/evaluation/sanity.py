"""Checks that a ground-truth file and a results file belong together, before they are scored:
what ``vistrack eval`` warns about. The scores of unrelated files are valid numbers (MOTA near
0 or below), so a mistake such as another sequence's results, or a detections file given as
ground truth, would otherwise go unnoticed."""

from __future__ import annotations

import numpy as np

from .._pool import frames_text
from ..io.motchallenge import MOTTable
from .mot import _lines_of, _similarity, _where

__all__ = ["sanity_warnings", "looks_like_detections"]


def looks_like_detections(table: MOTTable) -> str:
    """Why ``table`` looks like a detections (or results) file rather than ground truth, or
    ``""``.

    Ground truth has identities, a "consider" flag of 0 or 1 in column 7 and (MOT16/17/20) a
    class in column 8. A detections file has every id -1 and a detector's score in column 7;
    a results file has scores and no class.

    Parameters
    ----------
    table : MOTTable
        From :func:`vistrack.io.read_mot`.

    Returns
    -------
    str
        The reason, e.g. ``"every id is -1"``; empty when the table may be ground truth.

    Examples
    --------
    >>> det = MOTTable.from_rows([(1, -1, 0, 0, 10, 20, 0.9), (1, -1, 5, 5, 10, 20, 0.4)])
    >>> looks_like_detections(det)
    'every id is -1'
    >>> res = MOTTable.from_rows([(1, 1, 0, 0, 10, 20, 0.93, -1, -1, -1)])
    >>> looks_like_detections(res)
    'its column 7 holds scores (0.93) where ground truth has 0 or 1, and it has no class column'
    >>> looks_like_detections(MOTTable.from_rows([(1, 1, 0, 0, 10, 20, 1, 1, 0.8)]))
    ''
    """
    if not len(table):
        return ""
    if (table.ids == -1).all():
        return "every id is -1"
    scores = ~np.isin(table.conf, (0.0, 1.0))
    if scores.any() and (table.columns < 8 or (table.classes == -1).all()):
        return (f"its column 7 holds scores ({table.conf[scores][0]:g}) where ground truth has "
                "0 or 1, and it has no class column")
    return ""


_CHANCE = 0.1  # the share of predicted boxes meeting a ground-truth box below which they are
# unrelated


def _frames(t: MOTTable) -> str:
    return f"frames {int(t.frames.min())}-{int(t.frames.max())}"


def sanity_warnings(gt: MOTTable, pred: MOTTable, *, empty_said: bool = False,
                    zero_distance: float | None = None) -> list[str]:
    """Warnings that ``gt`` and ``pred`` may not be ground truth and results of one sequence.

    - ``gt`` looks like a detections or results file (:func:`looks_like_detections`);
    - the two share no frame, or no predicted box overlaps a ground-truth box by IoU ≥ 0.5 in
      any frame, "predictions and ground truth look unrelated". In crowded scenes unrelated
      boxes meet by chance (up to 5 % of the predicted boxes of one MOT17 sequence meet the
      ground truth of another; a detector's 87-99 %): fewer than 10 % of the predicted boxes
      of the common frames meeting one is warned about too.

    - a quarter or more of ``pred``'s rows lie past ``gt``'s last frame, where each counts
      as a false positive (a ground truth of part of the sequence);
    - ``pred`` is empty while ``gt`` is not: every ground-truth box counts as missed (a
      tracker may find nothing, but a results file of no rows is more often the wrong file,
      or a run whose thresholds no detection reached). An empty ``gt`` is not warned about
      (a sequence without objects).

    Parameters
    ----------
    gt, pred : MOTTable
        From :func:`vistrack.io.read_mot`, sorted by frame; their ``path`` names them.
    empty_said : bool
        Whether the caller has already said why ``pred`` or ``gt`` is empty (a run whose
        front-end found nothing, or a ground truth with no row on the frames tracked): then
        its emptiness is not warned of again.
    zero_distance : float, optional
        Positions scored by distance (:func:`~vistrack.evaluation.evaluate_mot`): a
        predicted position meets the ground truth within half of it, not a box by IoU.

    Returns
    -------
    list of str
        One sentence per warning, naming the files; empty when nothing looks wrong.

    Examples
    --------
    >>> gt = MOTTable.from_rows([(f, 1, 10 * f, 0, 20, 40, 1, 1, 1.0) for f in (1, 2, 3)],
    ...                         path="gt.txt")
    >>> sanity_warnings(gt, MOTTable.from_rows([(2, 7, 21, 1, 20, 40)], path="res.txt"))
    []
    >>> far = MOTTable.from_rows([(f, 7, 500, 500, 20, 40) for f in (1, 2)], path="res.txt")
    >>> print(*sanity_warnings(gt, far))
    predictions and ground truth look unrelated: no box of res.txt overlaps a box of gt.txt by IoU >= 0.5 in any of their 2 common frames
    >>> late = MOTTable.from_rows([(f, 7, 10, 0, 20, 40) for f in (8, 9)], path="res.txt")
    >>> print(*sanity_warnings(gt, late))
    predictions and ground truth look unrelated: res.txt has frames 8-9 and gt.txt frames 1-3, no frame in common
    >>> print(*sanity_warnings(gt, MOTTable.from_rows([], path="res.txt")))
    res.txt holds no rows: the 3 rows of gt.txt on its frames 1-3 count as missed (FN) or ignored
    """  # noqa: E501
    out = []
    gname, pname = gt.path or "the ground truth", pred.path or "the predictions"
    why = looks_like_detections(gt)
    if why:
        out.append(f"{gname} looks like a detections or results file, not ground truth: {why}")
    mot17 = np.isin(gt.classes, np.arange(1, 14)) if gt.columns >= 8 and len(gt) else None
    if mot17 is not None and 0.5 <= mot17.mean() < 1:
        # MOT16/17/20 columns with a few classes that are none of theirs: --benchmark auto
        # then scores the file as MOT15, without their preprocessing
        bad = gt.classes[~mot17][0]
        lines = _lines_of(gt.path, lambda row: len(row) >= 8 and row[7] == bad)[:1]
        out.append(f"{_where(gt, 'the ground truth', lines)}: class {bad:g} is not a MOT16/17/20 "
                   "class (1-13), though most rows have one: --benchmark auto scores the file "
                   "as MOT15, without their preprocessing (--benchmark MOT17 refuses it, naming "
                   "the row)")
    elif gt.columns in (8, 9) and len(gt) and (gt.classes == -1).all():
        # a value in column 8 that is not a whole number makes the reader take the column
        # for no classes at all (MOT15's world x): one such row among MOT16/17/20 classes
        # turns the whole file into MOT15's convention
        odd: list[float] = []

        def fraction(row: list[float]) -> bool:
            if len(row) in (8, 9) and not float(row[7]).is_integer():
                odd.append(row[7])
                return True
            return False

        lines = _lines_of(gt.path, fraction)[:1]
        if lines:
            out.append(f"{_where(gt, 'the ground truth', lines)}: class {odd[0]:g} is not a "
                       "whole number, so no value of column 8 is read as a class: --benchmark "
                       "auto scores the file as MOT15, without the preprocessing of MOT16/17/20 "
                       "(--benchmark MOT17 refuses it, naming the row)")
    if len(gt) and not len(pred) and not empty_said:
        out.append(f"{pname} holds no rows: the {len(gt)} rows of {gname} on its "
                   f"{_frames(gt)} count as missed (FN) or ignored")
    if len(pred) and not len(gt) and not empty_said:  # (all false positives, unsaid)
        out.append(f"{gname} holds no rows: the {len(pred)} rows of {pname} on its "
                   f"{_frames(pred)} count as false positives (FP)")
    if not len(gt) or not len(pred):
        return out
    common = np.intersect1d(gt.frames, pred.frames)
    if not len(common):
        out.append(f"predictions and ground truth look unrelated: {pname} has {_frames(pred)} "
                   f"and {gname} {_frames(gt)}, no frame in common")
        return out
    last = int(gt.frames.max())
    late = pred.frames[pred.frames > last]
    if len(late) and len(late) >= 0.25 * len(pred):
        # (a ground truth cut short scored every later row as a false positive, without a
        # word: MOTA -660 for results past a ground truth of the first 100 frames)
        on = frames_text(int(late.min()), int(late.max()))
        out.append(f"{len(late)} of the {len(pred)} rows of {pname} lie past the last frame of "
                   f"{gname} ({last}), on {on}: each counts as a false positive (a ground "
                   "truth of part of the sequence?)")
    gs = np.searchsorted(gt.frames, common, side="left"), np.searchsorted(gt.frames, common,
                                                                           side="right")
    ps = np.searchsorted(pred.frames, common, side="left"), np.searchsorted(pred.frames, common,
                                                                             side="right")
    boxes = int(np.sum(ps[1] - ps[0]))  # predicted boxes in the common frames
    similarity = _similarity(gt, pred, zero_distance)
    hits = 0
    for g0, g1, p0, p1 in zip(*gs, *ps):
        hits += int((similarity(gt.boxes[g0:g1], pred.boxes[p0:p1]) >= 0.5).any(0).sum())
        if hits >= _CHANCE * boxes:
            return out
    one, many = ("box", "boxes") if zero_distance is None else ("position", "positions")

    def meet(s: str) -> str:  # (verb's ending) where a predicted row meets the ground truth
        return (f"overlap{s} a box of {gname} by IoU >= 0.5" if zero_distance is None else
                f"lie{s} within {zero_distance / 2:g} of a position of {gname}")

    if hits:
        out.append(f"predictions and ground truth look unrelated: only {hits} of the {boxes} "
                   f"{many} of {pname} in their {len(common)} common frames {meet('')}")
    else:
        out.append(f"predictions and ground truth look unrelated: no {one} of {pname} "
                   f"{meet('s')} in any of their {len(common)} common frames")
    return out
