"""One seed gives one episode: every output of ``reset`` and ``step`` the same bit for bit.

Two envs made in the same process from the same seed and the same actions must agree on the
observations, rewards, flags and every number in ``info`` (the sensor frame, the wheel states,
the estimator's extras, the camera frame's pixels), with ``np.array_equal``; another seed must
change them (one env reset with the same seed again: ``test_seeds_and_defaults.py``). Nothing
is compared with a recording: trajectories may move when the physics is corrected, but never
between two runs on the same machine.
"""

from __future__ import annotations

import dataclasses

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401
from slipenv.envs.registration import PRESETS

STEPS = 40
CAMERA_ID = "slipenv/RoverMoundsVisual-v0"
CAMERA_ACTION = np.array([0.5, 0.1], dtype=np.float32)  # lays traces FTrace finds


def flatten(prefix: str, value, out: dict[str, np.ndarray]) -> None:
    """Every number in ``value`` as an array under a dotted key (nested dicts, dataclasses and
    sequences followed; strings as their bytes; None skipped)."""
    if value is None:
        return
    if isinstance(value, str):
        out[prefix] = np.frombuffer(value.encode(), dtype=np.uint8)
    elif isinstance(value, dict):
        for key in sorted(value):
            flatten(f"{prefix}.{key}", value[key], out)
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            flatten(f"{prefix}.{f.name}", getattr(value, f.name), out)
    else:
        array = np.asarray(value)
        assert array.dtype.kind in "biuf", f"{prefix}: unexpected {type(value)}"
        out[prefix] = array


def episode(env_id: str, seed: int, steps: int = STEPS, action: np.ndarray | None = None,
            **kwargs) -> list[dict[str, np.ndarray]]:
    """Everything ``reset(seed)`` and up to ``steps`` steps return, per step; actions drawn
    from a generator seeded with ``seed`` unless a constant ``action`` is given."""
    env = gym.make(env_id, **kwargs)
    rng = np.random.default_rng(seed)
    try:
        obs, info = env.reset(seed=seed)
        rows = [{}]
        flatten("obs", obs, rows[-1])
        flatten("info", info, rows[-1])
        space = env.action_space
        for _ in range(steps):
            a = rng.uniform(space.low, space.high).astype(space.dtype) if action is None \
                else action
            obs, reward, terminated, truncated, info = env.step(a)
            rows.append({})
            flatten("obs", obs, rows[-1])
            flatten("step", (reward, terminated, truncated), rows[-1])
            flatten("info", info, rows[-1])
            if terminated or truncated:
                break
    finally:
        env.close()
    return rows


def same(a: np.ndarray, b: np.ndarray) -> bool:
    """Equal arrays, NaN equal to NaN (a value absent in both runs, e.g. no trace seen)."""
    return np.array_equal(a, b, equal_nan=a.dtype.kind == "f" and b.dtype.kind == "f")


def assert_identical(a: list[dict[str, np.ndarray]], b: list[dict[str, np.ndarray]]) -> None:
    assert len(a) == len(b)
    for step, (row_a, row_b) in enumerate(zip(a, b, strict=True)):
        assert sorted(row_a) == sorted(row_b), step
        for key, value in row_a.items():
            assert same(value, row_b[key]), f"step {step}: {key} differs"


def differ(a: list[dict[str, np.ndarray]], b: list[dict[str, np.ndarray]], key: str) -> bool:
    values_a = [row[key] for row in a if key in row]
    values_b = [row[key] for row in b if key in row]
    return len(values_a) != len(values_b) or not all(
        same(x, y) for x, y in zip(values_a, values_b, strict=True))


@pytest.mark.parametrize("env_id", sorted(PRESETS))
def test_the_same_seed_gives_the_same_episode_bit_for_bit(env_id):
    first = episode(env_id, seed=5)
    assert len(first) > 10
    assert_identical(first, episode(env_id, seed=5))


@pytest.mark.parametrize("env_id", sorted(PRESETS))
def test_another_seed_gives_another_episode(env_id):
    first, other = episode(env_id, seed=5, steps=10), episode(env_id, seed=6, steps=10)
    assert differ(first, other, "info.true_pose")  # the start jitter
    assert differ(first, other, "obs")  # the jitter and the sensor noise reach the estimate


def test_the_camera_episode_is_the_same_bit_for_bit_and_ftrace_sees_traces():
    first = episode(CAMERA_ID, 0, 120, CAMERA_ACTION, camera_in_info=True)
    frames = [row for row in first if "info.trace_frame.image" in row]
    assert len(frames) >= 20  # 5 Hz over 6 s
    assert sum("info.trace_detection.angle_rad" in row for row in first) > 10
    assert_identical(first, episode(CAMERA_ID, 0, 120, CAMERA_ACTION, camera_in_info=True))

