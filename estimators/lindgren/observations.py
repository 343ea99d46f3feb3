"""Observation models of Lindgren's navigation EKF, as plain functions with their Jacobians.

Inertial (Lindgren Eq. 14), inclinometer, odometric without slip (Eq. 15-16) and with the
linear torque/slip model (Eq. 37, Jacobian Eq. 38-41) or Okello's curve in its place (Eq. 18-20,
beyond the paper), and beacon bearing (Eq. 17) with its
angle-wrapping residual and nearest-innovation association. Each ``*_hx`` takes the state
``x`` (layout in :mod:`slipenv.estimators.lindgren.models`) and returns the predicted measurement;
each ``*_H`` returns ``∂h/∂x`` with one column per state.

Departures from the paper, each for a stated reason:

* Odometer counts integrate the wheel speed over the interval, while the state is at its end;
  Eq. 15 and 37 are evaluated at the interval's mean speeds ``v - τ v̇ / 2`` and
  ``Ω - τ Ω̇ / 2`` (exact under the constant-acceleration process model). Without this the
  counts are biased by τ² v̇ / (2 Γ R_w), about 0.6 counts at 20 Hz and 0.5 m/s² — more than
  the odometer's standard deviation of 0.5 counts.
* Eq. 37 is written for forward driving. With ``σ = sign(v ± W Ω / 2)`` the slip is taken as
  ``σ T / k_s`` so that driving torque makes the wheel overspin in reverse as well; for
  forward travel σ = 1 and the formula is the paper's.
* The paper writes Γ for radians per count; here the geometry's ``counts_per_rad`` = 1/Γ.

Like :mod:`.models`, these functions are the code the filter runs, compiled from this text by
numba (``@njit(cache=True)``). The oracle's fixed soil is passed to the slip model as the array
``[R_wl, R_wr, k_sl, k_sr]`` (:meth:`.models.OracleSoil.as_array`) because compiled code takes
arrays, not dataclasses. They are written per wheel in plain loops rather than as numpy array
expressions: numba compiles loops several times faster. Those the filter calls at every frame
have an ``_into`` twin writing into arrays the caller owns (the filter's workspace), or a
per-wheel or per-beacon scalar form; the allocating function calls it, so each model is
written once.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from slipenv.contracts import angles
from slipenv.contracts.compiled_cache import refresh_stale_cache

from .models import (
    G_MPS2,
    IA1,
    IA2,
    IBL,
    IKL,
    IKR,
    IOM,
    IOMD,
    IRL,
    IRR,
    ITH,
    IV,
    IVD,
    IX,
    IY,
    N_OKELLO,
    N_SLIP,
    soil_size,
    wrap,
)

# the observation models call the models' compiled functions
refresh_stale_cache(__file__, "models.py", angles.__file__)

NO_SOIL = np.zeros(0)  # the ``soil`` argument of the slip models whose soil is in x


@njit(cache=True)
def _zero(H: np.ndarray) -> None:
    for a in range(H.shape[0]):
        for k in range(H.shape[1]):
            H[a, k] = 0.0


# ---------------------------------------------------------------------------------------------
# Inertial observation (Eq. 14) and inclinometer
# ---------------------------------------------------------------------------------------------
@njit(cache=True)
def ins_hx(x: np.ndarray) -> np.ndarray:
    """Predicted inertial readings ``[a1/g, a2/g, g1]`` (Lindgren Eq. 14).

    Returns
    -------
    np.ndarray, shape (3,)
        Forward and lateral specific force [g] and yaw rate [rad/s].
    """
    h = np.empty(3)
    ins_hx_into(x, h)
    return h


@njit(cache=True)
def ins_hx_into(x: np.ndarray, h: np.ndarray) -> None:
    """:func:`ins_hx` written into ``h`` (3,)."""
    h[0] = x[IVD] / G_MPS2 + x[IA1]
    h[1] = x[IV] * x[IOM] / G_MPS2 - x[IA2]
    h[2] = x[IOM]


@njit(cache=True)
def ins_H(x: np.ndarray) -> np.ndarray:
    """Jacobian of :func:`ins_hx`, shape (3, n)."""
    H = np.empty((3, x.shape[0]))
    ins_H_into(x, H)
    return H


@njit(cache=True)
def ins_H_into(x: np.ndarray, H: np.ndarray) -> None:
    """:func:`ins_H` written into ``H`` (3, n)."""
    _zero(H)
    H[0, IVD] = 1.0 / G_MPS2
    H[0, IA1] = 1.0
    H[1, IV] = x[IOM] / G_MPS2
    H[1, IOM] = x[IV] / G_MPS2
    H[1, IA2] = -1.0
    H[2, IOM] = 1.0


@njit(cache=True)
def tilt_hx(x: np.ndarray) -> np.ndarray:
    """Predicted inclinometer reading ``[α1, α2]`` [rad] in Lindgren's signs, shape (2,).

    ``SensorFrame`` reports ``pitch_rad = -α1`` and ``roll_rad = -α2`` (REP 103).
    """
    h = np.empty(2)
    tilt_hx_into(x, h)
    return h


@njit(cache=True)
def tilt_hx_into(x: np.ndarray, h: np.ndarray) -> None:
    """:func:`tilt_hx` written into ``h`` (2,)."""
    h[0], h[1] = x[IA1], x[IA2]


@njit(cache=True)
def tilt_H(x: np.ndarray) -> np.ndarray:
    """Jacobian of :func:`tilt_hx`, shape (2, n)."""
    H = np.empty((2, x.shape[0]))
    tilt_H_into(x, H)
    return H


@njit(cache=True)
def tilt_H_into(x: np.ndarray, H: np.ndarray) -> None:
    """:func:`tilt_H` written into ``H`` (2, n)."""
    _zero(H)
    H[0, IA1] = H[1, IA2] = 1.0


# ---------------------------------------------------------------------------------------------
# Odometric observations (Eq. 15-16 and the slip-aware Eq. 37-41)
# ---------------------------------------------------------------------------------------------
SIDES = (-1.0, 1.0)  # the ∓ of Eq. 16: left wheel -W/2 Ω, right wheel +W/2 Ω


@njit(cache=True)
def wheel_speeds(x: np.ndarray, tau: float, track_width_m: float) -> np.ndarray:
    """Mean ground speed of the (left, right) wheel over the interval ending at x [m/s]."""
    v_w = np.empty(2)
    for i in range(2):
        v_w[i] = wheel_speed(x, tau, track_width_m, i)
    return v_w


@njit(cache=True)
def wheel_speed(x: np.ndarray, tau: float, track_width_m: float, i: int) -> float:
    """:func:`wheel_speeds` of wheel i (0 left, 1 right): ``v ∓ W Ω / 2`` (Lindgren Eq. 16)
    at the interval's mean v and Ω [m/s]."""
    v_mid = x[IV] - 0.5 * tau * x[IVD]
    om_mid = x[IOM] - 0.5 * tau * x[IOMD]
    return v_mid + SIDES[i] * (0.5 * track_width_m) * om_mid


@njit(cache=True)
def travel_sign(v_w: float) -> float:
    """σ = sign of a wheel's ground speed, +1 at rest (the slip model's direction)."""
    return 1.0 if v_w >= 0.0 else -1.0


@njit(cache=True)
def odo_hx(
    x: np.ndarray, tau: float, radius_m: float, track_width_m: float, counts_per_rad: float
) -> np.ndarray:
    """Predicted odometer counts over τ without slip (Lindgren Eq. 15-16).

    ``z = τ / (Γ R_w) (v ∓ W Ω / 2)`` with Γ = 1 / counts_per_rad, at the interval's mean speed.

    Parameters
    ----------
    x : np.ndarray, shape (n,)
        State at the end of the interval.
    tau : float
        Interval [s].
    radius_m : float
        Wheel radius R_w [m] (the nominal one).
    track_width_m : float
        Lateral wheel separation W [m].
    counts_per_rad : float
        Encoder resolution 1/Γ [counts/rad].

    Returns
    -------
    np.ndarray, shape (2,)
        Counts of the (left, right) wheel over the interval.
    """
    z = np.empty(2)
    odo_hx_into(x, tau, radius_m, track_width_m, counts_per_rad, z)
    return z


@njit(cache=True)
def odo_hx_into(x: np.ndarray, tau: float, radius_m: float, track_width_m: float,
                counts_per_rad: float, z: np.ndarray) -> None:
    """:func:`odo_hx` written into ``z`` (2,)."""
    for i in range(2):
        z[i] = tau * counts_per_rad / radius_m * wheel_speed(x, tau, track_width_m, i)


@njit(cache=True)
def odo_H(
    x: np.ndarray, tau: float, radius_m: float, track_width_m: float, counts_per_rad: float
) -> np.ndarray:
    """Jacobian of :func:`odo_hx`, shape (2, n)."""
    H = np.empty((2, x.shape[0]))
    odo_H_into(x, tau, radius_m, track_width_m, counts_per_rad, H)
    return H


@njit(cache=True)
def odo_H_into(x: np.ndarray, tau: float, radius_m: float, track_width_m: float,
               counts_per_rad: float, H: np.ndarray) -> None:
    """:func:`odo_H` written into ``H`` (2, n)."""
    _zero(H)
    g = tau * counts_per_rad / radius_m
    for i in range(2):
        H[i, IV] = g
        H[i, IOM] = g * SIDES[i] * 0.5 * track_width_m
        H[i, IVD] = -0.5 * tau * H[i, IV]
        H[i, IOMD] = -0.5 * tau * H[i, IOM]


@njit(cache=True)
def slip_params(x: np.ndarray, soil: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(R_w, k_s) per wheel, each shape (2,): the states of a slip-model ``x`` (13 or 15
    states, with or without k_β), else the oracle's fixed ``soil = [R_wl, R_wr, k_sl, k_sr]``."""
    if soil_size(x.shape[0]) >= N_SLIP:
        return x[IRL:IRR + 1], x[IKL:IKR + 1]
    return soil[0:2], soil[2:4]


# ---------------------------------------------------------------------------------------------
# Okello's curve (Eq. 18-20) and its inverse, for the curved slip model
# ---------------------------------------------------------------------------------------------
# Taylor coefficients of φ(u) = g⁻¹(u) / (2u) about u = 0 (series reversion of g, below)
_PHI_SERIES = (1.0, 2.0 / 3.0, 5.0 / 9.0, 68.0 / 135.0, 193.0 / 405.0, 262.0 / 567.0)


@njit(cache=True)
def okello_g(x: float) -> float:
    """Okello's normalised curve g(x) = 1 - (1 - e^{-x}) / x at x = s / B (Lindgren Eq. 18,
    20: T = T_max g(s / B)), continued analytically to x < 0 (g → -∞), so that the filter's
    model stays smooth where an estimate strays there. g(0) = 0, g'(0) = 1/2."""
    if abs(x) < 0.1:  # Σ (-1)^(k+1) x^k / (k+1)!, below 1e-13 relative past the last term
        acc, term = 0.0, 1.0
        for k in range(1, 10):
            term *= -x / (k + 1) if k > 1 else x / 2.0
            acc += term
        return acc
    return 1.0 + math.expm1(-x) / x


@njit(cache=True)
def okello_dg(x: float) -> float:
    """g'(x) = (1 - (1 + x) e^{-x}) / x² of :func:`okello_g`, > 0 everywhere."""
    if abs(x) < 0.1:  # Σ (-1)^(k+1) k x^(k-1) / (k+1)!
        acc, term = 0.0, 1.0  # term = (-1)^(k+1) x^(k-1) / (k+1)!
        for k in range(1, 10):
            term = 0.5 if k == 1 else -term * x / (k + 1)
            acc += k * term
        return acc
    return (-math.expm1(-x) - x * math.exp(-x)) / (x * x)


@njit(cache=True)
def okello_inverse(u: float) -> float:
    """x with ``g(x) = u`` (:func:`okello_g`) for u < 1, by Newton's method.

    g is increasing and concave on the whole line, so from any start the first Newton step
    lands at or left of the root and the iterates then rise to it monotonically. Below
    u = 1/2 the start is 2u, already left of the root (g(x) <= x/2); above, 1/(1 - u), just
    right of it (g(x) = 1 - (1 - e^{-x}) / x)."""
    if abs(u) < 1e-3:
        acc = 0.0
        for k in range(len(_PHI_SERIES) - 1, -1, -1):
            acc = acc * u + _PHI_SERIES[k]
        return 2.0 * u * acc
    x = 2.0 * u if u < 0.5 else 1.0 / (1.0 - u)
    for _ in range(60):
        dx = (okello_g(x) - u) / okello_dg(x)
        x -= dx
        if abs(dx) <= 1e-14 * (1.0 + abs(x)):
            break
    return x


@njit(cache=True)
def okello_slip_factor(u: float) -> tuple[float, float]:
    """φ(u) = g⁻¹(u) / (2u) and φ'(u): the factor by which Okello's curve stretches the
    linear law's slip at torque ratio u = T / T_max (Lindgren Eq. 20, 24).

    With T = T_max g(s / B) and k_s = T_max / (2B) (Eq. 24), the slip at torque T is
    ``s = (T / k_s) φ(T / T_max)``; φ(0) = 1 is the linear law, φ → ∞ as T → T_max.
    Defined (smooth) for all u < 1, including u < 0 (a curve bending the other way)."""
    if abs(u) < 1e-3:
        phi, dphi = 0.0, 0.0
        for k in range(len(_PHI_SERIES) - 1, -1, -1):
            phi = phi * u + _PHI_SERIES[k]
            if k > 0:
                dphi = dphi * u + k * _PHI_SERIES[k]
        return phi, dphi
    x = okello_inverse(u)
    dx = 1.0 / okello_dg(x)  # dx/du
    return x / (2.0 * u), (dx * u - x) / (2.0 * u * u)


@njit(cache=True)
def okello_slip_factor_inverse(r: float) -> float:
    """u in [0, 1) with φ(u) = r >= 1 (:func:`okello_slip_factor`), by bisection, from below:
    φ rises from 1 at u = 0 to ∞ as u → 1 (g⁻¹ is convex through 0, so g⁻¹(u) / u rises)."""
    lo, hi = 0.0, 1.0
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if okello_slip_factor(mid)[0] < r:
            lo = mid
        else:
            hi = mid
    return lo


@njit(cache=True)
def slip_model(x: np.ndarray, tau: float, torque: np.ndarray, track_width_m: float,
               soil: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Slip of the (left, right) wheel from its torque, and its derivatives.

    Linear law (13-state ``x`` or the oracle's ``soil``): ``s = σ T / k_s`` (Lindgren Eq. 24,
    32; σ the wheel's direction of travel). Okello's curve (15-state ``x``, with b = 1/B):
    ``s = s_lin φ(b |s_lin| / 2)`` with ``s_lin = σ T / k_s`` (:func:`okello_slip_factor`;
    b |s_lin| / 2 = |T| / T_max), odd in the torque like Okello's curve, and the linear law
    exactly at b = 0.

    Returns
    -------
    s : np.ndarray, shape (2,)
        Slip ratio per wheel; ``inf`` where the torque reaches the curve's T_max.
    ds_dk : np.ndarray, shape (2,)
        ∂s/∂k_s.
    ds_db : np.ndarray, shape (2,)
        ∂s/∂b (zero for the linear law).
    """
    s = np.empty(2)
    ds_dk = np.empty(2)
    ds_db = np.empty(2)
    for i in range(2):
        s[i], ds_dk[i], ds_db[i] = wheel_slip_model(x, tau, torque, track_width_m, soil, i)
    return s, ds_dk, ds_db


@njit(cache=True)
def wheel_slip_model(x: np.ndarray, tau: float, torque: np.ndarray, track_width_m: float,
                     soil: np.ndarray, i: int) -> tuple[float, float, float]:
    """:func:`slip_model` of wheel i (0 left, 1 right): its slip s, ∂s/∂k_s and ∂s/∂b."""
    _, k_s = slip_params(x, soil)
    okello = soil_size(x.shape[0]) == N_OKELLO
    s_lin = travel_sign(wheel_speed(x, tau, track_width_m, i)) * torque[i] / k_s[i]
    return slip_law(s_lin, k_s[i], x[IBL + i] if okello else 0.0, okello)


@njit(cache=True)
def slip_law(s_lin: float, k_s: float, b: float, okello: bool) -> tuple[float, float, float]:
    """One wheel's slip ``s`` and its derivatives ∂s/∂k_s, ∂s/∂b from its linear-law slip
    ``s_lin = σ T / k_s`` (Lindgren Eq. 24): ``s_lin`` itself, or with Okello's curve
    (inverse shape ``b``) ``s_lin φ(b |s_lin| / 2)`` (:func:`slip_model`); ``inf`` (and zero
    derivatives) where the torque reaches the curve's T_max."""
    if not okello:
        return s_lin, -s_lin / k_s, 0.0
    u = 0.5 * b * abs(s_lin)
    if u >= 1.0:
        return math.inf, 0.0, 0.0
    phi, dphi = okello_slip_factor(u)
    return s_lin * phi, -(s_lin / k_s) * (phi + u * dphi), s_lin * dphi * 0.5 * abs(s_lin)


@njit(cache=True)
def wheel_slip(
    x: np.ndarray, tau: float, torque: np.ndarray, track_width_m: float, soil: np.ndarray,
) -> np.ndarray:
    """Slip of the (left, right) wheel (Lindgren Eq. 24, 32; :func:`slip_model`)."""
    return slip_model(x, tau, torque, track_width_m, soil)[0]


@njit(cache=True)
def odo_slip_hx(
    x: np.ndarray, tau: float, torque: np.ndarray, track_width_m: float, counts_per_rad: float,
    soil: np.ndarray,
) -> np.ndarray:
    """Predicted odometer counts with a torque/slip model (Lindgren Eq. 37).

    ``z = (τ / Γ) (v ∓ W Ω / 2) / (R_w (1 - s))`` per wheel with the slip s of
    :func:`slip_model`; for the linear law ``1 / (1 - s) = k_s / (k_s - σ T)``, the paper's
    Eq. 37 with σ = 1 forward.

    Parameters
    ----------
    x : np.ndarray, shape (13,) or (15,), or (9,) with ``soil``; plus k_β if it has one
        State at the end of the interval.
    tau : float
        Interval [s].
    torque : np.ndarray, shape (2,)
        Mean measured drive torque of the (left, right) wheel over the interval, in the
        torque sensor's unit (any scale: absorbed by k_s).
    track_width_m : float
        W [m].
    counts_per_rad : float
        1/Γ [counts/rad].
    soil : np.ndarray, shape (4,)
        The oracle's fixed ``[R_wl, R_wr, k_sl, k_sr]`` for a 9-state ``x``; ignored (pass
        :data:`NO_SOIL`) when R_w and k_s are states.

    Returns
    -------
    np.ndarray, shape (2,)
        Counts over the interval. Meaningful only while the slip is below 1.
    """
    z = np.empty(2)
    odo_slip_hx_into(x, tau, torque, track_width_m, counts_per_rad, soil, z)
    return z


@njit(cache=True)
def odo_slip_hx_into(x: np.ndarray, tau: float, torque: np.ndarray, track_width_m: float,
                     counts_per_rad: float, soil: np.ndarray, z: np.ndarray) -> None:
    """:func:`odo_slip_hx` written into ``z`` (2,)."""
    r_w, _ = slip_params(x, soil)
    for i in range(2):
        v_w = wheel_speed(x, tau, track_width_m, i)
        s = wheel_slip_model(x, tau, torque, track_width_m, soil, i)[0]
        z[i] = tau * counts_per_rad * v_w / (r_w[i] * (1.0 - s))


@njit(cache=True)
def odo_slip_H(
    x: np.ndarray, tau: float, torque: np.ndarray, track_width_m: float, counts_per_rad: float,
    soil: np.ndarray,
) -> np.ndarray:
    """Jacobian of :func:`odo_slip_hx` (Lindgren Eq. 38-41), shape (2, n).

    Columns v and Ω are Eq. 38-39; v̇ and Ω̇ follow from the mean-speed evaluation
    (-τ/2 times Eq. 38-39); R_w and k_s (only when they are states) are Eq. 40-41, the latter
    through ``∂z/∂s ∂s/∂k_s``, as is the column of Okello's 1/B.
    """
    H = np.empty((2, x.shape[0]))
    odo_slip_H_into(x, tau, torque, track_width_m, counts_per_rad, soil, H)
    return H


@njit(cache=True)
def odo_slip_H_into(x: np.ndarray, tau: float, torque: np.ndarray, track_width_m: float,
                    counts_per_rad: float, soil: np.ndarray, H: np.ndarray) -> None:
    """:func:`odo_slip_H` written into ``H`` (2, n)."""
    r_w, _ = slip_params(x, soil)
    base = soil_size(x.shape[0])
    _zero(H)
    for i in range(2):
        s, ds_dk, ds_db = wheel_slip_model(x, tau, torque, track_width_m, soil, i)
        dz_dvw = tau * counts_per_rad / (r_w[i] * (1.0 - s))  # Eq. 38
        H[i, IV] = dz_dvw
        H[i, IOM] = dz_dvw * SIDES[i] * 0.5 * track_width_m  # Eq. 39
        H[i, IVD] = -0.5 * tau * H[i, IV]
        H[i, IOMD] = -0.5 * tau * H[i, IOM]
        if base >= N_SLIP:
            z = dz_dvw * wheel_speed(x, tau, track_width_m, i)
            dz_ds = z / (1.0 - s)
            H[i, IRL + i] = -z / r_w[i]  # Eq. 40
            H[i, IKL + i] = dz_ds * ds_dk  # Eq. 41
            if base == N_OKELLO:
                H[i, IBL + i] = dz_ds * ds_db


# ---------------------------------------------------------------------------------------------
# Beacon bearing (Eq. 17)
# ---------------------------------------------------------------------------------------------
@njit(cache=True)
def bearing_hx(x: np.ndarray, beacons_xy: np.ndarray) -> np.ndarray:
    """Predicted bearings to beacons, relative to body x (Lindgren Eq. 17).

    Parameters
    ----------
    x : np.ndarray, shape (n,)
    beacons_xy : np.ndarray, shape (m, 2)
        Surveyed beacon positions [m].

    Returns
    -------
    np.ndarray, shape (m,)
        ``atan2(Y_b - y, X_b - x) - θ`` wrapped to (-π, π] [rad].
    """
    h = np.empty(beacons_xy.shape[0])
    for j in range(beacons_xy.shape[0]):
        h[j] = bearing_to(x, beacons_xy[j, 0], beacons_xy[j, 1])
    return h


@njit(cache=True)
def bearing_to(x: np.ndarray, beacon_x: float, beacon_y: float) -> float:
    """:func:`bearing_hx` of one beacon at (``beacon_x``, ``beacon_y``) [rad]."""
    return wrap(math.atan2(beacon_y - x[IY], beacon_x - x[IX]) - x[ITH])


@njit(cache=True)
def bearing_H(x: np.ndarray, beacon_xy: np.ndarray) -> np.ndarray:
    """Jacobian of :func:`bearing_hx` for one beacon ``[X_b, Y_b]``, shape (1, n)."""
    H = np.empty((1, x.shape[0]))
    bearing_H_into(x, beacon_xy, H)
    return H


@njit(cache=True)
def bearing_H_into(x: np.ndarray, beacon_xy: np.ndarray, H: np.ndarray) -> None:
    """:func:`bearing_H` written into ``H`` (1, n)."""
    dx, dy = beacon_xy[0] - x[IX], beacon_xy[1] - x[IY]
    r2 = dx * dx + dy * dy
    _zero(H)
    H[0, IX], H[0, IY], H[0, ITH] = dy / r2, -dx / r2, -1.0


@njit(cache=True)
def bearing_residual(z: float, h: float) -> float:
    """Innovation of a bearing, ``wrap(z - h)`` [rad] (the ``residual`` of filterpy's EKF)."""
    return wrap(z - h)


COSINE_MARGIN = 1e-9  # see nearest_beacon


@njit(cache=True)
def _direction_cosine(x: np.ndarray, beacon_x: float, beacon_y: float, ux: float,
                      uy: float) -> float:
    """Cosine of the angle between the unit vector (``ux``, ``uy``) and the direction from
    the state's position to the beacon; NaN at the beacon itself."""
    dx, dy = beacon_x - x[IX], beacon_y - x[IY]
    r2 = dx * dx + dy * dy
    return (dx * ux + dy * uy) / math.sqrt(r2) if r2 > 0.0 else math.nan


@njit(cache=True)
def nearest_beacon(x: np.ndarray, z: float, beacons_xy: np.ndarray) -> tuple[int, float]:
    """Associate a bearing with the beacon giving the smallest innovation (Lindgren §2.4).

    Parameters
    ----------
    x : np.ndarray, shape (n,)
    z : float
        Measured bearing relative to body x [rad].
    beacons_xy : np.ndarray, shape (m, 2)
        Surveyed beacon positions [m].

    Returns
    -------
    index : int
        Row of ``beacons_xy`` chosen.
    y : float
        Its innovation ``wrap(z - h_lz(x))`` [rad].
    """
    # The innovation's size |y| is the angle between the measured direction and the beacon's,
    # so the beacon with the largest cosine between the two has the smallest; cosines take a
    # square root per beacon where y takes an arctangent and two remainders. The exact y is
    # then computed, in the beacons' order, for every beacon whose cosine comes within
    # COSINE_MARGIN of the largest (far wider than the cosines' rounding, so the beacons that
    # tie for the smallest |y| are all among them) or is not finite: the same beacon and y,
    # bit for bit, as comparing the exact y of every beacon.
    heading = x[ITH] + z
    ux, uy = math.cos(heading), math.sin(heading)
    best_cos = -math.inf
    for j in range(beacons_xy.shape[0]):
        c = _direction_cosine(x, beacons_xy[j, 0], beacons_xy[j, 1], ux, uy)
        if c > best_cos:
            best_cos = c
    best, y_best = 0, math.inf
    for j in range(beacons_xy.shape[0]):
        c = _direction_cosine(x, beacons_xy[j, 0], beacons_xy[j, 1], ux, uy)
        if c >= best_cos - COSINE_MARGIN or not math.isfinite(c):
            y = bearing_residual(z, bearing_to(x, beacons_xy[j, 0], beacons_xy[j, 1]))
            if abs(y) < abs(y_best):
                best, y_best = j, y
    return best, y_best
