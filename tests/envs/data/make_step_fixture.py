"""Record the reference episodes of ``test_step_identical.py`` (run on the code to freeze).

For every registered env id (seed 0): the reset and 60 steps under actions drawn from a seeded
generator, recording per step everything a user of the env sees: the observation, the reward,
terminated/truncated and every numeric entry of ``info`` (nested dicts, the sensor frame and
any dataclass in it flattened to ``info.<key>.<field>``). Issue 15 item 3 makes the step's
Python around the physics cheaper; none of these may move by one ulp.

    python tests/envs/data/make_step_fixture.py   # writes step_reference.npz here

Entries whose length varies from step to step (beacon bearings, an absent trace detection)
are stored concatenated, with the per-step lengths under ``<key>#len``. Strings are stored as
their UTF-8 bytes; camera images (any array over ``DIGEST_OVER`` elements) as the SHA-256 of
their dtype, shape and bytes. One more episode, ``RoverMoundsVisual-v0`` with
``camera_in_info=True`` under a constant half-speed turn (``CAMERA_ACTION``, which lays traces
that FTrace finds, unlike the random actions), covers the camera and FTrace pipeline. The
Lindgren EKF runs on its numpy path (``SLIPENV_LINDGREN_NUMPY=1``): its compiled kernel rounds
differently by design and is checked against that path by its own tests.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
from pathlib import Path

import gymnasium as gym
import numpy as np

import slipenv  # noqa: F401  (registers the ids)
from slipenv.envs.registration import PRESETS

STEPS = 60
OUT = Path(__file__).with_name("step_reference.npz")
LINDGREN_NUMPY_ENV = "SLIPENV_LINDGREN_NUMPY"
DIGEST_OVER = 4096
CAMERA_ID = "slipenv/RoverMoundsVisual-v0"
CAMERA_KEY = f"{CAMERA_ID}+camera"
CAMERA_STEPS = 120
CAMERA_ACTION = np.array([0.5, 0.1], dtype=np.float32)


def flatten(prefix: str, value, out: dict[str, np.ndarray]) -> None:
    """Every number in ``value`` as a float64 1-D array under a dotted key (None skipped;
    ints and bools are exact in float64 at these magnitudes; strings as UTF-8 bytes, big
    arrays as a digest)."""
    if value is None:
        return
    if isinstance(value, str):
        out[prefix] = np.frombuffer(value.encode(), dtype=np.uint8).astype(np.float64)
        return
    if isinstance(value, dict):
        for key in sorted(value):
            flatten(f"{prefix}.{key}", value[key], out)
    elif dataclasses.is_dataclass(value) and not isinstance(value, type):
        for f in dataclasses.fields(value):
            flatten(f"{prefix}.{f.name}", getattr(value, f.name), out)
    elif isinstance(value, (bool, int, float, np.number, np.bool_, np.ndarray, list, tuple)):
        arr = np.asarray(value)
        if arr.size > DIGEST_OVER:
            digest = hashlib.sha256(f"{arr.dtype}{arr.shape}".encode())
            digest.update(np.ascontiguousarray(arr).tobytes())
            out[prefix + "#sha256"] = np.frombuffer(digest.digest(), np.uint8).astype(np.float64)
        elif arr.dtype.kind in "biuf":
            out[prefix] = arr.astype(np.float64).ravel()


def record(env_id: str, steps: int = STEPS, action: np.ndarray | None = None,
           **make_kwargs) -> dict[str, np.ndarray]:
    """The reset and up to ``steps`` steps of ``env_id`` from ``reset(seed=0)``, flattened;
    actions drawn from a generator seeded 0 unless a constant ``action`` is given."""
    env = gym.make(env_id, **make_kwargs)
    try:
        obs, info = env.reset(seed=0)
        rng = np.random.default_rng(0)
        space = env.action_space
        rows: list[dict[str, np.ndarray]] = []
        row: dict[str, np.ndarray] = {}
        flatten("obs", obs, row)
        flatten("info", info, row)
        rows.append(row)
        for _ in range(steps):
            a = rng.uniform(space.low, space.high).astype(space.dtype) if action is None \
                else action
            obs, reward, terminated, truncated, info = env.step(a)
            row = {}
            flatten("obs", obs, row)
            flatten("reward", reward, row)
            flatten("terminated", terminated, row)
            flatten("truncated", truncated, row)
            flatten("info", info, row)
            rows.append(row)
            if terminated or truncated:
                break
    finally:
        env.close()
    keys = sorted(set().union(*rows))
    out: dict[str, np.ndarray] = {}
    for key in keys:
        parts = [r.get(key, np.zeros(0)) for r in rows]
        out[key] = np.concatenate(parts)
        out[f"{key}#len"] = np.array([len(x) for x in parts], dtype=np.int64)
    return out


def record_camera() -> dict[str, np.ndarray]:
    """The camera episode (module docstring)."""
    return record(CAMERA_ID, CAMERA_STEPS, CAMERA_ACTION, camera_in_info=True)


def main() -> None:
    os.environ[LINDGREN_NUMPY_ENV] = "1"
    arrays = {}
    runs = {env_id: (lambda env_id=env_id: record(env_id)) for env_id in sorted(PRESETS)}
    runs[CAMERA_KEY] = record_camera
    for name, run in runs.items():
        rec = run()
        for key, value in rec.items():
            arrays[f"{name}|{key}"] = value
        print(name, len(rec) // 2, "entries,", len(rec["obs#len"]), "frames")
    np.savez_compressed(OUT, **arrays)
    print("wrote", OUT)


if __name__ == "__main__":
    main()
