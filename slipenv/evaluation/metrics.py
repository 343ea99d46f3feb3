"""Per-episode metrics of path following, all from the *true* pose the env reports in ``info``.

A :class:`TraceRecorder` (a :class:`slipenv.rollout.Recorder`) keeps the true and estimated
poses, the true cross-track error and the drive energy of one episode; :func:`episode_metrics`
turns that trace into numbers, and :func:`aggregate` turns a list of per-episode numbers into
the evaluation's summary (the mean over episodes, ``success_rate`` the fraction of successes).

Energy
    E = ∫ Σ_k |τ_k ω_k| dt over the drive channels k [J]. The env's ``info`` carries the
    torque sensors' readings (``info["sensors"].wheel_torque_nm``, with 5 % noise and the
    sensor's scale ``config.sensor_noise.torque_scale``, divided out here) but not the wheel
    speeds, so ω_k dt is taken from the encoder increments Δn_k / (counts per rad): the
    encoders count the true wheel rotation, quantised. The step's torque is the one measured
    at its end (rectangle rule). NaN when the vehicle has no torque sensor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, Protocol, cast

import gymnasium as gym
import numpy as np

from slipenv.envs.config import SlipEnvConfig
from slipenv.evaluation.trajectory import ape_translation, rmse, rpe_translation
from slipenv.vehicles.spec import VehicleSpec

RPE_DELTA_STEPS = 20
"""RPE pose separation Δ [env steps] (1 s at the envs' 20 Hz)."""

LOWER_IS_BETTER = (
    "cross_track_rmse_m", "mean_cross_track_m", "max_cross_track_m", "energy_j",
    "odometry_final_error_m", "odometry_mean_error_m", "ape_rmse_m", "rpe_rmse_m",
)
HIGHER_IS_BETTER = ("success_rate", "progress", "episode_return")
METRICS = ("cross_track_rmse_m", "mean_cross_track_m", "max_cross_track_m", "success_rate",
           "energy_j", "odometry_final_error_m", "odometry_mean_error_m", "ape_rmse_m",
           "rpe_rmse_m", "progress", "episode_return", "duration_s")
"""Summary metrics, in table order."""


@dataclass
class EpisodeTrace:
    """What one episode leaves behind (arrays over the reset and every step)."""

    seed: int | None
    t_s: list[float] = field(default_factory=list)
    true_pose: list[np.ndarray] = field(default_factory=list)
    est_pose: list[np.ndarray] = field(default_factory=list)
    cross_track_m: list[float] = field(default_factory=list)
    progress: float = 0.0
    energy_j: float = 0.0
    steps: int = 0
    episode_return: float = 0.0
    success: bool = False
    end_reason: str = ""

    def arrays(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(t_s (n,), true_pose (n, 3), est_pose (n, 3))`` as arrays."""
        return (np.asarray(self.t_s, dtype=float), np.asarray(self.true_pose).reshape(-1, 3),
                np.asarray(self.est_pose).reshape(-1, 3))


class _Recorded(Protocol):
    """What :class:`TraceRecorder` reads from the env: a ``SlipEnv``, or a stand-in."""

    @property
    def config(self) -> SlipEnvConfig: ...

    @property
    def vehicle(self) -> VehicleSpec: ...


class TraceRecorder:
    """Rollout recorder filling an :class:`EpisodeTrace` from the env's ``info``."""

    def __init__(self, seed: int | None) -> None:
        self.trace = EpisodeTrace(seed=seed)
        self._enc: np.ndarray | None = None
        self._counts_per_rad = 1.0
        self._torque_scale = 1.0

    def _pose(self, info: dict) -> None:
        if "true_pose" not in info or "estimated_pose" not in info:
            return  # a physics blow-up step carries no state
        self.trace.t_s.append(float(info.get("t_s", math.nan)))
        self.trace.true_pose.append(np.asarray(info["true_pose"], dtype=float).copy())
        self.trace.est_pose.append(np.asarray(info["estimated_pose"], dtype=float).copy())

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        # gymnasium types ``unwrapped`` as a plain Env; this recorder needs only these two
        base = cast(_Recorded, env.unwrapped)
        noise = base.config.sensor_noise
        self._counts_per_rad = float(getattr(noise, "counts_per_rad", None)
                                     or base.vehicle.counts_per_rad)
        self._torque_scale = float(getattr(noise, "torque_scale", 1.0) or 1.0)
        frame = info.get("sensors")
        self._enc = None if frame is None else np.asarray(frame.enc_counts, dtype=np.int64)
        self._pose(info)

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        tr = self.trace
        tr.steps += 1
        tr.episode_return += float(reward)
        self._pose(info)
        if "cross_track_true_m" in info:
            tr.cross_track_m.append(float(info["cross_track_true_m"]))
        if "progress_true" in info:
            tr.progress = float(info["progress_true"])
        frame = info.get("sensors")
        if frame is not None and self._enc is not None:
            enc = np.asarray(frame.enc_counts, dtype=np.int64)
            d_theta = (enc - self._enc) / self._counts_per_rad  # [rad] this step
            torque = np.asarray(frame.wheel_torque_nm, dtype=float) / self._torque_scale
            tr.energy_j += float(np.sum(np.abs(torque * d_theta)))
            self._enc = enc
        tr.success = bool(info.get("is_success", False))


def episode_metrics(trace: EpisodeTrace, rpe_delta_steps: int = RPE_DELTA_STEPS,
                    ) -> dict[str, Any]:
    """The numbers of one episode.

    Returns
    -------
    dict
        ``seed``, ``steps``, ``duration_s`` [s], ``success`` (bool: path completed within the
        corridor, the env's ``info["is_success"]``), ``end_reason``, ``episode_return``,
        ``progress`` (true fraction of the path done), ``cross_track_rmse_m``,
        ``mean_cross_track_m`` (mean |e|), ``max_cross_track_m`` [m] (true cross-track e over
        the steps), ``energy_j`` [J], ``odometry_final_error_m``, ``odometry_mean_error_m``,
        ``ape_rmse_m`` [m] (estimate vs truth, no alignment), ``rpe_rmse_m`` [m per
        ``rpe_delta_steps`` steps].
    """
    t_s, truth, est = trace.arrays()
    ct = np.abs(np.asarray(trace.cross_track_m, dtype=float))
    ape = ape_translation(est, truth) if len(truth) else np.zeros(0)
    rpe = rpe_translation(est, truth, rpe_delta_steps) if len(truth) else np.zeros(0)
    nan = float("nan")
    return {
        "seed": trace.seed,
        "steps": int(trace.steps),
        "duration_s": float(t_s[-1] - t_s[0]) if len(t_s) > 1 else 0.0,
        "success": bool(trace.success),
        "end_reason": trace.end_reason,
        "episode_return": float(trace.episode_return),
        "progress": float(trace.progress),
        "cross_track_rmse_m": rmse(ct),
        "mean_cross_track_m": float(np.mean(ct)) if ct.size else nan,
        "max_cross_track_m": float(np.max(ct)) if ct.size else nan,
        "energy_j": float(trace.energy_j),
        "odometry_final_error_m": float(ape[-1]) if ape.size else nan,
        "odometry_mean_error_m": float(np.mean(ape)) if ape.size else nan,
        "ape_rmse_m": rmse(ape),
        "rpe_rmse_m": rmse(rpe),
    }


def aggregate(per_episode: list[dict[str, Any]]) -> dict[str, float]:
    """Summary over episodes: the mean of each metric (NaN if any episode's is NaN), and
    ``success_rate``, the fraction of episodes with ``success``."""
    if not per_episode:
        raise ValueError("aggregate needs at least one episode")
    out: dict[str, float] = {}
    for name in METRICS:
        if name == "success_rate":
            out[name] = float(np.mean([bool(ep["success"]) for ep in per_episode]))
        else:
            out[name] = float(np.mean([float(ep[name]) for ep in per_episode]))
    return out


def spread(per_episode: list[dict[str, Any]]) -> dict[str, float]:
    """Standard deviation over episodes of each metric (population, ddof = 0)."""
    out = {}
    for name in METRICS:
        key = "success" if name == "success_rate" else name
        out[name] = float(np.std([float(ep[key]) for ep in per_episode]))
    return out


def worst_episode(per_episode: list[dict[str, Any]], name: str) -> dict[str, Any]:
    """The episode doing worst on metric ``name`` (highest error, or lowest success/progress)."""
    key = "success" if name == "success_rate" else name
    if key not in per_episode[0]:
        raise ValueError(f"unknown metric {name!r}; metrics: {', '.join(METRICS)}")
    values = [float(ep[key]) for ep in per_episode]
    # NaN is the worst of all: it means the metric could not be computed.
    if any(math.isnan(v) for v in values):
        return per_episode[next(k for k, v in enumerate(values) if math.isnan(v))]
    pick = np.argmin if name in HIGHER_IS_BETTER or key == "success" else np.argmax
    return per_episode[int(pick(values))]
