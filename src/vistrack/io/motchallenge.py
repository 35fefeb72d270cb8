"""MOTChallenge files: detections, ground truth and results (``det.txt``, ``gt.txt``, results),
and ``seqinfo.ini``.

Every row is ``frame, id, left, top, width, height, conf, ...``, frames from 1, its values
separated by commas (or, on a line without a comma, by spaces or tabs, as TrackEval and
py-motmetrics read them too; a separator ending the line is ignored; blank lines, and ``#``
comments to the end of a line, are skipped, as numpy's ``loadtxt`` skips them):

- detections: ``id = -1``, ``conf`` the detector's score;
- ground truth (MOT16/17/20): ``conf`` is 0 for boxes to ignore, then ``class`` and
  ``visibility``; MOT15 ground truth has ``-1, -1, -1`` (world coordinates) there instead, so
  its class is -1;
- results: ``frame, id, left, top, width, height, conf, -1, -1, -1``.

Rows need not be sorted: :func:`read_mot` sorts them by frame (stably, so rows of one frame keep
their order). A malformed row raises :class:`MOTFormatError` naming the file, line and column; a
file that is not UTF-8 text raises it naming the file. A UTF-8 byte-order mark and Windows
(CRLF) line ends are read as plain text.
"""

from __future__ import annotations

import ast
import configparser
import csv
import difflib
import importlib
import itertools
import math
import numbers
import os
import re
import warnings
from collections.abc import Generator, Sequence
from contextlib import closing
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any, overload

import numpy as np

from .._validate import as_finite, as_float_array, as_whole, decode_text, text_number
from .atomic import check_output, replacing

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

    from ..types import _Index

__all__ = ["FrameSlices", "MOTFormatError", "MOTTable", "SeqInfo", "read_mot", "write_mot",
           "box_decimals", "read_seqinfo", "read_seq_length", "MOT_CLASSES", "sequence_name"]

MOT_CLASSES = {
    1: "pedestrian", 2: "person_on_vehicle", 3: "car", 4: "bicycle", 5: "motorbike",
    6: "non_mot_vehicle", 7: "static_person", 8: "distractor", 9: "occluder",
    10: "occluder_on_ground", 11: "occluder_full", 12: "reflection", 13: "crowd",
}
"""The class numbers of MOT16/17/20 ground truth."""

_NAMES = ("frame", "id", "left", "top", "width", "height", "conf", "class", "visibility", "z")


class MOTFormatError(ValueError):
    """A MOTChallenge file that cannot be read; the message names the file, and the line and
    column of a bad row.

    A ``ValueError``; :func:`read_mot` and :func:`read_seqinfo` raise it.

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "gt.txt")
    >>> _ = open(p, "w").write("1,1,0,0,-3,4\\n")
    >>> try:
    ...     read_mot(p)
    ... except MOTFormatError as e:
    ...     print(str(e).split(", ", 1)[1])
    line 1, column 5 (width): width must be >= 0; got -3
    """


def _pandas(what: str) -> Any:
    try:
        import pandas
    except ImportError as e:  # pragma: no cover - pandas is there wherever trackpy is
        raise ImportError(f"{what} needs pandas (pip install pandas)") from e
    return pandas


def _csv_dialect(path: str | os.PathLike) -> dict[str, str]:
    """``read_csv``'s ``sep`` (and ``decimal``) for a CSV file, from its header (and rows):
    commas; or, where the header has none, tabs or semicolons (a spreadsheet's export), a
    semicolon file's numbers with decimal commas where any of its rows has a comma (its
    first rows may hold whole numbers only)."""
    with open(path, encoding="utf-8-sig", errors="replace") as fh:
        # the first line that is not blank, as pandas takes for the header (a blank first
        # line made a semicolon file's header, of no separator, one of commas)
        header = next((line for line in fh if line.strip(" \t\r\n")), "")
        if "," in header or not ("\t" in header or ";" in header):
            return {"sep": ","}
        if "\t" in header:
            return {"sep": "\t"}
        # a comma in a semicolon file is a decimal one
        return {"sep": ";", "decimal": ","} if any("," in row for row in fh) else {"sep": ";"}


def _read_csv(path: str | os.PathLike, what: str) -> Any:
    """A CSV file with a header as a DataFrame, its values separated by commas, or by tabs or
    semicolons where its header has no comma (:func:`_csv_dialect`); a row of more or fewer
    values than the header is a :class:`MOTFormatError` naming the file and the line (``"PATH,
    line 3: 4 values where the header has 6"``), another file pandas cannot parse (an empty
    file) one naming the file, in pandas' own words (``"PATH: not WHAT: No columns to parse
    from file"``), and so is a file that is not UTF-8 text (:func:`_not_utf8`)."""
    pandas = _pandas(what)
    dialect = _csv_dialect(path)
    try:
        # spaces after the separators skipped, as read_mot skips them: a header "frame, id,
        # bb_left, ..." named its columns " id", " bb_left" and lost every one
        df = pandas.read_csv(path, skipinitialspace=True, **dialect)
    except (pandas.errors.ParserError, pandas.errors.EmptyDataError) as e:
        _check_row_lengths(path, dialect["sep"])
        reason = re.sub(r"^(Error tokenizing data\. )?(C error: )?", "", str(e).strip())
        raise MOTFormatError(f"{path}: not {what}: {reason}") from None
    except UnicodeDecodeError as e:
        # pandas names neither the file nor the byte (its position counts from the start of
        # the piece it was decoding)
        raise _not_utf8(path, e) from None
    if any("\x00" in str(c) for c in df.columns):  # UTF-16 without a byte-order mark
        raise _not_utf8(path, None)
    df.columns = [c.strip() if isinstance(c, str) else c for c in df.columns]  # "id " too
    _check_header_names(path, dialect["sep"])
    if not df.index.equals(pandas.RangeIndex(len(df))) or _first_row_longer(path,
                                                                          dialect["sep"]):
        # every row one value longer than the header: pandas took the first column for the
        # index and read each of the others under the name of the one before it (its first
        # values counting 0, 1, 2, ... made that index a range, and the rows were read
        # shifted without a word)
        _check_row_lengths(path, dialect["sep"])
    if df.isna().to_numpy().any():
        # pandas fills a short row's missing values with NaN, named later as empty cells
        _check_row_lengths(path, dialect["sep"])
    # its rows are the file's, in order: MOTTable.from_pandas names a bad value by its line
    df.attrs["csv_sep"] = dialect["sep"]
    return df


def _csv_lines(path: str | os.PathLike, sep: str) -> Generator[tuple[int, list[str]], None, None]:
    """A CSV file's rows as pandas reads them (spaces after a separator skipped), each with
    the line it starts on: ``(line, values)``, blank lines skipped: empty or unquoted spaces
    and tabs alone, as pandas skips them (``""`` or a no-break space is a row of one value)."""
    with open(path, encoding="utf-8-sig", newline="") as fh:
        text: list[str] = []  # the lines of the row being read

        def kept() -> Generator[str, None, None]:
            for line in fh:
                text.append(line)
                yield line

        rows = csv.reader(kept(), delimiter=sep, skipinitialspace=True)
        start = 1
        for row in rows:
            if "".join(text).strip(" \t\r\n"):
                yield start, row
            text.clear()
            start = rows.line_num + 1  # (a quoted value may hold line breaks)


def _csv_body(path: str | os.PathLike, sep: str
              ) -> tuple[int, list[str], Generator[tuple[int, list[str]], None, None]] | None:
    """A CSV file's header, the line it is on, and the rows after it (:func:`_csv_lines`);
    None where it has no header: no row, or a first row of numbers only (a MOTChallenge text
    file named .csv, which the reader names later)."""
    lines = _csv_lines(path, sep)
    line, header = next(lines, (0, []))
    if not header or _all_numbers(header):
        lines.close()
        return None
    return line, header, lines


def _check_header_names(path: str | os.PathLike, sep: str) -> None:
    """Raise a :class:`MOTFormatError` naming a column that a CSV file's header names twice
    (pandas reads the second as ``conf.1``, a column nothing then reads)."""
    body = _csv_body(path, sep)
    if body is None:
        return
    line, header, rows = body
    rows.close()
    names = [c.strip() for c in header]
    twice = next((c for k, c in enumerate(names) if c and c in names[:k]), None)
    if twice is not None:
        raise MOTFormatError(f"{path}, line {line}: the header names column {twice!r} twice; "
                             "name each column once")


def _check_row_lengths(path: str | os.PathLike, sep: str) -> None:
    """Raise a :class:`MOTFormatError` naming the first line of a CSV file whose number of
    values is not the header's (blank lines skipped, as pandas skips them)."""
    body = _csv_body(path, sep)
    if body is None:
        return
    _, header, rows = body
    with closing(rows):
        for line, row in rows:
            if len(row) != len(header):
                raise MOTFormatError(f"{path}, line {line}: {len(row)} values where the "
                                     f"header has {len(header)}")


def _first_row_longer(path: str | os.PathLike, sep: str) -> bool:
    """Whether a CSV file's first row after its header has more values than the header
    (pandas then takes the first column for the index, from that row alone)."""
    body = _csv_body(path, sep)
    if body is None:
        return False
    _, header, rows = body
    with closing(rows):
        return len(next(rows, (0, header))[1]) > len(header)


def _csv_row_line(path: str | os.PathLike, sep: str, k: int) -> int | None:
    """The line of a CSV file that its row ``k`` after the header starts on, as pandas
    counts its rows (:func:`_csv_lines`); None where it has no such row, or no header."""
    try:
        body = _csv_body(path, sep)
    except (OSError, UnicodeDecodeError, csv.Error):  # (for a message: the row's place, then)
        return None
    if body is None:
        return None
    with closing(body[2]) as rows:
        return next(itertools.islice(rows, k, None), (None, []))[0]


def _csv_detection_line(path: str | os.PathLike, columns: dict[str, str] | None, frame: int,
                        box: list[float] | None) -> int | None:
    """The line of a CSV file of detections (with its header) of its first row of ``frame``
    (and ``box``, as :meth:`MOTTable.from_pandas` reads it, its columns named by
    ``columns``), for a message; None where there is none or the file cannot be read again.
    The file is read again with each row's place in it for its score, which the table
    carries through its sorting by frame."""
    try:
        df = _read_csv(path, "a CSV file of detections")
        sep = df.attrs["csv_sep"]
        df[(columns or {}).get("conf", "conf")] = np.arange(len(df), dtype=float)
        table = MOTTable.from_pandas(df, columns, path=os.fspath(path))
    except (OSError, ValueError, TypeError, ImportError):
        return None
    hit = table.frames == frame
    if box is not None:
        hit &= (table.boxes == np.asarray(box, dtype=float)).all(axis=1)
    if not hit.any():
        return None
    return _csv_row_line(path, sep, int(table.conf[hit].min()))


def _not_utf8(path: str | os.PathLike, exc: UnicodeDecodeError | None) -> MOTFormatError:
    """The error for a CSV file that is not UTF-8 text, naming it and the first byte (from the
    file's start, a byte-order mark counted) that is not UTF-8 or is a NUL byte, as read_mot
    names a text file's: ``"PATH is not a text CSV file (byte 20: b'\\xf6' is not UTF-8);
    save it as UTF-8"``. ``exc``: pandas' error, for its reason should the file's bytes decode
    (they did not, for pandas)."""
    data = Path(path).read_bytes()
    try:
        data.decode("utf-8")  # (a byte-order mark decodes: the position is the file's)
    except UnicodeDecodeError as e:
        why = f"byte {e.start}: {data[e.start:e.start + 1]!r} is not UTF-8"
    else:
        nul = data.find(b"\x00")
        why = f"byte {nul} is a NUL byte" if nul >= 0 else (exc.reason if exc else "not UTF-8")
    # Excel's "Unicode Text" export: UTF-16, its byte-order mark first, or (none) a NUL byte
    # beside each ASCII one
    head = data[:64]
    utf16 = head[:2] in (b"\xff\xfe", b"\xfe\xff") or (
        len(head.strip(b"\x00")) > 1 and (set(head[1::2]) == {0} or set(head[::2]) == {0}))
    return MOTFormatError(f"{path} is not a text CSV file ({why}); save it as UTF-8"
                          + (" (it looks like UTF-16 text)" if utf16 else ""))


def need_parquet() -> None:
    """Raise ImportError, saying what to install, unless pandas and pyarrow are there."""
    for name in ("pandas", "pyarrow"):
        try:
            importlib.import_module(name)
        except ImportError as e:
            raise ImportError(f"writing Parquet needs pandas and pyarrow; {name} is missing "
                              "(pip install 'vistrack[parquet]')") from e


@dataclass(frozen=True)
class MOTTable:
    """The rows of one MOTChallenge file, as columns, sorted by frame.

    Attributes
    ----------
    frames, ids : (N,) int
        Frame (from 1) and identity of each row (-1 for detections).
    boxes : (N, 4) float
        ``left, top, width, height`` in pixels.
    conf : (N,) float
        Score (detections, results) or the ground truth's "consider" flag (0: ignore).
    classes : (N,) int
        Column 8: the ground-truth class of MOT16/17/20, or the detector's; -1 where absent,
        and in every row where any row's is not an integer below 2**53 in size (MOT15
        ground truth and MOTChallenge's detections files hold a world ``x`` there).
    visibility : (N,) float
        Column 9 of MOT16/17/20 ground truth, -1 where absent, and in every row where
        column 8 is a world ``x`` (above) or any row's column 9 is not a share from 0 to 1
        (MOT15 ground truth's world ``y``).
    path : str
        The file read, for messages.
    columns : int
        Values per row in the file (MOT16/17/20 ground truth: 9; MOT15 and results: 10).

    Examples
    --------
    ``len()`` counts the rows; a boolean mask or indices select some:

    >>> t = MOTTable.from_rows([(1, 1, 0, 0, 10, 20), (1, 2, 5, 5, 10, 20), (2, 1, 1, 0, 10, 20)])
    >>> len(t), t[t.ids == 1].frames.tolist(), t.boxes[1].tolist()
    (3, [1, 2], [5.0, 5.0, 10.0, 20.0])
    """

    frames: np.ndarray
    ids: np.ndarray
    boxes: np.ndarray
    conf: np.ndarray
    classes: np.ndarray
    visibility: np.ndarray
    path: str = ""
    columns: int = 10

    def __len__(self) -> int:
        return int(self.frames.shape[0])

    @classmethod
    def from_rows(cls, rows: ArrayLike, path: str = "") -> MOTTable:
        """From rows ``frame, id, left, top, width, height[, conf, class, visibility, ...]``
        (at least 6 values each; the rest default to conf 1, class -1, visibility -1), sorted
        by frame.

        Parameters
        ----------
        rows : (N, w) array_like
            The rows, ``6 <= w``; values past the ninth are not kept.
        path : str
            The file they come from, for messages.

        Returns
        -------
        MOTTable
            The rows sorted by frame (stably), with ``columns = w``.

        Raises
        ------
        ValueError
            If ``rows`` is not 2-D (a single row not in a list), or the rows have fewer
            than 6 values; :class:`MOTFormatError` (a ``ValueError``)
            naming the row and value for one the table cannot hold as given: a value that is
            not finite, a frame or identity that is not an integer (1.7 was frame 1) or lies
            from 2**53 on. A frame of 0 or a negative width it holds, as a tracker that
            counts from 0 writes them, and :func:`~vistrack.evaluation.evaluate_mot` names
            them.
        TypeError
            If ``rows`` are not numbers (text, or rows of different lengths).

        Examples
        --------
        >>> t = MOTTable.from_rows([(2, 1, 0, 0, 10, 20), (1, 1, 5, 5, 10, 20)])
        >>> t.frames.tolist(), t.conf.tolist()
        ([1, 2], [1.0, 1.0])
        """
        a = as_float_array(rows, "rows")  # (ragged rows, or text, failed in numpy's words)
        if a.ndim != 2:
            if a.size:
                # (a flat row of 12 values was cut into two rows, one of 7 failed in a
                # reshape's words)
                raise ValueError(f"rows must be a list of rows, (N, w); got shape {a.shape}"
                                 + (" (one row: [row])" if a.ndim == 1 else ""))
            a = a.reshape(0, 6)  # (no rows: [])
        if a.shape[1] < 6:
            raise ValueError(f"rows need at least 6 values (frame, id, box); got {a.shape[1]}")
        # what the table cannot hold as given (a frame of 1.7 was frame 1); a frame of 0 or a
        # negative width it holds, and evaluate_mot names them
        where = f"{path}, " if path else ""
        for col, bad, text in ((None, lambda v: ~np.isfinite(v), "not a finite number"),
                               (0, lambda v: v != np.round(v), "frame must be an integer"),
                               (0, lambda v: np.abs(v) >= _INT_LIMIT, "frame must lie "
                                                                       "within ±(2**53 - 1)"),
                               (1, lambda v: v != np.round(v), "id must be an integer"),
                               (1, lambda v: np.abs(v) >= _INT_LIMIT, "id must lie "
                                                                       "within ±(2**53 - 1)")):
            broken = bad(a) if col is None else bad(a[:, col])[:, None]
            if broken.any():
                i, j = (int(v) for v in np.argwhere(broken)[0])
                c = j if col is None else col
                name = _NAMES[c] if c < len(_NAMES) else f"value {c + 1}"
                raise MOTFormatError(f"{where}row {i + 1}, value {c + 1} ({name}): {text}; got "
                                     f"{_shown(a[i, c])}")
        # (np.take copies whole rows 2-3 times faster than a[order])
        return cls._of(np.take(a, np.argsort(a[:, 0], kind="stable"), axis=0), path)

    @classmethod
    def _of(cls, a: np.ndarray, path: str) -> MOTTable:
        """The table of the rows ``a`` (float, sorted by frame), which it keeps (its conf and
        visibility are views of ``a``)."""
        N, w = a.shape

        def col(j: int, fill: float) -> np.ndarray:
            return a[:, j] if w > j else np.full(N, fill, dtype=float)

        c, v = col(7, -1.0), col(8, -1.0)
        if w > 7 and not ((c == np.round(c)) & (np.abs(c) < _INT_LIMIT)).all():
            # a class is an integer: a column holding anything else is MOT15's world x (as
            # detections files have it there too, -1 where there is none), and none of its
            # values is a class, a whole number among them (a world x of 3.000) no more
            # than the rest; the column after it is then the world y, no visibility (it was
            # read as one: 3.3 to 143 on ETH-Bahnhof)
            c = v = np.full(N, -1.0)
        elif w > 8 and not (((v >= 0) & (v <= 1)) | (v == -1)).all():
            # a visibility is a share, 0 to 1 (-1: none given): anything else is a world y
            # (beside a world x of whole numbers)
            v = np.full(N, -1.0)
        return cls(frames=a[:, 0].astype(np.int64), ids=a[:, 1].astype(np.int64),
                   boxes=np.ascontiguousarray(a[:, 2:6]), conf=col(6, 1.0),
                   classes=c.astype(np.int64), visibility=v, path=path, columns=w)

    def __getitem__(self, index: _Index) -> MOTTable:
        """Rows by boolean mask or indices."""
        return MOTTable(self.frames[index], self.ids[index], self.boxes[index], self.conf[index],
                        self.classes[index], self.visibility[index], self.path, self.columns)

    def to_pandas(self) -> Any:
        """The rows as a pandas DataFrame, with the columns trackpy names for particles
        (``frame``, ``particle``, ``x``, ``y``: the box's centre) beside MOTChallenge's own
        (``bb_left``, ``bb_top``, ``bb_width``, ``bb_height``, ``conf``, ``class``,
        ``visibility``), so that a trackpy user's code reads tracks as it reads its own.
        :meth:`from_pandas` reads it back unchanged where the rows are MOTChallenge's
        (frames from 1, sizes >= 0; it refuses others, which :meth:`from_rows` takes as a
        tracker that counts from 0 writes them). Needs pandas.

        Examples
        --------
        >>> t = MOTTable.from_rows([(1, 7, 0, 0, 10, 20, 0.9), (2, 7, 2, 0, 10, 20, 0.8)])
        >>> df = t.to_pandas()
        >>> df[["frame", "particle", "x", "y"]].values.tolist()
        [[1.0, 7.0, 5.0, 10.0], [2.0, 7.0, 7.0, 10.0]]
        >>> MOTTable.from_pandas(df).boxes.tolist() == t.boxes.tolist()
        True
        """
        pd = _pandas("to_pandas")
        b = self.boxes
        return pd.DataFrame({
            "frame": self.frames, "particle": self.ids, "x": b[:, 0] + b[:, 2] / 2,
            "y": b[:, 1] + b[:, 3] / 2, "bb_left": b[:, 0], "bb_top": b[:, 1],
            "bb_width": b[:, 2], "bb_height": b[:, 3], "conf": self.conf,
            "class": self.classes, "visibility": self.visibility})

    def to_parquet(self, path: str | os.PathLike) -> Path:
        """Write :meth:`to_pandas`'s frame to a Parquet file, whole or not at all (under a
        partial name renamed into place); ``MOTTable.from_pandas(pandas.read_parquet(path))``
        reads it back. Needs pandas and pyarrow (``pip install 'vistrack[parquet]'``).

        Raises
        ------
        ImportError
            If pandas or pyarrow is missing, saying what to install.
        IsADirectoryError, NotADirectoryError
            If ``path`` is a folder, or a folder above it is a file (before writing).
        """
        need_parquet()
        df = self.to_pandas()
        with replacing(path) as part:
            df.to_parquet(part, index=False, engine="pyarrow")
        return Path(path)

    def to_csv(self, path: str | os.PathLike) -> Path:
        """Write :meth:`to_pandas`'s frame to a CSV file with a header, whole or not at all;
        ``MOTTable.from_pandas(pandas.read_csv(path))`` reads it back, as does ``vistrack
        track`` as detections. Needs pandas.

        Raises
        ------
        ImportError
            If pandas is missing.
        IsADirectoryError, NotADirectoryError
            If ``path`` is a folder, or a folder above it is a file (before writing).
        """
        df = self.to_pandas()
        # the centre, derived from the box, to 15 digits: 1283.7, not the 1283.6999999999998
        # that left + width / 2 gives in binary (the box's own columns are written exactly)
        for c in ("x", "y"):
            df[c] = [f"{v:.15g}" for v in df[c].to_numpy()]
        with replacing(path) as part:
            df.to_csv(part, index=False)
        return Path(path)

    @classmethod
    def from_pandas(cls, df: Any, columns: dict[str, str] | None = None,
                    path: str = "", *, points: bool = False, truth: bool = False) -> MOTTable:
        """A table from a DataFrame (or any mapping of column names to arrays): ``frame``,
        an identity (``particle`` or ``id``; -1 for detections if neither) and a box,
        ``bb_left, bb_top, bb_width, bb_height``, or its centre ``x, y`` with ``bb_width,
        bb_height``, or its corners ``x1, y1, x2, y2`` (as supervision's and YOLO's ``xyxy``);
        or, with ``points``, a point, ``x, y`` alone (trackpy's columns), as a box of width
        and height 0 there; ``conf``, ``class`` and ``visibility`` if there (default 1, -1,
        -1).

        Parameters
        ----------
        df : pandas.DataFrame or mapping
            The rows, one a box.
        columns : dict, optional
            Other names for those columns, ``{ours: theirs}`` (``{"frame": "t",
            "bb_width": "w"}``).
        path : str
            What the rows come from, for messages.
        points : bool
            Read ``x, y`` without a width and height as points, to be scored by distance
            (:func:`~vistrack.evaluation.evaluate_mot`'s ``zero_distance``); without it,
            such a table has no box, an error (its size columns may be named otherwise).
        truth : bool
            The rows are a ground truth, read by their own columns' names (``vistrack eval
            --columns`` names the results' alone): a missing column's message says so, where
            it advises ``--columns`` for results.

        Raises
        ------
        ValueError
            Naming the columns that are missing, or a name in ``columns`` that is not one of
            ours (or not one of the table's).
        MOTFormatError
            A ``ValueError`` naming the row (its line, for a CSV file's rows as vistrack
            reads them) and the column of a value that is not a finite number (an empty
            cell is NaN), a frame that is not an integer >= 1 (so no row of frame 0 is left
            out unseen), an identity or a class that is not an integer, a negative width or
            height, or a far corner (``x2``, ``y2``) before the near one; and, for columns
            missing from a ``.csv`` file (``path``) whose header is numbers only, that the
            file has no header (a MOTChallenge text file named ``.csv``: its first row was
            read as the header).

        Examples
        --------
        >>> rows = {"t": [1, 1], "x": [15.0, 40.0], "y": [30.0, 30.0], "w": [10.0, 10.0],
        ...         "h": [20.0, 20.0], "score": [0.9, 0.4]}
        >>> t = MOTTable.from_pandas(rows, columns={"frame": "t", "bb_width": "w",
        ...                                         "bb_height": "h", "conf": "score"})
        >>> t.boxes.tolist(), t.ids.tolist(), t.conf.tolist()
        ([[10.0, 20.0, 10.0, 20.0], [35.0, 20.0, 10.0, 20.0]], [-1, -1], [0.9, 0.4])
        >>> corners = {"frame": [1], "x1": [10.0], "y1": [20.0], "x2": [20.0], "y2": [40.0]}
        >>> MOTTable.from_pandas(corners).boxes.tolist()
        [[10.0, 20.0, 10.0, 20.0]]
        """
        names = check_column_names(columns)
        have = set(df.keys())
        where = f" in {path}" if path else ""

        def no_header() -> None:
            # a MOTChallenge text file named .csv: its first row was read as the header, and
            # its columns named by numbers, whichever of ',', ';', tab separates them (the
            # header of a frame of numbered columns, 0 to n - 1, or one whose numbered
            # columns are named in `columns`, is one)
            header = [c for c in df.keys() if isinstance(c, str)]
            if (str(path).lower().endswith(".csv") and header and len(header) == len(have)
                    and _all_numbers(header)
                    and header != [str(k) for k in range(len(header))]
                    and not have & set(names.values())):
                raise MOTFormatError(
                    f"{path}: no header: its first line holds numbers, not the columns' "
                    "names (a MOTChallenge text file? name it .txt to read it as one; or add "
                    "a header line naming the columns, as "
                    "'frame,id,bb_left,bb_top,bb_width,bb_height,conf')")

        for ours, theirs in names.items():
            # a name mistyped on either side was ignored: the column then went unread
            if theirs not in have:
                no_header()
                raise ValueError(f"columns {ours}={theirs}: no column {theirs!r}{where}; "
                                 f"columns: {sorted(map(str, have))}")

        def name(ours: str) -> str:
            return names.get(ours, ours)

        def at(k: int, ours: str) -> str:
            # a row by its line in the CSV file it was read from (by _read_csv, which marks
            # the rows as the file's), or else by its place among the rows; a column by name
            sep = getattr(df, "attrs", {}).get("csv_sep")
            line = _csv_row_line(path, sep, k) if path and sep else None
            row = f"line {line}" if line is not None else f"row {k + 1} after the header"
            return (f"{path or 'the table'}, {row}, column {name(ours)!r}"
                    + (f" ({ours})" if name(ours) != ours else ""))

        def get(ours: str) -> np.ndarray | None:
            # the column as numbers, all finite, or the first that is not, by row
            if name(ours) not in have:
                return None
            column = df[name(ours)]
            if np.asarray(column).dtype.kind == "b" and len(column) and ours != "conf":
                # (pandas reads a column of True and False as booleans: ids of 1 and 0;
                # conf, a flag of 0 and 1 in ground truth, is meant by them)
                raise MOTFormatError(f"{at(0, ours)}: not a number: "
                                     f"{np.asarray(column, dtype=object).ravel()[0]!r}")
            try:
                v = np.asarray(column, dtype=float).ravel()
            except (TypeError, ValueError):
                # the values one by one, as objects, for the first that is not a number
                for k, x in enumerate(np.asarray(column, dtype=object).ravel()):
                    try:
                        float(x)
                    except (TypeError, ValueError):
                        raise MOTFormatError(f"{at(k, ours)}: not a number: {x!r}") from None
                raise  # unreachable: the conversion failed on a value that converts
            bad = ~np.isfinite(v)
            if bad.any():
                k = int(np.argmax(bad))
                x = np.asarray(column, dtype=object).ravel()[k]
                raise MOTFormatError(f"{at(k, ours)}: not a finite number: {x!r}"
                                     + (" (an empty cell, or NaN)" if np.isnan(v[k]) else ""))
            return v

        frame = get("frame")
        if frame is None:
            no_header()
            # a column of another case or spelling named as the one meant (Frame, frames)
            lower = {str(c).lower(): str(c) for c in have}
            close = difflib.get_close_matches(name("frame").lower(), lower, n=1, cutoff=0.7)
            hint = (f"did you mean {lower[close[0]]!r}? " if close else "") + (
                _TRUTH_NAMES if truth else
                "name the frame's column: --columns frame=NAME, or columns={'frame': NAME}")
            raise ValueError(f"no column {name('frame')!r} (the frame){where}; columns: "
                             f"{sorted(map(str, have))} ({hint})")
        n = len(frame)
        # a column named in `columns` goes before one read by its own name: --columns id=tid
        # on a file with a particle column too read the particle
        mapped = set(names)
        ident = None if "id" in mapped and "particle" not in mapped else get("particle")
        if ident is None:
            ident = get("id")
        w, h = get("bb_width"), get("bb_height")
        corners_named = bool(mapped & set(_CORNERS)) and not mapped & {"bb_left", "bb_top",
                                                                        "x", "y"}
        if (mapped & {"x", "y"} or corners_named) and not mapped & {"bb_left", "bb_top"}:
            left = top = None  # the box as named (a centre, or corners), not bb_left, bb_top
        else:
            left, top = get("bb_left"), get("bb_top")

        def every(*columns: np.ndarray | None) -> list[np.ndarray] | None:
            # the columns, if each is there
            there = [c for c in columns if c is not None]
            return there if len(there) == len(columns) else None

        # the box in the first of its three forms whose columns are all there (the columns
        # of the later ones are then not read)
        if left is not None and top is not None:
            if w is None or h is None:
                gone = " or ".join(repr(name(c)) for c, v in (("bb_width", w),
                                                              ("bb_height", h)) if v is None)
                raise ValueError(f"no column {gone}{where}; columns: {sorted(map(str, have))}")
        elif not corners_named and (centre := every(get("x"), get("y"), w, h)) is not None:
            x, y, w, h = centre
            left, top = x - w / 2, y - h / 2
        elif (corners := every(*map(get, _CORNERS))) is not None:
            x1, y1, x2, y2 = corners
            for a, b, lo, hi in ((x1, x2, "x1", "x2"), (y1, y2, "y1", "y2")):
                if (b < a).any():
                    k = int(np.argmax(b < a))
                    raise MOTFormatError(f"{at(k, hi)}: the box's far corner must not lie "
                                         f"before its near one; {name(lo)} = {_shown(a[k])}, "
                                         f"{name(hi)} = {_shown(b[k])}")
            left, top, w, h = x1, y1, x2 - x1, y2 - y1
        elif corners_named:  # (told "no column 'h'" of a column there, where x2 was missing)
            gone = " or ".join(repr(name(c)) for c in _CORNERS if get(c) is None)
            raise ValueError(f"no column {gone}{where} (a box by its corners needs all four, "
                             f"{', '.join(repr(name(c)) for c in _CORNERS)}); columns: "
                             f"{sorted(map(str, have))}")
        elif (point := every(get("x"), get("y"))) is not None and (
                w is not None or h is not None):  # one of a box's two: the other is missing
            gone = repr(name("bb_width" if w is None else "bb_height"))
            raise ValueError(f"no column {gone}{where} (x, y are a box's centre with "
                             f"{name('bb_width')!r} and {name('bb_height')!r}, or a point "
                             f"with neither); columns: {sorted(map(str, have))}")
        elif point is not None and points:
            # a point (trackpy's frame, particle, x, y): a row of width and height 0 there,
            # which evaluate_mot scores by distance
            (left, top), w, h = point, np.zeros(n), np.zeros(n)
        else:
            no_header()
            missing = [name(c) for c in ("bb_left", "bb_top", "bb_width", "bb_height")
                       if get(c) is None]
            raise ValueError(f"no box{where}: columns {missing} are missing (or give "
                             f"{name('x')!r}, {name('y')!r} with {name('bb_width')!r}, "
                             f"{name('bb_height')!r}; or the corners "
                             f"{', '.join(repr(name(c)) for c in _CORNERS)}); columns: "
                             f"{sorted(map(str, have))} ("
                             + (_TRUTH_NAMES if truth else "name yours: --columns "
                                "bb_left=NAME,..., or columns={'bb_left': NAME, ...}") + ")"
                             + ("; x, y alone are points, scored by distance with vistrack "
                                "eval --zero-distance PX" if point is not None else ""))
        box = np.column_stack([frame, ident if ident is not None else np.full(n, -1.0),
                               left, top, w, h])
        # the rules a text file's rows obey (_check_rows), named by row and column here
        found = _first_bad_row(box)
        if found is not None:
            k, col, text = found
            ours = {0: "frame", 1: "particle" if name("particle") in have else "id",
                    4: "bb_width", 5: "bb_height"}[col]
            raise MOTFormatError(f"{at(k, ours)}: {text}")

        def or_fill(ours: str, fill: float) -> np.ndarray:
            v = get(ours)
            return v if v is not None else np.full(n, fill)

        kind = or_fill("class", -1.0)
        # a text file's eighth value may be something else (MOT15's world x), read as no
        # class; a column named as the class is one, so a fraction there is an error
        bad = (kind != np.round(kind)) | (np.abs(kind) >= _INT_LIMIT)
        if bad.any():
            k = int(np.argmax(bad))
            raise MOTFormatError(f"{at(k, 'class')}: class must be an integer; got "
                                 f"{_shown(kind[k])}")
        seen = or_fill("visibility", -1.0)
        # a column named as the visibility is one: a value that is no share (a percentage of
        # 40, or 1.0000001) made the text file's rule read the whole column as a world y,
        # and every value became -1, written so by to_csv
        bad = ~(((seen >= 0) & (seen <= 1)) | (seen == -1))
        if bad.any():
            k = int(np.argmax(bad))
            raise MOTFormatError(f"{at(k, 'visibility')}: visibility must be a share from 0 "
                                 f"to 1 (-1: not given); got {_shown(seen[k])}")
        rows = np.column_stack([box, or_fill("conf", 1.0), kind, seen])
        return cls.from_rows(rows if n else np.zeros((0, 9)), path)

    def frame_slices(self, n_frames: int | None = None) -> FrameSlices:
        """``slices[f - 1]`` selects the rows of frame ``f``, for ``f = 1 .. n_frames``
        (default: the last frame in the file).

        Parameters
        ----------
        n_frames : int, optional
            The frames to slice; frames past the last row's get empty slices.

        Returns
        -------
        FrameSlices
            One slice per frame, of the table's rows (empty for a frame without rows), each
            found when asked for: memory does not grow with the frames, however far apart
            the file's frame numbers lie.

        Raises
        ------
        ValueError
            If the rows are not sorted by frame, ``n_frames`` is not a whole number of 0 or
            more, or rows lie past it (their frames were in no slice, unsaid).

        Examples
        --------
        >>> t = MOTTable.from_rows([(1, 1, 0, 0, 10, 20), (3, 1, 5, 5, 10, 20),
        ...                         (3, 2, 1, 1, 3, 3)])
        >>> [len(t.ids[s]) for s in t.frame_slices(4)]
        [1, 0, 2, 0]
        >>> t.frame_slices(2)
        Traceback (most recent call last):
        ...
        ValueError: MOTTable: frame 3 is beyond n_frames = 2 (2 rows past it)
        """
        name = self.path or "MOTTable"
        if len(self) > 1 and np.any(np.diff(self.frames) < 0):
            raise ValueError(f"{name}: rows must be sorted by frame (read_mot sorts them)")
        last = int(self.frames.max()) if len(self) else 0
        if n_frames is None:
            return FrameSlices(self.frames, last)
        # (2.7 was cut to 2, -1 gave no frame, text was read, and the rows past n_frames
        # were in no slice)
        n = as_whole(n_frames, "n_frames", 0)
        if last > n:
            past = len(self) - int(np.searchsorted(self.frames, n, side="right"))
            raise ValueError(f"{name}: frame {last} is beyond n_frames = {n} ({past} "
                             f"row{'s' * (past != 1)} past it)")
        return FrameSlices(self.frames, n)


class FrameSlices(Sequence[slice]):
    """The rows of each frame ``1 .. n`` of a table sorted by frame, ``slices[f - 1]``, found
    by binary search when asked for (:meth:`MOTTable.frame_slices`).

    Examples
    --------
    >>> s = FrameSlices(np.array([1, 3, 3]), 4)
    >>> len(s), s[0], s[1], s[2], s[-1]
    (4, slice(0, 1, None), slice(1, 1, None), slice(1, 3, None), slice(3, 3, None))
    """

    def __init__(self, frames: np.ndarray, n: int):
        self._frames, self._n = frames, max(0, int(n))

    def __len__(self) -> int:
        return self._n

    @overload
    def __getitem__(self, k: int) -> slice: ...

    @overload
    def __getitem__(self, k: slice) -> list[slice]: ...

    def __getitem__(self, k: int | slice) -> slice | list[slice]:
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(self._n))]
        i = int(k) + self._n if int(k) < 0 else int(k)
        if not 0 <= i < self._n:
            raise IndexError(f"frame {int(k) + 1} is outside frames 1-{self._n}")
        a, b = np.searchsorted(self._frames, (i + 1, i + 2))
        return slice(int(a), int(b))


_TRUTH_NAMES = ("a ground truth is read by its own columns' names, MOTChallenge's: frame, id, "
                "bb_left, bb_top, bb_width, bb_height; vistrack eval --columns names the "
                "results' columns only")
"""What a ground truth's missing column is told (:meth:`MOTTable.from_pandas`'s ``truth``)."""


def _bad(path: str, line: int, column: int, text: str) -> MOTFormatError:
    # (a column past MOTChallenge's ten has no name: "column 11 (column 11)" before)
    name = f" ({_NAMES[column - 1]})" if column <= len(_NAMES) else ""
    return MOTFormatError(f"{path}, line {line}, column {column}{name}: {text}")


def _read_text(path: str, what: str) -> str:
    """The file's text (UTF-8, a byte-order mark dropped), or :class:`MOTFormatError` naming it
    when it is not text."""
    return decode_text(Path(path).read_bytes(), path, what, MOTFormatError)


# frames and ids from 2**53 on are not integers a float holds exactly (nor fit in int64 when
# much larger)
_INT_LIMIT = 2.0 ** 53
_CORNERS = ("x1", "y1", "x2", "y2")
"""A box's corners, as :meth:`MOTTable.from_pandas` takes them (supervision's ``xyxy``)."""
_NUMBER = re.compile(r"\s*[-+]?(?:[0-9]+(?:[.,][0-9]*)?|[.,][0-9]+)(?:[eE][-+]?[0-9]+)?"
                     r"(?:\.[0-9]+)?\s*")
"""A header cell that is a number (a decimal comma too), as pandas names a column by it
(``.1``, ``.2`` ... after a number the header has already)."""


def _all_numbers(header: list[str]) -> bool:
    """Whether every cell of a header is a number (a MOTChallenge text file's first row read
    as one), each cell split at ';' and tabs too, whichever separated the values."""
    return all(_NUMBER.fullmatch(x) for c in header for x in re.split("[;\t]", c))


_COLUMNS = ("frame", "particle", "id", "bb_left", "bb_top", "bb_width", "bb_height", "x", "y",
            *_CORNERS, "conf", "class", "visibility")
"""Every column :meth:`MOTTable.from_pandas` reads, by our name."""


_LINE_BREAK = re.compile(r"\r\n|\r|\n")


def _text_without_header(path: Path) -> bool:
    """Whether ``path``'s first line that holds values is numbers only: MOTChallenge's text
    in a file named ``.csv`` (False where it cannot be read: the reader then says why)."""
    try:
        with open(path, encoding="utf-8-sig", errors="replace") as f:
            for line in f:
                cells = _row_cells(line)
                if cells:
                    return _all_numbers(cells)
    except OSError:
        pass
    return False


def check_column_names(columns: Any) -> dict[str, str]:
    """``columns``, ``{ours: theirs}`` names of a CSV or Parquet file's columns, as a dict,
    each of ours one vistrack reads (the file's own names are checked against the file).

    Examples
    --------
    >>> check_column_names({"frame": "t"})
    {'frame': 't'}
    >>> check_column_names({"fram": "t"})
    Traceback (most recent call last):
    ...
    ValueError: columns fram=t: 'fram' is not a column vistrack reads (did you mean 'frame'?); \
those are frame, particle, id, bb_left, bb_top, bb_width, bb_height, x, y, x1, y1, x2, y2, \
conf, class, visibility
    """
    if isinstance(columns, str):  # (dict() of it: "dictionary update sequence element #0
        # has length 1; 2 is required")
        raise TypeError(f"columns must be a dict {{ours: theirs}}, such as {{'frame': "
                        f"'t'}}; got the text {columns!r} (the command line's --columns "
                        "OURS=THEIRS,... form)")
    names = dict(columns or {})
    for ours, theirs in names.items():
        # a name mistyped was ignored: the column then went unread
        if ours not in _COLUMNS:
            close = difflib.get_close_matches(str(ours), _COLUMNS, n=1)
            raise ValueError(f"columns {ours}={theirs}: {ours!r} is not a column vistrack "
                             "reads" + (f" (did you mean {close[0]!r}?)" if close else "")
                             + f"; those are {', '.join(_COLUMNS)}")
    first: dict[Any, str] = {}
    for ours, theirs in names.items():
        # (bb_left=x,bb_top=x read one column as both, unsaid: a mistyped name, surely)
        if theirs in first:
            raise ValueError(f"columns {first[theirs]}={theirs} and {ours}={theirs}: one "
                             f"column, {theirs!r}, named for two of ours")
        first[theirs] = ours
    return names


def _text_lines(text: str) -> list[str]:
    r"""``text``'s lines as editors, ``wc -l`` and numpy's reader count them: broken at
    ``\n``, ``\r\n`` or a lone ``\r`` only (``str.splitlines`` also breaks at a form feed,
    ``\x0b``, ``\x1c``-``\x1e``, ``\x85``, U+2028 and U+2029, which put the lines named
    in messages past the ones meant), without an empty last line after a final break.

    Examples
    --------
    >>> _text_lines("1,2\r\n# a\fcomment\n3,4\n")
    ['1,2', '# a\x0ccomment', '3,4']
    """
    lines = _LINE_BREAK.split(text)
    if lines and lines[-1] == "":
        lines.pop()
    return lines


def _row_text(line: str) -> str:
    """The part of ``line`` that holds values: before a ``#`` (a comment, to the end of the
    line, as np.loadtxt drops it), stripped; empty for a blank or comment-only line, which
    holds no row."""
    return line.split("#", 1)[0].strip()


def _row_cells(line: str) -> list[str]:
    """The values of ``line`` as text, as the careful reader splits them: the part before a
    ``#`` (:func:`_row_text`), separated by commas, or on a line without a comma by spaces
    or tabs, a separator ending the line ignored (as TrackEval ignores it); ``[]`` for a
    line that holds no row."""
    text = _row_text(line)
    if not text:
        return []
    cells = [c.strip() for c in text.split(",")] if "," in text else text.split()
    if len(cells) > 1 and not cells[-1]:
        cells.pop()
    return cells


def _row_lines(lines: list[str]) -> list[int]:
    """The numbers (from 1) of the lines that hold a row, in order: the careful reader's row
    ``i`` is on line ``_row_lines(lines)[i]``. Its two parsers skip the same lines, those of
    no :func:`_row_text`: :func:`_parse_slow` by it, np.loadtxt a line left empty once its
    comment is dropped, or blank too between spaces and tabs (between commas it refuses a
    blank line, and :func:`_parse_slow` reads the file)."""
    return [k for k, t in enumerate(lines, start=1) if _row_text(t)]


def _parse_slow(path: str, lines: list[str]) -> np.ndarray:
    """Parse row by row, to name the first bad line and column; blank lines, comment-only
    lines and comments (``#`` to the end of the line) hold no values, as for np.loadtxt."""
    rows: list[list[float]] = []
    width = None
    for k, raw in enumerate(lines, start=1):
        cells = _row_cells(raw)
        if not cells:
            continue
        # the line as it is, and what a '#' in it does to the count
        line = repr(raw.strip()) + (" ('#' starts a comment, to the end of the line)"
                                    if "#" in raw else "")
        if len(cells) < 6 and ";" in raw:  # (a CSV file of semicolons)
            line += (" (values separated by ';': a CSV file? name it .csv to read it as one)"
                     if not path.lower().endswith(".csv") else
                     " (values separated by ';': a CSV file of semicolons is read by its "
                     "header, a first line naming its columns: "
                     "frame;id;bb_left;bb_top;bb_width;bb_height)")
        if len(cells) < 6:
            raise _bad(path, k, len(cells) + 1,
                       f"expected at least 6 values (separated by commas, or by spaces or tabs), "
                       f"got {len(cells)}: {line}")
        if len(cells) > 10:
            raise _bad(path, k, 11, f"expected at most 10 values, got {len(cells)}: {line}")
        if width is not None and len(cells) != width:
            raise _bad(path, k, min(len(cells), width) + 1,
                       f"{len(cells)} values where the lines before have {width}"
                       + (f": {line}" if "#" in raw else ""))
        width = len(cells)
        vals = []
        for j, c in enumerate(cells, start=1):
            try:
                v = text_number(c)
            except ValueError:
                words = not rows and any(ch.isalpha() for cell in cells for ch in cell)
                header = (" (a header line? MOTChallenge files have none; a .csv file's header "
                          "names its columns)" if words else "")
                raise _bad(path, k, j, f"not a number: {c!r}{header}") from None
            if not np.isfinite(v):
                raise _bad(path, k, j, f"not a finite number: {c!r}")
            vals.append(v)
        rows.append(vals)
    return np.array(rows, dtype=float).reshape(len(rows), width or 10)


_ROW_RULES = (
    (0, lambda v: (v < 1) | (v != np.round(v)),
     "frame must be an integer >= 1 (frames count from 1, as MOTChallenge's do)"),
    (0, lambda v: v >= _INT_LIMIT, "frame must be below 2**53"),
    (1, lambda v: v != np.round(v), "id must be an integer"),
    (1, lambda v: np.abs(v) >= _INT_LIMIT, "id must lie within ±(2**53 - 1)"),
    (4, lambda v: v < 0, "width must be >= 0"),
    (5, lambda v: v < 0, "height must be >= 0"),
)
"""What every row of a table must satisfy, whatever it was read from (a text file, a CSV
file, a DataFrame): (column, the values that break the rule, what is wrong)."""


def _shown(v: float) -> str:
    """A value as a message shows it: a whole number below 2**53 as one, any other as
    Python writes the float, every digit it holds (``:g`` kept six: 123456.5 was "123456",
    an integer in a message saying it was none)."""
    v = float(v)
    return str(int(v)) if v == v and abs(v) < _INT_LIMIT and v == int(v) else repr(v)


def _first_bad_row(a: np.ndarray) -> tuple[int, int, str] | None:
    """The first rule of :data:`_ROW_RULES` the rows ``a (N, >= 6)`` break: the first row
    breaking it, its column and what is wrong with the value; None if none is broken."""
    for col, breaks, text in _ROW_RULES:
        bad = breaks(a[:, col])
        if bad.any():
            i = int(np.argmax(bad))
            return i, col, f"{text}; got {_shown(a[i, col])}"
    return None


def _check_rows(path: str, a: np.ndarray, lines: list[str] | None) -> None:
    """:class:`MOTFormatError` naming the line and column of the first row of ``a`` that
    breaks a rule of :data:`_ROW_RULES`: row ``i`` is on line ``i + 1`` if ``lines`` is None
    (the plain reader's rows, one a line), else on the ``i``-th line of ``lines`` that holds
    a row (:func:`_row_lines`: blank and comment lines do not)."""
    found = _first_bad_row(a)
    if found is not None:
        i, col, text = found
        raise _bad(path, i + 1 if lines is None else _row_lines(lines)[i], col + 1, text)


# ---------------------------------------------------------------------------------------------
# The plain-file reader. numpy's loadtxt converts each value with the C library's strtod, about
# 150 ns a value (0.7 M rows/s); this reads the numbers most files hold eight bytes at a time,
# with integer arithmetic on arrays of 64-bit words (SWAR), a block of the file at a time so
# that the temporaries stay in the cache: about 4 times faster. It accepts only files that the
# careful reader (loadtxt, then line by line) reads without a doubt, and reads them to the same
# bits: an optional byte-order mark; lines ended by '\n' or '\r\n', blank lines only at the
# end; every line the same number (6 to 10) of comma-separated fields; every field an optional
# '-', then digits with at most one '.' and at least one digit (or, for at most 1 field in 64,
# a number with an exponent ('e' or 'E', no '+') or more than 15 digits, read with Python's
# float(), as loadtxt reads it). For anything else (a space, '+', 'nan', a comment, a blank
# line, any other byte) it returns None and the careful reader decides, so every message stays
# as it was.
#
# A plain field's value is its digits read as an integer M (exact: M < 2**53) divided by 10**k
# for its k decimals (exact: k <= 15): one IEEE division, so the correctly rounded value of the
# decimal, which is what float() and loadtxt (CPython's correctly rounded strtod) give.

_U8 = np.uint64


def _lanes(byte: int) -> np.uint64:
    """``byte`` in each of the 8 byte lanes of a 64-bit word."""
    return _U8(byte * 0x0101010101010101)


_L7F, _L30, _L76, _L80 = map(_lanes, (0x7F, 0x30, 0x76, 0x80))
# by the number n of a field's bytes in its word (clipped to 9: longer than a word), the mask
# of its lanes: the top n
_FIELD = np.array([(0xFFFFFFFFFFFFFFFF << (64 - 8 * n)) & 0xFFFFFFFFFFFFFFFF for n in range(9)]
                  + [0], dtype=np.uint64)
# 10**(decimals) by the '.''s lane p, looked up by the exponent bits of float(1 << 8p)
# (127 + p): the decimals are the lanes after the '.', 7 - p; float(0) (no '.') has exponent
# bits 0
_SCALE = np.ones(256)
_SCALE[127:135] = 10.0 ** (7 - np.arange(8))
_PLAIN_BLOCK = 1 << 17  # bytes parsed at a time: the temporaries stay in the cache
# the fields read one by one with Python's float(): longer than 17 bytes, digits above 2**53,
# or an exponent; at most 1 in 64 of a file's fields (more, and the careful reader is as fast)
_FIELD_RE = re.compile(rb"-?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?")


def _word_digits(word: np.ndarray, n: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The top ``n`` lanes (n <= 8: the callers refuse longer fields) of the words ``word``
    (ASCII; the other lanes taken as '0') as digits with at most one '.': the digits with the
    '.' dropped (one per lane, the first lane 0 where a '.' was dropped), the '.''s lane as 1
    (0 when none), and which words were such digits."""
    # a field's last 8 bytes, read as one little-endian word: lane 7 (the top byte) is its
    # last byte. Each lane minus '0' (xor: '0'-'9' are 0x30-0x39), 0 outside the field's n
    y: np.ndarray = word ^ _L30
    y &= _FIELD.take(n, mode="clip")
    # 0x80 in the lanes above 9, exactly (no carry from lane to lane): at most one, and '.'
    other: np.ndarray = y & _L7F
    other += _L76
    other |= y
    other &= _L80
    ok: np.ndarray = (other & (other - _U8(1))) == 0
    one = other >> _U8(7)
    dot = one * _U8(0x1E)  # '.' ^ '0'
    ok &= (y & (one * _U8(0xFF))) == dot
    y ^= dot  # '.' -> 0
    # the lanes before the '.' move up one, over it: y - x + (x << 8) with x those lanes
    x = one - (one != 0)
    x &= y
    x *= _U8(255)
    y += x
    return y, one, ok


def _digits_value(d: np.ndarray) -> np.ndarray:
    """8 lanes of digits 0-9, the first lane the most significant, as the integer they write
    (three multiplications: pairs, quadruples, the 8)."""
    d = d * _U8(10) + (d >> _U8(8))
    d = ((d & _U8(0x000000FF000000FF)) * _U8(0x000F424000000064)
         + ((d >> _U8(16)) & _U8(0x000000FF000000FF)) * _U8(0x0000271000000001))
    return d >> _U8(32)


def _scale(one: np.ndarray) -> np.ndarray:
    """10**(the lanes after the '.') of each word, from the '.''s lane (1 when none)."""
    return _SCALE.take(one.astype(float).view(np.uint64) >> _U8(55))


def _plain_fields(buf: np.ndarray, words: np.ndarray, start: np.ndarray,
                  end: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The values of the fields ``buf[start:end]`` of up to 8 bytes after a sign, and which
    were plain numbers."""
    neg = buf.take(start) == 45  # '-'
    n = end - start
    n -= neg
    d, dot, ok = _word_digits(words.take(end - 8), n)
    ok &= n > (dot != 0)  # a digit
    ok &= n <= 8
    value = _digits_value(d).astype(float)
    value /= _scale(dot)
    value *= 1.0 - 2.0 * neg  # (-0.0 for '-0', as float() reads it)
    return value, ok


def _long_fields(buf: np.ndarray, words: np.ndarray, start: np.ndarray,
                 end: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Like :func:`_plain_fields` for fields of 9 to 16 bytes after a sign (two words): their
    values, and which were plain numbers whose digits are below 2**53."""
    neg = buf.take(start) == 45
    n = end - start - neg
    d1, dot1, ok = _word_digits(words[end - 8], np.full(len(n), 8))
    d0, dot0, ok0 = _word_digits(words[end - 16], n - 8)
    ok &= ok0 & ((dot0 == 0) | (dot1 == 0)) & (n > 8) & (n <= 16)
    # a '.' in the second word moves the first word's last digit into it, and the first word
    # up a lane
    moved = (dot1 != 0).astype(np.uint64)
    d1 |= (d0 >> _U8(56)) * moved
    d0 <<= _U8(8) * moved
    m = _digits_value(d0) * _U8(100_000_000) + _digits_value(d1)
    ok &= m <= _U8(1 << 53)
    value = m.astype(float) / (_scale(dot1) * np.where(dot0 != 0, 1e8 * _scale(dot0), 1.0))
    np.negative(value, out=value, where=neg)
    return value, ok


def _python_fields(raw: bytes, start: np.ndarray, end: np.ndarray, out: np.ndarray,
                   at: np.ndarray) -> bool:
    """``out[at]``: the fields ``raw[start:end]`` read with Python's float(); whether they were
    plain numbers (with an exponent or many digits), finite."""
    for a, b, j in zip(start.tolist(), end.tolist(), at.tolist()):
        f = raw[a:b]
        if not _FIELD_RE.fullmatch(f):
            return False
        out[j] = x = float(f)
        if not math.isfinite(x):
            return False
    return True


def _parse_plain(data: bytes) -> np.ndarray | None:
    """The rows of a plain MOTChallenge file (see above), or None for any other."""
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    if b"\r" in data:
        data = data.replace(b"\r\n", b"\n")
        if b"\r" in data:
            return None
    end = len(data)
    while end and data[end - 1] == 10:  # blank lines at the end
        end -= 1
    if not end:
        return None
    pad = 16  # '0's before the first field: every field's last 16 bytes are in the buffer
    raw = b"".join((b"0" * pad, memoryview(data)[:end], b"\n"))
    buf = np.frombuffer(raw, dtype=np.uint8)
    out = np.empty(0)
    width = spare = row = 0
    later: list[tuple[np.ndarray, ...]] = []  # fields of 9 to 17 bytes: where in out, in raw
    s = pad
    while s < len(raw):
        e = raw.find(b"\n", min(s + _PLAIN_BLOCK, len(raw)) - 1) + 1
        u = buf[s:e]
        # the fields' ends: ',' or '\n' (the only bytes below '-' a plain file has: the counts
        # of ',' and '\n' tell whether there are others)
        sep = np.flatnonzero(u <= 44)
        kind = u.take(sep)
        ends = kind == 10
        rows = int(np.count_nonzero(ends))
        if len(sep) != rows + np.count_nonzero(kind == 44):
            return None
        if not width:
            width = len(sep) // rows
            if not 6 <= width <= 10:
                return None
            out = np.empty((raw.count(b"\n"), width))
            spare = out.size // 64 + 16
        # every line `width` fields: the rows' last fields end the lines
        if len(sep) != width * rows or not ends[width - 1::width].all():
            return None
        # the block and the 16 bytes before it, as bytes and as the words at every byte (a
        # view of the block only: numpy's take copies a view's whole array first)
        base = s - pad
        block = buf[base:e]
        words = np.ndarray((e - base - 7,), dtype="<u8", buffer=raw, offset=base, strides=(1,))
        sep += pad
        start = np.empty_like(sep)
        start[0] = pad
        start[1:] = sep[:-1] + 1
        value, ok = _plain_fields(block, words, start, sep)
        out[row:row + rows] = value.reshape(rows, width)
        if not ok.all():
            k = np.flatnonzero(~ok)
            n = sep[k] - start[k]
            two = (n > 8) & (n <= 17)  # two words: read after the last block, all at once
            later.append((row * width + k[two], base + start[k[two]], base + sep[k[two]]))
            k = k[~two]
            spare -= len(k)
            if spare < 0 or not _python_fields(raw, base + start[k], base + sep[k],
                                               out.reshape(-1), row * width + k):
                return None
        row += rows
        s = e
    if later:
        at, first, last = (np.concatenate(x) for x in zip(*later))
        words = np.ndarray((len(raw) - 7,), dtype="<u8", buffer=raw, strides=(1,))
        value, ok = _long_fields(buf, words, first, last)
        out.reshape(-1)[at[ok]] = value[ok]
        k = np.flatnonzero(~ok)
        if len(k) > spare or not _python_fields(raw, first[k], last[k], out.reshape(-1),
                                                at[k]):
            return None
    return out


def _ground_truth_file(gt: str | os.PathLike) -> Path:
    """``gt`` as a ground-truth file: itself, or a sequence folder's ``gt/gt.txt`` (as
    ``vistrack track`` takes a sequence folder).

    Raises
    ------
    ValueError
        If ``gt`` is a folder without ``gt/gt.txt``.
    """
    gt = Path(gt)
    if gt.is_dir():
        if not (gt / "gt" / "gt.txt").is_file():
            raise ValueError(f"--gt {gt} is a folder without gt/gt.txt: give a ground-truth "
                             "file, or a sequence folder that holds gt/gt.txt")
        return gt / "gt" / "gt.txt"
    return gt


def read_mot(path: str | os.PathLike) -> MOTTable:
    """Read a MOTChallenge detection, ground-truth or results file.

    Parameters
    ----------
    path : str or os.PathLike
        The file: rows of 6 to 10 numbers, all of one width, separated by commas (or, on a
        line without a comma, by spaces or tabs; blank lines, and ``#`` comments to the end
        of a line, skipped).

    Returns
    -------
    MOTTable
        Its rows, sorted by frame (an empty file gives an empty table).

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    MOTFormatError
        For a malformed row, naming the file, line and column (1-based, every line counted,
        blank and comment lines too), e.g.
        ``gt.txt, line 12, column 5 (width): width must be >= 0; got -3``; for a file that is
        not UTF-8 text (``gt.txt is not a text MOTChallenge file (...)``).

    Examples
    --------
    >>> import tempfile, os
    >>> p = os.path.join(tempfile.mkdtemp(), "det.txt")
    >>> _ = open(p, "w").write("2,-1,10,20,30,40,0.9,-1,-1,-1\\n1,-1,5,5,10,10,0.5,-1,-1,-1\\n")
    >>> t = read_mot(p)
    >>> t.frames.tolist(), t.boxes[0].tolist()
    ([1, 2], [5.0, 5.0, 10.0, 10.0])
    """
    path = os.fspath(path)
    data = Path(path).read_bytes()
    a = _parse_plain(data)
    if a is not None:
        try:
            _check_rows(path, a, None)
        except MOTFormatError:
            a = None  # the careful reader names the row, as it always has
    if a is None:
        a = _read_careful(path, data)
    elif len(a) < 2 or (a[1:, 0] >= a[:-1, 0]).all():
        return MOTTable._of(a, path)  # sorted already: from_rows would copy it as it is
    return MOTTable.from_rows(a, path)


def _read_careful(path: str, data: bytes) -> np.ndarray:
    """The rows of ``data`` (the file ``path``'s bytes), checked, or :class:`MOTFormatError`
    naming the file, and the line and column of a bad row."""
    text = decode_text(data, path, "MOTChallenge", MOTFormatError)
    lines = _text_lines(text)
    a = _parse_lines(path, text, lines)
    _check_rows(path, a, lines)
    return a


def _parse_lines(path: str, text: str, lines: list[str]) -> np.ndarray:
    """The values of ``text`` (split into ``lines``): by numpy's reader, or line by line where
    it fails, to name the first bad line and column."""
    a = None
    try:
        if text.strip():
            # the first line that holds a row (a comment line before it may have commas or
            # none, whatever the rows have)
            first = next((t for t in map(_row_text, lines) if t), "")
            with warnings.catch_warnings():  # a file of comments only: "no data"
                warnings.simplefilter("ignore", UserWarning)
                # values separated by commas, or (no comma) by spaces or tabs
                a = np.loadtxt(lines, delimiter="," if "," in first else None, ndmin=2,
                               dtype=float)
            if not 6 <= a.shape[1] <= 10 or not np.isfinite(a).all():
                a = None
        else:
            a = np.zeros((0, 10))
    except ValueError:
        a = None
    if a is None:
        a = _parse_slow(path, lines)
    return a


def write_mot(path: str | os.PathLike, frames: ArrayLike, ids: ArrayLike, boxes: ArrayLike,
              conf: ArrayLike | None = None, *, force: bool = False,
              decimals: int = 2) -> Path:
    """Write a MOTChallenge results file: ``frame, id, left, top, width, height, conf, -1, -1,
    -1``, sorted by frame and id. Refuses to overwrite an existing file unless ``force``.

    Parameters
    ----------
    path : str or os.PathLike
        The file; its folder is made if needed.
    frames, ids : (N,) array_like
        Frame and identity of each row (integers).
    boxes : (N, 4) array_like
        Boxes ``left, top, width, height``, written with ``decimals`` decimals.
    conf : (N,) array_like, optional
        Scores, written with 4 significant digits; default 1.
    force : bool
        Overwrite an existing file.
    decimals : int
        The boxes' decimals: 2, MOTChallenge's (a hundredth of a pixel), or more for boxes
        in other units (:func:`box_decimals`; 0 to 12).

    Returns
    -------
    pathlib.Path
        The file written.

    Raises
    ------
    FileExistsError
        If ``path`` exists and ``force`` is False.
    IsADirectoryError, NotADirectoryError, PermissionError
        Before anything is written: if ``path`` is a folder, a folder above it is a file,
        or its folder cannot be written in (:func:`~vistrack.io.atomic.check_output`).
    ValueError
        If ``decimals`` is not an integer in 0-12, the columns differ in length, or a row is
        one :func:`read_mot` would refuse: a
        frame or id that is not a whole number or lies from 2**53 on, a frame below 1, a box
        that is not finite or of negative width or height, a score that is not finite
        (naming the first such row).
    TypeError
        If ``boxes`` or ``conf`` is not an array of numbers (ragged rows, text).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> p = write_mot(pathlib.Path(tempfile.mkdtemp()) / "res.txt", [2, 1], [1, 1],
    ...               [[0, 0, 10, 20], [1, 2, 3, 4]], [0.9, 0.75])
    >>> print(p.read_text(), end="")
    1,1,1.00,2.00,3.00,4.00,0.75,-1,-1,-1
    2,1,0.00,0.00,10.00,20.00,0.9,-1,-1,-1
    """
    path = Path(path)
    # a folder, or a file above it, was found at the rename after the whole file was
    # written (and a folder was told to pass force=True)
    check_output(path, force=force, name="path")
    _check_decimals(decimals)
    f, i = _integers(frames, "frames"), _integers(ids, "ids")
    # (ragged boxes, or a conf of text, failed in numpy's words, naming neither)
    b = as_float_array(boxes, "boxes")
    if b.size == 0 or b.shape == (4,):  # no rows, or one
        b = b.reshape(-1, 4)
    if b.ndim != 2 or b.shape[1] != 4:
        raise ValueError(f"boxes must have shape (N, 4); got {b.shape}")
    c = np.ones(len(f)) if conf is None else as_float_array(conf, "conf").ravel()
    if not len(f) == len(i) == len(b) == len(c):
        raise ValueError(f"frames, ids, boxes and conf must have the same length; got "
                         f"{len(f)}, {len(i)}, {len(b)}, {len(c)}")
    # what read_mot would refuse to read back: (rows refused, their column, the message)
    for bad, column, what in (
            (f < 1, f, "frames[{k}] = {v}: MOTChallenge frames count from 1"),
            (~np.isfinite(b).all(axis=1), b, "boxes[{k}] = {v} is not finite"),
            ((b[:, 2] < 0) | (b[:, 3] < 0), b,
             "boxes[{k}] = {v} has a negative width or height"),
            (~np.isfinite(c), c, "conf[{k}] = {v} is not finite")):
        if bad.any():
            k = int(np.argmax(bad))
            v = column[k]
            raise ValueError(what.format(k=k, v=v.tolist() if np.ndim(v) else v))
    return _write_sorted(path, f, i, b, c, decimals)


def _check_decimals(decimals: int) -> None:
    if isinstance(decimals, bool) or not isinstance(decimals, (int, np.integer)) or not (
            0 <= decimals <= 12):
        raise ValueError(f"decimals must be an integer in 0-12; got {decimals!r}")


def box_decimals(heights: ArrayLike) -> int:
    """The decimals that write boxes of these heights to a thousandth of the typical one: 2
    (MOTChallenge's hundredth of a pixel) for boxes 10 units tall or more, more for smaller
    ones (boxes in fractions of the image, as YOLO's normalised ones: 0.13 tall, 4).

    Parameters
    ----------
    heights : (N,) array_like
        The boxes' heights (those above 0 count; none: 2).

    Returns
    -------
    int
        2 to 12.

    Examples
    --------
    >>> box_decimals([80.0, 120.0]), box_decimals([0.13, 0.2]), box_decimals([])
    (2, 4, 2)
    """
    h = np.asarray(heights, dtype=float).ravel()
    h = h[np.isfinite(h) & (h > 0)]
    if not len(h):
        return 2
    return int(min(12, max(2, math.ceil(math.log10(1000.0 / float(np.median(h))) - 1e-9))))


def _row_format(decimals: int) -> str:
    """``_ROW`` with the boxes to ``decimals`` decimals."""
    box = f"%.{decimals}f"
    return f"%d,%d,{box},{box},{box},{box},%.4g,-1,-1,-1\n"


def _format_rows_with(f: np.ndarray, i: np.ndarray, b: np.ndarray, c: np.ndarray,
                      decimals: int) -> bytes:
    """The rows with the boxes to ``decimals`` decimals, as bytes (the column-wise formatter
    for MOTChallenge's 2, Python's %-format row by row for others)."""
    if decimals == 2:
        return _format_rows(f, i, b, c)
    row = _row_format(decimals)
    cells = zip(f.tolist(), i.tolist(), *np.asarray(b, float).T.tolist(),
                np.asarray(c, float).tolist())
    return "".join(row % r for r in cells).encode()


def _write_sorted(path: Path, f: np.ndarray, i: np.ndarray, b: np.ndarray,
                  c: np.ndarray, decimals: int = 2) -> Path:
    """The rows, sorted by frame and id, formatted into ``path`` (any values: the checks are
    :func:`write_mot`'s)."""
    if len(f) > 1 and not np.all((f[1:] > f[:-1]) | ((f[1:] == f[:-1]) & (i[1:] >= i[:-1]))):
        order = np.lexsort((i, f))
        f, i, b, c = f[order], i[order], b[order], c[order]
    with replacing(path) as part, open(part, "wb") as out:
        for s in range(0, len(f), _WRITE_BLOCK):
            e = min(s + _WRITE_BLOCK, len(f))
            out.write(_format_rows_with(f[s:e], i[s:e], b[s:e], c[s:e], decimals))
    return path


def _integers(values: ArrayLike, name: str) -> np.ndarray:
    """``values`` as int64, refusing one that is not a whole number (2.7 was written as 2), or
    from 2**53 on either way, which :func:`read_mot` refuses (and a uint64 above int64's range
    was written as a negative number: 2**64 - 1 as -1, a detection's identity)."""
    a = np.asarray(values).ravel()
    integer = a.dtype.kind in "iub"
    if a.dtype.kind not in "iubf":  # (Python's big integers, None, text: an object array)
        for k, v in enumerate(a.tolist()):
            if isinstance(v, (str, bytes)) or not isinstance(v, numbers.Real):
                raise ValueError(f"{name}[{k}] = {v!r} is not a whole number")
    x = a.astype(float)
    if not integer:
        bad = ~np.isfinite(x) | (x != np.round(x))
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"{name}[{k}] = {np.asarray(a[k]).tolist()!r} is not a whole "
                             "number")
    # compared as integers where they are (2**53 + 1 becomes 2**53 as a float): from 2**53
    # on, a float no longer holds every integer, and read_mot refuses them
    big = ((a >= 2**53) | (a <= -(2**53))) if integer else (np.abs(x) >= _INT_LIMIT)
    if big.any():
        k = int(np.argmax(big))
        raise ValueError(f"{name}[{k}] = {np.asarray(a[k]).tolist()!r} is not within "
                         "±(2**53 - 1), which read_mot refuses")
    return a.astype(np.int64, copy=False) if integer else x.astype(np.int64)


_ROW = _row_format(2)  # "%d,%d,%.2f,%.2f,%.2f,%.2f,%.4g,-1,-1,-1\n"
_WRITE_BLOCK = 16384  # rows formatted at a time: the temporaries stay in the cache


# ---------------------------------------------------------------------------------------------
# The writer formats whole columns at a time with numpy, into a table of bytes, a row of the
# file in each row of the table and a 0 byte where a shorter value leaves room; the table's
# bytes without the 0s are the file. Python's %-format (C's printf, correctly rounded) was
# 1 us a row. The text is the same, byte for byte: a value is rounded as one integer q (the
# number's 2 decimals, or its 4 significant digits for %.4g) = rint(y), y = |x| * 10**k,
# where rint(y) is the exact product's rounding unless y lies within a few units of its last
# place of a half-integer (then the row is formatted with Python's %, as are rows with a
# value out of range, NaN or infinite, or a %.4g value that needs an exponent). %.4g's
# exponent X (10**X <= |x| < 10**(X+1)) comes from comparisons with 1e-4 ... 1e4, exact: the
# doubles nearest 1e-4 ... 0.1 lie above them.

_P10 = 10.0 ** np.arange(23)
_G_LIMITS = np.array([1e-4, 1e-3, 1e-2, 0.1, 1.0, 10.0, 100.0, 1000.0, 1e4])
_TENS = np.array([48 + k // 10 for k in range(100)], dtype=np.uint8)
_ONES = np.array([48 + k % 10 for k in range(100)], dtype=np.uint8)
_MINUS = np.array([0, 45], dtype=np.uint8)  # by the sign bit: nothing, '-'
_TAIL = np.frombuffer(b",-1,-1,-1\n", dtype=np.uint8)
# of 0 ... 9999: its trailing zeros, up to 3 (%.4g's digits are 1000 ... 9999, or 0)
_TRAILING_ZEROS = np.zeros(10_000, dtype=np.intp)
for _z in (10, 100, 1000):
    _TRAILING_ZEROS[::_z] += 1


def _rounded(y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """rint(y) (y >= 0, the product |x| * 10**k rounded once), and where it may not be the
    exact product's rounding: y within 4 units of its last place of a half-integer."""
    q = np.rint(y)
    with np.errstate(invalid="ignore"):
        return q, ~(0.5 - np.abs(y - q) > y * 2.0 ** -50)


def _width(v: np.ndarray, least: int) -> int:
    """The digits of the largest of ``v`` (integers >= 0), at least ``least``."""
    return max(least, int(np.searchsorted(_P10, v.max(initial=0), side="right")))


def _put_digits(table: np.ndarray, col: int, v: np.ndarray, width: int, least: int) -> None:
    """``table[:, col:col + width]``: the decimal digits of ``v`` (integers >= 0, < 2**46, as
    floats), right-aligned, 0 bytes before them (at least ``least`` digits), two at a time."""
    x = v
    for k in range(0, width, 2):
        q = np.floor(x / 100.0)  # exact below 2**46
        r = (x - q * 100.0).astype(np.intp)
        for j, digit in ((k, _ONES), (k + 1, _TENS)):
            if j < width:
                d = digit.take(r)
                if j >= least:
                    d *= v >= _P10[j]
                table[:, col + width - 1 - j] = d
        x = q


def _format_rows(f: np.ndarray, i: np.ndarray, b: np.ndarray, c: np.ndarray) -> bytes:
    """The rows ``_ROW % (f, i, *b, c)``, as bytes."""
    n = len(f)
    ff, fi = f.astype(float), i.astype(float)
    af, ai = np.abs(ff), np.abs(fi)
    with np.errstate(over="ignore"):  # (inf: refused below)
        qb, bad_b = _rounded(np.abs(b) * 100.0)
    ac = np.abs(c)
    zero = ac == 0
    x = np.searchsorted(_G_LIMITS, ac, side="right") - 5  # 10**x <= |c| < 10**(x+1)
    x[zero] = 3
    qc, bad = _rounded(ac * _P10.take(np.clip(3 - x, 0, 7)))
    carry = qc == 10000  # rounded up to 10**(x+1)
    qc[carry] = 1000
    x += carry
    bad &= ~zero
    bad |= (x < -4) | (x > 3)  # an exponent, NaN or infinite
    bad |= bad_b.any(axis=1)
    with np.errstate(invalid="ignore"):
        bad |= ~((af < 1e13) & (ai < 1e13) & (qb < 1e13).all(axis=1))
    if bad.any():  # formatted as 0 here, by Python below
        af[bad] = ai[bad] = qc[bad] = 0
        qb[bad] = 0
        x[bad] = 3
    # %.4g: the digits of qc, 3 - x of them after the '.', trailing zeros dropped
    decimals = 3 - x
    zeros = _TRAILING_ZEROS.take(qc.astype(np.intp))
    shown = decimals - np.minimum(zeros, decimals)
    scale = _P10.take(decimals)
    whole = np.floor(qc / scale)
    frac = (qc - whole * scale) / _P10.take(decimals - shown) * _P10.take(7 - shown)
    # %.2f: qb's digits, 2 after the '.'
    wb = np.floor(qb / 100.0)
    cents = (qb - wb * 100.0).astype(np.intp)

    widths = [_width(af, 1), _width(ai, 1)] + [_width(wb[:, k], 1) for k in range(4)]
    wc, fc = _width(whole, 1), int(shown.max(initial=0))
    table = np.empty((n, sum(widths[:2]) + 4 + sum(widths[2:]) + 20 + wc + 1 + (fc > 0) + fc
                      + len(_TAIL)), dtype=np.uint8)
    col = 0
    for k, (v, a) in enumerate(((ff, af), (fi, ai))):
        table[:, col] = _MINUS.take(np.signbit(v).view(np.uint8))
        _put_digits(table, col + 1, a, widths[k], 1)
        col += widths[k] + 1
        table[:, col] = 44  # ','
        col += 1
    for k in range(4):
        table[:, col] = _MINUS.take(np.signbit(b[:, k]).view(np.uint8))
        _put_digits(table, col + 1, wb[:, k], widths[2 + k], 1)
        col += widths[2 + k] + 1
        table[:, col] = 46  # '.'
        table[:, col + 1] = _TENS.take(cents[:, k])
        table[:, col + 2] = _ONES.take(cents[:, k])
        table[:, col + 3] = 44
        col += 4
    table[:, col] = _MINUS.take(np.signbit(c).view(np.uint8))
    _put_digits(table, col + 1, whole, wc, 1)
    col += wc + 1
    if fc:
        table[:, col] = (shown > 0) * np.uint8(46)
        col += 1
        digits = np.empty((n, 7), dtype=np.uint8)
        _put_digits(digits, 0, frac, 7, 7)
        for j in range(fc):
            table[:, col + j] = digits[:, j] * (shown > j)
        col += fc
    table[:, col:] = _TAIL
    text = table.ravel()
    text = text[text != 0]
    if not bad.any():
        return text.tobytes()
    ends = np.flatnonzero(text == 10) + 1
    starts = np.r_[0, ends[:-1]]
    parts = []
    last = 0
    for r in np.flatnonzero(bad).tolist():
        parts.append(text[last:starts[r]].tobytes())
        parts.append((_ROW % (int(f[r]), int(i[r]), *b[r].tolist(), float(c[r]))).encode())
        last = ends[r]
    parts.append(text[last:].tobytes())
    return b"".join(parts)


@dataclass(frozen=True)
class SeqInfo:
    """``seqinfo.ini`` of a MOTChallenge sequence.

    Attributes
    ----------
    name : str
        The sequence's name (default: its folder's).
    frame_rate : float
        Frames per second (``frameRate``).
    seq_length : int
        Number of frames (``seqLength``).
    im_width, im_height : int
        Image size in pixels (``imWidth``, ``imHeight``).
    im_dir : str
        The images' folder (``imDir``).
    im_ext : str
        The images' suffix (``imExt``).

    Examples
    --------
    >>> info = SeqInfo("MOT17-02", 30.0, 600, 1920, 1080)
    >>> info.seq_length / info.frame_rate, info.im_dir, info.im_ext
    (20.0, 'img1', '.jpg')
    """

    name: str
    frame_rate: float
    seq_length: int
    im_width: int
    im_height: int
    im_dir: str = "img1"
    im_ext: str = ".jpg"

    @classmethod
    def from_detections(cls, path: str | os.PathLike, table: MOTTable,
                        frame_rate: float) -> SeqInfo:
        """The sequence a detections file describes where no ``seqinfo.ini`` does: named as
        :func:`sequence_name` names ``path``, at ``frame_rate``, as long as its last frame,
        its image as large as its boxes reach (0 x 0 if it has none).

        Examples
        --------
        >>> t = MOTTable.from_rows([(2, -1, 10, 20, 30, 40), (5, -1, 600, 300, 40.5, 80)])
        >>> info = SeqInfo.from_detections("cam3/det/det.txt", t, 25.0)
        >>> info.name, info.frame_rate, info.seq_length, (info.im_width, info.im_height)
        ('cam3', 25.0, 5, (641, 380))
        """
        name = sequence_name(path)
        if not len(table):
            return cls(name, float(frame_rate), 0, 0, 0)
        far = table.boxes[:, :2] + table.boxes[:, 2:]
        return cls(name, float(frame_rate), int(table.frames.max()),
                   int(np.ceil(max(far[:, 0].max(), 1))), int(np.ceil(max(far[:, 1].max(), 1))))


DETECTION_SUFFIXES = (".txt", ".csv")
"""The suffixes of a detections file tracked without a sequence folder: MOTChallenge's text,
or CSV with a header."""

PARQUET_DETECTIONS = ("Parquet detections are not read: write them as CSV with a header, "
                      "DataFrame.to_csv, or as MOTChallenge text")
"""Said of a ``.parquet`` file given as detections (the command line and
:func:`~vistrack.pipeline.read_detections` say it alike)."""


def sequence_name(path: str | os.PathLike) -> str:
    """The name of the sequence a folder or a detections file holds: a folder's name, or a
    file's without its suffix, except MOTChallenge's ``SEQ/det/det.txt``, named ``SEQ``.
    A path whose last part names nothing (``.``, ``..``) is named from the folder it
    resolves to.

    Raises
    ------
    ValueError
        If the path resolves to no name (the root folder).

    Examples
    --------
    >>> sequence_name("MOT17-02/det/det.txt"), sequence_name("dets/cam3.csv")
    ('MOT17-02', 'cam3')
    """
    p = Path(path)
    if p.name in ("", ".", ".."):
        p = p.resolve()
        if p.name in ("", ".", ".."):
            raise ValueError(f"{path} has no name to name its results after (it resolves "
                             f"to {p})")
    seq = _det_file_sequence(p)
    if seq is not None:
        return seq
    return p.name if p.is_dir() else p.stem


def _det_file_sequence(p: Path) -> str | None:
    """``SEQ`` for MOTChallenge's ``SEQ/det/det.txt``, else None; given relative to its
    sequence's folder or below (``det/det.txt`` run inside ``SEQ``, ``det.txt`` inside its
    ``det``), named from the folders it lies in (it was named ``det``, its results
    ``det.txt`` where TrackEval looks for ``SEQ.txt``)."""
    if p.name != "det.txt":
        return None
    if not p.parent.parent.name or p.parent.parent.name in (".", ".."):
        p = Path(os.path.abspath(p))  # (the names as given: not a link's target's)
    if p.parent.name == "det" and p.parent.parent.name:
        return p.parent.parent.name
    return None


def _ini_error(exc: configparser.Error) -> str:
    """``, line N: not a valid INI file: what`` for configparser's error ``exc``, on one line
    (its own messages span several and repeat the file's name)."""
    line = getattr(exc, "lineno", None)
    if isinstance(exc, configparser.MissingSectionHeaderError):
        what = f"no [section] header before {exc.line.strip()!r}"
    elif isinstance(exc, configparser.DuplicateOptionError):
        what = f"{exc.option!r} appears twice in [{exc.section}]"
    elif isinstance(exc, configparser.DuplicateSectionError):
        what = f"[{exc.section}] appears twice"
    elif isinstance(exc, configparser.ParsingError) and exc.errors:
        line, text = exc.errors[0]  # the line's repr
        what = f"not 'key = value': {ast.literal_eval(text).strip()!r}"
    else:
        what = " ".join(str(exc).split())
    return (f", line {line}" if line else "") + f": not a valid INI file: {what}"


def read_seqinfo(path: str | os.PathLike, *, frame_rate: float | None = None) -> SeqInfo:
    """Read ``seqinfo.ini`` (or the ``seqinfo.ini`` inside a sequence folder).

    Parameters
    ----------
    path : str or os.PathLike
        The file, or the sequence folder holding it.
    frame_rate : float, optional
        The rate to take where the file has no ``frameRate`` (``vistrack track --fps``);
        where it has one, that is read and checked as without it.

    Returns
    -------
    SeqInfo
        Its ``[Sequence]`` section.

    Raises
    ------
    FileNotFoundError
        If the file does not exist.
    ValueError, TypeError
        If ``frame_rate`` is given and is not a finite number > 0.
    MOTFormatError
        If it is not a UTF-8 text INI file, has no ``[Sequence]`` section, or lacks
        ``frameRate`` (without ``frame_rate``), ``seqLength``, ``imWidth`` or ``imHeight`` or
        has one that is not a
        finite number > 0 (the last three whole numbers, written ``600`` or ``600.0``), naming
        the file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "seqinfo.ini").write_text("[Sequence]\\nname=S\\nframeRate=25\\nseqLength=3\\n"
    ...                                    "imWidth=640\\nimHeight=480\\n")
    >>> info = read_seqinfo(d)
    >>> info.name, info.frame_rate, info.seq_length, (info.im_width, info.im_height)
    ('S', 25.0, 3, (640, 480))
    """
    if frame_rate is not None:  # (-5, NaN and True were taken, "abc" failed unnamed)
        frame_rate = as_finite(frame_rate, "frame_rate", 0.0, above=True)
    path, s = _sequence_section(path)
    return SeqInfo(name=s.get("name", path.parent.name),
                   frame_rate=(float(frame_rate) if frame_rate is not None
                               and "frameRate" not in s
                               else _seqinfo_value(path, s, "frameRate", float)),
                   seq_length=_seqinfo_value(path, s, "seqLength", int),
                   im_width=_seqinfo_value(path, s, "imWidth", int),
                   im_height=_seqinfo_value(path, s, "imHeight", int),
                   im_dir=s.get("imDir", "img1"), im_ext=s.get("imExt", ".jpg"))


def read_seq_length(path: str | os.PathLike) -> int:
    """``seqLength`` of ``seqinfo.ini`` (or of the one inside a sequence folder), the one
    value scoring needs: the other keys :func:`read_seqinfo` requires may be absent, as
    TrackEval reads such files.

    Raises
    ------
    FileNotFoundError, MOTFormatError
        As :func:`read_seqinfo`, for ``seqLength`` alone.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> d = pathlib.Path(tempfile.mkdtemp())
    >>> _ = (d / "seqinfo.ini").write_text("[Sequence]\\nname=S\\nseqLength=3\\n")
    >>> read_seq_length(d)
    3
    """
    path, s = _sequence_section(path)
    return int(_seqinfo_value(path, s, "seqLength", int))


def _sequence_section(path: str | os.PathLike, required: bool = True) -> tuple[Path, Any]:
    """The file and its ``[Sequence]`` section (see :func:`read_seqinfo`'s errors); without
    ``required``, an empty one where the file has none (as :class:`~vistrack.io.VideoReader`
    reads a folder's images)."""
    path = Path(path)
    if path.is_dir():
        path = path / "seqinfo.ini"
    if not path.exists():
        raise FileNotFoundError(f"{path} does not exist")
    text = _read_text(os.fspath(path), "seqinfo.ini")
    # no interpolation: a '%' in a value is the value's
    cp = configparser.ConfigParser(interpolation=None)
    try:
        cp.read_string(text, source=str(path))
    except configparser.Error as exc:
        raise MOTFormatError(f"{path}{_ini_error(exc)}") from None
    if "Sequence" not in cp:
        if not required:
            return path, {}
        raise MOTFormatError(f"{path}: no [Sequence] section")
    return path, cp["Sequence"]


def _seqinfo_value(path: Path, s: Any, key: str, kind: type) -> Any:
    """``key`` of the section ``s``: a finite number > 0 (a whole one for ``int``, written
    ``600`` or ``600.0``), or a MOTFormatError naming the file."""
    if key not in s:
        hint = ("; give the rate (vistrack track --fps, read_seqinfo's frame_rate)"
                if key == "frameRate" else "")
        raise MOTFormatError(f"{path}: [Sequence] has no {key}{hint}")
    try:
        # a count written as a float (600.0, 6e2) is a number > 0 as the contract asks;
        # written as an integer, it is read as one (past 2**53 a float changed it)
        text = s[key].strip()
        # (at most 18 digits: int() took 400 and float() of it overflowed, unnamed)
        v = (int(text) if re.fullmatch(r"[+-]?[0-9]{1,18}", text) else text_number(text)) \
            if kind is int else text_number(text) if kind is float else kind(s[key])
    except ValueError:
        # ("is not float", Python's word, and no line before; the file is read again for
        # the line only on the way to an error)
        raise MOTFormatError(f"{_ini_line(path, key)}: {key} = {s[key]!r} is not a "
                             "number") from None
    if kind is not str and not 0 < v < np.inf:
        raise MOTFormatError(f"{_ini_line(path, key)}: {key} must be a finite number > 0; "
                             f"got {s[key]}")
    if kind is int:
        if not isinstance(v, int) and not float(v).is_integer():
            raise MOTFormatError(f"{_ini_line(path, key)}: {key} must be a whole number; "
                                 f"got {s[key]}")
        v = int(v)
    return v


def _ini_line(path: Path, key: str) -> str:
    """``path:LINE`` of the line that sets ``key`` in ``[Sequence]`` (keys are read without
    regard to case, as configparser reads them), or ``path`` alone where none is found."""
    section = ""
    # (lines as editors count them: splitlines also broke at a form feed or U+2028 in a
    # comment, and named the line after)
    for n, line in enumerate(_text_lines(_read_text(os.fspath(path), "seqinfo.ini")), 1):
        t = line.strip()
        if t.startswith("["):
            # the header as configparser reads it: "[Sequence] ; MOT" is [Sequence]
            head = re.match(r"\[(?P<h>.+)\]", t)
            section = head.group("h") if head else ""
        elif section == "Sequence" and t.partition("=")[0].partition(":")[0].strip().lower() \
                == key.lower():
            return f"{path}:{n}"
    return str(path)
