"""Shared builders for simulator tests."""

from __future__ import annotations

import pytest

from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.sim.simulator import Simulator
from slipenv.terrain.terrain import TerrainSpec


@pytest.fixture
def make_sim():
    """``make_sim(vehicle, soil, force_model, terrain=None)`` -> a Simulator, closed after."""
    sims = []

    def build(vehicle: str, soil: str, force_model: str, terrain: TerrainSpec | None = None,
              **kw) -> Simulator:
        spec = make_vehicle(vehicle)
        sim = Simulator(spec, terrain or TerrainSpec(), make_force_model(force_model, spec),
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
