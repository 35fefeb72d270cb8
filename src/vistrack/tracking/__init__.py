"""Tracking: one protocol (:class:`Tracker`: ``step(frame, detections) -> Tracks`` and
``reset()``) and every tracker built on it.

- multi-object, from detections: :class:`BoxTracker` (SORT, ByteTrack), :class:`PointTracker`
  (NN, GNN, PDA, JPDA), and the offline smoother :func:`smooth`;
- multi-object, from detections and pixels: :class:`DetectorConfidencePF`, and
  :class:`~vistrack.tracking.klt.KLTTracker` (features);
- one object (:class:`SingleObjectTracker`): colour, CamShift, particle, template, median
  flow, WSL, snake and OpenCV's, by name in :data:`METHODS`, and their composition
  (:class:`~vistrack.tracking.compose.Composite`);
- track management: :mod:`vistrack.tracking.lifecycle`;
- a box tracker's noise learned from tracks: :func:`fit_box_motion` (and
  :func:`smoothed_residual_share`, for tracks smoothed through the detections)
  (:mod:`vistrack.tracking.fit`).
"""

from ..types import Tracks
from .base import SingleObjectTracker, Tracker
from .box import TRACKERS, BoxTracker, BoxTrackerConfig
from .compose import Composite
from .dcpf import DCPFConfig, DetectorConfidencePF
from .fit import (
    MotionFit,
    fit_box_motion,
    matched_series,
    measurement_noise,
    smoothed_residual_share,
)
from .klt import Features, KLTTracker
from .lifecycle import CONFIRMED, LOST, TENTATIVE, TrackTable
from .offline import SmoothedTracks, smooth
from .point import POINT_ASSOCIATIONS, PointTracker
from .single import METHODS, single_tracker
from .snake import Snake, SnakeTracker

__all__ = ["Tracker", "SingleObjectTracker", "TRACKERS", "BoxTracker", "BoxTrackerConfig",
           "CONFIRMED", "LOST", "TENTATIVE", "TrackTable", "Tracks", "SmoothedTracks", "smooth",
           "POINT_ASSOCIATIONS", "PointTracker", "DCPFConfig", "DetectorConfidencePF",
           "Features", "KLTTracker", "METHODS", "single_tracker", "Composite", "Snake",
           "SnakeTracker", "MotionFit", "fit_box_motion", "matched_series",
           "measurement_noise", "smoothed_residual_share"]
