"""The compiled loop reads PyBullet through Bullet's C API, bit for bit as through pybullet's
Python functions, only on the pybullet releases it mirrors, and falls back to the Python API
with one warning when a check fails (slipenv/sim/bullet_native.h)."""

from __future__ import annotations

import struct
import warnings

import numpy as np
import pytest

from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim import bullet_native
from slipenv.sim.wheel_soil import WheelSoilInjector
from slipenv.terrain.terrain import TerrainSpec
from slipenv.vehicles.presets import rover_4ws
from tests.sim.conftest import drive, turn_and_stop

p = import_pybullet()

needs_native = pytest.mark.skipif(
    bullet_native.client_table() is None,
    reason="native PyBullet access needs a pybullet module with an ELF symbol table (Linux "
           "wheels have one) whose version is on the reader's list")


@pytest.fixture(autouse=True)
def _fresh_warnings(monkeypatch):
    """Each test sees the reader's once-per-process warnings anew."""
    monkeypatch.setattr(bullet_native, "_warned", set())


def _drive(sim, native: bool | None = None, bind: tuple | None = None,
           at_step: tuple | None = None) -> np.ndarray:
    """2 s: accelerate, turn hard, stop; per control step the truth and the wheel state.

    After the reset (which builds the injector): `native` switches the loop's native queries,
    `bind` binds them to another client table (`WheelLoop.bind_native`'s arguments);
    `at_step` = (i, fn) calls fn(loop) before control step i.
    """
    sim.reset(0.0, 0.0, 0.3)
    loop = sim.injector._loop
    if native is not None:
        loop.native = native
    if bind is not None:
        loop.bind_native(*bind)
    if at_step is not None:
        step, calls = sim.step, [0]

        def hooked(*args, **kwargs):
            if calls[0] == at_step[0]:
                at_step[1](loop)
            calls[0] += 1
            return step(*args, **kwargs)

        sim.step = hooked
    try:
        return turn_and_stop(sim)
    finally:
        sim.__dict__.pop("step", None)


def _reader_warnings(caught) -> list[str]:
    return [str(w.message) for w in caught if issubclass(w.category,
                                                         bullet_native.NativeReaderWarning)]


def test_the_installed_pybullet_is_on_the_native_readers_list():
    version = bullet_native.pybullet_version()
    assert version in bullet_native.NATIVE_PYBULLET_VERSIONS
    assert p.getAPIVersion() == bullet_native.NATIVE_PYBULLET_VERSIONS[version]
    assert bullet_native.native_refusal() is None


@pytest.mark.parametrize("version, api_version, named", [
    ("3.3.0", 202010061, "pybullet 3.3.0 is not one of the releases"),
    ("3.2.1", 202010061, "pybullet 3.2.1 is not one of the releases"),
    ("3.2.7", 202312010, "reports API version 202312010"),
])
def test_a_pybullet_the_reader_does_not_mirror_is_refused(version, api_version, named):
    assert named in bullet_native.native_refusal(version, api_version)


def test_an_unlisted_pybullet_reads_through_the_python_api_after_one_warning(make_sim,
                                                                              monkeypatch):
    sim = make_sim("husky", "loose_sand", "linear")
    monkeypatch.setattr(bullet_native, "pybullet_version", lambda: "9.9.9")
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        injectors = [WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                                       sim.injector.force_model, sim.injector.soil_map,
                                       sim.dt_s) for _ in range(3)]
    assert not any(injector.native_queries for injector in injectors)
    messages = _reader_warnings(caught)
    assert len(messages) == 1 and "pybullet 9.9.9" in messages[0]


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
        with pytest.warns(bullet_native.NativeReaderWarning, match="failed a check"):
            drive = _drive(sim, bind=table._replace(offset=table.offset + shift))
        loop = sim.injector._loop
        assert loop.native_mismatch and not loop.native
        assert drive.tobytes() == reference.tobytes()
    finally:
        p.disconnect(other)


@needs_native
@pytest.mark.parametrize("at_step", [0, 20])
def test_an_overwritten_guard_region_switches_to_the_python_api_with_one_warning(make_sim,
                                                                                 at_step):
    """A pybullet struct larger than the mirror writes past it into the guard region (simulated
    by the loop's test hook, before the first substep or mid-drive): the loop drops the native
    readings of that substep, warns once and drives on through the Python API, bit for bit as
    a drive through the Python API throughout."""
    sim = make_sim("husky", "loose_sand", "linear")
    reference = _drive(sim, native=False)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        drive = _drive(sim, native=True, at_step=(at_step, lambda loop: loop._scribble_guard()))
    loop = sim.injector._loop
    assert loop.native_mismatch and not loop.native
    messages = _reader_warnings(caught)
    assert len(messages) == 1 and "guard region after b3LinkState" in messages[0]
    assert drive.tobytes() == reference.tobytes()


@needs_native
@pytest.mark.parametrize("every", [0, 25, 5])
def test_native_readings_are_rechecked_against_the_python_api_every_nth_substep_with_contact(
        make_sim, every):
    """After the first substep with contact (during the reset's settling), every `every`-th
    substep with a wheel on the ground is read both ways and compared."""
    sim = make_sim("husky", "loose_sand", "linear")
    sim.reset(0.0, 0.0, 0.3)
    loop = sim.injector._loop
    assert loop.native_verified
    loop.verify_every = every
    before = loop.native_verifications
    contact = [0]

    def apply():
        loop.apply()
        contact[0] += any(load > 0.0 for load in loop.load)

    sim.injector.apply = apply
    turn_and_stop(sim)
    assert contact[0] == 40 * sim.substeps  # the Husky stays on the ground throughout
    assert loop.native and not loop.native_mismatch
    assert loop.native_verifications - before == (contact[0] // every if every else 0)


@needs_native
def test_wheels_leaving_a_heightfield_between_rechecks_keep_the_native_reader(make_sim):
    """The rigid 4WS rover (``rover_4ws(rocker=False)``, no pivoting axle) rocks over
    RoverMounds-v0's mounds (a heightfield): wheels lose and regain
    contact between two rechecks. A wheel without contact has no contact-patch reading (the
    loop skips it), so the rechecks find the two readings equal, warn nothing and the loop stays
    native. Counted alongside: rechecks at which a wheel had left the ground since it last
    touched it, the case in which comparing its leftover patch sums reported a mismatch."""
    terrain = TerrainSpec(kind="mounds", mound_height_m=0.06, mound_radius_m=0.4,
                          mound_count=30, size_m=8.0, clear_radius_m=0.6)
    sim = make_sim(rover_4ws(rocker=False), "lunar_simulant", "reina", terrain=terrain)
    sim.reset(0.0, 0.0, 0.3)
    loop = sim.injector._loop
    assert loop.native_verified
    every = 10
    loop.verify_every = every
    before = loop.native_verifications
    touched = [False] * len(loop.load)  # in contact between rechecks
    counts = {"contact": 0, "lifted_at_recheck": 0}

    def apply():
        checks = loop.native_verifications
        loop.apply()
        loads = loop.load
        counts["contact"] += any(load > 0.0 for load in loads)
        if loop.native_verifications > checks:
            counts["lifted_at_recheck"] += any(t and load == 0.0
                                               for t, load in zip(touched, loads, strict=True))
            touched[:] = [False] * len(loads)
        else:
            touched[:] = [t or load > 0.0 for t, load in zip(touched, loads, strict=True)]

    sim.injector.apply = apply
    with warnings.catch_warnings():
        warnings.simplefilter("error", bullet_native.NativeReaderWarning)
        drive(sim, 0.3, 0.0, 4.0)
    # the drive crossed mounds and the case occurred (14 times with the laws of this writing;
    # one occurrence made the comparison of leftover patch sums fail)
    assert counts["lifted_at_recheck"] >= 3
    assert loop.native and not loop.native_mismatch
    assert loop.native_verifications - before == counts["contact"] // every


@needs_native
def test_the_default_recheck_interval_is_the_modules(make_sim):
    sim = make_sim("husky", "loose_sand", "linear")
    sim.reset(0.0, 0.0, 0.3)
    assert sim.injector._loop.verify_every == bullet_native.VERIFY_EVERY > 0


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
    with pytest.raises(ValueError, match="native_queries=True .*SLIPENV_PYBULLET_API is set"):
        WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                          sim.injector.force_model, sim.injector.soil_map, sim.dt_s,
                          native_queries=True)
    injector = WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                                 sim.injector.force_model, sim.injector.soil_map, sim.dt_s)
    assert not injector.native_queries


@pytest.mark.parametrize("key, value", [("native_queries", "yes"), ("native_queries", 1)])
def test_switches_that_are_not_booleans_are_a_clear_error(make_sim, key, value):
    sim = make_sim("husky", "loose_sand", "linear")
    with pytest.raises(ValueError, match=f"{key} must be True, False or None"):
        WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                          sim.injector.force_model, sim.injector.soil_map, sim.dt_s,
                          **{key: value})


@needs_native
def test_bench_names_the_path_each_env_read_pybullet_through(monkeypatch):
    import gymnasium as gym

    import slipenv  # noqa: F401  (registers the envs)
    from slipenv import bench

    env = gym.make("slipenv/HuskySand-v0")
    try:
        env.reset(seed=0)
        native = bench.pybullet_path(env.unwrapped)
        monkeypatch.setenv(bullet_native.PYBULLET_API_ENV, "1")
        env.reset(seed=0)  # builds a new injector, which reads the switch
        public = bench.pybullet_path(env.unwrapped)
    finally:
        env.close()
    assert (native, public) == ("native", "public API")
    row = {"env_steps_per_s": 300.0, "substeps_per_step": 12, "bare_substeps_per_s": 7000.0,
           "ratio": 0.5, "realtime_factor": 15.0}
    text = bench.format_bench({"envs": {"a": {**row, "pybullet_path": native},
                                        "b": {**row, "pybullet_path": public}}})
    lines = text.splitlines()
    assert lines[0].endswith("PyBullet read")
    assert lines[2].startswith("a ") and lines[2].endswith("  native")
    assert lines[3].startswith("b ") and lines[3].endswith("  public API")
