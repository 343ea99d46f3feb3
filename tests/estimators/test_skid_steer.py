"""Skid-steer kinematics with slip (Yamauchi Eq. 1-7): closed forms and the exact inverse."""

import math

import numpy as np
import pytest

from slipenv.estimators.skid_steer.kinematics import (
    body_velocity,
    slips_from_body_velocity,
    track_ground_speeds,
    world_velocity,
)

TREAD = 0.41  # [m] Yamauchi Table 1


def test_round_trip_recovers_slips_and_beta():
    rng = np.random.default_rng(0)
    k = 1000
    v_l = rng.choice([-1.0, 1.0], k) * rng.uniform(0.02, 0.3, k)
    v_r = rng.choice([-1.0, 1.0], k) * rng.uniform(0.02, 0.3, k)
    alpha_l, alpha_r = rng.uniform(-0.8, 0.8, k), rng.uniform(-0.8, 0.8, k)
    beta = rng.uniform(-1.2, 1.2, k)
    v_x, v_y, omega = body_velocity(v_l, v_r, alpha_l, alpha_r, beta, TREAD)
    a_l, a_r, b = slips_from_body_velocity(v_l, v_r, v_x, v_y, omega, TREAD)
    np.testing.assert_allclose(a_l, alpha_l, rtol=0, atol=1e-12)
    np.testing.assert_allclose(a_r, alpha_r, rtol=0, atol=1e-12)
    np.testing.assert_allclose(b, beta, rtol=0, atol=1e-12)


def test_no_slip_is_differential_drive():
    v_x, v_y, omega = body_velocity(0.1, 0.3, 0.0, 0.0, 0.0, TREAD)
    assert v_x == pytest.approx(0.2)
    assert v_y == 0.0
    assert omega == pytest.approx(0.2 / TREAD)


def test_slip_closed_form():
    # Left track keeps 50 %, right 80 % of its speed; β = 0.1 rad.
    v_x, v_y, omega = body_velocity(0.2, 0.2, 0.5, 0.2, 0.1, TREAD)
    assert v_x == pytest.approx(0.5 * (0.16 + 0.10))
    assert v_y == pytest.approx(0.13 * math.tan(0.1))
    assert omega == pytest.approx(0.06 / TREAD)
    ground_l, ground_r = track_ground_speeds(v_x, omega, TREAD)
    assert (ground_l, ground_r) == (pytest.approx(0.10), pytest.approx(0.16))


def test_world_velocity_points_along_yaw_plus_beta():
    v_x, beta, yaw = 0.05, 0.3, 2.0
    x_dot, y_dot = world_velocity(v_x, v_x * math.tan(beta), yaw)
    speed = v_x / math.cos(beta)
    assert x_dot == pytest.approx(speed * math.cos(yaw + beta), abs=1e-15)
    assert y_dot == pytest.approx(speed * math.sin(yaw + beta), abs=1e-15)


def test_inverse_edge_cases():
    a_l, a_r, beta = slips_from_body_velocity(0.0, 0.1, 0.05, 0.0, 0.05 / TREAD, TREAD)
    assert math.isnan(a_l) and a_r == pytest.approx(0.25) and beta == 0.0
    _, _, beta = slips_from_body_velocity(0.1, 0.1, 0.0, 0.02, 0.0, TREAD)
    assert beta == pytest.approx(math.pi / 2)
    _, _, beta = slips_from_body_velocity(-0.1, -0.1, -0.1, 0.01, 0.0, TREAD)
    assert beta == pytest.approx(math.atan(0.01 / -0.1))  # reversing: Eq. 2 still holds


@pytest.mark.parametrize("tread", [-0.41, 0.0, float("nan"), float("inf")])
def test_bad_tread_is_rejected(tread):
    with pytest.raises(ValueError, match="tread_m"):
        body_velocity(0.1, 0.1, 0.0, 0.0, 0.0, tread)
    with pytest.raises(ValueError, match="tread_m"):
        slips_from_body_velocity(0.1, 0.1, 0.1, 0.0, 0.0, tread)
