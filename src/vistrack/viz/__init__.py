"""Pictures: the seeds' filter figures (:mod:`vistrack.viz.plots`). Needs matplotlib."""

from .plots import covariance_ellipse, plot_estimates_1d, plot_track_2d

__all__ = ["covariance_ellipse", "plot_estimates_1d", "plot_track_2d"]
