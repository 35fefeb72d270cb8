"""Scores: filter accuracy and consistency (RMSE, NEES, NIS), multi-object tracking
(CLEAR MOT, IDF1, HOTA) and single-object tracking (success rate, precision)."""

from .files import EvalResults, evaluate_files
from .filtering import chi2_band, nees, nis, rmse
from .mot import (
    ALPHAS,
    Matches,
    MOTCounts,
    box_iou_xywh,
    clear_matches,
    combine,
    evaluate_mot,
    point_similarity,
)
from .sanity import looks_like_detections, sanity_warnings
from .single import precision, region_to_bbox, success_curve, success_rate

__all__ = ["chi2_band", "nees", "nis", "rmse", "ALPHAS", "MOTCounts", "Matches", "box_iou_xywh",
           "clear_matches", "combine", "point_similarity",
           "evaluate_mot", "evaluate_files", "EvalResults", "sanity_warnings",
           "looks_like_detections", "precision", "region_to_bbox", "success_curve",
           "success_rate"]
