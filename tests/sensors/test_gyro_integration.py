"""The simulated gyro integrates: its readings sum to the body's turn on every vehicle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.sensors.noise import SensorNoise
from slipenv.sensors.onboard import SensorSuite
from slipenv.sim.simulator import Simulator
from slipenv.terrain.terrain import TerrainSpec
from slipenv.vehicles.kinematics import twist_to_commands
from slipenv.vehicles.presets import VEHICLES

PERIOD_S = 1.2  # [s] of the commanded yaw-rate sine: several control steps per swing


def weave(name: str, seconds: float = 2.4, sampling: str = "mean"):
    """Drive ``name`` on level concrete with a sine yaw-rate command, the speed ramped up over
    the first second; (gyro [rad/s], dt [s], unwrapped true yaw [rad], largest |roll| or
    |pitch| [rad]) per control step, the reset's reading first."""
    spec = make_vehicle(name)
    sim = Simulator(spec, TerrainSpec(), make_force_model("janosi", spec),
                    make_soil_map("concrete", None))
    suite = SensorSuite(spec.counts_per_rad, SensorNoise.perfect(), gyro_sampling=sampling)
    rng = np.random.default_rng(0)
    try:
        truth = sim.reset(0.0, 0.0, 0.3)
        frames, yaws, tilt = [suite.measure(truth, rng)], [truth.yaw_rad], 0.0
        for k in range(int(round(seconds / sim.control_dt_s))):
            t = k * sim.control_dt_s
            v = 0.6 * spec.max_speed_mps * min(1.0, t / 1.0)
            omega = 0.8 * spec.max_yaw_rate_rad_s * math.sin(2 * math.pi * t / PERIOD_S)
            truth = sim.step(*twist_to_commands(spec, v, omega))
            frames.append(suite.measure(truth, rng))
            yaws.append(truth.yaw_rad)
            tilt = max(tilt, abs(truth.roll_rad), abs(truth.pitch_rad))
    finally:
        sim.close()
    gyro = np.array([f.gyro_z_rad_s for f in frames])
    t = np.array([f.t_s for f in frames])
    return gyro, np.diff(t), np.unwrap(yaws), tilt


@pytest.mark.parametrize("name", sorted(VEHICLES))
def test_the_gyro_readings_integrate_to_the_true_heading_change(name):
    gyro, dt, yaw, tilt = weave(name)
    # the body does turn, and back: the rate varies within and between samples
    assert np.ptp(gyro) > 0.5 * VEHICLES[name]().max_yaw_rate_rad_s
    # the gyro turns about the body's z axis, the heading about the world's: they part by
    # O(tilt²) of the turn, below 1e-6 rad only while the chassis stays level to 2 mrad
    assert tilt < 2e-3
    np.testing.assert_allclose(np.sum(gyro[1:] * dt), yaw[-1] - yaw[0], rtol=0, atol=1e-6)
    # and sample by sample: each reading is its interval's turn over the interval (a gyro
    # sampling the instantaneous rate misses by 2-7e-3 rad in some interval of these drives,
    # and by 1e-3 to 2e-2 rad over the whole drive)
    np.testing.assert_allclose(gyro[1:] * dt, np.diff(yaw), rtol=0, atol=1e-6)
