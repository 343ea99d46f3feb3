"""Shared builders for simulator tests."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.sim.simulator import Simulator
from slipenv.terrain.terrain import TerrainSpec


@pytest.fixture
def make_sim():
    """``make_sim(vehicle, soil, force_model, terrain=None, force_options=None, **sim_kw)`` -> a
    Simulator (the force model built from its name with ``force_options``), closed after."""
    sims = []

    def build(vehicle: str, soil: str, force_model: str, terrain: TerrainSpec | None = None,
              force_options: dict | None = None, **kw) -> Simulator:
        spec = make_vehicle(vehicle)
        sim = Simulator(spec, terrain or TerrainSpec(),
                        make_force_model(force_model, spec, force_options),
                        make_soil_map(soil, None), **kw)
        sims.append(sim)
        return sim

    yield build
    for sim in sims:
        sim.close()


def hold(sim: Simulator, seconds: float):
    """Brakes on (zero wheel speed, full torque) for ``seconds``; returns the last truth."""
    zero = [0.0] * len(sim.spec.channels)
    steer = [0.0] * len(sim.spec.wheels)
    truth = None
    for _ in range(int(round(seconds / sim.control_dt_s))):
        truth = sim.step(zero, steer)
    return truth


def drive(sim: Simulator, v_mps: float, omega_rad_s: float, seconds: float):
    """Command a body twist for ``seconds``; returns the list of truths."""
    from slipenv.vehicles.kinematics import twist_to_commands

    speeds, steer = twist_to_commands(sim.spec, v_mps, omega_rad_s)
    return [sim.step(speeds, steer) for _ in range(int(round(seconds / sim.control_dt_s)))]


def turn_and_stop(sim: Simulator) -> np.ndarray:
    """2 s from the current state: accelerate, turn hard, stop on the spot; per control step
    the truth and every per-wheel state of the injector (to compare two runs bit for bit)."""
    from slipenv.vehicles.kinematics import twist_to_commands

    rows = []
    for i in range(40):
        v, w = (0.6, 0.0) if i < 15 else ((0.4, 1.2) if i < 30 else (0.0, 0.0))
        speeds, steer = twist_to_commands(sim.spec, v, w)
        truth = sim.step(speeds, steer)
        inj = sim.injector
        rows.append(np.concatenate([
            truth.position_m, truth.velocity_body_mps, [truth.yaw_rate_rad_s],
            inj.s, inj.b, inj.load, inj.fx, inj.fy, inj.res, inj.damper,
            np.ravel(inj.resistance_force_n)]))
    return np.array(rows)
