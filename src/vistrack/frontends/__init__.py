"""Front-ends: frames to :class:`~vistrack.types.Detections`. They know nothing of tracks."""

from .background import BACKGROUNDS, MOG2Background, SelectiveBackground, background
from .blobs import Blobs, find_blobs, threshold

__all__ = ["BACKGROUNDS", "MOG2Background", "SelectiveBackground", "background", "Blobs",
           "find_blobs", "threshold"]
