"""Tracks out: sinks that take a tracker's output frame by frame and write a file.

Every sink answers ``write(frame, tracks)`` (one :class:`~vistrack.types.Frame` and the
:class:`~vistrack.types.Tracks` reported in it) and ``close()``; :func:`vistrack.pipeline.run`
feeds any list of them. Here: :class:`MOTWriter` (MOTChallenge results), :class:`CSVWriter`
(``frame,id,bb_left,bb_top,bb_width,bb_height,conf,class`` with a header) and
:class:`BoxesWriter` (one object's ``frame,x,y,w,h``, OTB-style), which write their rows
as the frames come to a partial file renamed into place when closed
(:mod:`vistrack.io.atomic`), so that a long run's memory does not grow with its rows;
:class:`TrackRows` keeps the rows in memory instead. Pictures are sinks in
:mod:`vistrack.viz`.
"""

from __future__ import annotations

import itertools
import os
from dataclasses import replace
from pathlib import Path
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from .._validate import as_float_array
from ..types import Frame, Tracks
from .atomic import PartialFile, check_output, open_replacing
from .motchallenge import _ROW as _MOT_ROW
from .motchallenge import (
    MOTTable,
    _check_decimals,
    _format_rows,
    _format_rows_with,
    _integers,
    read_mot,
)

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["Sink", "TrackRows", "MOTWriter", "CSVWriter", "PointsCSVWriter", "BoxesWriter",
           "write_boxes"]


@runtime_checkable
class Sink(Protocol):
    """What every output of the pipeline answers: ``write(frame, tracks)`` and ``close()``.

    Any object with these two methods is a sink for :func:`vistrack.pipeline.run`, which
    writes every frame's tracks to it and closes it when the source ends (or calls its
    ``abort()``, where it has one, if the run fails). The protocol is checkable at run time
    with ``isinstance`` (which looks for the names only, not their signatures).

    Examples
    --------
    >>> class Count:
    ...     def __init__(self):
    ...         self.tracks = 0
    ...     def write(self, frame, tracks):
    ...         self.tracks += len(tracks)
    ...     def close(self):
    ...         print(self.tracks, "tracks")
    >>> isinstance(Count(), Sink), isinstance(TrackRows(), Sink)
    (True, True)
    """

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Take one frame's tracks.

        Parameters
        ----------
        frame : Frame
            The frame.
        tracks : Tracks
            The tracks the tracker reported in it.

        Examples
        --------
        >>> rows = TrackRows()
        >>> rows.write(Frame(3, 0.1), Tracks(ids=np.array([1]), boxes=np.array([[0, 0, 2.0, 3]]),
        ...                                   points=None, scores=np.ones(1), classes=np.zeros(1)))
        >>> rows.frames.tolist()
        [3]
        """
        ...

    def close(self) -> None:
        """Finish (write the file).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "tracks.csv"
        >>> sink = CSVWriter(path)
        >>> sink.close()
        >>> path.read_text()
        'frame,id,bb_left,bb_top,bb_width,bb_height,conf,class\\n'
        """
        ...


class _Column:
    """Rows appended in blocks to one array that doubles when full: ``values()`` equals the
    concatenation of the blocks (the dtype follows them as ``np.concatenate``'s would)."""

    def __init__(self) -> None:
        self.data: np.ndarray | None = None
        self.n = 0

    def add(self, block: np.ndarray) -> None:
        k = len(block)
        if self.data is None:
            self.data = np.empty((max(64, k),) + block.shape[1:], dtype=block.dtype)
        dtype = np.result_type(self.data, block)
        if self.n + k > len(self.data) or dtype != self.data.dtype:
            grown = np.empty((max(2 * len(self.data), self.n + k),) + self.data.shape[1:],
                             dtype=dtype)
            grown[:self.n] = self.data[:self.n]
            self.data = grown
        self.data[self.n:self.n + k] = block
        self.n += k

    def values(self) -> np.ndarray:
        assert self.data is not None
        return self.data[:self.n].copy()

    def view(self, shape: tuple[int, ...]) -> np.ndarray:
        """The rows so far without a copy (``np.zeros(shape)`` before any)."""
        return self.data[:self.n] if self.data is not None else np.zeros(shape)


class TrackRows:
    """Collects box tracks as rows: :attr:`frames`, :attr:`ids`, :attr:`xywh` and
    :attr:`scores`, in the order written (a sink that writes nothing).

    Examples
    --------
    >>> rows = TrackRows()
    >>> rows.write(Frame(1, 0.0), Tracks(ids=np.array([4]), boxes=np.array([[0, 0, 2.0, 3]]),
    ...                                   points=None, scores=np.ones(1), classes=np.zeros(1)))
    >>> rows.frames.tolist(), rows.ids.tolist(), rows.xywh.tolist()
    ([1], [4], [[0.0, 0.0, 2.0, 3.0]])
    """

    def __init__(self) -> None:
        # each column grows by doubling, so that a long run keeps a few large arrays rather
        # than four small ones a frame, which the C allocator cannot give back between the
        # frames' images (the process's memory then grew by ~80 KB a frame)
        self._frames = _Column()
        self._ids = _Column()
        self._xywh = _Column()
        self._scores = _Column()

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Keep the rows of one frame's tracks (boxes).

        Parameters
        ----------
        frame : Frame
            The frame; its index is each row's frame.
        tracks : Tracks
            Box tracks (point tracks have no ``xywh``).

        Raises
        ------
        ValueError
            If the tracks are points, or an id is not a whole number.

        Examples
        --------
        >>> rows = TrackRows()
        >>> rows.write(Frame(2, 0.04), Tracks(ids=np.array([4, 5]),
        ...                                   boxes=np.array([[0, 0, 2.0, 3], [1, 1, 3, 3]]),
        ...                                   points=None, scores=np.ones(2), classes=np.zeros(2)))
        >>> len(rows), rows.ids.tolist()
        (2, [4, 5])
        """
        if len(tracks):
            # (ids 1.2 and 1.7 were both track 1, where the writers name them)
            f = _frame_of(frame)
            ids = _integers_of(f, np.asarray(tracks.ids), "ids")
            self._frames.add(np.full(len(tracks), f))
            self._ids.add(ids)
            self._xywh.add(_box_rows(tracks, frame, "TrackRows"))
            self._scores.add(np.asarray(tracks.scores, dtype=float))

    def close(self) -> None:
        """Nothing to finish (the rows stay readable).

        Examples
        --------
        >>> rows = TrackRows()
        >>> rows.close()
        >>> len(rows)
        0
        """

    def __len__(self) -> int:
        return self._frames.n

    @staticmethod
    def _cat(column: _Column, shape: tuple[int, ...]) -> np.ndarray:
        return column.values() if column.n else np.zeros(shape)

    @property
    def frames(self) -> np.ndarray:
        """Frame index of each row ``(N,)`` int.

        Examples
        --------
        >>> TrackRows().frames
        array([], dtype=int64)
        """
        return self._cat(self._frames, (0,)).astype(int)

    @property
    def ids(self) -> np.ndarray:
        """Track identity of each row ``(N,)`` int.

        Examples
        --------
        >>> rows = TrackRows()
        >>> rows.write(Frame(1, 0.0), Tracks(ids=np.array([7]), boxes=np.array([[0, 0, 2.0, 3]]),
        ...                                   points=None, scores=np.ones(1), classes=np.zeros(1)))
        >>> rows.ids
        array([7])
        """
        return self._cat(self._ids, (0,)).astype(int)

    @property
    def xywh(self) -> np.ndarray:
        """Boxes ``(N, 4)``: ``x, y, w, h`` (top-left corner and size).

        Examples
        --------
        >>> rows = TrackRows()
        >>> rows.write(Frame(1, 0.0), Tracks(ids=np.array([7]), boxes=np.array([[1, 2, 4.0, 8]]),
        ...                                   points=None, scores=np.ones(1), classes=np.zeros(1)))
        >>> rows.xywh.tolist()
        [[1.0, 2.0, 3.0, 6.0]]
        """
        return self._cat(self._xywh, (0, 4))

    @property
    def scores(self) -> np.ndarray:
        """Score of each row ``(N,)``.

        Examples
        --------
        >>> rows = TrackRows()
        >>> rows.write(Frame(1, 0.0), Tracks(ids=np.array([7]), boxes=np.array([[1, 2, 4.0, 8]]),
        ...                                   points=None, scores=np.array([0.8]),
        ...                                   classes=np.zeros(1)))
        >>> rows.scores.tolist()
        [0.8]
        """
        return self._cat(self._scores, (0,))


_COLUMNS_FROM = 256
"""Rows a frame from which its text is formatted a column at a time (write_mot's formatter:
0.47 ms for 1,000 rows against 0.89 ms with %, but 0.17 ms for 4 rows against 5 us)."""


def _mot_text(frame: int, ids: np.ndarray, xywh: np.ndarray, scores: np.ndarray,
              decimals: int = 2) -> str:
    """One frame's rows as MOTChallenge lines, in the given order (:func:`~vistrack.io.write_mot`'s
    format, byte for byte: one %-format of the block, or write_mot's formatter for many)."""
    if decimals != 2:
        return _format_rows_with(np.full(len(ids), frame), ids, xywh, scores,
                                 decimals).decode("ascii")
    if len(ids) >= _COLUMNS_FROM:
        return _format_rows(np.full(len(ids), frame), ids, xywh, scores).decode("ascii")
    cells = zip([frame] * len(ids), ids.tolist(), *xywh.T.tolist(), scores.tolist())
    return (_MOT_ROW * len(ids)) % tuple(itertools.chain.from_iterable(cells))


def _frame_and_id(line: str) -> tuple[int, int]:
    f, i, _ = line.split(",", 2)
    return int(f), int(i)


def _box_rows(tracks: Tracks, frame: Frame, what: str) -> np.ndarray:
    """The tracks' boxes ``x, y, w, h``; point tracks are a ValueError that says where they
    can go instead (``what``: the sink, as the message names it)."""
    if tracks.boxes is None:
        raise ValueError(
            f"frame {int(frame.index)}: {what} takes box tracks (MOTChallenge's rows are "
            "boxes), and these tracks are points (a PointTracker's): run them with "
            "vistrack.pipeline.run and sinks that take points (io.PointsCSVWriter, "
            "viz.AnnotatedVideo, viz.TrajectoryPlot, or your own), or track_video's "
            "tracker 'particles'")
    return tracks.xywh


def _frame_of(frame: Frame) -> int:
    """``frame.index`` as an int, or a ValueError where it is no whole number or lies from
    2**53 on (a frame of 2.7 was written as frame 2, and one of 2**53 + 1 written where
    :func:`~vistrack.io.read_mot` refuses it); below 1 is for each sink to say."""
    v = frame.index
    x = float(v) if isinstance(v, (int, float, np.integer, np.floating)) \
        and not isinstance(v, bool) else float("nan")
    if not (np.isfinite(x) and x == np.round(x)):
        raise ValueError(f"frame {v!r}: a frame's index must be a whole number")
    if abs(int(v)) >= 2**53:
        raise ValueError(f"frame {int(v)}: a frame's index must lie within ±(2**53 - 1), "
                         "which read_mot refuses past")
    return int(v)


def _integers_of(f: int, values: np.ndarray, name: str) -> np.ndarray:
    """Frame ``f``'s ``values`` (the tracks' ids or classes) as integers, or a ValueError
    naming the frame."""
    try:
        return _integers(values, name)
    except ValueError as e:
        raise ValueError(f"frame {f}: {e}") from None


class _RowsFile:
    """Box tracks written as text rows, frame by frame, to the partial file of ``path``
    (:class:`~vistrack.io.atomic.PartialFile`), renamed into place when closed: only the
    count of rows and the identities, each with its class, are kept, so memory does not grow
    with the rows."""

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self._file = PartialFile(self.path)
        self._rows = 0
        self._ids: dict[int, int] = {}  # identity: its class (the latest written)
        # the latest frame written and its identities (a frame given again next is checked
        # against them)
        self._frame: tuple[int, set[int]] = (0, set())

    def _columns(self, frame: Frame, tracks: Tracks
                 ) -> tuple[int, np.ndarray, np.ndarray, np.ndarray, list[int]]:
        """The frame's index and its rows' ids, boxes ``x, y, w, h`` and scores, as
        :class:`TrackRows` keeps them (int and float64), and classes (a list), counted; a
        row :func:`~vistrack.io.read_mot` would refuse to read back (as
        :func:`~vistrack.io.write_mot` refuses it) is a ValueError naming the frame."""
        f = _frame_of(frame)
        if f < 1:
            raise ValueError(f"frame {f}: MOTChallenge frames count from 1 (read_mot refuses "
                             f"frame {f})")
        ids = _integers_of(f, tracks.ids, "ids")  # (1.7 was written as track 1)
        xywh = np.asarray(_box_rows(tracks, frame, f"{type(self).__name__}({self.path})"),
                          dtype=float)
        scores = np.asarray(tracks.scores, dtype=float)
        bad = ~np.isfinite(xywh).all(axis=1) | (xywh[:, 2:] < 0).any(axis=1) | ~np.isfinite(
            scores)
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"frame {f}, track {ids[k]}: box (x, y, w, h) "
                             f"{xywh[k].tolist()}, score {scores[k]}: a row read_mot refuses "
                             "(a box must be finite with w, h >= 0, a score finite)")
        return f, ids, xywh, scores, self._count(ids, tracks, f)

    def _count(self, ids: np.ndarray, tracks: Tracks, f: int) -> list[int]:
        """Count rows ``ids`` of frame ``f`` written, each identity with its class; returns
        the classes (whole numbers, or a ValueError naming the frame: a tracker's NaN class
        was written as -9223372036854775808, 2.7 as 2).

        An identity written twice in a frame (in one call, or in two calls for the frame one
        after the other) is a ValueError naming both: the file was written, and
        :func:`~vistrack.evaluation.evaluate_mot` refused it only when scored."""
        classes = _integers_of(f, tracks.classes, "classes").tolist()
        before = self._frame[1] if self._frame[0] == f else set()
        now = ids.tolist()
        given = set(now)
        if len(given) < len(now) or not before.isdisjoint(given):
            seen = set(before)
            for i in now:
                if i in seen:
                    raise ValueError(f"frame {f}: track {i} is given twice (a track is one "
                                     "row a frame; evaluate_mot refuses a file with two)")
                seen.add(i)
        self._frame = (f, before | given)
        self._rows += len(ids)
        self._ids.update(zip(ids.tolist(), classes))
        return classes

    def __len__(self) -> int:
        return self._rows

    @property
    def identities(self) -> np.ndarray:
        """The distinct track identities written so far, sorted ``(K,)`` int.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> sink = CSVWriter(pathlib.Path(tempfile.mkdtemp()) / "tracks.csv")
        >>> for k, ids in enumerate(([4, 2], [2], [9, 4]), start=1):
        ...     sink.write(Frame(k, 0.0), Tracks(ids=np.array(ids), boxes=np.ones((len(ids), 4)),
        ...                                      points=None, scores=np.ones(len(ids)),
        ...                                      classes=np.zeros(len(ids))))
        >>> len(sink), sink.identities.tolist()
        (5, [2, 4, 9])
        >>> sink.abort()
        """
        return np.array(sorted(self._ids), dtype=int)

    def classes_of(self, ids: ArrayLike) -> np.ndarray:
        """The class of each of ``ids``, identities written so far (a box tracker's track
        keeps the class of the detection it started from).

        Parameters
        ----------
        ids : (N,) array_like of int
            Identities written.

        Returns
        -------
        (N,) int64 ndarray

        Raises
        ------
        KeyError
            If an identity was never written.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> sink = CSVWriter(pathlib.Path(tempfile.mkdtemp()) / "tracks.csv")
        >>> sink.write(Frame(1, 0.0), Tracks(ids=np.array([4, 2]), boxes=np.ones((2, 4)),
        ...                                  points=None, scores=np.ones(2),
        ...                                  classes=np.array([3, 0])))
        >>> sink.classes_of([2, 4, 4]).tolist()
        [0, 3, 3]
        >>> sink.abort()
        """
        return np.array([self._ids[int(i)] for i in np.asarray(ids).ravel()], dtype=np.int64)

    def abort(self) -> None:
        """Give the file up (a run that failed): the rows written are removed, and an earlier
        file at ``path`` is left as it was."""
        self._file.abort()


class MOTWriter(_RowsFile):
    """Writes MOTChallenge results (:func:`~vistrack.io.write_mot`'s format and order: sorted
    by frame and id) to ``path``.

    The rows go to a partial file beside ``path`` as the frames come, and replace ``path``
    only when closed (:class:`~vistrack.io.atomic.PartialFile`); :meth:`abort` removes them.
    Frames given in increasing order (as :func:`vistrack.pipeline.run` gives them) are
    written as they come, each frame's rows sorted by id, so memory does not grow with the
    rows; frames out of order are sorted when the file is closed (the rows are then read
    back into memory once).

    Parameters
    ----------
    path : str or os.PathLike
        The results file (overwritten; its folder is made if needed).
    decimals : int
        The boxes' decimals (:func:`~vistrack.io.write_mot`'s): 2, MOTChallenge's, or more
        for boxes in smaller units (:func:`~vistrack.io.box_decimals`).

    Attributes
    ----------
    path : Path
        The results file.

    Raises
    ------
    ValueError
        If ``decimals`` is not an integer in 0-12.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "tracks.txt"
    >>> sink = MOTWriter(path)
    >>> sink.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=np.array([[10, 20, 40, 80.0]]),
    ...                                  points=None, scores=np.array([0.9]), classes=np.zeros(1)))
    >>> sink.close()
    >>> path.read_text()
    '1,1,10.00,20.00,30.00,60.00,0.9,-1,-1,-1\\n'
    >>> len(sink), sink.identities.tolist()
    (1, [1])
    """

    def __init__(self, path: str | os.PathLike, decimals: int = 2) -> None:
        _check_decimals(decimals)
        super().__init__(path)
        self.decimals = int(decimals)
        self._last: int | None = None  # the latest frame written
        self._in_order = True

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Write one frame's rows (boxes), sorted by id.

        Parameters
        ----------
        frame : Frame
            The frame; its index is each row's frame.
        tracks : Tracks
            Box tracks (point tracks have no ``xywh``).

        Raises
        ------
        ValueError
            If the tracks are points, or a row is one :func:`~vistrack.io.read_mot` or
            :func:`~vistrack.evaluation.evaluate_mot` refuses (a frame below 1, an id that
            is not a whole number or is given twice in the frame, a box or score that is
            not finite), naming the frame.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> sink = MOTWriter(pathlib.Path(tempfile.mkdtemp()) / "tracks.txt")
        >>> sink.write(Frame(2, 0.04), Tracks(ids=np.array([5, 4]),
        ...                                   boxes=np.array([[0, 0, 2.0, 3], [1, 1, 3, 3]]),
        ...                                   points=None, scores=np.ones(2), classes=np.zeros(2)))
        >>> print(sink._file.read(), end="")
        2,4,1.00,1.00,2.00,2.00,1,-1,-1,-1
        2,5,0.00,0.00,2.00,3.00,1,-1,-1,-1
        >>> sink.abort()
        """
        if not len(tracks):
            return
        f, ids, xywh, scores, _ = self._columns(frame, tracks)
        if self._last is not None and f <= self._last:
            self._in_order = False  # sorted when closed
        self._last = f if self._last is None else max(self._last, f)
        order = np.argsort(ids, kind="stable")
        self._file.write(_mot_text(f, ids[order], xywh[order], scores[order], self.decimals))

    def written(self) -> MOTTable:
        """The rows written so far, as the file will hold them (its text read back, before
        :meth:`close`: what a run scores before it commits its files).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> sink = MOTWriter(pathlib.Path(tempfile.mkdtemp()) / "tracks.txt")
        >>> sink.write(Frame(3, 0.1), Tracks(ids=np.array([2]), boxes=np.array([[1, 2, 4, 6.0]]),
        ...                                  points=None, scores=np.ones(1), classes=np.zeros(1)))
        >>> t = sink.written()
        >>> t.frames.tolist(), t.ids.tolist(), t.boxes.tolist(), sink.path.exists()
        ([3], [2], [[1.0, 2.0, 3.0, 4.0]], False)
        >>> sink.abort()
        """
        self._file.read()  # flushed to the partial file
        table = read_mot(self._file.part)  # (sorted by frame, stably)
        if not self._in_order:
            # as close() will sort the file: by frame and id (a frame written twice came
            # back as its two writes, each sorted by id on its own)
            table = table[np.lexsort((table.ids, table.frames))]
        return replace(table, path=str(self.path))

    def close(self) -> None:
        """Finish the file (sorting it by frame and id if frames came out of order) and
        rename it over ``path``.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "tracks.txt"
        >>> MOTWriter(path).close()
        >>> path.read_text()
        ''
        """
        if not self._in_order:
            try:
                # a stable sort of the lines by (frame, id): write_mot's np.lexsort order
                lines = sorted(self._file.read().splitlines(keepends=True), key=_frame_and_id)
                self._file.truncate()
                self._file.write("".join(lines))
            except BaseException:
                self._file.abort()
                raise
        self._file.commit()


class CSVWriter(_RowsFile):
    """Writes ``frame,id,bb_left,bb_top,bb_width,bb_height,conf,class`` rows, with that
    header, in the order written (boxes to 2 decimals, scores to 3; the class is the track's,
    that of the detections it follows, -1 where they had none), to ``path``.

    The columns are MOTChallenge's, named as :meth:`MOTTable.from_pandas
    <vistrack.io.motchallenge.MOTTable.from_pandas>` reads them, so the file reads back as
    the table it holds (``MOTTable.from_pandas(pandas.read_csv(path))``), and ``vistrack
    track`` reads it as detections. (Its header was ``frame,id,x,y,w,h,score,class``, where
    ``x, y`` was the box's corner, while ``x, y`` is its centre in :meth:`MOTTable.to_pandas
    <vistrack.io.motchallenge.MOTTable.to_pandas>`, trackpy's convention.)

    The rows go to a partial file beside ``path`` as the frames come, and replace ``path``
    only when closed (:class:`~vistrack.io.atomic.PartialFile`); :meth:`abort` removes them.

    Parameters
    ----------
    path : str or os.PathLike
        The file (overwritten; its folder is made if needed).

    Attributes
    ----------
    path : Path
        The file.

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "tracks.csv"
    >>> sink = CSVWriter(path)
    >>> sink.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=np.array([[10, 20, 40, 80.0]]),
    ...                                  points=None, scores=np.array([0.9]), classes=np.zeros(1)))
    >>> sink.close()
    >>> print(path.read_text(), end="")
    frame,id,bb_left,bb_top,bb_width,bb_height,conf,class
    1,1,10.00,20.00,30.00,60.00,0.900,0
    """

    _HEADER = "frame,id,bb_left,bb_top,bb_width,bb_height,conf,class\n"
    # %d, %.2f and %.3f are str.format's d, .2f and .3f
    _ROW = "%d,%d,%.2f,%.2f,%.2f,%.2f,%.3f,%d\n"

    def __init__(self, path: str | os.PathLike) -> None:
        super().__init__(path)
        self._started = False

    def _start(self) -> None:
        if not self._started:
            self._file.write(self._HEADER)
            self._started = True

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Write one frame's rows (boxes), in the tracks' order (the header first).

        Parameters
        ----------
        frame : Frame
            The frame; its index is each row's frame.
        tracks : Tracks
            Box tracks (point tracks have no ``xywh``).

        Raises
        ------
        ValueError
            If the tracks are points, or a row is one :func:`~vistrack.io.read_mot` or
            :func:`~vistrack.evaluation.evaluate_mot` refuses (a frame below 1, an id that
            is not a whole number or is given twice in the frame, a box or score that is
            not finite), naming the frame.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> sink = CSVWriter(pathlib.Path(tempfile.mkdtemp()) / "tracks.csv")
        >>> sink.write(Frame(3, 0.1), Tracks(ids=np.array([7]), boxes=np.array([[1, 2, 4, 8.0]]),
        ...                                  points=None, scores=np.array([0.5]),
        ...                                  classes=np.zeros(1)))
        >>> print(sink._file.read(), end="")
        frame,id,bb_left,bb_top,bb_width,bb_height,conf,class
        3,7,1.00,2.00,3.00,6.00,0.500,0
        >>> sink.abort()
        """
        self._start()
        if not len(tracks):
            return
        f, ids, xywh, scores, classes = self._columns(frame, tracks)
        cells = zip([f] * len(ids), ids.tolist(), *xywh.T.tolist(), scores.tolist(), classes)
        self._file.write((self._ROW * len(ids)) % tuple(itertools.chain.from_iterable(cells)))

    def close(self) -> None:
        """Finish the file (the header alone if no frame came) and rename it over ``path``.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "out" / "tracks.csv"
        >>> CSVWriter(path).close()
        >>> path.read_text()
        'frame,id,bb_left,bb_top,bb_width,bb_height,conf,class\\n'
        """
        try:
            self._start()
        except BaseException:
            self._file.abort()
            raise
        self._file.commit()


class PointsCSVWriter(_RowsFile):
    """Writes point tracks as ``frame,particle,x,y`` rows, with that header (trackpy's
    columns: a particle's identity and its position, the origin at the centre of pixel
    (0, 0)), positions to 3 decimals, in the order written, to ``path``; what
    :class:`CSVWriter` is for box tracks. The rows go to a partial file beside ``path`` as
    the frames come, and replace ``path`` only when closed.

    Parameters
    ----------
    path : str or os.PathLike
        The CSV file to write, replaced when the sink is closed (its folder made if needed).

    Examples
    --------
    >>> from pathlib import Path
    >>> from tempfile import mkdtemp
    >>> sink = PointsCSVWriter(Path(mkdtemp()) / "tracks.csv")
    >>> sink.write(Frame(2, 0.0), Tracks(ids=np.array([5]), boxes=None,
    ...                                  points=np.array([[12.25, 3.5]]),
    ...                                  scores=np.ones(1), classes=np.zeros(1)))
    >>> sink.close()
    >>> print(sink.path.read_text(), end="")
    frame,particle,x,y
    2,5,12.250,3.500
    >>> len(sink), sink.identities.tolist()
    (1, [5])
    """

    _HEADER = "frame,particle,x,y\n"
    _ROW = "%d,%d,%.3f,%.3f\n"

    def __init__(self, path: str | os.PathLike) -> None:
        super().__init__(path)
        self._file.write(self._HEADER)

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Write one frame's rows (points), in the tracks' order.

        Raises
        ------
        ValueError
            If the tracks are boxes, a frame is below 1, an identity is not a whole number
            or is given twice in the frame, or a position is not finite (each naming the
            frame).
        """
        f = _frame_of(frame)
        if len(tracks) and (tracks.points is None or tracks.boxes is not None):
            # (no tracks of either kind are none to write: Tracks.empty(), the default's
            # boxes, was refused)
            raise ValueError(f"frame {f}: PointsCSVWriter({self.path}) takes point tracks; "
                             "these are boxes (CSVWriter writes them)")
        if f < 1:
            raise ValueError(f"frame {f}: frames count from 1")
        if not len(tracks):
            return
        ids = _integers_of(f, tracks.ids, "ids")  # (1.7 was written as track 1)
        xy = np.asarray(tracks.points, dtype=float)
        if xy.ndim != 2 or xy.shape[1] != 2:  # (the row's %-format failed, naming nothing)
            raise ValueError(f"frame {f}: PointsCSVWriter({self.path}) writes points of two "
                             f"coordinates, x and y; got shape {xy.shape}")
        bad = ~np.isfinite(xy).all(axis=1)
        if bad.any():
            k = int(np.argmax(bad))
            raise ValueError(f"frame {f}, particle {ids[k]}: position {xy[k].tolist()} is not "
                             "finite")
        self._count(ids, tracks, f)
        cells = zip([f] * len(ids), ids.tolist(), *xy.T.tolist())
        self._file.write((self._ROW * len(ids)) % tuple(itertools.chain.from_iterable(cells)))

    def written(self) -> MOTTable:
        """The points written so far, as rows of width and height 0 (what a run scores by
        distance before it commits its files, :func:`~vistrack.evaluation.evaluate_mot`'s
        ``zero_distance``).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> sink = PointsCSVWriter(pathlib.Path(tempfile.mkdtemp()) / "tracks.csv")
        >>> sink.write(Frame(3, 0.1), Tracks(ids=np.array([2]), boxes=None,
        ...                                  points=np.array([[1.5, 2.0]]),
        ...                                  scores=np.ones(1), classes=np.zeros(1)))
        >>> t = sink.written()
        >>> t.frames.tolist(), t.ids.tolist(), t.boxes.tolist(), sink.path.exists()
        ([3], [2], [[1.5, 2.0, 0.0, 0.0]], False)
        >>> sink.abort()
        """
        lines = self._file.read().splitlines()[1:]  # (the header)
        rows = np.array([[float(v) for v in line.split(",")] for line in lines]).reshape(-1, 4)
        n = len(rows)
        return MOTTable.from_rows(
            np.c_[rows[:, :2], rows[:, 2:], np.zeros((n, 2)), np.ones(n), -np.ones((n, 2))]
            if n else np.zeros((0, 9)), str(self.path))

    def close(self) -> None:
        """Rename the file over ``path`` (the header alone if no frame came)."""
        self._file.commit()


def write_boxes(path: str | os.PathLike, boxes: ArrayLike, *, force: bool = False) -> None:
    """Write one object's boxes as ``frame,x,y,w,h`` lines, frames from 1 (vistrack's
    ``boxes.txt``, read by :func:`vistrack.evaluation.single.read_boxes`).

    Parameters
    ----------
    path : str or Path
        The file; its directory is made if needed.
    boxes : (T, 4) array_like
        Boxes ``x, y, w, h``, one per frame, written with two decimals.
    force : bool
        Overwrite an existing file.

    Raises
    ------
    FileExistsError
        If ``path`` exists and ``force`` is False.
    IsADirectoryError, NotADirectoryError, PermissionError
        Before anything is written: if ``path`` is a folder, a folder above it is a file,
        or its folder cannot be written in (:func:`~vistrack.io.atomic.check_output`).
    ValueError
        If ``boxes`` is not ``(T, 4)`` (a VOT polygon's ``(T, 8)`` corners, or ``(T, 2)``
        centres, were written as other boxes).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "boxes.txt"
    >>> write_boxes(path, [[1, 2, 30, 40]])
    >>> path.read_text()
    '1,1.00,2.00,30.00,40.00\\n'
    """
    path = Path(path)
    b = as_float_array(boxes, "boxes")
    if b.ndim != 2 or b.shape[1] != 4:
        raise ValueError(f"boxes must be (T, 4), x, y, w, h in each frame; got shape "
                         f"{b.shape}")
    # a folder, or a file above it, was found at the rename after the whole file was
    # written (and a folder was told to pass force=True)
    check_output(path, force=force, name="path")
    with open_replacing(path) as fh:
        for k, (x, y, w, h) in enumerate(b, start=1):
            fh.write(f"{k},{x:.2f},{y:.2f},{w:.2f},{h:.2f}\n")


class BoxesWriter:
    """One object's box in every frame, written as ``frame,x,y,w,h`` lines (frames counted
    from 1 at the first frame written, :func:`write_boxes`' format) to ``path``: a
    single-object tracker's track 1. Frames the source skips (an image folder without
    ``000004.png``) get a line of NaN each, so that every line stays at its frame.

    Each frame's line goes to a partial file beside ``path`` as it comes, and replaces
    ``path`` only when closed (:class:`~vistrack.io.atomic.PartialFile`); :meth:`abort`
    removes it. The boxes are also kept (:attr:`boxes`, one array that doubles as it fills).

    Parameters
    ----------
    path : str or os.PathLike
        The file (overwritten; its folder is made if needed).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "boxes.txt"
    >>> sink = BoxesWriter(path)
    >>> one = Tracks(ids=np.array([1]), boxes=np.array([[10, 20, 40, 80.0]]), points=None,
    ...              scores=np.ones(1), classes=np.zeros(1))
    >>> sink.write(Frame(1, 0.0), one)
    >>> sink.write(Frame(2, 0.04), Tracks.empty())
    >>> sink.write(Frame(4, 0.12), one)
    >>> sink.close()
    >>> print(path.read_text(), end="")
    1,10.00,20.00,30.00,60.00
    2,nan,nan,nan,nan
    3,nan,nan,nan,nan
    4,10.00,20.00,30.00,60.00
    """

    # %d and %.2f are str.format's d and .2f
    _ROW = "%d,%.2f,%.2f,%.2f,%.2f\n"

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self._file = PartialFile(self.path)
        self._boxes = _Column()
        self._first: int | None = None  # the first frame written: line 1

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Write and keep the frame's box (NaN when no track is reported), after a line of
        NaN for each frame skipped since the last one written.

        Parameters
        ----------
        frame : Frame
            The frame: line ``frame.index - first + 1``, ``first`` the first frame's index.
        tracks : Tracks
            The frame's box tracks; the first one's box is kept.

        Raises
        ------
        ValueError
            If the frame comes at or before the last one written.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> sink = BoxesWriter(pathlib.Path(tempfile.mkdtemp()) / "boxes.txt")
        >>> sink.write(Frame(1, 0.0), Tracks.empty())
        >>> sink.boxes
        array([[nan, nan, nan, nan]])
        >>> sink.abort()
        """
        # a whole frame within 2**53 (a frame of 2**53 + 1 wrote lines of NaN without end,
        # 2.5 was written as line 2)
        _frame_of(frame)
        # (before the first frame is kept: point tracks were refused in Tracks.xywh's words,
        # naming neither the frame nor the sink, after it)
        box = np.asarray(_box_rows(tracks, frame, f"BoxesWriter({self.path})")[0]
                         if len(tracks) else np.full(4, np.nan), dtype=float)
        if self._first is None:
            self._first = frame.index
        line = frame.index - self._first + 1
        if line <= self._boxes.n:
            raise ValueError(f"frame {frame.index} comes after frame "
                             f"{self._first + self._boxes.n - 1}: frames must increase")
        while self._boxes.n < line - 1:  # frames the source skipped
            self._boxes.add(np.full((1, 4), np.nan))
            self._file.write(self._ROW % (self._boxes.n, *(np.nan,) * 4))
        self._boxes.add(box.reshape(1, 4))
        self._file.write(self._ROW % (self._boxes.n, *box.tolist()))

    @property
    def boxes(self) -> np.ndarray:
        """The boxes written so far ``(T, 4)`` (``x, y, w, h``; NaN in a frame without the
        object).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> sink = BoxesWriter(pathlib.Path(tempfile.mkdtemp()) / "boxes.txt")
        >>> sink.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=np.array([[1, 2, 4, 8.0]]),
        ...                                  points=None, scores=np.ones(1), classes=np.zeros(1)))
        >>> sink.boxes.tolist()
        [[1.0, 2.0, 3.0, 6.0]]
        >>> sink.abort()
        """
        return self._boxes.values() if self._boxes.n else np.zeros((0, 4))

    def close(self) -> None:
        """Finish the file and rename it over ``path`` (an empty file if no frame came).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "boxes.txt"
        >>> BoxesWriter(path).close()
        >>> path.read_text()
        ''
        """
        self._file.commit()

    def abort(self) -> None:
        """Give the file up (a run that failed): the lines written are removed, and an
        earlier file at ``path`` is left as it was."""
        self._file.abort()
