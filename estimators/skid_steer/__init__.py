"""Odometry of skid-steer tracked vehicles with track slip and body slip angle (Endo 2007;
Yamauchi et al., slip-compensated odometry).

Modules, in reading order:

- :mod:`.kinematics`: body and track velocities with slip ratios and slip angle (Yamauchi
  Eq. 1-7);
- :mod:`.endo`: Endo's slip-ratio relation (Eq. 8) in closed form and :class:`EndoOdometry`;
- :mod:`.yamauchi`: the slip-angle regression's online regressors and
  :class:`SlipCompensatedOdometry` (Eq. 9);
- :mod:`.identification`: fitting Endo's exponent and the Eq. 9 regression from runs.
"""

from .endo import EndoOdometry
from .identification import EndoFit, SlipAngleModel, SlipRun, fit_endo_n, fit_slip_angle_runs
from .yamauchi import SlipAnglePredictor, SlipCompensatedOdometry

__all__ = [
    "EndoFit",
    "EndoOdometry",
    "SlipAngleModel",
    "SlipAnglePredictor",
    "SlipCompensatedOdometry",
    "SlipRun",
    "fit_endo_n",
    "fit_slip_angle_runs",
]
