"""Every output of ``env.step`` is bit-for-bit what it was when the fixture was recorded.

Issue 15 items 3 and 5 make the step's Python around the physics cheaper (sensors, truth,
observation, reward, info, the camera pipeline); the observations, rewards, terminations and
every numeric ``info`` entry must not move by one ulp. The reference,
``data/step_reference.npz``, was written by ``data/make_step_fixture.py`` on the code before
that change: the reset and 60 steps of every registered env id from seed 0 under seeded random
actions, plus a camera episode of ``RoverMoundsVisual-v0`` in which FTrace finds traces.
"""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from slipenv.envs.registration import PRESETS

DATA = Path(__file__).with_name("data")
_spec = importlib.util.spec_from_file_location("make_step_fixture", DATA / "make_step_fixture.py")
assert _spec is not None and _spec.loader is not None
fixture = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(fixture)


@pytest.fixture(autouse=True)
def _numpy_lindgren_ekf(monkeypatch):
    """The Lindgren EKF on its numpy path, the one the reference was recorded with: its
    compiled kernel (issue 15 item 3) rounds differently by design, within the bound its own
    tests check; this test pins everything else around the step."""
    monkeypatch.setenv(fixture.LINDGREN_NUMPY_ENV, "1")


@pytest.fixture(scope="module")
def reference() -> dict[str, np.ndarray]:
    with np.load(DATA / "step_reference.npz") as data:
        return {k: data[k] for k in data.files}


def _entries(reference: dict[str, np.ndarray], name: str) -> dict[str, np.ndarray]:
    return {k.split("|", 1)[1]: v for k, v in reference.items() if k.split("|", 1)[0] == name}


# The estimator's own outputs: the numpy Lindgren EKF's matrix products go through BLAS, whose
# kernels (chosen per CPU at run time) may round the last bit differently on another machine
# (seen: 2e-14 relative on an AMD EPYC against the recording machine). Everything else, the
# observation included, stays bit for bit.
_BLAS_KEYS = ("info.estimated_pose", "info.estimator_extras.")
_BLAS_RTOL = 1e-12


def _assert_identical(now: dict[str, np.ndarray], ref: dict[str, np.ndarray], name: str) -> None:
    assert sorted(now) == sorted(ref), f"{name}: the recorded entries changed"
    for key, value in now.items():
        assert value.shape == ref[key].shape, f"{name} {key}"
        if key.startswith(_BLAS_KEYS) and value.dtype.kind == "f":
            np.testing.assert_allclose(value, ref[key], rtol=_BLAS_RTOL, atol=0.0,
                                       err_msg=f"{name} {key}")
        else:
            np.testing.assert_array_equal(value, ref[key], err_msg=f"{name} {key}")


def test_reference_covers_every_registered_env_and_the_camera(reference):
    recorded = {key.split("|")[0] for key in reference}
    assert recorded == set(PRESETS) | {fixture.CAMERA_KEY}
    camera = _entries(reference, fixture.CAMERA_KEY)
    # the camera episode must exercise FTrace: frames rendered and traces detected
    assert camera["info.trace_frame.image#sha256#len"].sum() > 0
    assert camera["info.trace_detection.angle_rad#len"].sum() > 10


@pytest.mark.parametrize("env_id", sorted(PRESETS))
def test_step_outputs_are_bit_identical_to_reference(env_id, reference):
    _assert_identical(fixture.record(env_id), _entries(reference, env_id), env_id)


def test_camera_episode_is_bit_identical_to_reference(reference):
    _assert_identical(fixture.record_camera(), _entries(reference, fixture.CAMERA_KEY),
                      fixture.CAMERA_KEY)
