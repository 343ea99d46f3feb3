"""Paths: continuity checks, evaluation along the path, projection and sampling."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.paths import (
    Arc,
    Line,
    Path,
    PathBuilder,
    circle,
    field_rows,
    lindgren_circles,
    sample_path,
    straight,
)


def test_gap_corner_and_speed_jump_between_segments_are_rejected():
    a = Line((0.0, 0.0), (1.0, 0.0), 1.0, 1.0)
    with pytest.raises(ValueError, match="do not join"):
        Path([a, Line((1.0, 1e-3), (2.0, 0.0), 1.0, 1.0)])
    with pytest.raises(ValueError, match="corner"):
        Path([a, Line((1.0, 0.0), (1.0, 1.0), 1.0, 1.0)])
    with pytest.raises(ValueError, match="speed jumps"):
        Path([a, Line((1.0, 0.0), (2.0, 0.0), 2.0, 2.0)])
    with pytest.raises(ValueError, match="segments"):
        Path([])


def test_joint_within_tolerance_is_accepted():
    a = Line((0.0, 0.0), (1.0, 0.0), 1.0, 1.0)
    path = Path([a, Line((1.0, 5e-7), (2.0, 5e-7), 1.0, 1.0)])
    assert path.length_m == pytest.approx(2.0)


def test_pose_speed_and_time_along_a_line_then_arc():
    path = PathBuilder(speed_mps=1.0).line(2.0).arc(1.0, math.pi, speed_mps=2.0).build()
    assert path.length_m == pytest.approx(2.0 + math.pi)
    assert path.pose_at(1.0) == pytest.approx((1.0, 0.0, 0.0))
    assert path.pose_at(2.0 + 0.5 * math.pi) == pytest.approx((3.0, 1.0, 0.5 * math.pi))
    assert path.end_pose() == pytest.approx((2.0, 2.0, math.pi))
    assert path.curvature_at(3.0) == pytest.approx(1.0)
    assert path.speed_at(2.0 + math.pi) == pytest.approx(2.0)
    assert path.duration_s == pytest.approx(2.0 + 2.0 * math.pi / 3.0)
    assert path.time_at(path.length_m) == pytest.approx(path.duration_s)
    assert path.pose_at(-5.0) == path.start_pose()  # clamped


@pytest.mark.parametrize("offset", [0.7, -0.7])
def test_cross_track_on_a_line_is_positive_left_negative_right(offset):
    path = straight(10.0, 1.0, heading_rad=0.5 * math.pi)  # along +y: left is -x
    proj = path.project(-offset, 4.0)
    assert proj.s == pytest.approx(4.0)
    assert proj.cross_track_m == pytest.approx(offset)
    assert proj.heading_rad == pytest.approx(0.5 * math.pi)
    assert proj.remaining_m == pytest.approx(6.0)
    assert proj.speed_mps == pytest.approx(1.0)


@pytest.mark.parametrize(("clockwise", "inside_sign"), [(False, 1.0), (True, -1.0)])
def test_cross_track_on_an_arc_is_signed_and_exact(clockwise, inside_sign):
    path = circle(2.0, 1.0, loops=0.75, clockwise=clockwise, center=(1.0, 1.0))
    for radius, expected in ((1.5, 0.5 * inside_sign), (2.8, -0.8 * inside_sign)):
        x, y = 1.0 + radius * math.cos(-0.3), 1.0 + radius * math.sin(-0.3)
        proj = path.project(x, y)
        assert proj.cross_track_m == pytest.approx(expected)
        px, py, _ = path.pose_at(proj.s)
        assert math.hypot(px - x, py - y) == pytest.approx(abs(expected))
        assert proj.curvature_1pm == pytest.approx(inside_sign * 0.5)


def test_projection_beyond_the_end_keeps_the_lateral_offset():
    proj = straight(5.0, 1.0).project(7.0, -0.4)
    assert proj.s == pytest.approx(5.0)
    assert proj.cross_track_m == pytest.approx(-0.4)
    assert proj.remaining_m == pytest.approx(0.0)


def _walk(path: Path, offset_m: float, ds_m: float = 0.05) -> np.ndarray:
    """Project points ``offset_m`` left of the path every ``ds_m``, hinting with the last s."""
    s_hint, errors = 0.0, []
    for s in np.arange(0.0, path.length_m, ds_m):
        x, y, h = path.pose_at(s)
        proj = path.project(x - offset_m * math.sin(h), y + offset_m * math.cos(h), s_hint)
        s_hint = proj.s
        errors.append((proj.s - s, proj.cross_track_m - offset_m))
    return np.abs(np.asarray(errors))


def test_hinted_projection_follows_a_circle_driven_one_and_a_half_times():
    path = circle(4.0, 1.0, loops=1.5)
    err = _walk(path, 0.3)
    assert err[:, 0].max() < 1e-9 and err[:, 1].max() < 1e-9
    x, y, _ = path.pose_at(30.0)  # second lap; without a hint the first lap wins the tie
    assert path.project(x, y).s == pytest.approx(30.0 - 2.0 * math.pi * 4.0)
    assert path.project(x, y, s_hint=29.9).s == pytest.approx(30.0)


def test_hinted_projection_tracks_lindgren_circles_through_the_touching_point():
    path = lindgren_circles()
    err = _walk(path, -0.2)
    assert err[:, 0].max() < 1e-9 and err[:, 1].max() < 1e-9


def test_hinted_projection_tracks_a_figure_eight_through_its_crossing():
    r = 2.0
    path = (PathBuilder(heading_rad=0.25 * math.pi).line(r).arc(r, 1.5 * math.pi, True)
            .line(2.0 * r).arc(r, 1.5 * math.pi, False).line(2.0 * r).build())
    s_cross = r + 1.5 * math.pi * r + r  # second pass through the origin
    assert path.pose_at(s_cross)[:2] == pytest.approx((0.0, 0.0), abs=1e-12)
    err = _walk(path, 0.1)
    assert err[:, 0].max() < 1e-9 and err[:, 1].max() < 1e-9
    assert path.project(0.0, 0.0).s == pytest.approx(0.0)  # the global search jumps back
    assert path.project(0.0, 0.0, s_hint=s_cross - 0.05).s == pytest.approx(s_cross)


def test_default_search_window_is_shorter_than_the_tightest_half_turn():
    path = circle(0.25, 0.05, loops=3.0)
    extent = path.search_back_m + path.search_ahead_m
    assert extent < math.pi * 0.25
    assert straight(50.0, 1.0).search_ahead_m == pytest.approx(3.0)
    with pytest.raises(ValueError, match="search_ahead_m"):
        Path([Line((0.0, 0.0), (1.0, 0.0), 1.0, 1.0)], search_ahead_m=-1.0)


def test_sample_path_returns_arrays_covering_the_whole_path():
    path = field_rows(row_length_m=10.0, n_rows=3, turn_speed_mps=0.5)
    smp = sample_path(path, ds_m=0.1)
    n = math.ceil(path.length_m / 0.1) + 1
    assert all(len(a) == n for a in smp)
    assert smp.s_m[-1] == pytest.approx(path.length_m)
    assert (smp.x_m[-1], smp.y_m[-1]) == pytest.approx(path.end_pose()[:2])
    assert np.all(np.diff(smp.time_s) > 0.0)
    steps = np.hypot(np.diff(smp.x_m), np.diff(smp.y_m))
    assert steps.max() <= 0.1 + 1e-9
    assert smp.speed_mps.min() == pytest.approx(0.5)
    with pytest.raises(ValueError, match="ds_m"):
        path.sample(0.0)


def test_a_hinted_projection_examines_only_the_segments_its_search_window_overlaps(
        monkeypatch: pytest.MonkeyPatch) -> None:
    # The projection's cost per control step is in `slipenv bench` (observation_reward); what a
    # test can hold is the algorithm: with a hint, the work does not grow with the path's length.
    path = field_rows()
    assert len(path.segments) == 10
    examined: list[int] = []
    for cls in {type(seg) for seg in path.segments}:
        def counting(self, *args, _nearest=cls.nearest, **kwargs):
            examined[-1] += 1
            return _nearest(self, *args, **kwargs)
        monkeypatch.setattr(cls, "nearest", counting)
    starts = np.cumsum([0.0] + [seg.length_m for seg in path.segments])
    for s in np.linspace(0.0, path.length_m, 50):
        x, y, _ = path.pose_at(s)
        examined.append(0)
        proj = path.project(x + 0.1, y - 0.2, s)
        lo, hi = max(s - path.search_back_m, 0.0), min(s + path.search_ahead_m, path.length_m)
        overlapping = int(np.sum((starts[:-1] <= hi) & (starts[1:] >= lo)))
        assert 1 <= examined[-1] <= overlapping <= 3
        examined.append(0)
        assert path.project(x + 0.1, y - 0.2).s == pytest.approx(proj.s, abs=1e-9)


def test_segment_boundaries_hand_over_without_gaps():
    a = Line((0.0, 0.0), (2.0, 0.0), 1.0, 1.0)
    b = Arc((2.0, 1.0), 1.0, -0.5 * math.pi, math.pi, False, 1.0, 1.0)
    path = Path([a, b])
    proj = path.project(2.0, -0.1, s_hint=1.9)
    assert proj.s == pytest.approx(2.0)
    assert proj.cross_track_m == pytest.approx(-0.1)


def test_extent_turning_radius_speed_and_yaw_rate_of_lindgren_straights():
    from slipenv.paths import lindgren_straights

    path = lindgren_straights(length_m=10.0, n_legs=3, turn_radius_m=2.0, speed_mps=0.5)
    # Legs along +x, -x, +x stacked 4 m apart to the right; the turns bulge 2 m past each end.
    x0, y0, x1, y1 = path.extent()
    assert (x0, x1) == pytest.approx((-2.0, 12.0))
    assert (y0, y1) == pytest.approx((-8.0, 0.0))
    assert path.min_turning_radius_m == pytest.approx(2.0)
    assert path.max_speed_mps == 0.5
    assert path.max_yaw_rate_rps == pytest.approx(0.25)  # v / r on the turns


def test_a_straight_path_has_an_infinite_turning_radius_and_no_yaw_rate():
    from slipenv.paths import straight

    path = straight(length_m=5.0, speed_mps=0.3, heading_rad=math.pi / 2)
    assert path.min_turning_radius_m == math.inf and path.max_yaw_rate_rps == 0.0
    assert path.extent() == pytest.approx((0.0, 0.0, 0.0, 5.0), abs=1e-12)
