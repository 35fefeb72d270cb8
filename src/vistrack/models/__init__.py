"""Physics: motion models (``F(dt)``, ``Q(dt)``; nonlinear: ``f``, ``jacobian``) and measurement
models (``H``, ``R``; nonlinear: ``h``, ``jacobian``); what a model must provide is
:mod:`vistrack.models.protocols`."""

from .adapters import MeasurementFunctions, MotionFunctions, psd_sqrt
from .box import BoxMotion
from .linear_gaussian import LinearGaussian
from .measurement import LinearMeasurement, MeasurementModel, Position
from .motion import (
    ConstantAcceleration,
    ConstantPosition,
    ConstantVelocity,
    LinearMotion,
    MotionModel,
    Periodic,
)
from .nonlinear import (
    AngleAwareMeasurement,
    CoordinatedTurn,
    GrowthMeasurement,
    GrowthMotion,
    NonlinearMeasurement,
    NonlinearMotion,
    RangeBearing,
    growth_model,
    numerical_jacobian,
    wrap_angle,
)
from .protocols import NonlinearMeasurementModel, NonlinearMotionModel
from .switching import SwitchingLinearSystem

__all__ = [
    "MeasurementFunctions",
    "MotionFunctions",
    "psd_sqrt",
    "AngleAwareMeasurement",
    "BoxMotion",
    "ConstantAcceleration",
    "ConstantPosition",
    "ConstantVelocity",
    "CoordinatedTurn",
    "GrowthMeasurement",
    "GrowthMotion",
    "NonlinearMeasurement",
    "NonlinearMeasurementModel",
    "NonlinearMotion",
    "NonlinearMotionModel",
    "RangeBearing",
    "SwitchingLinearSystem",
    "growth_model",
    "numerical_jacobian",
    "wrap_angle",
    "LinearGaussian",
    "LinearMeasurement",
    "LinearMotion",
    "MeasurementModel",
    "MotionModel",
    "Periodic",
    "Position",
]
