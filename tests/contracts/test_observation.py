"""The observation builder of slipenv.contracts: layout, clipping to the declared bounds and the
refusal of non-finite input."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from slipenv.contracts import OBS_DIM, OBS_HIGH, OBS_LOW, OBS_NAMES, build_observation
from slipenv.contracts import observation as ob
from slipenv.paths import PathBuilder


@dataclass(frozen=True)
class Projection:
    """A path projection with chosen values (satisfies ``ProjectionLike``)."""

    s: float = 3.0
    cross_track_m: float = -0.4
    heading_rad: float = 0.5
    curvature_1pm: float = 0.25
    speed_mps: float = 1.5
    remaining_m: float = 9.0


def projection(**overrides: float) -> ob.ProjectionLike:
    return Projection(**overrides)


def test_each_entry_lands_at_its_named_index_with_its_value():
    obs = build_observation(2.0, -1.0, 0.7, 1.1, 0.2, projection(), slip_angle_est_rad=0.05)
    expected = {
        "x_m": 2.0, "y_m": -1.0, "cos_yaw": math.cos(0.7), "sin_yaw": math.sin(0.7),
        "speed_mps": 1.1, "yaw_rate_rps": 0.2, "slip_angle_est_rad": 0.05,
        "cross_track_m": -0.4, "heading_error_rad": 0.7 - 0.5, "path_curvature_1pm": 0.25,
        "ref_speed_mps": 1.5, "progress": 3.0 / 12.0,
    }
    assert obs.shape == (OBS_DIM,) and obs.dtype == np.float32
    assert list(expected) == list(OBS_NAMES)
    for i, name in enumerate(OBS_NAMES):
        assert obs[i] == pytest.approx(expected[name], abs=1e-6), name


def test_observation_is_built_from_a_real_path_projection():
    path = PathBuilder(speed_mps=0.8).line(4.0).arc(2.0, math.pi / 2).build()
    proj = path.project(1.0, 0.3)
    obs = build_observation(1.0, 0.3, 0.0, 0.8, 0.0, proj)
    assert obs[ob.OBS_CROSS_TRACK] == pytest.approx(0.3, abs=1e-6)  # > 0: left of the path
    assert obs[ob.OBS_PROGRESS] == pytest.approx(1.0 / path.length_m, abs=1e-6)
    assert obs[ob.OBS_REF_SPEED] == pytest.approx(0.8)


def test_heading_error_is_wrapped_across_the_pi_seam():
    # yaw just below +π, path heading just above -π: 0.2 rad apart, not 2π - 0.2
    obs = build_observation(0.0, 0.0, math.pi - 0.1, 1.0, 0.0,
                            projection(heading_rad=-math.pi + 0.1))
    assert obs[ob.OBS_HEADING_ERROR] == pytest.approx(-0.2, abs=1e-6)


def test_progress_is_one_on_a_path_of_zero_length():
    obs = build_observation(0.0, 0.0, 0.0, 0.0, 0.0, projection(s=0.0, remaining_m=0.0))
    assert obs[ob.OBS_PROGRESS] == 1.0


@pytest.mark.parametrize(("field", "index", "value", "bound"), [
    ("x_m", ob.OBS_X, 5e4, "high"),
    ("y_m", ob.OBS_Y, -5e4, "low"),
    ("speed_mps", ob.OBS_SPEED, 80.0, "high"),
    ("yaw_rate_rps", ob.OBS_YAW_RATE, -30.0, "low"),
    ("slip_angle_est_rad", ob.OBS_SLIP_ANGLE, 4.0, "high"),
])
def test_out_of_range_state_is_clipped_to_the_declared_bound(field, index, value, bound):
    state = {"x_m": 0.0, "y_m": 0.0, "yaw_rad": 0.0, "speed_mps": 0.0, "yaw_rate_rps": 0.0,
             "slip_angle_est_rad": 0.0}
    state[field] = value
    obs = build_observation(**state, projection=projection())
    assert obs[index] == (OBS_HIGH if bound == "high" else OBS_LOW)[index]
    assert np.all(obs >= OBS_LOW) and np.all(obs <= OBS_HIGH)


def test_out_of_range_projection_entries_are_clipped():
    obs = build_observation(0.0, 0.0, 0.0, 0.0, 0.0,
                            projection(cross_track_m=2e4, curvature_1pm=-5e3, speed_mps=-1.0))
    assert obs[ob.OBS_CROSS_TRACK] == OBS_HIGH[ob.OBS_CROSS_TRACK]
    assert obs[ob.OBS_CURVATURE] == OBS_LOW[ob.OBS_CURVATURE]
    assert obs[ob.OBS_REF_SPEED] == OBS_LOW[ob.OBS_REF_SPEED] == 0.0


def test_bounds_have_one_float32_entry_per_name_and_heading_error_spans_pi():
    assert OBS_LOW.shape == OBS_HIGH.shape == (OBS_DIM,) == (len(OBS_NAMES),)
    assert OBS_LOW.dtype == OBS_HIGH.dtype == np.float32
    assert np.all(OBS_LOW < OBS_HIGH)
    assert OBS_LOW[ob.OBS_HEADING_ERROR] == pytest.approx(-math.pi)
    assert OBS_HIGH[ob.OBS_HEADING_ERROR] == pytest.approx(math.pi)


@pytest.mark.parametrize("field", ["x_m", "yaw_rad", "speed_mps", "yaw_rate_rps",
                                   "slip_angle_est_rad"])
@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_non_finite_state_raises_floating_point_error(field, bad):
    state = {"x_m": 0.0, "y_m": 0.0, "yaw_rad": 0.0, "speed_mps": 0.0, "yaw_rate_rps": 0.0,
             "slip_angle_est_rad": 0.0}
    state[field] = bad
    with pytest.raises(FloatingPointError, match="non-finite observation"):
        build_observation(**state, projection=projection())


def test_non_finite_projection_raises_floating_point_error():
    with pytest.raises(FloatingPointError, match="non-finite observation"):
        build_observation(0.0, 0.0, 0.0, 0.0, 0.0, projection(cross_track_m=math.nan))
