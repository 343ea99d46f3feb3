"""Throughput benchmark: env steps per second next to bare ``stepSimulation`` (DESIGN §6).

For each env id, in one process and interleaved (env chunk, bare chunk, env chunk, ...) so
that machine noise hits both alike: ``env_steps_per_s`` is the full ``env.step`` (force law at
every substep, sensors, estimator, observation, reward); ``bare_substeps_per_s`` is plain
``p.stepSimulation`` of the very same PyBullet world (same bodies, contacts and solver
settings, no force injection and no Python on top). The ratio

    ratio = env_steps_per_s * substeps_per_step / bare_substeps_per_s

is the share of time spent in physics: 1.0 means slipenv adds nothing on top of PyBullet.
Medians over the repetitions are reported.
"""

from __future__ import annotations

import platform
import statistics
import time

import gymnasium as gym
import numpy as np
import pybullet as p

import slipenv  # noqa: F401


def bench_env(env_id: str, steps: int = 200, repeats: int = 5) -> dict:
    """Measure one env id; see the module docstring."""
    env = gym.make(env_id)
    try:
        base = env.unwrapped
        client, substeps = base.physics_client_id, base.substeps_per_step
        env.reset(seed=0)
        action = np.array([0.5, 0.1], dtype=np.float32)
        for _ in range(10):  # warm-up: caches, first contacts
            env.step(action)
        env_rates, bare_rates = [], []
        for _ in range(repeats):
            state = p.saveState(physicsClientId=client)
            t0 = time.perf_counter()
            for _ in range(steps):
                _, _, terminated, truncated, _ = env.step(action)
                if terminated or truncated:
                    env.reset(seed=0)
            env_rates.append(steps / (time.perf_counter() - t0))
            p.restoreState(state, physicsClientId=client)
            n_bare = steps * substeps
            t0 = time.perf_counter()
            for _ in range(n_bare):
                p.stepSimulation(physicsClientId=client)
            bare_rates.append(n_bare / (time.perf_counter() - t0))
            p.restoreState(state, physicsClientId=client)
            p.removeState(state, physicsClientId=client)
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


def run_bench(env_ids: list[str], steps: int = 200, repeats: int = 5,
              progress: bool = True) -> dict:
    """Benchmark every id; returns ``{"envs": {id: {...}}, "machine": {...}}``."""
    envs = {}
    iterator = env_ids
    if progress:
        from tqdm import tqdm
        iterator = tqdm(env_ids, desc="bench", unit="env")
    for env_id in iterator:
        envs[env_id] = bench_env(env_id, steps=steps, repeats=repeats)
    return {
        "envs": envs,
        "machine": {"python": platform.python_version(), "processor": platform.machine(),
                    "pybullet_api": p.getAPIVersion()},
        "settings": {"steps": steps, "repeats": repeats},
    }


def format_bench(result: dict) -> str:
    """A table of the benchmark figures."""
    head = (f"{'env id':<32} {'env steps/s':>12} {'substeps':>9} {'bare substeps/s':>16} "
            f"{'ratio':>6} {'x realtime':>10}")
    lines = [head, "-" * len(head)]
    for env_id, r in result["envs"].items():
        lines.append(
            f"{env_id:<32} {r['env_steps_per_s']:>12.1f} {r['substeps_per_step']:>9d} "
            f"{r['bare_substeps_per_s']:>16.0f} {r['ratio']:>6.2f} {r['realtime_factor']:>10.1f}"
        )
    return "\n".join(lines)
