"""The main job: a baseline controller drives one episode; a table and a trajectory plot.

``slipenv run ENV_ID`` calls :func:`run_episode` then :func:`summarize`, :func:`completion_text`
and :func:`plot_episode`. The controller is used exactly as an RL agent would be: through
``predict(obs)`` on the env's observation, in the one rollout loop (:mod:`slipenv.rollout`),
with an :class:`EpisodeRecorder` keeping what the table and the plot need. Whether the path was
completed is judged on the true pose (the env's ``info["is_success"]``); the estimate's own
view is reported beside it.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from pathlib import Path as FsPath
from typing import Any

import gymnasium as gym
import numpy as np

from slipenv.contracts.angles import wrap_angle
from slipenv.controllers.baseline import BASELINE_NAMES, baseline_controller
from slipenv.envs.estimation import odometry_geometry
from slipenv.envs.slip_env import SlipEnv
from slipenv.estimators.dead_reckoning import DeadReckoning
from slipenv.rollout import RolloutResult, Trajectory, TrajectoryRecorder, rollout

__all__ = ["BASELINE_NAMES", "EpisodeRecord", "EpisodeRecorder", "completion_text",
           "format_table", "plot_episode", "run_episode", "summarize"]


@dataclass(frozen=True, kw_only=True)
class EpisodeRecord(Trajectory):
    """A :class:`~slipenv.rollout.Trajectory` of the driven wheels plus what the main job
    reports: the reference path, how the episode ended, and plain dead reckoning on the same
    sensor frames."""

    env_id: str
    seed: int
    reference_xy: np.ndarray
    end_reason: str
    dead_reckoning_xy: np.ndarray | None = None
    info_last: dict = field(default_factory=dict)
    success: bool = False


class EpisodeRecorder:
    """Rollout recorder of the main job: a :class:`~slipenv.rollout.TrajectoryRecorder` plus
    plain dead reckoning run on the very same sensor frames (what slip does to naive odometry).

    Use :meth:`record` after the rollout to get the :class:`EpisodeRecord`.
    """

    def __init__(self, env_id: str, seed: int) -> None:
        self.env_id, self.seed = env_id, seed
        self.trajectory = TrajectoryRecorder()
        self._naive: DeadReckoning | None = None
        self._naive_xy: list[tuple[float, float]] = []
        self._info_last: dict = {}
        self._reference_xy = np.zeros((0, 2))

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        self.trajectory.on_reset(env, obs, info)
        base = env.unwrapped
        if not isinstance(base, SlipEnv):
            raise TypeError(f"EpisodeRecorder records a SlipEnv, got {type(base).__name__}")
        self._naive = DeadReckoning(odometry_geometry(base.vehicle))
        self._naive.reset(*info["true_pose"], info["sensors"])
        self._naive_xy = []
        samples = base.path.sample(0.05)
        self._reference_xy = np.stack([samples.x_m, samples.y_m], axis=1)
        self._info_last = {}

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        self.trajectory.on_step(env, action, obs, reward, terminated, truncated, info)
        self._info_last = {k: v for k, v in info.items() if k != "sensors"}
        if "sensors" in info and self._naive is not None:
            estimate = self._naive.update(info["sensors"])
            self._naive_xy.append((estimate.x_m, estimate.y_m))

    def record(self, result: RolloutResult) -> EpisodeRecord:
        """The :class:`EpisodeRecord` of the episode that ``result`` ended."""
        traj = self.trajectory.trajectory()
        driven = traj.driven()
        return EpisodeRecord(
            env_id=self.env_id, seed=self.seed, t_s=traj.t_s, true_pose=traj.true_pose,
            est_pose=traj.est_pose, cross_track_true_m=traj.cross_track_true_m,
            wheel_slip=traj.wheel_slip[:, driven], slip_angle_rad=traj.slip_angle_rad,
            actions=traj.actions, rewards=traj.rewards, reference_xy=self._reference_xy,
            end_reason=result.end_reason,
            wheel_names=tuple(traj.wheel_names[k] for k in driven),
            dead_reckoning_xy=np.array(self._naive_xy).reshape(-1, 2),
            info_last=self._info_last,
            wheel_channels=tuple(traj.wheel_channels[k] for k in driven),
            success=result.success, progress_true=traj.progress_true,
            progress_est=traj.progress_est,
        )


def run_episode(env_id: str, seed: int = 0, controller: str = "yamauchi",
                max_steps: int | None = None, progress: bool = False,
                controller_kwargs: dict | None = None, **env_kwargs: Any) -> EpisodeRecord:
    """Drive one episode of ``env_id`` with a baseline controller and record it.

    Parameters
    ----------
    env_id : str
        A registered id.
    seed : int
        Reset seed.
    controller : str
        One of :data:`~slipenv.controllers.baseline.BASELINE_NAMES`.
    max_steps : int, optional
        Stop earlier than the env's time limit (>= 1).
    progress : bool
        Show a tqdm bar.
    controller_kwargs, **env_kwargs
        Passed to :func:`~slipenv.controllers.baseline.baseline_controller` and ``gym.make``.
    """
    env = gym.make(env_id, **env_kwargs)
    bar = None
    try:
        policy = baseline_controller(env, controller, **(controller_kwargs or {}))
        recorder = EpisodeRecorder(env_id, seed)
        if progress:
            from tqdm import tqdm

            base = env.unwrapped
            assert isinstance(base, SlipEnv)  # baseline_controller has checked it
            from slipenv.envs.compiled import KERNELS, kernels_used, warm_up

            compiled = kernels_used(env)
            if compiled:
                # Otherwise the first step stalls silently while numba compiles them.
                print(f"preparing {' and '.join(KERNELS[k] for k in compiled)} (numba compiles "
                      "on the first run after an install, 15-30 s; later runs load from the "
                      "cache)", file=sys.stderr, flush=True)
                warm_up(compiled)
            limit = None if env.spec is None else env.spec.max_episode_steps
            total = max_steps or limit or base.max_steps
            bar = tqdm(total=total, desc=env_id, unit="step", leave=False)
        result = rollout(env, policy, seed=seed, max_steps=max_steps, recorders=[recorder],
                         progress=bar)
        return recorder.record(result)
    finally:
        if bar is not None:
            bar.close()
        env.close()


def summarize(rec: EpisodeRecord) -> dict[str, float]:
    """Cross-track, slip, progress and odometry statistics of an episode (truth-based)."""
    ct = rec.cross_track_true_m
    err = np.hypot(*(rec.est_pose[:, :2] - rec.true_pose[:, :2]).T)
    slip = np.abs(rec.wheel_slip)
    stats = {
        "duration_s": float(rec.t_s[-1]) if len(rec.t_s) else 0.0,
        "cross_track_rmse_m": float(np.sqrt(np.mean(ct**2))),
        "cross_track_mean_abs_m": float(np.mean(np.abs(ct))),
        "cross_track_max_m": float(np.max(np.abs(ct))),
        "cross_track_final_m": float(ct[-1]),
        "progress_true": _last(rec.progress_true),
        "progress_estimated": _last(rec.progress_est),
        "wheel_slip_mean": float(np.mean(slip)),
        "wheel_slip_p95": float(np.percentile(slip, 95)),
        "slip_angle_mean_abs_deg": float(np.degrees(np.mean(np.abs(rec.slip_angle_rad)))),
        "odometry_final_error_m": float(err[-1]),
        "odometry_mean_error_m": float(np.mean(err)),
        "odometry_final_heading_error_deg": float(np.degrees(abs(
            wrap_angle(rec.est_pose[-1, 2] - rec.true_pose[-1, 2])))),
        "return": float(np.sum(rec.rewards)),
    }
    if rec.dead_reckoning_xy is not None and len(rec.dead_reckoning_xy):
        naive = np.hypot(*(rec.dead_reckoning_xy - rec.true_pose[: len(rec.dead_reckoning_xy),
                                                                  :2]).T)
        stats["dead_reckoning_final_error_m"] = float(naive[-1])
    return stats


def _last(values: np.ndarray | None) -> float:
    return float(values[-1]) if values is not None and len(values) else float("nan")


def completion_text(rec: EpisodeRecord) -> str:
    """How the episode ended, judged on the true pose, with the estimate's view beside it."""
    end_xy = rec.reference_xy[-1]
    to_end = float(np.hypot(*(rec.true_pose[-1, :2] - end_xy)))
    verdict = "path complete" if rec.success else f"path NOT complete ({rec.end_reason})"
    truth = (f"truth: {verdict}: progress {100 * _last(rec.progress_true):.1f} %, final "
             f"cross-track {rec.cross_track_true_m[-1]:+.2f} m, {to_end:.2f} m from the path's "
             "end point")
    gap = float(np.hypot(*(rec.est_pose[-1, :2] - rec.true_pose[-1, :2])))
    estimate = (f"estimate: progress {100 * _last(rec.progress_est):.1f} %, "
                f"{gap:.2f} m from the true position")
    return f"{truth}\n{estimate}"


def format_table(stats: dict[str, float], title: str) -> str:
    """A plain two-column table."""
    width = max(len(k) for k in stats)
    lines = [title, "-" * (width + 14)]
    lines += [f"{k:<{width}}  {v:>12.4f}" for k, v in stats.items()]
    return "\n".join(lines)


def slip_groups(rec: EpisodeRecord) -> list[tuple[str, np.ndarray]]:
    """(label, wheel columns) per drive channel: a track's road wheels become one group."""
    n = rec.wheel_slip.shape[1]
    names = rec.wheel_names if len(rec.wheel_names) == n else tuple(f"wheel {k}" for k in range(n))
    channels = rec.wheel_channels if len(rec.wheel_channels) == n else names
    groups: dict[str, list[int]] = {}
    for k, channel in enumerate(channels):
        groups.setdefault(channel or names[k], []).append(k)
    out = []
    for channel, cols in groups.items():
        label = names[cols[0]] if len(cols) == 1 else f"{channel} (mean of {len(cols)} wheels)"
        out.append((label, np.array(cols)))
    return out


def plot_episode(rec: EpisodeRecord, out_png: str | FsPath) -> FsPath:
    """Trajectory (reference, truth, odometry), cross-track error and wheel slip over time.

    Wheel slip is drawn per drive channel: one labelled line per wheel when each channel has
    one wheel, else the channel's mean with its min-max band (a track's road wheels).
    """
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
    if rec.dead_reckoning_xy is not None and len(rec.dead_reckoning_xy):
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
    groups = slip_groups(rec)
    for k, (label, cols) in enumerate(groups):
        slip = rec.wheel_slip[:, cols]
        line, = axes[2].plot(rec.t_s, slip.mean(axis=1), lw=1.0, color=f"C{k}", label=label)
        if len(cols) > 1:
            axes[2].fill_between(rec.t_s, slip.min(axis=1), slip.max(axis=1),
                                 color=line.get_color(), alpha=0.2, lw=0)
    axes[2].set_xlabel("t [s]")
    axes[2].set_ylabel("true slip ratio")
    if any(len(cols) > 1 for _, cols in groups):
        axes[2].set_title("wheel slip per track (band: min-max over its wheels)", fontsize=9)
    axes[2].legend(fontsize=7, loc="best")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
