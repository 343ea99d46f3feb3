"""Every bad option is a ValueError at ``gymnasium.make`` naming it; good ones build."""

from __future__ import annotations

import math
import time

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.registration import preset_config
from slipenv.sensors.noise import SensorNoise
from slipenv.vehicles.presets import husky

CONF = "slipenv/Configurable-v0"


def make_and_step(env_id: str = CONF, **kwargs):
    env = gym.make(env_id, **kwargs)
    try:
        obs, _ = env.reset(seed=0)
        obs, reward, *_ = env.step(np.array([0.5, 0.1]))
        assert np.all(np.isfinite(obs)) and math.isfinite(reward)
        return env.unwrapped
    finally:
        env.close()


@pytest.mark.parametrize(("kwargs", "names"), [
    (dict(terrain={"kind": "mounds", "clear_radius_m": 100}), "clear_radius_m"),
    (dict(terrain={"kind": "mounds", "mound_radius_m": 10}), "mound_radius_m"),
    (dict(terrain={"kind": "mounds", "size_m": 0.5}), "size_m"),
    (dict(terrain={"kind": "mounds", "resolution_m": 1e-4}), "resolution_m"),
    (dict(terrain={"kind": "mounds", "mound_count": 2.5}), "mound_count"),
    (dict(terrain={"kind": "slope", "slope_deg": 10, "downhill_azimuth_deg": math.nan}),
     "downhill_azimuth_deg"),
    (dict(terrain={"kind": "slope", "slope_deg": math.inf}), "slope_deg"),
    (dict(terrain={"kind": "slope", "azimuth": 3.0}), "downhill_azimuth_deg"),
    (dict(beacons="yes"), "beacons"),
    (dict(beacons=np.zeros((3, 3))), "beacons"),
    (dict(sensor_noise=None), "sensor_noise"),
    (dict(sensor_noise={"gyro_var": 1e-4}), "gyro_var_rad2_s2"),
    (dict(sensor_noise={"compass_std_rad": "x"}), "compass_std_rad"),
    (dict(reward_weights={"cross_track": "big"}), "cross_track"),
    (dict(reward_weights={"cross_track": math.nan}), "cross_track"),
    (dict(reward_weights={"crosstrack": 1.0}), "did you mean 'cross_track'"),
    (dict(path_kwargs={"radius": 3}), "did you mean 'radius_m'"),
    (dict(path_kwargs={"radius_m": "x"}), "radius_m"),
    (dict(estimator="lindgren_ek"), "did you mean 'lindgren_ekf'"),
    (dict(estimator_kwargs={"foo": 1}), "foo"),
    (dict(vehicle="huskey"), "did you mean 'husky'"),
    (dict(physics_hz=1e5), "physics_hz"),
    (dict(physics_hz=250.0), "physics_hz"),
    (dict(control_hz=True), "control_hz"),
    (dict(start_jitter=(5.0, 0.0)), "start_jitter"),
    (dict(soil="sand"), "soil"),
    (dict(force_model="reinna"), "did you mean 'reina'"),
    (dict(modle={}), "unknown slipenv option 'modle'"),
])
def test_a_bad_option_is_a_value_error_at_make_naming_it(kwargs, names):
    start = time.monotonic()
    with pytest.raises(ValueError, match=names.replace("(", r"\(")):
        gym.make(CONF, **kwargs)
    assert time.monotonic() - start < 5.0  # an error, promptly: never a hang


@pytest.mark.parametrize("kwargs", [
    dict(estimator_kwargs={"scheme": 7}),
    dict(estimator_kwargs={"foo": 1}),
    dict(estimator_kwargs={"schem": 3}),
])
def test_bad_estimator_options_fail_at_make_not_at_reset(kwargs):
    with pytest.raises(ValueError, match="estimator_kwargs"):
        gym.make("slipenv/FarmField-v0", **kwargs)


def test_a_misspelt_estimator_option_gets_a_suggestion():
    with pytest.raises(ValueError, match="did you mean 'scheme'"):
        gym.make("slipenv/FarmField-v0", estimator_kwargs={"schem": 3})


def test_an_implausible_vehicle_is_refused():
    spec = husky()
    with pytest.raises(ValueError, match="chassis_mass_kg"):
        type(spec)(**{**spec.__dict__, "chassis_mass_kg": 1e9})


def test_the_documented_beacon_array_works():
    beacons = np.array([[5, 5], [-5, 5], [0, -5]])
    env = make_and_step(vehicle="farm_2wd", estimator="lindgren_ekf", beacons=beacons)
    np.testing.assert_array_equal(env.beacons_xy, beacons)


def test_perfect_sensor_noise_and_a_noise_dict_work():
    make_and_step(sensor_noise=SensorNoise.perfect())
    env = make_and_step(sensor_noise={"gyro_var_rad2_s2": 1e-4})
    assert env.config.sensor_noise.gyro_var_rad2_s2 == 1e-4


def test_the_readme_rover_slalom_example_builds():
    # Choosing another path by name drops the preset's path_kwargs (regression: radius_m
    # used to reach slalom()).
    make_and_step(vehicle="rover_4ws", soil="lunar_simulant", force_model="reina",
                  path="slalom")


def test_a_config_replaces_the_preset_and_kwargs_override_it():
    cfg = preset_config("slipenv/HuskySand-v0")
    env = gym.make(CONF, config=cfg)
    assert env.unwrapped.config == cfg
    env.close()
    env = gym.make(CONF, config=cfg, soil="field_loam")
    assert env.unwrapped.config.soil == "field_loam"
    assert env.unwrapped.config.path == cfg.path
    env.close()


def test_a_config_that_is_not_a_slipenvconfig_is_refused():
    with pytest.raises(ValueError, match="config"):
        gym.make(CONF, config={"soil": "field_loam"})


def test_the_config_has_no_model_field_and_the_env_does_not_import_the_diagnosis():
    import subprocess
    import sys

    assert "model" not in SlipEnvConfig.__dataclass_fields__
    code = ("import sys, gymnasium as gym, slipenv; gym.make('slipenv/HuskySand-v0').reset();"
            "print('slipenv.diagnose' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip().endswith("False")


@pytest.mark.parametrize("action", [
    np.array([1 + 1j, 0]), np.array(["a", "b"]), np.array([None, 1], dtype=object),
    "ab", np.zeros(3), np.array([np.nan, 0.0]),
])
def test_a_non_real_action_is_a_value_error(action):
    env = gym.make("slipenv/HuskySand-v0")
    env.reset(seed=0)
    with pytest.raises(ValueError, match="action"):
        env.unwrapped.step(action)
    env.close()


def test_a_bad_path_value_is_an_error_of_the_config_itself():
    """Not only at ``make``: a config built in code (or by a sweep's grid loader) is checked
    when it is built, naming the option."""
    from slipenv.envs.config import SlipEnvConfig

    with pytest.raises(ValueError, match="path_kwargs for path 'circle': radius_m must be > 0"):
        SlipEnvConfig(path="circle", path_kwargs={"radius_m": -2.0})


@pytest.mark.parametrize(("kwargs", "names"), [
    # A 1e9 m circle would start the vehicle at y = -1e9 m, past the observation's ±1e4 m.
    (dict(path_kwargs={"radius_m": 1e9}), r"path_kwargs: .*1e\+09 m .*±10000 m"),
    (dict(path="straight", path_kwargs={"length_m": 2e4}), r"path_kwargs: .*±10000 m"),
    (dict(path_kwargs={"speed_mps": 1e6}), r"path_kwargs: speed_mps .*50 m/s.*'husky' tops"),
    (dict(path_kwargs={"radius_m": 1e-4}), r"path_kwargs: .*radius of 0.0001 m, below 1 mm"),
    (dict(path_kwargs={"radius_m": 0.02, "speed_mps": 1.0}),
     r"path_kwargs: .*yaw rate of 50 rad/s .*20 rad/s"),
    (dict(reward_weights={"heading": -0.2}), r"reward_weights\['heading'\] .* >= 0"),
    (dict(reward_weights={"progress": -1.0}), r"reward_weights\['progress'\] .* >= 0"),
])
def test_a_path_or_reward_value_beyond_its_bound_is_refused_naming_option_and_bound(
        kwargs, names):
    with pytest.raises(ValueError, match=names):
        gym.make(CONF, **kwargs)


def test_a_built_path_beyond_the_observation_range_is_refused_naming_path():
    from slipenv.paths import circle

    with pytest.raises(ValueError, match=r"^path: path 'circle' reaches"):
        SlipEnvConfig(path=circle(radius_m=3.0, center=(9999.0, 0.0)))


def test_a_path_just_inside_the_observation_range_builds_and_observes_unclipped():
    # Extent 9990 m + the 2 m corridor + 2 cm jitter stays inside ±1e4 m.
    env = gym.make(CONF, path="straight", path_kwargs={"length_m": 9990.0, "speed_mps": 0.5})
    try:
        obs, _ = env.reset(seed=0)
        assert abs(obs[0]) < 1.0 and obs[10] == pytest.approx(0.5)
    finally:
        env.close()


def test_zero_reward_weights_are_accepted_and_switch_their_terms_off():
    env = gym.make(CONF, reward_weights=dict.fromkeys(
        ("cross_track", "heading", "progress", "effort"), 0.0))
    try:
        env.reset(seed=0)
        _, reward, *_, info = env.step(np.array([0.5, 0.3]))
    finally:
        env.close()
    assert reward == 0.0 and info["reward_terms"]["effort"] == pytest.approx(-0.34)
