"""Replay in PyBullet: the physics world driven by the logged wheel motion, segment by segment.

What it adds over the kinematic replay (``replay.py``): the vehicle's dynamics (inertia, motor
limits, load transfer, the response lag after a command), the terrain's geometry and gravity
on a slope, skid-steer scrub emerging from the force law, and soil maps — and it is the world
the next training run will use, so replaying there checks that the extension carried into it
(``extension.extend``) reproduces the log. What it costs: a vehicle model the log does not
give (mass, chassis, wheel layout are generic, built from the nominal meta), and about 1 ms
per step. The diagnosis itself is fitted on the kinematic replay; PyBullet replays the first
segments (about a minute) for the report's overlay, nominal world against the world extended
by the model fitted *without* each segment's fold (held-out).

Skid-steer: a generic four-wheel vehicle on rigid ground turns less than its wheel spacing
says; its side stiffness is tuned (bisection) until its effective track width is the log's
nominal one, as an operator's calibration would make it.
"""

from __future__ import annotations

import math

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.diagnose.extension import extend
from slipenv.diagnose.select import Selection
from slipenv.diagnose.slip_law import ScaledSlip
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.logs.log import Log
from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim.simulator import PhysicsBlowUp, Simulator
from slipenv.terrain.terrain import TerrainSpec
from slipenv.vehicles.spec import VehicleSpec, WheelSpec

p = import_pybullet()  # the banner-free first import (see slipenv.pybullet_quiet)

REPLAY_S = 60.0  # [s] of log replayed in PyBullet for the report
RIGID_LAW = {"diff_drive": "reina", "skid_steer": "janosi", "rover4ws": "reina"}
RIGID_LONG = {"diff_drive": 30.0, "skid_steer": 5.0, "rover4ws": 30.0}
RIGID_LAT = {"diff_drive": 5.0, "skid_steer": 1.0, "rover4ws": 5.0}


def rigid_ground(kind: str, lat_scale: float = 1.0) -> ScaledSlip:
    """Force law of rigid ground: the concrete preset's slip stiffnesses scaled up.

    A hard tyre on a hard floor: ``RIGID_LONG``/``RIGID_LAT`` times the concrete preset's
    stiffnesses, Reina's law (separate longitudinal and side stiffness) for differential
    drive, Janosi's (isotropic: a skid-steer's effective width stays the same in gentle and
    sharp turns) for skid-steer.
    """
    return ScaledSlip(RIGID_LAW[kind], (("lat_scale", RIGID_LAT[kind] * lat_scale),
                                        ("long_scale", RIGID_LONG[kind])))


def generic_vehicle(log: Log) -> VehicleSpec:
    """A generic vehicle with the log's nominal geometry (mass and chassis assumed)."""
    meta = log.meta
    r, w = meta.wheel_radius_m, meta.track_width_m
    mass = meta.mass_kg or float(np.clip(40.0 * (w / 0.55) ** 2, 2.0, 3000.0))
    chassis = 0.8 * mass
    wheels: tuple[WheelSpec, ...]
    if meta.kind == "diff_drive":
        wheels = (WheelSpec("left", (0.0, w / 2, 0.0), r, 0.3 * r, 0.05 * mass, "left"),
                  WheelSpec("right", (0.0, -w / 2, 0.0), r, 0.3 * r, 0.05 * mass, "right"),
                  WheelSpec("caster_left", (-0.8 * w, 0.4 * w, -0.5 * r), 0.5 * r, 0.2 * r,
                            0.05 * mass, None, role="caster"),
                  WheelSpec("caster_right", (-0.8 * w, -0.4 * w, -0.5 * r), 0.5 * r, 0.2 * r,
                            0.05 * mass, None, role="caster"))
        size = (1.2 * w, 0.8 * w, 0.4 * w)
    else:  # a skid-steer vehicle's geometric track is narrower than its effective one
        half_w, half_l = 0.4 * w, 0.35 * w
        wheels = tuple(WheelSpec(f"{a}_{s}", (x, y, 0.0), r, 0.4 * r, 0.05 * mass, s)
                       for a, x in (("front", half_l), ("rear", -half_l))
                       for s, y in (("left", half_w), ("right", -half_w)))
        size = (2.6 * half_l, 1.6 * half_w, 0.4 * w)
    return VehicleSpec(
        name="generic", kind=meta.kind, chassis_mass_kg=chassis, chassis_size_m=size,
        chassis_center_height_m=0.5 * size[2], wheels=wheels, channels=("left", "right"),
        track_width_m=w if meta.kind == "diff_drive" else 2 * half_w,
        wheel_radius_nominal_m=r, max_wheel_speed_rad_s=1e3,
        max_wheel_torque_nm=20.0 * mass * G_MPS2 * r, max_speed_mps=1.0, max_yaw_rate_rad_s=1.0,
        counts_per_rad=meta.counts_per_rad)


def world(log: Log, lat_scale: float = 1.0) -> SlipEnvConfig:
    """The nominal PyBullet world of the log: generic vehicle, rigid ground, declared slope."""
    meta = log.meta
    terrain = (TerrainSpec(kind="slope", slope_deg=meta.slope_deg,
                           downhill_azimuth_deg=meta.slope_downhill_azimuth_deg or 0.0,
                           size_m=200.0) if meta.slope_deg else TerrainSpec(size_m=200.0))
    return SlipEnvConfig(vehicle=generic_vehicle(log), terrain=terrain, soil="concrete",
                         force_model=rigid_ground(meta.kind, lat_scale))


def _yaw_ratio(cfg: SlipEnvConfig, hz: float) -> float:
    """Yaw rate over the kinematic one (geometric width) in a steady arc."""
    spec = make_vehicle(cfg.vehicle)
    sim = _simulator(cfg, hz)
    try:
        r, w = spec.wheel_radius_nominal_m, spec.track_width_m
        v = 0.2 * w * 4  # about four track widths per second... scaled to the vehicle
        omega = 0.4 * v / w
        sim.reset(0.0, 0.0, 0.0)
        steps = max(int(2 * hz), 1)  # 2 s to settle into the arc, then 2 s measured
        truths = [sim.step([(v - omega * w / 2) / r, (v + omega * w / 2) / r], [0.0] * 4)
                  for _ in range(2 * steps)]
        start, end = truths[steps - 1], truths[-1]
        turned = (end.yaw_rad - start.yaw_rad + math.pi) % (2 * math.pi) - math.pi
        return turned / (end.t_s - start.t_s) / omega
    finally:
        sim.close()


def calibrated_world(log: Log, hz: float) -> SlipEnvConfig:
    """``world(log)``, skid-steer side stiffness bisected to the log's effective width."""
    cfg = world(log)
    if log.meta.kind != "skid_steer":
        return cfg
    target = make_vehicle(cfg.vehicle).track_width_m / log.meta.track_width_m
    lo, hi = -3.0, 3.0  # log10 of the side-stiffness factor (more stiffness: less yaw)
    for _ in range(8):
        mid = 0.5 * (lo + hi)
        if _yaw_ratio(world(log, 10.0**mid), hz) > target:
            lo = mid
        else:
            hi = mid
    return world(log, 10.0 ** (0.5 * (lo + hi)))


def _simulator(cfg: SlipEnvConfig, hz: float) -> Simulator:
    spec = make_vehicle(cfg.vehicle)
    physics = hz * max(1, round(240.0 / hz))
    assert isinstance(cfg.terrain, TerrainSpec)  # SlipEnvConfig keeps a spec
    return Simulator(spec, cfg.terrain, make_force_model(cfg.force_model, spec),
                     make_soil_map(cfg.soil, cfg.soil_map), physics_hz=physics, control_hz=hz)


def replay_segment(sim: Simulator, seg_t: np.ndarray, speeds: np.ndarray,
                   start: np.ndarray) -> np.ndarray:
    """Drive ``sim`` from the logged pose ``start`` with the logged wheel speeds; poses (n, 3).

    ``speeds`` (n-1, 2) are the left/right wheel speeds of each interval [rad/s]. The vehicle
    starts rolling at the first interval's speed (body and wheels set to it after settling).
    """
    truth = sim.reset(float(start[0]), float(start[1]), float(start[2]), settle_s=0.2)
    spec = sim.spec
    v = 0.5 * spec.wheel_radius_nominal_m * (speeds[0, 0] + speeds[0, 1])
    yaw = truth.yaw_rad
    p.resetBaseVelocity(sim.body.body_id, [v * math.cos(yaw), v * math.sin(yaw), 0.0],
                        [0.0, 0.0, 0.0], physicsClientId=sim.client)
    for joint, wheel in zip(sim.body.spin_joints, spec.wheels, strict=True):
        if joint is not None:
            rate = speeds[0, 0] if wheel.position_m[1] > 0 else speeds[0, 1]
            state = p.getJointState(sim.body.body_id, joint, physicsClientId=sim.client)
            p.resetJointState(sim.body.body_id, joint, state[0], rate, physicsClientId=sim.client)
    out = np.empty((len(seg_t), 3))
    out[0] = start
    for k in range(len(seg_t) - 1):
        try:
            truth = sim.step(list(speeds[k]), [0.0] * len(spec.wheels))
        except PhysicsBlowUp:
            out[k + 1:] = np.nan
            break
        out[k + 1] = (truth.position_m[0], truth.position_m[1], truth.yaw_rad)
    return out


def pybullet_overlay(log: Log, sel: Selection, problem, seed: int = 0,
                     progress: bool = False) -> dict | None:
    """Replay the first ``REPLAY_S`` of ``log`` in PyBullet, nominal and extended worlds.

    Returns None when the log's vehicle cannot be built (not diff-drive/skid-steer).
    """
    from tqdm import tqdm

    seg = problem.seg
    if log.meta.kind not in ("diff_drive", "skid_steer"):
        return None
    rows = [j for j in range(len(seg)) if seg.log_index[j] == 0
            and seg.t[j, 0] - seg.t[0, 0] < REPLAY_S]
    hz = 1.0 / float(np.median(np.diff(log.t)))
    base = calibrated_world(log, hz)
    cand = sel.final.get("pose")
    folds = np.unique(sel.folds)
    nominal = {"wheel_radius_m": log.meta.wheel_radius_m,
               "track_width_m": log.meta.track_width_m}
    sims: dict = {"nominal": _simulator(base, hz)}
    out: dict = {"logged": [], "nominal": [], "extended": [], "segments": len(rows)}
    refused: list[str] = []  # fold models the simulation cannot take (a negative stiffness)
    try:
        for j in tqdm(rows, desc="PyBullet replay", unit="segment", disable=not progress):
            n = int(np.flatnonzero(seg.gt_ok[j])[-1]) + 1
            rates = seg.dphi[j, :n - 1] / np.maximum(seg.dt[j, :n - 1, None], 1e-9)
            speeds = np.column_stack([rates[:, seg.sides == 0].mean(-1),
                                      rates[:, seg.sides == 1].mean(-1)])
            out["logged"].append(seg.gt[j, :n])
            out["nominal"].append(replay_segment(sims["nominal"], seg.t[j, :n], speeds,
                                                 seg.gt[j, 0]))
            if cand is None:
                out["extended"].append(out["nominal"][-1])
                continue
            k = int(np.searchsorted(folds, sel.folds[j]))
            if k not in sims:  # the generic vehicle is built for the log: no vehicle check
                try:
                    sims[k] = _simulator(extend(base, cand.fold_fits[k].params, nominal), hz)
                except ValueError as exc:
                    sims[k] = None
                    refused.append(f"fold {k}: {exc}")
            out["extended"].append(
                np.full((n, 3), np.nan) if sims[k] is None
                else replay_segment(sims[k], seg.t[j, :n], speeds, seg.gt[j, 0]))
    finally:
        for sim in sims.values():
            if sim is not None:
                sim.close()
    for name in ("nominal", "extended"):
        per_segment = [np.hypot(*(s[:, :2] - g[:, :2]).T)
                       for s, g in zip(out[name], out["logged"], strict=True)]
        err = np.concatenate(per_segment) if per_segment else np.zeros(1)
        err = err[np.isfinite(err)]  # a blow-up, or a fold the world could not take
        out[f"rmse_{name}_m"] = float(np.sqrt(np.mean(err**2))) if err.size else float("nan")
    out["note"] = ("Generic vehicle with the log's nominal geometry on rigid ground (mass and "
                   "chassis assumed); extended world = nominal world + the model fitted "
                   "without each segment's fold, carried in by extension.extend.")
    if refused:
        out["note"] += (" Not replayed in the extended world (the model fitted without the "
                        "fold cannot be applied to the simulation): " + "; ".join(refused))
    return out
