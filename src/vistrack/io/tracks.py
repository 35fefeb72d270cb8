"""Tracks out: sinks that take a tracker's output frame by frame and write a file when closed.

Every sink answers ``write(frame, tracks)`` (one :class:`~vistrack.types.Frame` and the
:class:`~vistrack.types.Tracks` reported in it) and ``close()``; :func:`vistrack.pipeline.run`
feeds any list of them. Here: :class:`MOTWriter` (MOTChallenge results), :class:`CSVWriter`
(``frame,id,x,y,w,h,score`` with a header) and :class:`BoxesWriter` (one object's
``frame,x,y,w,h``, OTB-style); pictures are sinks in :mod:`vistrack.viz`.
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Protocol, runtime_checkable

import numpy as np

from ..types import Frame, Tracks
from .atomic import open_replacing
from .motchallenge import write_mot

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["Sink", "TrackRows", "MOTWriter", "CSVWriter", "BoxesWriter", "write_boxes"]


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
        'frame,id,x,y,w,h,score\\n'
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
            If the tracks are points.

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
            self._frames.add(np.full(len(tracks), int(frame.index)))
            self._ids.add(np.asarray(tracks.ids))
            self._xywh.add(tracks.xywh)
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


class MOTWriter(TrackRows):
    """Writes MOTChallenge results (:func:`~vistrack.io.write_mot`) to ``path`` when closed.

    Parameters
    ----------
    path : str or os.PathLike
        The results file (overwritten; its folder is made if needed).

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
    """

    def __init__(self, path: str | os.PathLike) -> None:
        super().__init__()
        self.path = Path(path)

    def close(self) -> None:
        """Write the file (the rows sorted by frame and id).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "tracks.txt"
        >>> MOTWriter(path).close()
        >>> path.read_text()
        ''
        """
        write_mot(self.path, self.frames, self.ids, self.xywh, self.scores, force=True)


class CSVWriter(TrackRows):
    """Writes ``frame,id,x,y,w,h,score`` rows, with that header, to ``path`` when closed
    (boxes to 2 decimals, scores to 3).

    Parameters
    ----------
    path : str or os.PathLike
        The file (overwritten; its folder is made if needed).

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "tracks.csv"
    >>> sink = CSVWriter(path)
    >>> sink.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=np.array([[10, 20, 40, 80.0]]),
    ...                                  points=None, scores=np.array([0.9]), classes=np.zeros(1)))
    >>> sink.close()
    >>> print(path.read_text(), end="")
    frame,id,x,y,w,h,score
    1,1,10.00,20.00,30.00,60.00,0.900
    """

    def __init__(self, path: str | os.PathLike) -> None:
        super().__init__()
        self.path = Path(path)

    def close(self) -> None:
        """Write the file: the header, then the rows in the order written.

        Examples
        --------
        >>> import tempfile, pathlib
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "out" / "tracks.csv"
        >>> CSVWriter(path).close()
        >>> path.read_text()
        'frame,id,x,y,w,h,score\\n'
        """
        with open_replacing(self.path) as fh:
            fh.write("frame,id,x,y,w,h,score\n")
            for f, i, (x, y, w, h), s in zip(self.frames, self.ids, self.xywh, self.scores):
                fh.write(f"{f},{i},{x:.2f},{y:.2f},{w:.2f},{h:.2f},{s:.3f}\n")


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

    Examples
    --------
    >>> import tempfile, pathlib
    >>> path = pathlib.Path(tempfile.mkdtemp()) / "boxes.txt"
    >>> write_boxes(path, [[1, 2, 30, 40]])
    >>> path.read_text()
    '1,1.00,2.00,30.00,40.00\\n'
    """
    path = Path(path)
    if path.exists() and not force:
        raise FileExistsError(f"{path} exists; pass --force to overwrite it")
    b = np.asarray(boxes, dtype=float).reshape(-1, 4)
    with open_replacing(path) as fh:
        for k, (x, y, w, h) in enumerate(b, start=1):
            fh.write(f"{k},{x:.2f},{y:.2f},{w:.2f},{h:.2f}\n")


class BoxesWriter:
    """One object's box in every frame, written as ``frame,x,y,w,h`` lines (frames counted
    from 1, :func:`write_boxes`) to ``path`` when closed: a single-object tracker's track 1.

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
    >>> sink.close()
    >>> print(path.read_text(), end="")
    1,10.00,20.00,30.00,60.00
    2,nan,nan,nan,nan
    """

    def __init__(self, path: str | os.PathLike) -> None:
        self.path = Path(path)
        self._boxes: list[np.ndarray] = []

    def write(self, frame: Frame, tracks: Tracks) -> None:
        """Keep the frame's box (NaN when no track is reported).

        Parameters
        ----------
        frame : Frame
            The frame (its boxes are kept in the order written, one per call).
        tracks : Tracks
            The frame's box tracks; the first one's box is kept.

        Examples
        --------
        >>> sink = BoxesWriter("unused.txt")
        >>> sink.write(Frame(1, 0.0), Tracks.empty())
        >>> sink.boxes
        array([[nan, nan, nan, nan]])
        """
        self._boxes.append(tracks.xywh[0] if len(tracks) else np.full(4, np.nan))

    @property
    def boxes(self) -> np.ndarray:
        """The boxes written so far ``(T, 4)`` (``x, y, w, h``; NaN in a frame without the
        object).

        Examples
        --------
        >>> sink = BoxesWriter("unused.txt")
        >>> sink.write(Frame(1, 0.0), Tracks(ids=np.array([1]), boxes=np.array([[1, 2, 4, 8.0]]),
        ...                                  points=None, scores=np.ones(1), classes=np.zeros(1)))
        >>> sink.boxes.tolist()
        [[1.0, 2.0, 3.0, 6.0]]
        """
        return np.array(self._boxes, dtype=float).reshape(-1, 4)

    def close(self) -> None:
        """Write the file (:func:`write_boxes`, overwriting).

        Examples
        --------
        >>> import tempfile, pathlib
        >>> path = pathlib.Path(tempfile.mkdtemp()) / "boxes.txt"
        >>> BoxesWriter(path).close()
        >>> path.read_text()
        ''
        """
        write_boxes(self.path, self.boxes, force=True)
