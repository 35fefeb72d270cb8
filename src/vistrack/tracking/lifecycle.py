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

from ..types import Tracks

__all__ = ["TENTATIVE", "CONFIRMED", "LOST", "TrackTable", "Tracks"]

TENTATIVE, CONFIRMED, LOST = 0, 1, 2


class TrackTable:
    """Tracks as columns: ``mean (K, n)``, ``cov (K, *cov_shape)`` (default ``(n, n)``), ``ids``,
    ``state``, ``hits`` (updates in a row), ``streak`` (the length of the last run of updates
    in a row, kept while the track is lost), ``last_time`` (of the last update), ``classes``
    and ``scores``."""

    def __init__(self, n: int, cov_shape: tuple[int, ...] | None = None):
        self.n = n
        self.cov_shape = (n, n) if cov_shape is None else tuple(cov_shape)
        self.reset()

    def reset(self) -> None:
        n = self.n
        self.mean, self.cov = np.zeros((0, n)), np.zeros((0,) + self.cov_shape)
        self.ids = np.zeros(0, np.int64)
        self.state = np.zeros(0, np.int8)
        self.hits = np.zeros(0, np.int64)
        self.streak = np.zeros(0, np.int64)
        self.last_time = np.zeros(0)
        self.classes = np.zeros(0, np.int64)
        self.scores = np.zeros(0)
        self.next_id = 1

    def __len__(self) -> int:
        return int(self.ids.shape[0])

    def add(self, mean: np.ndarray, cov: np.ndarray, time: float, classes: np.ndarray,
            scores: np.ndarray, confirmed: bool) -> None:
        k = len(mean)
        self.mean = np.concatenate([self.mean, mean])
        self.cov = np.concatenate([self.cov, cov])
        self.ids = np.concatenate([self.ids, np.arange(self.next_id, self.next_id + k)])
        self.next_id += k
        self.state = np.concatenate([self.state, np.full(k, CONFIRMED if confirmed else TENTATIVE,
                                                         np.int8)])
        self.hits = np.concatenate([self.hits, np.ones(k, np.int64)])
        self.streak = np.concatenate([self.streak, np.ones(k, np.int64)])
        self.last_time = np.concatenate([self.last_time, np.full(k, float(time))])
        self.classes = np.concatenate([self.classes, classes])
        self.scores = np.concatenate([self.scores, scores])

    def keep(self, mask: np.ndarray) -> None:
        for name in ("mean", "cov", "ids", "state", "hits", "streak", "last_time", "classes",
                     "scores"):
            setattr(self, name, getattr(self, name)[mask])

    def advance(self, updated: np.ndarray, time: float, confirm_hits: int) -> None:
        """After a frame's updates: count hits, confirm (``confirm_hits`` updates in a row, or
        a lost track updated again), and lose the confirmed tracks not updated."""
        self.hits = np.where(updated, self.hits + 1, 0)
        self.streak = np.where(updated, self.hits, self.streak)
        self.last_time = np.where(updated, float(time), self.last_time)
        confirm = updated & (self.state != CONFIRMED) & (
            (self.hits >= confirm_hits) | (self.state == LOST))
        self.state[confirm] = CONFIRMED
        self.state[~updated & (self.state == CONFIRMED)] = LOST

    def ended(self, updated: np.ndarray, time: float, max_lost: float) -> np.ndarray:
        """The tracks to delete after :meth:`advance`: tentative ones not updated, and those
        lost for longer than ``max_lost`` seconds."""
        return (~updated & (self.state == TENTATIVE)) | (
            (self.state == LOST) & (time - self.last_time > max_lost))

    def manage(self, updated: np.ndarray, time: float, confirm_hits: int,
               max_lost: float) -> np.ndarray:
        """After a frame's updates: count hits, confirm, lose, delete (:meth:`advance`, then
        :meth:`ended`). Returns the mask of the tracks kept."""
        self.advance(updated, time, confirm_hits)
        dead = self.ended(updated, time, max_lost)
        if dead.any():
            self.keep(~dead)
        return ~dead
