"""Export simulated runs as slipenv-log/1 logs (``log-format.md``).

Every simulated episode can become a measured-style log: wheel commands, encoder counts,
torques, IMU, inclinometer, compass and the ground-truth pose, with a ``meta.json`` holding the
vehicle's *nominal* geometry (what an operator believes) and the terrain. Two entry points:

- :func:`export_episode` runs a ``SlipEnv`` episode (a policy or a list of actions) through the
  one rollout loop with an :class:`ExportRecorder`, which records its sensor frames
  (``info["sensors"]``) and true pose (``info["true_pose"]``); the recorder also rides along
  any other ``rollout`` call;
- :class:`LogRecorder` collects frames from a bare :class:`~slipenv.sim.simulator.Simulator`
  loop (``record(t, frame, truth, commands)``) and builds the log.

The sensor readings are the simulation's own (with its noise); ground truth is exact unless the
caller adds noise. Columns can be left out (``columns=``) to mimic vehicles without a torque
sensor or an IMU.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable, Iterable
from typing import Any

import gymnasium as gym
import numpy as np

from slipenv.contracts.frame import SensorFrame
from slipenv.logs.log import Log
from slipenv.logs.meta import LogMeta
from slipenv.rollout import PolicyPredictor, rollout
from slipenv.terrain.terrain import TerrainSpec
from slipenv.vehicles.kinematics import twist_to_commands
from slipenv.vehicles.spec import VehicleSpec

OPTIONAL_GROUPS = ("cmd", "torque", "imu", "attitude", "heading")
"""Column groups that may be left out: ``cmd_*``, ``torque_*``, ``gyro_z/acc_x/acc_y``,
``roll/pitch``, ``heading``."""


def meta_for(spec: VehicleSpec, terrain: TerrainSpec | None = None, soil: str = "rigid",
             counts_per_rad: float | None = None, notes: str = "", **extra: Any) -> LogMeta:
    """``meta.json`` for a simulated vehicle: wheels = drive channels, nominal geometry."""
    terrain = terrain or TerrainSpec()
    slope = terrain.plane_slope_deg
    n_mounds = terrain.mound_count + len(terrain.placed_mounds)
    description = {"flat": "flat plane", "slope": f"planar slope {slope:g}°",
                   "mounds": f"{n_mounds} Gaussian mounds"
                             + (f" on a {slope:g}° slope" if slope else "")}[terrain.kind]
    return LogMeta.new(
        spec.kind, list(spec.channels), wheel_radius_m=spec.wheel_radius_nominal_m,
        track_width_m=spec.track_width_m,
        counts_per_rad=float(counts_per_rad or spec.counts_per_rad),
        wheelbase_m=spec.wheelbase_m, mass_kg=spec.mass_kg,
        terrain_description=f"simulated: {description}", soil=soil, slope_deg=slope,
        slope_downhill_azimuth_deg=terrain.downhill_azimuth_deg if slope else None,
        notes=notes or f"exported from a slipenv simulation ({spec.name})", **extra,
    )


class LogRecorder:
    """Accumulates one row per control step and builds a :class:`Log`.

    Parameters
    ----------
    meta : LogMeta
        From :func:`meta_for` (or any meta whose wheels are the vehicle's channels).
    columns : iterable of str, optional
        Optional column groups to keep (subset of ``OPTIONAL_GROUPS``); default all.
    """

    def __init__(self, meta: LogMeta, columns: Iterable[str] | None = None) -> None:
        keep = set(OPTIONAL_GROUPS if columns is None else columns)
        _check_columns(keep)
        self.meta, self.keep = meta, keep
        self.rows: list[dict[str, float]] = []

    def record(self, frame: SensorFrame, pose: Iterable[float] | None,
               commands: Iterable[float] | None = None,
               steer: Iterable[float] | None = None) -> None:
        """Add the sample of ``frame`` with the true pose ``(x, y, yaw)`` (None = not measured).

        ``commands`` are the channel speed commands [rad/s] in force over the step that ended
        at this frame; ``steer`` the steering angle of each wheel column (``rover4ws``).
        """
        wheels = self.meta.wheels
        row: dict[str, float] = {"t": float(frame.t_s)}
        if "cmd" in self.keep:
            cmd = list(commands) if commands is not None else [math.nan] * len(wheels)
            row.update({f"cmd_{w}": float(c) for w, c in zip(wheels, cmd, strict=True)})
        row.update({f"enc_{w}": float(c) for w, c in zip(wheels, frame.enc_counts, strict=True)})
        if "torque" in self.keep:
            row.update({f"torque_{w}": float(q)
                        for w, q in zip(wheels, frame.wheel_torque_nm, strict=True)})
        if self.meta.kind == "rover4ws":
            angles = list(steer) if steer is not None else [0.0] * len(wheels)
            row.update({f"steer_{w}": float(a) for w, a in zip(wheels, angles, strict=True)})
        if "imu" in self.keep:
            row.update(gyro_z=frame.gyro_z_rad_s, acc_x=frame.acc_x_mps2, acc_y=frame.acc_y_mps2)
        if "attitude" in self.keep:
            row.update(roll=frame.roll_rad, pitch=frame.pitch_rad)
        if "heading" in self.keep:
            row["heading"] = frame.heading_rad
        x, y, yaw = (math.nan,) * 3 if pose is None else tuple(float(v) for v in pose)
        row.update(gt_x=x, gt_y=y, gt_yaw=yaw)
        self.rows.append(row)

    def to_log(self) -> Log:
        """The validated log (``LogFormatError`` if it breaks the contract)."""
        if not self.rows:
            raise ValueError("nothing recorded")
        names = list(self.rows[0])
        cols = {n: np.array([r[n] for r in self.rows], dtype=float) for n in names}
        return Log.from_arrays(self.meta, require_ground_truth=True, **cols)


class ExportRecorder:
    """Rollout recorder that turns an episode into a slipenv-log/1 log.

    Keeps the reset sample and one row per step: the sensor frame (``info["sensors"]``), the
    true pose (``info["true_pose"]``) and the channel speed commands [rad/s] (and steering
    angles) that the step's action became through the vehicle's nominal kinematics — the same
    conversion the env applies. A step without a sensor frame (a physics blow-up) is not kept.

    Parameters
    ----------
    columns : iterable of str, optional
        Optional column groups to keep (``OPTIONAL_GROUPS``); default all.
    notes : str
        ``meta.json`` notes.
    seed : int, optional
        Recorded in ``meta.json`` (``simulation.seed``).
    """

    def __init__(self, columns: Iterable[str] | None = None, notes: str = "",
                 seed: int | None = None) -> None:
        self.columns = None if columns is None else list(columns)
        self.notes, self.seed = notes, seed
        self._rec: LogRecorder | None = None
        self._spec: VehicleSpec | None = None
        if self.columns is not None:  # fail before the episode runs
            _check_columns(self.columns)

    def on_reset(self, env, obs: np.ndarray, info: dict) -> None:
        base = env.unwrapped
        spec, cfg = base.vehicle, base.config
        soil = cfg.soil if isinstance(cfg.soil, str) else getattr(cfg.soil, "name", "custom")
        meta = meta_for(spec, cfg.terrain, soil, counts_per_rad=cfg.sensor_noise.counts_per_rad,
                        notes=self.notes,
                        simulation={"env": getattr(env.spec, "id", None), "seed": self.seed,
                                    "vehicle": spec.name, "soil": soil})
        self._spec = spec
        self._rec = LogRecorder(meta, self.columns)
        self._rec.record(info["sensors"], info["true_pose"], np.zeros(len(spec.channels)))

    def on_step(self, env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        if self._rec is None or self._spec is None:
            raise RuntimeError("ExportRecorder.on_step before on_reset")
        if "sensors" not in info:  # a physics blow-up ends the episode without a frame
            return
        spec = self._spec
        a = np.clip(np.asarray(action, dtype=float).reshape(-1), -1.0, 1.0)
        speeds, steer = twist_to_commands(spec, a[0] * spec.max_speed_mps,
                                          a[1] * spec.max_yaw_rate_rad_s)
        self._rec.record(info["sensors"], info["true_pose"], speeds, _channel_steer(spec, steer))

    def to_log(self) -> Log:
        """The validated log of the last episode."""
        if self._rec is None:
            raise ValueError("nothing recorded")
        return self._rec.to_log()


def _check_columns(columns: Iterable[str]) -> None:
    unknown = set(columns) - set(OPTIONAL_GROUPS)
    if unknown:
        raise ValueError(f"unknown column group(s) {sorted(unknown)}; choose from "
                         f"{OPTIONAL_GROUPS}")


class _ActionSequence:
    """A fixed list of actions as a policy (``rollout`` stops when it is used up)."""

    def __init__(self, actions: list[Any]) -> None:
        self.actions, self.k = actions, 0

    def __call__(self, obs: np.ndarray) -> Any:
        action = self.actions[self.k]
        self.k += 1
        return action


def export_episode(env: gym.Env,
                   policy: PolicyPredictor | Callable[[np.ndarray], Any] | None = None,
                   actions: Iterable[Any] | None = None, seed: int | None = None,
                   max_steps: int | None = None, columns: Iterable[str] | None = None,
                   notes: str = "") -> Log:
    """Run one ``SlipEnv`` episode (in :func:`slipenv.rollout.rollout`) and return it as a log.

    Parameters
    ----------
    env : gymnasium.Env
        A slipenv env (wrappers allowed).
    policy : callable, optional
        ``policy(obs) -> action``; or anything with ``predict(obs)`` (SB3 style).
    actions : iterable, optional
        A fixed action sequence instead of a policy.
    seed : int, optional
        Passed to ``reset``.
    max_steps : int, optional
        Stop after this many steps (default: the episode's end).
    columns : iterable of str, optional
        Optional column groups to keep (``OPTIONAL_GROUPS``).
    """
    if (policy is None) == (actions is None):
        raise ValueError("give exactly one of policy and actions")
    recorder = ExportRecorder(columns, notes=notes, seed=seed)
    if actions is not None:
        feed = list(actions if max_steps is None else itertools.islice(actions, max_steps))
        if not feed:
            raise ValueError("actions is empty")
        policy = _ActionSequence(feed)
        max_steps = len(feed)
    assert policy is not None  # exactly one of policy and actions, checked above
    rollout(env, policy, seed=seed, max_steps=max_steps, recorders=[recorder])
    return recorder.to_log()


def _channel_steer(spec: VehicleSpec, steer: list[float]) -> list[float]:
    """Steering angle per channel (rover4ws channels are wheels) from the per-wheel list."""
    by_channel = {w.channel: a for w, a in zip(spec.wheels, steer, strict=True)}
    return [by_channel.get(c, 0.0) for c in spec.channels]
