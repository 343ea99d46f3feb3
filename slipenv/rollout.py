"""One rollout loop for every caller: the main job, the experiments, export, bench and agents.

In the spirit of stable-baselines3's ``evaluate_policy``: a policy is anything with SB3's
``predict(obs, state, episode_start, deterministic) -> (action, state)`` (every slipenv
controller and every SB3 model), or a plain callable ``obs -> action``. What a caller needs to
keep from the episode it says with *recorders*: objects whose ``on_reset`` and ``on_step`` are
called with the env's own outputs, so the loop itself never grows a special case.

Recorders shipped for reuse (each documents what it keeps):

- :class:`TrajectoryRecorder` (here): per step the time, true and estimated pose, true
  cross-track error, wheel slip, true body slip angle, action, reward and true / estimated
  progress, as a :class:`Trajectory`;
- ``slipenv.run.EpisodeRecorder``: the main job's ``EpisodeRecord`` (a trajectory plus plain
  dead reckoning on the same sensor frames);
- ``slipenv.logs.export.ExportRecorder``: the episode as a slipenv-log/1 log;
- ``slipenv.bench.StepTimer``: wall time of the env steps (the benchmark).

A recorder is reusable: ``on_reset`` starts a new episode.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any, Protocol

import gymnasium as gym
import numpy as np

from slipenv.contracts.observation import OBS_PROGRESS


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


@dataclass(frozen=True)
class Trajectory:
    """One episode's history, one row per env step (the reset is not a row).

    Attributes
    ----------
    t_s : np.ndarray, shape (n,)
        Simulation time at the end of each step [s].
    true_pose, est_pose : np.ndarray, shape (n, 3)
        True and estimated ``(x [m], y [m], yaw [rad])`` (``info["true_pose"]``,
        ``info["estimated_pose"]``).
    cross_track_true_m : np.ndarray, shape (n,)
        True cross-track error [m], > 0 left of the path.
    wheel_slip : np.ndarray, shape (n, n_wheels)
        True longitudinal slip ratio of every wheel [-] (``info["wheel_slip"]``).
    slip_angle_rad : np.ndarray, shape (n,)
        True body slip angle β [rad].
    actions : np.ndarray, shape (n, 2)
        Actions sent to the env (``[v / v_max, ω / ω_max]``).
    rewards : np.ndarray, shape (n,)
    progress_true, progress_est : np.ndarray, shape (n,)
        Fraction of the path done judged on the true pose and on the estimate [-].
    wheel_names, wheel_channels, wheel_roles : tuple of str
        Per column of ``wheel_slip``: name, drive channel (``""`` for none) and role.
    skipped_steps : int
        Steps without a truth in ``info`` (a physics blow-up), not recorded.
    """

    t_s: np.ndarray
    true_pose: np.ndarray
    est_pose: np.ndarray
    cross_track_true_m: np.ndarray
    wheel_slip: np.ndarray
    slip_angle_rad: np.ndarray
    actions: np.ndarray
    rewards: np.ndarray
    progress_true: np.ndarray
    progress_est: np.ndarray
    wheel_names: tuple[str, ...] = ()
    wheel_channels: tuple[str, ...] = ()
    wheel_roles: tuple[str, ...] = ()
    skipped_steps: int = 0

    def __len__(self) -> int:
        return len(self.t_s)

    def driven(self) -> np.ndarray:
        """Column indices of the driven wheels in ``wheel_slip`` (all if roles are unknown)."""
        if not self.wheel_roles:
            return np.arange(self.wheel_slip.shape[1])
        return np.array([k for k, r in enumerate(self.wheel_roles) if r == "driven"], dtype=int)


_FIELDS = ("t", "true", "est", "ct", "slip", "beta", "act", "rew", "prog_true", "prog_est")


class TrajectoryRecorder:
    """Keeps a :class:`Trajectory` of the episode: truth, estimate, slip, actions, rewards.

    Reads only the env's ``info`` (``t_s``, ``true_pose``, ``estimated_pose``,
    ``cross_track_true_m``, ``wheel_slip``, ``true_slip_angle_rad``, ``progress_true``), the
    observation's progress entry and the wheel list of ``env.unwrapped.vehicle``. Use
    :meth:`trajectory` after the rollout.
    """

    def __init__(self) -> None:
        self._rows: dict[str, list] = {k: [] for k in _FIELDS}
        self._wheels: tuple[tuple[str, ...], ...] = ((), (), ())
        self._skipped = 0

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        self._rows = {k: [] for k in _FIELDS}
        self._skipped = 0
        wheels = getattr(getattr(env.unwrapped, "vehicle", None), "wheels", ())
        self._wheels = (tuple(w.name for w in wheels), tuple(w.channel or "" for w in wheels),
                        tuple(w.role for w in wheels))

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        if "true_pose" not in info:  # a physics blow-up ends the episode without a truth
            self._skipped += 1
            return
        rows = self._rows
        rows["t"].append(float(info.get("t_s", np.nan)))
        rows["true"].append(np.asarray(info["true_pose"], dtype=float))
        rows["est"].append(np.asarray(info.get("estimated_pose", np.full(3, np.nan)),
                                      dtype=float))
        rows["ct"].append(float(info.get("cross_track_true_m", np.nan)))
        rows["slip"].append(np.asarray(info.get("wheel_slip", ()), dtype=float))
        rows["beta"].append(float(info.get("true_slip_angle_rad", np.nan)))
        rows["act"].append(np.asarray(action, dtype=float).reshape(-1))
        rows["rew"].append(float(reward))
        rows["prog_true"].append(float(info.get("progress_true", np.nan)))
        flat = np.asarray(obs).reshape(-1)
        rows["prog_est"].append(float(flat[OBS_PROGRESS]) if flat.size > OBS_PROGRESS
                                else np.nan)

    def trajectory(self) -> Trajectory:
        """The steps recorded since the last reset."""
        rows = self._rows
        n_wheels = len(self._wheels[0])

        def stack(key: str, width: int) -> np.ndarray:
            return np.array(rows[key], dtype=float).reshape(len(rows[key]), width)

        slip = np.array(rows["slip"]) if rows["slip"] else np.zeros((0, n_wheels))
        return Trajectory(
            t_s=np.array(rows["t"]), true_pose=stack("true", 3), est_pose=stack("est", 3),
            cross_track_true_m=np.array(rows["ct"]),
            wheel_slip=slip,
            slip_angle_rad=np.array(rows["beta"]), actions=stack("act", 2),
            rewards=np.array(rows["rew"]), progress_true=np.array(rows["prog_true"]),
            progress_est=np.array(rows["prog_est"]), wheel_names=self._wheels[0],
            wheel_channels=self._wheels[1], wheel_roles=self._wheels[2],
            skipped_steps=self._skipped,
        )
