"""Stage 4 of the pipeline: the servo axes (reference → actual position) and contour error."""

from cnc_gym.plant.contour import ContourErrorMeter
from cnc_gym.plant.servo import ServoPlant

__all__ = ["ContourErrorMeter", "ServoPlant"]
