"""The injector's ``multi_pass`` and the force models' ``lateral_stiffness_ratio``
are make options that reach the physics; bad values fail at make time; defaults are off / 1."""

from __future__ import annotations

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401  (registers the envs)
from slipenv.envs.config import SlipEnvConfig
from slipenv.terramechanics.presets import soil_by_name

CONF = "slipenv/Configurable-v0"


def test_the_defaults_are_single_pass_and_the_models_own_options():
    cfg = SlipEnvConfig()
    assert cfg.multi_pass is False and cfg.force_model_kwargs == {}
    env = gym.make(CONF, vehicle="rover_4ws", force_model="janosi")
    try:
        sim = env.unwrapped._sim
        assert sim.injector.multi_pass is False
        assert sim.force_model.lateral_stiffness_ratio == 1.0
    finally:
        env.close()


def _front_and_rear_resistance(multi_pass: bool) -> tuple[np.ndarray, np.ndarray]:
    """Rover driven straight on loose sand for 2 s: mean resistance of front and rear wheels."""
    env = gym.make(CONF, vehicle="rover_4ws", soil="loose_sand", force_model="janosi",
                   path="straight", multi_pass=multi_pass, start_jitter=(0.0, 0.0))
    try:
        env.reset(seed=0)
        rows = []
        for _ in range(40):
            *_, info = env.step(np.array([0.5, 0.0]))
            rows.append(info["wheel_resistance_n"])
        res = np.mean(rows[20:], axis=0)
        return res[:2], res[2:]
    finally:
        env.close()


def test_multi_pass_lowers_only_the_rear_wheels_resistance_on_the_rover():
    """The rover's rear wheels run in the front wheels' ruts (Wong §2.4): with multi_pass they
    meet only f_r W plus the compaction below the rut, with equal loads about f_r W alone,
    while the front wheels still cut their own ruts."""
    front_1, rear_1 = _front_and_rear_resistance(False)
    front_m, rear_m = _front_and_rear_resistance(True)
    assert np.all(rear_m < 0.5 * rear_1)
    np.testing.assert_allclose(front_m, front_1, rtol=0.1)  # load transfer only


@pytest.mark.parametrize("model", ["janosi", "linear"])
def test_lateral_stiffness_ratio_reaches_the_simulated_force_law(model):
    """kappa = 3.6 (Reina Table 3) raises the small-slip side force 3.6x, the thrust not at
    all, in the force model the simulator injects."""
    forces = {}
    for kappa in (1.0, 3.6):
        env = gym.make(CONF, vehicle="husky", force_model=model,
                       force_model_kwargs={"lateral_stiffness_ratio": kappa})
        try:
            sim = env.unwrapped._sim
            assert sim.injector.force_model is sim.force_model
            kernel = sim.force_model.scalar_kernel(soil_by_name("loose_sand").params())
            forces[kappa] = (kernel(0.0, 1e-4, 100.0)[1], kernel(1e-4, 0.0, 100.0)[0])
        finally:
            env.close()
    assert forces[3.6][0] == pytest.approx(3.6 * forces[1.0][0], rel=1e-3)
    assert forces[3.6][1] == pytest.approx(forces[1.0][1], rel=1e-9)


@pytest.mark.parametrize(("kwargs", "names"), [
    (dict(multi_pass="yes"), "multi_pass"),
    (dict(vehicle="tracked_patako_wong_chiang", multi_pass=True), "multi_pass"),
    (dict(force_model="janosi", force_model_kwargs={"lateral_stiffness_ratio": 0.0}),
     "lateral_stiffness_ratio"),
    (dict(force_model="janosi", force_model_kwargs={"lateral_stiffness_ratio": float("nan")}),
     "lateral_stiffness_ratio"),
    (dict(force_model="linear", force_model_kwargs={"lateral_stiffness_ratio": "3.6"}),
     "lateral_stiffness_ratio"),
    (dict(force_model="janosi", force_model_kwargs={"lateral_ratio": 3.6}),
     "did you mean 'lateral_stiffness_ratio'"),
    (dict(force_model="reina", force_model_kwargs={"lateral_stiffness_ratio": 3.6}),
     "Reina's law has its own lateral stiffness"),
    (dict(force_model="reina", force_model_kwargs={"compaction": 1}), "compaction"),
    (dict(force_model_kwargs=["lateral_stiffness_ratio"]), "force_model_kwargs"),
    (dict(castor_own_geometry="yes"), "castor_own_geometry"),
])
def test_bad_force_options_fail_at_make_naming_the_option(kwargs, names):
    with pytest.raises(ValueError, match=names):
        gym.make(CONF, **kwargs)


def test_force_model_kwargs_with_a_model_instance_are_refused():
    from slipenv.envs.factory import contact_geometry
    from slipenv.terramechanics.models import JanosiForceModel
    from slipenv.vehicles.presets import husky

    model = JanosiForceModel(contact_geometry(husky()))
    with pytest.raises(ValueError, match="force_model_kwargs"):
        gym.make(CONF, force_model=model, force_model_kwargs={"lateral_stiffness_ratio": 2.0})


def test_choosing_another_force_model_drops_the_presets_model_options():
    base = SlipEnvConfig(force_model="janosi", force_model_kwargs={"lateral_stiffness_ratio": 2})
    cfg = SlipEnvConfig.from_kwargs(base, force_model="reina")
    assert cfg.force_model_kwargs == {}


def test_castor_own_geometry_reaches_the_farm_vehicles_castors():
    """Off (default) the castors meet the driven wheels' compaction law; on, their own narrower,
    smaller wheel's, which sinks deeper per newton (Bekker; Wong Ch. 5): about twice the
    resistance at the same load on field loam."""
    per_load = {}
    for own in (False, True):
        env = gym.make("slipenv/FarmField-v0", castor_own_geometry=own)
        try:
            env.reset(seed=0)
            for _ in range(30):
                *_, info = env.step(np.array([0.5, 0.0], dtype=np.float32))
            castors = [k for k, w in enumerate(env.unwrapped._sim.spec.wheels)
                       if w.role == "caster"]
            per_load[own] = (info["wheel_resistance_n"][castors]
                             / info["wheel_load_n"][castors])
        finally:
            env.close()
    assert np.all(per_load[True] > 1.6 * per_load[False])
