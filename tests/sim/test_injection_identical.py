"""The per-substep force injection is bit-for-bit what it was when the fixture was recorded.

Issue 15 item 2 makes `WheelSoilInjector.apply` cheaper (fewer PyBullet calls, less Python);
the trajectories must not move by one ulp. The reference, ``data/injection_reference.npz``, was
written by ``data/make_injection_fixture.py`` on the code before that change: 60 steps of every
registered env id from seed 0 under seeded random actions (true pose and wheel contact state).
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from slipenv.envs.registration import PRESETS

DATA = Path(__file__).with_name("data")
_spec = importlib.util.spec_from_file_location("make_injection_fixture",
                                               DATA / "make_injection_fixture.py")
assert _spec is not None and _spec.loader is not None
fixture = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fixture)


@pytest.fixture(scope="module")
def reference() -> dict[str, np.ndarray]:
    with np.load(DATA / "injection_reference.npz") as data:
        return {k: data[k] for k in data.files}


def test_reference_covers_every_registered_env(reference):
    recorded = {key.split("|")[0] for key in reference}
    assert recorded == set(PRESETS)


@pytest.mark.parametrize("env_id", sorted(PRESETS))
def test_trajectory_is_bit_identical_to_reference(env_id, reference):
    now = fixture.record(env_id)
    for key, value in now.items():
        ref = reference[f"{env_id}|{key}"]
        assert value.shape == ref.shape, key
        np.testing.assert_array_equal(value, ref, err_msg=f"{env_id} {key}")
