"""Planar-slope geometry shared by the replay model: tilted frame, in-plane heading, attitude.

A log's ``terrain.slope_deg`` (α) and ``slope_downhill_azimuth_deg`` (a) declare a plane through
the world origin (``log-format.md``). The plane is the world x-y plane turned by α about the
horizontal axis k = (-sin a, cos a, 0), the rotation ``slipenv.terrain`` applies to its PyBullet
plane, so its upward normal is (sin α cos a, sin α sin a, cos α). The replay integrates the
vehicle in that plane's own frame (u, v, θ): θ is the heading of the body x axis measured in
the plane, and a body displacement (du, dv) moves the reference point by R_tilt (du, dv, 0) in
the world. Ground truth gives the Z-Y-X yaw ψ of the body, i.e. the azimuth of the horizontal
projection of body x; on level ground θ = ψ.
"""

from __future__ import annotations

import math

import numpy as np


def tilt_matrix(slope_deg: float, downhill_azimuth_deg: float | None) -> np.ndarray:
    """Rotation R_tilt (3, 3) taking the world x-y plane onto the declared slope (Rodrigues)."""
    alpha = math.radians(slope_deg or 0.0)
    if alpha == 0.0:
        return np.eye(3)
    az = math.radians(downhill_azimuth_deg or 0.0)
    k = np.array([-math.sin(az), math.cos(az), 0.0])
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + math.sin(alpha) * kx + (1.0 - math.cos(alpha)) * kx @ kx


def yaw_from_heading(theta: np.ndarray, tilt: np.ndarray) -> np.ndarray:
    """Z-Y-X yaw ψ [rad] of a body lying in the plane with in-plane heading θ [rad].

    ``tilt`` is (3, 3) or a stack (..., 3, 3) whose leading axes broadcast against ``theta``.
    """
    c, s = np.cos(theta), np.sin(theta)
    return np.arctan2(tilt[..., 1, 0] * c + tilt[..., 1, 1] * s,
                      tilt[..., 0, 0] * c + tilt[..., 0, 1] * s)


def heading_from_yaw(yaw: np.ndarray, tilt: np.ndarray) -> np.ndarray:
    """In-plane heading θ [rad] of a body in the plane whose Z-Y-X yaw is ψ (inverse of above).

    Solves M (cos θ, sin θ) ∝ (cos ψ, sin ψ) with M the horizontal 2 × 2 block of R_tilt
    (the adjugate suffices: only the direction matters, and det M = cos α > 0).
    """
    a, b = tilt[..., 0, 0], tilt[..., 0, 1]
    c_, d = tilt[..., 1, 0], tilt[..., 1, 1]
    c, s = np.cos(yaw), np.sin(yaw)
    return np.arctan2(-c_ * c + a * s, d * c - b * s)


def roll_from_heading(theta: np.ndarray, tilt: np.ndarray) -> np.ndarray:
    """Roll [rad] (> 0 lifts the left side) of a body in the plane with heading θ.

    Z-Y-X angles of R = R_tilt Rz(θ): roll = atan2(R[2, 1], R[2, 2]).
    """
    c, s = np.cos(theta), np.sin(theta)
    r21 = -tilt[..., 2, 0] * s + tilt[..., 2, 1] * c
    return np.arctan2(r21, np.broadcast_to(tilt[..., 2, 2], np.shape(r21)))


def pitch_from_heading(theta: np.ndarray, tilt: np.ndarray) -> np.ndarray:
    """Pitch [rad] (> 0 nose down) of a body in the plane with heading θ: -asin(R[2, 0])."""
    r20 = tilt[..., 2, 0] * np.cos(theta) + tilt[..., 2, 1] * np.sin(theta)
    return -np.arcsin(np.clip(r20, -1.0, 1.0))


def wrap(angle: np.ndarray) -> np.ndarray:
    """Wrap angles to [-π, π)."""
    return (np.asarray(angle) + np.pi) % (2.0 * np.pi) - np.pi
