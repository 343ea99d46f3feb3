"""The compiled wheel-soil loop is the Python loop, bit for bit (issue 15 item 1).

``slipenv/sim/_wheel_loop.c`` transcribes the plain functions of ``slip_dynamics``, ``janosi``,
``lindgren``, ``reina``, ``bekker`` and the models' kernels. Each transcription is fuzzed
against its original here (equal as doubles, not close), and whole drives are compared
substep for substep with the Python loop (``SLIPENV_PURE_PYTHON``), on options no registered env
uses (multi-pass, Reina's gross thrust, lateral anisotropy, a soil map). The registered envs
themselves are held to the recorded fixture by ``test_injection_identical.py``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from slipenv.sim import compiled
from slipenv.terramechanics import bekker, slip_dynamics
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import (
    JanosiForceModel,
    LinearSlipForceModel,
    ReinaForceModel,
)
from slipenv.terramechanics.presets import SOILS
from tests.sim.conftest import turn_and_stop

loop = compiled.wheel_loop_module()
pytestmark = pytest.mark.skipif(
    loop is None, reason="the compiled wheel loop was not built (pip install -e . builds it; "
    "setup.py marks it optional) or SLIPENV_PURE_PYTHON is set")

WHEEL = ContactGeometry(radius_m=0.165, width_m=0.1, contact_length_m=0.08)
TRACK = ContactGeometry(radius_m=0.04, width_m=0.06, contact_length_m=0.05, track_length_m=0.48)


def _models():
    out = []
    for geometry in (WHEEL, TRACK):
        for kappa in (1.0, 3.6):
            out.append(JanosiForceModel(geometry, lateral_stiffness_ratio=kappa))
            out.append(LinearSlipForceModel(geometry, lateral_stiffness_ratio=kappa,
                                            rolling_resistance_coeff=0.02))
    for scaled in (True, False):
        for gross in (True, False):
            out.append(ReinaForceModel(WHEEL, scale_stiffness_with_load=scaled,
                                       compaction=gross))
    return out


MODELS = _models()
SOIL_PARAMS = [soil.params() for soil in SOILS.values()]

unit = st.floats(-1.0, 1.0, allow_nan=False)
speed = st.floats(-5.0, 5.0, allow_nan=False)
small = st.one_of(st.just(0.0), st.floats(-1e-6, 1e-6, allow_nan=False))
loads = st.floats(1e-6, 1e4)  # the kernels' contract: W > 0 (the loop skips unloaded wheels)
positive = st.floats(1e-4, 10.0)


def same(a, b) -> bool:
    """Equal as doubles: bit for bit, NaN equal to NaN, 0.0 and -0.0 told apart."""
    a, b = np.atleast_1d(np.asarray(a, dtype=float)), np.atleast_1d(np.asarray(b, dtype=float))
    return a.shape == b.shape and a.tobytes() == b.tobytes()


@settings(max_examples=400, deadline=None)
@given(model=st.sampled_from(MODELS), soil=st.sampled_from(SOIL_PARAMS),
       slip=st.one_of(unit, small), tan_beta=st.one_of(unit, small), load=loads)
def test_kernel_is_each_models_float_law_bit_for_bit(model, soil, slip, tan_beta, load):
    expected = model.scalar_kernel(soil)(slip, tan_beta, load)
    got = loop.kernel(model.kernel_constants(soil), slip, tan_beta, load)
    assert same(got, expected), (model, soil, slip, tan_beta, load, got, expected)


@settings(max_examples=300, deadline=None)
@given(slip=unit, tan_beta=unit, rim=speed, v=speed, v_lat=speed, h=st.floats(0.0, 50.0))
def test_relax_slip_is_the_plain_function(slip, tan_beta, rim, v, v_lat, h):
    assert same(loop.relax_slip(slip, tan_beta, rim, v, v_lat, h),
                slip_dynamics.relax_slip(slip, tan_beta, rim, v, v_lat, h))


@settings(max_examples=200, deadline=None)
@given(change=st.floats(-2.0, 2.0), v_ref=st.floats(0.0, 5.0), d=st.floats(0.0, 1e5),
       fade=positive, rim=speed, v=speed, c=st.floats(0.0, 1e5), low=positive)
def test_soil_dampers_are_the_plain_functions(change, v_ref, d, fade, rim, v, c, low):
    assert same(loop.lateral_soil_damping_n(change, v_ref, d, fade),
                slip_dynamics.lateral_soil_damping_n(change, v_ref, d, fade))
    assert same(loop.longitudinal_soil_damping_n(rim, v, v_ref, c, low),
                slip_dynamics.longitudinal_soil_damping_n(rim, v, v_ref, c, low))


vec3 = st.tuples(st.floats(-1.0, 1.0), st.floats(-1.0, 1.0), st.floats(-1.0, 1.0))


@settings(max_examples=300, deadline=None)
@given(res=st.floats(0.0, 500.0), state=unit, v=speed, dt=st.floats(1e-4, 0.01),
       stick=st.floats(1e-4, 0.01), c=st.floats(0.0, 1e4), u=vec3, vel=vec3,
       a=st.floats(0.0, 300.0), b=st.floats(0.0, 300.0))
def test_resistance_elements_are_the_plain_functions(res, state, v, dt, stick, c, u, vel, a, b):
    assert same(loop.rut_resistance_n(res, state, v * dt, v, stick, c),
                slip_dynamics.rut_resistance_n(res, state, v * dt, v, stick, c))
    got_r, got_u = loop.rut_resistance_vector_n(res, u, vel, dt, stick, c)
    exp_r, exp_u = slip_dynamics.rut_resistance_vector_n(res, u, vel, dt, stick, c)
    assert same(got_r, exp_r) and same(got_u, exp_u)
    assert same(loop.rut_following_compaction_n(a, b), bekker.rut_following_compaction_n(a, b))


def test_a_subclass_that_changes_the_law_is_not_compiled():
    class Doubled(JanosiForceModel):
        def _forces(self, soil):
            law = super()._forces(soil)
            return lambda s, t, w: tuple(2.0 * f for f in law(s, t, w))

    assert Doubled(WHEEL).kernel_constants(SOIL_PARAMS[0]) is None
    assert JanosiForceModel(WHEEL).kernel_constants(SOIL_PARAMS[0]) is not None


# -- whole drives: compiled loop against the Python loop -------------------------------------

def _drive(make_sim, monkeypatch, pure: bool, vehicle: str, soil: str, force_model: str,
           **kw) -> tuple[np.ndarray, bool]:
    if pure:
        monkeypatch.setenv(compiled.PURE_PYTHON_ENV, "1")
    else:
        monkeypatch.delenv(compiled.PURE_PYTHON_ENV, raising=False)
    sim = make_sim(vehicle, soil, force_model, **kw)
    sim.reset(0.0, 0.0, 0.3)
    return turn_and_stop(sim), sim.injector.is_compiled


@pytest.mark.parametrize("vehicle, soil, force_model, kw", [
    ("farm_2wd", "field_loam", "janosi", {"multi_pass": True, "castor_own_geometry": True}),
    ("rover_4ws", "lunar_simulant", "reina", {}),
    ("husky", "loose_sand", "linear", {}),
])
def test_drive_is_bit_identical_to_the_python_loop(make_sim, monkeypatch, vehicle, soil,
                                                   force_model, kw):
    fast, fast_compiled = _drive(make_sim, monkeypatch, False, vehicle, soil, force_model, **kw)
    slow, slow_compiled = _drive(make_sim, monkeypatch, True, vehicle, soil, force_model, **kw)
    assert fast_compiled and not slow_compiled
    assert np.all(np.isfinite(fast))
    assert fast.tobytes() == slow.tobytes(), np.max(np.abs(fast - slow))


def test_compiled_true_with_a_foreign_force_model_is_a_clear_error(make_sim):
    from slipenv.sim.wheel_soil import WheelSoilInjector

    sim = make_sim("husky", "loose_sand", "janosi")

    class Foreign(JanosiForceModel):
        def _forces(self, soil):
            return super()._forces(soil)

    with pytest.raises(ValueError, match="Foreign is not one of slipenv's force models"):
        WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                          Foreign(WHEEL), sim.injector.soil_map, sim.dt_s, compiled=True)
    assert not WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                                 Foreign(WHEEL), sim.injector.soil_map, sim.dt_s).is_compiled


def test_division_by_zero_raises_as_in_python():
    model = ReinaForceModel(WHEEL, scale_stiffness_with_load=False)
    constants = model.kernel_constants(SOIL_PARAMS[0])._replace(mu=0.0)  # Python: / (mu W)
    params = SOIL_PARAMS[0]._replace(mu=0.0)
    with pytest.raises(ZeroDivisionError):
        model.scalar_kernel(params)(0.1, 0.0, 100.0)
    with pytest.raises(ZeroDivisionError):
        loop.kernel(constants, 0.1, 0.0, 100.0)
    assert math.isfinite(loop.kernel(model.kernel_constants(SOIL_PARAMS[0]), 0.1, 0.0, 100.0)[0])


def _episode(env_id: str, seed: int, steps: int = 15) -> tuple[np.ndarray, bool]:
    import gymnasium as gym

    import slipenv  # noqa: F401  (registers the envs)

    env = gym.make(env_id)
    try:
        env.reset(seed=seed)
        rng = np.random.default_rng(seed)
        rows = []
        for _ in range(steps):
            action = rng.uniform(env.action_space.low, env.action_space.high)
            *_, info = env.step(action.astype(env.action_space.dtype))
            rows.append(np.concatenate([info["true_pose"], info["wheel_load_n"],
                                        np.ravel(info["wheel_force_n"]), info["wheel_slip"]]))
        return np.array(rows), env.unwrapped._sim.injector.is_compiled
    finally:
        env.close()


@pytest.mark.parametrize("seed", [3, 1234])
@pytest.mark.parametrize("env_id", ["slipenv/Configurable-v0", "slipenv/FarmField-v0",
                                    "slipenv/HuskySand-v0", "slipenv/RoverMounds-v0",
                                    "slipenv/TrackedSlopeCircle-v0"])
def test_registered_envs_are_bit_identical_to_the_python_loop_for_other_seeds(
        monkeypatch, env_id, seed):
    """The recorded fixture holds seed 0; other seeds start elsewhere and draw other actions."""
    monkeypatch.delenv(compiled.PURE_PYTHON_ENV, raising=False)
    fast, fast_compiled = _episode(env_id, seed)
    monkeypatch.setenv(compiled.PURE_PYTHON_ENV, "1")
    slow, slow_compiled = _episode(env_id, seed)
    assert fast_compiled and not slow_compiled
    assert fast.tobytes() == slow.tobytes(), np.max(np.abs(fast - slow))
