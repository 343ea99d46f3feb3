"""Driving the farm vehicle once and recording everything the offline filters need.

Like the paper (Lindgren §5: "the raw sensor data ... run through four different EKF
schemes"), a drive records the raw sensor frames; the filters run over them afterwards
(:mod:`.filters`). The drive is one :func:`slipenv.rollout.rollout` with a
:class:`FrameRecorder`, steered by the env's baseline path follower on the env's own EKF.
"""

from __future__ import annotations

import contextlib
import logging
from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

import gymnasium as gym
import numpy as np

from slipenv.contracts.frame import SensorFrame
from slipenv.controllers.baseline import baseline_controller
from slipenv.envs.estimation import default_k_s_prior, odometry_geometry
from slipenv.envs.slip_env import SlipEnv
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren import LindgrenEKF, LindgrenNoise, OracleSoil
from slipenv.paths import Path
from slipenv.rollout import rollout

from ..progress import step_bar
from .settings import ENV_ID, HEADLINE, STEER_SCHEME, Setting


@dataclass
class Recording:
    """One drive: every SensorFrame, the truth, and what the filters may be told.

    Attributes
    ----------
    path : Path
        The commanded path.
    frames : list of SensorFrame
        The reset's frame, then one per env step.
    t_s : np.ndarray, shape (K,)
        Frame times [s].
    truth : np.ndarray, shape (K, 3)
        True (x [m], y [m], yaw [rad]) of the reference point.
    s_true_m : np.ndarray, shape (K,)
        True progress along the path [m].
    oracle : OracleSoil
        True R_w and k_s (privileged, for the oracle filter only).
    params : LindgrenNoise
        The filters' parameters: the block's (:attr:`~.settings.Setting.noise`) and the k_s
        prior.
    geometry : OdometryGeometry
    beacons_xy : np.ndarray, shape (n_beacons, 2)
        Beacon positions [m].
    no_slip_radius_m : float or None
        One effective radius for both wheels [m], measured on a straight drive
        (:mod:`.calibration`); None: the geometry's nominal (concrete) radius.
    no_slip_radii_m : tuple of float or None
        Each side's effective radius (left, right) [m], measured on the same drive: what the
        no-slip schemes (2, 3) are given; None: the geometry's nominal (concrete) radius.
    k_s_secant_nm : float or None
        The secant torque/slip gradient measured on that drive [N m] (for the secant oracle
        variant); None without a calibration.
    """

    path: Path
    frames: list[SensorFrame]
    t_s: np.ndarray
    truth: np.ndarray
    s_true_m: np.ndarray
    oracle: OracleSoil
    params: LindgrenNoise
    geometry: OdometryGeometry
    beacons_xy: np.ndarray
    no_slip_radius_m: float | None = None
    no_slip_radii_m: tuple[float, float] | None = None
    k_s_secant_nm: float | None = None


class FrameRecorder:
    """A rollout recorder keeping each step's sensor frame, true pose and true progress [m].

    A step without a sensor frame (the env ends an episode on a physics blow-up without
    one) is an error: the offline filters need every frame.
    """

    def __init__(self) -> None:
        self.frames: list[SensorFrame] = []
        self.truth: list = []
        self.s_true_m: list[float] = []
        self._length_m = 0.0
        self._path_name = ""

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        base = env.unwrapped
        if not isinstance(base, SlipEnv):
            raise TypeError(f"FrameRecorder records a SlipEnv, got {type(base).__name__}")
        self._length_m, self._path_name = base.path.length_m, base.path.name
        self.frames, self.truth, self.s_true_m = [info["sensors"]], [info["true_pose"]], [0.0]

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        if "sensors" not in info:  # physics blow-up: nothing recorded this step
            raise RuntimeError(f"drive on {self._path_name} ended: "
                               f"{info.get('truncation_reason')}")
        self.frames.append(info["sensors"])
        self.truth.append(info["true_pose"])
        self.s_true_m.append(info["progress_true"] * self._length_m)


@contextlib.contextmanager
def quiet_estimator() -> Iterator[None]:
    """Silence the EKF's first-skip warnings (the skips are counted and reported instead)."""
    log = logging.getLogger(LindgrenEKF.__module__)
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        yield
    finally:
        log.setLevel(level)


def record(path: Path, seed: int, progress: bool = False, setting: Setting = HEADLINE,
           calibration: dict | None = None) -> Recording:
    """Drive ``path`` once in FarmField-v0 (steered on scheme 1) and record every frame.

    ``setting`` picks the world's force law and the filters' parameters; ``calibration``
    (:func:`~.calibration.calibrate`) gives the no-slip schemes their measured radii and
    the secant oracle its k_s (see :class:`Recording`).
    """
    limit_s = path.duration_s + 20.0
    world: dict[str, Any] = ({} if setting.force_model is None
                             else {"force_model": setting.force_model})
    env = gym.make(ENV_ID, path=path, estimator_kwargs={"scheme": STEER_SCHEME},
                   max_episode_s=limit_s, max_episode_steps=int(limit_s * 20.0) + 1, **world)
    with contextlib.closing(env), quiet_estimator():  # steering EKF's skips: in its extras
        base = env.unwrapped
        assert isinstance(base, SlipEnv)  # ENV_ID is a slipenv id
        beacons_xy = base.beacons_xy
        if beacons_xy is None:
            raise ValueError(f"{ENV_ID} has no beacons: the Lindgren filters need them")
        rec = FrameRecorder()
        bar = step_bar(progress, base.max_steps, f"drive {path.name}")
        rollout(env, baseline_controller(env), seed=seed, recorders=[rec], progress=bar)
        if bar is not None:
            bar.close()
        spec = base.vehicle
        return Recording(
            path=path, frames=rec.frames, t_s=np.array([f.t_s for f in rec.frames]),
            truth=np.array(rec.truth), s_true_m=np.array(rec.s_true_m),
            oracle=base.true_soil(),
            params=LindgrenNoise(k_s0=default_k_s_prior(spec), **setting.noise),
            geometry=odometry_geometry(spec), beacons_xy=beacons_xy,
            no_slip_radius_m=None if calibration is None else calibration["radius_m"],
            no_slip_radii_m=(None if calibration is None
                             else tuple(calibration["radius_per_side_m"])),
            k_s_secant_nm=None if calibration is None else calibration["k_s_secant_nm"])
