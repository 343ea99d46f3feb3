"""Record the reference trajectories of ``test_injection_identical.py`` (run on the code to freeze).

For every registered env id (seed 0): 60 steps under actions drawn from a seeded generator,
recording per step the true pose and the injector's per-wheel contact state (load, force law,
resistance, damper share), so that any change of the per-substep force injection shows.

    python tests/sim/data/make_injection_fixture.py   # writes injection_reference.npz here
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

import slipenv  # noqa: F401  (registers the ids)
from slipenv.envs.registration import PRESETS

STEPS = 60
OUT = Path(__file__).with_name("injection_reference.npz")


def record(env_id: str, steps: int = STEPS) -> dict[str, np.ndarray]:
    """Per-step true pose and wheel contact state of ``env_id`` from ``reset(seed=0)``."""
    env = gym.make(env_id)
    try:
        env.reset(seed=0)
        rng = np.random.default_rng(0)
        space = env.action_space
        rows: dict[str, list[np.ndarray]] = {k: [] for k in (
            "true_pose", "wheel_load_n", "wheel_force_n", "wheel_resistance_n",
            "wheel_damper_n", "wheel_slip")}
        for _ in range(steps):
            action = rng.uniform(space.low, space.high).astype(space.dtype)
            _, _, terminated, truncated, info = env.step(action)
            for key, rows_k in rows.items():
                rows_k.append(np.asarray(info[key], dtype=np.float64))
            if terminated or truncated:
                break
        return {k: np.stack(v) for k, v in rows.items()}
    finally:
        env.close()


def main() -> None:
    arrays = {}
    for env_id in sorted(PRESETS):
        for key, value in record(env_id).items():
            arrays[f"{env_id}|{key}"] = value
        print(env_id, arrays[f"{env_id}|true_pose"].shape)
    np.savez_compressed(OUT, **arrays)
    print("wrote", OUT)


if __name__ == "__main__":
    main()
