"""Detectors: OpenCV's HOG people detector, and the protocol a user's detector follows.

A detector is any object with ``detect(image) -> Detections``; nothing here downloads weights
(HOG's linear SVM ships inside OpenCV).
"""

from __future__ import annotations

from typing import Any, Protocol

import numpy as np

from ..types import Detections

__all__ = ["Detector", "HOGDetector", "nms"]


def nms(boxes: np.ndarray, scores: np.ndarray, max_iou: float) -> np.ndarray:
    """Greedy non-maximum suppression: indices of the boxes ``(N, 4)`` ``x0, y0, x1, y1``
    kept, best score first; a box overlapping a kept one by more than ``max_iou`` is
    dropped."""
    from ..association import iou

    order = np.argsort(-np.asarray(scores), kind="stable")
    ov = iou(boxes[order], boxes[order])
    keep = np.ones(len(order), bool)
    for a in range(len(order)):
        if keep[a]:
            keep[a + 1:] &= ov[a, a + 1:] <= max_iou
    return order[keep]


class Detector(Protocol):
    """What :func:`vistrack.pipeline.track_video` needs of a detector."""

    def detect(self, image: np.ndarray) -> Detections: ...


class HOGDetector:
    """Dalal and Triggs' HOG people detector (OpenCV's default people SVM), with non-maximum
    suppression; boxes are the detection windows without their margin (as OpenCV's sample
    draws them), and scores the SVM margins squashed to (0, 1) by a logistic.

    Parameters
    ----------
    scale : float
        Step between pyramid levels.
    hit_threshold : float
        SVM margin below which windows are dropped.
    nms_iou : float
        Overlap above which the weaker of two detections is dropped.
    upscale : float
        Enlarge the image first: the detector's window is 64×128 pixels, so people smaller
        than about 50×100 pixels need it (PETS09's are about 30×80).
    """

    def __init__(self, scale: float = 1.05, hit_threshold: float = 0.0, nms_iou: float = 0.4,
                 upscale: float = 2.0):
        import cv2

        self._hog = cv2.HOGDescriptor()
        self._hog.setSVMDetector(cv2.HOGDescriptor_getDefaultPeopleDetector())
        self.scale, self.hit_threshold, self.nms_iou = float(scale), float(hit_threshold), \
            float(nms_iou)
        if not upscale > 0:
            raise ValueError(f"upscale must be > 0; got {upscale}")
        self.upscale = float(upscale)

    def detect(self, image: Any) -> Detections:
        import cv2

        im = np.asarray(image)
        if self.upscale != 1.0:
            im = cv2.resize(im, None, fx=self.upscale, fy=self.upscale,
                            interpolation=cv2.INTER_LINEAR)
        rects, w = self._hog.detectMultiScale(im, hitThreshold=self.hit_threshold,
                                              winStride=(8, 8), padding=(8, 8),
                                              scale=self.scale)
        if len(rects) == 0:
            return Detections(boxes=np.zeros((0, 4)))
        w = np.asarray(w, float).ravel()
        r = np.asarray(rects, float).reshape(-1, 4) / self.upscale
        # the window holds the person with a margin: keep its inner 70 % of the width and 90 %
        # of the height (OpenCV's peopledetect sample)
        r = r + np.c_[0.15 * r[:, 2], 0.05 * r[:, 3], -0.3 * r[:, 2], -0.1 * r[:, 3]]
        keep = nms(np.c_[r[:, :2], r[:, :2] + r[:, 2:]], w, self.nms_iou)
        return Detections.from_xywh(r[keep], 1.0 / (1.0 + np.exp(-w[keep])))
