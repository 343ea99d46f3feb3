"""Segments against closed forms: lengths, points, tangents, curvature, speed profiles."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.paths import Arc, Line, QuadraticSpline


def test_line_point_tangent_and_zero_curvature():
    seg = Line((1.0, 2.0), (4.0, 6.0), 1.0, 1.0)
    assert seg.length_m == pytest.approx(5.0)
    assert seg.point(2.5) == pytest.approx((2.5, 4.0))
    assert seg.tangent(1.0) == pytest.approx((0.6, 0.8))
    assert seg.curvature(3.0) == 0.0


@pytest.mark.parametrize("loops", [0.25, 1.0, 1.5, 3.0])
def test_arc_length_is_two_pi_r_times_loops(loops):
    seg = Arc((0.0, 0.0), 4.0, 0.0, 2.0 * math.pi * loops, False, 1.0, 1.0)
    assert seg.length_m == pytest.approx(2.0 * math.pi * 4.0 * loops, rel=1e-14)


@pytest.mark.parametrize(("clockwise", "sign"), [(False, 1.0), (True, -1.0)])
def test_arc_curvature_is_one_over_r_signed_by_direction(clockwise, sign):
    seg = Arc((1.0, -2.0), 2.5, 0.3, 4.0, clockwise, 1.0, 1.0)
    for s in np.linspace(0.0, seg.length_m, 7):
        assert seg.curvature(s) == pytest.approx(sign / 2.5)
        x, y = seg.point(s)
        assert math.hypot(x - 1.0, y + 2.0) == pytest.approx(2.5)
        tx, ty = seg.tangent(s)
        assert (x - 1.0) * tx + (y + 2.0) * ty == pytest.approx(0.0, abs=1e-12)
        # Turning left means the centre is on the tangent's left.
        assert sign * ((x - 1.0) * ty - (y + 2.0) * tx) == pytest.approx(2.5)


def test_arc_quarter_turn_counter_clockwise_lands_on_closed_form_point():
    seg = Arc((0.0, 0.0), 2.0, -0.5 * math.pi, math.pi, False, 1.0, 1.0)  # starts at (0, -2)
    assert seg.point(0.0) == pytest.approx((0.0, -2.0))
    assert seg.heading(0.0) == pytest.approx(0.0)
    assert seg.point(0.5 * math.pi * 2.0) == pytest.approx((2.0, 0.0))
    assert seg.heading(0.5 * math.pi * 2.0) == pytest.approx(0.5 * math.pi)


def test_spline_passes_through_end_points_with_tangents_along_control_polygon():
    p0, p1, p2 = (0.0, 0.0), (3.0, 1.0), (4.0, 4.0)
    seg = QuadraticSpline(p0, p1, p2, 1.0, 1.0)
    assert seg.point(0.0) == pytest.approx(p0)
    assert seg.point(seg.length_m) == pytest.approx(p2, abs=1e-12)
    assert seg.tangent(0.0) == pytest.approx(np.array([3.0, 1.0]) / math.hypot(3.0, 1.0))
    assert seg.tangent(seg.length_m) == pytest.approx(np.array([1.0, 3.0]) / math.hypot(1, 3))


def test_spline_parabola_matches_closed_form_length_and_apex_curvature():
    # B(t) = (2t - 1, 2t(1 - t)) is y = (1 - x^2) / 2 on [-1, 1]: length = sqrt(2) + asinh(1),
    # curvature y'' / (1 + y'^2)^1.5 = -1 at the apex (a right turn while moving +x).
    seg = QuadraticSpline((-1.0, 0.0), (0.0, 1.0), (1.0, 0.0), 1.0, 1.0)
    assert seg.length_m == pytest.approx(math.sqrt(2.0) + math.asinh(1.0), rel=1e-13)
    apex = 0.5 * seg.length_m
    assert seg.point(apex) == pytest.approx((0.0, 0.5), abs=1e-12)
    assert seg.curvature(apex) == pytest.approx(-1.0, rel=1e-10)
    assert seg.max_abs_curvature_1pm == pytest.approx(1.0)


def test_spline_is_parametrised_by_arc_length():
    seg = QuadraticSpline((0.0, 0.0), (5.0, 0.0), (5.0, 3.0), 1.0, 1.0)
    h = 1e-6
    for s in np.linspace(h, seg.length_m - h, 9):
        (xa, ya), (xb, yb) = seg.point(s - h), seg.point(s + h)
        assert math.hypot(xb - xa, yb - ya) / (2 * h) == pytest.approx(1.0, abs=1e-7)


def test_spline_nearest_point_solves_the_cubic_exactly():
    seg = QuadraticSpline((0.0, 0.0), (2.0, 0.0), (2.0, 2.0), 1.0, 1.0)
    s_true = 1.3
    x, y = seg.point(s_true)
    nx, ny = -seg.tangent(s_true)[1], seg.tangent(s_true)[0]
    near = seg.nearest(x + 0.2 * nx, y + 0.2 * ny, 0.0, seg.length_m)
    assert near.s == pytest.approx(s_true, abs=1e-9)
    assert near.d2 == pytest.approx(0.04, abs=1e-12)


def test_straight_spline_with_midpoint_control_is_a_line():
    seg = QuadraticSpline((0.0, 0.0), (1.0, 1.0), (2.0, 2.0), 1.0, 1.0)
    assert seg.length_m == pytest.approx(math.sqrt(8.0))
    assert seg.curvature(1.0) == pytest.approx(0.0)
    assert seg.nearest(2.0, 0.0, 0.0, seg.length_m).s == pytest.approx(math.sqrt(2.0))


def test_constant_acceleration_speed_profile_matches_kinematics():
    # v0 = 1, v1 = 3 over 8 m: a = (9 - 1) / 16 = 0.5 m/s^2, T = 2 L / (v0 + v1) = 4 s.
    seg = Line((0.0, 0.0), (8.0, 0.0), 1.0, 3.0)
    assert seg.accel_mps2 == pytest.approx(0.5)
    assert seg.duration_s == pytest.approx(4.0)
    for t in (0.0, 1.0, 2.0, 4.0):
        s = 1.0 * t + 0.5 * 0.5 * t**2
        assert seg.speed(s) == pytest.approx(1.0 + 0.5 * t)
        assert seg.time(s) == pytest.approx(t)


def test_speed_profile_from_rest_and_constant_speed():
    seg = Arc((0.0, 0.0), 1.0, 0.0, 4.0, True, 0.0, 2.0)  # from rest: a = 4 / 8 = 0.5
    assert seg.time(1.0) == pytest.approx(math.sqrt(2.0 * 1.0 / 0.5))
    assert seg.duration_s == pytest.approx(4.0)
    flat = Line((0.0, 0.0), (3.0, 0.0), 1.5, 1.5)
    assert flat.speed(2.0) == pytest.approx(1.5)
    assert flat.time(3.0) == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("factory", "argument"),
    [
        (lambda: Line((0.0, 0.0), (0.0, 0.0), 1.0, 1.0), "end"),
        (lambda: Line((0.0, math.nan), (1.0, 0.0), 1.0, 1.0), r"start\[1\]"),
        (lambda: Line((0.0, 0.0), (1.0, 0.0), -1.0, 1.0), "v0_mps"),
        (lambda: Line((0.0, 0.0), (1.0, 0.0), 0.0, 0.0), "v0_mps and v1_mps"),
        (lambda: Arc((0.0, 0.0), -1.0, 0.0, 1.0, False, 1.0, 1.0), "radius_m"),
        (lambda: Arc((0.0, 0.0), 1.0, 0.0, 0.0, False, 1.0, 1.0), "sweep_rad"),
        (lambda: Arc((math.inf, 0.0), 1.0, 0.0, 1.0, False, 1.0, 1.0), r"center\[0\]"),
        (lambda: Arc((0.0, 0.0), 1.0, 0.0, 1.0, False, 1.0, math.nan), "v1_mps"),
        (lambda: QuadraticSpline((0.0, 0.0), (3.0, 0.0), (1.0, 0.0), 1.0, 1.0), "control"),
        (lambda: QuadraticSpline((0.0, 0.0), (1.0, 1.0), (0.0, 0.0), 1.0, 1.0), "end"),
    ],
)
def test_invalid_segment_raises_value_error_naming_the_argument(factory, argument):
    with pytest.raises(ValueError, match=argument):
        factory()
