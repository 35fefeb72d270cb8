"""Scores: filter accuracy and consistency (RMSE, NEES, NIS)."""

from .filtering import chi2_band, nees, nis, rmse

__all__ = ["chi2_band", "nees", "nis", "rmse"]
