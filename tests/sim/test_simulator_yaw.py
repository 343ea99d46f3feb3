"""The rotation about body z over a step, from orientations (what a yaw gyro integrates)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.sim.simulator import body_z_rotation_rad


def compose(a, b):
    """Hamilton product a b of quaternions (x, y, z, w)."""
    ax, ay, az, aw = a
    bx, by, bz, bw = b
    return (aw * bx + ax * bw + ay * bz - az * by, aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw, aw * bw - ax * bx - ay * by - az * bz)


def about(axis, angle):
    """The rotation by ``angle`` about the unit vector along ``axis``."""
    n = np.asarray(axis, float) / np.linalg.norm(axis)
    return (*(math.sin(angle / 2) * n), math.cos(angle / 2))


def world_yaw(q) -> float:
    """Z-Y-X Euler yaw of q: the heading of its x axis in the world's horizontal plane."""
    x, y, z, w = q
    return math.atan2(2 * (w * z + x * y), 1 - 2 * (y * y + z * z))


TILTED = compose(about((0, 0, 1), 2.0), about((1, 0.4, 0), 0.35))  # on a 20° slope


@pytest.mark.parametrize("psi", [1e-4, -0.02, 1.0, -3.0])
def test_a_rotation_about_the_body_z_axis_is_its_angle_at_any_tilt(psi):
    for q0 in [(0, 0, 0, 1), TILTED]:
        assert body_z_rotation_rad(q0, compose(q0, about((0, 0, 1), psi))) == pytest.approx(
            psi, abs=1e-12)


def test_a_roll_or_a_pitch_is_no_rotation_about_body_z():
    for axis in [(1, 0, 0), (0, 1, 0)]:
        assert body_z_rotation_rad(TILTED, compose(TILTED, about(axis, 0.1))) == pytest.approx(
            0.0, abs=1e-15)


def test_the_sign_of_a_quaternion_does_not_change_the_rotation():
    q1 = compose(TILTED, about((0, 0, 1), 0.4))
    assert body_z_rotation_rad(TILTED, tuple(-c for c in q1)) == pytest.approx(0.4, abs=1e-12)


def test_a_constant_rate_turn_on_a_slope_sums_to_rate_times_time():
    # 1.2 rad/s about the slope's normal for 2 s at 240 Hz: 1.2 t rad at every t, where the
    # world yaw (Euler) of the tilted body turns unevenly
    rate, dt, n = 1.2, 1.0 / 240.0, 480
    qs = [TILTED]
    for _ in range(n):
        qs.append(compose(qs[-1], about((0, 0, 1), rate * dt)))
    turn = np.cumsum([body_z_rotation_rad(a, b) for a, b in zip(qs[:-1], qs[1:], strict=True)])
    expected = rate * dt * np.arange(1, n + 1)
    np.testing.assert_allclose(turn, expected, rtol=0, atol=1e-9)
    yaw = np.unwrap([world_yaw(q) for q in qs])
    assert np.max(np.abs((yaw[1:] - yaw[0]) - expected)) > 1e-2


def test_a_step_of_the_simulator_carries_its_turn_and_a_reset_does_not(make_sim):
    from slipenv.vehicles.kinematics import twist_to_commands

    sim = make_sim("farm_2wd", "concrete", "janosi")
    start = sim.reset(0.0, 0.0, 0.0)
    assert start.yaw_increment_rad is None
    assert start.mean_yaw_rate_rad_s == start.yaw_rate_rad_s
    previous = start
    for _ in range(5):
        truth = sim.step(*twist_to_commands(sim.spec, 0.5, 0.6))
        assert truth.interval_s == sim.control_dt_s
        # level ground: the body-z turn is the heading change (to the chassis' tilt²)
        assert truth.yaw_increment_rad == pytest.approx(truth.yaw_rad - previous.yaw_rad,
                                                        abs=1e-7)
        assert math.isclose(truth.mean_yaw_rate_rad_s,
                            truth.yaw_increment_rad / sim.control_dt_s)
        previous = truth
    assert abs(previous.yaw_rad - start.yaw_rad) > 0.02  # it did turn
