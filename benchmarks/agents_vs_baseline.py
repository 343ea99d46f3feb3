"""Benchmark (not a test): PPO training throughput, and a residual PPO agent vs the baseline.

1. Throughput: env steps/s of PPO training (``MlpPolicy``, CPU, one torch thread) with 1 env
   (``DummyVecEnv``) and 2 env processes (``SubprocVecEnv``) on ``slipenv/TrackedSlopeCircle-v0``.
2. For ``slipenv/TrackedSlopeCircle-v0`` (trained on its preset soil, toyoura sand) and
   ``slipenv/FarmField-v0`` (field loam): a residual PPO agent (action = baseline + 0.3 ×
   residual, ``slipenv.agents.residual.ResidualActionWrapper``) trained for ``--timesteps``
   env steps with 2 env processes, then evaluated with :func:`slipenv.evaluation.evaluator`
   next to the baseline on held-out seeds (1000, 1001, ...; training uses 0 and 1) on the
   training soil and on a held-out soil (loose sand, never seen in training). Metrics are
   from the true pose. The target is >= 20 % lower true cross-track RMSE than the
   baseline on the held-out soil; the script prints the change whichever way it comes out.

Budget: the defaults (``--timesteps 120000`` per env, 5 held-out seeds) take about 30 minutes
on 2 cores; ``--quick`` (4 000 steps, 2 seeds, throughput over 1 024 steps) proves the pipeline
in about 3 minutes. Writes ``OUT/agents_vs_baseline.json``, ``OUT/learning_curve.png`` and the
models (``OUT/<env>/model.zip`` with the ``config.json`` that ``slipenv evaluate`` reads).

    python benchmarks/agents_vs_baseline.py --quick
    python benchmarks/agents_vs_baseline.py                 # the stated budget
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch
from stable_baselines3 import PPO
from stable_baselines3.common.callbacks import BaseCallback
from stable_baselines3.common.env_util import make_vec_env
from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

import slipenv  # noqa: F401  (registers the envs)
from slipenv.agents.residual import ResidualActionWrapper
from slipenv.evaluation.evaluator import evaluate

TASKS = {  # env id -> (training soil = the preset's, held-out soil)
    "slipenv/TrackedSlopeCircle-v0": ("toyoura_sand", "loose_sand"),
    "slipenv/FarmField-v0": ("field_loam", "loose_sand"),
}
RESIDUAL_SCALE = 0.3
PPO_KWARGS = dict(n_steps=1024, batch_size=256, learning_rate=3e-4, gamma=0.99,
                  policy_kwargs=dict(net_arch=[64, 64], log_std_init=-1.5))


def make_residual_env(env_id: str) -> gym.Env:
    return ResidualActionWrapper(gym.make(env_id), scale=RESIDUAL_SCALE)


class Curve(BaseCallback):
    """Learning curve: (env steps, mean return of the episodes finished in the rollout, count),
    from the ``info["episode"]`` that SB3's Monitor adds at each episode end."""

    def __init__(self) -> None:
        super().__init__()
        self.points: list[tuple[int, float, int]] = []
        self._returns: list[float] = []

    def _on_step(self) -> bool:
        self._returns += [float(i["episode"]["r"]) for i in self.locals.get("infos", [])
                          if "episode" in i]
        return True

    def _on_rollout_end(self) -> None:
        if self._returns:
            self.points.append((int(self.num_timesteps), float(np.mean(self._returns)),
                                len(self._returns)))
            self._returns = []


def vec_env(env_id: str, n_envs: int, seed: int):
    cls = SubprocVecEnv if n_envs > 1 else DummyVecEnv
    return make_vec_env(make_residual_env, n_envs=n_envs, seed=seed, vec_env_cls=cls,
                        env_kwargs={"env_id": env_id})


def throughput(env_id: str, n_envs: int, steps: int) -> float:
    """PPO training env steps/s (rollouts and updates) with ``n_envs`` env processes."""
    env = vec_env(env_id, n_envs, seed=0)
    model = PPO("MlpPolicy", env, seed=0, device="cpu", verbose=0,
                **{**PPO_KWARGS, "n_steps": max(steps // (2 * n_envs), 64)})
    start = time.perf_counter()
    model.learn(total_timesteps=steps)
    elapsed = time.perf_counter() - start
    env.close()
    return model.num_timesteps / elapsed


def train(env_id: str, timesteps: int, out: Path) -> tuple[Path, list, float]:
    env = vec_env(env_id, 2, seed=0)
    model = PPO("MlpPolicy", env, seed=0, device="cpu", verbose=0, **PPO_KWARGS)
    curve = Curve()
    start = time.perf_counter()
    model.learn(total_timesteps=timesteps, callback=curve)
    elapsed = time.perf_counter() - start
    env.close()
    out.mkdir(parents=True, exist_ok=True)
    model.save(out / "model.zip")
    (out / "config.json").write_text(json.dumps({
        "algo": "ppo", "env_id": env_id, "residual": True, "residual_scale": RESIDUAL_SCALE,
        "timesteps": timesteps, "n_envs": 2, "seed": 0, "ppo_kwargs": PPO_KWARGS}, indent=2))
    return out / "model.zip", curve.points, elapsed


def compare(env_id: str, model: Path, seeds: list[int]) -> dict:
    rows = {}
    for label, soil in zip(("training soil", "held-out soil"), TASKS[env_id], strict=True):
        for policy in ("baseline", str(model)):
            ev = evaluate(policy, env_id, seeds, {"soil": soil})
            name = "baseline" if policy == "baseline" else "residual PPO"
            rows[f"{label}|{name}"] = {"soil": soil, **{k: ev.metrics[k] for k in (
                "cross_track_rmse_m", "mean_cross_track_m", "success_rate", "energy_j")}}
    for label in ("training soil", "held-out soil"):
        base = rows[f"{label}|baseline"]["cross_track_rmse_m"]
        agent = rows[f"{label}|residual PPO"]["cross_track_rmse_m"]
        rows[f"{label}|change"] = {"cross_track_rmse_change_pct": 100.0 * (agent - base) / base}
    return rows


def plot_curves(curves: dict, out_png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    for env_id, points in curves.items():
        if points:
            steps, ret, _ = zip(*points, strict=True)
            ax.plot(steps, ret, marker="o", ms=3, label=env_id)
    ax.set_xlabel("env steps")
    ax.set_ylabel("mean episode return (training episodes)")
    ax.set_title("residual PPO learning curves")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out_png, dpi=110)
    plt.close(fig)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--timesteps", type=int, default=120_000, help="training steps per env")
    parser.add_argument("--seeds", type=int, default=5, help="held-out evaluation seeds")
    parser.add_argument("--throughput-steps", type=int, default=4096)
    parser.add_argument("--quick", action="store_true", help="4000 steps, 2 seeds")
    parser.add_argument("--out", default="runs/bench_agents")
    args = parser.parse_args()
    if args.quick:
        args.timesteps, args.seeds, args.throughput_steps = 4000, 2, 1024
    torch.set_num_threads(1)  # two cores: one per env process, not a torch thread pool
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    t0 = time.perf_counter()
    tracked = "slipenv/TrackedSlopeCircle-v0"
    result: dict = {"budget": {"timesteps_per_env": args.timesteps, "n_envs": 2,
                               "held_out_seeds": list(range(1000, 1000 + args.seeds)),
                               "residual_scale": RESIDUAL_SCALE, "ppo": PPO_KWARGS}}
    result["throughput_steps_per_s"] = {
        f"{n} env{'s' if n > 1 else ''}": throughput(tracked, n, args.throughput_steps)
        for n in (1, 2)}
    print("PPO training throughput on", tracked)
    for k, v in result["throughput_steps_per_s"].items():
        print(f"  {k:<7} {v:8.0f} env steps/s")
    curves = {}
    seeds = result["budget"]["held_out_seeds"]
    for env_id in TASKS:
        model, curves[env_id], elapsed = train(env_id, args.timesteps,
                                               out / env_id.split("/")[-1])
        result[env_id] = {"train_s": elapsed, "learning_curve": curves[env_id],
                          "model": str(model), **compare(env_id, model, seeds)}
        print(f"\n{env_id}: residual PPO, {args.timesteps} steps in {elapsed:.0f} s; held-out "
              f"seeds {seeds}")
        print(f"  {'soil':<30} {'policy':<13} {'ct RMSE [m]':>11} {'success':>8} "
              f"{'energy [J]':>11}")
        for key, row in result[env_id].items():
            if "|" in key and "soil" in row:
                label, name = key.split("|")
                print(f"  {label + ' (' + row['soil'] + ')':<30} {name:<13} "
                      f"{row['cross_track_rmse_m']:>11.4f} {row['success_rate']:>8.2f} "
                      f"{row['energy_j']:>11.1f}")
        for label in ("training soil", "held-out soil"):
            pct = result[env_id][f"{label}|change"]["cross_track_rmse_change_pct"]
            print(f"  {label}: residual PPO cross-track RMSE {pct:+.1f} % vs baseline "
                  f"(target on held-out soil: <= -20 %)")
    plot_curves(curves, out / "learning_curve.png")
    result["wall_s"] = time.perf_counter() - t0
    (out / "agents_vs_baseline.json").write_text(json.dumps(result, indent=2))
    print(f"\nwall time {result['wall_s']:.0f} s; {out / 'agents_vs_baseline.json'}, "
          f"{out / 'learning_curve.png'}")


if __name__ == "__main__":
    main()
