"""One straight drive of Reina's rover with the rear camera, FTrace and sComp (§4.2-4.3).

The rover holds its compass heading along +x at about 8 cm/s (Reina: remote control along a
straight line) on ``slipenv/Configurable-v0`` with ``estimator="scomp"``, so every step the
env renders the 5 Hz rear camera, runs FTrace and feeds sComp. A :class:`DriveRecorder` rides
along :func:`slipenv.rollout.rollout` and keeps, per step, the truth, the sensor frame and the
slip angle sComp used, and per camera frame the image's truth and FTrace's detection.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import gymnasium as gym
import numpy as np

from slipenv.envs.slip_env import SlipEnv
from slipenv.estimators.reina import FTraceSComp
from slipenv.rollout import rollout

from ..progress import step_bar
from .settings import Settings

ENV_ID = "slipenv/Configurable-v0"


def env_kwargs(cfg: Settings, test: str) -> dict:
    """``gymnasium.make`` kwargs of test ``"sideways"`` or ``"mounds"``."""
    # Both tests climb +x: the plane falls towards -x (azimuth 180°).
    if test == "sideways":
        terrain: dict = {"kind": "mounds", "slope_deg": cfg.climb_deg,
                         "downhill_azimuth_deg": 180.0, "mound_count": 0,
                         "placed_mounds": [cfg.sideways_mound], "size_m": 20.0,
                         "resolution_m": 0.05}
        length = cfg.sideways_length_m
    elif test == "mounds":
        terrain = {"kind": "mounds", "slope_deg": cfg.climb_deg, "downhill_azimuth_deg": 180.0,
                   "mound_count": cfg.mound_count,
                   "mound_height_m": cfg.mound_height_m, "mound_radius_m": cfg.mound_radius_m,
                   "size_m": cfg.mound_field_m, "clear_radius_m": 0.6, "resolution_m": 0.05}
        length = cfg.mounds_length_m
    else:
        raise ValueError(f"unknown test {test!r}; tests: sideways, mounds")
    return dict(vehicle="rover_4ws", soil="loose_sand", force_model="reina", terrain=terrain,
                path="straight", path_kwargs={"length_m": length, "speed_mps": cfg.speed_mps},
                estimator="scomp", camera_in_info=True, max_cross_track_m=50.0,
                max_episode_s=2.0 * length / cfg.speed_mps + 10.0)


class HeadingHold:
    """Constant speed, compass heading held at 0 (Ω = -k ψ̂ from the observation)."""

    def __init__(self, speed_frac: float, gain: float, yaw_rate_max: float) -> None:
        self.speed_frac, self.gain, self.yaw_rate_max = speed_frac, gain, yaw_rate_max

    def __call__(self, obs: np.ndarray) -> np.ndarray:
        yaw = math.atan2(float(obs[3]), float(obs[2]))
        turn = float(np.clip(-self.gain * yaw / self.yaw_rate_max, -1.0, 1.0))
        return np.array([self.speed_frac, turn], np.float32)


@dataclass
class Drive:
    """What one drive recorded (arrays per control step unless named per frame)."""

    test: str
    seed: int
    dt_s: float
    t_s: list = field(default_factory=list)
    true_xy: list = field(default_factory=list)
    true_yaw: list = field(default_factory=list)
    true_v_body: list = field(default_factory=list)
    true_beta: list = field(default_factory=list)
    frames: list = field(default_factory=list)  # SensorFrame per step (index 0: reset)
    beta_used: list = field(default_factory=list)  # slip angle sComp used at each step
    start: tuple = (0.0, 0.0, 0.0)
    frame_t: list = field(default_factory=list)  # per camera frame
    frame_present: list = field(default_factory=list)
    frame_angle: list = field(default_factory=list)
    detections: list = field(default_factory=list)
    frame_step: list = field(default_factory=list)
    images: list = field(default_factory=list)  # a few (step, image, detection) to draw

    def arrays(self) -> dict:
        """The per-step lists as numpy arrays."""
        return {k: np.asarray(getattr(self, k)) for k in
                ("t_s", "true_xy", "true_yaw", "true_v_body", "true_beta", "beta_used")}


class DriveRecorder:
    """Keeps a :class:`Drive` from the env's outputs (``slipenv.rollout`` recorder)."""

    def __init__(self, drive: Drive, keep_images_every: int) -> None:
        self.drive, self.keep_every = drive, max(int(keep_images_every), 1)

    @staticmethod
    def _estimator(env: gym.Env) -> FTraceSComp:
        base = env.unwrapped
        estimator = base.estimator if isinstance(base, SlipEnv) else None
        if not isinstance(estimator, FTraceSComp):
            raise TypeError("DriveRecorder records a SlipEnv that runs the scomp estimator")
        return estimator

    def _truth(self, env: gym.Env, info: dict) -> None:
        estimator = self._estimator(env)
        d = self.drive
        d.t_s.append(info["t_s"])
        d.true_xy.append(info["true_pose"][:2].copy())
        d.true_yaw.append(float(info["true_pose"][2]))
        d.true_v_body.append(info["true_velocity_body_mps"].copy())
        d.true_beta.append(info["true_slip_angle_rad"])
        d.frames.append(info["sensors"])
        d.beta_used.append(estimator.odometry.beta_rad)
        frame = info.get("trace_frame")
        if frame is not None:
            det = estimator.last_detection
            d.frame_t.append(frame.t_s)
            d.frame_present.append(frame.trace_present)
            d.frame_angle.append(frame.trace_angle_rad)
            d.detections.append(det)
            d.frame_step.append(len(d.t_s) - 1)
            if len(d.frame_t) % self.keep_every == 0:
                d.images.append((len(d.t_s) - 1, frame.image, det, frame.trace_angle_rad))

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        self.drive.start = tuple(float(v) for v in info["true_pose"])
        self._truth(env, info)

    def on_step(self, env: gym.Env, action, obs, reward, terminated, truncated,
                info: dict) -> None:
        if "t_s" in info:  # a physics blow-up's info has no truth
            self._truth(env, info)


def drive(cfg: Settings, test: str, seed: int, progress: bool = False) -> Drive:
    """Drive test ``test`` once with ``seed``; return what was recorded."""
    kwargs = env_kwargs(cfg, test)
    steps = int(math.ceil(kwargs["max_episode_s"] * 20.0))  # the id's own limit is 60 s
    env = gym.make(ENV_ID, max_episode_steps=steps, **kwargs)
    try:
        base = env.unwrapped
        assert isinstance(base, SlipEnv)  # ENV_ID is a slipenv id
        spec = base.vehicle
        policy = HeadingHold(cfg.speed_mps / spec.max_speed_mps, cfg.heading_gain,
                             spec.max_yaw_rate_rad_s)
        out = Drive(test, seed, base.control_dt_s)
        length = cfg.sideways_length_m if test == "sideways" else cfg.mounds_length_m
        n_frames = int(length / cfg.speed_mps * 5.0)
        rec = DriveRecorder(out, max(n_frames // max(cfg.frames_saved, 1), 1))
        bar = step_bar(progress, base.max_steps, f"{test} seed {seed}")
        rollout(env, policy, seed=seed, recorders=[rec], progress=bar)
        if bar is not None:
            bar.close()
    finally:
        env.close()
    return out
