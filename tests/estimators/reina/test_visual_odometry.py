"""FTraceSComp: FTrace's slip angle (Eq. 1-2) handed to sComp (Eq. 15-17)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.contracts import SensorFrame
from slipenv.estimators import OdometryGeometry
from slipenv.estimators.reina import FTraceSComp, SlipRatioModel
from slipenv.sensors.trace_camera import TraceCamera, TraceCameraConfig
from slipenv.sensors.trace_history import history_from_poses

R, CPR, DT = 0.09, 285.0, 0.05
GEOM = OdometryGeometry(R, 0.5, CPR, left=(0, 2), right=(1, 3))
CLEAN = TraceCameraConfig(p_old_trace=0.0, p_shadow=0.0, p_patch=0.0)
WHEELS = {"front_left": (0.30, 0.25), "rear_left": (-0.30, 0.25)}


def crab_image(beta: float) -> np.ndarray:
    """A frame of a rover that crabbed straight at β for 1.5 m (heading 0)."""
    s = np.linspace(-1.5, 0.0, 151)
    poses = np.column_stack([s * math.cos(beta), s * math.sin(beta), np.zeros_like(s)])
    tracks = history_from_poses(poses, WHEELS, 0.08, 0.01)
    return TraceCamera(CLEAN).measure(tracks, [0, 0, 0, 0, 0, 0], np.random.default_rng(0)).image


def frame(k: int, gyro: float) -> SensorFrame:
    counts = np.full(4, k * 5, dtype=np.int64)  # 5 counts per 0.05 s: 3.2 cm/s of rolling
    return SensorFrame(k * DT, counts, np.full(4, np.nan), gyro_z_rad_s=gyro, heading_rad=0.0,
                       steer_rad=np.zeros(4))


def make(window_s: float = 4.0) -> FTraceSComp:
    return FTraceSComp(GEOM, SlipRatioModel(0.0, 0.0), CLEAN.nominal_camera(),
                       rear_to_cg_m=0.30, yaw_rate_window_s=window_s)


@pytest.mark.parametrize("beta_deg", [-8.0, 6.0])
def test_the_trace_angle_becomes_the_odometry_slip_angle(beta_deg):
    est = make()
    est.reset(0.0, 0.0, 0.0, frame(0, 0.0))
    for k in range(1, 40):
        est.update(frame(k, 0.0))
    det = est.update_trace(crab_image(math.radians(beta_deg)))
    assert det.status == "detected"
    e = est.update(frame(40, 0.0))
    assert math.degrees(e.slip_angle_rad) == pytest.approx(beta_deg, abs=1.0)
    # sComp moves sideways by tan β of the forward step (Eq. 16).
    e2 = est.update(frame(41, 0.0))
    assert (e2.y_m - e.y_m) / (e2.x_m - e.x_m) == pytest.approx(math.tan(e.slip_angle_rad),
                                                                rel=1e-6)


def test_a_jittering_yaw_rate_does_not_bend_the_slip_angle():
    """Yaw-rate swings faster than the trace is laid down average out of Eq. 2's b r / V."""
    beta = math.radians(-8.0)
    results = {}
    for window in (0.05, 4.0):
        est = make(window)
        est.reset(0.0, 0.0, 0.0, frame(0, 0.0))
        for k in range(1, 81):
            est.update(frame(k, 0.1 * (-1) ** k + (0.1 if k == 80 else 0.0)))
        results[window] = est.update_trace(crab_image(beta)).slip_angle_rad
    assert math.degrees(abs(results[4.0] - beta)) < 1.0
    # Over the last 0.05 s only (0.2 and -0.1 rad/s) the term b r / V adds about 25°.
    assert math.degrees(abs(results[0.05] - beta)) > 5.0


def test_bad_window_is_an_error():
    with pytest.raises(ValueError, match="yaw_rate_window_s"):
        make(0.0)
