"""pytest plugin (entry point ``pytest11: slipenv``): gate a controller's path following in CI.

Fixture ``slipenv_eval`` — a function ``(policy, env_id, seeds=(0, 1, 2), *, max_steps=None,
**env_kwargs) -> Evaluation`` whose summary metrics are attributes::

    def test_my_controller_tracks_the_slope(slipenv_eval):
        ev = slipenv_eval(my_controller, "slipenv/TrackedSlopeCircle-v0", seeds=range(5))
        assert ev.cross_track_rmse_m < 0.05
        ev.assert_below("cross_track_rmse_m", 0.05)   # failure names the worst seed
        ev.assert_above("success_rate", 0.99)

The policy is anything ``slipenv evaluate --policy`` takes -- a built-in name, a model path,
an object with SB3's ``predict`` -- and an SB3 model trained on the residual wrapper (a path or
``PPO.load(...)``) acts through its base controller as its ``.zip`` records.

Episodes are cached per (policy identity, env id, env kwargs, seed, max_steps) for the whole
test session, so a module asserting several metrics, or several tests sharing seeds, run each
episode once. The policy's identity is its name or model path, or the object itself (an
object is kept alive by the cache, so its ``id`` cannot be reused).

This module is imported by every pytest run in an environment where slipenv is installed: it
imports nothing heavy at import time.
"""

from __future__ import annotations

import json
from collections.abc import Callable, Iterable
from typing import Any

import pytest

DEFAULT_SEEDS = (0, 1, 2)


class EvaluationCache:
    """Per-episode results keyed by (policy key, env id, env kwargs, seed, max_steps)."""

    def __init__(self) -> None:
        self._episodes: dict[tuple, dict] = {}
        self._traces: dict[tuple, Any] = {}
        self._alive: dict[str, Any] = {}  # keeps policy objects alive: ids stay unique
        self.episodes_run = 0

    def evaluate(self, policy: Any, env_id: str, seeds: Iterable[int] = DEFAULT_SEEDS, *,
                 max_steps: int | None = None, **env_kwargs: Any):
        from slipenv.evaluation.evaluator import Evaluation, check_env, run_episode
        from slipenv.evaluation.policies import resolve_policy

        source = resolve_policy(policy)
        seeds = tuple(int(s) for s in seeds)
        if not seeds:
            raise ValueError("slipenv_eval: seeds must name at least one seed")
        check_env(env_id, env_kwargs)
        self._alive[source.key] = policy
        kwargs_key = json.dumps(env_kwargs, sort_keys=True, default=repr)
        for seed in seeds:
            key = (source.key, env_id, kwargs_key, seed, max_steps)
            if key not in self._episodes:
                self._episodes[key], self._traces[key] = run_episode(
                    source, env_id, seed, env_kwargs, max_steps)
                self.episodes_run += 1
        keys = [(source.key, env_id, kwargs_key, s, max_steps) for s in seeds]
        return Evaluation(policy=source.label, env_id=env_id, seeds=seeds,
                          env_kwargs=dict(env_kwargs),
                          per_episode=tuple(self._episodes[k] for k in keys),
                          traces=tuple(self._traces[k] for k in keys))


@pytest.fixture(scope="session")
def slipenv_eval_cache() -> EvaluationCache:
    """The session's episode cache behind :func:`slipenv_eval`."""
    return EvaluationCache()


@pytest.fixture(scope="session")
def slipenv_eval(slipenv_eval_cache: EvaluationCache) -> Callable[..., Any]:
    """Evaluate a policy on a slipenv env over seeds; returns an ``Evaluation`` whose metrics
    are attributes (``cross_track_rmse_m``, ``mean_cross_track_m``, ``success_rate``,
    ``energy_j``, ``odometry_final_error_m``, ``ape_rmse_m``, ...) with ``assert_below`` /
    ``assert_above`` helpers. See :func:`slipenv.evaluation.evaluator`."""
    return slipenv_eval_cache.evaluate


def pytest_configure(config: pytest.Config) -> None:
    config.addinivalue_line("markers", "slipenv: a slipenv closed-loop evaluation test")
