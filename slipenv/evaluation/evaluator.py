"""Evaluate a policy on a slipenv task over seeds: the same metrics for controllers and agents.

Each seed's episode runs in a fresh env (``gymnasium.make(env_id, **env_kwargs)``, reset with
that seed) through THE rollout loop, :func:`slipenv.rollout.rollout`, so an episode's result
depends only on (policy, env id, env kwargs, seed): the same seed gives the same evaluation
bit for bit, and a seed's result can be cached or run on another machine.
"""

from __future__ import annotations

import json
import math
from collections.abc import Iterable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym

from slipenv.evaluation.metrics import (
    HIGHER_IS_BETTER,
    METRICS,
    RPE_DELTA_STEPS,
    EpisodeTrace,
    TraceRecorder,
    aggregate,
    episode_metrics,
    spread,
    worst_episode,
)
from slipenv.evaluation.policies import PolicySource, resolve_policy
from slipenv.evaluation.trajectory import write_tum
from slipenv.rollout import rollout


@dataclass(frozen=True, eq=False)
class Evaluation:
    """An evaluation's results; every summary metric is also an attribute
    (``ev.cross_track_rmse_m``, ``ev.success_rate``, ...).

    Attributes
    ----------
    policy, env_id : str
        The policy's label and the env id.
    seeds : tuple of int
    env_kwargs : dict
    metrics : dict
        Mean over episodes of each metric in :data:`slipenv.evaluation.metrics.METRICS`.
    per_episode : tuple of dict
        :func:`slipenv.evaluation.metrics.episode_metrics` of each seed, in seed order.
    traces : tuple of EpisodeTrace
        The episodes' trajectories (not serialised; empty when rebuilt from results).
    """

    policy: str
    env_id: str
    seeds: tuple[int, ...]
    env_kwargs: dict
    per_episode: tuple[dict, ...]
    traces: tuple[EpisodeTrace, ...] = field(default=(), repr=False)
    rpe_delta_steps: int = RPE_DELTA_STEPS
    metrics: dict = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "metrics", aggregate(list(self.per_episode)))

    def __getattr__(self, name: str) -> Any:
        metrics = self.__dict__.get("metrics", {})
        if name in metrics:
            return metrics[name]
        raise AttributeError(f"{type(self).__name__} has no attribute or metric {name!r}; "
                             f"metrics: {', '.join(METRICS)}")

    @property
    def episodes(self) -> int:
        return len(self.per_episode)

    def worst(self, name: str) -> dict:
        """The per-episode record doing worst on metric ``name``."""
        return worst_episode(list(self.per_episode), name)

    def _check(self, name: str, bound: float, below: bool) -> None:
        if name not in self.metrics:
            raise ValueError(f"unknown metric {name!r}; metrics: {', '.join(METRICS)}")
        value = self.metrics[name]
        ok = (value < bound) if below else (value > bound)
        if ok and not math.isnan(value):
            return
        worst = self.worst(name)
        key = "success" if name == "success_rate" else name
        raise AssertionError(
            f"{name} = {value:.6g} is not {'<' if below else '>'} {bound:.6g} "
            f"({self.policy} on {self.env_id}, seeds {list(self.seeds)}); worst episode: "
            f"seed {worst['seed']} with {key} = {worst[key]} ({worst['end_reason']})")

    def assert_below(self, name: str, bound: float) -> Evaluation:
        """Assert ``metrics[name] < bound``; the failure names the metric, the bound and the
        worst episode's seed. Returns self, so checks chain."""
        self._check(name, bound, below=True)
        return self

    def assert_above(self, name: str, bound: float) -> Evaluation:
        """Assert ``metrics[name] > bound`` (e.g. ``success_rate``), failing as above."""
        self._check(name, bound, below=False)
        return self

    def to_dict(self) -> dict:
        """The JSON document: policy, env id, episodes, seeds, metrics, spread, per episode."""
        return _finite({
            "policy": self.policy, "env_id": self.env_id, "episodes": self.episodes,
            "seeds": list(self.seeds), "env_kwargs": self.env_kwargs,
            "rpe_delta_steps": self.rpe_delta_steps, "metrics": self.metrics,
            "spread": spread(list(self.per_episode)),
            "per_episode": list(self.per_episode),
        })

    def write_json(self, path: str | Path) -> Path:
        out = Path(path)
        out.parent.mkdir(parents=True, exist_ok=True)
        out.write_text(json.dumps(self.to_dict(), indent=2) + "\n")
        return out

    def export_tum(self, out_dir: str | Path) -> list[Path]:
        """Each episode's truth and estimate as ``seed_<s>_{truth,estimate}.tum`` files
        (score with ``evo_ape tum seed_0_truth.tum seed_0_estimate.tum``)."""
        written = []
        for trace in self.traces:
            t_s, truth, est = trace.arrays()
            stem = Path(out_dir) / f"seed_{trace.seed}"
            written.append(write_tum(f"{stem}_truth.tum", t_s, truth))
            written.append(write_tum(f"{stem}_estimate.tum", t_s, est))
        return written

    def table(self) -> str:
        """Mean ± std of each metric, then one line per episode."""
        sd = spread(list(self.per_episode))
        width = max(len(m) for m in METRICS)
        lines = [f"{self.policy} on {self.env_id}: {self.episodes} episodes, seeds "
                 f"{list(self.seeds)}", "-" * (width + 30)]
        lines += [f"{m:<{width}}  {self.metrics[m]:>12.5g} ± {sd[m]:<10.3g}" for m in METRICS]
        head = ("seed", "success", "ct_rmse_m", "energy_j", "odo_final_m", "steps", "end")
        lines += ["", "  ".join(f"{h:>11}" for h in head)]
        for ep in self.per_episode:
            lines.append("  ".join([f"{ep['seed']!s:>11}", f"{ep['success']!s:>11}",
                                    f"{ep['cross_track_rmse_m']:>11.5f}",
                                    f"{ep['energy_j']:>11.4g}",
                                    f"{ep['odometry_final_error_m']:>11.5f}",
                                    f"{ep['steps']:>11d}", f"  {ep['end_reason']}"]))
        return "\n".join(lines)


def _finite(obj: Any) -> Any:
    """NaN/inf -> None, so the JSON is standard (json.dumps would write NaN)."""
    if isinstance(obj, float):
        return obj if math.isfinite(obj) else None
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [_finite(v) for v in obj]
    return obj


def run_episode(source: PolicySource, env_id: str, seed: int, env_kwargs: dict | None = None,
                max_steps: int | None = None, rpe_delta_steps: int = RPE_DELTA_STEPS,
                progress: Any = None) -> tuple[dict, EpisodeTrace]:
    """One seeded episode in a fresh env: ``(episode_metrics, trace)``."""
    env = source.wrap_env(gym.make(env_id, **(env_kwargs or {})))
    try:
        policy = source.build(env)
        recorder = TraceRecorder(seed)
        result = rollout(env, policy, seed=seed, max_steps=max_steps, recorders=[recorder],
                         deterministic=True, progress=progress)
        recorder.trace.end_reason = result.end_reason
        recorder.trace.success = result.success
        return episode_metrics(recorder.trace, rpe_delta_steps), recorder.trace
    finally:
        env.close()


def check_env(env_id: str, env_kwargs: dict | None = None) -> None:
    """Fail fast on an unknown env id or bad env kwargs (ValueError), before any episode."""
    from slipenv.envs.config import SlipEnvConfig
    from slipenv.envs.registration import preset_config

    if env_id not in gym.registry:
        preset_config(env_id)  # raises the "unknown id, did you mean" error for slipenv ids
    if env_kwargs:
        if not isinstance(env_kwargs, dict):
            raise ValueError(f"env kwargs must be a JSON object, got {env_kwargs!r}")
        base = gym.registry[env_id].kwargs.get("config")
        SlipEnvConfig.from_kwargs(base, **env_kwargs)


def evaluate(policy: Any, env_id: str, seeds: Iterable[int], env_kwargs: dict | None = None,
             *, max_steps: int | None = None, rpe_delta_steps: int = RPE_DELTA_STEPS,
             progress: bool = False) -> Evaluation:
    """Evaluate ``policy`` on ``env_id``, one episode per seed.

    Parameters
    ----------
    policy : str, path or object
        ``baseline``, ``feedback``, ``pure_pursuit``, ``stanley``, a path to an SB3 ``.zip``,
        or anything with SB3's ``predict`` (see :func:`resolve_policy`).
    env_id : str
        A registered slipenv id.
    seeds : iterable of int
        One episode per seed (the env's reset seed).
    env_kwargs : dict, optional
        Overrides of the id's preset (``gymnasium.make(env_id, **env_kwargs)``).
    max_steps : int, optional
        Stop each episode after this many steps (default: the env's time limit).
    rpe_delta_steps : int
        RPE separation Δ [steps].
    progress : bool
        Show a progress bar over steps.

    Raises
    ------
    ValueError
        Bad policy, env id, env kwargs or seeds, before any episode runs.
    """
    source = resolve_policy(policy)
    seeds = tuple(int(s) for s in seeds)
    if not seeds:
        raise ValueError("seeds must name at least one seed")
    env_kwargs = dict(env_kwargs or {})
    check_env(env_id, env_kwargs)
    bar = None
    if progress:
        from tqdm.auto import tqdm

        bar = tqdm(desc=f"{source.label} on {env_id}", unit="step", leave=False)
    try:
        results = [run_episode(source, env_id, s, env_kwargs, max_steps, rpe_delta_steps, bar)
                   for s in seeds]
    finally:  # on Ctrl-C too: the bar's remains must not print after the CLI's one line
        if bar is not None:
            bar.close()
    return Evaluation(policy=source.label, env_id=env_id, seeds=seeds, env_kwargs=env_kwargs,
                      per_episode=tuple(r[0] for r in results),
                      traces=tuple(r[1] for r in results), rpe_delta_steps=rpe_delta_steps)


__all__ = ["HIGHER_IS_BETTER", "Evaluation", "check_env", "evaluate", "run_episode"]
