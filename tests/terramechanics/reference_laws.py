"""The wheel-soil laws in plain Python: the oracle the compiled laws are tested against.

slipenv runs each wheel-soil law once, in C (``slipenv/terramechanics/_laws.h``). This module is
an independent transcription of the same equations in Python floats, kept in the tests only:
``test_laws_match_the_python_reference.py`` compares every C law with its function here to a
stated relative tolerance. The sources and equations are in the C header and in the docstrings
of the public Python API of the same names (`slipenv.terramechanics.slip_dynamics`,
`bekker`, `janosi`, `lindgren`, `reina`, `models`).
"""

from __future__ import annotations

import math

_X_SMALL = 1e-5
_SIXTH = 1.0 / 6.0
_TINY = 1e-300


def relax_slip(slip: float, tan_beta: float, rim_speed_mps: float, long_speed_mps: float,
               lat_speed_mps: float, step_per_length: float, forward_reference: bool = False
               ) -> tuple[float, float, float, float]:
    v_ref = max(abs(rim_speed_mps), abs(long_speed_mps), abs(lat_speed_mps))
    # Reina's convention: tan_beta relaxes to v_lat/|v_x| (leak without the rim speed)
    v_lat_ref = max(abs(long_speed_mps), abs(lat_speed_mps)) if forward_reference else v_ref
    s = (slip + step_per_length * (rim_speed_mps - long_speed_mps)) / (1.0 + step_per_length
                                                                      * v_ref)
    t = (tan_beta + step_per_length * lat_speed_mps) / (1.0 + step_per_length * v_lat_ref)
    s = 1.0 if s > 1.0 else (-1.0 if s < -1.0 else s)
    t = 1.0 if t > 1.0 else (-1.0 if t < -1.0 else t)
    return s, t, v_ref, v_lat_ref


def critical_damping_ns_per_m(slip_stiffness_n: float, relaxation_m: float, mass_kg: float,
                              damping_ratio: float, max_ns_per_m: float) -> float:
    c = 2.0 * damping_ratio * math.sqrt(slip_stiffness_n / relaxation_m * mass_kg)
    return c if c < max_ns_per_m else max_ns_per_m


def lateral_soil_damping_n(tan_beta_change: float, reference_speed_mps: float,
                           damping_n: float, fade_speed_mps: float) -> float:
    fade = reference_speed_mps / fade_speed_mps
    fade *= fade
    return -damping_n * tan_beta_change / (1.0 + fade * fade)


def longitudinal_soil_damping_n(rim_speed_mps: float, long_speed_mps: float,
                                reference_speed_mps: float, damping_ns_per_m: float,
                                low_speed_mps: float) -> float:
    speed = reference_speed_mps / low_speed_mps
    if speed < 1.0:
        return (1.0 - speed) * damping_ns_per_m * (rim_speed_mps - long_speed_mps)
    return 0.0


def rut_resistance_n(resistance_n: float, state: float, displacement_m: float,
                     speed_mps: float, stick_m: float,
                     damping_ns_per_m: float) -> tuple[float, float]:
    u = state + displacement_m / stick_m
    u = 1.0 if u > 1.0 else (-1.0 if u < -1.0 else u)
    r = resistance_n * u + damping_ns_per_m * speed_mps
    r = resistance_n if r > resistance_n else (-resistance_n if r < -resistance_n else r)
    return r, u


def rut_resistance_vector_n(resistance_n: float, state: tuple[float, float, float],
                            velocity_mps: tuple[float, float, float], dt_s: float,
                            stick_m: float, damping_ns_per_m: float
                            ) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    vx, vy, vz = velocity_mps
    h = dt_s / stick_m
    ux, uy, uz = state[0] + h * vx, state[1] + h * vy, state[2] + h * vz
    norm = math.sqrt(ux * ux + uy * uy + uz * uz)
    if norm > 1.0:
        ux, uy, uz = ux / norm, uy / norm, uz / norm
    rx = resistance_n * ux + damping_ns_per_m * vx
    ry = resistance_n * uy + damping_ns_per_m * vy
    rz = resistance_n * uz + damping_ns_per_m * vz
    norm = math.sqrt(rx * rx + ry * ry + rz * rz)
    if norm > resistance_n:
        scale = resistance_n / norm
        rx, ry, rz = rx * scale, ry * scale, rz * scale
    return (rx, ry, rz), (ux, uy, uz)


def wheel_sinkage_m(load_n: float, width_m: float, diameter_m: float, k_c: float,
                          k_phi: float, n_exp: float) -> float:
    k_eq_b = k_c + width_m * k_phi
    base = 3.0 * max(load_n, 0.0) / ((3.0 - n_exp) * k_eq_b * math.sqrt(diameter_m))
    return base ** (2.0 / (2.0 * n_exp + 1.0))


def rut_following_compaction_n(compaction_n: float, rut_compaction_n: float) -> float:
    extra = compaction_n - rut_compaction_n
    return extra if extra > 0.0 else 0.0


def rut_load_ratio(width_m: float, diameter_m: float, leader_width_m: float,
                   leader_diameter_m: float, k_c: float, k_phi: float) -> float:
    if width_m == leader_width_m and diameter_m == leader_diameter_m:
        return 1.0
    return ((k_c + width_m * k_phi) * diameter_m ** 0.5
            / ((k_c + leader_width_m * k_phi) * leader_diameter_m ** 0.5))


def _okello_h(x: float) -> float:
    xc = x if x > _X_SMALL else _X_SMALL
    return (math.expm1(-xc) + xc) / (xc * xc) + (xc - x) * _SIXTH  # h'(0) = -1/6 where clamped


def janosi_forces(slip: float, tan_beta: float, load_n: float, cohesion_force_n: float,
                  tan_phi: float, shear_ratio: float,
                  lateral_ratio: float = 1.0) -> tuple[float, float]:
    if load_n <= 0.0:
        return 0.0, 0.0
    f_max = load_n * tan_phi + cohesion_force_n
    lateral = tan_beta * lateral_ratio
    secant = f_max * _okello_h(math.hypot(slip, lateral) * shear_ratio) * shear_ratio
    return secant * slip, -secant * lateral


def linear_slip_forces(slip: float, tan_beta: float, load_n: float, cohesion_force_n: float,
                       tan_phi: float, shear_ratio: float) -> tuple[float, float]:
    if load_n <= 0.0:
        return 0.0, 0.0
    half_ratio = 0.5 * shear_ratio  # 1/(2B)
    excess = math.hypot(slip, tan_beta) * half_ratio  # sigma/(2B): saturated beyond 1
    secant = (load_n * tan_phi + cohesion_force_n) * half_ratio / (excess if excess > 1.0
                                                                     else 1.0)
    return secant * slip, -secant * tan_beta


def _exp_secant(y: float) -> float:
    return -math.expm1(-y) / y if y > _TINY else 1.0


def reina_forces(slip: float, tan_beta: float, load_n: float, mu: float, c_x_n: float,
                 c_y_n: float, a_x: float, a_y: float) -> tuple[float, float]:
    if load_n <= 0.0:
        return 0.0, 0.0
    sigma_per_mu_w = math.hypot(slip, tan_beta) / (mu * load_n)
    k_x = c_x_n * _exp_secant(c_x_n * sigma_per_mu_w) - load_n * a_x
    k_y = c_y_n * _exp_secant(c_y_n * sigma_per_mu_w) - load_n * a_y
    return (slip * k_x if k_x > 0.0 else 0.0), (-tan_beta * k_y if k_y > 0.0 else 0.0)


def motion_resistance_n(load_n: float, f_r: float, gamma: float, exponent: float) -> float:
    res = f_r * load_n
    if gamma:
        res += gamma * load_n ** exponent
    return res


def slip_sinkage_factor(slip: float) -> float:
    """Lyasko (2010): z/z0 = (1 + i)/(1 - 0.5 i), i clipped to [0, 1]."""
    i = min(max(slip, 0.0), 1.0)
    return (1.0 + i) / (1.0 - 0.5 * i)


def bulldozing_coefficients(phi: float) -> tuple[float, float]:
    """Bekker (1956): D_1 = cot X + tan(X + phi), D_2 = cot X + cot^2 X tan phi, X = 45° - phi/2."""
    x = math.pi / 4.0 - phi / 2.0
    return 1.0 / math.tan(x) + math.tan(x + phi), (1.0 / math.tan(x)
                                                   + math.tan(phi) / math.tan(x) ** 2)


def bulldozing_resistance_n_per_m(depth_m: float, cohesion_pa: float, phi: float,
                                  unit_weight: float) -> float:
    """Bekker (1956): R_b = D_1 (c h + D_2 gamma h^2/2), 0 for h <= 0."""
    if not depth_m > 0.0:
        return 0.0
    d1, d2 = bulldozing_coefficients(phi)
    return d1 * (cohesion_pa * depth_m + d2 * unit_weight * depth_m ** 2 / 2.0)


def slip_sinkage_resistance_n(slip: float, compaction_n: float, n_exp: float, sinkage_m: float,
                              width_m: float, cohesion_pa: float, phi: float,
                              unit_weight: float) -> float:
    """Compaction at the slip sinkage minus at the static one, plus the front's bulldozing of
    the depth the slip adds."""
    f = slip_sinkage_factor(abs(slip))
    dug = sinkage_m * (f - 1.0)
    return (compaction_n * f ** (n_exp + 1.0) - compaction_n
            + width_m * bulldozing_resistance_n_per_m(dug, cohesion_pa, phi, unit_weight))


def dug_resistance_n(dug_m: float, compaction_n: float, n_exp: float, sinkage_m: float,
                     width_m: float, cohesion_pa: float, phi: float,
                     unit_weight: float) -> float:
    """A wheel dug d below its static rut z0: the front bulldozes the dug soil, b R_b(d), and
    the compaction grows from R_c0 to R_c0 ((z0 + d)/z0)^(n+1); 0 for d <= 0."""
    if not dug_m > 0.0:
        return 0.0
    res = width_m * bulldozing_resistance_n_per_m(dug_m, cohesion_pa, phi, unit_weight)
    if compaction_n and sinkage_m > 0.0:
        res += compaction_n * (((sinkage_m + dug_m) / sinkage_m) ** (n_exp + 1.0) - 1.0)
    return res


def slip_sinkage_step(dug_m: float, rim: float, v_long: float, h: float, delta_m: float,
                      cap_m: float) -> float:
    """Backward Euler of sigma dd/dt = delta |r omega - v| - v_roll d, h = dt/sigma,
    v_roll = min(|r omega|, |v|) when both point the same way (else 0), d in [0, cap]."""
    slide = abs(rim - v_long)
    roll = min(abs(rim), abs(v_long)) if rim * v_long > 0.0 else 0.0
    d = (dug_m + h * delta_m * slide) / (1.0 + h * roll)
    return min(max(d, 0.0), max(cap_m, 0.0))


def kernel_sinkage_state(constants: tuple, dug_m: float, rim: float, v_long: float, h: float,
                         load_n: float) -> tuple[float, float]:
    """(dug, resistance) of the simulation's slip-sinkage state of one wheel over one substep:
    delta = the constants' excavation depth, capped where the wheel is buried to its axle
    (D/2 - z0)."""
    (*_, s_gamma, s_exponent, width, diameter, k_c, k_phi, n_exp, cohesion, phi, unit_weight,
     state, excavation) = constants
    if not state or load_n <= 0.0:
        return 0.0, 0.0
    z0 = wheel_sinkage_m(load_n, width, diameter, k_c, k_phi, n_exp)
    dug = slip_sinkage_step(dug_m, rim, v_long, h, excavation, diameter / 2.0 - z0)
    return dug, dug_resistance_n(dug, s_gamma * load_n ** s_exponent, n_exp, z0, width,
                                 cohesion, phi, unit_weight)


def kernel(constants: tuple, slip: float, tan_beta: float,
           load_n: float) -> tuple[float, float, float]:
    """(fx, fy, resistance) of a force model bound to one soil (`models.KernelConstants`)."""
    (kind, ac, tan_phi, ratio, kappa, mu, c_x, c_y, a_x, a_y, scaled, gross, gross_c_x,
     w_ref, f_r, gamma, exponent, sinks, s_gamma, s_exponent, width, diameter, k_c, k_phi,
     n_exp, cohesion, phi, unit_weight, _state, _excavation) = constants
    if kind == 0:
        fx, fy = janosi_forces(slip, tan_beta, load_n, ac, tan_phi, ratio, kappa)
    elif kind == 1:
        fx, fy = linear_slip_forces(slip, kappa * tan_beta, load_n, ac, tan_phi, ratio)
    elif scaled:
        fx, fy = reina_forces(slip, tan_beta, 1.0, mu, c_x, c_y, a_x, a_y)
        fx, fy = fx * load_n, fy * load_n
    else:
        fx, fy = reina_forces(slip, tan_beta, load_n, mu, c_x, c_y, a_x, a_y)
    res = motion_resistance_n(load_n, f_r, gamma, exponent)
    if sinks and slip != 0.0 and load_n > 0.0:
        z0 = wheel_sinkage_m(load_n, width, diameter, k_c, k_phi, n_exp)
        res += slip_sinkage_resistance_n(slip, s_gamma * load_n ** s_exponent, n_exp, z0, width,
                                         cohesion, phi, unit_weight)
    if gross:
        sigma = math.hypot(slip, tan_beta)
        if sigma > 0.0 and gamma:
            y = gross_c_x * sigma / (mu * (w_ref if scaled else load_n))
            fx += gamma * load_n ** exponent * -math.expm1(-y) * slip / sigma
    return fx, fy, res


def multi_pass_resistance_n(res: float, load_n: float, lead_res: float, lead_load_n: float,
                            f_r: float) -> float:
    """Rolling f_r W whole, compaction only below the leader's rut."""
    rolling = f_r * load_n
    return rolling + rut_following_compaction_n(res - rolling, lead_res - f_r * lead_load_n)


def contact_frame(patch, load_n, q, centre, v, omega):
    """(c, e, l, v_long, v_side, v_lat) of one wheel's contact (see `_laws.h`)."""
    inv_w = 1.0 / load_n
    cx, cy, cz = patch[0] * inv_w, patch[1] * inv_w, patch[2] * inv_w
    nx, ny, nz = patch[3], patch[4], patch[5]
    inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
    nx, ny, nz = nx * inv, ny * inv, nz * inv
    qx, qy, qz, qw = q
    ax = 2.0 * (qx * qy - qw * qz)
    ay = 1.0 - 2.0 * (qx * qx + qz * qz)
    az = 2.0 * (qy * qz + qw * qx)
    ex, ey, ez = ay * nz - az * ny, az * nx - ax * nz, ax * ny - ay * nx
    inv = 1.0 / math.sqrt(ex * ex + ey * ey + ez * ez)
    ex, ey, ez = ex * inv, ey * inv, ez * inv
    lx, ly, lz = ny * ez - nz * ey, nz * ex - nx * ez, nx * ey - ny * ex
    px, py, pz = centre
    vx, vy, vz = v
    wx, wy, wz = omega
    rx, ry, rz = cx - px, cy - py, cz - pz
    v_long = vx * ex + vy * ey + vz * ez
    v_side = vx * lx + vy * ly + vz * lz
    v_lat = ((vx + wy * rz - wz * ry) * lx + (vy + wz * rx - wx * rz) * ly
             + (vz + wx * ry - wy * rx) * lz)
    return (cx, cy, cz), (ex, ey, ez), (lx, ly, lz), v_long, v_side, v_lat
