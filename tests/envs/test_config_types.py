"""SlipEnvConfig's fields have precise types, and its options are refused at ``make`` by name."""

from __future__ import annotations

import dataclasses
import typing

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.factory import contact_geometry
from slipenv.terramechanics.models import JanosiForceModel
from slipenv.terramechanics.presets import soil_by_name
from slipenv.terramechanics.soil_map import UniformSoil

CONF = "slipenv/Configurable-v0"


def test_every_field_has_a_resolvable_type_and_none_is_any():
    hints = typing.get_type_hints(SlipEnvConfig)
    for f in dataclasses.fields(SlipEnvConfig):
        assert hints[f.name] is not typing.Any, f.name
        assert hints[f.name] is not object, f.name


def test_the_documented_kinds_of_each_choice_build():
    cfg = SlipEnvConfig(soil=soil_by_name("loose_sand"),
                        soil_map=UniformSoil(soil_by_name("field_loam")),
                        force_model=JanosiForceModel, terrain={"kind": "slope", "slope_deg": 5.0},
                        sensor_noise={"torque_rel_std": 0.1}, beacons=[(0.0, 5.0), (5.0, 0.0)])
    assert cfg.terrain.slope_deg == 5.0
    assert cfg.sensor_noise.torque_rel_std == 0.1
    assert cfg.beacons == ((0.0, 5.0), (5.0, 0.0))


class NotASoilMap:
    def soil_at(self, x, y):
        return None


@pytest.mark.parametrize(("kwargs", "name"), [
    (dict(soil_map=NotASoilMap()), "soil_map"),
    (dict(soil_map="loose_sand"), "soil_map"),
    (dict(force_model=42), "force_model"),
    (dict(force_model=lambda geometry: "not a model"), "force_model"),
    (dict(vehicle=3), "vehicle"),
    (dict(soil=0.5), "soil"),
    (dict(path=None), "path"),
    (dict(multi_pass=1), "multi_pass"),
    (dict(terrain={"kind": "slope", "slope_deg": float("nan")}), "slope_deg"),
    (dict(sensor_noise={"gyro_var_rad2_s2": -1.0}), "gyro_var_rad2_s2"),
])
def test_a_bad_option_is_a_value_error_at_make_that_names_it(kwargs, name):
    with pytest.raises(ValueError, match=name):
        gym.make(CONF, **kwargs)


def test_a_force_model_instance_and_a_factory_reach_the_simulation():
    from slipenv.vehicles.presets import husky

    model = JanosiForceModel(contact_geometry(husky()))
    for option in (model, JanosiForceModel):
        env = gym.make(CONF, vehicle="husky", force_model=option)
        try:
            env.reset(seed=0)
            env.step(np.zeros(2, dtype=np.float32))
            injected = env.unwrapped._sim.injector.force_model
            assert isinstance(injected, JanosiForceModel)
            assert (injected is model) == (option is model)
        finally:
            env.close()
