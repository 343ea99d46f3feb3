"""Gyrodometry: encoder distance with gyro heading; contract and validation."""

import math
from dataclasses import replace

import numpy as np
import pytest

from slipenv.estimators.base import Estimator, OdometryGeometry
from slipenv.estimators.dead_reckoning import DeadReckoning
from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.skid_steer.endo import EndoOdometry
from tests.estimators import skid_steer_synth as synth

R, TREAD, CPR = 0.06, 0.41, 1e9  # fine encoders: quantisation below 1e-9 rad
GEOM = OdometryGeometry(R, TREAD, CPR)


def constant_run(v_l, v_r, gyro, n=100):
    return synth.constant_frames(v_l, v_r, gyro, n=n, geometry=GEOM)


run = synth.feed


@pytest.mark.parametrize("v_l, v_r", [(0.03, 0.07), (0.1, 0.1), (-0.05, 0.05), (0.08, -0.02)])
def test_zero_slip_equals_dead_reckoning(v_l, v_r):
    frames = constant_run(v_l, v_r, (v_r - v_l) / TREAD)
    reference = run(DeadReckoning(GEOM), frames, (1.0, -2.0, 0.3))
    for estimator in (Gyrodometry(GEOM), EndoOdometry(GEOM, 0.824)):
        for a, b in zip(run(estimator, frames, (1.0, -2.0, 0.3)), reference, strict=True):
            assert abs(a.x_m - b.x_m) < 1e-9 and abs(a.y_m - b.y_m) < 1e-9
            assert abs(math.remainder(a.yaw_rad - b.yaw_rad, 2 * math.pi)) < 1e-9
            assert a.speed_mps == pytest.approx(b.speed_mps, abs=1e-9)


def test_heading_from_gyro_distance_from_encoders():
    # Encoders say straight at 0.1 m/s for 5 s; the gyro says 0.2 rad/s: an arc of length 0.5 m.
    est = run(Gyrodometry(GEOM), constant_run(0.1, 0.1, 0.2))[-1]
    radius = 0.1 / 0.2
    assert est.yaw_rad == pytest.approx(1.0)
    # Midpoint rule over 100 steps of 0.01 rad: chord error ≈ L Δθ²/24 ≈ 2e-6 m.
    assert est.x_m == pytest.approx(radius * math.sin(1.0), abs=1e-5)
    assert est.y_m == pytest.approx(radius * (1 - math.cos(1.0)), abs=1e-5)
    assert est.slip_angle_rad == 0.0 and est.yaw_rate_rps == pytest.approx(0.2)


def test_is_an_estimator():
    assert isinstance(Gyrodometry(GEOM), Estimator)


def test_frame_validation():
    frames = constant_run(0.1, 0.1, 0.0, n=3)
    est = Gyrodometry(GEOM)
    with pytest.raises(RuntimeError):
        est.update(frames[1])
    est.reset(0.0, 0.0, 0.0, frames[0])
    est.update(frames[2])
    with pytest.raises(ValueError, match="out of order"):
        est.update(frames[1])
    with pytest.raises(ValueError, match="not finite"):
        est.update(replace(frames[3], t_s=float("nan")))
    with pytest.raises(ValueError, match="frame.gyro_z_rad_s"):
        est.update(replace(frames[3], gyro_z_rad_s=float("nan")))
    with pytest.raises(ValueError, match="enc_counts"):
        est.update(replace(frames[3], enc_counts=np.array([1])))


def test_geometry_validation():
    with pytest.raises(ValueError, match="geometry"):
        Gyrodometry({"wheel_radius_m": 0.06})
    frames = constant_run(0.1, 0.1, 0.0, n=1)
    with pytest.raises(ValueError, match="geometry.left"):
        bad = OdometryGeometry(R, TREAD, CPR, left=(0,), right=(3,))
        Gyrodometry(bad).reset(0.0, 0.0, 0.0, frames[0])
    with pytest.raises(ValueError, match="x_m"):
        Gyrodometry(GEOM).reset(float("nan"), 0.0, 0.0, frames[0])
