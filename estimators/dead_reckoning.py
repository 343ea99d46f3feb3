"""Plain dead reckoning from wheel encoders (the baseline every paper compares against).

Differential-drive kinematics with the nominal radius and track width and no slip model:
v = R (ω_r + ω_l)/2, Ω = R (ω_r - ω_l)/W (Lindgren Eq. 15-16 inverted; Yamauchi Eq. 1-3 with
zero slip). Left/right wheel groups are averaged, so the same code serves two-wheel, four-wheel
skid-steer and tracked vehicles. Integration uses the exact arc (midpoint heading).
"""

from __future__ import annotations

import math

import numpy as np

from slipenv.contracts import PoseEstimate, SensorFrame, wrap_angle

from .base import OdometryGeometry, check_frame_time


def side_angles_rad(frame: SensorFrame, geometry: OdometryGeometry) -> tuple[float, float]:
    """Mean cumulative wheel angle of the left and right groups [rad].

    The group means are taken in plain floats (the same left-to-right sum ``np.mean`` does
    for a handful of values, so the same bits): this runs once per control step.
    """
    counts = frame.enc_counts
    c = counts.tolist() if isinstance(counts, np.ndarray) else np.asarray(counts).tolist()
    left = [float(c[i]) for i in geometry.left]
    right = [float(c[i]) for i in geometry.right]
    return (sum(left) / len(left) / geometry.counts_per_rad,
            sum(right) / len(right) / geometry.counts_per_rad)


def integrate_arc(
    x: float, y: float, yaw: float, distance_m: float, dyaw_rad: float
) -> tuple[float, float, float]:
    """Advance a pose by a travelled distance and heading change (midpoint rule)."""
    mid = yaw + 0.5 * dyaw_rad
    return (x + distance_m * math.cos(mid), y + distance_m * math.sin(mid),
            wrap_angle(yaw + dyaw_rad))


class DeadReckoning:
    """Encoder-only odometry with nominal geometry and no slip model.

    Parameters
    ----------
    geometry : OdometryGeometry
        Nominal radius, track width, encoder resolution and wheel grouping.
    """

    def __init__(self, geometry: OdometryGeometry) -> None:
        self.geometry = geometry
        self._t: float | None = None
        self._angles = (0.0, 0.0)
        self._pose = (0.0, 0.0, 0.0)

    def reset(self, x_m: float, y_m: float, yaw_rad: float, frame: SensorFrame) -> PoseEstimate:
        self._t = float(frame.t_s)
        self._angles = side_angles_rad(frame, self.geometry)
        self._pose = (float(x_m), float(y_m), wrap_angle(float(yaw_rad)))
        return PoseEstimate(*self._pose)

    def update(self, frame: SensorFrame) -> PoseEstimate:
        dt = check_frame_time(self._t, frame)
        left, right = side_angles_rad(frame, self.geometry)
        r, w = self.geometry.wheel_radius_m, self.geometry.track_width_m
        d_left, d_right = r * (left - self._angles[0]), r * (right - self._angles[1])
        distance, dyaw = 0.5 * (d_left + d_right), (d_right - d_left) / w
        self._pose = integrate_arc(*self._pose, distance, dyaw)
        self._angles, self._t = (left, right), float(frame.t_s)
        return PoseEstimate(*self._pose, speed_mps=distance / dt, yaw_rate_rps=dyaw / dt)
