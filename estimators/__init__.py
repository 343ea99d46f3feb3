"""Pose estimators: each eats :class:`slipenv.contracts.SensorFrame` readings and returns a
:class:`slipenv.contracts.PoseEstimate`; none sees PyBullet or ground truth.

The estimators import only :mod:`slipenv.contracts` (tests/test_layering.py checks it), so they
run as well on a measured log as in the simulator.

================================  ===============================================================
class                             what it is
================================  ===============================================================
:class:`DeadReckoning`            encoders only, nominal geometry, no slip model
:class:`Gyrodometry`              encoder distance, gyro heading (Borenstein & Feng 1996)
:class:`LindgrenEKF`              inertial, odometric and beacon EKF with the torque/slip model
                                  (Lindgren et al., :mod:`.lindgren`)
:class:`EndoOdometry`             gyrodometry with Endo's track slip ratios (:mod:`.skid_steer`)
:class:`SlipCompensatedOdometry`  Endo plus Yamauchi's slip-angle regression (Eq. 9)
================================  ===============================================================

:mod:`.consistency` holds the NEES/NIS χ² checks used to judge a filter.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from .base import Estimator, OdometryGeometry
from .dead_reckoning import DeadReckoning
from .gyrodometry import Gyrodometry
from .skid_steer import EndoOdometry, SlipAngleModel, SlipCompensatedOdometry

if TYPE_CHECKING:
    from .lindgren import LindgrenEKF, LindgrenNoise, OracleSoil, Scheme

# The Lindgren filter is compiled by numba, whose import alone takes about a second: it loads
# when first asked for, so the envs and tools that never use it do not pay for it.
_LAZY = {"LindgrenEKF", "LindgrenNoise", "OracleSoil", "Scheme"}


def __getattr__(name: str) -> object:
    if name in _LAZY:
        from . import lindgren

        return getattr(lindgren, name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")

__all__ = [
    "DeadReckoning",
    "EndoOdometry",
    "Estimator",
    "Gyrodometry",
    "LindgrenEKF",
    "LindgrenNoise",
    "OdometryGeometry",
    "OracleSoil",
    "Scheme",
    "SlipAngleModel",
    "SlipCompensatedOdometry",
]
