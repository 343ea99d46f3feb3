"""Lindgren's linear torque-slip law and the effect of the rolling radius on measured slip.

At the small slips of a lightly loaded vehicle Okello's curve reduces to T = k_s s with
k_s = T_max/(2B) (Lindgren Eq. 21-24). Slip is measured from an assumed wheel radius R_m; when
the true rolling radius R_a differs (it depends on the surface: 0.283/0.287 m on soil, 0.275 m
on concrete, Lindgren Sec. 3.2) the measured slip s_m is off, and the torque/slip line seen in
s_m no longer passes through the origin (Eq. 25-31).

`linear_slip_forces` is the combined-slip form of the linear law that the simulation injects, in
plain floats (called per wheel and per physics substep); its one implementation is C
(``_laws.h``, which the substep loop runs, there also with lateral anisotropy). The other
functions broadcast.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

import slipenv.terramechanics._laws as _laws

__all__ = [
    "linear_slip_forces",
    "linear_torque_nm",
    "slip_from_speeds",
    "actual_slip",
    "measured_slip",
    "torque_slip_line",
    "stiffness_and_radius_ratio",
]


def linear_torque_nm(slip: ArrayLike, stiffness_nm: ArrayLike,
                     max_torque_nm: ArrayLike) -> np.ndarray:
    """Linear torque-slip law T = k_s s (Lindgren Eq. 24), saturated at |T| <= T_max.

    T_max is the torque the soil can carry, r (A c + W tan phi) (Lindgren Eq. 3, 20); the
    linear law would otherwise exceed it once s > 2B.

    Parameters
    ----------
    slip : array_like
        Slip ratio s [-].
    stiffness_nm : array_like
        k_s [N m] (torque per unit slip), e.g. `janosi.small_slip_stiffness(T_max, B)`.
    max_torque_nm : array_like
        T_max [N m], >= 0.
    """
    t_max = np.asarray(max_torque_nm, dtype=float)
    return np.clip(np.asarray(stiffness_nm) * np.asarray(slip), -t_max, t_max)


def linear_slip_forces(slip: float, tan_beta: float, load_n: float, cohesion_force_n: float,
                       tan_phi: float, shear_ratio: float) -> tuple[float, float]:
    """Lindgren's linear slip law F = (k_s/r) s, combined slip, capped at Mohr-Coulomb [N].

    k_s = T_max/(2B) (Lindgren Eq. 24) with T_max = r (A c + W tan phi) and B = K/L, so the
    force stiffness is k_s/r = F_max L/(2K): the initial slope of the Janosi law, which it
    matches to 2 % while sigma L/K < 0.059 (Eq. 23: relative error ~ s/(3B)). The lateral
    force uses the same stiffness on tan_beta, and the resultant is capped at F_max:

        (fx, fy) = (s, -tan_beta) F_max min(sigma/(2B), 1)/sigma,  sigma = sqrt(s^2 + tan^2 b).

    Parameters
    ----------
    slip, tan_beta : float
        Slip ratio s [-] and tan of the slip angle [-] (convention of `contact`).
    load_n : float
        Normal load W [N]; W <= 0 (no contact) gives no force.
    cohesion_force_n, tan_phi, shear_ratio : float
        A c [N], tan phi [-] and L/K = 1/B [-], as in `janosi.janosi_forces`.

    Returns
    -------
    fx_n, fy_n : float
        fx with the sign of s; fy opposing the lateral sliding.
    """
    return _laws.linear_slip_forces(slip, tan_beta, load_n, cohesion_force_n, tan_phi,
                                    shear_ratio, 1.0)


def slip_from_speeds(ground_speed_mps: ArrayLike, wheel_rate_rad_s: ArrayLike,
                     radius_m: ArrayLike) -> np.ndarray:
    """Drive slip s = 1 - v/(omega R) (Lindgren Eq. 1, 25-26).

    With R the measured radius R_m this is the measured slip s_m (Eq. 25); with the actual
    rolling radius R_a it is the actual slip s_a (Eq. 26). omega R must be non-zero.

    Parameters
    ----------
    ground_speed_mps : array_like
        Actual speed v_a of the wheel centre [m/s].
    wheel_rate_rad_s : array_like
        Wheel spin rate omega [rad/s].
    radius_m : array_like
        Radius R [m].
    """
    return 1.0 - np.asarray(ground_speed_mps) / (np.asarray(wheel_rate_rad_s) * radius_m)


def actual_slip(slip_measured: ArrayLike, measured_radius_m: ArrayLike,
                actual_radius_m: ArrayLike) -> np.ndarray:
    """Actual slip from measured slip, s_a = s_m (R_m/R_a) + (1 - R_m/R_a) (Lindgren Eq. 30).

    Parameters
    ----------
    slip_measured : array_like
        s_m [-], computed with the assumed radius R_m.
    measured_radius_m, actual_radius_m : array_like
        R_m, R_a [m].
    """
    ratio = np.asarray(measured_radius_m) / actual_radius_m
    return np.asarray(slip_measured) * ratio + (1.0 - ratio)


def measured_slip(slip_actual: ArrayLike, measured_radius_m: ArrayLike,
                  actual_radius_m: ArrayLike) -> np.ndarray:
    """Measured slip from actual slip: Lindgren Eq. 30 solved for s_m.

    s_m = (s_a - 1) R_a/R_m + 1, the slip an odometer using R_m reports.
    """
    ratio = np.asarray(actual_radius_m) / measured_radius_m
    return (np.asarray(slip_actual) - 1.0) * ratio + 1.0


def torque_slip_line(stiffness_nm: ArrayLike, measured_radius_m: ArrayLike,
                     actual_radius_m: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Slope and intercept of T against measured slip (Lindgren Eq. 31).

    T = k_s (R_m/R_a) s_m + k_s (1 - R_m/R_a): the law T = k_s s_a seen through a wrong radius.

    Returns
    -------
    slope_nm, intercept_nm : ndarray
        dT/ds_m = k_s R_m/R_a [N m] and T at s_m = 0, k_s (1 - R_m/R_a) [N m].
    """
    k_s = np.asarray(stiffness_nm, dtype=float)
    ratio = np.asarray(measured_radius_m) / actual_radius_m
    return k_s * ratio, k_s * (1.0 - ratio)


def stiffness_and_radius_ratio(slope_nm: ArrayLike,
                               intercept_nm: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    """Invert Lindgren Eq. 31: a fitted line T = a s_m + b gives k_s = a + b, R_m/R_a = a/(a+b).

    Lindgren's own fit, T = 0.4575 + 7.2874 s (Sec. 3.2), gives k_s = 7.7449 and R_m/R_a = 0.9409
    in his (arbitrary) torque units.

    Returns
    -------
    stiffness_nm, radius_ratio : ndarray
        k_s [units of T] and R_m/R_a [-].
    """
    k_s = np.asarray(slope_nm, dtype=float) + intercept_nm
    return k_s, np.asarray(slope_nm) / k_s
