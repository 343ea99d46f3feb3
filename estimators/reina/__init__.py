"""Reina et al.'s visual slip angle and slip-compensated odometry (FTrace, sComp).

Reina, Ishigami, Nagatani, Yoshida, "Odometry correction using visual slip angle estimation
for planetary exploration rovers", Advanced Robotics 24 (2010) (``seeds/004_...``):

- :class:`FTrace` — the wheel trace in a rear camera image by Hough transform and fuzzy
  reasoning, and the slip angle from it (§2, Eq. 1-2); :class:`FTraceScore` counts false
  positives, false negatives and misidentifications as in Table 4;
- :class:`SlipRatioModel` and :func:`fit_slip_ratio_model` — s_x(β) (Eq. 12);
- :class:`SCompOdometry` (Eq. 15-17), :class:`CompassOdometry` and
  :func:`final_position_error` (Eq. 18); plain odometry is
  :class:`slipenv.estimators.DeadReckoning`;
- :class:`FTraceSComp` — sComp fed by FTrace on the rear camera's images (the env's
  ``estimator="scomp"``).
"""

from .ftrace import FTrace, FTraceConfig, TraceDetection, slip_angle_from_trace
from .fuzzy import FuzzyTraceRules
from .odometry import CompassOdometry, SCompOdometry, final_position_error
from .scoring import FTraceScore
from .slip_model import SlipRatioFit, SlipRatioModel, fit_slip_ratio_model
from .visual_odometry import FTraceSComp

__all__ = [
    "CompassOdometry",
    "FTrace",
    "FTraceConfig",
    "FTraceSComp",
    "FTraceScore",
    "FuzzyTraceRules",
    "SCompOdometry",
    "SlipRatioFit",
    "SlipRatioModel",
    "TraceDetection",
    "final_position_error",
    "fit_slip_ratio_model",
    "slip_angle_from_trace",
]
