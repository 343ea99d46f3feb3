"""The rotation run's stop rule and recorder, on a stand-in env (no physics), and its start
heading in the tracked env."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

from slipenv.experiments.yamauchi.rotation import InfoRecorder, TurnLimit, collect_runs
from slipenv.experiments.yamauchi.settings import Settings
from slipenv.rollout import rollout


class Spinner(gym.Env):
    """Turns by ``rate_rad`` per step; reports its heading as ``info["true_pose"][2]``."""

    observation_space = gym.spaces.Box(-1.0, 1.0, (1,))
    action_space = gym.spaces.Box(-1.0, 1.0, (1,))

    def __init__(self, rate_rad: float) -> None:
        self.rate_rad, self.yaw, self.t = rate_rad, 0.0, 0

    def _info(self) -> dict:
        return {"true_pose": np.array([0.0, 0.0, np.angle(np.exp(1j * self.yaw))]),
                "t_s": 0.05 * self.t}

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.yaw, self.t = 0.0, 0
        return np.zeros(1, dtype=np.float32), self._info()

    def step(self, action):
        self.yaw += self.rate_rad
        self.t += 1
        return np.zeros(1, dtype=np.float32), 0.0, False, False, self._info()


@pytest.mark.parametrize("rate", [0.3, -0.3])
def test_the_run_ends_once_the_heading_has_turned_the_limit_either_way(rate):
    rec = InfoRecorder(("true_pose", "t_s"))
    result = rollout(TurnLimit(Spinner(rate), np.radians(90.0)), lambda obs: np.zeros(1),
                     recorders=[rec], max_steps=100)
    assert result.steps == 6  # 5 x 0.3 rad = 1.5 rad < π/2 <= 6 x 0.3 rad
    assert result.truncated and result.end_reason == "turned"
    assert len(rec.rows["t_s"]) == 7  # the reset and every step


def test_turning_through_the_wrap_at_pi_is_counted_as_turning():
    result = rollout(TurnLimit(Spinner(0.5), 4.0), lambda obs: np.zeros(1), max_steps=100)
    assert result.steps == 8  # 8 x 0.5 rad = 4 rad, across ±π


def test_a_run_that_never_turns_far_enough_stops_at_the_step_limit():
    result = rollout(TurnLimit(Spinner(0.01), np.radians(90.0)), lambda obs: np.zeros(1),
                     max_steps=20)
    assert result.steps == 20 and not result.truncated


def test_a_turn_limit_must_be_positive():
    with pytest.raises(ValueError, match="limit_rad"):
        TurnLimit(Spinner(0.1), 0.0)


@pytest.mark.parametrize("start_deg", [0.0, -90.0])
def test_a_rotation_run_starts_at_the_settings_heading_from_across_the_slope(start_deg):
    """Downhill is -y on the slope (heading -90° faces it): 0 starts across the slope, -90
    facing downhill, the heading jitter off."""
    cfg = Settings(tilts_deg=(8.0,), turn_rates_dps=(30.0,), directions=(1,), repeats=1,
                   rotation_deg=5.0, heading_jitter_deg=0.0, start_heading_deg=start_deg)
    (run,) = collect_runs(cfg, np.random.default_rng(0), False)
    assert run.pose[0, 2] == pytest.approx(np.radians(start_deg), abs=0.02)


@pytest.mark.parametrize("field,value", [("start_heading_deg", 200.0), ("cv_folds", 1)])
def test_the_start_heading_and_the_folds_are_validated(field, value):
    with pytest.raises(ValueError, match=field):
        Settings(**{field: value})
