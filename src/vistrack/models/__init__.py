"""Physics: motion models (``F(dt)``, ``Q(dt)``) and measurement models (``H``, ``R``)."""

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

__all__ = [
    "ConstantAcceleration",
    "ConstantPosition",
    "ConstantVelocity",
    "LinearGaussian",
    "LinearMeasurement",
    "LinearMotion",
    "MeasurementModel",
    "MotionModel",
    "Periodic",
    "Position",
]
