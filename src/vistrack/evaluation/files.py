"""Score results files against ground-truth files: what ``vistrack eval`` runs."""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import TYPE_CHECKING, Any

from .._pool import one_line
from .._validate import as_whole
from ..io.motchallenge import (
    MOTTable,
    _text_without_header,
    check_column_names,
    read_mot,
    read_seq_length,
)
from .mot import (
    BENCHMARKS,
    Matches,
    MOTCounts,
    check_zero_distance,
    clear_matches,
    combine,
    evaluate_mot,
)
from .sanity import sanity_warnings

if TYPE_CHECKING:
    from concurrent.futures import Executor

__all__ = ["evaluate_files", "pair_matches", "EvalResults"]


class EvalResults(dict[str, MOTCounts]):
    """What :func:`evaluate_files` returns: a dict of each sequence's :class:`MOTCounts` by
    name, with the warnings of :func:`~vistrack.evaluation.sanity_warnings` about the files.

    Attributes
    ----------
    warnings : list of str
        One sentence per warning, naming the files, in the order of the sequences; empty when
        nothing looks wrong. ``vistrack eval`` prints each on stderr.
    errors : dict of str to str
        With ``keep_going``: each sequence that could not be scored, by name, and why (its
        error in one line); it is not among the scores, nor in ``"COMBINED"``.

    Examples
    --------
    >>> r = EvalResults({"a": MOTCounts(TP=3)}, warnings=["gt.txt looks like ..."])
    >>> r["a"].TP, r.warnings
    (3, ['gt.txt looks like ...'])
    """

    def __init__(self, *args, warnings: list[str] | None = None,
                 errors: dict[str, str] | None = None, **kwargs):
        super().__init__(*args, **kwargs)
        self.warnings: list[str] = list(warnings or [])
        self.errors: dict[str, str] = dict(errors or {})


def _score(pair: tuple[str, Path, Path, Path | None], benchmark: str, keep_going: bool = False,
           columns: dict[str, str] | None = None, zero_distance: float | None = None
           ) -> tuple[MOTCounts | None, list[str], str]:
    """One pair's counts, sanity warnings and (``keep_going``) the error that stopped it, in
    one line ("" if none; raised without ``keep_going``); in a worker, for
    :func:`evaluate_files`."""
    try:
        # the ground truth's warning goes with the scores (raised in a worker, jobs > 1 or
        # Dask's, it was said on the worker's stderr, or nowhere)
        g, p, n, said = _read(pair, columns, points=zero_distance is not None)
        return (evaluate_mot(g, p, n, benchmark=benchmark, zero_distance=zero_distance),
                said + sanity_warnings(g, p, zero_distance=zero_distance), "")
    except Exception as e:
        if not keep_going:
            raise
        return None, [], one_line(e)


def _read(pair: tuple[str, Path, Path, Path | None], columns: dict[str, str] | None = None,
          *, points: bool = False) -> tuple[MOTTable, MOTTable, int | None, list[str]]:
    """A pair's ground truth, results, sequence length (None without seqinfo.ini) and the
    ground truth's warnings (:func:`read_truth`'s, returned); ground truth in a CSV or
    Parquet file is read by its own columns' names, ``columns`` naming the results';
    ``points``, ``x, y`` alone read as points."""
    _, gt, pred, info = pair
    n = read_seq_length(info) if info is not None else None
    truth, said = _truth(gt, points=points)
    return truth, _read_results(Path(pred), columns, points), n, said


def read_truth(path: str | Path, *, points: bool = False) -> MOTTable:
    """A ground-truth file: MOTChallenge's text (named ``.csv`` too, without a header, as it
    always was read), or a CSV or Parquet file with a header, read by its own columns' names
    (:meth:`MOTTable.from_pandas <vistrack.io.MOTTable.from_pandas>`: a box; with
    ``points``, ``x, y`` alone as a point's, to be scored by distance)."""
    table, said = _truth(path, points=points)
    for message in said:
        warnings.warn(message, UserWarning, stacklevel=2)
    return table


def _truth(path: str | Path, *, points: bool = False) -> tuple[MOTTable, list[str]]:
    """:func:`read_truth`'s table and its warning, returned rather than warned."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix == ".parquet" or (suffix == ".csv" and not _text_without_header(path)):
        # (its own columns: without conf, every row counts, as a points file's always does)
        return MOTTable.from_pandas(_table_file(path, "ground-truth"), path=str(path),
                                    points=points, truth=True), []
    table = read_mot(path)
    if len(table) and table.columns < 7:
        # (its rows to ignore, conf 0 in MOTChallenge's ground truth, were counted as people
        # to find without a word: PETS09-S2L1's FN 941 became 1,091)
        return table, [f"{path}: {table.columns} values a row, no conf (MOTChallenge's 7th "
                       "value, 0 on the rows a benchmark ignores): every row is counted"]
    return table, []


def _table_file(path: Path, what: str) -> Any:
    """A Parquet or CSV file with a header (by its suffix) as a pandas DataFrame; ``what``
    it holds (``"results"``, ``"ground-truth"``) for its errors."""
    from ..io.motchallenge import _pandas, _read_csv, need_parquet

    if path.suffix.lower() == ".parquet":
        need_parquet()
        return _pandas(f"a Parquet {what} file").read_parquet(path)
    return _read_csv(path, f"a CSV {what} file")


def _read_results(path: Path, columns: dict[str, str] | None = None,
                  points: bool = False) -> MOTTable:
    """A results file: MOTChallenge's text, or the Parquet or CSV file ``vistrack track
    --out`` writes (``MOTTable.to_pandas``'s columns, or those ``columns`` names)."""
    suffix = path.suffix.lower()
    if suffix not in (".parquet", ".csv"):
        if columns and not path.exists():  # what is wrong is that it is missing
            raise FileNotFoundError(f"{path} does not exist")
        if columns:
            raise ValueError(f"columns name a CSV or Parquet file's columns; {path} is read as "
                             "a MOTChallenge text file")
        return read_mot(path)
    return MOTTable.from_pandas(_table_file(path, "results"), columns, path=str(path),
                                points=points)


def _score_on(executor: Executor, pairs: list[tuple[str, Path, Path, Path | None]],
              benchmark: str, keep_going: bool, columns: dict[str, str] | None = None,
              zero_distance: float | None = None
              ) -> list[tuple[MOTCounts | None, list[str], str]]:
    """Each pair's :func:`_score`, all submitted to ``executor`` at once, in the pairs' order;
    with ``keep_going``, a pair's worker failure (a pool broken by a worker's death, an
    executor's own error) as its error."""
    futures = [executor.submit(_score, pair, benchmark, keep_going, columns, zero_distance)
               for pair in pairs]
    scored = []
    for future in futures:
        try:
            scored.append(future.result())
        except Exception as e:
            if not keep_going:
                raise
            scored.append((None, [], one_line(e)))
    return scored


def _check_pair(pair: Any, name: str) -> None:
    if not isinstance(pair, (tuple, list)) or len(pair) != 4:
        raise ValueError(f"a pair is a (name, gt, results, seqinfo or None) tuple; {name} is "
                         f"{pair!r}")


def pair_matches(pair: tuple[str, Path, Path, Path | None], benchmark: str = "auto",
                 columns: dict[str, str] | None = None,
                 zero_distance: float | None = None) -> Matches:
    """The CLEAR MOT matches of one ``(name, gt, results, seqinfo-or-None)`` pair, frame by
    frame (:func:`~vistrack.evaluation.clear_matches`), read and scored as
    :func:`evaluate_files` does (a CSV or Parquet file's ``columns`` named as there;
    positions by distance with ``zero_distance``)."""
    _check_pair(pair, "pair")
    g, p, n, said = _read(pair, columns, points=zero_distance is not None)
    for message in said:
        warnings.warn(message, UserWarning, stacklevel=2)
    return clear_matches(g, p, n, benchmark=benchmark, zero_distance=zero_distance)


def evaluate_files(pairs: list[tuple[str, Path, Path, Path | None]], *,
                   benchmark: str = "auto", jobs: int | None = None,
                   executor: Executor | None = None, keep_going: bool = False,
                   columns: dict[str, str] | None = None,
                   zero_distance: float | None = None) -> EvalResults:
    """Score ``(name, gt, results, seqinfo-or-None)`` pairs; adds ``"COMBINED"`` when there are
    several. Files that look unrelated, or ground truth that looks like detections, are warned
    about in the result's ``warnings`` (:func:`~vistrack.evaluation.sanity_warnings`).

    Parameters
    ----------
    pairs : list of (str, Path, Path, Path or None)
        Each sequence's name, ground-truth file, results file (MOTChallenge's text, or the
        ``.parquet`` or ``.csv`` file ``vistrack track --out`` writes) and ``seqinfo.ini`` (which
        gives the number of frames; None: the files' last frame). Ground truth may be a CSV or
        Parquet file too, read by its own columns' names (``frame``, ``id`` or ``particle``,
        and a box or, for points, ``x, y``).
    benchmark : {"auto", "MOT15", "MOT16", "MOT17", "MOT20"}
        The ground truth's preprocessing, passed to
        :func:`~vistrack.evaluation.evaluate_mot`.
    jobs : int, optional
        Score this many pairs at once, on a pool of processes (default 1: one after the
        other, in this process); the same scores either way.
    executor : concurrent.futures.Executor, optional
        Score the pairs there instead (``submit(fn, *args) -> future``; a Dask client's
        executor works).
    keep_going : bool
        A pair that cannot be read or scored (the errors below, or its worker's failure: the
        pool's or the executor's) is left out and named in the result's ``errors``, and the
        others are scored (True); or its error is raised (False).
    columns : dict, optional
        The names of the results' columns in CSV or Parquet files, ``{ours: theirs}``
        (:meth:`MOTTable.from_pandas <vistrack.io.MOTTable.from_pandas>`; ``vistrack eval
        --columns``).
    zero_distance : float, optional
        Score positions rather than boxes, by their distance
        (:func:`~vistrack.evaluation.evaluate_mot`; ``vistrack eval --zero-distance``).

    Returns
    -------
    EvalResults
        A dict: the counts of each sequence by name, and ``"COMBINED"``, their sum, when
        several were scored; its ``warnings`` list the sanity warnings of every pair, its
        ``errors`` the pairs left out.

    Raises
    ------
    FileNotFoundError
        If a file does not exist.
    MOTFormatError
        If a file is malformed.
    ValueError
        If a pair is not four items, two pairs have one name (or one is named
        ``"COMBINED"``), ``benchmark`` is not one of the names, ``zero_distance`` is not a
        finite number > 0 (without it, a file of points alone), or a file's rows
        go past the sequence, hold an id twice in a frame or (ground truth of MOT16/17/20) a
        class outside 1-13, naming the file and the line(s) of the row (see
        :func:`~vistrack.evaluation.evaluate_mot`).

    Examples
    --------
    Results that are the ground truth itself:

    >>> import tempfile
    >>> from vistrack.io import write_mot
    >>> gt = Path(tempfile.mkdtemp()) / "gt.txt"
    >>> _ = write_mot(gt, [1, 2, 3], [1, 1, 1], [[10, 20, 30, 60]] * 3)
    >>> scores = evaluate_files([("a", gt, gt, None), ("b", gt, gt, None)])
    >>> sorted(scores), scores["COMBINED"].TP, scores["a"].FN, scores.warnings
    (['COMBINED', 'a', 'b'], 6, 0, [])
    """
    out = EvalResults()
    if jobs is not None:
        jobs = as_whole(jobs, "jobs", 1)
    # any iterable of pairs (a zip, a generator): the checks below would use one up
    pairs = list(pairs)
    if benchmark not in BENCHMARKS:  # an argument's error, not a file's (keep_going)
        raise ValueError(f"benchmark must be one of {', '.join(map(repr, BENCHMARKS))}; got "
                         f"{benchmark!r}")
    if zero_distance is not None:  # (the same: not one pair's error)
        zero_distance = check_zero_distance(zero_distance)
    if columns is not None:  # (the same: a misspelt name failed every pair, one by one)
        columns = check_column_names(columns)
    for k, pair in enumerate(pairs):
        _check_pair(pair, f"pairs[{k}]")
    seen: dict[str, int] = {}
    for k, (name, gt, *_) in enumerate(pairs):
        # the results are keyed by the name as text: two pairs of one name would keep one
        # (one pair alone has no sum: a sequence folder of that name was refused)
        if str(name) == "COMBINED" and len(pairs) > 1:
            raise ValueError(f"pairs[{k}] ({gt}) is named 'COMBINED', the name of the sum of "
                             "all: give its sequence another name")
        if str(name) in seen:
            raise ValueError(f"pairs[{seen[str(name)]}] and pairs[{k}] are both named "
                             f"{str(name)!r}: each pair needs a name of its own")
        seen[str(name)] = k
    if executor is None and (jobs or 1) > 1 and len(pairs) > 1:
        from .._pool import process_pool  # one BLAS thread a worker

        with process_pool(min(jobs or 1, len(pairs)), imports=(__name__,)) as pool:
            scored = _score_on(pool, pairs, benchmark, keep_going, columns, zero_distance)
    elif executor is not None:
        # its workers' working folders are their own (Dask's): the files' paths absolute,
        # or relative ones were looked for there
        anywhere = [(name, Path(gt).absolute(), Path(pred).absolute(),
                     None if info is None else Path(info).absolute())
                    for name, gt, pred, info in pairs]
        scored = _score_on(executor, anywhere, benchmark, keep_going, columns, zero_distance)
    else:
        scored = [_score(pair, benchmark, keep_going, columns, zero_distance)
                  for pair in pairs]
    for (name, *_), (counts, warned, error) in zip(pairs, scored):
        out.warnings += warned
        if counts is None:
            out.errors[str(name)] = error
        else:
            out[str(name)] = counts
    if len(out) > 1:
        out["COMBINED"] = combine(out.values())
    return out
