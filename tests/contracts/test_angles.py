"""One angle convention, (-π, π], for scalars and arrays; one body slip angle (Yamauchi Eq. 2)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.contracts import body_slip_angle, body_slip_angles, wrap_angle, wrap_angles


def test_plus_pi_stays_plus_pi_and_minus_pi_maps_to_plus_pi():
    assert wrap_angle(math.pi) == math.pi
    assert wrap_angle(-math.pi) == math.pi
    np.testing.assert_array_equal(wrap_angles([math.pi, -math.pi]), [math.pi, math.pi])


def test_angles_just_inside_the_seam_keep_their_sign():
    eps = 1e-9
    assert wrap_angle(-math.pi + eps) == pytest.approx(-math.pi + eps, abs=1e-15)
    assert wrap_angle(math.pi - eps) == pytest.approx(math.pi - eps, abs=1e-15)
    assert wrap_angle(math.pi + eps) == pytest.approx(-math.pi + eps, abs=1e-12)


@pytest.mark.parametrize("turns", [1, 2, 7, -1, -3, 1000, -1000])
@pytest.mark.parametrize("base", [0.0, 0.3, -2.5, 3.0])
def test_whole_turns_are_removed_from_large_angles(turns, base):
    angle = base + 2.0 * math.pi * turns
    assert wrap_angle(angle) == pytest.approx(base, abs=1e-9)
    assert float(wrap_angles(angle)) == pytest.approx(base, abs=1e-9)


def test_wrapped_angles_lie_in_the_half_open_interval_and_point_the_same_way():
    rng = np.random.default_rng(5)
    angles = rng.uniform(-1e3, 1e3, 10_000)
    wrapped = wrap_angles(angles)
    assert np.all(wrapped > -math.pi) and np.all(wrapped <= math.pi)
    np.testing.assert_allclose(np.cos(wrapped), np.cos(angles), atol=1e-9)
    np.testing.assert_allclose(np.sin(wrapped), np.sin(angles), atol=1e-9)


def test_scalar_and_array_wrapping_agree_element_wise():
    angles = np.array([-7.0, -math.pi, -1.0, 0.0, 1.0, math.pi, 4.0, 100.0])
    np.testing.assert_array_equal(wrap_angles(angles), [wrap_angle(a) for a in angles])


def test_wrap_angles_keeps_the_input_shape():
    assert wrap_angles(np.zeros((3, 4))).shape == (3, 4)


@pytest.mark.parametrize(("v_x", "v_y", "beta"), [
    (1.0, 0.0, 0.0),
    (1.0, 1.0, math.pi / 4),  # forward, drifting left
    (2.0, -1.0, math.atan(-0.5)),
    (-1.0, 0.0, 0.0),  # straight reversing: 0, not π
    (-1.0, 1.0, -math.pi / 4),  # V_y = V_x tan β holds in reverse too
    (0.0, 1.0, math.pi / 2),
    (0.0, -1.0, -math.pi / 2),
    (0.0, 0.0, 0.0),  # standing: undefined, reported as 0
])
def test_body_slip_angle_solves_yamauchi_eq2(v_x, v_y, beta):
    assert body_slip_angle(v_x, v_y) == pytest.approx(beta, abs=1e-12)
    assert float(body_slip_angles(v_x, v_y)) == pytest.approx(beta, abs=1e-12)
    if v_x != 0.0:
        assert v_y == pytest.approx(v_x * math.tan(beta), abs=1e-12)


def test_body_slip_angle_is_zero_at_or_below_the_minimum_speed():
    assert body_slip_angle(0.0005, 0.0005, min_speed_mps=1e-3) == 0.0
    assert body_slip_angle(0.001, 0.001, min_speed_mps=1e-3) == pytest.approx(math.pi / 4)
    np.testing.assert_allclose(body_slip_angles([0.0005, 0.001], [0.0005, 0.001], 1e-3),
                               [0.0, math.pi / 4])


def test_body_slip_angles_broadcast_and_match_the_scalar_form():
    rng = np.random.default_rng(11)
    v_x, v_y = rng.normal(size=(50, 1)), rng.normal(size=(1, 3))
    beta = body_slip_angles(v_x, v_y, 0.2)
    assert beta.shape == (50, 3)
    expected = [[body_slip_angle(float(a), float(b), 0.2) for b in v_y[0]] for a in v_x[:, 0]]
    np.testing.assert_allclose(beta, expected, atol=1e-15)
    assert np.all(np.abs(beta) <= math.pi / 2)


@pytest.mark.parametrize("bad", [-1.0, math.nan, math.inf])
def test_a_bad_minimum_speed_is_a_value_error_naming_it(bad):
    with pytest.raises(ValueError, match="min_speed_mps"):
        body_slip_angle(1.0, 0.0, min_speed_mps=bad)
    with pytest.raises(ValueError, match="min_speed_mps"):
        body_slip_angles([1.0], [0.0], min_speed_mps=bad)
