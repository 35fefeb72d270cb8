"""vistrack: visual object tracking, from pixels to tracks to scores.

The public API is re-exported here; submodules hold the details:

- :mod:`vistrack.models` — motion and measurement models (the physics);
- :mod:`vistrack.filters` — Kalman filter and smoothers, EKF, UKF, ensemble KF, particle
  filters and multiple models (the inference);
- :mod:`vistrack.simulate` — sample states and measurements from a model;
- :mod:`vistrack.association` — costs, gates, assignment, PDA and JPDA;
- :mod:`vistrack.tracking` — the tracker protocol, track management, and every tracker;
- :mod:`vistrack.io` — MOTChallenge files, video in and out;
- :mod:`vistrack.frontends` — frames to detections: background models, blobs, HOG;
- :mod:`vistrack.pipeline` — one loop, source → detector → tracker → sinks (:func:`run`);
- :mod:`vistrack.evaluation` — RMSE, NEES, NIS; CLEAR MOT, IDF1, HOTA;
- :mod:`vistrack.viz` — the seeds' figures.

Names load on first use, so ``import vistrack`` costs little memory.
"""

import importlib
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # what type checkers see; at run time they load on first use (below)
    from .types import Detections, Frame, Gaussian, Tracks

# Every name loads on first use (PEP 562), so that `import vistrack` stays light: numba and
# scipy, which the filters and trackers need, cost about 100 MB of memory on their own, and
# numpy, which even the types need, starts its BLAS threads when it loads (a command that
# only hands its inputs to worker processes sets their number first, vistrack.batch)
_LAZY = {
    **{name: "types" for name in ("Detections", "Frame", "Gaussian", "Tracks")},
    **{name: "filters" for name in (
        "EnsembleKalmanFilter", "ExtendedKalmanFilter", "FilterResult", "IMMFilter",
        "KalmanFilter", "OnlineFilter", "ParticleFilter", "SmoothResult",
        "UnscentedKalmanFilter", "kalman_filter", "kalman_filter_1d", "kf_predict", "kf_step",
        "kf_update", "rts_smooth", "two_filter_smooth")},
    **{name: "models" for name in (
        "ConstantAcceleration", "ConstantPosition", "ConstantVelocity", "LinearGaussian",
        "LinearMeasurement", "LinearMotion", "Periodic", "Position")},
    "BoxTracker": "tracking",
    "Tracker": "tracking",
    "run": "pipeline",
}
_SUBMODULES = ("association", "evaluation", "filters", "frontends", "io", "models", "pipeline",
               "simulate", "tracking", "types", "viz")


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        value = getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    elif name in _SUBMODULES:
        value = importlib.import_module(f".{name}", __name__)
    else:
        raise AttributeError(f"module 'vistrack' has no attribute {name!r}")
    globals()[name] = value
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(_LAZY) | set(_SUBMODULES))


__version__ = "0.1.0"

__all__ = [
    "BoxTracker",
    "Detections",
    "Frame",
    "Tracks",
    "Tracker",
    "run",
    "association",
    "filters",
    "frontends",
    "io",
    "models",
    "pipeline",
    "tracking",
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
