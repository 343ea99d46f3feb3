"""Side-wall bulldozing force of a rigid wheel sliding sideways in soil.

A wheel that slides sideways pushes the soil in front of its sunken side wall; the soil fails
in a passive wedge, and the reaction on the wall is Bekker's bulldozing resistance per unit wall
width (Bekker, Theory of Land Locomotion, 1956, pp. 280-282, as used by Ishigami, Miwa,
Nagatani and Yoshida, "Terramechanics-based model for steering maneuver of planetary
exploration rovers on loose soil", J. Field Robotics 24(3), 2007, the side force's bulldozing
term):

    R_b(h) = D_1 (c h + D_2 gamma h^2 / 2),
    D_1 = cot X_c + tan(X_c + phi),   D_2 = cot X_c + cot^2 X_c / cot phi,
    X_c = pi/4 - phi/2,

with h the depth of the wall in the soil [m], c the cohesion [Pa], phi the friction angle and
gamma the soil's unit weight [N/m^3]. Ishigami et al. integrate it over the wheel's contact arc,
the depth at angle theta from the bottom dead centre being h(theta) = r (cos theta -
cos theta_f) with entry angle theta_f = acos(1 - z/r) for sinkage z, each slice of the wall
weighted by its arm (r - h cos theta):

    F_s = integral from theta_r to theta_f of R_b(h(theta)) (r - h(theta) cos theta) dtheta.

The force opposes the lateral sliding and needs no friction at the patch: it is not bounded by
mu W, which is why a sunken wheel at a large slip angle can carry side forces above its load.
Quasi-static (Ishigami et al.): its magnitude does not depend on the sliding speed or the slip
angle, only its direction does.

R_b and its coefficients are the C laws ``laws_bulldozing_per_width`` and
``laws_bulldozing_coefficients`` of ``_laws.h`` (one text with the wheel's frontal bulldozing of
`models.slip_sinkage_resistance`, which the simulation runs).
"""

from __future__ import annotations

import math

import numpy as np

import slipenv.terramechanics._laws as _laws

__all__ = ["bulldozing_coefficients", "bulldozing_resistance_n_per_m", "sidewall_force_n"]

# Gauss-Legendre nodes on [-1, 1]: the integrand is a polynomial in cos theta of degree <= 4
# times smooth functions of theta, integrated to rounding with 24 nodes.
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(24)


def bulldozing_coefficients(friction_angle_rad: float) -> tuple[float, float]:
    """Bekker's bulldozing coefficients (D_1, D_2) for friction angle phi (module docstring).

    D_1 = cot X_c + tan(X_c + phi), D_2 = cot X_c + cot^2 X_c / cot phi, X_c = pi/4 - phi/2
    (Bekker 1956, pp. 280-282; Ishigami et al. 2007). phi in [0, pi/2).
    """
    phi = float(friction_angle_rad)
    if not 0.0 <= phi < math.pi / 2.0:
        raise ValueError(f"friction_angle_rad={friction_angle_rad!r} must be in [0, pi/2)")
    return _laws.bulldozing_coefficients(phi)


def bulldozing_resistance_n_per_m(depth_m, cohesion_pa: float, friction_angle_rad: float,
                                  unit_weight_n_m3: float) -> np.ndarray:
    """R_b(h) = D_1 (c h + D_2 gamma h^2 / 2) [N per metre of wall] (Bekker 1956; module).

    Parameters
    ----------
    depth_m : array_like
        Depth h of the wall in the soil [m]; negative depths count as 0.
    cohesion_pa, friction_angle_rad, unit_weight_n_m3 : float
        c [Pa] >= 0, phi [rad] in [0, pi/2), gamma [N/m^3] >= 0.
    """
    if not (cohesion_pa >= 0.0 and unit_weight_n_m3 >= 0.0):
        raise ValueError(f"cohesion_pa={cohesion_pa!r} and unit_weight_n_m3="
                         f"{unit_weight_n_m3!r} must be >= 0")
    bulldozing_coefficients(friction_angle_rad)  # checks phi
    c, phi, gamma = float(cohesion_pa), float(friction_angle_rad), float(unit_weight_n_m3)
    h = np.asarray(depth_m, dtype=float)
    law = _laws.bulldozing_resistance_n_per_m
    return np.array([law(x, c, phi, gamma) for x in h.ravel().tolist()],
                    dtype=float).reshape(h.shape)


def sidewall_force_n(sinkage_m: float, radius_m: float, cohesion_pa: float,
                     friction_angle_rad: float, unit_weight_n_m3: float,
                     exit_angle_rad: float = 0.0) -> float:
    """Magnitude of the side-wall bulldozing force F_s [N] of a rigid wheel sunk z (module).

    F_s = integral over [theta_r, theta_f] of R_b(h) (r - h cos theta) dtheta, h(theta) =
    r (cos theta - cos theta_f), theta_f = acos(1 - z/r) (Ishigami et al. 2007). Apply it
    against the wheel's lateral sliding.

    Parameters
    ----------
    sinkage_m : float
        Sinkage z [m], in [0, r]; 0 gives 0.
    radius_m : float
        Wheel radius r [m], > 0.
    cohesion_pa, friction_angle_rad, unit_weight_n_m3 : float
        Soil (see `bulldozing_resistance_n_per_m`).
    exit_angle_rad : float
        theta_r [rad], in [-theta_f, 0]: where the wall leaves the soil behind the bottom dead
        centre (0: the soil does not rebound behind the wheel; -theta_f: a symmetric rut).
    """
    r, z = float(radius_m), float(sinkage_m)
    if not (r > 0.0 and 0.0 <= z <= r):
        raise ValueError(f"need radius_m > 0 and 0 <= sinkage_m <= radius_m, got r={r!r}, "
                         f"z={z!r}")
    theta_f = math.acos(1.0 - z / r)
    if not -theta_f <= exit_angle_rad <= 0.0:
        raise ValueError(f"exit_angle_rad={exit_angle_rad!r} must be in [-theta_f, 0] = "
                         f"[{-theta_f:.4g}, 0]")
    if theta_f == 0.0:
        return 0.0
    half = 0.5 * (theta_f - exit_angle_rad)
    theta = exit_angle_rad + half * (_NODES + 1.0)
    cos_t = np.cos(theta)
    h = r * (cos_t - math.cos(theta_f))
    rb = bulldozing_resistance_n_per_m(h, cohesion_pa, friction_angle_rad, unit_weight_n_m3)
    return float(half * np.sum(_WEIGHTS * rb * (r - h * cos_t)))
