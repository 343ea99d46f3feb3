"""``apply_model``: a fitted extension becomes the simulated world
(``gymnasium.make(id, config=apply_model(config, report))``, ``make_env(id, report)``)."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401  (registers the envs)
from slipenv.diagnose import apply_model, make_env
from slipenv.diagnose.extension import parse_model
from slipenv.diagnose.slip_law import ScaledSlip
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.registration import preset_config
from slipenv.terramechanics.soil_map import PatchSoilMap

FARM = dict(vehicle="farm_2wd", soil="concrete", force_model="linear", path="circle",
            path_kwargs={"radius_m": 4.0, "speed_mps": 0.5})


def make(**kw):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return gym.make("slipenv/Configurable-v0", **{**FARM, **kw})


def make_extended(model):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return make_env("slipenv/Configurable-v0", model, **FARM)


def travelled(env, steps=40) -> tuple[float, float]:
    """(distance [m], mean wheel rotation [rad]) driving straight, after 20 steps to settle."""
    env.reset(seed=0)
    for _ in range(20):
        _, _, _, _, info = env.step(np.array([0.4, 0.0], dtype=np.float32))
    start, counts0 = info["true_pose"][:2], np.mean(info["sensors"].enc_counts)
    for _ in range(steps):
        _, _, _, _, info = env.step(np.array([0.4, 0.0], dtype=np.float32))
    counts = np.mean(info["sensors"].enc_counts) - counts0
    angle = counts / env.unwrapped.vehicle.counts_per_rad
    return float(np.hypot(*(info["true_pose"][:2] - start))), float(angle)


def test_make_with_model_changes_the_world():
    model = {"rolling_radius": {"radius_left_m": 0.30, "radius_right_m": 0.30},
             "gyro_bias": {"gyro_bias_rad_s": 0.02}}
    plain, extended = make(), make_extended(model)
    try:
        u = extended.unwrapped
        assert [w.rolling_radius_m for w in u.vehicle.wheels][:2] == [0.30, 0.30]
        assert u.config.sensor_noise.gyro_bias_rad_s == 0.02
        # applied once, by apply_model: the env takes the config as it is
        cfg = apply_model(SlipEnvConfig.from_kwargs(preset_config("slipenv/Configurable-v0"),
                                                    **FARM), model)
        assert u.config == cfg
        d0, a0 = travelled(plain)
        d1, a1 = travelled(extended)
        # metres per radian follow the rolling radius: 0.275 m nominal, 0.30 m extended
        assert d0 / a0 == pytest.approx(0.275, rel=0.02)
        assert d1 / a1 == pytest.approx(0.30, rel=0.02)
    finally:
        plain.close()
        extended.close()


def test_report_form_and_all_effects():
    report = {"format": "slipenv-diagnosis/1", "cause": "torque_slip",
              "also": ["soil_patch", "slope_side_slip", "track_width"],
              "nominal": {"wheel_radius_m": 0.275, "track_width_m": 1.6},
              "parameters": {"k_s_left_nm": [800.0, 10.0], "k_s_right_nm": [820.0, 10.0],
                             "patch_center_x_m": [1.0, 0.1], "patch_center_y_m": [2.0, 0.1],
                             "patch_radius_m": [1.5, 0.1], "patch_k_s_left_nm": [300.0, 5.0],
                             "patch_k_s_right_nm": [300.0, 5.0], "beta_per_roll": [-0.3, 0.01],
                             "beta_offset_rad": [0.0, 0.01], "track_width_m": [1.7, 0.01]}}
    cfg = apply_model(SlipEnvConfig(**FARM), report)
    assert isinstance(cfg.force_model, ScaledSlip)
    options = dict(cfg.force_model.options)
    assert options["long_scale"] > 0 and options["lat_scale"] > 0
    assert isinstance(cfg.soil_map, PatchSoilMap)
    assert cfg.vehicle.track_width_m == pytest.approx(1.6 * 1.7 / 1.6)
    env = make(**{k: getattr(cfg, k) for k in ("vehicle", "soil_map", "force_model")})
    try:
        env.reset(seed=0)
        for _ in range(5):
            env.step(np.zeros(2, dtype=np.float32))
    finally:
        env.close()


@pytest.mark.parametrize(("model", "message"), [
    ({"wheel_wobble": {}}, "unknown effect 'wheel_wobble'"),
    ({"gyro_bias": {"bias": 0.1}}, "unknown parameter"),
    ({"track_width": {}}, "missing parameter"),
    ({"rolling_radius": {}}, "missing parameter"),
    ({"gyro_bias": {"gyro_bias_rad_s": "fast"}}, "finite number"),
    ({"cause": "gyro_bias", "parameters": {"k_s_left_nm": [1.0, 0.1]}}, "belongs to none"),
    ("gyro_bias", "must be a dict"),
])
def test_bad_models_are_clear_errors(model, message):
    with pytest.raises(ValueError, match=message):
        parse_model(model)


_MAP = {"map_angle_rad": 0.3, "map_rects": 1.0, "map_rect0_u0_m": 0.0, "map_rect0_v0_m": -1.0,
        "map_rect0_u1_m": 2.0, "map_rect0_v1_m": 1.0, "map_rect0_region": 0.0}


@pytest.mark.parametrize(("model", "message"), [
    # a fit's bounds straddle zero, so a fitted (or edited) value can be one the physics
    # cannot take: refused naming the parameter, never a world with a negative stiffness
    ({"torque_slip": {"k_s_left_nm": -50.0, "k_s_right_nm": 400.0}},
     r"'torque_slip': k_s_<wheel>_nm cannot be applied .* must be > 0"),
    ({"torque_slip": {"k_s_left_nm": 0.0, "k_s_right_nm": 400.0}},
     r"'torque_slip': k_s_<wheel>_nm must be nonzero"),
    ({"soil_patch": {"patch_center_x_m": 0.0, "patch_center_y_m": 0.0, "patch_radius_m": 1.0,
                     "k_s_left_nm": -50.0, "k_s_right_nm": -50.0}},
     r"'soil_patch': k_s_<wheel>_nm cannot be applied"),
    ({"soil_map": {**_MAP, "c_region0_per_nm": -0.01}},
     r"'soil_map': c_region0_per_nm cannot be applied .* >= 0"),
    ({"combined_slip": {"s_x0": 1.5, "k_beta": 0.5, "beta0_rad": 0.0}},
     r"'combined_slip': s_x0 cannot be applied .* \|s_x0\| < 1"),
    ({"track_width": {"track_width_m": 0.0}},
     r"'track_width': TrackWidth: width_m must be > 0.*\['track_width_m'\]"),
    # the world's own checks, named by the effect that broke them (a 32 m wide vehicle)
    ({"turning_slip": {"endo_n": 0.8, "turn_slip_scale": 0.97}},
     r"'turning_slip' cannot be applied to the simulation: .*track_width_m"),
])
def test_a_model_the_simulation_cannot_take_is_refused_naming_the_parameter(model, message):
    config = SlipEnvConfig(**FARM)
    with pytest.raises(ValueError, match=message):
        apply_model(config, model)


def test_unknown_effect_in_make_env_is_an_error():
    with pytest.raises(ValueError, match="unknown effect"):
        make_extended({"slope": {}})


def test_config_from_apply_model_goes_through_gymnasium_make():
    report = {"cause": "track_width", "also": [], "vehicle_kind": "diff_drive",
              "wheels": ["left", "right"], "nominal": {"track_width_m": 1.6},
              "parameters": {"track_width_m": [1.76, 0.01]}}
    cfg = apply_model(preset_config("slipenv/FarmField-v0"), report)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make("slipenv/FarmField-v0", config=cfg)
    try:  # 10 % wider than the log's nominal width: 10 % wider than the farm vehicle's
        assert env.unwrapped.vehicle.track_width_m == pytest.approx(1.6 * 1.1)
        assert preset_config("slipenv/FarmField-v0").vehicle == "farm_2wd"  # preset untouched
    finally:
        env.close()


HUSKY_REPORT = {"format": "slipenv-diagnosis/1", "cause": "rolling_radius", "also": [],
                "vehicle_kind": "skid_steer", "wheels": ["left", "right"],
                "nominal": {"wheel_radius_m": 0.165, "track_width_m": 0.555},
                "parameters": {"radius_left_m": [0.17, 1e-4], "radius_right_m": [0.17, 1e-4]}}


def test_report_of_another_vehicle_kind_is_refused():
    farm = preset_config("slipenv/FarmField-v0")
    with pytest.raises(ValueError, match=r"skid_steer.*farm_2wd.*diff_drive"):
        apply_model(farm, HUSKY_REPORT)
    # the same report fits a skid-steer vehicle with left/right drive channels
    cfg = apply_model(SlipEnvConfig(vehicle="husky"), HUSKY_REPORT)
    assert {w.rolling_radius_m for w in cfg.vehicle.wheels if w.role == "driven"} != {None}


@pytest.mark.parametrize("model", [
    {"cause": "rolling_radius", "also": [], "vehicle_kind": "diff_drive",
     "wheels": ["wheel_l", "wheel_r"],
     "parameters": {"radius_wheel_l_m": [0.28, 1e-4], "radius_wheel_r_m": [0.28, 1e-4]}},
    {"rolling_radius": {"radius_front_left_m": 0.28, "radius_front_right_m": 0.28}},
], ids=["report", "plain"])
def test_report_with_other_wheel_names_is_refused(model):
    with pytest.raises(ValueError, match=r"wheels \[.*\].*farm_2wd.*wheels \['left', 'right'\]"):
        apply_model(SlipEnvConfig(**FARM), model)


def test_make_env_checks_the_vehicle_of_the_preset():
    with pytest.raises(ValueError, match="skid_steer"):
        make_env("slipenv/FarmField-v0", HUSKY_REPORT)


def test_none_model_changes_nothing():
    cfg = SlipEnvConfig(**FARM)
    assert apply_model(cfg, None) is cfg
    assert apply_model(cfg, {"cause": "none", "also": [], "parameters": {}}).vehicle == \
        cfg.vehicle
