"""Data association: costs between tracks and detections, gates, and assignment."""

from .assign import (
    ASSIGNERS,
    assign,
    components,
    gnn,
    gnn_sparse,
    greedy,
    greedy_pairs,
    lsa,
    lsa_kernel,
    nearest_neighbour,
    nearest_pairs,
)
from .costs import (
    euclidean,
    giou,
    iou,
    iou_pairs,
    iou_pairs_same_class,
    mahalanobis,
    non_maximum,
    overlapping_pairs,
    paired_iou,
)
from .gating import chi2_gate, chi2_threshold
from .pda import ipda_weights, jipda_weights, jpda_weights, likelihoods, pda_weights

__all__ = ["ASSIGNERS", "assign", "components", "gnn", "gnn_sparse", "greedy", "greedy_pairs",
           "lsa", "lsa_kernel", "nearest_neighbour", "nearest_pairs",
           "euclidean", "giou", "iou", "iou_pairs", "iou_pairs_same_class", "mahalanobis",
           "non_maximum", "overlapping_pairs", "paired_iou", "chi2_gate", "chi2_threshold",
           "ipda_weights", "jipda_weights", "jpda_weights", "likelihoods", "pda_weights"]
