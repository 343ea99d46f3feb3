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
``scomp``                   Reina: sComp odometry (Eq. 15-17) on the compass heading with
                            the slip angle from FTrace on the 5 Hz rear trace camera
                            (Eq. 1-2); kwargs ``slip_model`` (s_x(β) of Eq. 12 as a
                            ``SlipRatioModel`` or its dict, default s_x = 0), ``ftrace`` (dict
                            of ``FTraceConfig`` fields), ``camera`` (dict of
                            ``TraceCameraConfig`` fields) and ``wheel`` (the watched wheel,
                            default ``rear_left``). The env renders the camera for it.
==========================  ===========================================================
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.estimators.base import Estimator, OdometryGeometry
from slipenv.estimators.dead_reckoning import DeadReckoning
from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.lindgren.ekf import LindgrenEKF
from slipenv.estimators.lindgren.models import OracleSoil
from slipenv.estimators.lindgren.params import LindgrenNoise
from slipenv.estimators.skid_steer.endo import EndoOdometry
from slipenv.sim.simulator import Simulator
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
    per_wheel_n = spec.mass_kg * G_MPS2 / len(spec.wheels)
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


SLIP_MODEL_KEYS = ("s_x0", "k_per_rad", "beta0_rad", "k_pitch", "pitch_ref_rad")


def _slip_ratio_model(value: Any):
    from slipenv.estimators.reina import SlipRatioModel

    if value is None:
        return SlipRatioModel(0.0, 0.0, 0.0)
    if isinstance(value, SlipRatioModel):
        return value
    if isinstance(value, dict):
        unknown = sorted(set(value) - set(SLIP_MODEL_KEYS))
        if unknown:
            raise ValueError(f"unknown slip_model key(s) {unknown}; allowed: {SLIP_MODEL_KEYS}")
        return SlipRatioModel(**{k: float(v) for k, v in value.items()})
    raise ValueError(f"slip_model must be a SlipRatioModel or a dict of {SLIP_MODEL_KEYS}, got "
                     f"{value!r}")


def _options(cls, values: Any, option: str):
    """``cls(**values)`` for a dict of its fields; an unknown field is a ``ValueError``."""
    from dataclasses import fields

    if values is None:
        return cls()
    if isinstance(values, cls):
        return values
    if not isinstance(values, dict):
        raise ValueError(f"{option} must be a dict of {cls.__name__} fields, got {values!r}")
    known = [f.name for f in fields(cls)]
    unknown = sorted(set(values) - set(known))
    if unknown:
        raise ValueError(f"unknown {option} option(s) {unknown}; allowed: {known}")
    return cls(**{k: tuple(v) if isinstance(v, list) else v for k, v in values.items()})


def _scomp(spec: VehicleSpec, context: dict, slip_model: Any = None, ftrace: Any = None,
           camera: Any = None, wheel: str = "rear_left") -> Estimator:
    from dataclasses import replace

    from slipenv.estimators.reina import FTraceConfig, FTraceSComp
    from slipenv.sensors.trace_camera import TraceCameraConfig

    mount = context.get("trace_camera")
    if mount is None:
        raise ValueError("estimator 'scomp' needs the env's rear trace camera "
                         "(context['trace_camera'])")
    cam_cfg = mount(_options(TraceCameraConfig, camera, "camera"), wheel)
    ft_cfg = _options(FTraceConfig, ftrace, "ftrace")
    # The trace model's wheel is the camera's wheel (contact point, rut width, ground height).
    ft_cfg = replace(ft_cfg, wheel_xy_m=cam_cfg.wheel_xy_m, wheel_width_m=cam_cfg.wheel_width_m,
                     ground_z_m=cam_cfg.ground_z_m)
    return FTraceSComp(odometry_geometry(spec), _slip_ratio_model(slip_model),
                       cam_cfg.nominal_camera(), ft_cfg,
                       rear_to_cg_m=max(-cam_cfg.wheel_xy_m[0], 0.0))


ESTIMATORS: dict[str, Callable[..., Estimator]] = {
    "dead_reckoning": _dead_reckoning,
    "gyrodometry": _gyrodometry,
    "endo": _endo,
    "slip_compensated": _slip_compensated,
    "lindgren_ekf": _lindgren,
    "lindgren_oracle": _lindgren_oracle,
    "scomp": _scomp,
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


def true_soil_for_oracle(sim: Simulator, torque_scale: float = 1.0) -> OracleSoil:
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
