"""Lindgren's navigation EKF (Lindgren, Hague, Probert Smith and Marchant, "Relating torque and
slip in an odometric model for an autonomous agricultural vehicle").

Modules, in reading order:

- :mod:`.models`: the state layout and the process model (Eq. 12-13) as plain functions;
- :mod:`.observations`: the observation models and Jacobians (Eq. 14-17, 37-41);
- :mod:`.params`: the four schemes of §5 and the noise set;
- :mod:`.ekf`: :class:`LindgrenEKF`, the filter that strings them together.
"""

from .ekf import SENSORS, LindgrenEKF
from .models import OracleSoil
from .params import LindgrenNoise, Scheme, parse_scheme

__all__ = ["SENSORS", "LindgrenEKF", "LindgrenNoise", "OracleSoil", "Scheme", "parse_scheme"]
