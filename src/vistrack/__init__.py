"""vistrack: visual object tracking, from pixels to tracks to scores.

The public API is re-exported here; submodules hold the details:

- :mod:`vistrack.models` — motion and measurement models (the physics);
- :mod:`vistrack.filters` — Kalman filter and smoothers, EKF, UKF, ensemble KF, particle
  filters and multiple models (the inference);
- :mod:`vistrack.simulate` — sample states and measurements from a model;
- :mod:`vistrack.evaluation` — RMSE, NEES, NIS;
- :mod:`vistrack.viz` — the seeds' figures.
"""

from .filters import (
    EnsembleKalmanFilter,
    ExtendedKalmanFilter,
    FilterResult,
    IMMFilter,
    KalmanFilter,
    OnlineFilter,
    ParticleFilter,
    SmoothResult,
    UnscentedKalmanFilter,
    kalman_filter,
    kalman_filter_1d,
    kf_predict,
    kf_step,
    kf_update,
    rts_smooth,
    two_filter_smooth,
)
from .models import (
    ConstantAcceleration,
    ConstantPosition,
    ConstantVelocity,
    LinearGaussian,
    LinearMeasurement,
    LinearMotion,
    Periodic,
    Position,
)
from .types import Gaussian
from . import evaluation, simulate  # noqa: E402  (submodules; viz is imported on use)

__version__ = "0.1.0"

__all__ = [
    "ConstantAcceleration",
    "ConstantPosition",
    "ConstantVelocity",
    "EnsembleKalmanFilter",
    "ExtendedKalmanFilter",
    "FilterResult",
    "Gaussian",
    "IMMFilter",
    "KalmanFilter",
    "OnlineFilter",
    "ParticleFilter",
    "UnscentedKalmanFilter",
    "LinearGaussian",
    "LinearMeasurement",
    "LinearMotion",
    "Periodic",
    "Position",
    "SmoothResult",
    "__version__",
    "evaluation",
    "kalman_filter",
    "kalman_filter_1d",
    "kf_predict",
    "kf_step",
    "kf_update",
    "rts_smooth",
    "simulate",
    "two_filter_smooth",
]
