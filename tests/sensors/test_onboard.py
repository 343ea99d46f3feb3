"""Onboard sensors: quantisation, noise levels (DESIGN §4), seeding, conventions."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.contracts.constants import G_MPS2
from slipenv.sensors.noise import SensorNoise
from slipenv.sensors.onboard import Compass, Imu, SensorSuite, WheelEncoders
from slipenv.sim.simulator import VehicleTruth


def truth(yaw=0.3, angles=(1.0, -2.5), torque=(10.0, 20.0)) -> VehicleTruth:
    return VehicleTruth(
        t_s=1.0, position_m=(1.0, 2.0, 0.0), yaw_rad=yaw, pitch_rad=0.05, roll_rad=-0.1,
        velocity_body_mps=(0.5, 0.01, 0.0), yaw_rate_rad_s=0.2,
        specific_force_body_mps2=(0.3, 0.1, 9.81),
        channel_angle_rad=np.array(angles), channel_torque_nm=np.array(torque),
    )


def test_encoders_report_integer_counts_quantised_at_285_per_rad():
    counts = WheelEncoders(285.0).measure(truth(), np.random.default_rng(0))
    assert counts.dtype == np.int64
    np.testing.assert_array_equal(counts, [285, -713])


def test_imu_noise_has_the_lindgren_variances():
    noise = SensorNoise()
    imu = Imu(noise)
    rng = np.random.default_rng(1)
    samples = np.array([imu.measure(truth(), rng) for _ in range(20000)])
    assert np.var(samples[:, 0] / G_MPS2) == pytest.approx(4.5e-4, rel=0.05)
    assert np.var(samples[:, 1] / G_MPS2) == pytest.approx(3.0e-4, rel=0.05)
    assert np.var(samples[:, 2]) == pytest.approx(6.5e-5, rel=0.05)
    assert np.mean(samples[:, 2]) == pytest.approx(0.2, abs=3e-4)


def test_gyro_bias_shifts_the_yaw_rate():
    imu = Imu(SensorNoise(gyro_bias_rad_s=0.01, gyro_var_rad2_s2=0.0))
    assert imu.measure(truth(), np.random.default_rng(0))[2] == pytest.approx(0.21)


def test_compass_wraps_to_minus_pi_pi():
    reading = Compass(0.0).measure(truth(yaw=3.5), np.random.default_rng(0))
    assert reading == pytest.approx(3.5 - 2 * math.pi)


def test_the_same_generator_state_gives_the_same_frame():
    suite = SensorSuite(285.0, SensorNoise())
    a = suite.measure(truth(), np.random.default_rng(42))
    b = suite.measure(truth(), np.random.default_rng(42))
    c = suite.measure(truth(), np.random.default_rng(43))
    assert a == b and a != c


def test_perfect_sensors_report_the_truth():
    frame = SensorSuite(285.0, SensorNoise.perfect()).measure(truth(), np.random.default_rng(0))
    assert frame.gyro_z_rad_s == 0.2 and frame.roll_rad == -0.1 and frame.pitch_rad == 0.05
    np.testing.assert_allclose(frame.wheel_torque_nm, [10.0, 20.0])


@pytest.mark.parametrize("field", ["acc_x_var_g2", "torque_rel_std", "compass_std_rad"])
def test_negative_or_nan_noise_is_rejected(field):
    with pytest.raises(ValueError, match=field):
        SensorNoise(**{field: -1.0})
    with pytest.raises(ValueError, match=field):
        SensorNoise(**{field: float("nan")})


def test_the_suite_draws_what_each_sensor_would_draw_in_turn():
    # the suite draws all its noise at once: the frame must be the one the sensors
    # give when each draws its own, in the suite's order, from the same generator state
    noise = SensorNoise(torque_rel_std=0.05, compass_std_rad=0.02, incl_std_rad=0.01)
    suite = SensorSuite(285.0, noise)
    state = truth(yaw=3.1, torque=(10.0, -4.0, 7.5))
    state = VehicleTruth(**{**vars(state), "channel_angle_rad": np.array([1.0, 2.0, 3.0])})
    rng_suite, rng_each = np.random.default_rng(4), np.random.default_rng(4)
    frame = suite.measure(state, rng_suite)
    torque = suite.torque.measure(state, rng_each)
    imu = suite.imu.measure(state, rng_each)
    incl = suite.inclinometer.measure(state, rng_each)
    heading = suite.compass.measure(state, rng_each)
    np.testing.assert_array_equal(frame.wheel_torque_nm, torque)
    assert (frame.acc_x_mps2, frame.acc_y_mps2, frame.gyro_z_rad_s) == imu
    assert (frame.roll_rad, frame.pitch_rad) == incl
    assert frame.heading_rad == heading and type(frame.heading_rad) is type(heading)
    assert rng_suite.random() == rng_each.random()


def test_gyro_reads_the_turn_over_the_interval_divided_by_the_interval():
    # 0.05 rad in 0.05 s is 1 rad/s whatever the rate at the sample instant (0.2 rad/s)
    state = VehicleTruth(**{**vars(truth()), "yaw_increment_rad": 0.05, "interval_s": 0.05})
    imu = Imu(SensorNoise(gyro_bias_rad_s=0.01, gyro_var_rad2_s2=0.0))
    assert imu.measure(state, np.random.default_rng(0))[2] == pytest.approx(1.01, abs=1e-12)
    instant = Imu(SensorNoise(gyro_bias_rad_s=0.01, gyro_var_rad2_s2=0.0), sampling="instant")
    assert instant.measure(state, np.random.default_rng(0))[2] == pytest.approx(0.21, abs=1e-12)


def test_gyro_reads_the_instantaneous_rate_where_no_interval_was_integrated():
    # a reset's truth holds no step: the settled body's rate is all there is
    imu = Imu(SensorNoise.perfect())
    assert imu.measure(truth(), np.random.default_rng(0))[2] == 0.2


def test_an_unknown_gyro_sampling_is_rejected():
    with pytest.raises(ValueError, match="sampling"):
        Imu(SensorNoise(), sampling="median")
