"""The evaluation figure: every episode's true trajectory over the path, and error distributions."""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

from slipenv.envs.slip_env import SlipEnv
from slipenv.evaluation.trajectory import ape_translation


def reference_xy(env_id: str, env_kwargs: dict | None = None, step_m: float = 0.02,
                 ) -> np.ndarray:
    """The reference path of ``env_id`` sampled every ``step_m`` [m], shape (n, 2)."""
    env = gym.make(env_id, **(env_kwargs or {}))
    try:
        base = env.unwrapped
        if not isinstance(base, SlipEnv):
            raise TypeError(f"{env_id} is not a slipenv environment")
        samples = base.path.sample(step_m)
        return np.stack([samples.x_m, samples.y_m], axis=1)
    finally:
        env.close()


def plot_evaluation(evaluation, out_png: str | Path) -> Path:
    """Three panels: true trajectories of all episodes over the reference path; histogram of
    the true |cross-track error| pooled over episodes; odometry (APE) error over time.

    Parameters
    ----------
    evaluation : slipenv.evaluation.Evaluation
        With its traces (a fresh :func:`~slipenv.evaluation.evaluator` result).
    out_png : path
        Where to save the figure.
    """
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_png)
    out.parent.mkdir(parents=True, exist_ok=True)
    ref = reference_xy(evaluation.env_id, evaluation.env_kwargs)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.6))
    ax = axes[0]
    ax.plot(ref[:, 0], ref[:, 1], "k--", lw=1.2, label="reference path")
    errors = []
    for k, trace in enumerate(evaluation.traces):
        t_s, truth, est = trace.arrays()
        ax.plot(truth[:, 0], truth[:, 1], color=f"C{k % 10}", lw=1.2, label=f"seed {trace.seed}"
                if k < 8 else None)
        errors.append(np.abs(np.asarray(trace.cross_track_m)))
        axes[2].plot(t_s - t_s[0] if len(t_s) else t_s, ape_translation(est, truth),
                     color=f"C{k % 10}", lw=1)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"{evaluation.policy} on {evaluation.env_id}: true trajectories")
    ax.legend(loc="best", fontsize=7)
    pooled = np.concatenate(errors) if errors else np.zeros(0)
    axes[1].hist(pooled * 100.0, bins=40, color="C0", alpha=0.8)
    axes[1].axvline(evaluation.metrics["cross_track_rmse_m"] * 100.0, color="k", ls="--",
                    label="mean of episode RMSEs")
    axes[1].set_xlabel("true |cross-track error| [cm]")
    axes[1].set_ylabel("steps")
    axes[1].legend(fontsize=8)
    axes[2].set_xlabel("t [s]")
    axes[2].set_ylabel("odometry error (APE, no alignment) [m]")
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out
