"""Lindgren's navigation EKF (Lindgren, Hague, Probert Smith and Marchant, "Relating torque and
slip in an odometric model for an autonomous agricultural vehicle").

Modules, in reading order:

- :mod:`.models`: the state layout and the process model (Eq. 12-13) as plain functions, with
  the optional lateral slip gain (the body's slip angle from the lateral specific force);
- :mod:`.observations`: the observation models and Jacobians (Eq. 14-17, 37-41), and Okello's
  curve (Eq. 18-20) with its inverse for scheme 5;
- :mod:`.params`: the four schemes of §5, scheme 5 (Okello's curve per wheel in place of the
  linear law) and the noise set;
- :mod:`.kernel`: one frame's predictions and Kalman updates (Eq. 6-11) with those models;
- :mod:`.ekf`: :class:`LindgrenEKF`, the filter around it (validation, skips, history).

The models and the kernel are the only implementation, compiled from their Python text by
numba (``@njit(cache=True)``; ``NUMBA_DISABLE_JIT=1`` runs the same text as plain Python).
"""

from .ekf import SENSORS, LindgrenEKF
from .models import OracleSoil
from .params import LindgrenNoise, Scheme, parse_scheme

__all__ = ["SENSORS", "LindgrenEKF", "LindgrenNoise", "OracleSoil", "Scheme", "parse_scheme"]
