"""Front-ends: frames to :class:`~vistrack.types.Detections`. They know nothing of tracks.

Background models and blobs (:class:`BlobDetector`), HOG people detection and its dense
confidence (:class:`HOGDetector`, :class:`HOGConfidence`, :class:`ConfidencePeaks`), and
spots in microscopy (:func:`locate`), and the user's own ONNX model
(:class:`ONNXDetector`, in :mod:`vistrack.frontends.onnx`; onnxruntime is imported when one
is made). Every detector answers ``detect(image) ->
Detections`` (:class:`Detector`). Trackers that follow features, templates, colours,
contours or appearance models from frame to frame are in :mod:`vistrack.tracking`.
"""

from .background import BACKGROUNDS, MOG2Background, SelectiveBackground, background, view_shift
from .blobs import BlobDetector, Blobs, find_blobs, threshold
from .detectors import ConfidenceMap, ConfidencePeaks, Detector, HOGConfidence, HOGDetector
from .onnx import ONNXDetector
from .spots import Spots, locate

__all__ = ["BACKGROUNDS", "MOG2Background", "SelectiveBackground", "background", "Blobs",
           "BlobDetector", "find_blobs", "threshold", "Detector", "HOGDetector", "Spots",
           "locate", "ConfidenceMap", "HOGConfidence", "ConfidencePeaks", "ONNXDetector",
           "view_shift"]
