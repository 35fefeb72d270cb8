"""Front-ends: frames to :class:`~vistrack.types.Detections`, and single-object trackers.
They know nothing of tracks."""

from .appearance import WSLModel, WSLTracker
from .background import BACKGROUNDS, MOG2Background, SelectiveBackground, background
from .blobs import Blobs, find_blobs, threshold
from .compose import Composite
from .detectors import ConfidenceMap, Detector, HOGConfidence, HOGDetector
from .klt import Features, KLTTracker
from .single import METHODS, single_tracker
from .snake import Snake
from .spots import Spots, locate

__all__ = ["BACKGROUNDS", "MOG2Background", "SelectiveBackground", "background", "Blobs",
           "find_blobs", "threshold", "Detector", "HOGDetector", "Features", "KLTTracker",
           "METHODS", "single_tracker", "Snake", "Spots", "locate", "WSLModel", "WSLTracker",
           "Composite", "ConfidenceMap", "HOGConfidence"]
