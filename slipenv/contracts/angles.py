"""Angle wrapping to (-π, π] and the body slip angle, for scalars (hot paths) and arrays.

One convention for the whole package: that of ``atan2``, the paths' headings and the
controllers' errors.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

TWO_PI = 2.0 * math.pi


def wrap_angle(angle_rad: float) -> float:
    """Wrap one angle to (-π, π] [rad] (plain float: cheap in per-step code)."""
    return math.pi - (math.pi - angle_rad) % TWO_PI


def wrap_angles(angle_rad: ArrayLike) -> np.ndarray:
    """Wrap angles element-wise to (-π, π] [rad]."""
    return np.pi - np.mod(np.pi - np.asarray(angle_rad, dtype=float), TWO_PI)


def _check_min_speed(min_speed_mps: float) -> float:
    value = float(min_speed_mps)
    if not (math.isfinite(value) and value >= 0.0):
        raise ValueError(f"min_speed_mps must be finite and >= 0, got {min_speed_mps!r}")
    return value


def body_slip_angle(v_x: float, v_y: float, min_speed_mps: float = 0.0) -> float:
    """Body slip angle ``β = atan(V_y / V_x)`` [rad], in [-π/2, π/2] (Yamauchi Eq. 2 inverted).

    The angle from the body x axis to the velocity of the reference point, with the velocity
    folded to the forward half plane, so that ``V_y = V_x tan β`` holds when reversing too
    (straight reversing has β = 0, not π). ±π/2 when V_x = 0 and V_y ≠ 0.

    Parameters
    ----------
    v_x, v_y : float
        Body-frame ground velocity (x forward, y left) [m/s].
    min_speed_mps : float
        At or below this speed |v| the angle is undefined and 0 is returned [m/s], >= 0.

    Returns
    -------
    float
        β [rad], > 0 when the vehicle moves to its left of where it points (forward driving).
    """
    if math.hypot(v_x, v_y) <= _check_min_speed(min_speed_mps):
        return 0.0
    return math.atan2(-v_y if v_x < 0.0 else v_y, abs(v_x))


def body_slip_angles(v_x: ArrayLike, v_y: ArrayLike, min_speed_mps: float = 0.0) -> np.ndarray:
    """Element-wise :func:`body_slip_angle` [rad]; ``v_x`` and ``v_y`` broadcast [m/s]."""
    min_speed = _check_min_speed(min_speed_mps)
    vx, vy = np.broadcast_arrays(np.asarray(v_x, dtype=float), np.asarray(v_y, dtype=float))
    beta = np.arctan2(np.where(vx < 0.0, -vy, vy), np.abs(vx))
    return np.where(np.hypot(vx, vy) > min_speed, beta, 0.0)
