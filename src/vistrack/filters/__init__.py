"""Inference: batched Kalman kernels, the whole-sequence filter, smoothers."""

from .kalman import (
    FilterResult,
    KalmanFilter,
    OnlineFilter,
    kalman_filter,
    kalman_filter_1d,
    kf_predict,
    kf_step,
    kf_update,
)
from .smoothers import SmoothResult, rts_smooth, two_filter_smooth

__all__ = [
    "FilterResult",
    "KalmanFilter",
    "OnlineFilter",
    "SmoothResult",
    "kalman_filter",
    "kalman_filter_1d",
    "kf_predict",
    "kf_step",
    "kf_update",
    "rts_smooth",
    "two_filter_smooth",
]
