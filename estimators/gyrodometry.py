"""Gyrodometry: distance from the track encoders, heading from the integrated yaw gyro.

Borenstein & Feng (1996), the baseline Yamauchi §2.4 compares against: the translation is the mean
of the two track displacements (no slip), the heading change is the integrated gyro rate, and the
position advances along the midpoint heading (the exact arc for a constant-curvature step).

:class:`Gyrodometry` is also the template of the skid-steer slip odometries
(:class:`~slipenv.estimators.skid_steer.endo.EndoOdometry`,
:class:`~slipenv.estimators.skid_steer.yamauchi.SlipCompensatedOdometry`): they override one
hook, :meth:`Gyrodometry._translation`, that turns the step's track displacements and gyro
heading change into a body-x displacement and a slip angle.
"""

from __future__ import annotations

import math

import numpy as np

from slipenv.contracts import PoseEstimate, SensorFrame, wrap_angle

from .base import OdometryGeometry, check_frame_time
from .dead_reckoning import integrate_arc, side_angles_rad


def finite_reading(value: float, name: str) -> float:
    """Return ``value`` as float, raising ``ValueError`` naming ``name`` if it is not finite."""
    value = float(value)
    if not math.isfinite(value):
        raise ValueError(f"{name} must be finite, got {value!r}")
    return value


def track_angles_rad(frame: SensorFrame, geometry: OdometryGeometry) -> tuple[float, float]:
    """Mean cumulative sprocket angle of the left and right track [rad], checked against geometry.

    Raises
    ------
    ValueError
        If ``geometry.left``/``geometry.right`` index past ``frame.enc_counts`` or a count used is
        not finite.
    """
    counts = frame.enc_counts
    if not isinstance(counts, np.ndarray):
        counts = np.asarray(counts, dtype=float)
    used = geometry.left + geometry.right
    if counts.ndim != 1 or max(used) >= counts.size or min(used) < -counts.size:
        raise ValueError(
            f"geometry.left={geometry.left}/geometry.right={geometry.right} do not index "
            f"frame.enc_counts of shape {counts.shape}"
        )
    c = counts.tolist()
    if not all(math.isfinite(c[i]) for i in used):
        raise ValueError(f"frame.enc_counts must be finite, got {counts!r}")
    return side_angles_rad(frame, geometry)


class Gyrodometry:
    """Encoder translation with gyro heading (Borenstein 1996; Yamauchi §2.4 baseline).

    Per step of length dt between frames k-1 and k:

    - track displacements ``Δs_l, Δs_r = R (φ_k - φ_{k-1})`` from the encoders [m];
    - heading change ``Δθ = (g_{k-1} + g_k) dt / 2`` from the gyro readings g (trapezoid);
    - body-x displacement and slip angle from :meth:`_translation` (here ``(Δs_l + Δs_r)/2``, 0);
    - position advanced by ``Δx / cos β̄`` along ``θ + Δθ/2 + β̄`` with β̄ the mean slip angle of
      the step (Yamauchi Eq. 5-6 integrated with the midpoint rule).

    Parameters
    ----------
    geometry : OdometryGeometry
        Sprocket radius ``wheel_radius_m``, tread ``track_width_m``, encoder resolution and the
        encoder indices of the left and right track.

    Raises
    ------
    ValueError
        On a wrong ``geometry`` type, on frames whose encoders do not match it, on out-of-order or
        NaN frame times and on a NaN gyro reading.
    """

    def __init__(self, geometry: OdometryGeometry) -> None:
        if not isinstance(geometry, OdometryGeometry):
            raise ValueError(f"geometry must be an OdometryGeometry, got {type(geometry).__name__}")
        self.geometry = geometry
        self._t: float | None = None
        self._angles = (0.0, 0.0)
        self._pose = (0.0, 0.0, 0.0)
        self._gyro = math.nan
        self._beta = math.nan

    def reset(self, x_m: float, y_m: float, yaw_rad: float, frame: SensorFrame) -> PoseEstimate:
        """Start from a known pose; ``frame`` gives the initial encoder counts (and gyro)."""
        named = ((x_m, "x_m"), (y_m, "y_m"), (yaw_rad, "yaw_rad"))
        pose = tuple(finite_reading(value, name) for value, name in named)
        check_frame_time(None, frame)
        self._angles = track_angles_rad(frame, self.geometry)
        self._t = float(frame.t_s)
        self._pose = (pose[0], pose[1], wrap_angle(pose[2]))
        self._gyro = float(frame.gyro_z_rad_s)  # NaN allowed: the first step uses its own reading
        self._beta = math.nan
        self._reset_hook(frame)
        return PoseEstimate(*self._pose)

    def update(self, frame: SensorFrame) -> PoseEstimate:
        """Advance to ``frame`` (time strictly increasing) and return the new estimate."""
        if self._t is None:
            raise RuntimeError(f"{type(self).__name__}.update called before reset")
        dt = check_frame_time(self._t, frame)
        gyro = finite_reading(frame.gyro_z_rad_s, "frame.gyro_z_rad_s")
        left, right = track_angles_rad(frame, self.geometry)
        radius = self.geometry.wheel_radius_m
        d_left, d_right = radius * (left - self._angles[0]), radius * (right - self._angles[1])
        previous_gyro = gyro if math.isnan(self._gyro) else self._gyro
        dyaw = 0.5 * (previous_gyro + gyro) * dt
        forward_m, beta, extras = self._translation(d_left, d_right, dyaw, dt, frame)
        beta_mid = beta if math.isnan(self._beta) else 0.5 * (self._beta + beta)
        x, y, yaw = self._pose
        x, y, _ = integrate_arc(x, y, yaw + beta_mid, forward_m / math.cos(beta_mid), dyaw)
        self._pose = (x, y, wrap_angle(yaw + dyaw))
        self._angles, self._t, self._gyro, self._beta = (left, right), float(frame.t_s), gyro, beta
        return PoseEstimate(
            *self._pose,
            speed_mps=forward_m / dt,
            yaw_rate_rps=dyaw / dt,
            slip_angle_rad=beta,
            extras=extras,
        )

    def _reset_hook(self, frame: SensorFrame) -> None:
        """Reset subclass state at :meth:`reset` (nothing here)."""

    def _translation(
        self, d_left: float, d_right: float, dyaw: float, dt: float, frame: SensorFrame
    ) -> tuple[float, float, dict]:
        """Body-x displacement [m], slip angle [rad] and extras of one step (no slip here).

        Parameters
        ----------
        d_left, d_right : float
            Input displacements of the tracks, sprocket radius × sprocket angle change [m].
        dyaw : float
            Heading change from the gyro [rad].
        dt : float
            Step length [s], > 0.
        frame : SensorFrame
            The new frame (for attitude readings).
        """
        return 0.5 * (d_left + d_right), 0.0, {}
