"""Score results files against ground-truth files: what ``vistrack eval`` runs."""

from __future__ import annotations

from pathlib import Path

from ..io.motchallenge import read_mot, read_seqinfo
from .mot import MOTCounts, combine, evaluate_mot

__all__ = ["evaluate_files"]


def evaluate_files(pairs: list[tuple[str, Path, Path, Path | None]], *,
                   benchmark: str = "auto") -> dict[str, MOTCounts]:
    """Score ``(name, gt, results, seqinfo-or-None)`` pairs; adds ``"COMBINED"`` when there are
    several.

    Parameters
    ----------
    pairs : list of (str, Path, Path, Path or None)
        Each sequence's name, ground-truth file, results file and ``seqinfo.ini`` (which
        gives the number of frames; None: the files' last frame).
    benchmark : {"auto", "MOT15", "MOT16", "MOT17", "MOT20"}
        The ground truth's preprocessing, passed to
        :func:`~vistrack.evaluation.evaluate_mot`.

    Returns
    -------
    dict of str to MOTCounts
        The counts of each sequence by name, and ``"COMBINED"``, their sum, when there are
        several.

    Raises
    ------
    FileNotFoundError
        If a file does not exist.
    MOTFormatError
        If a file is malformed.
    ValueError
        If ``benchmark`` is not one of the names, or a file's rows go past the sequence.

    Examples
    --------
    Results that are the ground truth itself:

    >>> import tempfile
    >>> from vistrack.io import write_mot
    >>> gt = Path(tempfile.mkdtemp()) / "gt.txt"
    >>> _ = write_mot(gt, [1, 2, 3], [1, 1, 1], [[10, 20, 30, 60]] * 3)
    >>> scores = evaluate_files([("a", gt, gt, None), ("b", gt, gt, None)])
    >>> sorted(scores), scores["COMBINED"].TP, scores["a"].FN
    (['COMBINED', 'a', 'b'], 6, 0)
    """
    out: dict[str, MOTCounts] = {}
    for name, gt, pred, info in pairs:
        n = read_seqinfo(info).seq_length if info is not None else None
        out[str(name)] = evaluate_mot(read_mot(gt), read_mot(pred), n, benchmark=benchmark)
    if len(out) > 1:
        out["COMBINED"] = combine(out.values())
    return out
