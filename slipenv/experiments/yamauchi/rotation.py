"""The rotation runs of Yamauchi §2.3: from rest, a constant twist (5 cm/s and 10/20/30 °/s)
until the vehicle has turned about 90°, from a heading across the slope
(``Settings.start_heading_deg``), turning either way.

Each run is one :func:`slipenv.rollout.rollout` of the tracked env with a constant action,
a :class:`TurnLimit` wrapper that ends it at 90° and an :class:`InfoRecorder` that keeps the
sensor frames and the ground truth (the paper's motion capture).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

from slipenv.contracts import wrap_angle
from slipenv.envs.slip_env import SlipEnv
from slipenv.estimators.skid_steer.identification import train_test_split_runs
from slipenv.paths import straight
from slipenv.rollout import rollout

from ..progress import iterate
from .settings import Settings
from .world import make_world

RECORDED = ("sensors", "t_s", "true_pose", "true_velocity_body_mps", "true_yaw_rate_rps",
            "true_slip_angle_rad")
"""The ``info`` entries a rotation run keeps, at the reset and at every step."""


@dataclass
class RotationRun:
    """One rotation run: sensor frames and ground truth at each control step (k samples).

    Attributes
    ----------
    name : str
        ``tilt{deg}_rate{deg/s}_{ccw|cw}_{repeat}``.
    tilt_deg, rate_dps : float
        Slope [deg] and commanded turn rate [deg/s].
    direction : int
        +1 counter-clockwise, -1 clockwise.
    frames : list of SensorFrame
    t_s : np.ndarray, shape (k,)
        Times [s].
    pose : np.ndarray, shape (k, 3)
        True x, y, yaw [m, m, rad].
    v_body : np.ndarray, shape (k, 2)
        True body-frame velocity of the reference point [m/s].
    yaw_rate : np.ndarray, shape (k,)
        True yaw rate [rad/s].
    slip_angle : np.ndarray, shape (k,)
        True body slip angle [rad] (the simulator's definition).
    """

    name: str
    tilt_deg: float
    rate_dps: float
    direction: int
    frames: list
    t_s: np.ndarray
    pose: np.ndarray
    v_body: np.ndarray
    yaw_rate: np.ndarray
    slip_angle: np.ndarray


class InfoRecorder:
    """A rollout recorder keeping the ``info`` entries ``keys`` of the reset and every step."""

    def __init__(self, keys: tuple[str, ...] = RECORDED) -> None:
        self.keys = keys
        self.rows: dict[str, list] = {k: [] for k in keys}

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        self.rows = {k: [info[k]] for k in self.keys}

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        for k in self.keys:
            self.rows[k].append(info[k])


class TurnLimit(gym.Wrapper):
    """Truncates the episode once the true heading has turned ``limit_rad`` [rad] either way
    since the reset (summing wrapped per-step heading changes)."""

    def __init__(self, env: gym.Env, limit_rad: float) -> None:
        super().__init__(env)
        if not limit_rad > 0.0:
            raise ValueError(f"limit_rad must be > 0, got {limit_rad}")
        self.limit_rad = limit_rad
        self.turned_rad = 0.0
        self._yaw = 0.0

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self.turned_rad, self._yaw = 0.0, float(info["true_pose"][2])
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        yaw = float(info["true_pose"][2])
        self.turned_rad += wrap_angle(yaw - self._yaw)
        self._yaw = yaw
        if abs(self.turned_rad) >= self.limit_rad and not (terminated or truncated):
            truncated = True
            info = {**info, "truncation_reason": "turned"}
        return obs, reward, terminated, truncated, info


def rotation_run(cfg: Settings, tilt_deg: float, rate_dps: float, direction: int, seed: int,
                 heading_rad: float, name: str) -> RotationRun:
    """Drive a constant twist (``cfg.speed_mps``, ±``rate_dps``) from rest until the true
    heading has turned ``cfg.rotation_deg``, or ``cfg.max_rotation_s`` has passed."""
    env = make_world(tilt_deg, cfg.soil, cfg.vehicle,
                     path=straight(5.0, cfg.speed_mps, heading_rad),
                     estimator="gyrodometry", estimator_kwargs={}, max_cross_track_m=10.0)
    base = env.unwrapped
    assert isinstance(base, SlipEnv)  # make_world makes a slipenv id
    spec, dt_s = base.vehicle, base.control_dt_s
    action = np.array([cfg.speed_mps / spec.max_speed_mps,
                       direction * math.radians(rate_dps) / spec.max_yaw_rate_rad_s],
                      dtype=np.float32)
    rec = InfoRecorder()
    limited = TurnLimit(env, math.radians(cfg.rotation_deg))
    rollout(limited, lambda obs: action, seed=seed, recorders=[rec],
            max_steps=int(cfg.max_rotation_s / dt_s))
    limited.close()
    rows = rec.rows
    return RotationRun(
        name=name, tilt_deg=tilt_deg, rate_dps=rate_dps, direction=direction,
        frames=rows["sensors"], t_s=np.array(rows["t_s"]), pose=np.array(rows["true_pose"]),
        v_body=np.array(rows["true_velocity_body_mps"]),
        yaw_rate=np.array(rows["true_yaw_rate_rps"]),
        slip_angle=np.array(rows["true_slip_angle_rad"]),
    )


def collect_runs(cfg: Settings, rng: np.random.Generator, progress: bool) -> list[RotationRun]:
    """Every rotation run of the experiment (seeded start-heading jitter around
    ``cfg.start_heading_deg`` and sensor noise)."""
    plan = [(t, w, d, i) for t in cfg.tilts_deg for w in cfg.turn_rates_dps
            for d in cfg.directions for i in range(cfg.repeats)]
    seeds = rng.integers(0, 2**31 - 1, size=len(plan))
    jitter = rng.uniform(-1.0, 1.0, size=len(plan)) * math.radians(cfg.heading_jitter_deg)
    jitter += math.radians(cfg.start_heading_deg)
    steps = zip(iterate(plan, progress, "rotation runs"), seeds, jitter, strict=True)
    return [rotation_run(cfg, t, w, d, int(s), float(h),
                         f"tilt{t:g}_rate{w:g}_{'ccw' if d > 0 else 'cw'}_{i}")
            for (t, w, d, i), s, h in steps]


def split_runs(runs: list[RotationRun], cfg: Settings,
               rng: np.random.Generator) -> tuple[list, list]:
    """Hold out ``test_fraction`` of the runs of every (tilt, direction) group, by run."""
    train, test = [], []
    for t in cfg.tilts_deg:
        for d in cfg.directions:
            group = [r for r in runs if r.tilt_deg == t and r.direction == d]
            a, b = train_test_split_runs(group, cfg.test_fraction, rng)
            train += a
            test += b
    return train, test
