"""Scores: filter accuracy and consistency (RMSE, NEES, NIS) and multi-object tracking
(CLEAR MOT, IDF1, HOTA)."""

from .filtering import chi2_band, nees, nis, rmse
from .mot import ALPHAS, MOTCounts, box_iou_xywh, combine, evaluate_mot

__all__ = ["chi2_band", "nees", "nis", "rmse", "ALPHAS", "MOTCounts", "box_iou_xywh", "combine",
           "evaluate_mot"]
