"""Fuzz ``gymnasium.make`` kwargs: every config field and nested option, valid and invalid.

Each drawn case either builds an env whose reset and first steps give finite observations and
rewards (the entries the path decides strictly inside the observation's range, never clipped),
or raises ``ValueError`` whose message names one of the options drawn.
"""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
from hypothesis import event, given
from hypothesis import strategies as st

import slipenv  # noqa: F401
from slipenv.contracts.observation import (
    OBS_CURVATURE,
    OBS_HIGH,
    OBS_LOW,
    OBS_REF_SPEED,
    OBS_X,
    OBS_Y,
)
from slipenv.sensors.noise import SensorNoise

from .conftest import FUZZ, names_in, time_limit

ENV_IDS = sorted(e for e in gym.registry if e.startswith("slipenv/"))
# Entries the path decides (position, curvature, reference speed): never at the clip.
PATH_ENTRIES = [OBS_X, OBS_Y, OBS_CURVATURE, OBS_REF_SPEED]
NAN, INF = math.nan, math.inf

numbers = st.sampled_from([0.0, -1.0, 0.3, 1.0, 3.0, 15.0, NAN, INF, 1e9, "x", None, True])
small_ints = st.sampled_from([0, 1, 2, 3, 2.5, -1, 10**6, "3"])

slope = st.fixed_dictionaries(
    {"kind": st.just("slope")},
    optional={"slope_deg": st.sampled_from([0.0, 5.0, 15.0, 44.9, 45.0, 95.0, NAN, -3.0]),
              "downhill_azimuth_deg": st.sampled_from([0.0, -90.0, 400.0, NAN, INF, "n"]),
              "azimuth": numbers},
)
mounds = st.fixed_dictionaries(
    {"kind": st.just("mounds")},
    optional={"clear_radius_m": st.sampled_from([0.0, 0.6, 1.0, 14.0, 100.0, -1.0, NAN]),
              "mound_radius_m": st.sampled_from([0.2, 0.4, 0.6, 10.0, 0.0, NAN]),
              "mound_height_m": st.sampled_from([0.03, 0.12, 1e3, 0.0, NAN]),
              "size_m": st.sampled_from([0.5, 6.0, 14.0, 24.0, 1e4, NAN]),
              "resolution_m": st.sampled_from([1e-4, 0.05, 0.1, 0.5, 0.0, NAN]),
              "mound_count": small_ints,
              "layout_seed": small_ints},
)
terrain = st.one_of(st.sampled_from(["flat", "slope", "mounds", "cliff", 7, None]), slope,
                    mounds)

path_kwargs = st.dictionaries(
    st.sampled_from(["radius_m", "speed_mps", "loops", "n_gates", "gate_spacing_m",
                     "amplitude_m", "length_m", "offset_m", "radius", "foo"]),
    st.one_of(numbers, small_ints), max_size=3,
)
estimator_kwargs = st.dictionaries(
    st.sampled_from(["scheme", "n", "foo", "use_beacons", "params"]),
    st.sampled_from([1, 2, 3, 4, 7, 0.8, "all_slip", "x", NAN, None, {"bogus": 1}]),
    max_size=2,
)
reward_weights = st.dictionaries(
    st.sampled_from(["cross_track", "heading", "progress", "effort", "crosstrack"]),
    st.sampled_from([0.0, 1.0, -2.0, NAN, INF, "big", None]), max_size=3,
)
sensor_noise = st.one_of(
    st.sampled_from([None, SensorNoise.perfect(), "noisy", 3]),
    st.dictionaries(st.sampled_from(["gyro_var_rad2_s2", "compass_std_rad", "torque_scale",
                                     "gyro_var", "counts_per_rad"]), numbers, max_size=2),
)
beacons = st.sampled_from([
    None, True, False, "default", "yes", np.array([[5, 5], [-5, 5], [0, -5]]),
    np.zeros((3, 3)), [[NAN, 0.0]], [], [[1e9, 0.0]], [[1.0, 2.0], [3.0, 4.0]],
])
rates = st.sampled_from([(20.0, 240.0), (10.0, 240.0), (20.0, 250.0), (0.0, 240.0),
                         (20.0, 1e5), (NAN, 240.0), ("20", 240.0), (20.0, 20.0), (40.0, 20.0)])

OPTIONS = {
    "vehicle": st.sampled_from(["husky", "farm_2wd", "rover_4ws", "tracked_patako", "huskey",
                                3, None]),
    "terrain": terrain,
    "soil": st.sampled_from(["loose_sand", "field_loam", "lunar_simulant", "concrete", "sand",
                             5]),
    "force_model": st.sampled_from(["reina", "janosi", "linear", "magic", 1.5]),
    "path": st.sampled_from(["circle", "straight", "slalom", "s_curve", "lindgren_circles",
                             "lindgren_straights", "field_rows", "nope", 4]),
    "path_kwargs": st.one_of(path_kwargs, st.sampled_from([None, [1], "radius_m=3"])),
    "estimator": st.sampled_from(["dead_reckoning", "gyrodometry", "endo", "lindgren_ekf",
                                  "lindgren_oracle", "slip_compensated", "ekf", None]),
    "estimator_kwargs": st.one_of(estimator_kwargs, st.sampled_from([None, "scheme=4"])),
    "sensor_noise": sensor_noise,
    "beacons": beacons,
    "max_episode_s": st.sampled_from([0.5, 5.0, -1.0, NAN, 1e9]),
    "max_cross_track_m": st.sampled_from([0.01, 2.0, 0.0, INF]),
    "reward_weights": st.one_of(reward_weights, st.sampled_from([None, 1.0])),
    "start_jitter": st.sampled_from([(0.0, 0.0), (0.02, 1.0), (5.0, 0.0), (NAN, 1.0), "x",
                                     (0.1,)]),
    "soil_map": st.sampled_from([None, "patchy", 3.0]),
    "no_such_option": st.just(1),
}


@st.composite
def make_cases(draw):
    env_id = draw(st.sampled_from(ENV_IDS))
    keys = draw(st.lists(st.sampled_from(sorted(OPTIONS) + ["rates"]), max_size=4,
                         unique=True))
    kwargs = {}
    for key in keys:
        if key == "rates":
            kwargs["control_hz"], kwargs["physics_hz"] = draw(rates)
        else:
            kwargs[key] = draw(OPTIONS[key])
    return env_id, kwargs


@FUZZ
@given(make_cases(), st.integers(0, 2**31 - 1))
def test_make_either_works_with_finite_outputs_or_names_the_bad_option(case, seed):
    env_id, kwargs = case
    with time_limit():
        try:
            env = gym.make(env_id, **kwargs)
        except ValueError as exc:
            named = names_in(kwargs) | {"control_hz", "physics_hz"}
            assert any(name in str(exc) for name in named), (kwargs, str(exc))
            event("refused at make")
            return
        event("built")
        try:
            obs, _ = env.reset(seed=seed)
            assert np.all(np.isfinite(obs))
            rng = np.random.default_rng(seed)
            for _ in range(3):
                obs, reward, terminated, truncated, _ = env.step(
                    rng.uniform(-1, 1, 2).astype(np.float32))
                assert np.all(np.isfinite(obs)) and math.isfinite(reward), kwargs
                assert np.all(obs[PATH_ENTRIES] < OBS_HIGH[PATH_ENTRIES]), (kwargs, obs)
                assert np.all(obs[PATH_ENTRIES[:3]] > OBS_LOW[PATH_ENTRIES[:3]]), (kwargs, obs)
                if terminated or truncated:
                    break
        finally:
            env.close()
