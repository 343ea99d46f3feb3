"""Measuring the no-slip filter's effective wheel radii as the paper's operators did.

Lindgren §5 gave the no-slip scheme "a carefully measured effective wheel radius", and §3.2
measured the left and right wheels separately (0.283 / 0.287 m on soil) from the distance each
wheel travelled over its rotation. Here each driven wheel's R_eff = d / Δθ is measured on a
straight drive under the vehicle's own driving torque: d the distance that wheel's ground
contact covered, Δθ its rotation. On soil this R_eff holds the true rolling radius and the slip
at the calibration drive's torque, R_eff = R_w (1 - s) (slip s = 1 - R_eff/R_w, Lindgren Eq. 25),
so the no-slip filter is right exactly where the drive was like the calibration and off
elsewhere (turns, accelerations, load changes): the effect the slip model is meant to capture.
(§3.2 towed the vehicle with the transmission disconnected, which measures R_w at zero torque,
the radius a driven no-slip filter would be most wrong with; the driven drive is the kinder
calibration.)

:func:`effective_radius_m` is the formula on its own; :func:`calibrate` drives a
:data:`~.settings.CALIBRATION_M` straight in a block's world and applies it between two marks
:data:`~.settings.CALIBRATION_SETTLE_M` in from either end (start-up and stop left out).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from slipenv.paths import path_by_name

from .recording import Recording, record
from .settings import CALIBRATION_M, CALIBRATION_SETTLE_M, SPEED_MPS, Setting


def effective_radius_m(distance_m: float, wheel_angle_rad: ArrayLike) -> float:
    """R_eff = d / Δθ [m]: the distance driven over the wheels' mean rotation angle.

    Parameters
    ----------
    distance_m : float
        True distance covered between the two marks [m], > 0.
    wheel_angle_rad : array_like
        Rotation of each driven wheel between the marks [rad]; their mean is used (one
        radius for both sides, as the no-slip filter holds one), > 0.

    Raises
    ------
    ValueError
        If the distance or the mean angle is not finite and positive.
    """
    angle = float(np.mean(np.asarray(wheel_angle_rad, dtype=float)))
    if not (np.isfinite(distance_m) and distance_m > 0.0):
        raise ValueError(f"distance_m must be finite and > 0, got {distance_m!r}")
    if not (np.isfinite(angle) and angle > 0.0):
        raise ValueError(f"wheel_angle_rad must have a finite positive mean, got {angle!r}")
    return float(distance_m) / angle


def radius_from_recording(rec: Recording, settle_m: float = CALIBRATION_SETTLE_M) -> dict:
    """:func:`effective_radius_m`, for both sides together and each side, between the marks
    ``settle_m`` after the start and before the end of a recorded straight drive.

    Returns
    -------
    dict
        ``radius_m`` [m] (one radius: the reference point's distance over the driven wheels'
        mean rotation), ``radius_per_side_m`` [m] (left, right: each side's contact distance
        over its rotation, :func:`effective_radius_m` per side), ``distance_m`` [m] (true,
        reference point, between the marks), ``distance_per_side_m`` [m], ``wheel_angle_rad``
        (per driven wheel), ``slip_vs_true_radius`` (1 - R_eff / mean true rolling radius),
        ``slip_per_side`` (1 - R_eff / R_w, left, right), ``mean_torque_nm`` (measured, per
        driven wheel, between the marks) and ``k_s_secant_nm``, their mean over that slip: the
        torque/slip gradient a linear law through the origin would need at this torque
        (Lindgren Eq. 24 read as a secant).
    """
    s = rec.s_true_m
    inside = np.flatnonzero((s >= settle_m) & (s <= s.max() - settle_m))
    if inside.size < 2:
        raise ValueError(f"the drive ({s.max():.2f} m) is too short for marks {settle_m} m in")
    k0, k1 = int(inside[0]), int(inside[-1])
    wheels = list(rec.geometry.left + rec.geometry.right)
    counts = (np.asarray(rec.frames[k1].enc_counts, dtype=float)
              - np.asarray(rec.frames[k0].enc_counts, dtype=float))[wheels]
    angle = counts / rec.geometry.counts_per_rad
    distance = float(np.hypot(*(rec.truth[k1, :2] - rec.truth[k0, :2])))
    radius = effective_radius_m(distance, angle)
    g = rec.geometry
    x, y, yaw = rec.truth[k0:k1 + 1].T
    side_radius, side_distance = [], []
    n_left = len(g.left)
    for side, sel in ((list(g.left), slice(0, n_left)), (list(g.right), slice(n_left, None))):
        # each side's contact point, at its lateral offset from the reference point
        offset = (float(np.mean(g.wheel_xy_m[side, 1])) if g.wheel_xy_m is not None
                  else (0.5 if sel.start == 0 else -0.5) * g.track_width_m)
        px, py = x - offset * np.sin(yaw), y + offset * np.cos(yaw)
        d = float(np.sum(np.hypot(np.diff(px), np.diff(py))))
        side_distance.append(d)
        side_radius.append(effective_radius_m(d, angle[sel]))
    torque = np.array([np.asarray(f.wheel_torque_nm, dtype=float)[wheels]
                       for f in rec.frames[k0:k1 + 1]])
    slip = 1.0 - radius / float(np.mean(rec.oracle.wheel_radius_m))
    mean_torque = np.mean(torque, axis=0)
    return {"radius_m": radius, "radius_per_side_m": side_radius, "distance_m": distance,
            "distance_per_side_m": side_distance, "wheel_angle_rad": angle.tolist(),
            "slip_vs_true_radius": slip,
            "slip_per_side": [1.0 - r / rw for r, rw in zip(side_radius,
                                                             rec.oracle.wheel_radius_m,
                                                             strict=True)],
            "mean_torque_nm": mean_torque.tolist(),
            "k_s_secant_nm": float(np.mean(mean_torque)) / slip if slip > 0.0 else None}


def calibrate(setting: Setting, seed: int, progress: bool = False) -> dict:
    """Drive :data:`~.settings.CALIBRATION_M` straight in ``setting``'s world and measure the
    effective radius (:func:`radius_from_recording`; the drive's length is added)."""
    path = path_by_name("straight", length_m=CALIBRATION_M, speed_mps=SPEED_MPS)
    rec = record(path, seed, progress, setting)
    return {**radius_from_recording(rec), "drive_m": CALIBRATION_M}
