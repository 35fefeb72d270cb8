r"""Box trackers: a Kalman filter per box, batched over all tracks, and IoU association.

One step, as on the slides (predict, associate, correct, manage):

0. **scores**: with ``scores="calibrated"`` (the default) every threshold below applies to
   the detection's calibrated confidence in ``[0, 1]``, not to its raw score: how nearly
   detections of that score persist from frame to frame, and lie on chains of detections
   that last, as the detector's most confident ones do, learnt online from the frames seen
   so far, or fitted to the whole file beforehand (:mod:`vistrack.tracking.calibration`);
   each class of detection from its own detections, so that a detector scoring two classes
   on scales of their own has each tracked as in a file of its own.
   It depends on the order of the scores only, so one setting serves a detector
   thresholded at 0.5, one whose raw scores run from −1 to 16, and any strictly increasing
   transform of either, identically;
1. **predict** every track with :class:`~vistrack.models.BoxMotion` over the true time since the
   last frame (a gap of frames predicts further, with more noise; the noise per frame follows
   the frame rate, :meth:`~vistrack.models.BoxMotion.at_rate`). With diagonal noise the
   8-state filter is four independent 2-state filters, one per box value and its rate, so
   each track keeps a 2×2 covariance per axis, ``[pp, pv, vv]``, and predict and update are
   a few elementwise operations over all tracks: :mod:`vistrack.filters.axes` (tested
   against the full 8-state Kalman filter), with the motion's process noise
   (:meth:`~vistrack.models.BoxMotion.Q_diag`) and detection noise
   (:meth:`~vistrack.models.BoxMotion.R_diag`) at each track's predicted box;
   with ``camera_motion``, the predictions then follow the camera: where the camera turns or
   shakes, every box in the image moves by the same amount, which no track's own velocity
   foresees. Confirmed tracks are matched to confident detections at IoU ≥
   ``camera_min_iou`` (global nearest neighbour), and the median of the matched detections'
   centres minus the predicted ones is the frame's shift, when at least
   ``camera_min_matches`` pairs give it and it is more than ``camera_sig`` standard errors
   from zero (``1.4826 MAD / √n`` per axis), so most of a still camera's noise is left alone.
   This is BoT-SORT's camera-motion compensation (Aharon et al., 2022) estimated from the
   tracks themselves instead of from the image. One shift does not describe every scene: from
   a car driving forward, or among cars passing it, boxes at different depths move
   differently, and the median of a few tracks is wrong for the rest. So each track follows
   the shift only where its moved prediction overlaps its best-overlapping detection at
   least as much as its own prediction does (tracks near no detection follow it), and is
   associated at that prediction alone; its velocity still learns the motion seen in the
   image, so that where the next frame gives no shift (too few pairs), a camera that keeps
   turning is followed by the tracks' own predictions. A jump larger than about a third of a
   box leaves too few overlapping pairs and goes unseen;
2. **associate** by IoU between predicted and detected boxes, by global nearest neighbour with
   a minimum IoU as the gate, which is also the price of a pair left unassigned
   (:func:`~vistrack.association.gnn` with a ``limit``): the assignment takes the pairs of
   most total similarity above the gate, not the most pairs, so that where one person is
   missed beside another who is detected, the missed person's track does not take the
   other's detection while the other's track takes a stranger's; a track only takes
   detections of its own class. With
   ``two_stage`` (ByteTrack's idea, Zhang et al., 2022):

   - confirmed and lost tracks take the confident detections first (confidence ≥ ``high``);
   - confirmed tracks still unmatched (not lost ones, nor tentative) take the less
     confident ones (``low`` ≤ confidence < ``high``), which are often the partly occluded
     objects a single threshold would drop;
   - tentative tracks take what is left of the confident detections;
   - a tentative track still unmatched (updated once, with ``confirm_hits`` 2, so with no
     velocity yet) takes a detection left over that could start a track itself (confidence
     ≥ ``high`` and ≥ ``new_track``) within its prediction's gate: the squared Mahalanobis
     distance of the box (centre and size) from the predicted one, with the prediction's
     covariance and the detection noise, under ``tentative_gate`` (the 99 % point of
     chi-square with 4 degrees of freedom), where the pair is unambiguous (no other such
     detection in the track's gate, no other such track's gate holds the detection).
     The overlap misses an object that moves more than its size between frames, as at a
     low frame rate, and the prediction of a track with one update stands still; its
     covariance, though, holds the velocity's prior uncertainty over the time between the
     frames, so the gate widens as the frame rate falls and stays inside the overlap's reach
     at a high one. Without it, such an object starts a new tentative track at every frame
     and none is ever confirmed;

3. **correct** the matched tracks with their detections (one batched Kalman update);
4. **manage**: :mod:`vistrack.tracking.lifecycle`; unmatched confident detections with
   confidence ≥ ``new_track`` start tentative tracks;
5. **report** the confirmed tracks updated in this frame, and, with ``coast_time``, a track
   lost for at most that long (to the nearest frame), at its prediction, while that lies
   inside the image, where it was followed for ``coast_after`` seconds or more and found in
   at least ``coast_rate`` of its recent frames
   (:attr:`~vistrack.tracking.lifecycle.TrackTable.found`, over ``coast_window`` seconds):
   a detector misses a person it has found for a while for a moment (occlusion, blur) far
   more often than the person vanishes, and a half-hidden person's misses come now and
   then, not in one run.

``"sort"`` is the one-stage tracker with a single threshold (Bewley et al., 2016),
``"bytetrack"`` the two-stage one; :data:`TRACKERS` maps names to configurations.
"""

from __future__ import annotations

from dataclasses import dataclass, fields, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from .._jit import njit
from .._prebuilt import kernel
from .._registry import Registry
from .._validate import check_in_pixels, is_number
from ..association import ASSIGNERS, assign, iou_pairs, non_maximum
from ..association.assign import _gnn_sparse, gnn_pairs, gnn_pairs_limited
from ..association.costs import iou_pairs_same_class
from ..filters.axes import (
    _predict_inplace,
    _predicted_values,
    _update_inplace,
    axes_predict,
    axes_to_full,
    axes_update,
)
from ..models.box import MAX_SECONDS, BoxMotion
from ..types import Detections, Frame, Tracks, _whole_numbers
from .base import FixedSettings, frame_index
from .calibration import ScoreCalibration, ScoreCalibrator
from .lifecycle import CONFIRMED, LOST, TENTATIVE, TrackTable, time_slack

if TYPE_CHECKING:
    from numpy.typing import ArrayLike

__all__ = ["BoxTracker", "BoxTrackerConfig", "TRACKERS"]



@dataclass(frozen=True)
class BoxTrackerConfig:
    """Settings of :class:`BoxTracker` (one set for every sequence).

    Attributes
    ----------
    two_stage : bool
        Associate low-score detections in a second stage.
    scores : {"calibrated", "raw"}
        What the thresholds ``high``, ``low`` and ``new_track`` (and ``fuse_score``) apply to:
        the calibrated confidence of each detection's score, in ``[0, 1]``, learnt from the
        detections themselves (:mod:`vistrack.tracking.calibration`: how nearly detections
        of that score persist and last as the detector's best ones do), so that one
        setting serves detectors whose scores live on any scale; or the raw scores.
    high, low : float
        Thresholds: confident detections, and the lowest used at all.
    new_track : float
        Lowest that starts a track (a detection must also reach ``high``: the new tracks
        come from the confident detections no track took).
    min_iou, min_iou_low, min_iou_tentative : float
        IoU gates of the three stages. The gate is also what a track and a detection left
        unassigned cost: a stage takes the pairs whose similarities above the gate add up
        most, not the most pairs.
    tentative_gate : float
        The gate of the last stage, on the squared Mahalanobis distance from a tentative track
        still unmatched of a detection left over that could start a track itself, over the
        box's centre and size (13.28: chi-square's 99 % point with 4 degrees of freedom; 0:
        no such stage; see the module).
    fuse_score : bool
        The first stage's similarity is ``IoU * score`` (cost ``1 -`` it; its gate
        ``min_iou`` applies to it too, as in ByteTrack): a confident detection wins a tie,
        and a less confident one must overlap more to be taken.
    confirm_hits : int
        Updates in a row that confirm a track.
    max_lost : float
        Seconds a confirmed track may go unmatched before it is deleted. It is deleted after
        the association of the first frame past them, so it can still take a detection there
        (over a gap in frame numbers, tracks lost that long at the frame before are deleted
        first).
    assigner : {"gnn", "greedy", "nn"}
        How each stage assigns its gated pairs (:data:`~vistrack.association.ASSIGNERS`):
        global nearest neighbour (the default, and the only one the compiled tracker runs),
        the best pair first, or each track its nearest detection (one detection can then
        update two tracks). The gate's price of a pair left unassigned is GNN's alone.
    camera_motion : bool
        Move the predictions by the shift of the image between frames, estimated from the
        confidently matched tracks, track by track where it fits the detections (see the
        module).
    camera_min_iou, camera_min_matches, camera_sig : float, int, float
        The IoU of the pairs that estimate the shift, how many pairs it needs, and how many
        standard errors from zero it must be.
    coast_time, coast_after, coast_rate, coast_window : float
        Report a lost track's prediction for up to ``coast_time`` seconds, rounded to the
        nearest frame, a half up (0: never; 0.1 s is 3 frames at 30 or 25 frames/s, 2 at 15,
        1 at 10, 7 or 5), if it had been followed for at least ``coast_after`` seconds
        (from its first update to its last) and found in at least ``coast_rate`` (in
        [0, 1]) of its recent frames, weighed over ``coast_window`` seconds (> 0;
        :attr:`~vistrack.tracking.lifecycle.TrackTable.found`).
    calibration_iou, calibration_top, calibration_prior : float
        With calibrated scores: the IoU at which a detection continues one of the previous
        frame, the fraction of the outcomes, by score, whose rate is full confidence, and
        how many outcomes weigh as much as the rank prior
        (:class:`~vistrack.tracking.calibration.ScoreCalibrator`).
    calibration_top_min : int
        The least number of outcomes the full confidence's rate is taken over.
    calibration_window : int
        How many outcomes the online calibration holds, the latest, so that it follows a
        scene that changes (0: all of them; the offline mode fits every outcome).
    calibration_cap_sigma : float
        How many standard errors a bin of outcomes below the top third may lie above the fit
        of the bins scored above it before it is taken down to that fit (the calibration's
        bound on outcomes that contradict the detector's ranking; ``inf``: none, the plain
        isotonic fit; :meth:`~vistrack.tracking.calibration.ScoreCalibration.fit`).
    chain_span, chain_gap : float
        With calibrated scores: seconds. A detection also counts as an object's if it lies on
        a chain of detections that spans ``chain_span`` or more, linked across gaps of up to
        ``chain_gap`` (0: frame-to-frame persistence alone; see
        :mod:`vistrack.tracking.calibration`).
    nms_iou : float
        Non-maximum suppression of each frame's detections before anything else: a detection
        overlapping a more confident one of its class at IoU ``nms_iou`` or more is dropped,
        for a detector that applies none, whose duplicates of one object would each start a
        track of their own (1, the default: none dropped; detectors apply their own; 0:
        any that overlaps a more confident one at all).
    """

    two_stage: bool = True
    scores: str = "calibrated"
    high: float = 0.6
    low: float = 0.3
    new_track: float = 0.7
    min_iou: float = 0.2
    min_iou_low: float = 0.3
    min_iou_tentative: float = 0.3
    tentative_gate: float = 13.28
    fuse_score: bool = True
    confirm_hits: int = 2
    max_lost: float = 2.0
    assigner: str = "gnn"
    camera_motion: bool = True
    camera_min_iou: float = 0.3
    camera_min_matches: int = 3
    camera_sig: float = 2.0
    coast_time: float = 0.1
    coast_after: float = 1.0
    coast_rate: float = 0.5
    coast_window: float = 1 / 3
    calibration_iou: float = 0.3
    calibration_top: float = 0.05
    calibration_prior: float = 0.0
    calibration_top_min: int = 20
    calibration_window: int = 20000
    calibration_cap_sigma: float = 5.0
    chain_span: float = 1.0
    chain_gap: float = 0.2
    nms_iou: float = 1.0

    def __post_init__(self) -> None:
        def bad(name: str, must: str) -> ValueError:
            return ValueError(f"{name} must be {must}; got {getattr(self, name)!r}")

        kinds = {f.name: f.type for f in fields(self)}
        # numbers are numpy's too (np.float32(0.5) was refused as "not a number"), each
        # kept as Python's own type
        for name, kind in kinds.items():
            v = getattr(self, name)
            if kind == "bool":
                if not isinstance(v, (bool, np.bool_)):
                    raise bad(name, "True or False")
                object.__setattr__(self, name, bool(v))
            if kind == "int":
                if (not is_number(v) or not np.isfinite(v) or not float(v).is_integer()
                        or not -2**63 <= v < 2**63):  # the compiled tracker's int64
                    raise bad(name, "an integer")
                object.__setattr__(self, name, int(v))
            if kind == "float":
                if not is_number(v) or np.isnan(v):
                    raise bad(name, "a number")
                object.__setattr__(self, name, float(v))
        if self.scores not in ("calibrated", "raw"):
            raise bad("scores", "'calibrated' or 'raw'")
        if self.assigner not in ASSIGNERS:
            raise bad("assigner", f"one of {sorted(ASSIGNERS)}")
        unit = ("high", "low", "new_track") if self.scores == "calibrated" else ()
        for name in ("high", "low", "new_track"):
            # (raw scores: -inf and inf were taken from a file where --high refuses them)
            if not np.isfinite(getattr(self, name)):
                raise bad(name, "a finite number")
        for name in unit + ("min_iou", "min_iou_low", "min_iou_tentative", "camera_min_iou",
                            "nms_iou", "coast_rate"):
            if not 0 <= getattr(self, name) <= 1:
                raise bad(name, "in [0, 1]" + (" (a calibrated confidence)" if name in unit
                                               else ""))
        if self.two_stage and self.low > self.high:
            raise ValueError(f"low must be at most high with two_stage (the second stage takes "
                             f"the detections between them); got low {self.low!r} above high "
                             f"{self.high!r}")
        for name in ("calibration_iou", "calibration_top"):
            if not 0 < getattr(self, name) <= 1:
                raise bad(name, "in (0, 1]")
        for name in ("camera_sig", "calibration_prior", "tentative_gate"):
            if not 0 <= getattr(self, name) < np.inf:
                raise bad(name, "a finite number >= 0")
        for name in ("max_lost", "coast_time", "coast_after", "chain_span", "chain_gap"):
            # seconds, counted in frames: 1e308 overflowed there, with a traceback
            if not 0 <= getattr(self, name) <= MAX_SECONDS:
                raise bad(name, f"a number of seconds from 0 to {MAX_SECONDS:g}")
        for name in ("confirm_hits", "camera_min_matches", "calibration_top_min"):
            if getattr(self, name) < 1:
                raise bad(name, "an integer >= 1")
        if self.calibration_window < 0:
            raise bad("calibration_window", "an integer >= 0 (0: every outcome)")
        if not self.calibration_cap_sigma > 0:
            raise bad("calibration_cap_sigma", "> 0 (inf: no bound)")
        if not 0 < self.coast_window <= MAX_SECONDS:
            raise bad("coast_window", f"a number of seconds > 0 and at most {MAX_SECONDS:g}")

    def calibration_options(self, frame_rate: float) -> dict[str, Any]:
        """The score calibration's settings at ``frame_rate`` frames a second, as
        :class:`~vistrack.tracking.calibration.ScoreCalibrator` (online) and
        :meth:`~vistrack.tracking.calibration.ScoreCalibration.from_frames` (offline) take
        them."""
        return dict(link_iou=self.calibration_iou, top=self.calibration_top,
                    top_min=self.calibration_top_min, cap_sigma=self.calibration_cap_sigma,
                    frame_rate=frame_rate, chain_span=self.chain_span, chain_gap=self.chain_gap)


TRACKERS: Registry[BoxTrackerConfig] = Registry("box-tracker preset", {
    "bytetrack": BoxTrackerConfig(),
    "sort": BoxTrackerConfig(two_stage=False, high=0.5, low=0.5, new_track=0.5, min_iou=0.3,
                             fuse_score=False, confirm_hits=3, max_lost=0.1,
                             camera_motion=False, coast_time=0.0, tentative_gate=0.0),
})
"""Box-tracker configurations by name (``vistrack track --tracker NAME``)."""


def _noise(mean: np.ndarray, dt: float,
           motion: BoxMotion) -> tuple[np.ndarray, np.ndarray]:
    """The motion's noise at the boxes that states ``(K, 8)`` predict to over ``dt`` frames:
    ``(q, r)``, the process noise ``q (K, 8)`` over ``|dt|`` and the detections' noise
    ``r (K, 4)`` (the diagonals of ``Q`` and ``R``). The tracker corrects with ``r`` of the
    prediction before the camera's shift, which moves centres only (the same ``r`` for
    :class:`~vistrack.models.BoxMotion`, whose noise scales with the size)."""
    boxes = _predicted_values(mean, dt)  # mean[:, :4] + dt * mean[:, 4:]
    return motion.Q_diag(boxes, abs(dt)), motion.R_diag(boxes)


def _contiguous(a: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(a, dtype=np.float64)


def _writable(d: Detections) -> Detections:
    """``d``, or a copy of it whose arrays are writable where one of ``d``'s is read-only
    (``np.load`` with ``mmap_mode``, ``setflags(write=False)``, pandas' views): the kernels
    are compiled, at install, for writable arrays, and numba would compile each of them again
    for a read-only one on first use."""
    if all(a is None or a.flags.writeable for a in (d.boxes, d.scores, d.classes)):
        return d
    return replace(d, **{name: np.array(a) for name in ("boxes", "scores", "classes")
                         if (a := getattr(d, name)) is not None})


def _to_xyxy(m: np.ndarray) -> np.ndarray:
    c, s = m[:, 0:2], np.maximum(m[:, 2:4], 0.0)
    return np.concatenate([c - s / 2, c + s / 2], axis=1)


def _to_cxcywh(b: np.ndarray) -> np.ndarray:
    return np.concatenate([(b[:, :2] + b[:, 2:]) / 2, b[:, 2:] - b[:, :2]], axis=1)


@njit(cache=True)
def _camera_shift(mean, db, r, c, min_matches, sig):
    # the median of detection centre minus predicted centre over the pairs (r, c), per axis;
    # zeros with fewer than min_matches pairs, or where neither axis' median is more than
    # sig standard errors (1.4826 MAD / sqrt(n)) from zero
    n = r.shape[0]
    out = np.zeros(2)
    if n < max(min_matches, 1):
        return out
    res = np.empty(n)
    significant = False
    for a in range(2):
        for k in range(n):
            res[k] = (db[c[k], a] + db[c[k], a + 2]) / 2 - mean[r[k], a]
        m = np.median(res)
        out[a] = m
        if abs(m) > sig * 1.4826 * np.median(np.abs(res - m)) / np.sqrt(n):
            significant = True
    if not significant:
        out[:] = 0.0
    return out


@njit(cache=True)
def _choose_prediction(K, D, rows, cols, ov, rows1, cols1, ov1):
    # each track keeps the candidate pairs of the prediction, its own (rows, cols, ov) or the
    # one moved with the camera (rows1, ...), that overlaps its best detection more (moved on
    # a tie); returns the pairs kept, sorted by (row, col), and which tracks keep their own
    best_own, best_moved = np.zeros(K), np.zeros(K)
    for p in range(rows.shape[0]):
        best_own[rows[p]] = max(best_own[rows[p]], ov[p])
    for p in range(rows1.shape[0]):
        best_moved[rows1[p]] = max(best_moved[rows1[p]], ov1[p])
    own = best_own > best_moved
    k0, k1 = own[rows], ~own[rows1]
    r = np.concatenate((rows1[k1], rows[k0]))
    c = np.concatenate((cols1[k1], cols[k0]))
    o = np.concatenate((ov1[k1], ov[k0]))
    order = np.argsort(r * D + c, kind="mergesort")
    return r[order], c[order], o[order], own


@njit(cache=True)
def _pred_boxes(mean):
    K = mean.shape[0]
    pred = np.empty((K, 4))
    for i in range(K):
        for a in range(2):
            h = max(mean[i, 2 + a], 0.0) / 2
            pred[i, a], pred[i, 2 + a] = mean[i, a] - h, mean[i, a] + h
    return pred


_STAGE_STATES = np.array([[CONFIRMED, LOST], [CONFIRMED, CONFIRMED], [TENTATIVE, TENTATIVE]],
                         dtype=np.int8)
"""The track states each association stage takes: confirmed and lost, confirmed, tentative."""


@njit(cache=True)
def _stage(rows, cols, ov, state, stage_state, det_ok, min_iou, fuse, ds, match, used, T, D):
    # one association stage over the candidate pairs whose track (state in stage_state, not
    # matched) and detection (det_ok, not used) are free and whose similarity, IoU (x score
    # if fuse), is at least min_iou; cost 1 - similarity, and leaving a pair unassigned
    # costs 1 - min_iou (gnn_pairs_limited)
    keep = np.empty(rows.shape[0], np.int64)
    n = 0
    for p in range(rows.shape[0]):
        i, j = rows[p], cols[p]
        if (match[i] < 0 and not used[j] and det_ok[j]
                and (ov[p] * ds[j] if fuse else ov[p]) >= min_iou
                and (state[i] == stage_state[0] or state[i] == stage_state[1])):
            keep[n] = p
            n += 1
    keep = keep[:n]
    # each pair's cost less the cost of leaving it unassigned
    cost = (1.0 - (ov[keep] * ds[cols[keep]] if fuse else ov[keep])) - (1.0 - min_iou)
    r, c = gnn_pairs_limited(rows[keep], cols[keep], cost, T, D)
    for q in range(r.shape[0]):
        match[r[q]] = c[q]
        used[c[q]] = True


_ASSOCIATION = np.dtype([
    ("two_stage", np.bool_), ("high", np.float64), ("low", np.float64),
    ("min_iou", np.float64), ("min_iou_low", np.float64), ("min_iou_tentative", np.float64),
    ("fuse_score", np.bool_), ("camera_motion", np.bool_), ("camera_min_iou", np.float64),
    ("camera_min_matches", np.int64), ("camera_sig", np.float64)], align=True)
"""The settings the compiled association reads, fields of :class:`BoxTrackerConfig` by name
and type, as one record (numba takes an array of records at the cost of an array, a tuple of
eleven values at several times that)."""


def _association(c: BoxTrackerConfig) -> np.ndarray:
    """The settings of ``c`` the compiled association reads: an array of one
    :data:`_ASSOCIATION` record."""
    return np.array([tuple(getattr(c, name) for name in _ASSOCIATION.fields or ())],
                    dtype=_ASSOCIATION)


@kernel
@njit(cache=True)
def _associate(mean, cov, state, tclass, db, ds, dc, dt, q, r, settings, shift):
    """Predict, associate and correct in one compiled call: :meth:`BoxTracker.step` with
    ``gnn``. The filter's steps are :mod:`vistrack.filters.axes`' compiled ones, with the
    motion's noise ``q (K, 8)`` and ``r (K, 4)`` at the predicted boxes (:func:`_noise`);
    between them come the camera's shift and the three association stages (see the module),
    with the settings ``settings[0]`` (:func:`_association`). Updates ``mean`` and ``cov`` in
    place and writes the camera's shift into ``shift``; returns each track's detection (-1:
    none), which detections were used, which tracks were moved with the camera, and False if
    a box is not finite."""
    K, D = mean.shape[0], db.shape[0]
    cfg = settings[0]
    if dt != 0.0:
        _predict_inplace(mean, cov, dt, q)
    match = np.full(K, -1)
    used = np.zeros(D, np.bool_)
    moved = np.zeros(K, np.bool_)
    if K == 0 or D == 0:
        return match, used, moved, True
    high_d = ds >= cfg.high
    # the lowest IoU any stage, or the camera's estimate, looks at
    gate = min(cfg.min_iou, cfg.min_iou_low, cfg.min_iou_tentative,
               cfg.camera_min_iou if cfg.camera_motion else 1.0)
    rows, cols, ov, ok = iou_pairs_same_class(_pred_boxes(mean), tclass, db, dc, gate)
    if not ok:
        return match, used, moved, False
    if cfg.camera_motion:
        # the camera's shift from confirmed tracks and confident detections (see the module)
        sel = (ov >= cfg.camera_min_iou) & high_d[cols] & (state[rows] == CONFIRMED)
        pr, pc = gnn_pairs(rows[sel], cols[sel], 1.0 - ov[sel], K, D)
        est = _camera_shift(mean, db, pr, pc, cfg.camera_min_matches, cfg.camera_sig)
        # element by element: a slice assignment costs numba a compilation of its error path
        shift[0], shift[1] = est[0], est[1]
        if shift[0] != 0.0 or shift[1] != 0.0:
            for i in range(K):
                mean[i, 0] += shift[0]
                mean[i, 1] += shift[1]
            r1, c1, ov1, ok = iou_pairs_same_class(_pred_boxes(mean), tclass, db, dc, gate)
            # each track follows the camera, or not, as its best detection says
            rows, cols, ov, own = _choose_prediction(K, D, rows, cols, ov, r1, c1, ov1)
            for i in range(K):
                if own[i]:
                    mean[i, 0] -= shift[0]
                    mean[i, 1] -= shift[1]
                else:
                    moved[i] = True
    low_d = (ds >= cfg.low) & ~high_d if cfg.two_stage else np.zeros(D, np.bool_)
    # 1: confirmed and lost tracks, confident detections; 2: confirmed tracks left,
    # low-score detections; 3: tentative tracks, confident detections left
    # the stages' track states come from one array and "no fuse" from a variable, so that the
    # three calls share one signature (constants would be typed as literals: one compilation
    # per call)
    no_fuse = cfg.fuse_score and not cfg.fuse_score
    _stage(rows, cols, ov, state, _STAGE_STATES[0], high_d, cfg.min_iou, cfg.fuse_score, ds,
           match, used, K, D)
    if cfg.two_stage:
        _stage(rows, cols, ov, state, _STAGE_STATES[1], low_d, cfg.min_iou_low, no_fuse, ds,
               match, used, K, D)
    _stage(rows, cols, ov, state, _STAGE_STATES[2], high_d,
           cfg.min_iou_tentative if cfg.two_stage else cfg.min_iou, no_fuse, ds, match, used, K,
           D)
    updated = np.flatnonzero(match >= 0)
    M = updated.shape[0]
    z, rm, offset = np.empty((M, 4)), np.empty((M, 4)), np.zeros((M, 4))
    for k in range(M):
        i = updated[k]
        j = match[i]
        for a in range(2):  # the detection's [cx, cy, w, h]
            z[k, a] = (db[j, a] + db[j, a + 2]) / 2
            z[k, 2 + a] = db[j, 2 + a] - db[j, a]
            # the velocity learns the motion seen in the image, the camera's included
            offset[k, a] = shift[a] if moved[i] else 0.0
        for a in range(4):
            rm[k, a] = r[i, a]
    _update_inplace(mean, cov, updated, z, rm, offset)
    return match, used, moved, True


_NOTHING = Detections(boxes=np.zeros((0, 4)))
"""A frame without detections, shown to a class's calibration where the frame holds none of
that class (never changed)."""


def _kinds(classes: np.ndarray) -> list:
    """The distinct classes, increasing (one compare where there is one: the usual file)."""
    if not len(classes):
        return []
    if (classes == classes[0]).all():
        return [classes[0].item()]
    return np.unique(classes).tolist()


def _only_map(maps: dict[int, ScoreCalibration], give: str) -> ScoreCalibration:
    """The one class's calibration among ``maps`` (no class seen: :func:`_nothing_seen`'s), or
    a ValueError asking for the argument ``give`` that names the classes."""
    if len(maps) > 1:
        raise ValueError(f"each of the classes {sorted(maps)} has a calibration of its own: "
                         f"give {give}")
    return next(iter(maps.values())) if maps else _nothing_seen()


def _nothing_seen() -> ScoreCalibration:
    """The calibration of a class with no detection seen: nothing to tell apart, confidence 1
    for every score (as a :class:`ScoreCalibrator` gives before it has seen any)."""
    return ScoreCalibration([0.0], [1.0])


class BoxTracker(FixedSettings):
    """A multi-object box tracker (see the module for the algorithm).

    Parameters
    ----------
    config : BoxTrackerConfig or str
        Settings, or a name in :data:`TRACKERS`.
    motion : BoxMotion, optional
        The motion and its noise (default ``BoxMotion()``); a subclass, or any object with
        the same ``at_rate``, ``initial``, ``Q_diag``, ``R_diag`` (and ``F``, for the offline
        mode), changes the noise of the filter in both the compiled and the numpy steps.
    frame_rate : float
        Frames per second, to turn frame numbers into time.
    image_size : (width, height), optional
        A coasting track is reported only while its box lies inside the image (without it,
        wherever it is).
    record : bool
        Keep every frame's filtered states and detections, for
        :func:`vistrack.tracking.offline.smooth` (the offline mode); memory then grows with the
        sequence.
    calibration : ScoreCalibration or dict, optional
        With calibrated scores (``config.scores``), a fixed map from scores to confidences,
        such as one fitted to the whole sequence beforehand
        (:meth:`~vistrack.tracking.calibration.ScoreCalibration.from_frames`, the offline
        mode), for every class; or a dict of such maps by detection class, each for its
        class. Without one for a class, the tracker learns that class's map online from the
        frames it has seen. Each class has a map of its own: a detector of people and cars
        may score each on a scale of its own (PointRCNN's cars from −1 to 16, its
        pedestrians mostly below 1), and tracking a file of both is then tracking each alone.
    compiled : bool
        Predict, associate and correct in one compiled call when the configuration allows it
        (``assigner="gnn"``); the results equal the numpy steps', which run otherwise.
    **overrides
        Fields of the configuration to change.

    Attributes
    ----------
    camera_shift : (2,) float
        The shift of the image in pixels (x, y) estimated at the last frame, zeros where none
        was applied (``camera_motion``).

    Examples
    --------
    >>> from vistrack.types import Detections
    >>> tr = BoxTracker("bytetrack")
    >>> for f in range(1, 4):
    ...     out = tr.step(f, Detections.from_xywh([[10 + 5 * f, 20, 30, 60]], [0.9]))
    >>> out.ids.tolist(), out.boxes.round(1).tolist()
    ([1], [[24.0, 20.0, 54.0, 80.0]])
    """

    _fixed = frozenset({"config", "motion", "frame_rate", "calibration", "image_size",
                        "compiled"})

    def __init__(self, config: BoxTrackerConfig | str = "bytetrack", *,
                 motion: BoxMotion | None = None, frame_rate: float = 30.0,
                 record: bool = False, compiled: bool = True,
                 image_size: tuple[int, int] | None = None,
                 calibration: ScoreCalibration | None = None, **overrides: Any):
        if isinstance(config, str):
            if config not in TRACKERS:
                raise ValueError(f"tracker must be one of {sorted(TRACKERS)}; got {config!r}")
            config = TRACKERS[config]
        if not isinstance(config, BoxTrackerConfig):  # (a dict or None: an AttributeError)
            raise TypeError(f"config must be a BoxTrackerConfig or a preset's name, one of "
                            f"{sorted(TRACKERS)}; got {type(config).__name__}")
        unknown = sorted(set(overrides) - {f.name for f in fields(BoxTrackerConfig)})
        if unknown:  # (the dataclass said "__init__() got an unexpected keyword argument")
            import difflib

            near = difflib.get_close_matches(unknown[0], [f.name for f in
                                                          fields(BoxTrackerConfig)], 1)
            raise TypeError(f"{unknown[0]} is no setting of BoxTrackerConfig"
                            + (f" (did you mean {near[0]!r}?)" if near else ""))
        self.config = replace(config, **overrides) if overrides else config
        if calibration is not None and not isinstance(calibration, ScoreCalibration) and not (
                isinstance(calibration, dict) and all(
                    isinstance(v, ScoreCalibration) for v in calibration.values())):
            raise TypeError(f"calibration must be a ScoreCalibration, or a dict of them by "
                            f"class; got {type(calibration).__name__}")
        if isinstance(calibration, dict):
            bad = [k for k in calibration if isinstance(k, (bool, np.bool_))
                   or not isinstance(k, (int, np.integer))]
            if bad:  # ("2", as --print-config writes the classes, was never looked up)
                raise TypeError(f"calibration's keys must be detection classes, integers; "
                                f"got {bad[0]!r}")
            calibration = {int(k): v for k, v in calibration.items()}
        if calibration is not None and self.config.scores != "calibrated":
            raise ValueError("calibration goes with scores='calibrated'")
        self.calibration = calibration
        if isinstance(frame_rate, (bool, str)) or not isinstance(frame_rate, (int, float,
                                                                            np.number)):
            raise TypeError(f"frame_rate must be a number; got {type(frame_rate).__name__} "
                            f"{frame_rate!r}")
        if not frame_rate > 0:
            raise ValueError(f"frame_rate must be > 0; got {frame_rate}")
        lacks = [a for a in ("at_rate", "initial", "Q_diag", "R_diag")
                 if motion is not None and not callable(getattr(motion, a, None))]
        if lacks:  # what the docstring asks of a motion that is not a BoxMotion
            raise TypeError(f"motion must be a vistrack.models.BoxMotion, or have its "
                            f"{', '.join(lacks)}; got {type(motion).__name__} {motion!r}")
        # the motion's noise at this tracker's frame rate (models/box.py)
        self.motion = (motion or BoxMotion()).at_rate(frame_rate)
        self.frame_rate = float(frame_rate)
        if image_size is not None and (np.shape(image_size) != (2,) or not all(
                0 < float(v) < np.inf for v in image_size)):  # NaN: no track ever coasted
            raise ValueError(f"image_size must be (width, height), finite and > 0; got "
                             f"{image_size}")
        self.image_size = None if image_size is None else tuple(float(v) for v in image_size)
        self.tracks = TrackTable(8, cov_shape=(4, 3), window=self.config.coast_window)
        self.record = bool(record)
        self.compiled = bool(compiled) and self.config.assigner == "gnn"
        self._association = _association(self.config)
        self.reset()
        self._made = True  # the settings are fixed from here (FixedSettings)

    def reset(self) -> None:
        """Forget every track (and what the online score calibration learnt); identities
        start again from 1."""
        # the online calibration: a learner for each class without a fixed map, made when
        # the class is first seen, in that order; the first class's is made now (and shown
        # the frames before it came, none of which held it), as the one calibrator was
        self.calibrators: dict[int, ScoreCalibrator] = {}
        self._observed = 0  # frames shown to the calibrators (a new one is shown as many)
        self._unclaimed = (self._new_calibrator() if self.config.scores == "calibrated"
                           and not isinstance(self.calibration, ScoreCalibration) else None)
        self.tracks.reset()
        self.frame: int | None = None
        # the frame before the first stepped: times count from it, exact at any frame number
        # (from frame 1e15 on, frame / frame_rate rounded by more than time_slack's margin,
        # and coasting and max_lost counted other frames); frames from 1 keep frame /
        # frame_rate, bit for bit
        self._origin = 0
        self._passed = 0  # frames passed over since the last step (pass_over)
        self.history: list = []
        self._q, self._r = np.zeros((0, 8)), np.zeros((0, 4))
        self._confirmed: set = set()
        self.camera_shift = np.zeros(2)
        self._camera_offset = np.zeros(2)  # the shifts so far, summed (for the smoother)
        self._offsets = np.zeros((0, 2))  # the shifts each track was moved by, summed
        self._moved = np.zeros(0, bool)

    def _predict(self, dt: float) -> None:
        """The motion's noise at the predicted boxes (:func:`_noise`) into ``_q`` and ``_r``,
        and, in numpy, the prediction (the compiled call predicts with ``_q``)."""
        t = self.tracks
        if len(t) == 0 or dt == 0:
            self._q, self._r = np.zeros((len(t), 8)), np.zeros((len(t), 4))
            return
        self._q, self._r = _noise(t.mean, dt, self.motion)
        if not self.compiled:
            t.mean, t.cov = axes_predict(t.mean, t.cov, dt, self._q)

    def _update(self, idx: np.ndarray, z: np.ndarray) -> None:
        """The numpy correction of the tracks ``idx`` with boxes ``z [cx, cy, w, h]``."""
        t = self.tracks
        offset = np.zeros(z.shape)
        offset[:, :2] = self._moved[idx, None] * self.camera_shift
        t.mean[idx], t.cov[idx] = axes_update(t.mean[idx], t.cov[idx], z, self._r[idx], offset)

    def _learns(self, k: int) -> bool:
        """Whether class ``k``'s map is learnt online (calibrated scores, no fixed map)."""
        cal = self.calibration
        return self.config.scores == "calibrated" and (
            cal is None or (isinstance(cal, dict) and k not in cal))

    def _new_calibrator(self) -> ScoreCalibrator:
        c = self.config
        cal = ScoreCalibrator(prior=c.calibration_prior, window=c.calibration_window or None,
                              **c.calibration_options(self.frame_rate))
        for _ in range(self._observed):  # the frames before the class was first seen held
            cal.observe(_NOTHING)       # none of it, as in a file of that class alone
        return cal

    def _observe(self, detections: Detections, step: int = 1) -> None:
        """Show one frame, ``step`` frames after the one shown before, to the online
        calibration: each class's detections to its own learner (the frame as it is where it
        holds one class, or none)."""
        if self.config.scores != "calibrated" or isinstance(self.calibration, ScoreCalibration):
            return
        dc = detections.classes
        assert dc is not None  # set by Detections.__post_init__
        if len(self.calibrators) == 1 and self.calibration is None:
            (k, learner), = self.calibrators.items()
            if not len(dc) or (dc == k).all():  # the one class seen so far (the usual file)
                learner.observe(detections, step)
                self._observed += 1
                return
        seen = _kinds(dc)
        for k in seen:
            if k not in self.calibrators and self._learns(k):
                if self._unclaimed is not None:  # shown every frame so far, all without k
                    self.calibrators[k], self._unclaimed = self._unclaimed, None
                else:
                    self.calibrators[k] = self._new_calibrator()
        for k, cal in self.calibrators.items():
            if seen == [k]:
                cal.observe(detections, step)
            elif k in seen:
                cal.observe(detections[dc == k], step)
            else:  # (one empty frame for every class the frame holds none of)
                cal.observe(_NOTHING, step)
        if self._unclaimed is not None:
            self._unclaimed.observe(_NOTHING, step)
        self._observed += 1

    @property
    def calibrator(self) -> ScoreCalibrator | None:
        """The online calibration's learner, where the detections seen so far are of one
        class or none (before any, the one the first class will take); None with raw scores
        or one fixed calibration. Assign a
        :class:`~vistrack.tracking.calibration.ScoreCalibrator` that has seen other frames of
        the same detector to start from what it learnt (where one class or none has been
        seen); :meth:`reset` makes a new one.

        Raises
        ------
        ValueError
            If several classes have been seen: each has its own, in :attr:`calibrators`.

        Examples
        --------
        >>> BoxTracker().calibrator.window, BoxTracker(scores="raw").calibrator
        (20000, None)
        """
        if self.config.scores != "calibrated" or isinstance(self.calibration, ScoreCalibration):
            return None
        if len(self.calibrators) > 1:
            raise ValueError(f"each of the classes {sorted(self.calibrators)} has a calibrator "
                             "of its own: calibrators[class]")
        if self.calibrators:
            return next(iter(self.calibrators.values()))
        return self._unclaimed

    @calibrator.setter
    def calibrator(self, learner: ScoreCalibrator) -> None:
        """Put ``learner`` in the place of the online calibration's learner (one that has
        seen other frames of the same detector, to start from what it learnt), where the
        detections seen so far are of one class or none.

        Raises
        ------
        TypeError
            If ``learner`` is not a :class:`~vistrack.tracking.calibration.ScoreCalibrator`.
        ValueError
            With raw scores or one fixed calibration (nothing is learnt), or where several
            classes have been seen (``calibrators[class] = learner``).
        """
        if not isinstance(learner, ScoreCalibrator):
            raise TypeError(f"calibrator must be a ScoreCalibrator; got "
                            f"{type(learner).__name__}")
        if self.config.scores != "calibrated" or isinstance(self.calibration, ScoreCalibration):
            raise ValueError("calibrator: this tracker learns no calibration ("
                             + ("scores='raw'" if self.config.scores != "calibrated"
                                else "a fixed calibration is given") + ")")
        if len(self.calibrators) > 1:
            raise ValueError(f"each of the classes {sorted(self.calibrators)} has a calibrator "
                             "of its own: calibrators[class] = learner")
        if self.calibrators:
            self.calibrators[next(iter(self.calibrators))] = learner
        else:
            self._unclaimed = learner

    def score_calibrations(self) -> dict[int, ScoreCalibration]:
        """The calibration of each class seen (or given a fixed map), by class.

        Returns
        -------
        dict
            Class to :class:`~vistrack.tracking.calibration.ScoreCalibration`: the fixed one,
            or what the tracker has learnt so far; ``{}`` with raw scores, and with one fixed
            map for every class, ``{-1: map}`` (for whichever class).

        Examples
        --------
        >>> tr = BoxTracker()
        >>> _ = tr.step(1, Detections.from_xywh([[0, 0, 9, 9], [50, 0, 9, 9]], [0.9, 0.2],
        ...                                     classes=[2, 0]))
        >>> sorted(tr.score_calibrations())
        [0, 2]
        """
        if self.config.scores == "raw":
            return {}
        if isinstance(self.calibration, ScoreCalibration):
            return {-1: self.calibration}
        out: dict[int, ScoreCalibration] = dict(self.calibration or {})
        out.update((k, cal.calibration()) for k, cal in self.calibrators.items())
        return out

    def score_calibration(self, cls: int | None = None) -> ScoreCalibration | None:
        """The calibration in use for the detections of class ``cls``.

        Parameters
        ----------
        cls : int, optional
            A detection class; may be left out where one class has been seen (or none).

        Returns
        -------
        ScoreCalibration or None
            The fixed one (``calibration``), or what the tracker has learnt from the frames
            so far (for a class not seen yet, confidence 1 for every score); None with
            ``scores="raw"``.

        Raises
        ------
        ValueError
            If ``cls`` is left out where several classes have been seen.

        Examples
        --------
        >>> BoxTracker(scores="raw").score_calibration() is None
        True
        """
        if self.config.scores == "raw":
            return None
        if isinstance(self.calibration, ScoreCalibration):
            return self.calibration
        maps = self.score_calibrations()
        if cls is not None:  # ("2" or 0.5 was a class never seen: confidence 1)
            cls = int(_whole_numbers(np.asarray([cls]), "cls")[0])
        if cls is None:
            return _only_map(maps, "cls")
        return maps[cls] if cls in maps else _nothing_seen()

    def confidence(self, scores: ArrayLike, classes: ArrayLike | None = None) -> np.ndarray:
        """Scores as the thresholds see them.

        Parameters
        ----------
        scores : (N,) array_like
            Raw detection scores.
        classes : (N,) array_like, optional
            Their classes, each calibrated by its own class's map (may be left out where one
            class has been seen).

        Returns
        -------
        (N,) ndarray
            Calibrated confidences in ``[0, 1]`` (by :meth:`score_calibration`), or the raw
            scores with ``scores="raw"``.

        Raises
        ------
        ValueError
            If ``classes`` is left out where several classes have been seen, or differs from
            ``scores`` in length.

        Examples
        --------
        >>> BoxTracker(scores="raw").confidence([0.2, 3.0]).tolist()
        [0.2, 3.0]
        """
        if self.config.scores == "raw":
            return np.asarray(scores, dtype=np.float64)
        if isinstance(self.calibration, ScoreCalibration):
            return self.calibration(scores)
        if classes is None:  # (it said "give cls", an argument of score_calibration's)
            return _only_map(self.score_calibrations(), "classes")(scores)
        s = np.asarray(scores, dtype=np.float64).reshape(-1)
        # as Detections takes them ("0" or 0.5 was a class never seen: confidence 1)
        c = np.asarray(classes).reshape(-1)
        if c.dtype.kind not in "iu":  # (Detections' classes are int64 already)
            c = _whole_numbers(c, "classes")
        if c.shape != s.shape:
            raise ValueError(f"classes must have one per score; got {c.shape[0]} classes for "
                             f"{s.shape[0]} scores")
        if len(self.calibrators) == 1 and self.calibration is None:
            (k, learner), = self.calibrators.items()
            if (c == k).all():  # the one class seen (the usual file): its map alone
                return learner.calibration()(s)
        # every class's map, each refitted as it would be tracked alone (once a frame)
        maps = self.score_calibrations()
        kinds = _kinds(c)
        if len(kinds) == 1:
            return (maps[kinds[0]] if kinds[0] in maps else _nothing_seen())(s)
        out = np.empty(s.shape)
        for k in kinds:
            out[c == k] = (maps[k] if k in maps else _nothing_seen())(s[c == k])
        return out

    def covariances(self) -> np.ndarray:
        """The tracks' full covariances, from the per-axis ones kept
        (:func:`~vistrack.filters.axes.axes_to_full`).

        Returns
        -------
        (K, 8, 8) ndarray
            One per track, state ``[cx, cy, w, h, vcx, vcy, vw, vh]``.

        Examples
        --------
        >>> tr = BoxTracker()
        >>> _ = tr.step(1, Detections.from_xywh([[10, 20, 30, 60]], [0.9]))
        >>> tr.covariances().shape
        (1, 8, 8)
        """
        return axes_to_full(self.tracks.cov)

    def pass_over(self) -> None:
        """A frame the detector did not deliver, between two :meth:`step` calls (as
        :func:`vistrack.detector_checks.undelivered_frames` finds them): the tracks are left as
        they are, and the next step predicts them over both frames; the score calibration
        learnt online sees a frame without detections, as it sees one where nothing was
        found, its links running from one frame to the next.

        Examples
        --------
        A second person comes in frame 2; frame 3 is not delivered. Their track, started in
        frame 2, is confirmed by its second update, in frame 4 (had frame 3 been one where
        only the first person was found, it would have been dropped there):

        >>> tr = BoxTracker(frame_rate=10)
        >>> one = Detections.from_xywh([[200, 20, 30, 60]], [0.9])
        >>> two = lambda x: Detections.from_xywh([[200, 20, 30, 60], [x, 20, 30, 60]],
        ...                                      [0.9, 0.9])
        >>> tr.step(1, one).ids.tolist(), tr.step(2, two(14)).ids.tolist()
        ([1], [1])
        >>> tr.pass_over()  # frame 3
        >>> tr.step(4, two(22)).ids.tolist()
        [1, 2]

        Raises
        ------
        RuntimeError
            Before the first :meth:`step` (or after :meth:`reset`): there is no frame before
            it to be between (it was taken, the calibration shown an empty frame, and the
            first step numbered 1 all the same).
        """
        if self.frame is None:
            raise RuntimeError("pass_over() is for a frame the detector did not deliver "
                               "between two steps; no frame has been stepped yet")
        self._observe(_NOTHING)
        self._passed += 1  # step(None) next is the frame after this one

    def boxes_ahead(self, ids: ArrayLike, dt: float) -> np.ndarray:
        """The boxes of tracks predicted ``dt`` frames past the last step, along their
        filtered velocities (the motion's prediction of the state's mean, without its noise):
        where the tracks are expected between frames the detector did not run on.

        Parameters
        ----------
        ids : (K,) array_like of int
            Tracks alive after the last :meth:`step` (those it reported, for instance).
        dt : float
            Frames past the last step (at ``frame_rate``).

        Returns
        -------
        (K, 4) ndarray
            ``[x0, y0, x1, y1]`` each.

        Raises
        ------
        ValueError
            If an id is not an integer, or not a track alive after the last step, or ``dt``
            is not finite.

        Examples
        --------
        A box moving 4 pixels a frame to the right, half a frame ahead:

        >>> tr = BoxTracker(frame_rate=10)
        >>> for f in range(1, 9):
        ...     out = tr.step(f, Detections.from_xywh([[10 + 4 * f, 20, 30, 60]], [0.9]))
        >>> out.boxes.round(1).tolist(), tr.boxes_ahead(out.ids, 0.5).round(1).tolist()
        ([[42.0, 20.0, 72.0, 80.0]], [[43.9, 20.0, 73.9, 80.0]])
        """
        t = self.tracks
        given = np.asarray(ids).reshape(-1)
        if given.dtype.kind not in "iu":
            # 1.7 was read as track 1 (cast to integers), NaN as garbage
            raw = np.asarray(given, dtype=float) if given.dtype.kind in "fb" else None
            if raw is None or given.dtype.kind == "b" or not (
                    np.isfinite(raw).all() and (raw == np.round(raw)).all()):
                raise ValueError(f"ids must be track identities (integers); got "
                                 f"{given.tolist()[:5]}")
        if not (is_number(dt) and np.isfinite(float(dt))):  # ("0.5": numpy's words)
            raise ValueError(f"dt must be a finite number of frames; got {dt!r}")
        want = given.astype(np.int64)
        order = np.argsort(t.ids, kind="stable")
        at = np.minimum(np.searchsorted(t.ids[order], want), max(len(order) - 1, 0))
        found = (t.ids[order][at] == want) if len(order) else np.zeros(len(want), bool)
        if not found.all():
            raise ValueError(f"ids[{int(np.argmin(found))}] = {int(want[~found][0])} is not a "
                             "track alive after the last step")
        m = t.mean[order[at]]
        return _to_xyxy(m[:, :4] + float(dt) * m[:, 4:])

    def _match(self, rows: np.ndarray, cols: np.ndarray, ov: np.ndarray, track_ok: np.ndarray,
               det_ok: np.ndarray, min_iou: float, fuse: np.ndarray | None,
               ) -> tuple[np.ndarray, np.ndarray]:
        """Assign among the candidate pairs whose track and detection are still available
        and whose similarity, IoU (times the score with ``fuse``), is at least ``min_iou``."""
        sim = ov * fuse[cols] if fuse is not None else ov
        keep = track_ok[rows] & det_ok[cols] & (sim >= min_iou)
        r, c = rows[keep], cols[keep]
        if len(r) == 0:
            return r, c
        cost = 1.0 - sim[keep]
        if self.config.assigner == "gnn":
            i, j = _gnn_sparse(r, c, cost, len(track_ok), len(det_ok), limit=1.0 - min_iou)
            return i, j
        dense = np.full((len(track_ok), len(det_ok)), np.inf)
        dense[r, c] = cost
        return assign(dense, np.isfinite(dense), self.config.assigner)

    def _tentative_in_gate(self, db: np.ndarray, dc: np.ndarray, free: np.ndarray,
                           updated: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The last stage (see the module): the tentative tracks not ``updated``, each with
        the one detection of ``free`` (left over, confident enough to start a track) of its
        class within its gate, where no other track's gate holds that detection:
        ``(tracks, detections)``."""
        t = self.tracks
        ti = np.flatnonzero((t.state == TENTATIVE) & ~updated)
        if len(ti) == 0:  # most frames: nothing more to do
            return ti, ti
        # a box of no area has no noise to measure a distance by (the noise scales with
        # the size): like the overlap, the gate follows none
        di = np.flatnonzero(free & (db[:, 2] > db[:, 0]) & (db[:, 3] > db[:, 1]))
        if len(di) == 0:
            return ti[:0], di
        gate = self.config.tentative_gate
        z = _to_cxcywh(db[di])
        s = t.cov[ti, :, 0] + self._r[ti]  # the innovation's variances, per box value
        # the candidates: detections whose centre's x lies within the track's reach along x
        # (necessary for d2 < gate), found by sorting, not over every track and detection
        order = np.argsort(z[:, 0], kind="stable")
        x = z[order, 0]
        reach = np.sqrt(gate * s[:, 0])
        lo = np.searchsorted(x, t.mean[ti, 0] - reach, side="left")
        n = np.searchsorted(x, t.mean[ti, 0] + reach, side="right") - lo
        rows = np.repeat(np.arange(len(ti)), n)
        cols = order[np.repeat(lo - np.cumsum(n) + n, n) + np.arange(int(n.sum()))]
        # and along y, before the whole distance
        near = np.abs(z[cols, 1] - t.mean[ti[rows], 1]) <= np.sqrt(gate * s[rows, 1])
        rows, cols = rows[near], cols[near]
        e = z[cols] - t.mean[ti[rows], :4]
        with np.errstate(divide="ignore", invalid="ignore"):  # a track of no area: never in
            d2 = ((e * e) / s[rows]).sum(-1)
        ok = (d2 < gate) & (t.classes[ti[rows]] == dc[di[cols]])
        rows, cols = rows[ok], cols[ok]
        alone = ((np.bincount(rows, minlength=len(ti)) == 1)[rows]
                 & (np.bincount(cols, minlength=len(di)) == 1)[cols])
        return ti[rows[alone]], di[cols[alone]]

    def _associate_numpy(self, db: np.ndarray, ds: np.ndarray, dc: np.ndarray,
                         high: np.ndarray) -> tuple[np.ndarray, ...]:
        """The stages of association (see the module) in numpy, after :meth:`_predict`:
        ``(updated (K,), free detections (D,), matched tracks, their detections)``."""
        cfg, t = self.config, self.tracks
        gate = min(cfg.min_iou, cfg.min_iou_low, cfg.min_iou_tentative,
                   cfg.camera_min_iou if cfg.camera_motion else 1.0)

        def candidates():
            # every candidate pair once: overlapping boxes of the same class
            rows, cols, ov = iou_pairs(_to_xyxy(t.mean[:, :4]), db, gate)
            same = t.classes[rows] == dc[cols]
            return rows[same], cols[same], ov[same]

        rows, cols, ov = candidates()
        self._moved = np.zeros(len(t), bool)
        if cfg.camera_motion and len(t) and len(ds):
            ok = (ov >= cfg.camera_min_iou) & high[cols] & (t.state[rows] == CONFIRMED)
            i, j = _gnn_sparse(rows[ok], cols[ok], 1.0 - ov[ok], len(t), len(ds))
            self.camera_shift = _camera_shift(t.mean, db, i, j, cfg.camera_min_matches,
                                              cfg.camera_sig)
            if self.camera_shift.any():
                t.mean[:, :2] += self.camera_shift
                # each track follows the camera, or not, as its best detection says
                rows, cols, ov, own = _choose_prediction(len(t), len(ds), rows, cols, ov,
                                                         *candidates())
                t.mean[own, :2] -= self.camera_shift
                self._moved = ~own
        low = (ds >= cfg.low) & ~high if cfg.two_stage else np.zeros(len(ds), bool)
        free_t = np.ones(len(t), bool)
        free_d = np.ones(len(ds), bool)
        tentative = t.state == TENTATIVE
        matched_t, matched_d = [], []
        stages = [(~tentative, high, cfg.min_iou, ds if cfg.fuse_score else None)]
        if cfg.two_stage:
            stages.append((t.state == CONFIRMED, low, cfg.min_iou_low, None))
        stages.append((tentative, high, cfg.min_iou_tentative if cfg.two_stage else cfg.min_iou,
                       None))
        # 1: confirmed and lost tracks, confident detections; 2: confirmed tracks left,
        # low-score detections; 3: tentative tracks, confident detections left
        for tracks_ok, dets_ok, min_iou, fuse in stages:
            r, c = self._match(rows, cols, ov, tracks_ok & free_t, dets_ok & free_d, min_iou,
                               fuse)
            free_t[r] = False
            free_d[c] = False
            matched_t.append(r)
            matched_d.append(c)
        return ~free_t, free_d, np.concatenate(matched_t), np.concatenate(matched_d)

    def step(self, frame: Frame | int | None = None,
             detections: Detections | None = None) -> Tracks:
        """Track one frame (:class:`~vistrack.tracking.Tracker`).

        Parameters
        ----------
        frame : Frame or int, optional
            The frame, or its index (increasing; default the next one): the time since the
            last frame is the gap in indices over ``frame_rate``, so gaps in frame numbers are
            predicted over. The image is not used.
        detections : Detections
            The frame's detections, with boxes (None: no detections). A box of zero width or
            height overlaps no other, so no track follows it from frame to frame (a
            detections file's reader in :mod:`vistrack.pipeline` warns of such boxes).

        Returns
        -------
        Tracks
            The tracks reported in this frame (see the module, step 5).
        """
        if detections is None:
            detections = Detections(boxes=np.zeros((0, 4)))
        if not isinstance(detections, Detections) or detections.boxes is None:
            raise TypeError("detections must be vistrack.Detections with boxes")
        detections = _writable(detections)
        # after the last frame stepped or passed over (None: the one after it); a frame
        # passed over and then stepped was taken twice (predicted over one frame, not two,
        # and seen by the calibration twice)
        last = None if self.frame is None else self.frame + self._passed
        try:
            frame = frame_index(frame, last)
        except ValueError:
            if not self._passed:
                raise
            raise ValueError(f"frame must increase; got {frame_index(frame, None)} after "
                             f"{last}, a frame passed over (pass_over)") from None
        first = self.frame is None
        cfg, t = self.config, self.tracks
        db, raw, dc = detections.boxes, detections.scores, detections.classes
        # set by Detections.__post_init__ (boxes checked above)
        assert db is not None and raw is not None and dc is not None
        # every check before the frame is taken: a frame refused had been counted as
        # stepped (retried, "frame must increase"; the next one predicted a frame short)
        # (Detections refuses these as made; arrays changed after were taken: an infinite
        # score, a box whose far corner lies before its near one, or a NaN box, which failed
        # in an IndexError) one pass each where all is well
        if not np.isfinite(raw).all():
            i = int(np.flatnonzero(~np.isfinite(raw))[0])
            raise ValueError(f"detection scores must not be NaN; scores[{i}] is NaN (frame "
                             f"{frame})" if np.isnan(raw[i]) else
                             f"detection scores must be finite; scores[{i}] is {raw[i]} (frame "
                             f"{frame})")
        ordered = db[:, 2:] >= db[:, :2]  # (False for NaN too)
        if not ordered.all():
            i = int(np.flatnonzero(~ordered.all(axis=1))[0])
            raise ValueError(f"detection boxes must be (x1, y1, x2, y2) with x1 <= x2 and y1 "
                             f"<= y2, not NaN; boxes[{i}] = {db[i].tolist()} (frame {frame})")
        # the filters square a box's size; far past any image the squares overflow
        check_in_pixels(db, "detection boxes", f" (frame {frame})")
        if cfg.nms_iou < 1 and len(raw) > 1:  # (changes no state)
            keep = non_maximum(db, raw, dc, cfg.nms_iou)
            if not keep.all():
                detections = detections[keep]
                db, raw, dc = db[keep], raw[keep], dc[keep]
        if cfg.scores == "raw" and cfg.fuse_score and len(raw) and not (
                (raw >= 0) & (raw <= 1)).all():
            # (raw scores are the thresholds' confidences as they are; those suppressed
            # above take no part)
            raise ValueError(f"fuse_score weighs IoU by the score, which must lie in [0, 1]; "
                             f"frame {frame} has scores from {raw.min():.4g} to "
                             f"{raw.max():.4g} (use scores='calibrated', or fuse_score=False)")
        # the frames since the last one stepped or passed over (1: the next frame): a gap in
        # frame numbers is time to the calibration's chains and to coasting's rounding too
        step = 1 if last is None else frame - last
        self._passed = 0
        dt = 0.0 if self.frame is None else float(frame - self.frame)
        if self.frame is None:
            self._origin = frame - 1
        self.frame = frame
        time = (frame - self._origin) / self.frame_rate
        self._observe(detections, step)
        ds = self.confidence(raw, dc)
        high = ds >= cfg.high
        self.camera_shift = np.zeros(2)
        if dt > 1 and len(t):
            # frames left out of the steps (a gap in their indices): the tracks that stepping
            # through them would have deleted, lost longer than max_lost at the frame before
            # this one, are deleted before they can take a detection (one last seen 3 s
            # before was found again, max_lost 2 s)
            gone = t.stale((frame - 1 - self._origin) / self.frame_rate, cfg.max_lost)
            if gone.any():
                t.keep(~gone)
                self._offsets = self._offsets[~gone]
        self._predict(dt)
        if self.compiled:
            c = _contiguous  # one compiled signature for every layout of the input
            match, used, self._moved, ok = _associate(
                t.mean, t.cov, t.state, t.classes, c(db), c(ds), np.ascontiguousarray(dc), dt,
                c(self._q), c(self._r), self._association, self.camera_shift)
            if not ok:
                raise ValueError("track boxes must be finite")
            updated, free_d = match >= 0, ~used
            mt = np.flatnonzero(updated)
            md = match[mt]
        else:
            updated, free_d, mt, md = self._associate_numpy(db, ds, dc, high)
        self._camera_offset = self._camera_offset + self.camera_shift
        self._offsets[self._moved] += self.camera_shift
        if cfg.tentative_gate > 0:
            # (left over and able to start a track: confident enough for both thresholds)
            ti, di = self._tentative_in_gate(db, dc, free_d & high & (ds >= cfg.new_track),
                                             updated)
            if len(ti):
                if self.compiled:  # (numpy corrects every matched track below)
                    self._update(ti, _to_cxcywh(db[di]))
                updated[ti], free_d[di] = True, False
                mt, md = np.r_[mt, ti], np.r_[md, di]
        if len(mt):
            if not self.compiled:
                self._update(mt, _to_cxcywh(db[md]))
            t.scores[mt] = raw[md]
        kept = t.manage(updated, time, cfg.confirm_hits, cfg.max_lost)
        self._offsets = self._offsets[kept]
        if self.record:
            q = (self._q if len(self._q) == len(kept) else np.zeros((len(kept), 8)))[kept]
            upd = updated[kept]
        # new tracks from the confident detections nobody took
        new = np.flatnonzero(free_d & high & (ds >= cfg.new_track))
        if len(new):
            mean, cov = self.motion.initial(_to_cxcywh(db[new]))
            d = np.diagonal(cov, axis1=1, axis2=2)
            axes = np.stack([d[:, :4], np.zeros((len(new), 4)), d[:, 4:]], axis=-1)
            # confirmed at once in the first frame, or where one update confirms
            t.add(mean, axes, time, dc[new], raw[new], confirmed=first or cfg.confirm_hits <= 1)
            self._offsets = np.concatenate([self._offsets, np.zeros((len(new), 2))])
        if self.record:
            k = len(new)
            self.history.append((frame, dt, t.ids.copy(), t.mean.copy(), t.cov.copy(),
                                 np.concatenate([q, np.zeros((k, 8))]),
                                 np.concatenate([upd, np.ones(k, bool)]), t.scores.copy(),
                                 t.classes.copy(), self._camera_offset,
                                 (db.copy(), raw.copy(), dc.copy(), ds.copy()),
                                 self._offsets.copy()))
            self._confirmed.update(t.ids[t.state == CONFIRMED].tolist())
        report = (t.state == CONFIRMED) & (t.last_time == time)
        if cfg.coast_time > 0:
            coast = ((t.state == LOST) & (t.found >= cfg.coast_rate)
                     & (t.last_time - t.first_time >= cfg.coast_after - time_slack(time))
                     # (coast_time to the nearest frame stepped, a half up: half a step's
                     # slack, and the times' rounding, or 2.5 frames were 2 or 3 by where
                     # in the sequence the miss fell)
                     & (time - t.last_time <= cfg.coast_time + 0.5 * step / self.frame_rate
                        + time_slack(time)))
            if self.image_size is not None and coast.any():
                b = _to_xyxy(t.mean[:, :4])
                coast &= ((b[:, 0] >= 0) & (b[:, 1] >= 0) & (b[:, 2] <= self.image_size[0])
                          & (b[:, 3] <= self.image_size[1]))
            report |= coast
        out = np.flatnonzero(report)
        covs = np.zeros((len(out), 2, 2))
        covs[:, 0, 0], covs[:, 1, 1] = t.cov[out, 0, 0], t.cov[out, 1, 0]
        return Tracks(ids=t.ids[out], boxes=_to_xyxy(t.mean[out, :4]), points=None,
                      scores=t.scores[out], classes=t.classes[out], covs=covs)
