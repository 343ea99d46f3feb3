"""One rollout loop for every caller: the main job, the experiments, export, bench and agents.

In the spirit of stable-baselines3's ``evaluate_policy``: a policy is anything with SB3's
``predict(obs, state, episode_start, deterministic) -> (action, state)`` (every slipenv
controller and every SB3 model), or a plain callable ``obs -> action``. What a caller needs to
keep from the episode it says with *recorders*: objects whose ``on_reset`` and ``on_step`` are
called with the env's own outputs, so the loop itself never grows a special case.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import gymnasium as gym
import numpy as np


class PolicyPredictor(Protocol):
    """SB3's policy protocol (``stable_baselines3.common.type_aliases.PolicyPredictor``)."""

    def predict(self, observation: np.ndarray, state: tuple[np.ndarray, ...] | None = None,
                episode_start: np.ndarray | None = None,
                deterministic: bool = False) -> tuple[np.ndarray, tuple[np.ndarray, ...] | None]:
        ...


class Recorder(Protocol):
    """Told about every reset and step of a rollout; keeps what its caller needs."""

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        ...

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        ...


@dataclass(frozen=True)
class RolloutResult:
    """How an episode ended.

    Attributes
    ----------
    steps : int
        Env steps taken.
    episode_return : float
        Sum of the rewards.
    end_reason : str
        ``"path complete"``, the env's termination or truncation reason, or ``"step limit"``
        when ``max_steps`` stopped the loop first.
    success : bool
        The env's ``info["is_success"]`` at the last step: judged on the true pose.
    terminated, truncated : bool
        The env's flags at the last step (both False when ``max_steps`` stopped the loop).
    """

    steps: int
    episode_return: float
    end_reason: str
    success: bool
    terminated: bool
    truncated: bool


def end_reason(info: dict, terminated: bool, truncated: bool) -> str:
    """The human-readable reason an episode ended, from the env's ``info``."""
    if info.get("is_success"):
        return "path complete"
    return str(info.get("termination_reason") or info.get("truncation_reason")
               or ("terminated" if terminated else "truncated" if truncated else "step limit"))


def _as_action_fn(policy: PolicyPredictor | Callable[[np.ndarray], Any],
                  deterministic: bool) -> Callable[[np.ndarray, bool], np.ndarray]:
    predict = getattr(policy, "predict", None)
    if predict is None:
        if not callable(policy):
            raise TypeError(f"a policy needs predict() or must be callable, got {policy!r}")
        return lambda obs, _start: np.asarray(policy(obs))
    state: list[Any] = [None]

    def act(obs: np.ndarray, episode_start: bool) -> np.ndarray:
        action, state[0] = predict(obs, state=state[0],
                                   episode_start=np.array([episode_start]),
                                   deterministic=deterministic)
        return np.asarray(action)

    return act


def rollout(env: gym.Env, policy: PolicyPredictor | Callable[[np.ndarray], Any], *,
            seed: int | None = None, options: dict | None = None,
            max_steps: int | None = None, recorders: Sequence[Recorder] = (),
            deterministic: bool = True, progress: Any = None) -> RolloutResult:
    """Run one episode of ``env`` with ``policy``.

    Parameters
    ----------
    env : gymnasium.Env
        A (possibly wrapped) env; it is reset here with ``seed`` and ``options``.
    policy : PolicyPredictor or callable
        SB3-style ``predict`` or ``obs -> action``. A ``reset()`` method, if the policy has
        one, is called after the env's reset (controllers clear their integrators).
    max_steps : int, optional
        Stop after this many steps even if the env has not ended (``end_reason`` is then
        ``"step limit"``); by default the env's own time limit ends the episode.
    recorders : sequence of Recorder
        Called with every reset and step, in order.
    progress : object with ``update(n)``, optional
        A progress bar (tqdm) advanced once per step.

    Returns
    -------
    RolloutResult
    """
    if max_steps is not None and max_steps < 1:
        raise ValueError(f"max_steps must be >= 1, got {max_steps}")
    act = _as_action_fn(policy, deterministic)
    obs, info = env.reset(seed=seed, options=options)
    if hasattr(policy, "reset"):
        policy.reset()
    for rec in recorders:
        rec.on_reset(env, obs, info)
    total, steps = 0.0, 0
    terminated = truncated = False
    start = True
    while max_steps is None or steps < max_steps:
        action = act(obs, start)
        start = False
        obs, reward, terminated, truncated, info = env.step(action)
        steps += 1
        total += float(reward)
        for rec in recorders:
            rec.on_step(env, action, obs, float(reward), terminated, truncated, info)
        if progress is not None:
            progress.update(1)
        if terminated or truncated:
            break
    return RolloutResult(steps=steps, episode_return=total,
                         end_reason=end_reason(info, terminated, truncated),
                         success=bool(info.get("is_success", False)),
                         terminated=bool(terminated), truncated=bool(truncated))
