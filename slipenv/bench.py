"""Throughput benchmark: env steps per second next to bare ``stepSimulation`` (DESIGN §6).

For each env id, in one process and interleaved (env chunk, bare chunk, env chunk, ...) so
that machine noise hits both alike: ``env_steps_per_s`` is the full ``env.step`` (force law at
every substep, sensors, estimator, observation, reward); ``bare_substeps_per_s`` is plain
``p.stepSimulation`` of the very same PyBullet world (same bodies, contacts and solver
settings, no force injection and no Python on top). The ratio

    ratio = env_steps_per_s * substeps_per_step / bare_substeps_per_s

is the share of time spent in physics: 1.0 means slipenv adds nothing on top of PyBullet.
Medians over the repetitions are reported.

Each env chunk is one :func:`slipenv.rollout.rollout` from ``reset(seed=0)`` with a constant
action: the first ``WARMUP_STEPS`` steps (caches, first contacts) are not timed; a
:class:`StepTimer` recorder saves the world's state when timing starts and times the rest; the
bare chunk then restores that state and steps it as often as the env chunk did substeps.
Warnings and log records emitted while benchmarking (an estimator skipping measurements, ...)
are collected and counted, not printed in the middle of the table.
"""

from __future__ import annotations

import contextlib
import logging
import platform
import statistics
import time
import warnings
from collections import Counter
from collections.abc import Iterator

import gymnasium as gym
import numpy as np

from slipenv.pybullet_quiet import import_pybullet
from slipenv.rollout import rollout

p = import_pybullet()

WARMUP_STEPS = 10
"""Env steps after each reset that are not timed (caches, first contacts)."""
BENCH_ACTION = np.array([0.5, 0.1], dtype=np.float32)
"""Constant action of the benchmark: half speed, a gentle turn."""


class StepTimer:
    """Rollout recorder timing env steps after a warm-up (see the module docstring).

    After the rollout: ``steps`` timed steps took ``elapsed_s`` seconds; ``state_id`` is the
    PyBullet state saved when timing started (the caller restores and removes it).
    """

    def __init__(self, client: int, warmup_steps: int = WARMUP_STEPS) -> None:
        self.client, self.warmup_steps = client, warmup_steps
        self.steps, self.elapsed_s = 0, 0.0
        self.state_id: int | None = None
        self._seen = 0
        self._t0 = 0.0

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        self._seen, self.steps, self.elapsed_s = 0, 0, 0.0
        if self.warmup_steps == 0:
            self._start()

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        self._seen += 1
        if self._seen <= self.warmup_steps:
            if self._seen == self.warmup_steps:
                self._start()
            return
        self.steps += 1
        self.elapsed_s = time.perf_counter() - self._t0

    def _start(self) -> None:
        self.state_id = p.saveState(physicsClientId=self.client)
        self._t0 = time.perf_counter()


def bench_env(env_id: str, steps: int = 200, repeats: int = 5) -> dict:
    """Measure one env id; see the module docstring."""
    if steps < 1 or repeats < 1:
        raise ValueError(f"steps and repeats must be >= 1, got steps={steps}, repeats={repeats}")
    env = gym.make(env_id)
    try:
        base = env.unwrapped
        client, substeps = base.physics_client_id, base.substeps_per_step
        timer = StepTimer(client)
        env_rates, bare_rates = [], []
        for _ in range(repeats):
            rollout(env, lambda _obs: BENCH_ACTION, seed=0, max_steps=WARMUP_STEPS + steps,
                    recorders=[timer])
            if timer.state_id is None or timer.steps == 0:
                raise ValueError(f"{env_id}: the episode ended within the {WARMUP_STEPS} "
                                 "warm-up steps; nothing to time")
            env_rates.append(timer.steps / timer.elapsed_s)
            p.restoreState(timer.state_id, physicsClientId=client)
            n_bare = timer.steps * substeps
            t0 = time.perf_counter()
            for _ in range(n_bare):
                p.stepSimulation(physicsClientId=client)
            bare_rates.append(n_bare / (time.perf_counter() - t0))
            p.removeState(timer.state_id, physicsClientId=client)
            timer.state_id = None
        env_rate = statistics.median(env_rates)
        bare_rate = statistics.median(bare_rates)
        return {
            "env_steps_per_s": round(env_rate, 2),
            "substeps_per_step": substeps,
            "bare_substeps_per_s": round(bare_rate, 1),
            "ratio": round(env_rate * substeps / bare_rate, 3),
            "vehicle": base.vehicle.name,
            "wheels": len(base.vehicle.wheels),
            "realtime_factor": round(env_rate * base.control_dt_s, 2),
        }
    finally:
        env.close()


class _Collect(logging.Handler):
    def __init__(self, sink: Counter) -> None:
        super().__init__(level=logging.WARNING)
        self.sink = sink

    def emit(self, record: logging.LogRecord) -> None:
        self.sink[f"{record.name}: {record.getMessage()}"] += 1


@contextlib.contextmanager
def collected_warnings() -> Iterator[Counter]:
    """Collect Python warnings and WARNING+ log records instead of printing them.

    Yields a :class:`collections.Counter` of ``"source: message"`` -> count, filled when the
    block exits (log records as they arrive).
    """
    sink: Counter = Counter()
    handler = _Collect(sink)
    root = logging.getLogger()
    saved = logging.lastResort
    root.addHandler(handler)
    logging.lastResort = None  # records must not reach stderr through the last-resort handler
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            yield sink
        for w in caught:
            sink[f"{w.category.__name__}: {w.message}"] += 1
    finally:
        root.removeHandler(handler)
        logging.lastResort = saved


def run_bench(env_ids: list[str], steps: int = 200, repeats: int = 5,
              progress: bool = True) -> dict:
    """Benchmark every id.

    Returns
    -------
    dict
        ``{"envs": {id: {...}}, "machine": {...}, "settings": {...},
        "warnings": {"count": n, "messages": {message: count}}}``.
    """
    envs = {}
    iterator = env_ids
    if progress:
        from tqdm import tqdm

        iterator = tqdm(env_ids, desc="bench", unit="env")
    with collected_warnings() as caught:
        for env_id in iterator:
            envs[env_id] = bench_env(env_id, steps=steps, repeats=repeats)
    return {
        "envs": envs,
        "machine": {"python": platform.python_version(), "processor": platform.machine(),
                    "pybullet_api": p.getAPIVersion()},
        "settings": {"steps": steps, "repeats": repeats, "warmup_steps": WARMUP_STEPS},
        "warnings": {"count": sum(caught.values()), "messages": dict(caught.most_common())},
    }


def format_bench(result: dict) -> str:
    """A table of the benchmark figures, and one line counting the warnings collected."""
    head = (f"{'env id':<32} {'env steps/s':>12} {'substeps':>9} {'bare substeps/s':>16} "
            f"{'ratio':>6} {'x realtime':>10}")
    lines = [head, "-" * len(head)]
    for env_id, r in result["envs"].items():
        lines.append(
            f"{env_id:<32} {r['env_steps_per_s']:>12.1f} {r['substeps_per_step']:>9d} "
            f"{r['bare_substeps_per_s']:>16.0f} {r['ratio']:>6.2f} {r['realtime_factor']:>10.1f}"
        )
    caught = result.get("warnings", {})
    if caught.get("count"):
        first = next(iter(caught["messages"]))
        lines.append(f"{caught['count']} warning(s) during the benchmark, "
                     f"{len(caught['messages'])} distinct (most frequent: {first})")
    return "\n".join(lines)
