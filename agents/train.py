"""Train and evaluate stable-baselines3 agents on slipenv tasks, next to the baseline.

``train`` builds a vectorised env (optionally wrapped for residual RL), trains PPO or SAC with a
seeded setup and a progress bar, and saves the model. ``evaluate`` runs any policy with SB3's
``predict`` signature — an SB3 model or a slipenv controller — through SB3's
``evaluate_policy`` and also reports the true cross-track error, so agents and the baseline are
compared by the same code.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
from stable_baselines3 import PPO, SAC
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.evaluation import evaluate_policy

import slipenv  # noqa: F401
from slipenv.run import baseline_controller

from .residual import ResidualActionWrapper

ALGORITHMS = {"ppo": PPO, "sac": SAC}


@dataclass(frozen=True)
class Evaluation:
    """Mean and spread of the episode return, and the mean absolute true cross-track error."""

    mean_return: float
    std_return: float
    mean_abs_cross_track_m: float
    episodes: int


def make_env(env_id: str, residual: bool = False, **env_kwargs: Any) -> gym.Env:
    """One env, wrapped for residual RL if asked."""
    env = gym.make(env_id, **env_kwargs)
    return ResidualActionWrapper(env) if residual else env


def train(env_id: str, algo: str = "ppo", total_timesteps: int = 20_000, seed: int = 0,
          n_envs: int = 2, residual: bool = True, out: str | None = None,
          progress: bool = False, algo_kwargs: dict | None = None, **env_kwargs: Any):
    """Train an agent; returns the SB3 model (saved to ``out`` if given)."""
    if algo not in ALGORITHMS:
        raise ValueError(f"unknown algorithm {algo!r}; known: {sorted(ALGORITHMS)}")
    if total_timesteps <= 0:
        raise ValueError(f"total_timesteps must be > 0, got {total_timesteps}")
    vec = make_vec_env(lambda: make_env(env_id, residual, **env_kwargs), n_envs=n_envs,
                       seed=seed)
    kwargs = {"seed": seed, "verbose": 0, "device": "cpu", **(algo_kwargs or {})}
    if algo == "ppo":
        kwargs.setdefault("n_steps", 256)
        kwargs.setdefault("batch_size", 64)
    model = ALGORITHMS[algo]("MlpPolicy", vec, **kwargs)
    model.learn(total_timesteps=total_timesteps, progress_bar=progress)
    if out is not None:
        Path(out).parent.mkdir(parents=True, exist_ok=True)
        model.save(out)
    vec.close()
    return model


class _CrossTrackRecorder:
    def __init__(self) -> None:
        self.values: list[float] = []

    def __call__(self, local_vars: dict, global_vars: dict) -> None:
        info = local_vars["info"]
        if "cross_track_true_m" in info:
            self.values.append(abs(float(info["cross_track_true_m"])))


def evaluate(policy, env_id: str, n_episodes: int = 3, seed: int = 100,
             residual: bool = False, **env_kwargs: Any) -> Evaluation:
    """Evaluate ``policy`` (anything with SB3's ``predict``) with SB3's ``evaluate_policy``.

    ``policy="baseline"`` evaluates the baseline path follower itself.
    """
    env = make_env(env_id, residual, **env_kwargs)
    env.reset(seed=seed)
    if isinstance(policy, str) and policy == "baseline":
        policy = baseline_controller(env)
    recorder = _CrossTrackRecorder()
    returns, _ = evaluate_policy(policy, env, n_eval_episodes=n_episodes, deterministic=True,
                                 return_episode_rewards=True, callback=recorder, warn=False)
    env.close()
    return Evaluation(float(np.mean(returns)), float(np.std(returns)),
                      float(np.mean(recorder.values)) if recorder.values else float("nan"),
                      n_episodes)
