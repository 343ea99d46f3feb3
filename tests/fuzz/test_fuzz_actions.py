"""Fuzz ``step`` with actions of every dtype, shape and value on one reused env.

Each action is either taken (finite observation and reward) or refused with a ``ValueError``
that names the action; the env stays usable after a refusal.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp

import slipenv  # noqa: F401

from .conftest import FUZZ, time_limit

DTYPES = [np.float16, np.float32, np.float64, np.int8, np.int32, np.int64, np.uint8, np.bool_,
          np.complex64, np.complex128, np.str_, np.object_]
SHAPES = [(), (0,), (1,), (2,), (3,), (2, 1), (1, 2), (2, 2)]


@st.composite
def arrays(draw):
    dtype = np.dtype(draw(st.sampled_from(DTYPES)))
    shape = draw(st.sampled_from(SHAPES))
    if dtype.kind in "fc":
        elements = st.floats(allow_nan=True, allow_infinity=True, width=32)
        if dtype.kind == "c":
            elements = st.complex_numbers(allow_nan=True, allow_infinity=True, width=64)
        return draw(hnp.arrays(dtype, shape, elements=elements))
    if dtype.kind == "O":
        return draw(hnp.arrays(dtype, shape, elements=st.sampled_from([None, 1.0, "a", []])))
    return draw(hnp.arrays(dtype, shape))


actions = st.one_of(
    arrays(),
    st.lists(st.one_of(st.floats(), st.integers(-10**30, 10**30), st.text(max_size=2)),
             max_size=3),
    st.tuples(st.floats(-2, 2), st.floats(-2, 2)),
    st.sampled_from([None, "go", b"\x00\x01", {"v": 1}, 1.0, [[0.1, 0.2]], [1e308, -1e308]]),
)


@pytest.fixture(scope="module")
def env():
    env = gym.make("slipenv/HuskySand-v0")
    env.reset(seed=0)
    yield env.unwrapped  # unwrapped: the env's own validation, not Gymnasium's checker
    env.close()


@FUZZ
@given(action=actions)
def test_step_takes_a_real_finite_pair_or_refuses_it_naming_the_action(env, action):
    with time_limit():
        try:
            obs, reward, terminated, truncated, _ = env.step(action)
        except ValueError as exc:
            assert "action" in str(exc)
            obs, reward, terminated, truncated, _ = env.step(np.zeros(2))  # still usable
        assert np.all(np.isfinite(obs)) and math.isfinite(reward)
        if terminated or truncated:
            env.reset(seed=1)
