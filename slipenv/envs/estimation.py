"""Estimators the env can put behind its observation, by name.

The env builds the estimator from the vehicle spec: the estimator gets the operator's nominal
belief (nominal radius, track width, encoder resolution), never the simulation's truth —
except the deliberately privileged ``oracle`` variants, which say so in their name.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from estimators.base import Estimator, OdometryGeometry
from estimators.dead_reckoning import DeadReckoning
from slipenv.vehicles.spec import VehicleSpec


def odometry_geometry(spec: VehicleSpec) -> OdometryGeometry:
    """What an operator knows of the vehicle: nominal radius, track width, encoders."""
    return OdometryGeometry(
        wheel_radius_m=spec.wheel_radius_nominal_m,
        track_width_m=spec.track_width_m,
        counts_per_rad=spec.counts_per_rad,
        left=spec.left_channels,
        right=spec.right_channels,
        wheel_xy_m=np.array(spec.channel_xy_m()),
    )


def _dead_reckoning(spec: VehicleSpec, context: dict, **kw: Any) -> Estimator:
    return DeadReckoning(odometry_geometry(spec), **kw)


ESTIMATORS: dict[str, Callable[..., Estimator]] = {
    "dead_reckoning": _dead_reckoning,
}


def register_estimator(name: str, factory: Callable[..., Estimator]) -> None:
    """Make ``factory(spec, context, **kwargs) -> Estimator`` available as ``estimator=name``."""
    ESTIMATORS[name] = factory


def make_estimator(name: str, spec: VehicleSpec, context: dict, **kwargs: Any) -> Estimator:
    """Build the estimator called ``name``; unknown names are a ``ValueError`` listing them."""
    if name not in ESTIMATORS:
        raise ValueError(f"unknown estimator {name!r}; known estimators: {sorted(ESTIMATORS)}")
    return ESTIMATORS[name](spec, context, **kwargs)
