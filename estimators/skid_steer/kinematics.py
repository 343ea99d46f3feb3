"""Kinematics of a skid-steer tracked vehicle with track slip and body slip angle (Yamauchi §2.1).

Symbols (Yamauchi Fig. 1, REP 103 body frame: x forward, y left):

========  =====================================================================  =======
symbol    meaning                                                                unit
========  =====================================================================  =======
v_l, v_r  input track speeds, sprocket radius × sprocket angular speed (encoders)  m/s
v'_l,v'_r ground speeds of the track contact lines                               m/s
α_l, α_r  slip ratios α = 1 - v'/v (Eq. 3-4); > 0 means the track moves slower   --
          over ground than it turns, < 0 that it is dragged faster (skid)
β         slip angle, from body x to the velocity of the reference point         rad
V_x, V_y  ground velocity of the reference point (midway between the tracks)     m/s
ω         yaw rate                                                                rad/s
2d        tread, distance between the track centre lines (``tread_m``)           m
========  =====================================================================  =======

All functions are vectorised: array arguments broadcast against each other.

Departure from the paper: Eq. 6 is printed as ``ẏ = V_x sin θ - V_y cos θ``; the rotation of the
body velocity into the world frame is ``ẏ = V_x sin θ + V_y cos θ`` (otherwise a positive
slip angle would turn the velocity the wrong way and Eq. 5-6 would not be a rotation), and that is
what :func:`world_velocity` implements.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike

from slipenv.contracts import body_slip_angles


def check_tread(tread_m: float) -> float:
    """Return ``tread_m`` as float, raising ``ValueError`` unless it is finite and > 0 [m]."""
    tread = float(tread_m)
    if not (math.isfinite(tread) and tread > 0.0):
        raise ValueError(f"tread_m must be finite and > 0, got {tread_m!r}")
    return tread


def body_velocity(
    v_l: ArrayLike,
    v_r: ArrayLike,
    alpha_l: ArrayLike,
    alpha_r: ArrayLike,
    beta: ArrayLike,
    tread_m: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body velocity from track speeds, slip ratios and slip angle (Yamauchi Eq. 1, 2, 7).

    Parameters
    ----------
    v_l, v_r : array_like
        Input (encoder) track speeds [m/s].
    alpha_l, alpha_r : array_like
        Slip ratios of the left and right track [-] (Eq. 3-4).
    beta : array_like
        Slip angle [rad], |β| < π/2.
    tread_m : float
        Tread 2d [m].

    Returns
    -------
    v_x, v_y : np.ndarray
        Longitudinal and lateral ground velocity [m/s]: ``V_x = (v_r(1-α_r) + v_l(1-α_l))/2``
        (Eq. 1), ``V_y = V_x tan β`` (Eq. 2).
    omega : np.ndarray
        Yaw rate ``(v_r(1-α_r) - v_l(1-α_l))/(2d)`` [rad/s] (Eq. 7).
    """
    tread = check_tread(tread_m)
    ground_l = np.asarray(v_l, dtype=float) * (1.0 - np.asarray(alpha_l, dtype=float))
    ground_r = np.asarray(v_r, dtype=float) * (1.0 - np.asarray(alpha_r, dtype=float))
    v_x = 0.5 * (ground_r + ground_l)
    return v_x, v_x * np.tan(np.asarray(beta, dtype=float)), (ground_r - ground_l) / tread


def world_velocity(
    v_x: ArrayLike, v_y: ArrayLike, yaw: ArrayLike
) -> tuple[np.ndarray, np.ndarray]:
    """Rotate the body velocity into the world frame (Yamauchi Eq. 5-6, sign of Eq. 6 corrected).

    Parameters
    ----------
    v_x, v_y : array_like
        Body-frame ground velocity [m/s].
    yaw : array_like
        Heading θ, counter-clockwise from world x [rad].

    Returns
    -------
    x_dot, y_dot : np.ndarray
        World-frame velocity [m/s]; equal to ``(V_x / cos β)·(cos(θ+β), sin(θ+β))``.
    """
    v_x, v_y, yaw = (np.asarray(a, dtype=float) for a in (v_x, v_y, yaw))
    c, s = np.cos(yaw), np.sin(yaw)
    return v_x * c - v_y * s, v_x * s + v_y * c


def track_ground_speeds(
    v_x: ArrayLike, omega: ArrayLike, tread_m: float
) -> tuple[np.ndarray, np.ndarray]:
    """Ground speeds of the left and right track lines, ``V_x ∓ d ω`` [m/s] (Eq. 1 and 7 solved)."""
    half = 0.5 * check_tread(tread_m)
    v_x, omega = np.asarray(v_x, dtype=float), np.asarray(omega, dtype=float)
    return v_x - half * omega, v_x + half * omega


def slips_from_body_velocity(
    v_l: ArrayLike,
    v_r: ArrayLike,
    v_x: ArrayLike,
    v_y: ArrayLike,
    omega: ArrayLike,
    tread_m: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Slip ratios and slip angle from track speeds and body velocity (inverse of Eq. 1-7).

    Parameters
    ----------
    v_l, v_r : array_like
        Input (encoder) track speeds [m/s].
    v_x, v_y : array_like
        Body-frame ground velocity of the reference point [m/s].
    omega : array_like
        Yaw rate [rad/s].
    tread_m : float
        Tread 2d [m].

    Returns
    -------
    alpha_l, alpha_r : np.ndarray
        ``α = 1 - v'/v`` with ``v' = V_x ∓ d ω`` (Eq. 3-4). NaN where the input speed is 0
        (the slip ratio of a track that does not turn is undefined).
    beta : np.ndarray
        ``β = atan(V_y / V_x)`` in [-π/2, π/2] (Eq. 2 inverted); ±π/2 when V_x = 0 and V_y ≠ 0,
        0 when the vehicle does not translate.
    """
    ground_l, ground_r = track_ground_speeds(v_x, omega, tread_m)
    v_l, v_r = np.asarray(v_l, dtype=float), np.asarray(v_r, dtype=float)
    with np.errstate(divide="ignore", invalid="ignore"):
        alpha_l = np.where(v_l != 0.0, 1.0 - ground_l / np.where(v_l != 0.0, v_l, 1.0), np.nan)
        alpha_r = np.where(v_r != 0.0, 1.0 - ground_r / np.where(v_r != 0.0, v_r, 1.0), np.nan)
    return alpha_l, alpha_r, body_slip_angles(v_x, v_y)
