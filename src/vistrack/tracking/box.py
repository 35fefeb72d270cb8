r"""Box trackers: a Kalman filter per box, batched over all tracks, and IoU association.

One step, as on the slides (predict, associate, correct, manage):

1. **predict** every track with :class:`~vistrack.models.BoxMotion` over the true time since the
   last frame (a gap of frames predicts further, with more noise);
2. **associate** by IoU between predicted and detected boxes, by global nearest neighbour with
   a minimum IoU as the gate; a track only takes detections of its own class. With
   ``two_stage`` (ByteTrack's idea, Zhang et al., 2022):

   - confirmed and lost tracks take the confident detections first (score ≥ ``high``);
   - tracks still unmatched and not lost take the low-score ones (``low`` ≤ score < ``high``),
     which are often the partly occluded objects a single threshold would drop;
   - tentative tracks take what is left of the confident detections;

3. **correct** the matched tracks with their detections (one batched Kalman update);
4. **manage**: :mod:`vistrack.tracking.lifecycle`; unmatched confident detections with score
   ≥ ``new_track`` start tentative tracks.

``"sort"`` is the one-stage tracker with a single score threshold (Bewley et al., 2016),
``"bytetrack"`` the two-stage one; :data:`TRACKERS` maps names to configurations.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Any

import numpy as np

from ..association import assign, iou
from ..models.box import BoxMotion
from ..types import Detections
from .lifecycle import CONFIRMED, LOST, TENTATIVE, TrackTable, Tracks

__all__ = ["BoxTracker", "BoxTrackerConfig", "TRACKERS"]


@dataclass(frozen=True)
class BoxTrackerConfig:
    """Settings of :class:`BoxTracker` (one set for every sequence).

    Attributes
    ----------
    two_stage : bool
        Associate low-score detections in a second stage.
    high, low : float
        Score thresholds: confident detections, and the lowest score used at all.
    new_track : float
        Lowest score that starts a track.
    min_iou, min_iou_low, min_iou_tentative : float
        IoU gates of the three stages.
    fuse_score : bool
        First-stage cost ``1 - IoU * score`` (a confident detection wins a tie) instead of
        ``1 - IoU``.
    confirm_hits : int
        Updates in a row that confirm a track.
    max_lost : float
        Seconds a confirmed track may go unmatched before it is deleted.
    """

    two_stage: bool = True
    high: float = 0.6
    low: float = 0.1
    new_track: float = 0.7
    min_iou: float = 0.2
    min_iou_low: float = 0.5
    min_iou_tentative: float = 0.3
    fuse_score: bool = True
    confirm_hits: int = 2
    max_lost: float = 1.0
    assigner: str = "gnn"


TRACKERS: dict[str, BoxTrackerConfig] = {
    "bytetrack": BoxTrackerConfig(),
    "sort": BoxTrackerConfig(two_stage=False, high=0.5, low=0.5, new_track=0.5, min_iou=0.3,
                             fuse_score=False, confirm_hits=3, max_lost=0.1),
}
"""Box-tracker configurations by name (``vistrack track --tracker NAME``)."""


def _to_xyxy(m: np.ndarray) -> np.ndarray:
    c, s = m[:, 0:2], np.maximum(m[:, 2:4], 0.0)
    return np.concatenate([c - s / 2, c + s / 2], axis=1)


def _to_cxcywh(b: np.ndarray) -> np.ndarray:
    return np.concatenate([(b[:, :2] + b[:, 2:]) / 2, b[:, 2:] - b[:, :2]], axis=1)


class BoxTracker:
    """A multi-object box tracker (see the module for the algorithm).

    Parameters
    ----------
    config : BoxTrackerConfig or str
        Settings, or a name in :data:`TRACKERS`.
    motion : BoxMotion, optional
    frame_rate : float
        Frames per second, to turn frame numbers into time.
    **overrides
        Fields of the configuration to change.

    Examples
    --------
    >>> from vistrack.types import Detections
    >>> tr = BoxTracker("bytetrack")
    >>> for f in range(1, 4):
    ...     out = tr.step(Detections.from_xywh([[10 + 5 * f, 20, 30, 60]], [0.9]), frame=f)
    >>> out.ids.tolist(), out.boxes.round(1).tolist()
    ([1], [[24.0, 20.0, 54.0, 80.0]])
    """

    def __init__(self, config: BoxTrackerConfig | str = "bytetrack", *,
                 motion: BoxMotion | None = None, frame_rate: float = 30.0, **overrides: Any):
        if isinstance(config, str):
            if config not in TRACKERS:
                raise ValueError(f"tracker must be one of {sorted(TRACKERS)}; got {config!r}")
            config = TRACKERS[config]
        self.config = replace(config, **overrides) if overrides else config
        if not frame_rate > 0:
            raise ValueError(f"frame_rate must be > 0; got {frame_rate}")
        self.motion = motion or BoxMotion()
        self.frame_rate = float(frame_rate)
        self.tracks = TrackTable(8)
        self.reset()

    def reset(self) -> None:
        """Forget every track; identities start again from 1."""
        self.tracks.reset()
        self.frame: int | None = None

    def _predict(self, dt: float) -> None:
        t = self.tracks
        if len(t) == 0 or dt == 0:
            return
        F = self.motion.F(dt)
        t.mean = t.mean @ F.T
        t.cov = F @ t.cov @ F.T + self.motion.Q(t.mean[:, :4], dt)

    def _update(self, idx: np.ndarray, z: np.ndarray) -> None:
        t = self.tracks
        m, P = t.mean[idx], t.cov[idx]
        S = P[:, :4, :4] + self.motion.R(m[:, :4])
        K = np.swapaxes(np.linalg.solve(S, P[:, :4, :]), 1, 2)  # P H' S^-1 (S symmetric)
        t.mean[idx] = m + np.einsum("kij,kj->ki", K, z - m[:, :4])
        P = P - K @ S @ np.swapaxes(K, 1, 2)
        t.cov[idx] = 0.5 * (P + np.swapaxes(P, 1, 2))

    def _match(self, tracks: np.ndarray, dets: np.ndarray, boxes: np.ndarray, det_boxes: np.ndarray,
               scores: np.ndarray, classes: np.ndarray, min_iou: float,
               fuse: bool) -> tuple[np.ndarray, np.ndarray]:
        if len(tracks) == 0 or len(dets) == 0:
            return np.zeros(0, np.int64), np.zeros(0, np.int64)
        ov = iou(boxes[tracks], det_boxes[dets])
        gate = (ov >= min_iou) & (self.tracks.classes[tracks][:, None] == classes[dets][None, :])
        cost = 1.0 - (ov * scores[dets][None, :] if fuse else ov)
        r, c = assign(cost, gate, self.config.assigner)
        return tracks[r], dets[c]

    def step(self, detections: Detections, frame: int | None = None) -> Tracks:
        """Track one frame. ``frame`` (an integer, increasing; default the next one) gives the
        time since the last frame, so gaps in frame numbers are predicted over."""
        if not isinstance(detections, Detections) or detections.boxes is None:
            raise TypeError("detections must be vistrack.Detections with boxes")
        frame = (1 if self.frame is None else self.frame + 1) if frame is None else int(frame)
        if self.frame is not None and frame <= self.frame:
            raise ValueError(f"frame must increase; got {frame} after {self.frame}")
        first = self.frame is None
        dt = 0.0 if first else float(frame - self.frame)
        self.frame = frame
        time = frame / self.frame_rate
        cfg, t = self.config, self.tracks
        self._predict(dt)
        boxes = _to_xyxy(t.mean[:, :4])
        db, ds, dc = detections.boxes, detections.scores, detections.classes
        high = np.flatnonzero(ds >= cfg.high)
        low = np.flatnonzero((ds >= cfg.low) & (ds < cfg.high)) if cfg.two_stage else \
            np.zeros(0, np.int64)
        matched_t, matched_d = [], []
        # 1: confirmed and lost tracks, confident detections
        pool = np.flatnonzero(t.state != TENTATIVE)
        r, c = self._match(pool, high, boxes, db, ds, dc, cfg.min_iou, cfg.fuse_score)
        matched_t.append(r)
        matched_d.append(c)
        # 2: tracks still unmatched and not lost, low-score detections
        if cfg.two_stage:
            rest = np.setdiff1d(pool[t.state[pool] == CONFIRMED], r)
            r2, c2 = self._match(rest, low, boxes, db, ds, dc, cfg.min_iou_low, False)
            matched_t.append(r2)
            matched_d.append(c2)
        # 3: tentative tracks, the confident detections left
        left = np.setdiff1d(high, c)
        r3, c3 = self._match(np.flatnonzero(t.state == TENTATIVE), left, boxes, db, ds, dc,
                             cfg.min_iou_tentative if cfg.two_stage else cfg.min_iou, False)
        matched_t.append(r3)
        matched_d.append(c3)
        mt, md = np.concatenate(matched_t), np.concatenate(matched_d)
        if len(mt):
            self._update(mt, _to_cxcywh(db[md]))
            t.scores[mt] = ds[md]
        updated = np.zeros(len(t), bool)
        updated[mt] = True
        t.manage(updated, time, cfg.confirm_hits, cfg.max_lost)
        # new tracks from the confident detections nobody took
        new = np.setdiff1d(high, c3 if len(c3) else np.zeros(0, np.int64))
        new = np.setdiff1d(new, c)
        new = new[ds[new] >= cfg.new_track]
        if len(new):
            mean, cov = self.motion.initial(_to_cxcywh(db[new]))
            t.add(mean, cov, time, dc[new], ds[new], confirmed=first)
        out = np.flatnonzero((t.state == CONFIRMED) & (t.last_time == time))
        return Tracks(ids=t.ids[out].copy(), boxes=_to_xyxy(t.mean[out, :4]), points=None,
                      scores=t.scores[out].copy(), classes=t.classes[out].copy())
