"""The rover on a loose slope beyond its traction limit digs in instead of sliding away.

Reina's net law gives at most about 0.33 W at full slip on loose sand, below W sin 20°; with
only the rate-independent motion resistance the rover commanded uphill slides down at metres
per second, and braked it slides too. With the slip-sinkage option (the soil a spinning or
locked wheel digs out is bulldozed ahead of it: Lyasko 2010, Bekker 1956) it stalls or creeps
below 1 cm/s, and on the flat it still drives at its commanded speed.
"""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401  (registers the envs)

CREEP_MPS = 0.01
DIG_IN = {"slip_sinkage": "bulldozing"}


def downhill_speed(slope_deg: float, soil: str, command: float, seconds: float,
                   force_model_kwargs: dict) -> tuple[float, float]:
    """(downhill speed [m/s] at the end, mean forward speed [m/s]) of the rover facing straight
    up the slope (the downhill direction is world -x) under a constant speed command."""
    env = gym.make("slipenv/Configurable-v0", vehicle="rover_4ws", soil=soil,
                   force_model="reina", force_model_kwargs=force_model_kwargs,
                   path="straight", start_jitter=(0.0, 0.0), max_episode_s=seconds + 5.0,
                   terrain={"kind": "slope", "slope_deg": slope_deg,
                            "downhill_azimuth_deg": 180.0})
    try:
        _, info = env.reset(seed=0)
        x0 = info["true_pose"][0]
        action = np.array([command, 0.0], dtype=np.float32)
        for _ in range(round(seconds / env.unwrapped.control_dt_s)):
            _, _, terminated, truncated, info = env.step(action)
            assert not (terminated or truncated)
        forward = float(info["true_velocity_body_mps"][0])
        return -forward, (info["true_pose"][0] - x0) / seconds
    finally:
        env.close()


def test_commanded_up_20_deg_loose_sand_the_rover_stalls_instead_of_sliding_down():
    down, _ = downhill_speed(20.0, "loose_sand", 1.0, 12.0, DIG_IN)
    assert abs(down) < CREEP_MPS


def test_without_slip_sinkage_the_same_rover_slides_down_the_20_deg_slope():
    down, _ = downhill_speed(20.0, "loose_sand", 1.0, 12.0, {})
    assert down > 1.0


@pytest.mark.parametrize(("slope_deg", "soil"), [(20.0, "loose_sand"), (25.0, "loose_sand"),
                                                 (25.0, "lunar_simulant")])
def test_braked_on_a_steep_loose_slope_the_rover_holds(slope_deg, soil):
    down, mean = downhill_speed(slope_deg, soil, 0.0, 6.0, DIG_IN)
    assert abs(down) < CREEP_MPS and abs(mean) < CREEP_MPS


def test_with_slip_sinkage_the_rover_still_drives_on_flat_loose_sand():
    _, mean = downhill_speed(0.0, "loose_sand", 1.0, 12.0, DIG_IN)
    assert mean > 0.25
