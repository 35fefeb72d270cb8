r"""Offline mode: smooth finished tracks and fill their short gaps, with covariances.

An online tracker must report each frame from the past alone. With the whole sequence, each
track's states can use its future too: the Rauch-Tung-Striebel smoother
(:func:`vistrack.filters.rts_smooth`) runs backwards over the track's filtered states, with the
same per-step ``F(dt)`` and size-scaled ``Q`` the tracker used (in coordinates that follow the
camera, where the tracker compensated its motion). Then

- boxes at the frames where the track was updated are the smoothed ones;
- a gap of up to ``max_gap`` frames between two updates (the object was missed or occluded) is
  filled with the smoothed states there: an interpolation that follows the motion model and
  comes with its covariance, rather than a straight line;
- the tentative frames of a track that was later confirmed are reported too (online, a track
  cannot be reported before it is confirmed); tracks never confirmed are dropped, and so are
  the predictions after a track's last update;
- with ``min_score``, a track whose detections score less than that on average is dropped:
  with the whole track known, one that lived mostly on the second stage's low-score
  detections is more often a false one than an object.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..filters.kalman import FilterResult
from ..filters.smoothers import rts_smooth
from ..types import Gaussian, xyxy_to_xywh
from .box import BoxTracker, _to_xyxy, axes_to_full

__all__ = ["SmoothedTracks", "smooth"]


@dataclass(frozen=True)
class SmoothedTracks:
    """Rows of smoothed tracks, sorted by frame and id: ``frames``, ``ids``, ``boxes`` (``x0, y0, x1, y1``), ``scores``
    (of the detection, 0 for a filled gap), ``classes``, ``filled`` (True in a gap), and the
    smoothed state covariances ``covs (N, 8, 8)`` of ``[cx, cy, w, h, vcx, vcy, vw, vh]``."""

    frames: np.ndarray
    ids: np.ndarray
    boxes: np.ndarray
    scores: np.ndarray
    classes: np.ndarray
    filled: np.ndarray
    covs: np.ndarray

    def __len__(self) -> int:
        return int(self.frames.shape[0])

    @property
    def xywh(self) -> np.ndarray:
        return xyxy_to_xywh(self.boxes)


def _empty() -> SmoothedTracks:
    z = np.zeros(0)
    return SmoothedTracks(z.astype(int), z.astype(int), np.zeros((0, 4)), z, z.astype(int),
                          z.astype(bool), np.zeros((0, 8, 8)))


def smooth(tracker: BoxTracker, max_gap: int = 20, min_score: float = 0.0) -> SmoothedTracks:
    """Smooth the tracks a ``BoxTracker(record=True)`` has followed (see the module).

    Parameters
    ----------
    tracker
        A tracker created with ``record=True`` that has run over a sequence.
    max_gap
        The longest gap (in frames without an update) that is filled.
    min_score
        The lowest mean score of a track's detections that is kept.
    """
    if not tracker.record:
        raise ValueError("the tracker must be created with record=True for offline smoothing")
    if not tracker.history:
        return _empty()
    frame = np.concatenate([np.full(len(h[2]), h[0]) for h in tracker.history])
    dt = np.concatenate([np.full(len(h[2]), h[1]) for h in tracker.history])
    ids, mean, cov, q, upd, score, cls = (np.concatenate([h[k] for h in tracker.history])
                                          for k in range(2, 9))
    # the camera's shifts moved every track: in coordinates that follow the camera (minus
    # the shifts so far) the tracks move by F(dt) alone, as the smoother assumes
    cam = np.concatenate([np.broadcast_to(h[9], (len(h[2]), 2)) for h in tracker.history])
    mean = mean.copy()
    mean[:, :2] -= cam
    keep = np.isin(ids, np.fromiter(tracker._confirmed, dtype=np.int64))
    order = np.lexsort((frame[keep], ids[keep]))
    frame, dt, ids, mean, cov, q, upd, score, cls, cam = (
        a[keep][order] for a in (frame, dt, ids, mean, cov, q, upd, score, cls, cam))
    if len(ids) == 0:
        return _empty()
    edges = np.flatnonzero(np.diff(ids)) + 1
    out = []
    for a, b in zip(np.r_[0, edges], np.r_[edges, len(ids)]):
        u = np.flatnonzero(upd[a:b])
        if score[a:b][u].mean() < min_score:
            continue
        last = a + int(u[-1]) + 1  # nothing after the last update
        L = last - a
        P = axes_to_full(cov[a:last])
        F = np.stack([tracker.motion.F(d) for d in dt[a:last]])
        Q = q[a:last, :, None] * np.eye(8)
        res = FilterResult(mean[a:last], P, None, None, np.zeros(()),
                           Gaussian(mean[last - 1], P[-1]))
        if L > 1:
            sm = rts_smooth(res, F=F, Q=Q)
            m_s, P_s = np.asarray(sm.means), np.asarray(sm.covs)
        else:
            m_s, P_s = mean[a:last], P
        m_s = m_s.copy()
        m_s[:, :2] += cam[a:last]
        # frames to report: updates, and gaps between updates of at most max_gap frames
        f = frame[a:last]
        updated = upd[a:last]
        uf = f[updated]
        gap_len = np.diff(uf) - 1
        fill = np.zeros(L, bool)
        for g0, g1, n in zip(uf[:-1], uf[1:], gap_len):
            if 0 < n <= max_gap:
                fill |= (f > g0) & (f < g1)
        rep = updated | fill
        out.append((f[rep], ids[a:last][rep], _to_xyxy(m_s[rep, :4]),
                    np.where(updated, score[a:last], 0.0)[rep], cls[a:last][rep], fill[rep],
                    P_s[rep]))
    if not out:
        return _empty()
    cols = [np.concatenate([o[k] for o in out]) for k in range(7)]
    by_frame = np.lexsort((cols[1], cols[0]))
    return SmoothedTracks(*(c[by_frame] for c in cols))
