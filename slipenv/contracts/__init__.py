"""The contracts every layer may import: the sensor frame, the pose estimate, angle wrapping and
the body slip angle (one convention each), the observation layout with its bounds and the one
function that builds it.

Nothing here imports any other part of slipenv; estimators and controllers import only this
(controllers may also use :mod:`slipenv.paths`).
"""

from slipenv.contracts.angles import body_slip_angle, body_slip_angles, wrap_angle, wrap_angles
from slipenv.contracts.frame import SensorFrame
from slipenv.contracts.observation import (
    ACT_DIM,
    OBS_DIM,
    OBS_HIGH,
    OBS_LOW,
    OBS_NAMES,
    build_observation,
)
from slipenv.contracts.pose import PoseEstimate

__all__ = [
    "ACT_DIM",
    "OBS_DIM",
    "OBS_HIGH",
    "OBS_LOW",
    "OBS_NAMES",
    "PoseEstimate",
    "SensorFrame",
    "body_slip_angle",
    "body_slip_angles",
    "build_observation",
    "wrap_angle",
    "wrap_angles",
]
