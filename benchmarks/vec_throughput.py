"""Vectorised throughput: env steps/s with 1, 2 and 4 worker processes.

Measures, for one env id (default ``slipenv/HuskySand-v0``), total env steps per second of

* ``single``: one env stepped in this process (no IPC; the per-process ceiling);
* ``gymnasium.make_vec(id, n, vectorization_mode="async")`` for n = 1, 2, 4;
* stable-baselines3's ``SubprocVecEnv`` for n = 1, 2, 4;

each after ``WARMUP`` untimed batched steps (process start-up and first reset excluded), with a
constant action; episodes auto-reset. The measurements are interleaved (single, async n,
SB3 n, for each n in turn) and repeated; medians are reported.

The model for a bigger machine: a worker's step costs ``t_env`` (the single-process figure) plus
an IPC overhead ``t_ipc`` (pickling the action and the step's results, two pipe round trips),
measured as ``1/rate(async, n=1) - 1/rate(single)``. With at least one free core per worker,

    total steps/s(n) ≈ n / (t_env + t_ipc),

so the n = 1 row times the core count, minus nothing else while the parent's own work (one
``step_wait`` per batch) stays small against ``t_env``.

Where ``t_ipc`` goes (``anatomy``): with one SB3 worker, the env's own ``step`` is timed inside
the worker (wall and CPU time) and in this process; the rest of the round trip is the pipe,
pickling and the two processes' wake-ups. On this 2-core machine shared with
other jobs, n = 4 oversubscribes the cores and shows the cost of doing so.

Run from the repository root::

    python benchmarks/vec_throughput.py [--env slipenv/HuskySand-v0] [--steps 200]
                                        [--repeats 3] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import gymnasium as gym

import slipenv  # noqa: F401  (registers the envs)
from slipenv.bench import BENCH_ACTION, WARMUP_STEPS, batched_steps_per_s, vec_steps_per_s

PROCESSES = (1, 2, 4)


def single_steps_per_s(env_id: str, steps: int) -> float:
    """Env steps/s of one env in this process (auto-reset on episode end)."""
    env = gym.make(env_id)
    try:
        env.reset(seed=0)
        for _ in range(WARMUP_STEPS):
            env.step(BENCH_ACTION)
        t0 = time.perf_counter()
        for _ in range(steps):
            _, _, term, trunc, _ = env.step(BENCH_ACTION)
            if term or trunc:
                env.reset()
        return steps / (time.perf_counter() - t0)
    finally:
        env.close()


def sb3_steps_per_s(env_id: str, n: int, steps: int) -> float:
    """Total env steps/s of stable-baselines3's ``SubprocVecEnv`` with ``n`` workers."""
    from stable_baselines3.common.vec_env import SubprocVecEnv

    envs = SubprocVecEnv([lambda: gym.make(env_id) for _ in range(n)])
    try:
        envs.seed(0)
        envs.reset()
        return batched_steps_per_s(envs, n, steps)
    finally:
        envs.close()


class _StepClock(gym.Wrapper):
    """Adds the env's own step time to ``info`` (``step_wall_us``, ``step_cpu_us``)."""

    def step(self, action):
        t0, c0 = time.perf_counter(), time.thread_time()
        obs, reward, terminated, truncated, info = self.env.step(action)
        info = dict(info, step_wall_us=1e6 * (time.perf_counter() - t0),
                    step_cpu_us=1e6 * (time.thread_time() - c0))
        return obs, reward, terminated, truncated, info


def anatomy(env_id: str, steps: int) -> dict[str, float]:
    """Median µs per step with one env: SB3 ``SubprocVecEnv`` round trip, the env's own step
    inside that worker (wall, CPU) and in this process (``DummyVecEnv``)."""
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    out = {}
    for name, cls in (("in_process", DummyVecEnv), ("worker", SubprocVecEnv)):
        envs = cls([lambda: _StepClock(gym.make(env_id))])
        try:
            envs.seed(0)
            envs.reset()
            actions = BENCH_ACTION[None, :]
            for _ in range(WARMUP_STEPS):
                envs.step(actions)
            trips, walls, cpus = [], [], []
            for _ in range(steps):
                t0 = time.perf_counter()
                *_, infos = envs.step(actions)
                trips.append(1e6 * (time.perf_counter() - t0))
                if "step_wall_us" in infos[0]:  # (not on the step that resets)
                    walls.append(infos[0]["step_wall_us"])
                    cpus.append(infos[0]["step_cpu_us"])
        finally:
            envs.close()
        out[f"{name}_round_trip_us"] = statistics.median(trips)
        out[f"{name}_step_wall_us"] = statistics.median(walls)
        out[f"{name}_step_cpu_us"] = statistics.median(cpus)
    return {k: round(v, 1) for k, v in out.items()}


def run(env_id: str, steps: int = 200, repeats: int = 3) -> dict:
    samples: dict[str, list[float]] = {"single": []}
    for n in PROCESSES:
        samples[f"gym_async_{n}"] = []
        samples[f"sb3_subproc_{n}"] = []
    for _ in range(repeats):
        samples["single"].append(single_steps_per_s(env_id, steps))
        for n in PROCESSES:
            samples[f"gym_async_{n}"].append(vec_steps_per_s(env_id, n, steps))
            samples[f"sb3_subproc_{n}"].append(sb3_steps_per_s(env_id, n, steps))
    rates = {k: statistics.median(v) for k, v in samples.items()}
    t_env = 1.0 / rates["single"]
    t_ipc_gym = 1.0 / rates["gym_async_1"] - t_env
    t_ipc_sb3 = 1.0 / rates["sb3_subproc_1"] - t_env
    model = {f"{c}_cores": round(c / (t_env + max(t_ipc_gym, 0.0)), 1) for c in (8, 16, 32, 64)}
    return {
        "env": env_id, "steps": steps, "repeats": repeats, "cpu_count": os.cpu_count(),
        "env_steps_per_s": {k: round(v, 1) for k, v in rates.items()},
        "t_env_us": round(1e6 * t_env, 1),
        "t_ipc_us": {"gym_async": round(1e6 * t_ipc_gym, 1),
                     "sb3_subproc": round(1e6 * t_ipc_sb3, 1)},
        "model_gym_async_env_steps_per_s": model,
        "anatomy_us": anatomy(env_id, 2 * steps),
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", default="slipenv/HuskySand-v0")
    ap.add_argument("--steps", type=int, default=200)
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    r = run(args.env, args.steps, args.repeats)
    print(f"{r['env']}: {r['steps']} batched steps, median of {r['repeats']}, "
          f"{r['cpu_count']} CPUs")
    print(f"{'setting':<18} {'total env steps/s':>18}")
    for k, v in r["env_steps_per_s"].items():
        print(f"{k:<18} {v:>18.1f}")
    print(f"t_env = {r['t_env_us']} us per step in one process; IPC per step: "
          f"gym async {r['t_ipc_us']['gym_async']} us, SB3 {r['t_ipc_us']['sb3_subproc']} us")
    print("model, n workers on n free cores (gym async): "
          + ", ".join(f"{k.replace('_', ' ')}: {v:.0f}/s"
                      for k, v in r["model_gym_async_env_steps_per_s"].items()))
    a = r["anatomy_us"]
    print(f"one SB3 worker: round trip {a['worker_round_trip_us']:.0f} us per step, of which "
          f"the env's own step {a['worker_step_wall_us']:.0f} us (CPU "
          f"{a['worker_step_cpu_us']:.0f}); the same step in this process "
          f"{a['in_process_step_wall_us']:.0f} us (round trip through DummyVecEnv "
          f"{a['in_process_round_trip_us']:.0f} us)")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(r, fh, indent=2)


if __name__ == "__main__":
    main()
