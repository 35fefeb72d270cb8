"""Inference: batched Kalman kernels, the whole-sequence filter, smoothers, the filter of
independent (value, rate) pairs that the box tracker runs, and the EKF, UKF and ensemble Kalman
filter for nonlinear models, and expectation-maximisation to learn a linear model's
parameters from its measurements."""

from .axes import axes_predict, axes_to_full, axes_update, full_to_axes
from .ekf import ExtendedKalmanFilter, ekf_predict, ekf_update
from .enkf import Ensemble, EnsembleKalmanFilter, enkf_predict, enkf_update
from .imm import GaussianFilter, IMMFilter, IMMResult, SwitchingParticleFilter, SwitchingResult
from .kalman import (
    FilterResult,
    FilterResult1D,
    kalman_filter,
    kalman_filter_1d,
    kf_predict,
    kf_step,
    kf_update,
)
from .learn import FitResult, em, mle
from .linear import KalmanFilter, OnlineFilter
from .particle import (
    RESAMPLERS,
    ParticleDegeneracyError,
    ParticleFilter,
    ParticleResult,
    effective_sample_size,
    particle_mode,
    resample,
    weighted_cov,
    weighted_mean,
)
from .pda import pda_update
from .smoothers import SmoothResult, rts_smooth, two_filter_smooth
from .ukf import (
    JulierSigmaPoints,
    MerweScaledSigmaPoints,
    UnscentedKalmanFilter,
    ukf_predict,
    ukf_update,
)

__all__ = [
    "RESAMPLERS",
    "ParticleDegeneracyError",
    "ParticleFilter",
    "ParticleResult",
    "effective_sample_size",
    "particle_mode",
    "resample",
    "weighted_cov",
    "weighted_mean",
    "FitResult",
    "em",
    "mle",
    "Ensemble",
    "EnsembleKalmanFilter",
    "ExtendedKalmanFilter",
    "FilterResult",
    "GaussianFilter",
    "IMMFilter",
    "IMMResult",
    "SwitchingParticleFilter",
    "SwitchingResult",
    "JulierSigmaPoints",
    "MerweScaledSigmaPoints",
    "UnscentedKalmanFilter",
    "ekf_predict",
    "ekf_update",
    "enkf_predict",
    "enkf_update",
    "KalmanFilter",
    "OnlineFilter",
    "pda_update",
    "axes_predict",
    "axes_to_full",
    "axes_update",
    "full_to_axes",
    "SmoothResult",
    "kalman_filter",
    "kalman_filter_1d",
    "FilterResult1D",
    "kf_predict",
    "kf_step",
    "kf_update",
    "rts_smooth",
    "two_filter_smooth",
    "ukf_predict",
    "ukf_update",
]
