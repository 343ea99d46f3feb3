"""Hidden-effect logs from the PyBullet simulation, for testing the diagnosis against physics.

:func:`generate` drives a simulated vehicle (Lindgren's ``farm_2wd`` for ``diff_drive``, the
symmetric four-wheel :func:`skid4` for ``skid_steer``, Patako's tracked vehicle for
``tracked``, Reina's 4WD/4WS rover for ``rover4ws``) between random waypoints on rigid,
level or sloped ground, and exports the run as a slipenv-log/1 log whose ``meta.json`` holds
the *nominal* model. One effect of random size is hidden in the *physics* of the world (never
in the kinematic model the diagnosis fits), or none. How each effect is hidden — on which
vehicle kinds, what changes in the world, which columns the log needs — is in its module
(``effects/<effect>.py``, its ``Hiding``); this module is generic over them.

Why some effects are hidden on one kind only: on a skid-steer vehicle a softer longitudinal
law shows mainly in turns (the scrub torque dominates and the slip follows the combined law),
so soil patches are hidden on the differential-drive vehicle, soil maps (two fields of their
own softness) on it and on the rover (on a slope, as torque slip); torque slip is hidden on every
kind, the rover and the skid-steer vehicles on a slope: the rover so that it has a drive
torque to slip with, the skid-steer vehicles because on level ground their drive torque is
their turning resistance, so that a softer law is the world ``turning_slip`` hides and is
named so (its ``Confound``), while a grade torque is one the turn does not set
(``effects/torque_slip.py``); a
differential-drive vehicle with castors on a soft side slope yaws downhill (the castors carry
no side force), which is not Yamauchi's side slip, so slopes with side slip are skid-steer
only. ``combined_slip`` is not generated: on these vehicles a slip angle comes only with side
slip, so it never appears alone. About 30 % of the differential-drive logs stand on a 5-12°
slope, except where the effect's ``Hiding`` says otherwise.

The rover (``rover4ws``) carries rolling-radius, track-width, gyro and torque-slip errors
(torque slip on a 6-12° slope: on level rigid ground its only drive torque is its wheels
fighting one another, which a softer law takes away). Its steering
fixes the turn (each wheel points along its arc about the commanded centre), so a left/right
radius difference shows mostly as wheels fighting each other (longitudinal slip), less as
heading drift than on a differential drive. Its PyBullet body's yaw rate chatters between
control steps; the simulated gyro integrates (it reads the mean rate over each sample
interval), so a noise-free gyro's integral is the rover's turn.

A skid-steer vehicle never turns as its wheel spacing says (the wheels scrub), so its nominal
track width is the *effective* one, fitted on a long run of the clean world — as an operator
would calibrate it. True parameters: a gyro offset is taken one to one; every other effective
value is shifted a little by the vehicle's own dynamics, so it is fitted on a long noise-free
calibration run of the same world (``SynthLog.truth``); the values set in the physics are in
``SynthLog.world``.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import numpy as np

from slipenv.diagnose.effects import EFFECTS, effect
from slipenv.diagnose.effects.base import DrawContext
from slipenv.diagnose.extension import extend
from slipenv.diagnose.segments import wheel_sides
from slipenv.diagnose.simreplay import rigid_ground
from slipenv.diagnose.slip_law import scaled
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.logs.export import LogRecorder, meta_for
from slipenv.logs.log import Log
from slipenv.sensors.noise import SensorNoise
from slipenv.sensors.onboard import SensorSuite
from slipenv.sim.simulator import Simulator
from slipenv.terrain.terrain import TerrainSpec
from slipenv.vehicles.kinematics import twist_to_commands
from slipenv.vehicles.presets import farm_2wd, rover_4ws, tracked_patako
from slipenv.vehicles.spec import VehicleSpec, WheelSpec


def skid4() -> VehicleSpec:
    """A symmetric four-wheel skid-steer vehicle (Husky-sized, centred mass) for the tests.

    pybullet_data's Husky carries its mass ahead of its wheel centre, so in a turn its
    reference point slides sideways (the instantaneous centre of rotation sits off the axle
    midpoint): a real effect the vocabulary has no name for. This vehicle turns about its
    reference point, so its clean logs are explained by the nominal model.
    """
    r, half_l, half_w = 0.165, 0.25, 0.28
    wheels = tuple(
        WheelSpec(name, (x, y, 0.0), r, 0.11, 2.5, side)
        for name, x, y, side in (("front_left", half_l, half_w, "left"),
                                 ("front_right", half_l, -half_w, "right"),
                                 ("rear_left", -half_l, half_w, "left"),
                                 ("rear_right", -half_l, -half_w, "right")))
    return VehicleSpec(
        name="skid4", kind="skid_steer", chassis_mass_kg=40.0, chassis_size_m=(0.8, 0.5, 0.25),
        chassis_center_height_m=0.1, wheels=wheels, channels=("left", "right"),
        track_width_m=2 * half_w, wheel_radius_nominal_m=r, max_wheel_speed_rad_s=6.0,
        max_wheel_torque_nm=30.0, max_speed_mps=1.0, max_yaw_rate_rad_s=1.5,
        counts_per_rad=285.0)


VEHICLES = {"diff_drive": farm_2wd, "skid_steer": skid4, "tracked": tracked_patako,
            "rover4ws": rover_4ws}
"""The generator's vehicles by label: the label is the vehicle's kind, except ``tracked``
(Patako's tracked vehicle, road wheels under each track: a second skid-steer vehicle)."""
PHYSICAL_KIND = {label: make().kind for label, make in VEHICLES.items()}
"""The vehicle kind (``VehicleSpec.kind``) of each label: what an effect's ``Hiding.kinds``,
the force law of rigid ground and the diagnosis go by."""
HIDINGS = {name: e.hiding for name, e in EFFECTS.items() if e.hiding is not None}
"""How each effect the generator can hide is hidden."""
GENERATED = ("none", *HIDINGS)
DRAWN = ("none", *(name for name, hiding in HIDINGS.items() if hiding.drawn))
"""The effects :func:`generate` picks from at random (the others only when named)."""
KINDS = {"none": tuple(VEHICLES)} | {
    name: tuple(label for label in VEHICLES if PHYSICAL_KIND[label] in hiding.kinds)
    for name, hiding in HIDINGS.items()}
"""Vehicle labels each effect is hidden on (those whose kind is in its ``Hiding.kinds``)."""
ARENA_M = {"diff_drive": 5.0, "skid_steer": 3.5,  # half-size of the waypoint box [m]
           "tracked": 2.0, "rover4ws": 2.0}  # (the 0.3 m/s vehicles: a smaller box)
MAX_TURN_RATIO = {"diff_drive": 0.8, "skid_steer": 0.35,  # |v_r - v_l| / |v_r + v_l| limit
                  "tracked": 0.35, "rover4ws": 0.8}
CALIBRATION_S = 150.0  # [s] length of the noise-free calibration runs
EXACT = {kind: tuple(name for name, hiding in HIDINGS.items()
                     if hiding.exact and kind in KINDS[name]) for kind in VEHICLES}
"""Effects whose true parameters the physics takes one to one (a sensor offset). For all
others the vehicle's own dynamics shift the effective value a little (the farm vehicle's
castors let it oversteer, tread compliance adds slip), so their true values are those fitted
on a long noise-free calibration run of the same world; the set values are in ``world``."""
ACCEL_LIMIT = 0.4  # [1/s] speed command changes by at most this fraction of top speed per s


@dataclass
class SynthLog:
    """A generated log and what is hidden in it.

    Attributes
    ----------
    log : Log
    effect : str
        The hidden effect id (``none`` for a clean log).
    truth : dict
        True parameters in the contract's names (SI), where they are known.
    world : dict
        The simulated world's settings (for the record; also written to ``meta.json``).
    """

    log: Log
    effect: str
    truth: dict[str, float] = field(default_factory=dict)
    world: dict = field(default_factory=dict)


def base_config(kind: str, slope_deg: float = 0.0, azimuth_deg: float = 0.0,
                noise: SensorNoise | None = None) -> SlipEnvConfig:
    """The clean world of ``kind``: the vehicle on rigid ground, optional planar slope.

    Rigid ground (``simreplay.rigid_ground``): the concrete preset with its slip stiffnesses
    scaled up, so that the slip a clean log holds uphill stays near 0.1 %.
    """
    terrain = (TerrainSpec(kind="slope", slope_deg=slope_deg, downhill_azimuth_deg=azimuth_deg,
                           size_m=60.0) if slope_deg else TerrainSpec())
    return SlipEnvConfig(vehicle=VEHICLES[kind](), terrain=terrain, soil="concrete",
                         force_model=rigid_ground(PHYSICAL_KIND[kind]),
                         sensor_noise=noise or SensorNoise())


def hidden_world(kind: str, name: str, rng: np.random.Generator,
                 focus: tuple[float, float]) -> tuple[SlipEnvConfig, dict, dict]:
    """The world with effect ``name`` hidden: (config, model applied, settings).

    The effect's ``Hiding`` draws it: parameters applied to the world as a diagnosed model
    would be (``extension.extend``; the model is returned in the contract's names), or
    settings of the force law the effect emerges from. A skid-steer vehicle that turns on a
    side slope scrubs sideways and slides downhill, so it stands on a slope only when its
    effect asks for one; a differential-drive vehicle stands on a 5-12° slope in 30 % of the
    logs unless the effect forbids it.
    """
    hiding = effect(name).hiding if name != "none" else None
    slope_range = None if hiding is None else hiding.slope_range(PHYSICAL_KIND[kind])
    slope = 0.0
    if slope_range is not None:
        slope = float(rng.uniform(*slope_range))
    elif (PHYSICAL_KIND[kind] == "diff_drive" and (hiding is None or hiding.random_slope)
          and rng.random() < 0.3):
        slope = float(rng.uniform(5.0, 12.0))
    azimuth = float(rng.uniform(-180.0, 180.0))
    cfg = base_config(kind, slope, azimuth)
    world = {"slope_deg": slope, "azimuth_deg": azimuth}
    if hiding is None:
        return cfg, {}, world
    spec = make_vehicle(cfg.vehicle)
    ctx = DrawContext(PHYSICAL_KIND[kind], spec, arena_m(kind, slope > 0.0), focus,
                      lambda: typical_torque_nm(kind), slope)
    hidden = hiding.draw(rng, ctx)
    if hidden.slip_options:
        world.update(hidden.slip_options)
        return dataclasses.replace(cfg, force_model=scaled(cfg.force_model,
                                                           **hidden.slip_options)), {}, world
    if hidden.params is None:
        raise ValueError(f"{name}: Hiding.draw gave neither parameters nor slip options")
    wheels = list(spec.channels)
    params = effect(name).to_contract(hidden.params, dict.fromkeys(effect(name).fields(), 0.0),
                                      wheels, wheel_sides(wheels))
    model = {name: {k: v[0] for k, v in params.items()}}
    return extend(cfg, {name: hidden.params}), model, world


def arena_m(kind: str, sloped: bool) -> float:
    """Half-size of the waypoint box [m]; twice ``ARENA_M`` on a slope (long legs, gentle
    turns)."""
    return ARENA_M[kind] * (2.0 if sloped else 1.0)


@functools.lru_cache(maxsize=4)
def typical_torque_nm(kind: str) -> float:
    """Median |channel torque| of the clean world while driving the generator's routes."""
    rec = drive(base_config(kind), kind, np.random.default_rng(12345), 40.0, exact=True)
    torque = np.abs(np.concatenate([rec.log.signals[f"torque_{w}"] for w in rec.log.wheels]))
    return float(np.median(torque[torque > 0]))


@dataclass
class _Drive:
    log: Log
    spec: object


def drive(cfg: SlipEnvConfig, kind: str, rng: np.random.Generator, duration_s: float,
          focus: tuple[float, float] = (0.0, 0.0), columns=None, exact: bool = False,
          meta_track_m: float | None = None, gyro_sampling: str = "mean") -> _Drive:
    """Drive ``cfg``'s world between random waypoints; the run as a log (exact truth/sensors).

    Every other waypoint lies near ``focus`` (so a soil patch there is crossed again and
    again); speeds change every 3-8 s between 30 and 90 % of the vehicle's top speed.
    ``gyro_sampling`` is the gyro's (`slipenv.sensors.onboard.Imu`).
    """
    spec = make_vehicle(cfg.vehicle)
    terrain, world_noise = cfg.terrain, cfg.sensor_noise
    # SlipEnvConfig keeps both as specs, whatever form they were given in
    assert isinstance(terrain, TerrainSpec) and isinstance(world_noise, SensorNoise)
    noise = world_noise
    if exact:
        noise = dataclasses.replace(SensorNoise.perfect(),
                                    gyro_bias_rad_s=world_noise.gyro_bias_rad_s)
    sim = Simulator(spec, terrain, make_force_model(cfg.force_model, spec),
                    make_soil_map(cfg.soil, cfg.soil_map), control_hz=cfg.control_hz)
    sensors = SensorSuite(spec.counts_per_rad, noise, gyro_sampling=gyro_sampling)
    nominal = VEHICLES[kind]()
    meta = meta_for(nominal, terrain, "rigid", notes="slipenv.diagnose.synth")
    if meta_track_m is not None:
        meta.data["vehicle"]["track_width_m"] = meta_track_m
    rec = LogRecorder(meta, columns)
    steered = any(w.steered for w in nominal.wheels)  # the log holds the steering angles
    sloped = terrain.kind == "slope"
    arena = arena_m(kind, sloped)
    turn_ratio = MAX_TURN_RATIO[kind] * (0.4 if sloped else 1.0)
    try:
        truth = sim.reset(0.0, 0.0, float(rng.uniform(-math.pi, math.pi)))
        rec.record(sensors.measure(truth, rng), _pose(truth), [0.0] * len(spec.channels))
        target, toward_focus = _waypoint(rng, arena, focus, True), True
        v_ref, next_change, v_cmd, w_cmd = 0.0, 0.0, 0.0, 0.0
        dv = ACCEL_LIMIT * nominal.max_speed_mps / cfg.control_hz
        dw = ACCEL_LIMIT * nominal.max_yaw_rate_rad_s / cfg.control_hz
        for _ in range(int(round(duration_s * cfg.control_hz))):
            x, y, _ = truth.position_m
            if truth.t_s >= next_change:
                v_ref = float(rng.uniform(0.3, 0.9)) * nominal.max_speed_mps
                next_change = truth.t_s + float(rng.uniform(3.0, 8.0))
            if math.hypot(target[0] - x, target[1] - y) < 0.15 * arena:
                toward_focus = not toward_focus
                target = _waypoint(rng, arena, focus, toward_focus)
            err = math.atan2(target[1] - y, target[0] - x) - truth.yaw_rad
            err = (err + math.pi) % (2 * math.pi) - math.pi
            limit = 2.0 * turn_ratio * v_ref / nominal.track_width_m
            omega = float(np.clip(1.5 * err, -limit, limit))
            v_cmd += float(np.clip(v_ref - v_cmd, -dv, dv))  # smooth commands, as a real
            w_cmd += float(np.clip(omega - w_cmd, -dw, dw))  # drive's ramps would give
            speeds, steer = twist_to_commands(nominal, v_cmd, w_cmd)
            truth = sim.step(speeds, steer)
            rec.record(sensors.measure(truth, rng), _pose(truth), speeds,
                       _channel_steer(nominal, steer) if steered else None)
    finally:
        sim.close()
    return _Drive(rec.to_log(), spec)


def _channel_steer(spec: VehicleSpec, steer: list[float]) -> list[float]:
    """Commanded steering angle per channel [rad] (rover4ws channels are wheels)."""
    by_channel = {w.channel: a for w, a in zip(spec.wheels, steer, strict=True)}
    return [by_channel.get(c, 0.0) for c in spec.channels]


def _pose(truth) -> tuple[float, float, float]:
    return truth.position_m[0], truth.position_m[1], truth.yaw_rad


def _waypoint(rng: np.random.Generator, arena: float, focus, near_focus: bool):
    if near_focus:
        r, a = 0.1 * arena * math.sqrt(rng.random()), rng.uniform(0, 2 * math.pi)
        return focus[0] + r * math.cos(a), focus[1] + r * math.sin(a)
    return tuple(rng.uniform(-arena, arena, size=2))


_CALIBRATIONS: dict[tuple, dict[str, list[float]]] = {}


def calibrate(cfg: SlipEnvConfig, kind: str, effects: tuple[str, ...],
              meta_track_m: float | None = None,
              focus: tuple[float, float] = (0.0, 0.0)) -> dict[str, list[float]]:
    """Parameters of ``effects`` fitted on a long noise-free run of ``cfg``'s world (cached)."""
    from slipenv.diagnose.fit import Problem, fit
    from slipenv.diagnose.replay import build_segments

    key = (repr(cfg), kind, effects, meta_track_m, focus)
    if key not in _CALIBRATIONS:
        run = drive(cfg, kind, np.random.default_rng(2024), CALIBRATION_S, focus, exact=True,
                    meta_track_m=meta_track_m)
        seg = build_segments([run.log], 10.0)
        _CALIBRATIONS[key] = fit(Problem.from_segments(seg), effects).report(seg)
    return _CALIBRATIONS[key]


@functools.lru_cache(maxsize=8)
def effective_track_m(kind: str, slope_deg: float = 0.0, azimuth_deg: float = 0.0) -> float:
    """Nominal track width of the log's meta: geometric (diff-drive) or calibrated (skid)."""
    spec = VEHICLES[kind]()
    if PHYSICAL_KIND[kind] == "diff_drive":
        return spec.track_width_m
    return calibrate(base_config(kind), kind, ("track_width",))["track_width_m"][0]


def generate(seed: int, effect: str | None = None, kind: str | None = None,
             duration_s: float = 60.0, columns=None, gt_gaps: bool | None = None) -> SynthLog:
    """One log with one hidden effect of random size (random kind of effect if None).

    Parameters
    ----------
    seed : int
        Everything random (effect, size, route, noise, columns, gaps) follows from it.
    effect : str, optional
        One of ``GENERATED``; random among ``DRAWN`` if None.
    kind : str, optional
        A label of ``VEHICLES`` (``diff_drive``, ``skid_steer``, ``tracked``, ``rover4ws``);
        random among those the effect is hidden on (``KINDS``) if None.
    duration_s : float
        Log length [s] at 20 Hz.
    columns : iterable of str, optional
        Optional column groups (``slipenv.logs.export.OPTIONAL_GROUPS``); random if None,
        always including what the effect needs (torque, IMU).
    gt_gaps : bool, optional
        Cut 1-2 stretches of 3-6 s out of the ground truth; random if None.
    """
    rng = np.random.default_rng(seed)
    effect = effect or str(rng.choice(DRAWN))
    if effect not in GENERATED:
        raise ValueError(f"cannot hide {effect!r}; the generator hides {GENERATED}")
    kinds = KINDS[effect]
    kind = kind or str(rng.choice(kinds))
    if kind not in kinds:
        raise ValueError(f"the generator hides {effect} on {' and '.join(kinds)} vehicles only")
    focus = tuple(rng.uniform(-0.5, 0.5, size=2) * ARENA_M[kind])
    cfg, model, world = hidden_world(kind, effect, rng, focus)
    if columns is None:
        columns = {g for g in ("cmd", "torque", "imu", "attitude", "heading") if rng.random() < 0.6}
    hiding = EFFECTS[effect].hiding if effect != "none" else None
    columns = set(columns)
    if hiding is not None:  # what the effect needs (torque, IMU) or must not have
        columns = (columns | hiding.columns) - hiding.drop_columns
    meta_w = effective_track_m(kind)
    if hiding is not None and hiding.level_width:  # the operator calibrated it on level ground
        level = dataclasses.replace(cfg, terrain=TerrainSpec())
        meta_w = calibrate(level, kind, ("track_width",))["track_width_m"][0]
    run = drive(cfg, kind, rng, duration_s, focus, columns, meta_track_m=meta_w)
    log = _add_truth_noise(run.log, rng, gt_gaps)
    world.update({k: v for values in model.values() for k, v in values.items()})
    if effect in EXACT[kind]:
        truth = dict(model[effect])
    elif hiding is not None and hiding.compare:  # hiding is None for "none" only
        truth = {k: v[0] for k, v in calibrate(cfg, kind, (effect,), meta_w, focus).items()}
    else:
        truth = {}
    world.update(vehicle=VEHICLES[kind]().name, seed=seed)
    log.meta.data["synth"] = {"effect": effect, "truth": truth, "world": world}
    return SynthLog(log, effect, truth, world)


def _add_truth_noise(log: Log, rng: np.random.Generator, gaps: bool | None) -> Log:
    """OptiTrack-like ground truth: 0.5-3 mm and 0.5-3 mrad noise, optional gaps."""
    sig = dict(log.signals)
    n = len(log)
    sigma = float(rng.uniform(0.5e-3, 3e-3))
    for name, scale in (("gt_x", sigma), ("gt_y", sigma), ("gt_yaw", sigma)):
        sig[name] = sig[name] + rng.normal(0.0, scale, n)
    if gaps if gaps is not None else rng.random() < 0.5:
        dt = float(np.median(np.diff(log.t)))
        for _ in range(int(rng.integers(1, 3))):
            length = int(rng.uniform(3.0, 6.0) / dt)
            start = int(rng.integers(n // 10, max(n // 10 + 1, n - length - n // 10)))
            for name in ("gt_x", "gt_y", "gt_yaw"):
                sig[name][start:start + length] = np.nan
    return Log(log.meta.copy(), sig)
