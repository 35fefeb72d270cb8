"""Multi-object tracking: track management and trackers built from filters and association."""

from .box import TRACKERS, BoxTracker, BoxTrackerConfig
from .dcpf import DCPFConfig, DetectorConfidencePF
from .lifecycle import CONFIRMED, LOST, TENTATIVE, Tracks, TrackTable
from .offline import SmoothedTracks, smooth
from .point import POINT_ASSOCIATIONS, PointTracker

__all__ = ["TRACKERS", "BoxTracker", "BoxTrackerConfig", "CONFIRMED", "LOST", "TENTATIVE",
           "TrackTable", "Tracks", "SmoothedTracks", "smooth", "POINT_ASSOCIATIONS",
           "PointTracker", "DCPFConfig", "DetectorConfidencePF"]
