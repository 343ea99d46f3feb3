"""Estimators the env can put behind its observation, by name.

The env builds the estimator from the vehicle spec: the estimator gets the operator's nominal
belief (nominal radius, track width, encoder resolution, surveyed beacon positions), never the
simulation's truth, except the deliberately privileged ``*_oracle`` variants, which say so in
their name.

==========================  ===========================================================
name                        estimator
==========================  ===========================================================
``dead_reckoning``          encoders only, nominal geometry, no slip model
``gyrodometry``             encoders for distance, gyro for heading
``endo``                    Endo's skid-steer slip odometry (kwarg ``n``, default 0.824)
``slip_compensated``        Yamauchi: Endo + slip angle regression (kwarg ``beta_model``)
``lindgren_ekf``            Lindgren's EKF, kwarg ``scheme`` 1-4 (default 4, slip model)
``lindgren_oracle``         scheme 4 with the simulation's true R_w and k_s (privileged)
==========================  ===========================================================
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from slipenv.estimators.base import Estimator, OdometryGeometry
from slipenv.estimators.dead_reckoning import DeadReckoning
from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.lindgren.ekf import LindgrenEKF
from slipenv.estimators.lindgren.models import OracleSoil
from slipenv.estimators.lindgren.params import LindgrenNoise
from slipenv.estimators.skid_steer.endo import EndoOdometry
from slipenv.vehicles.spec import VehicleSpec

ENDO_N_HARD_FLOOR = 0.824  # Yamauchi Table 1


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


def _gyrodometry(spec: VehicleSpec, context: dict, **kw: Any) -> Estimator:
    return Gyrodometry(odometry_geometry(spec), **kw)


def _endo(spec: VehicleSpec, context: dict, n: float = ENDO_N_HARD_FLOOR, **kw: Any) -> Estimator:
    return EndoOdometry(odometry_geometry(spec), n, **kw)


def _slip_compensated(spec: VehicleSpec, context: dict, beta_model: Any = None,
                      n: float = ENDO_N_HARD_FLOOR, **kw: Any) -> Estimator:
    from slipenv.estimators.skid_steer.identification import SlipAngleModel
    from slipenv.estimators.skid_steer.yamauchi import SlipCompensatedOdometry

    if beta_model is None:
        raise ValueError(
            "estimator 'slip_compensated' needs estimator_kwargs={'beta_model': ...}: a fitted "
            "SlipAngleModel or its dict (see `slipenv reproduce yamauchi`)"
        )
    if isinstance(beta_model, dict):
        beta_model = SlipAngleModel.from_dict(beta_model)
    return SlipCompensatedOdometry(odometry_geometry(spec), n, beta_model, **kw)


def default_k_s_prior(spec: VehicleSpec) -> float:
    """Torque/slip gradient prior [N m]: C ≈ 2 W per wheel (traction coefficient ~0.5 at 25 %
    slip, typical of agricultural soils), k_s = r C. Known to the operator from the vehicle's
    weight alone; the filter estimates the real value (Lindgren §4)."""
    per_wheel_n = spec.mass_kg * 9.81 / len(spec.wheels)
    return 2.0 * spec.wheel_radius_nominal_m * per_wheel_n


def _lindgren(spec: VehicleSpec, context: dict, scheme: int | str = 4,
              params: LindgrenNoise | dict | None = None, oracle: OracleSoil | None = None,
              **kw: Any) -> Estimator:
    if len(spec.channels) != 2:
        raise ValueError("the Lindgren EKF models a two-channel (left/right) vehicle")
    if params is None:
        params = LindgrenNoise(k_s0=default_k_s_prior(spec))
    elif isinstance(params, dict):
        params = LindgrenNoise(**{"k_s0": default_k_s_prior(spec), **params})
    if not kw.pop("use_beacons", True):
        beacons = None
    else:
        beacons = context.get("beacons_xy")
    if kw:
        raise ValueError(f"unknown lindgren_ekf option(s) {sorted(kw)}")
    return LindgrenEKF(odometry_geometry(spec), scheme=scheme, params=params,
                       beacons_xy=beacons, oracle=oracle)


def _lindgren_oracle(spec: VehicleSpec, context: dict, **kw: Any) -> Estimator:
    truth = context.get("true_soil")
    if truth is None:
        raise ValueError("lindgren_oracle needs the env's true soil (context['true_soil'])")
    return _lindgren(spec, context, scheme=4, oracle=truth(), **kw)


ESTIMATORS: dict[str, Callable[..., Estimator]] = {
    "dead_reckoning": _dead_reckoning,
    "gyrodometry": _gyrodometry,
    "endo": _endo,
    "slip_compensated": _slip_compensated,
    "lindgren_ekf": _lindgren,
    "lindgren_oracle": _lindgren_oracle,
}


def register_estimator(name: str, factory: Callable[..., Estimator]) -> None:
    """Make ``factory(spec, context, **kwargs) -> Estimator`` available as ``estimator=name``."""
    ESTIMATORS[name] = factory


def make_estimator(name: str, spec: VehicleSpec, context: dict, **kwargs: Any) -> Estimator:
    """Build the estimator called ``name``; unknown names are a ``ValueError`` listing them."""
    if name not in ESTIMATORS:
        raise ValueError(f"unknown estimator {name!r}; known estimators: {sorted(ESTIMATORS)}")
    try:
        return ESTIMATORS[name](spec, context, **kwargs)
    except TypeError as exc:
        raise ValueError(f"bad options for estimator {name!r}: {exc}") from None


def true_soil_for_oracle(sim, torque_scale: float = 1.0) -> OracleSoil:
    """The simulation's true effective radius and k_s per channel (privileged: oracle only).

    k_s = r dF/ds at s = 0 of the injected force law, at each driven wheel's current load and
    soil, times the torque sensor's scale (Lindgren Eq. 24).
    """
    inj = sim.injector
    radii, k_s = [], []
    for channel in sim.spec.channels:
        ks = [k for k, w in enumerate(sim.spec.wheels) if w.channel == channel]
        k = ks[0]
        load = np.array([max(float(inj.load[k]), 1.0)])
        eps = 1e-4
        fx, _ = inj.force_model(np.array([eps]), np.zeros(1), load, inj.soil_at_wheel(k))
        radii.append(inj.rolling_radius_m(k))
        k_s.append(len(ks) * torque_scale * sim.spec.wheels[k].radius_m * float(fx[0]) / eps)
    return OracleSoil(wheel_radius_m=tuple(radii), k_s=tuple(k_s))
