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
  detections is more often a false one than an object;
- each track is followed back in time from its first update, by a Kalman filter running
  backwards from the smoothed first state, through the detections no track took: online, a
  track starts only at a detection confident enough to start one (``new_track``), and the
  same person is often detected less confidently in the frames before;
- a track that ends is joined to one that starts up to ``link_gap`` frames later when their
  boxes, each carried across the gap by its velocity, overlap the other's on average (the
  mean of the two IoUs at least ``link_iou``): online, a person who comes back where the
  lost track's prediction does not reach starts a new track while the old one is still
  kept; the gap between them is filled by a smoother bridging it, from the first track's
  last state to the second one's first box, however long (up to ``link_gap``: the overlap
  of the carried boxes is the evidence that bridges it, where a gap inside one track is
  filled up to ``max_gap`` only). A track deleted online (lost longer than ``max_lost``,
  as long as ``link_gap`` by default) is joined only where its successor was followed back
  to within ``link_gap`` of it.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from .._validate import as_finite, as_number, is_whole
from ..association import gnn_sparse, iou_pairs, paired_iou
from ..filters.axes import axes_predict, axes_to_full, axes_update, full_to_axes
from ..filters.kalman import FilterResult
from ..filters.smoothers import rts_smooth
from ..models.box import BoxMotion
from ..types import Gaussian, xyxy_to_xywh
from .box import BoxTracker, _to_cxcywh, _to_xyxy

__all__ = ["SmoothedTracks", "smooth"]


@dataclass(frozen=True)
class SmoothedTracks:
    """Rows of smoothed tracks, sorted by frame and id: ``frames``, ``ids``, ``boxes``
    (``x0, y0, x1, y1``), ``scores`` (of the detection, 0 for a filled gap), ``classes``,
    ``filled`` (True in a gap), and the smoothed state covariances ``covs (N, 8, 8)`` of
    ``[cx, cy, w, h, vcx, vcy, vw, vh]``.

    What :func:`smooth` returns; ``len()`` is the number of rows.

    Attributes
    ----------
    frames : (N,) int ndarray
        Frame of each row.
    ids : (N,) int ndarray
        Track identity of each row.
    boxes : (N, 4) ndarray
        Smoothed boxes ``x0, y0, x1, y1``.
    scores : (N,) ndarray
        Score of the detection the track was updated with in that frame; 0 in a filled gap.
    classes : (N,) int ndarray
        Class of each row's track.
    filled : (N,) bool ndarray
        True where the row fills a gap (no detection).
    covs : (N, 8, 8) ndarray
        Smoothed covariances of the state ``[cx, cy, w, h, vcx, vcy, vw, vh]``.

    Examples
    --------
    >>> from vistrack.tracking import BoxTracker
    >>> from vistrack.types import Detections
    >>> tr = BoxTracker(record=True, frame_rate=10)
    >>> for f in range(1, 6):
    ...     _ = tr.step(f, Detections.from_xywh([[10 + 5 * f, 20, 30, 60]], [0.9]))
    >>> rows = smooth(tr)
    >>> len(rows), rows.frames.tolist(), rows.covs.shape
    (5, [1, 2, 3, 4, 5], (5, 8, 8))
    """

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
        """Boxes as ``x, y, w, h`` ``(N, 4)`` (top-left corner and size).

        Examples
        --------
        >>> z = np.zeros(1)
        >>> SmoothedTracks(z.astype(int), z.astype(int), np.array([[10.0, 20, 40, 80]]), z,
        ...                z.astype(int), z.astype(bool), np.zeros((1, 8, 8))).xywh.tolist()
        [[10.0, 20.0, 30.0, 60.0]]
        """
        return xyxy_to_xywh(self.boxes)


def _empty() -> SmoothedTracks:
    z = np.zeros(0)
    return SmoothedTracks(z.astype(int), z.astype(int), np.zeros((0, 4)), z, z.astype(int),
                          z.astype(bool), np.zeros((0, 8, 8)))


_DUPLICATE_IOU = 0.5  # a detection overlapping a reported box this much is that box's


@dataclass
class _Track:
    """One smoothed track's rows (image coordinates) and its end states (camera coordinates)."""

    id: int
    cls: int
    frames: np.ndarray
    boxes: np.ndarray
    scores: np.ndarray
    filled: np.ndarray
    covs: np.ndarray
    first: tuple  # (frame, mean (8,), cov (8, 8)) at the first update
    last: tuple  # the same at the last update


def smooth(tracker: BoxTracker, max_gap: int | None = None, min_score: float | None = None, *,
           extend_iou: float | None = 0.5, link_gap: int | None = None, link_iou: float = 0.3,
           link_window: int | None = None) -> SmoothedTracks:
    """Smooth the tracks a ``BoxTracker(record=True)`` has followed (see the module).

    Parameters
    ----------
    tracker : BoxTracker
        A tracker created with ``record=True`` that has run over a sequence.
    max_gap : int, optional
        The longest gap (in frames without an update) inside a track that is filled (the gap
        between two joined tracks is filled whatever its length, up to ``link_gap``). The
        frames filled are
        those the tracker was stepped on: a frame never stepped (a loop over the frames of
        a detections file skips those where nothing was detected) has no state and is not
        written, so step every frame, with no detections where there are none, as
        ``vistrack track`` does.
    min_score : float, optional
        The lowest mean score of a track's detections that is kept (the scores as the
        tracker's thresholds see them, :meth:`BoxTracker.confidence`); None keeps every
        track, whatever its scores (a raw score may be negative).
    extend_iou : float or None
        Follow each track back from its first update through the detections no track took
        (any score down to the tracker's ``low``), while one overlaps its backward prediction
        by at least this IoU; None: not at all.
    link_gap, link_iou, link_window : int, float, int
        Join a track that ends to one that starts at most ``link_gap`` frames later (0: never)
        when their boxes, carried across the gap by the velocities of their last and first
        ``link_window`` detected frames, overlap the other's by ``link_iou`` on average; the
        gap between them is filled from the smoother.

        ``max_gap``, ``link_gap`` and ``link_window`` left out (None) are the offline mode's
        defaults (:class:`vistrack.config.OfflineConfig`, in seconds) at the tracker's
        ``frame_rate``: 30, 60 and 9 frames at 30 frames/s.

    Returns
    -------
    SmoothedTracks
        The rows of the tracks ever confirmed, sorted by frame and id: the smoothed boxes at
        their updates, the gaps filled, and the frames added by following back and joining
        (empty when nothing was tracked). A joined track keeps the identity of the first
        one.

    Raises
    ------
    ValueError
        If the tracker was not created with ``record=True``, ``max_gap``, ``link_gap`` or
        ``link_window`` is not a whole number of frames >= 0 (>= 1 for ``link_window``),
        ``link_iou`` is not in (0, 1] (or [0, 1] with ``link_gap`` 0, no joining) or
        ``extend_iou`` not in [0, 1], or ``min_score`` is given and not finite.
    TypeError
        If ``tracker`` is not a :class:`BoxTracker`, or a setting that is a number is given
        as something else (a string, or None for ``link_iou``).

    Notes
    -----
    ``max_gap``, ``link_gap`` and ``link_window`` count frames. The offline mode's settings
    (:class:`vistrack.config.OfflineConfig`, ``vistrack track --offline``) give them in
    seconds, turned into frames with the sequence's frame rate
    (:meth:`vistrack.config.OfflineConfig.frames`).

    Examples
    --------
    A box moving 5 pixels a frame, missed in frames 5 and 6: online, frame 5 is its
    prediction (coasting) and frame 6 is not reported; offline, both are filled from the
    smoothed motion:

    >>> from vistrack.types import Detections
    >>> tr = BoxTracker(record=True, frame_rate=10)
    >>> for f in range(1, 11):
    ...     boxes = [] if f in (5, 6) else [[10 + 5 * f, 20, 30, 60]]
    ...     _ = tr.step(f, Detections.from_xywh(np.reshape(boxes, (-1, 4)), [0.9] * len(boxes)))
    >>> rows = smooth(tr)
    >>> rows.frames.tolist()
    [1, 2, 3, 4, 5, 6, 7, 8, 9, 10]
    >>> rows.xywh[3:7, 0].round(1).tolist(), rows.filled[3:7].tolist()
    ([30.0, 35.0, 40.0, 45.0], [False, True, True, False])
    """
    if not isinstance(tracker, BoxTracker):  # (None failed in an attribute, naming nothing)
        raise TypeError(f"tracker must be a BoxTracker(record=True); got {tracker!r}")
    if not tracker.record:
        raise ValueError("the tracker must be created with record=True for offline smoothing")
    from ..config import OfflineConfig  # (vistrack.config imports the trackers)

    default = OfflineConfig().frames(tracker.frame_rate)
    max_gap = default["max_gap"] if max_gap is None else max_gap
    link_gap = default["link_gap"] if link_gap is None else link_gap
    link_window = default["link_window"] if link_window is None else link_window
    for name, v, least in (("max_gap", max_gap, 0), ("link_gap", link_gap, 0),
                           ("link_window", link_window, 1)):
        # (checked before int(): NaN and inf failed there, naming nothing)
        if not is_whole(v, least):
            raise ValueError(f"{name} must be a whole number of frames >= {least}; got {v!r}")
    # (3.0 frames, or a Fraction, was used as an index below)
    max_gap, link_gap, link_window = int(max_gap), int(link_gap), int(link_window)
    # an IoU (NaN fails this too; a string was a TypeError in a comparison). link_iou 0 took
    # any two tracks within link_gap as one, however far apart (extend_iou 0 takes only
    # overlapping boxes: its pairs need some overlap), and None failed where a pair was met
    link_iou = _iou(link_iou, "link_iou", zero=link_gap == 0)  # (0: any two tracks joined)
    if extend_iou is not None:
        extend_iou = _iou(extend_iou, "extend_iou", zero=True)
    if min_score is not None:
        min_score = as_finite(min_score, "min_score")
    if not tracker.history:
        return _empty()
    cam = {h[0]: h[9] for h in tracker.history}
    tracks = _smooth_tracks(tracker, max_gap, min_score)
    if not tracks:
        return _empty()
    if extend_iou is not None:
        _extend_back(tracker, tracks, cam, extend_iou)
    if link_gap > 0:
        tracks = _link(tracker, tracks, cam, link_gap, link_iou, link_window)
    n = [len(t.frames) for t in tracks]
    cols = [np.concatenate([t.frames for t in tracks]),
            np.repeat([t.id for t in tracks], n), np.concatenate([t.boxes for t in tracks]),
            np.concatenate([t.scores for t in tracks]), np.repeat([t.cls for t in tracks], n),
            np.concatenate([t.filled for t in tracks]), np.concatenate([t.covs for t in tracks])]
    by_frame = np.lexsort((cols[1], cols[0]))
    return SmoothedTracks(*(c[by_frame] for c in cols))


def _iou(value: object, name: str, zero: bool) -> float:
    """``value`` as an IoU in [0, 1] (``zero``) or (0, 1], or an error naming ``name``."""
    v = as_number(value, name)
    if not (0.0 < v <= 1.0 or (zero and v == 0.0)):  # (NaN fails both)
        raise ValueError(f"{name} must be an IoU in {'[0' if zero else '(0'}, 1]; got {value!r}")
    return v


def _predict(mean: np.ndarray, cov: np.ndarray, dt: float,
             motion: BoxMotion) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Box states ``(K, 8)`` and per-axis covariances ``(K, 4, 3)`` predicted over ``dt`` frames
    (negative: backwards in time), with the motion's noise at the predicted boxes, as the
    tracker predicts: ``(mean, cov, q)``, ``q (K, 8)`` the diagonal of the noise added."""
    q = motion.Q_diag(mean[:, :4] + dt * mean[:, 4:], abs(dt))
    return (*axes_predict(mean, cov, dt, q), q)


def _correct(mean: np.ndarray, cov: np.ndarray, z: np.ndarray,
             motion: BoxMotion) -> tuple[np.ndarray, np.ndarray]:
    """Predicted box states and covariances corrected with boxes ``[cx, cy, w, h] (K, 4)``,
    with the motion's detection noise at the predicted boxes, as the tracker corrects."""
    return axes_update(mean, cov, z, motion.R_diag(mean[:, :4]))


def _smooth_tracks(tracker: BoxTracker, max_gap: int, min_score: float | None
                   ) -> list[_Track]:
    """RTS-smooth every confirmed track and fill its gaps of up to ``max_gap`` frames."""
    frame = np.concatenate([np.full(len(h[2]), h[0]) for h in tracker.history])
    dt = np.concatenate([np.full(len(h[2]), h[1]) for h in tracker.history])
    ids, mean, cov, q, upd, score, cls = (np.concatenate([h[k] for h in tracker.history])
                                          for k in range(2, 9))
    # the camera's shifts moved the tracks: minus the shifts each track was moved by so far,
    # it moves by F(dt) alone, as the smoother assumes; `glob` is the camera's own offset,
    # the coordinates the later steps (following back, joining) work in
    cam = np.concatenate([h[11] for h in tracker.history])
    glob = np.concatenate([np.broadcast_to(h[9], (len(h[2]), 2)) for h in tracker.history])
    mean = mean.copy()
    mean[:, :2] -= cam
    keep = np.isin(ids, np.fromiter(tracker._confirmed, dtype=np.int64))
    order = np.lexsort((frame[keep], ids[keep]))
    frame, dt, ids, mean, cov, q, upd, score, cls, cam, glob = (
        a[keep][order] for a in (frame, dt, ids, mean, cov, q, upd, score, cls, cam, glob))
    if len(ids) == 0:
        return []
    edges = np.flatnonzero(np.diff(ids)) + 1
    # F(dt) once per distinct step, not once per step (nearly every step is one frame)
    steps, step_of = np.unique(dt, return_inverse=True)
    F_steps = np.stack([tracker.motion.F(d) for d in steps])
    out = []
    best = -np.inf  # the highest mean confidence of a track dropped
    for a, b in zip(np.r_[0, edges], np.r_[edges, len(ids)]):
        u = np.flatnonzero(upd[a:b])
        if min_score is not None:
            mean_conf = float(tracker.confidence(score[a:b][u], cls[a:b][u]).mean())
            if mean_conf < min_score:
                best = max(best, mean_conf)
                continue
        last = a + int(u[-1]) + 1  # nothing after the last update
        L = last - a
        P = axes_to_full(cov[a:last])
        F = F_steps[step_of[a:last]]
        Q = q[a:last, :, None] * np.eye(8)
        res = FilterResult(mean[a:last], P, None, None, np.zeros(()),
                           Gaussian(mean[last - 1], P[-1]))
        if L > 1:
            sm = rts_smooth(res, F=F, Q=Q)
            m_s, P_s = np.asarray(sm.means), np.asarray(sm.covs)
        else:
            m_s, P_s = mean[a:last], P
        f = frame[a:last]
        updated = upd[a:last]
        first_u = int(u[0])
        ends = []
        for k in (first_u, L - 1):  # in the camera's coordinates
            m = m_s[k].copy()
            m[:2] += cam[a + k] - glob[a + k]
            ends.append((int(f[k]), m, P_s[k]))
        m_s = m_s.copy()
        m_s[:, :2] += cam[a:last]
        # frames to report: updates, and gaps between updates of at most max_gap frames
        uf = f[updated]
        gap_len = np.diff(uf) - 1
        fill = np.zeros(L, bool)
        for g0, g1, n in zip(uf[:-1], uf[1:], gap_len):
            if 0 < n <= max_gap:
                fill |= (f > g0) & (f < g1)
        rep = updated | fill
        out.append(_Track(int(ids[a]), int(cls[a]), f[rep], _to_xyxy(m_s[rep, :4]),
                          np.where(updated, score[a:last], 0.0)[rep], fill[rep], P_s[rep],
                          *ends))
    if not out and min_score is not None:
        # a run that writes nothing says why (0 boxes of 0 tracks gave no reason)
        warnings.warn(f"min_score {min_score:g} (min_track_score under [offline] in a "
                      f"--config file, --min-track-score) drops every one of the "
                      f"{len(edges) + 1} confirmed tracks, the highest mean confidence of a "
                      f"track's detections being {best:.3g}: the results hold no rows",
                      UserWarning, stacklevel=3)
    return out


def _extend_back(tracker: BoxTracker, tracks: list[_Track], cam: dict, min_iou: float) -> None:
    """Follow every track back in time from its first update, in place: a backward Kalman
    filter from the smoothed first state, updated at each earlier frame by the free detection
    overlapping its prediction most (global nearest neighbour over the tracks being followed),
    until a frame has none. Free: of the track's class, scoring at least the tracker's
    ``low``, and not overlapping a box of its class already reported in that frame (another
    class's track takes none of its detections, so in a file of several classes each is
    followed back as in a file of its own)."""
    motion, low = tracker.motion, tracker.config.low
    frames = list(cam)  # the recorded frames, in order
    dets = {h[0]: h[10] for h in tracker.history}
    starts: dict[int, list[int]] = {}
    reported: dict[int, list[np.ndarray]] = {}
    reported_cls: dict[int, list[int]] = {}
    for k, t in enumerate(tracks):
        starts.setdefault(t.first[0], []).append(k)
        for f, b in zip(t.frames.tolist(), t.boxes):
            reported.setdefault(f, []).append(b)
            reported_cls.setdefault(f, []).append(t.cls)
    active = np.zeros(0, int)
    mean, cov = np.zeros((0, 8)), np.zeros((0, 4, 3))
    added: dict[int, list] = {}
    for i in range(len(frames) - 1, -1, -1):
        f = frames[i]
        if len(active):
            mean, cov, _ = _predict(mean, cov, f - frames[i + 1], motion)
            pred = mean[:, :4].copy()
            pred[:, :2] += cam[f]
            db, ds, dc, conf = dets[f]
            free = conf >= low
            if f in reported and free.any():
                r, c, _ = iou_pairs(db, np.array(reported[f]), _DUPLICATE_IOU)
                free[r[dc[r] == np.array(reported_cls[f])[c]]] = False
            rows, cols, ov = iou_pairs(_to_xyxy(pred), db, min_iou)
            ok = free[cols] & (dc[cols] == np.array([tracks[k].cls for k in active])[rows])
            r, c = gnn_sparse(rows[ok], cols[ok], 1.0 - ov[ok], (len(active), len(db)))
            if len(r):
                z = _to_cxcywh(db[c])
                z[:, :2] -= cam[f]
                mean[r], cov[r] = _correct(mean[r], cov[r], z, motion)
                box = mean[r, :4].copy()
                box[:, :2] += cam[f]
                for k, b, sc, P in zip(active[r], _to_xyxy(box), ds[c], axes_to_full(cov[r])):
                    added.setdefault(int(k), []).append((f, b, sc, P))
            active, mean, cov = active[r], mean[r], cov[r]
        new = starts.get(f, [])
        if new:
            active = np.r_[active, new].astype(int)
            mean = np.concatenate([mean, [tracks[k].first[1] for k in new]])
            cov = np.concatenate([cov, full_to_axes(np.stack([tracks[k].first[2] for k in new]))])
    for k, newest_first in added.items():
        t = tracks[k]
        rec = newest_first[::-1]  # in time order
        t.frames = np.r_[[r[0] for r in rec], t.frames]
        t.boxes = np.concatenate([[r[1] for r in rec], t.boxes])
        t.scores = np.r_[[r[2] for r in rec], t.scores]
        t.filled = np.r_[np.zeros(len(rec), bool), t.filled]
        t.covs = np.concatenate([[r[3] for r in rec], t.covs])


def _carried_ends(t: _Track, cam: dict, window: int) -> tuple[np.ndarray, ...]:
    """A track's first and last detected boxes in camera coordinates (``cx, cy, w, h``) and
    the velocities of their centres over the first and last ``window`` detected frames."""
    f = t.frames[~t.filled]
    c = _to_cxcywh(t.boxes[~t.filled])
    c[:, :2] -= np.array([cam[x] for x in f.tolist()])
    n = min(window, len(f) - 1)
    v0, v1 = np.zeros(2), np.zeros(2)
    if n > 0:
        v0 = (c[n, :2] - c[0, :2]) / (f[n] - f[0])
        v1 = (c[-1, :2] - c[-1 - n, :2]) / (f[-1] - f[-1 - n])
    return c[0], c[-1], v0, v1, f[0], f[-1]


def _link(tracker: BoxTracker, tracks: list[_Track], cam: dict, link_gap: int,
          min_iou: float, window: int) -> list[_Track]:
    """Join tracks that end to tracks that start up to ``link_gap`` frames later (global
    nearest neighbour on the mean IoU of the boxes carried across the gap) and fill the gaps
    from a smoother bridging them."""
    ends = [_carried_ends(t, cam, window) for t in tracks]
    c0, c1, v0, v1, f0, f1 = (np.array([e[k] for e in ends]) for k in range(6))
    cls = np.array([t.cls for t in tracks])
    # the pairs (a, b) where b starts 1 to link_gap frames after a's last, of a's class and
    # scoring min_iou or more, in the order of a then b: each block of tracks a against the
    # tracks sorted by their first frame, about 260,000 pairs at a time (every track
    # against every other, tracks x tracks arrays, took 3.4 GB for 10,000 tracks, and all
    # the pairs at once 0.6 GB for 3,000 tracks born 20 a frame)
    if len(tracks):  # a gap past the recorded span joins as the span does (f1 + 2**63 - 1
        # wrapped in int64: numpy's "repeats may not contain negative values")
        link_gap = min(link_gap, max(0, int(f0.max()) - int(f1.min())))
    order = np.argsort(f0, kind="stable")
    lo = np.searchsorted(f0[order], f1, "right")
    counts = np.searchsorted(f0[order], f1 + link_gap, "right") - lo
    kept: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []
    start = 0
    while start < len(tracks):
        stop = start + max(1, int(np.searchsorted(np.cumsum(counts[start:]), 1 << 18,
                                                  "right")))
        k = counts[start:stop]
        a = np.repeat(np.arange(start, stop), k)
        b = order[np.arange(k.sum()) - np.repeat(np.cumsum(k) - k - lo[start:stop], k)]
        same = cls[a] == cls[b]
        a, b = a[same], b[same]
        pairs = np.lexsort((b, a))
        a, b = a[pairs], b[pairs]
        d = (f0[b] - f1[a])[:, None]  # frames from a's last to b's first
        fwd = c1[a].copy()
        fwd[:, :2] += v1[a] * d  # a's last box carried forward to b's first frame
        back = c0[b].copy()
        back[:, :2] -= v0[b] * d  # b's first box carried back to a's last frame
        score = (paired_iou(_to_xyxy(fwd), _to_xyxy(c0[b]))
                 + paired_iou(_to_xyxy(back), _to_xyxy(c1[a]))) / 2
        ok = score >= min_iou
        kept.append((a[ok], b[ok], score[ok]))
        start = stop
    if not kept or not sum(len(x[0]) for x in kept):
        return tracks
    a, b, score = (np.concatenate([x[k] for x in kept]) for k in range(3))
    r, c = gnn_sparse(a, b, 1.0 - score, (len(tracks), len(tracks)))
    nxt = dict(zip(r.tolist(), c.tolist()))
    frames = np.fromiter(cam, dtype=np.int64)  # the recorded frames, in order
    heads = set(range(len(tracks))) - set(nxt.values())
    out = []
    for h in sorted(heads):
        chain = [h]
        while chain[-1] in nxt:
            chain.append(nxt[chain[-1]])
        parts = [tracks[chain[0]]]
        for p, q in zip(chain[:-1], chain[1:]):
            parts.append(_bridge(tracker, tracks[p], tracks[q], frames, cam))
            parts.append(tracks[q])
        t = parts[0]
        fr, bx, sc, fi, cv = (np.concatenate([getattr(x, k) for x in parts])
                              for k in ("frames", "boxes", "scores", "filled", "covs"))
        out.append(_Track(t.id, t.cls, fr, bx, sc, fi, cv, t.first, tracks[chain[-1]].last))
    return out


def _bridge(tracker: BoxTracker, a: _Track, b: _Track, frames: np.ndarray,
            cam: dict) -> _Track:
    """The rows between track ``a``'s last update and track ``b``'s first box: a Kalman filter
    from ``a``'s smoothed last state, predicted across the gap and corrected by ``b``'s first
    box, smoothed back (RTS)."""
    motion = tracker.motion
    fl, m, P = a.last
    f_b = int(b.frames[0])
    gf = frames[(frames > fl) & (frames <= f_b)]
    z = _to_cxcywh(b.boxes[:1])
    z[:, :2] -= cam[f_b]
    mean, cov = m[None].copy(), full_to_axes(P[None])
    means, covs, Fs, Qs = [mean[0]], [cov[0]], [np.eye(8)], [np.zeros((8, 8))]
    prev = fl
    for f in gf.tolist():
        mean, cov, q = _predict(mean, cov, f - prev, motion)
        if f == f_b:
            mean, cov = _correct(mean, cov, z, motion)
        means.append(mean[0].copy())
        covs.append(cov[0].copy())
        Fs.append(motion.F(f - prev))
        Qs.append(np.diag(q[0]))
        prev = f
    full_covs = axes_to_full(np.array(covs))
    res = FilterResult(np.array(means), full_covs, None, None, np.zeros(()),
                       Gaussian(means[-1], full_covs[-1]))
    sm = rts_smooth(res, F=np.array(Fs), Q=np.array(Qs))
    m_s, P_s = np.asarray(sm.means)[1:-1].copy(), np.asarray(sm.covs)[1:-1]
    g = gf[:-1]
    m_s[:, :2] += np.array([cam[x] for x in g.tolist()]).reshape(-1, 2)
    return _Track(a.id, a.cls, g, _to_xyxy(m_s[:, :4]), np.zeros(len(g)),
                  np.ones(len(g), bool), P_s, a.first, a.last)
