"""Data association: costs between tracks and detections, gates, and assignment."""

from .assign import ASSIGNERS, assign, components, gnn, greedy, nearest_neighbour
from .costs import euclidean, giou, iou, mahalanobis
from .gating import chi2_gate, chi2_threshold

__all__ = ["ASSIGNERS", "assign", "components", "gnn", "greedy", "nearest_neighbour",
           "euclidean", "giou", "iou", "mahalanobis", "chi2_gate", "chi2_threshold"]
