"""Scores: filter accuracy and consistency (RMSE, NEES, NIS), multi-object tracking
(CLEAR MOT, IDF1, HOTA) and single-object tracking (success rate, precision)."""

from .files import evaluate_files
from .filtering import chi2_band, nees, nis, rmse
from .mot import ALPHAS, MOTCounts, box_iou_xywh, combine, evaluate_mot
from .single import precision, region_to_bbox, success_curve, success_rate

__all__ = ["chi2_band", "nees", "nis", "rmse", "ALPHAS", "MOTCounts", "box_iou_xywh", "combine",
           "evaluate_mot", "evaluate_files", "precision", "region_to_bbox", "success_curve",
           "success_rate"]
