"""Track management: a table of tracks as columns, and their lifecycle.

tentative → confirmed → lost → deleted (seed 003, "track initiation, confirmation and
deletion"):

- a new track is **tentative**; it is **confirmed** after ``confirm_hits`` updates in a row
  (M-of-M), or at once in a sequence's first frame (nothing can have been seen before it);
- a tentative track that misses a frame is deleted (a false alarm);
- a confirmed track that misses is **lost**: it keeps predicting and can be matched again,
  until it has been lost longer than ``max_lost`` seconds; then it is **deleted**, and nothing
  of it is kept (memory stays flat however long the sequence).

Identities are integers from 1, never reused until :meth:`TrackTable.reset`.
"""

from __future__ import annotations

import numpy as np

from .._validate import as_finite, is_whole
from ..types import Tracks

__all__ = ["TENTATIVE", "CONFIRMED", "LOST", "TrackTable", "Tracks"]

TENTATIVE, CONFIRMED, LOST = 0, 1, 2


def time_slack(time: float) -> float:
    """A few units of the rounding of times near ``time`` (seconds): the margin a duration
    measured between two frames' times is compared with (:meth:`TrackTable.stale`, coasting's
    ``coast_after``), so that a duration of exactly a setting counts the same wherever in the
    sequence it falls."""
    return 16 * float(np.spacing(max(1.0, abs(time))))


def nearest_whole(x: float) -> int:
    """``x`` to the nearest whole number, a half up, with :func:`time_slack`'s margin for the
    rounding of the product that gave it: a duration in frames or steps (0.3 s at 25
    frames/s is 7.5 frames, 8; 0.2 s at 12.5 is 2.5, 3), as coasting rounds its
    ``coast_time`` (Python's ``round`` takes a half to the even number: 2.5 to 2, 7.5 to 8).

    >>> nearest_whole(2.5), nearest_whole(0.3 * 25), nearest_whole(2.4999)
    (3, 8, 2)
    """
    return int(np.floor(x + 0.5 + time_slack(x)))


def _check_lost(time: float, max_lost: float) -> None:
    """A ValueError unless ``max_lost`` is a number >= 0 (inf: kept for good) and ``time``
    finite (NaN kept every lost track for good, without a word)."""
    if not (max_lost >= 0 and np.isfinite(time)):
        raise ValueError(f"max_lost must be a number >= 0 (seconds) and time finite; got "
                         f"max_lost={max_lost}, time={time}")


class TrackTable:
    """Tracks as columns: ``mean (K, n)``, ``cov (K, *cov_shape)`` (default ``(n, n)``), ``ids``,
    ``state``, ``hits`` (updates in a row), ``streak`` (the length of the last run of updates
    in a row, kept while the track is lost), ``first_time`` and ``last_time`` (of the first
    and the last update), ``found`` (the share of its recent frames the track was updated
    in), ``classes`` and ``scores``.

    The trackers correct the rows of ``mean`` and ``cov`` themselves; the table adds tracks
    (:meth:`add`), runs the lifecycle after each frame (:meth:`manage`, see the module) and
    drops rows (:meth:`keep`).

    Parameters
    ----------
    n : int
        State size.
    cov_shape : tuple of int, optional
        Shape of one track's covariance; default ``(n, n)`` (the box tracker keeps ``(4, 3)``,
        per-axis covariances, :mod:`vistrack.filters.axes`).
    window : float
        Seconds: the time constant of ``found``'s weights (> 0).

    Attributes
    ----------
    mean : (K, n) ndarray
        The tracks' states.
    cov : (K, \\*cov_shape) ndarray
        Their covariances.
    ids : (K,) int64 ndarray
        Identities, integers from 1.
    state : (K,) int8 ndarray
        :data:`TENTATIVE`, :data:`CONFIRMED` or :data:`LOST`.
    hits : (K,) int64 ndarray
        Updates in a row, up to the last frame (0 after a miss).
    streak : (K,) int64 ndarray
        The length of the last run of updates in a row, kept while the track is lost.
    first_time, last_time : (K,) float ndarray
        Time of the first and of the last update (seconds; the package's trackers count
        it from the frame before their first, so that it keeps its digits at any frame
        number: frame ``f`` of a run from frame 1 at ``f / frame_rate``).
    found : (K,) float ndarray
        The share of its recent frames the track was updated in: the mean of its updates (1)
        and misses (0), each frame weighing the time since the frame before it (or since
        the track's start, if it started later), decayed by
        ``exp(-age / window)``, as a running mean in continuous time (1 when it starts).
    classes : (K,) int64 ndarray
        Class of each track.
    scores : (K,) float ndarray
        Score of the detection each track was last updated with (as the tracker sets it).
    next_id : int
        The identity the next track gets.

    Examples
    --------
    Two tentative tracks; the first is updated in the next frame and confirmed, the second
    missed and deleted:

    >>> t = TrackTable(2)
    >>> t.add(np.array([[0.0, 0.0], [5.0, 5.0]]), np.tile(np.eye(2), (2, 1, 1)), 0.0,
    ...       np.zeros(2, np.int64), np.array([0.9, 0.8]), confirmed=False)
    >>> t.manage(np.array([True, False]), 0.1, confirm_hits=2, max_lost=1.0)
    array([ True, False])
    >>> t.ids.tolist(), t.state.tolist() == [CONFIRMED], t.hits.tolist()
    ([1], True, [2])
    """

    def __init__(self, n: int, cov_shape: tuple[int, ...] | None = None, *,
                 window: float = 1 / 3):
        if not 0 < window < np.inf:
            raise ValueError(f"window must be > 0 and finite (seconds); got {window!r}")
        self.n, self.window = n, float(window)
        self.cov_shape = (n, n) if cov_shape is None else tuple(cov_shape)
        self.reset()

    def reset(self) -> None:
        """Drop every track; identities start again from 1.

        Examples
        --------
        >>> t = TrackTable(2)
        >>> t.add(np.zeros((1, 2)), np.eye(2)[None], 0.0, np.zeros(1, np.int64), np.ones(1),
        ...       confirmed=True)
        >>> t.reset()
        >>> len(t), t.next_id
        (0, 1)
        """
        n = self.n
        self.mean, self.cov = np.zeros((0, n)), np.zeros((0,) + self.cov_shape)
        self.ids = np.zeros(0, np.int64)
        self.state = np.zeros(0, np.int8)
        self.hits = np.zeros(0, np.int64)
        self.streak = np.zeros(0, np.int64)
        self.first_time, self.last_time = np.zeros(0), np.zeros(0)
        self.found = np.zeros(0)
        self.classes = np.zeros(0, np.int64)
        self.scores = np.zeros(0)
        self.next_id = 1
        self._time: float | None = None  # of the last advance

    def __len__(self) -> int:
        return int(self.ids.shape[0])

    def add(self, mean: np.ndarray, cov: np.ndarray, time: float, classes: np.ndarray,
            scores: np.ndarray, confirmed: bool) -> None:
        """Add new tracks, with the next identities, one hit, ``found`` 1, and ``time`` as
        their first and last update.

        Parameters
        ----------
        mean : (k, n) ndarray
            Their states.
        cov : (k, \\*cov_shape) ndarray
            Their covariances.
        time : float
            The time of the frame they start in (seconds).
        classes : (k,) int ndarray
            Their classes.
        scores : (k,) ndarray
            The scores of the detections they start from.
        confirmed : bool
            Start them confirmed (in a sequence's first frame) rather than tentative.

        Examples
        --------
        >>> t = TrackTable(2)
        >>> t.add(np.zeros((2, 2)), np.zeros((2, 2, 2)), 0.0, np.zeros(2, np.int64),
        ...       np.ones(2), confirmed=True)
        >>> t.ids.tolist(), t.state.tolist() == [CONFIRMED, CONFIRMED], t.next_id
        ([1, 2], True, 3)
        """
        k = len(mean)
        # (a NaN time kept a track lost for good, its found NaN)
        time = as_finite(time, "time", what="number of seconds")
        for name, column in (("cov", cov), ("classes", classes), ("scores", scores)):
            if len(column) != k:  # one row per track in every column
                raise ValueError(f"{name} must have one row for each of the {k} tracks' "
                                 f"mean; got {len(column)}")
        for name, column in (("classes", classes), ("scores", scores)):
            # (scores of shape (1, 1) failed in numpy's words after the columns before it had
            # grown: the table's columns no longer had one row per track)
            if np.ndim(column) != 1:
                raise ValueError(f"{name} must be of shape ({k},), one value per track; got "
                                 f"shape {np.shape(column)}")
        # each row as the table's (numpy's concatenate named neither), and classes whole:
        # float classes turned the column to float for every later track
        for name, column, shape in (("mean", mean, (self.n,)), ("cov", cov, self.cov_shape)):
            if np.shape(column)[1:] != shape:
                raise ValueError(f"{name} must have rows of shape {shape}; got "
                                 f"{np.shape(column)[1:]}")
        if k and not np.issubdtype(np.asarray(classes).dtype, np.integer):
            raise ValueError(f"classes must be integers; got {np.asarray(classes).dtype}")
        if not k:  # (an empty float column, numpy's default, turned the classes to float)
            return
        self.mean = np.concatenate([self.mean, mean])
        self.cov = np.concatenate([self.cov, cov])
        self.ids = np.concatenate([self.ids, np.arange(self.next_id, self.next_id + k)])
        self.next_id += k
        self.state = np.concatenate([self.state, np.full(k, CONFIRMED if confirmed else TENTATIVE,
                                                         np.int8)])
        self.hits = np.concatenate([self.hits, np.ones(k, np.int64)])
        self.streak = np.concatenate([self.streak, np.ones(k, np.int64)])
        self.first_time = np.concatenate([self.first_time, np.full(k, float(time))])
        self.last_time = np.concatenate([self.last_time, np.full(k, float(time))])
        self.found = np.concatenate([self.found, np.ones(k)])
        self.classes = np.concatenate([self.classes, classes])
        self.scores = np.concatenate([self.scores, scores])

    def keep(self, mask: np.ndarray) -> None:
        """Keep only some rows of every column.

        Parameters
        ----------
        mask : (K,) bool ndarray or int ndarray
            The rows to keep (a mask, or their indices).

        Examples
        --------
        >>> t = TrackTable(1)
        >>> t.add(np.arange(3.0)[:, None], np.ones((3, 1, 1)), 0.0, np.zeros(3, np.int64),
        ...       np.ones(3), confirmed=False)
        >>> t.keep(np.array([True, False, True]))
        >>> t.ids.tolist(), t.mean.ravel().tolist()
        ([1, 3], [0.0, 2.0])
        """
        rows = np.asarray(mask)
        if rows.size == 0 and rows.dtype.kind == "f":  # ([]: no row, as numpy took it)
            rows = rows.astype(np.int64)
        if rows.dtype != np.bool_ and len(np.unique(np.arange(len(self.ids))[rows])) != rows.size:
            # (a row kept twice gave two tracks of one identity, which is never reused; -1
            # and the last row are one row)
            raise ValueError(f"mask's indices must each be given once; got {rows.tolist()}")
        for name in ("mean", "cov", "ids", "state", "hits", "streak", "first_time",
                     "last_time", "found", "classes", "scores"):
            setattr(self, name, getattr(self, name)[rows])

    def _updated(self, updated: np.ndarray) -> np.ndarray:
        """``updated`` checked: a bool mask of one entry per track (indices were taken as a
        mask, ``~`` of integers is not the complement, and one entry broadcast to all)."""
        u = np.asarray(updated)
        if u.dtype != np.bool_ or u.shape != (len(self.ids),):
            raise ValueError(f"updated must be a bool mask of the {len(self.ids)} tracks; got "
                             f"{u.dtype} of shape {u.shape}")
        return u

    def advance(self, updated: np.ndarray, time: float, confirm_hits: int) -> None:
        """After a frame's updates: count hits, confirm and lose (the first half of
        :meth:`manage`).

        The updated tracks get a hit (the others lose their run of hits) and ``time`` as
        their last update, and ``found`` takes the frame in; a tentative track with
        ``confirm_hits`` hits in a row, or a lost track updated again, is confirmed; a
        confirmed track not updated is lost.

        Parameters
        ----------
        updated : (K,) bool ndarray
            Which tracks were updated in this frame (anything else, such as their indices,
            is a ValueError).
        time : float
            The frame's time (seconds).
        confirm_hits : int
            Updates in a row that confirm a tentative track (the one it started with counts).
        """
        updated = self._updated(updated)
        # checked before the table changes (a NaN time was taken in, and named by ended only
        # after; confirm_hits NaN kept every track tentative, 0 or -1 was 1)
        time = as_finite(time, "time", what="number of seconds")
        if self._time is not None and time < self._time:
            # (an earlier frame's time was taken: found weighed it as no time gone by, and a
            # track's last update went back)
            raise ValueError(f"time must not go back: {time} after the last frame's "
                             f"{self._time}")
        if not is_whole(confirm_hits, 1):
            raise ValueError(f"confirm_hits must be a whole number >= 1; got {confirm_hits!r}")
        # found: this frame weighs the time since the last (a frame passed over, none: its
        # time goes to the next one stepped on), or since the track's start if it started
        # later (added after the last advance, or before any)
        start = self.first_time if self._time is None else np.maximum(self.first_time,
                                                                      self._time)
        keep = np.exp(-np.maximum(float(time) - start, 0.0) / self.window)
        self.found = keep * self.found + (1 - keep) * updated
        self._time = float(time)
        self.hits = np.where(updated, self.hits + 1, 0)
        self.streak = np.where(updated, self.hits, self.streak)
        self.last_time = np.where(updated, float(time), self.last_time)
        confirm = updated & (self.state != CONFIRMED) & (
            (self.hits >= confirm_hits) | (self.state == LOST))
        self.state[confirm] = CONFIRMED
        self.state[~updated & (self.state == CONFIRMED)] = LOST

    def ended(self, updated: np.ndarray, time: float, max_lost: float, *,
              miss_ends_tentative: bool = True) -> np.ndarray:
        """The tracks to delete after :meth:`advance` (the second half of :meth:`manage`).

        Parameters
        ----------
        updated : (K,) bool ndarray
            Which tracks were updated in this frame (anything else, such as their indices,
            is a ValueError).
        time : float
            The frame's time (seconds).
        max_lost : float
            Seconds a lost track is kept after its last update.
        miss_ends_tentative : bool
            Whether a tentative track not updated ends; if not (a tracker that decides by
            other evidence, such as a probability of existence), a tentative track ends as a
            lost one does, ``max_lost`` seconds after its last update.

        Returns
        -------
        (K,) bool ndarray
            The tentative tracks not updated (with ``miss_ends_tentative``), and the tracks
            lost (or tentative, without it) for more than ``max_lost`` seconds since their
            last update.
        """
        updated = self._updated(updated)
        stale = self.stale(time, max_lost)  # (with a slack for the times' rounding)
        if not miss_ends_tentative:
            return (self.state != CONFIRMED) & stale
        return (~updated & (self.state == TENTATIVE)) | ((self.state == LOST) & stale)

    def stale(self, time: float, max_lost: float) -> np.ndarray:
        """The tracks whose last update is more than ``max_lost`` seconds before ``time``
        (:meth:`ended`'s rule, whatever their state: a tracker stepped over a gap in its
        frames longer than that deletes them before it associates).

        Examples
        --------
        >>> t = TrackTable(1)
        >>> t.add(np.zeros((2, 1)), np.ones((2, 1, 1)), 0.0, np.zeros(2, np.int64),
        ...       np.ones(2), confirmed=True)
        >>> t.last_time[1] = 2.5
        >>> t.stale(3.0, max_lost=2.0).tolist(), t.stale(2.0, max_lost=2.0).tolist()
        ([True, False], [False, False])
        """
        # lost for more than max_lost, whatever the rounding of the frames' times: k frames at
        # 30 frames/s are k / 30 s, but (9 + 3) / 30 - 9 / 30 > 0.1 where (12 + 3) / 30 -
        # 12 / 30 < 0.1, so a track lost for exactly max_lost was kept or deleted by where
        # in the sequence its gap fell. The slack is a few units of the times' rounding (it
        # was 1e-9 of the time: frames numbered by milliseconds since 1970, 1.7e9 s, kept
        # lost tracks 1.7 s longer)
        _check_lost(time, max_lost)
        return np.asarray(time - self.last_time > max_lost + time_slack(time))

    def manage(self, updated: np.ndarray, time: float, confirm_hits: int,
               max_lost: float) -> np.ndarray:
        """After a frame's updates: count hits, confirm, lose (:meth:`advance`), and delete
        (:meth:`ended`). Returns the mask of the tracks kept.

        The updated tracks get a hit (the others lose their run of hits) and ``time`` as
        their last update; a tentative track with ``confirm_hits`` hits in a row, or a lost
        track updated again, is confirmed; a confirmed track not updated is lost; a tentative
        track not updated, or a track lost for more than ``max_lost`` seconds since its last
        update, is deleted.

        Parameters
        ----------
        updated : (K,) bool ndarray
            Which tracks were updated in this frame (anything else, such as their indices,
            is a ValueError).
        time : float
            The frame's time (seconds).
        confirm_hits : int
            Updates in a row that confirm a tentative track (the one it started with counts).
        max_lost : float
            Seconds a lost track is kept after its last update.

        Returns
        -------
        (K,) bool ndarray
            Which of the tracks before the call are kept (their rows, in order, are the table
            now).

        Examples
        --------
        A confirmed track missed for longer than ``max_lost`` is deleted:

        >>> t = TrackTable(1)
        >>> t.add(np.zeros((1, 1)), np.ones((1, 1, 1)), 0.0, np.zeros(1, np.int64),
        ...       np.ones(1), confirmed=True)
        >>> t.manage(np.array([False]), 0.5, 3, 1.0), t.state.tolist() == [LOST]
        (array([ True]), True)
        >>> t.manage(np.array([False]), 1.5, 3, 1.0), len(t)
        (array([False]), 0)
        """
        _check_lost(time, max_lost)  # (before the table changes)
        self.advance(updated, time, confirm_hits)
        dead = self.ended(updated, time, max_lost)
        if dead.any():
            self.keep(~dead)
        return ~dead
