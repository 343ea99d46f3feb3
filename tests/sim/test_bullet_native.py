"""The compiled loop reads PyBullet through Bullet's C API, bit for bit as through pybullet's
Python functions, and falls back to them when it cannot (slipenv/sim/bullet_native.h)."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim import bullet_native, compiled
from slipenv.sim.wheel_soil import WheelSoilInjector
from tests.sim.conftest import turn_and_stop

p = import_pybullet()

needs_native = pytest.mark.skipif(
    compiled.wheel_loop_module() is None or bullet_native.client_table() is None,
    reason="native PyBullet access needs the compiled wheel loop (pip install -e .) and a "
           "pybullet module with an ELF symbol table (Linux wheels have one)")


def _drive(sim, native: bool | None = None, bind: tuple | None = None) -> np.ndarray:
    """2 s: accelerate, turn hard, stop; per control step the truth and the wheel state.

    After the reset (which builds the injector): `native` switches the loop's native queries,
    `bind` binds them to another client table (`WheelLoop.bind_native`'s arguments).
    """
    sim.reset(0.0, 0.0, 0.3)
    if native is not None:
        sim.injector._loop.native = native
    if bind is not None:
        sim.injector._loop.bind_native(*bind)
    return turn_and_stop(sim)


def test_elf_symbols_reads_nothing_from_a_file_that_is_not_elf(tmp_path):
    path = tmp_path / "not_a_module.so"
    path.write_bytes(b"#!/bin/sh\n" * 10)
    assert bullet_native.elf_symbols(path, {"sPhysicsClients1"}) == {}


@needs_native
def test_pybullets_client_table_is_found_with_one_pointer_per_client():
    table = bullet_native.client_table()
    assert table.n_clients >= 16  # pybullet.c: MAX_PHYSICS_CLIENTS (1024 in 3.2.x)
    value, size = bullet_native.elf_symbols(table.path, {"sPhysicsClients1"})["sPhysicsClients1"]
    assert (value, size) == (table.offset, table.n_clients * struct.calcsize("P"))


@needs_native
@pytest.mark.parametrize("vehicle, soil, force_model", [
    ("farm_2wd", "field_loam", "janosi"),
    ("rover_4ws", "lunar_simulant", "reina"),
    ("husky", "loose_sand", "linear"),
])
def test_native_drive_is_bit_identical_to_the_python_api(make_sim, vehicle, soil, force_model):
    sim = make_sim(vehicle, soil, force_model)
    via_python = _drive(sim, native=False)
    via_native = _drive(sim, native=True)
    assert sim.injector.native_queries and sim.injector._loop.native_verified
    assert via_native.tobytes() == via_python.tobytes()


@needs_native
def test_registered_wheel_envs_read_pybullet_natively():
    import gymnasium as gym

    import slipenv  # noqa: F401  (registers the envs)

    env = gym.make("slipenv/HuskySand-v0")
    try:
        env.reset(seed=0)
        for _ in range(3):
            env.step(env.action_space.sample())
        loop = env.unwrapped._sim.injector._loop
        assert loop.native and loop.native_verified and not loop.native_mismatch
    finally:
        env.close()


@needs_native
def test_readings_that_differ_from_the_python_api_switch_the_loop_back_to_it(make_sim):
    """Bound to another client's slot (another world), the native readings differ from the
    Python API's on the first substep with contact; the loop keeps the Python API, and the
    drive is the Python API's."""
    sim = make_sim("husky", "loose_sand", "linear")
    reference = _drive(sim, native=False)
    other = p.connect(p.DIRECT)
    try:
        p.createMultiBody(1.0, p.createCollisionShape(p.GEOM_SPHERE, radius=0.2,
                                                      physicsClientId=other),
                          physicsClientId=other)
        table = bullet_native.client_table()
        shift = (other - sim.client) * struct.calcsize("P")
        drive = _drive(sim, bind=(table.path, table.offset + shift, table.n_clients,
                                  table.anchor_offset))
        loop = sim.injector._loop
        assert loop.native_mismatch and not loop.native
        assert drive.tobytes() == reference.tobytes()
    finally:
        p.disconnect(other)


@needs_native
def test_a_disconnected_client_is_pybullets_own_error(make_sim):
    sim = make_sim("husky", "loose_sand", "linear")
    assert sim.injector.native_queries
    injector = sim.injector
    p.disconnect(sim.client)
    with pytest.raises(p.error, match="Not connected"):
        injector.apply()


def test_native_queries_required_but_switched_off_is_a_clear_error(make_sim, monkeypatch):
    sim = make_sim("husky", "loose_sand", "linear")
    monkeypatch.setenv(bullet_native.PYBULLET_API_ENV, "1")
    with pytest.raises(ValueError, match="native_queries=True .*SLIPENV_PYBULLET_API is set"
                       if compiled.wheel_loop_module() is not None else "native_queries=True"):
        WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                          sim.injector.force_model, sim.injector.soil_map, sim.dt_s,
                          native_queries=True)
    injector = WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                                 sim.injector.force_model, sim.injector.soil_map, sim.dt_s)
    assert not injector.native_queries


@pytest.mark.parametrize("key, value", [("native_queries", "yes"), ("compiled", 1)])
def test_switches_that_are_not_booleans_are_a_clear_error(make_sim, key, value):
    sim = make_sim("husky", "loose_sand", "linear")
    with pytest.raises(ValueError, match=f"{key} must be True, False or None"):
        WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                          sim.injector.force_model, sim.injector.soil_map, sim.dt_s,
                          **{key: value})
