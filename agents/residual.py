"""Residual RL: the agent learns a correction on top of the baseline path follower.

action = clip(baseline(obs) + scale * residual, -1, 1). With a zero residual the wrapped env
behaves exactly like the baseline controller, so training starts from a working policy.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from slipenv.run import baseline_controller


class ResidualActionWrapper(gym.ActionWrapper):
    """Adds the baseline controller's action to the agent's (scaled) residual action.

    Parameters
    ----------
    env : gym.Env
        A slipenv environment.
    scale : float
        Residual authority as a fraction of the action range (0 < scale <= 1).
    controller : str
        Baseline controller name (``slipenv.run.baseline_controller``).
    """

    def __init__(self, env: gym.Env, scale: float = 0.3, controller: str = "yamauchi",
                 **controller_kwargs: Any) -> None:
        super().__init__(env)
        if not (0.0 < scale <= 1.0):
            raise ValueError(f"scale must be in (0, 1], got {scale!r}")
        self.scale = float(scale)
        self.baseline = baseline_controller(env, controller, **controller_kwargs)
        self._obs: np.ndarray | None = None

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self.baseline.reset()
        self._obs = obs
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = super().step(action)
        self._obs = obs
        info["residual_action"] = np.asarray(action, dtype=np.float32)
        return obs, reward, terminated, truncated, info

    def action(self, action: np.ndarray) -> np.ndarray:
        if self._obs is None:
            raise RuntimeError("call reset() before step()")
        base = self.baseline.act(self._obs)
        return np.clip(base + self.scale * np.asarray(action, dtype=np.float32), -1.0,
                       1.0).astype(np.float32)
