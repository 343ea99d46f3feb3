"""The main job: a baseline controller drives one episode; a table and a trajectory plot.

``slipenv run ENV_ID`` calls :func:`run_episode` then :func:`summarize` and
:func:`plot_episode`. The controller is used exactly as an RL agent would be: through
``predict(obs)`` on the env's observation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from pathlib import Path as FsPath
from typing import Any

import gymnasium as gym
import numpy as np

from slipenv.contracts.angles import wrap_angle
from slipenv.controllers import controller_by_name
from slipenv.controllers.yamauchi import YamauchiController
from slipenv.envs.estimation import odometry_geometry
from slipenv.estimators.dead_reckoning import DeadReckoning


@dataclass
class EpisodeRecord:
    """Everything recorded along one episode (arrays over steps)."""

    env_id: str
    seed: int
    t_s: np.ndarray
    true_pose: np.ndarray
    est_pose: np.ndarray
    cross_track_true_m: np.ndarray
    wheel_slip: np.ndarray
    slip_angle_rad: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    reference_xy: np.ndarray
    end_reason: str
    wheel_names: tuple[str, ...] = ()
    dead_reckoning_xy: np.ndarray | None = None
    info_last: dict = field(default_factory=dict)


def baseline_controller(env: gym.Env, name: str = "yamauchi", **kwargs: Any):
    """The path-following baseline with gains scaled to the env's reference speed.

    Gains place a triple pole at p = clip(v_ref / 0.6 m, 0.15, 1.0) rad/s (Yamauchi §3
    law, ``YamauchiController.from_poles``): a pole tied to the time it takes to cover about
    one vehicle length, so a 5 cm/s tracked vehicle and a 1 m/s Husky get the same behaviour
    per metre travelled.
    """
    base = env.unwrapped
    spec = base.vehicle
    common = dict(v_max_mps=spec.max_speed_mps, omega_max_rps=spec.max_yaw_rate_rad_s,
                  dt_s=base.control_dt_s)
    if name == "yamauchi":
        v_ref = max(float(base.path.speed_at(0.0)), 1e-3)
        pole = min(max(v_ref / 0.6, 0.15), 1.0)
        return YamauchiController.from_poles(pole, v_ref, **common, **kwargs)
    return controller_by_name(name, **common, **kwargs)


def run_episode(env_id: str, seed: int = 0, controller: str = "yamauchi",
                max_steps: int | None = None, progress: bool = False,
                controller_kwargs: dict | None = None, **env_kwargs: Any) -> EpisodeRecord:
    """Drive one episode of ``env_id`` with a baseline controller and record it."""
    env = gym.make(env_id, **env_kwargs)
    try:
        policy = baseline_controller(env, controller, **(controller_kwargs or {}))
        obs, info = env.reset(seed=seed)
        policy.reset()
        limit = max_steps or env.spec.max_episode_steps or 10_000
        rows: dict[str, list] = {k: [] for k in (
            "t", "true", "est", "ct", "slip", "beta", "act", "rew")}
        spec = env.unwrapped.vehicle
        driven = [k for k, w in enumerate(spec.wheels) if w.role == "driven"]
        # Plain dead reckoning on the very same sensor frames: what slip does to naive odometry.
        naive = DeadReckoning(odometry_geometry(spec))
        naive.reset(*info["true_pose"], info["sensors"])
        naive_xy = []
        bar = None
        if progress:
            from tqdm import tqdm
            bar = tqdm(total=limit, desc=env_id, unit="step", leave=False)
        end = "step limit"
        for _ in range(limit):
            action, _ = policy.predict(obs, deterministic=True)
            obs, reward, terminated, truncated, info = env.step(action)
            rows["t"].append(info.get("t_s", math.nan))
            rows["true"].append(info.get("true_pose", np.full(3, np.nan)))
            rows["est"].append(info.get("estimated_pose", np.full(3, np.nan)))
            rows["ct"].append(info.get("cross_track_true_m", math.nan))
            rows["slip"].append(info["wheel_slip"][driven])
            estimate = naive.update(info["sensors"])
            naive_xy.append((estimate.x_m, estimate.y_m))
            rows["beta"].append(info.get("true_slip_angle_rad", math.nan))
            rows["act"].append(np.asarray(action))
            rows["rew"].append(reward)
            if bar is not None:
                bar.update(1)
            if terminated or truncated:
                end = (info.get("termination_reason") or info.get("truncation_reason")
                       or ("path complete" if info.get("is_success") else "terminated"))
                break
        if bar is not None:
            bar.close()
        path = env.unwrapped.path
        samples = path.sample(0.05)
        return EpisodeRecord(
            env_id=env_id, seed=seed, t_s=np.array(rows["t"]), true_pose=np.array(rows["true"]),
            est_pose=np.array(rows["est"]), cross_track_true_m=np.array(rows["ct"]),
            wheel_slip=np.array(rows["slip"]), slip_angle_rad=np.array(rows["beta"]),
            actions=np.array(rows["act"]), rewards=np.array(rows["rew"]),
            reference_xy=np.stack([samples.x_m, samples.y_m], axis=1), end_reason=end,
            wheel_names=tuple(spec.wheels[k].name for k in driven),
            dead_reckoning_xy=np.array(naive_xy),
            info_last={k: v for k, v in info.items() if k != "sensors"},
        )
    finally:
        env.close()


def summarize(rec: EpisodeRecord) -> dict[str, float]:
    """Cross-track, slip and odometry statistics of an episode."""
    ct = rec.cross_track_true_m
    err = np.hypot(*(rec.est_pose[:, :2] - rec.true_pose[:, :2]).T)
    naive = np.hypot(*(rec.dead_reckoning_xy - rec.true_pose[:, :2]).T)
    slip = np.abs(rec.wheel_slip)
    return {
        "duration_s": float(rec.t_s[-1]) if len(rec.t_s) else 0.0,
        "cross_track_rmse_m": float(np.sqrt(np.mean(ct**2))),
        "cross_track_mean_abs_m": float(np.mean(np.abs(ct))),
        "cross_track_max_m": float(np.max(np.abs(ct))),
        "wheel_slip_mean": float(np.mean(slip)),
        "wheel_slip_p95": float(np.percentile(slip, 95)),
        "slip_angle_mean_abs_deg": float(np.degrees(np.mean(np.abs(rec.slip_angle_rad)))),
        "odometry_final_error_m": float(err[-1]),
        "odometry_mean_error_m": float(np.mean(err)),
        "dead_reckoning_final_error_m": float(naive[-1]),
        "odometry_final_heading_error_deg": float(np.degrees(abs(
            wrap_angle(rec.est_pose[-1, 2] - rec.true_pose[-1, 2])))),
        "return": float(np.sum(rec.rewards)),
    }


def format_table(stats: dict[str, float], title: str) -> str:
    """A plain two-column table."""
    width = max(len(k) for k in stats)
    lines = [title, "-" * (width + 14)]
    lines += [f"{k:<{width}}  {v:>12.4f}" for k, v in stats.items()]
    return "\n".join(lines)


def plot_episode(rec: EpisodeRecord, out_png: str | FsPath) -> FsPath:
    """Trajectory (reference, truth, odometry), cross-track error and wheel slip over time."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = FsPath(out_png)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    ax = axes[0]
    ax.plot(*rec.reference_xy.T, "k--", lw=1, label="reference path")
    ax.plot(rec.true_pose[:, 0], rec.true_pose[:, 1], "C0", lw=2, label="true trajectory")
    ax.plot(rec.est_pose[:, 0], rec.est_pose[:, 1], "C3", lw=1.2, label="estimate (observation)")
    if rec.dead_reckoning_xy is not None:
        ax.plot(*rec.dead_reckoning_xy.T, "C7", lw=1, ls=":", label="plain dead reckoning")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{rec.env_id} (seed {rec.seed})")
    ax.legend(loc="best", fontsize=8)
    axes[1].plot(rec.t_s, rec.cross_track_true_m, "C0")
    axes[1].axhline(0, color="k", lw=0.5)
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylabel("true cross-track error [m]")
    for k in range(rec.wheel_slip.shape[1]):
        name = rec.wheel_names[k] if k < len(rec.wheel_names) else f"wheel {k}"
        axes[2].plot(rec.t_s, rec.wheel_slip[:, k], lw=0.8, label=name)
    axes[2].set_xlabel("t [s]")
    axes[2].set_ylabel("true slip ratio")
    if rec.wheel_slip.shape[1] <= 6:
        axes[2].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
