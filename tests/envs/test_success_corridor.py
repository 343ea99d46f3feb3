"""Success is judged in a corridor that fits the path, and a gate on success fails a policy
that spins in place."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401
from slipenv.envs.config import SlipEnvConfig, corridor_for
from slipenv.envs.registration import PRESETS
from slipenv.evaluation import evaluate
from slipenv.paths import circle, lindgren_straights, straight

TRACKED = "slipenv/TrackedSlopeCircle-v0"
SHORT_TRACKED = {"path_kwargs": {"radius_m": 0.25, "speed_mps": 0.05, "loops": 0.1}}
GATE_ENV = "slipenv/RoverMounds-v0"


class Spinner:
    """Turns in place at full yaw rate, never driving forward."""

    def reset(self) -> None:
        pass

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        return np.array([0.0, 1.0], dtype=np.float32), None


def readme_gate(ev):
    """The gate proposed for the README: the baseline passes it on every seed."""
    ev.assert_below("cross_track_rmse_m", 0.10)
    ev.assert_above("success_rate", 0.99)


@pytest.mark.parametrize(("path", "expected_m"), [
    (circle(radius_m=0.25, speed_mps=0.05), 0.1),  # Yamauchi's circle
    (circle(radius_m=3.0), 1.2),
    (lindgren_straights(turn_radius_m=2.0), 0.8),  # the tightest turn rules, not the straights
    (circle(radius_m=10.0), 2.0),
    (straight(), 2.0),
])
def test_the_default_corridor_is_four_tenths_of_the_tightest_turn_at_most_two_metres(
        path, expected_m):
    assert corridor_for(path) == pytest.approx(expected_m)


@pytest.mark.parametrize("env_id", sorted(PRESETS))
def test_every_registered_env_judges_success_in_a_corridor_inside_its_tightest_turn(env_id):
    env = gym.make(env_id)
    try:
        corridor, path = env.unwrapped.max_cross_track_m, env.unwrapped.path
    finally:
        env.close()
    assert corridor <= 0.4 * path.min_turning_radius_m + 1e-12 and corridor <= 2.0


def test_the_tracked_circle_corridor_is_a_tenth_of_a_metre_and_follows_path_kwargs():
    env = gym.make(TRACKED)
    wide = gym.make(TRACKED, path_kwargs={"radius_m": 1.0, "speed_mps": 0.05})
    try:
        assert env.unwrapped.max_cross_track_m == pytest.approx(0.1)
        assert wide.unwrapped.max_cross_track_m == pytest.approx(0.4)
    finally:
        env.close()
        wide.close()


def test_an_explicit_corridor_is_kept_as_given():
    env = gym.make(TRACKED, max_cross_track_m=0.5)
    try:
        assert env.unwrapped.max_cross_track_m == 0.5
    finally:
        env.close()
    assert SlipEnvConfig(max_cross_track_m=0.05).corridor_m(straight()) == 0.05


@pytest.mark.parametrize("value", [0.0, -0.1, math.nan, math.inf, "1", 1e4])
def test_an_explicit_corridor_must_be_a_finite_positive_number(value):
    with pytest.raises(ValueError, match="max_cross_track_m"):
        gym.make(TRACKED, max_cross_track_m=value)


def test_leaving_the_corridor_ends_the_episode_as_failed():
    """Spinning in place on the 15° slope, the tracked vehicle slides downhill: the episode
    ends as soon as it is more than 0.1 m off the circle (measured 0.101-0.102 m)."""
    ev = evaluate(Spinner(), TRACKED, [0], SHORT_TRACKED)
    (episode,) = ev.per_episode
    assert episode["end_reason"] == "left the path corridor"
    assert ev.success_rate == 0.0
    assert 0.1 < episode["max_cross_track_m"] < 0.11


def test_the_readme_gate_passes_the_baseline_and_fails_a_policy_that_spins_in_place():
    """Measured on seeds 0-2: the baseline 0.045 m RMSE, every path complete; the spinner
    0.0064 m RMSE (it stays at the start, so a cross-track bound alone cannot tell) and no
    success (every episode runs into the time limit; 200 steps show the same)."""
    readme_gate(evaluate("baseline", GATE_ENV, range(3)))
    spin = evaluate(Spinner(), GATE_ENV, range(3), max_steps=200)
    assert spin.cross_track_rmse_m < 0.10  # why the gate needs its success bound
    with pytest.raises(AssertionError, match="success_rate"):
        readme_gate(spin)
