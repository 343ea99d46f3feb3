"""Rotating beacon scanner: layout, rates, geometry, timing, randomness (Lindgren §2.4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.sensors.beacons import BeaconScanner, default_beacons_xy


def true_bearing(beacon: np.ndarray, x: float, y: float, yaw: float) -> float:
    b = math.atan2(beacon[1] - y, beacon[0] - x) - yaw
    return (b + math.pi) % (2.0 * math.pi) - math.pi


def test_default_layout() -> None:
    b = default_beacons_xy()
    assert b.shape == (15, 2)
    np.testing.assert_allclose(np.max(np.abs(b), axis=1), 15.0)  # all on the field's edge
    assert len({tuple(p) for p in b}) == 15


def test_rate_is_about_30_bearings_per_second() -> None:
    """Driving a 4 m circle near the field centre for 20 s at 3.6 scans/s."""
    sc = BeaconScanner()
    rng = np.random.default_rng(0)
    n, n_scans = 0, 0
    sc.reset(0.0, 4.0, 0.0, math.pi / 2)
    for k in range(1, 401):
        t = 0.05 * k
        bearings, times = sc.scan(t, 4.0 * math.cos(t / 4), 4.0 * math.sin(t / 4),
                                  t / 4 + math.pi / 2, rng)
        assert np.all((times > t - 0.05) & (times <= t)) and np.all(np.diff(times) >= 0.0)
        assert np.all(np.abs(bearings) <= math.pi)
        n += len(bearings)
    n_scans = 20.0 * 3.6
    assert 25.0 <= n / 20.0 <= 40.0
    assert n / n_scans < 15.0  # some beacons are always out of view


def test_stationary_scanner_sees_each_visible_beacon_once_per_revolution() -> None:
    beacons = np.array([[10.0, 0.0], [0.0, 10.0], [-10.0, 0.5], [30.0, 30.0]])
    # third is behind (outside the 240° field of view), fourth beyond the 25 m range
    sc = BeaconScanner(beacons, bearing_var_rad2=0.0)
    rng = np.random.default_rng(0)
    sc.reset(0.0, 0.0, 0.0, 0.0)
    period = 1.0 / 3.6
    bearings, times = sc.scan(10 * period, 0.0, 0.0, 0.0, rng)
    assert len(bearings) == 20
    # the head (phase 0 at t = 0, counter-clockwise) points at φ at t = (φ/2π + m) period;
    # the scan interval (0, 10 periods] excludes t = 0
    for expected, first_hit in ((0.0, period), (math.pi / 2, period / 4)):
        hit = np.isclose(bearings, expected, atol=1e-12)
        assert hit.sum() == 10
        np.testing.assert_allclose(np.diff(times[hit]), period, rtol=1e-9)
        assert times[hit][0] == pytest.approx(first_hit, rel=1e-9)


def test_bearings_use_the_pose_at_their_own_time() -> None:
    """Straight line at 1 m/s, yawing 0.2 rad/s: linear interpolation is exact, so noise-free
    bearings equal the true bearing from the pose at each time stamp."""
    beacons = default_beacons_xy()
    sc = BeaconScanner(beacons, bearing_var_rad2=0.0)
    rng = np.random.default_rng(3)

    def pose(t: float) -> tuple[float, float, float]:
        return -5.0 + t, 2.0, 0.2 * t

    sc.reset(0.0, *pose(0.0))
    for k in range(1, 41):
        t = 0.05 * k
        bearings, times = sc.scan(t, *pose(t), rng)
        for z, tb in zip(bearings, times, strict=True):
            errors = [abs(z - true_bearing(b, *pose(tb))) for b in beacons]
            assert min(errors) < 1e-9


def test_noise_variance_and_reproducibility() -> None:
    beacons = np.array([[10.0, 0.0]])
    sc = BeaconScanner(beacons, bearing_var_rad2=1e-4)
    sc.reset(0.0, 0.0, 0.0, 0.0)
    b1, t1 = sc.scan(300.0, 0.0, 0.0, 0.0, np.random.default_rng(5))
    assert len(b1) == 1080
    assert np.var(b1) == pytest.approx(1e-4, rel=0.1)
    assert abs(np.mean(b1)) < 3e-3
    sc.reset(0.0, 0.0, 0.0, 0.0)
    b2, t2 = sc.scan(300.0, 0.0, 0.0, 0.0, np.random.default_rng(5))
    np.testing.assert_array_equal(b1, b2)
    np.testing.assert_array_equal(t1, t2)


def test_clutter_adds_spurious_bearings() -> None:
    sc = BeaconScanner(np.array([[10.0, 0.0]]), clutter_rate_hz=20.0)
    sc.reset(0.0, 0.0, 0.0, 0.0)
    b, t = sc.scan(10.0, 0.0, 0.0, 0.0, np.random.default_rng(1))
    assert len(b) == pytest.approx(36 + 200, abs=45)
    assert np.all((t > 0.0) & (t <= 10.0)) and np.all(np.diff(t) >= 0.0)


def test_first_call_starts_and_bad_input_raises() -> None:
    sc = BeaconScanner()
    rng = np.random.default_rng(0)
    b, t = sc.scan(1.0, 0.0, 0.0, 0.0, rng)
    assert b.size == 0 and t.size == 0
    with pytest.raises(ValueError, match="not after"):
        sc.scan(1.0, 0.0, 0.0, 0.0, rng)
    with pytest.raises(ValueError, match="beacons_xy"):
        BeaconScanner(np.zeros((3, 3)))
    with pytest.raises(ValueError, match="scan_rate_hz"):
        BeaconScanner(scan_rate_hz=0.0)


@pytest.mark.parametrize("bad", ["yes", [[1.0, 2.0, 3.0]], np.zeros((0, 2)),
                                 [[np.nan, 0.0]], [["a", "b"]], {"x": 1}, [[1e9, 0.0]]])
def test_bad_beacon_positions_are_a_value_error_naming_them(bad) -> None:
    from slipenv.sensors.beacons import as_beacons_xy

    with pytest.raises(ValueError, match="beacons"):
        as_beacons_xy(bad)


def test_an_integer_beacon_array_is_the_documented_form() -> None:
    from slipenv.sensors.beacons import as_beacons_xy

    xy = as_beacons_xy(np.array([[5, 5], [-5, 5], [0, -5]]))
    assert xy.dtype == float and xy.shape == (3, 2)


@pytest.mark.parametrize(("field", "value"), [
    ("gyro_var_rad2_s2", 1e6), ("torque_scale", 1e9), ("compass_std_rad", -1.0),
    ("acc_x_var_g2", float("nan")), ("torque_rel_std", "5%"), ("incl_std_rad", True),
])
def test_implausible_sensor_noise_is_a_value_error_naming_the_field(field, value) -> None:
    from slipenv.sensors.noise import SensorNoise

    with pytest.raises(ValueError, match=field):
        SensorNoise(**{field: value})
