"""Pictures: the seeds' filter figures and track plots (:mod:`vistrack.viz.plots`, matplotlib),
and tracks drawn on frames (:mod:`vistrack.viz.annotate`, OpenCV)."""

from .annotate import AnnotatedVideo, Annotator, id_colour
from .plots import (
    TrajectoryPlot,
    covariance_ellipse,
    plot_estimates_1d,
    plot_hota_alpha,
    plot_timeline,
    plot_track_2d,
    plot_trajectories,
)

__all__ = ["Annotator", "id_colour", "covariance_ellipse", "plot_estimates_1d", "plot_track_2d",
           "plot_trajectories", "plot_hota_alpha", "plot_timeline", "AnnotatedVideo",
           "TrajectoryPlot"]
