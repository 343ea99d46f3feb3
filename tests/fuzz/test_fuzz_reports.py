"""Fuzzing the diagnosis report's way into the simulation (``apply_model``).

A report is the user's file: hand-written, edited, or fitted on a log where a value came out
of bounds the physics can take. Whatever its values, ``apply_model`` either returns a world
the simulation can run (finite, positive stiffness scales and geometry) or raises a
``ValueError`` naming the effect or the parameter — never another exception, never a world
with a negative stiffness in it.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from slipenv.contracts.constants import G_MPS2
from slipenv.diagnose import apply_model, synth
from slipenv.diagnose.slip_law import ScaledSlip
from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle

from .conftest import FUZZ, time_limit

CONFIG = synth.base_config("diff_drive")
SPEC = make_vehicle(CONFIG.vehicle)

# A plausible report of every effect for the farm vehicle (values the fits give).
BASE = {
    "rolling_radius": {"radius_left_m": 1.01 * SPEC.wheel_radius_nominal_m,
                       "radius_right_m": 0.99 * SPEC.wheel_radius_nominal_m},
    "track_width": {"track_width_m": 1.02 * SPEC.track_width_m},
    "torque_slip": {"k_s_left_nm": 500.0, "k_s_right_nm": 450.0},
    "turning_slip": {"endo_n": 0.8, "turn_slip_scale": 0.05},
    "slope_side_slip": {"beta_per_roll": 0.1, "beta_offset_rad": 0.01,
                        "beta_per_roll_yaw_rate_s": 0.0},
    "combined_slip": {"s_x0": 0.01, "k_beta": 0.5, "beta0_rad": 0.01},
    "soil_patch": {"patch_center_x_m": 1.0, "patch_center_y_m": -1.0, "patch_radius_m": 1.5,
                   "k_s_left_nm": 300.0, "k_s_right_nm": 300.0},
    "soil_map": {"map_angle_rad": 0.3, "map_rects": 2.0,
                 "map_rect0_u0_m": 0.0, "map_rect0_v0_m": -1.0, "map_rect0_u1_m": 2.0,
                 "map_rect0_v1_m": 1.0, "map_rect0_region": 0.0, "map_rect0_shape": 1.0,
                 "map_rect1_u0_m": -3.0, "map_rect1_v0_m": -1.0, "map_rect1_u1_m": -1.0,
                 "map_rect1_v1_m": 2.0, "map_rect1_region": 1.0, "map_rect1_shape": 0.0,
                 "c_region0_per_nm": 0.002, "c_region1_per_nm": 0.004},
    "gyro_bias": {"gyro_bias_rad_s": 0.01},
}

EXTREMES = st.sampled_from([0.0, -0.0, 1e-300, -1e-300, 1e300, -1e300, -1.0, 0.5, 1.0, 7.0,
                            math.nan, math.inf, -math.inf])


@st.composite
def reports(draw):
    cause = draw(st.sampled_from(sorted(BASE)))
    params = dict(BASE[cause])
    for key in draw(st.lists(st.sampled_from(sorted(params)), min_size=1, max_size=3,
                             unique=True)):
        if draw(st.integers(0, 9)) == 0:
            params.pop(key)
        else:
            params[key] = draw(st.one_of(EXTREMES, st.floats(-1e6, 1e6)))
    report = {"format": "slipenv-diagnosis/1", "cause": cause, "also": [],
              "parameters": {k: [v, 0.0] for k, v in params.items()}}
    return cause, report


def _scaled_options(model) -> list[tuple[str, float]]:
    out = []
    while isinstance(model, ScaledSlip):
        out += list(model.options)
        model = model.base
    return out


@FUZZ
@given(case=reports())
def test_a_report_applies_to_a_world_that_can_run_or_is_refused_naming_it(case):
    cause, report = case
    with time_limit():
        try:
            config = apply_model(CONFIG, report)
        except ValueError as exc:
            text = str(exc)
            assert cause in text or any(k in text for k in report["parameters"]) \
                or "k_s_<wheel>_nm" in text, text
            return
    for name, value in _scaled_options(config.force_model):
        assert math.isfinite(value), (name, value)
        if name.endswith("_scale"):
            assert value > 0.0, (name, value)
    # the world runs: its force law, on its soil wherever the map puts it, gives finite
    # forces over slips both ways (the vehicle's and the soils' own checks ran when built)
    spec = make_vehicle(config.vehicle)
    model = make_force_model(config.force_model, spec, config.force_model_kwargs)
    x, y = (g.ravel() for g in np.meshgrid(np.linspace(-5.0, 5.0, 11),
                                           np.linspace(-5.0, 5.0, 11)))
    soil = make_soil_map(config.soil, config.soil_map).params_at(x, y)
    load = np.full(x.size, spec.mass_kg * G_MPS2 / len(spec.wheels))
    fx, fy = model(np.linspace(-0.5, 0.5, x.size), np.linspace(0.3, -0.3, x.size), load, soil)
    assert np.all(np.isfinite(fx)) and np.all(np.isfinite(fy))
