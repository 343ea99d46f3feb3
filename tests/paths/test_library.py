"""Named paths: shapes from the papers, builder validation and the registry."""

from __future__ import annotations

import math

import pytest

from slipenv.paths import (
    PATHS,
    Arc,
    QuadraticSpline,
    circle,
    field_rows,
    lindgren_circles,
    lindgren_straights,
    path_by_name,
    s_curve,
    slalom,
    straight,
)


def test_circle_starts_with_the_requested_heading_on_the_requested_centre():
    path = circle(3.0, 0.5, loops=2.0, clockwise=True, center=(1.0, 2.0),
                  start_heading_rad=0.5 * math.pi)
    x, y, h = path.start_pose()
    assert h == pytest.approx(0.5 * math.pi)
    assert math.hypot(x - 1.0, y - 2.0) == pytest.approx(3.0)
    assert x == pytest.approx(-2.0)  # clockwise heading north: the centre is to the east
    assert path.length_m == pytest.approx(2.0 * math.pi * 3.0 * 2.0)
    assert path.curvature_at(1.0) == pytest.approx(-1.0 / 3.0)
    assert path.duration_s == pytest.approx(path.length_m / 0.5)


def test_lindgren_circles_are_one_and_a_half_loops_clockwise_then_counter_clockwise():
    path = lindgren_circles()
    cw, ccw = path.segments
    assert isinstance(cw, Arc) and isinstance(ccw, Arc)
    assert cw.clockwise and not ccw.clockwise
    assert cw.radius_m == ccw.radius_m == 4.0
    assert path.length_m == pytest.approx(2 * 1.5 * 2.0 * math.pi * 4.0)
    assert path.curvature_at(1.0) == pytest.approx(-0.25)
    assert path.curvature_at(path.length_m - 1.0) == pytest.approx(0.25)
    assert path.pose_at(cw.length_m)[:2] == pytest.approx((0.0, -8.0), abs=1e-12)


def test_lindgren_straights_alternate_right_and_left_half_turns():
    path = lindgren_straights(length_m=10.0, n_legs=4, turn_radius_m=2.0, speed_mps=0.5)
    turns = [seg for seg in path.segments if isinstance(seg, Arc)]
    assert [t.clockwise for t in turns] == [True, False, True]
    assert all(t.sweep_rad == pytest.approx(math.pi) for t in turns)
    x, y, heading = path.end_pose()
    assert (x, y, math.cos(heading)) == pytest.approx((0.0, -12.0, -1.0))
    assert path.length_m == pytest.approx(4 * 10.0 + 3 * math.pi * 2.0)


def test_field_rows_are_parallel_and_spaced_with_spline_headland_turns():
    path = field_rows(row_length_m=20.0, n_rows=3, row_spacing_m=3.0, speed_mps=1.0,
                      turn_speed_mps=0.5, ramp_m=2.0)
    assert sum(isinstance(s, QuadraticSpline) for s in path.segments) == 4
    assert path.end_pose() == pytest.approx((20.0, 6.0, 0.0), abs=1e-9)
    # Row 0 (18 m + 2 m ramp), turn (2 splines), then row 1 starts with its 2 m ramp.
    s_mid_row1 = sum(seg.length_m for seg in path.segments[:4]) + 10.0
    x, y, heading = path.pose_at(s_mid_row1)
    assert (x, y, math.cos(heading)) == pytest.approx((10.0, 3.0, -1.0), abs=1e-9)
    assert path.speed_at(10.0) == pytest.approx(1.0)
    assert path.speed_at(20.5) == pytest.approx(0.5)  # inside the first headland turn
    assert max(s.max_abs_curvature_1pm for s in path.segments) == pytest.approx(
        math.sqrt(2.0) / 1.5)


def test_s_curve_and_slalom_end_parallel_to_the_start_at_their_offsets():
    lane = s_curve(length_m=10.0, offset_m=-2.0, lead_m=1.0)
    assert lane.end_pose() == pytest.approx((12.0, -2.0, 0.0), abs=1e-12)
    gates = slalom(n_gates=3, gate_spacing_m=5.0, amplitude_m=1.0)
    for k, expected_y in enumerate((1.0, -1.0, 1.0)):
        proj = gates.project(5.0 * (k + 1), expected_y)
        assert proj.cross_track_m == pytest.approx(0.0, abs=1e-9)
        assert proj.heading_rad == pytest.approx(0.0, abs=1e-9)


@pytest.mark.parametrize(
    ("name", "kw", "argument"),
    [
        ("circle", {"radius_m": -4.0, "speed_mps": 1.0}, "radius_m"),
        ("circle", {"radius_m": 4.0, "speed_mps": 0.0}, "speed_mps"),
        ("circle", {"radius_m": math.nan, "speed_mps": 1.0}, "radius_m"),
        ("circle", {"radius_m": 4.0, "speed_mps": 1.0, "loops": 0.0}, "loops"),
        ("straight", {"length_m": 0.0, "speed_mps": 1.0}, "length_m"),
        ("straight", {"length_m": 5.0, "speed_mps": -1.0}, "speed_mps"),
        ("lindgren_circles", {"radius_m": 0.0}, "radius_m"),
        ("lindgren_straights", {"n_legs": 0}, "n_legs"),
        ("lindgren_straights", {"turn_radius_m": math.inf}, "turn_radius_m"),
        ("field_rows", {"row_spacing_m": -3.0}, "row_spacing_m"),
        ("field_rows", {"turn_speed_mps": 0.5, "ramp_m": 10.0}, "ramp_m"),
        ("s_curve", {"length_m": 0.0}, "length_m"),
        ("slalom", {"amplitude_m": math.nan}, "amplitude_m"),
    ],
)
def test_invalid_builder_input_raises_value_error_naming_the_argument(name, kw, argument):
    with pytest.raises(ValueError, match=argument):
        path_by_name(name, **kw)


def test_registry_builds_every_path_and_lists_names_for_unknown_ones():
    for name in PATHS:  # every path builds from its defaults
        assert path_by_name(name).length_m > 0.0
    assert path_by_name("straight", length_m=5.0, speed_mps=1.0).end_pose() == straight(
        5.0, 1.0).end_pose()
    with pytest.raises(ValueError, match="known paths: circle, field_rows"):
        path_by_name("spiral")


@pytest.mark.parametrize(("name", "kwargs", "option"), [
    ("slalom", {"n_gates": 10**6}, "n_gates"),
    ("slalom", {"n_gates": 2.5}, "n_gates"),
    ("lindgren_straights", {"n_legs": 10**5}, "n_legs"),
    ("field_rows", {"n_rows": True}, "n_rows"),
])
def test_a_count_beyond_a_thousand_or_not_an_integer_is_refused_promptly(name, kwargs, option):
    # 10**6 gates would build 2 million splines before answering.
    with pytest.raises(ValueError, match=option):
        path_by_name(name, **kwargs)
