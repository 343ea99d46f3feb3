"""A skid-steer track on deformable soil: the Wong-Chiang shear field and its companions.

Plain functions of (state, kinematics, soil) for one track, or for the two tracks of a vehicle
at once (arrays of shape (n_tracks, n_cells)). The simulator (``slipenv.sim.track_soil``) calls
them once per physics substep; the tests check them against the closed forms.

Frame: the hull frame projected on the ground, x forward, y left, origin at the hull reference
point; a track at lateral offset y_i, contact -L/2 <= x <= L/2, width b. The belt moves
backwards along the ground run at u_i = r_s omega_i (positive in forward drive).

Terms and sources
-----------------
Shear displacement (Wong & Chiang 2001, Proc. IMechE D 215:343-355; Wong, *Theory of Ground
    Vehicles*, 4th ed., Ch. 7 "steering of tracked vehicles"): a belt element slides over the
    ground at v_j = (V_x - Omega y_i - u_i, V_y + Omega x) and its displacement j is the
    integral of v_j along its path since it entered the contact. In the hull frame that is the
    advection equation  dj/dt - u dj/dx = v_j - Omega z x j  (j = 0 at the entry end), whose
    steady state is Wong-Chiang's j(x) including the hull rotation during contact
    (:func:`steady_shear_displacement` integrates it exactly). `advance_shear` solves it with
    first-order upwinding on cell faces, the source at cell centres (midpoint rule).
Shear stress (Janosi & Hanamoto; Wong Eq. 2.56) with Mohr-Coulomb strength (Wong Eq. 2.54):
    tau = (c + p tan phi)(1 - exp(-|j|/K)), directed against the local sliding velocity
    (Wong & Chiang's choice). The direction is carried by a short "bristle" state e per belt
    element, de/dt = v_j - |v_j| e/e_max (the LuGre / brush-model form, Canudas de Wit et al.
    1995): in sliding it aligns with v_j within a sliding distance of a few e_max, so the
    steady forces are Wong-Chiang's (tested within 5 %); at rest it is an elastic spring. A
    stress that jumped with the sign of v_j would be an infinitely stiff damper, which an
    explicit step at 240 Hz cannot integrate (the vehicle chatters and ratchets downhill).
Normal pressure: the road-wheel loads, spread piecewise-linearly over the cells
    (`load_spread_matrix`, hat functions that conserve the load exactly).
Sinkage (Bekker's pressure-sinkage law, Wong Ch. 2): z0 = (p/(k_c/b + k_phi))^(1/n) per cell,
    times Lyasko's slip-sinkage factor (1 + i)/(1 - 0.5 i) (Lyasko, J. Terramech. 47 (2010)
    21-31).
Compaction resistance (Bekker; Wong Ch. 2 and 5): R_c = b (k_c/b + k_phi) z^(n+1)/(n+1) per
    track, acting only while the track advances into soil it has not yet cut (a rut *state*:
    `rut_resistance_n`): rate independent, zero in its own rut, so a stalled track does not
    creep.
Side-wall (bulldozing) resistance: Rankine passive earth pressure on the track's side wall of
    height h, P = 1/2 gamma h^2 N_phi + 2 c h sqrt(N_phi), N_phi = tan^2(45 deg + phi/2) (Wong
    Ch. 2, "passive earth pressure"; Bekker's bulldozing resistance is the same Rankine
    wedge), on each side of each cell separately, mobilised with the wall's penetration d
    into the soil on that side, P (1 - e^{-d/d_b}), d_b a tenth of the wall height (passive
    pressure is mobilised after a wall movement of a few per cent of its height in loose sand:
    Terzaghi, Peck & Mesri, *Soil Mechanics in Engineering Practice*, 3rd ed., passive earth
    pressure); moving away unloads it (the soil does not pull). h = sinkage + berm height; the
    berm is a ridge at the angle of repose (taken = phi) whose cross-section grows with the
    volume the wall sweeps (z |dd|); wall states and berms leave with the ground as the track
    moves on (`advance_wall`).
Not modelled: shear on the track's side faces and grousers, soil flow around the track ends,
    compaction of the soil a track sweeps sideways, multi-pass effects within one track.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "DIRECTION_SPEED_MPS",
    "load_spread_matrix",
    "janosi_stress_pa",
    "shear_direction",
    "direction_of_stress",
    "advance_shear",
    "steady_shear_displacement",
    "steady_track_forces",
    "cell_forces",
    "bekker_sinkage_m",
    "slip_sinkage_factor",
    "compaction_resistance_n",
    "rut_resistance_n",
    "passive_pressure_n_per_m",
    "berm_height_m",
    "advance_wall",
    "wall_force_n_per_m",
]

DIRECTION_SPEED_MPS = 2e-3
"""[m/s] Below this sliding speed the stress direction blends from -v_j to -j (at rest the soil
is a spring along its displacement; the sliding direction is undefined)."""


# -- normal pressure -------------------------------------------------------------------------
def load_spread_matrix(wheel_x_m: np.ndarray, cell_x_m: np.ndarray) -> np.ndarray:
    """Matrix M (n_cells, n_wheels) spreading road-wheel loads piecewise-linearly over cells.

    Column k is the hat function of road wheel k (1 at x_k, 0 at its neighbours, flat beyond
    the end wheels) sampled at the cell centres and normalised to sum to 1, so the cell loads
    q = M W conserve the total load exactly; p = q / (b dx) is the pressure.
    """
    xw = np.asarray(wheel_x_m, dtype=float)
    xc = np.asarray(cell_x_m, dtype=float)
    order = np.argsort(xw)
    xs = xw[order]
    m = np.zeros((xc.size, xw.size))
    for rank, k in enumerate(order):
        unit = np.zeros(xw.size)
        unit[rank] = 1.0
        col = np.interp(xc, xs, unit)  # flat beyond the end wheels
        total = col.sum()
        m[:, k] = col / total if total > 0.0 else 0.0
    # Cells beyond the outer wheels get the end wheels' hats (np.interp holds end values).
    return m


# -- shear ---------------------------------------------------------------------------------
def janosi_stress_pa(j_abs_m, pressure_pa, cohesion_pa: float, tan_phi: float,
                     shear_modulus_m: float):
    """Janosi-Hanamoto stress tau = (c + p tan phi)(1 - e^{-j/K}) [Pa] (Wong Eq. 2.56, 2.54).

    Broadcasts over arrays of |j| [m] and pressure p [Pa].
    """
    return (cohesion_pa + pressure_pa * tan_phi) * (1.0 - np.exp(-np.asarray(j_abs_m)
                                                                 / shear_modulus_m))


def shear_direction(vx, vy, jx, jy, v_reg: float = DIRECTION_SPEED_MPS):
    """Unit vector (dx, dy) *along which the soil resists*: the stress is -tau (dx, dy).

    (dx, dy) is the sliding velocity's direction v_j/|v_j| (Wong & Chiang) for |v_j| >= v_reg;
    below, the sliding velocity's weight |v_j|/v_reg blends it with the displacement's direction
    j/|j| (at rest the soil acts as a spring along its displacement). Zero where both vanish.
    """
    vx, vy, jx, jy = (np.asarray(a, dtype=float) for a in (vx, vy, jx, jy))
    speed = np.hypot(vx, vy)
    jn = np.hypot(jx, jy)
    w = np.minimum(speed / v_reg, 1.0)
    inv_j = np.where(jn > 0.0, 1.0 / np.maximum(jn, 1e-300), 0.0)
    # v/v_reg has length w; the displacement part has length (1 - w).
    dx = vx / v_reg * (speed < v_reg) + vx / np.maximum(speed, 1e-300) * (speed >= v_reg) \
        + (1.0 - w) * jx * inv_j
    dy = vy / v_reg * (speed < v_reg) + vy / np.maximum(speed, 1e-300) * (speed >= v_reg) \
        + (1.0 - w) * jy * inv_j
    norm = np.hypot(dx, dy)
    inv = np.where(norm > 0.0, 1.0 / np.maximum(norm, 1e-300), 0.0)
    return dx * inv, dy * inv


def _upwind(field: np.ndarray, forward: np.ndarray, backward: np.ndarray) -> np.ndarray:
    """The upstream neighbour of every entry along the last axis (0 beyond the entry end):
    the previous entry where ``forward``, the next where ``backward``, itself elsewhere.
    ``forward``/``backward`` are boolean masks broadcasting over the leading axes."""
    zero = np.zeros(field.shape[:-1] + (1,))
    prev = np.concatenate((zero, field[..., :-1]), axis=-1)
    nxt = np.concatenate((field[..., 1:], zero), axis=-1)
    return np.where(forward, prev, np.where(backward, nxt, field))


def advance_shear(j: np.ndarray, v_cell: np.ndarray, belt_speed_mps: np.ndarray,
                  yaw_rate_rad_s: float, dx_m: float, dt_s: float,
                  e: np.ndarray | None = None, direction_length_m=1e-3) -> np.ndarray:
    """One explicit step of dj/dt - u dj/dx = v_j - Omega z x j on cell faces (in place).

    Parameters
    ----------
    j : ndarray, shape (2, n_tracks, n_cells + 1)
        Shear displacement (x, y components) [m] at the faces, face 0 at the front (x = L/2),
        face n at the rear.
    v_cell : ndarray, shape (2, n_tracks, n_cells)
        Sliding velocity of the belt over the ground at the cell centres [m/s].
    belt_speed_mps : ndarray, shape (n_tracks,)
        u_i: belt speed along the ground run, > 0 when it moves rearwards (forward drive).
    yaw_rate_rad_s : float
        Omega [rad/s] (the rotation term keeps j in the ground frame while stored in hull axes;
        it produces Wong-Chiang's cos/sin terms).
    dx_m, dt_s : float
        Cell length [m] and time step [s] (|u| dt/dx < 1 for stability).
    e : ndarray, shape (2, n_tracks, n_cells), optional
        The stress-direction state [m] at the cell centres (see `direction_of_stress`),
        advected the same way with the source v_j - |v_j| e / e_max - Omega z x e (implicit in
        the relaxation).
    direction_length_m : float or ndarray (n_tracks, 1)
        e_max [m], the sliding distance over which the stress direction turns to a new sliding
        direction.

    Returns j. Upwinding: for u > 0 the front face is the entry (j = 0) and face f takes the
    flux from face f-1 with the source of the cell between them (midpoint rule: exact for the
    linear v_j of a rigid hull); for u < 0 mirrored; at |u| below 1 mm/s every face
    integrates the mean source of its neighbouring cells (the soil spring).
    """
    u = np.asarray(belt_speed_mps, dtype=float)[:, None]
    fwd, bwd = u > 1e-3, u < -1e-3
    a = np.abs(u) * (dt_s / dx_m)
    src = v_cell.copy()
    src[0] += yaw_rate_rad_s * 0.5 * (j[1, :, :-1] + j[1, :, 1:])
    src[1] -= yaw_rate_rad_s * 0.5 * (j[0, :, :-1] + j[0, :, 1:])
    if fwd.all():  # the common case, without masks (same arithmetic)
        j[..., 1:] += a * (j[..., :-1] - j[..., 1:]) + dt_s * src
        j[..., 0] = 0.0
    else:
        zero = np.zeros(src.shape[:-1] + (1,))
        face_src = np.where(fwd, np.concatenate((zero, src), axis=-1),
                            np.where(bwd, np.concatenate((src, zero), axis=-1),
                                     np.concatenate((src[..., :1], 0.5 * (src[..., :-1]
                                                                          + src[..., 1:]),
                                                     src[..., -1:]), axis=-1)))
        j += a * (_upwind(j, fwd, bwd) - j) + dt_s * face_src
        j[..., 0] *= ~fwd[:, 0]
        j[..., -1] *= ~bwd[:, 0]
    if e is not None:
        leak = 1.0 + (dt_s / direction_length_m) * np.sqrt(v_cell[0] ** 2 + v_cell[1] ** 2)
        e_src = v_cell.copy()
        e_src[0] += yaw_rate_rad_s * e[1]
        e_src[1] -= yaw_rate_rad_s * e[0]
        if fwd.all():
            e_src[..., 1:] += a * (e[..., :-1] - e[..., 1:]) * (1.0 / dt_s)
            e_src[..., 0] -= a[:, 0] * e[..., 0] * (1.0 / dt_s)
            e += dt_s * e_src
        else:
            e += a * (_upwind(e, fwd, bwd) - e) + dt_s * e_src
        e /= leak
    return j


def direction_of_stress(ex, ey):
    """Unit vector of the direction state e, (0, 0) where e = 0 (the stress is -tau e/|e|)."""
    ex, ey = np.asarray(ex, dtype=float), np.asarray(ey, dtype=float)
    n = np.hypot(ex, ey)
    inv = np.where(n > 0.0, 1.0 / np.maximum(n, 1e-300), 0.0)
    return ex * inv, ey * inv


def steady_shear_displacement(x_m: np.ndarray, vx: float, vy: float, yaw_rate: float,
                              y_track_m: float, belt_speed_mps: float, length_m: float,
                              n_quad: int = 4001) -> tuple[np.ndarray, np.ndarray]:
    """Wong-Chiang steady shear displacement j(x) [m] of a track, by exact path integration.

    An element at x entered at x = L/2 a time t = (L/2 - x)/u ago; in complex form (hull axes
    at time t) j = e^{-i Omega t} int_0^t e^{i Omega s} v_j(L/2 - u s) ds with v_j = (V_x -
    Omega y_i - u) + i (V_y + Omega x): the hull's rotation during contact kept exactly (Wong &
    Chiang 2001; Wong, Theory of Ground Vehicles, Ch. 7). Needs u > 0. The integral is
    evaluated by the trapezoid rule on ``n_quad`` points (an independent check of the
    advection scheme in :func:`advance_shear`).
    """
    if belt_speed_mps <= 0.0:
        raise ValueError(f"belt_speed_mps must be > 0, got {belt_speed_mps!r}")
    u = belt_speed_mps
    t_end = length_m / u
    s = np.linspace(0.0, t_end, n_quad)
    xs = length_m / 2.0 - u * s
    v = (vx - yaw_rate * y_track_m - u) + 1j * (vy + yaw_rate * xs)
    integrand = np.exp(1j * yaw_rate * s) * v
    cum = np.concatenate(([0.0 + 0.0j], np.cumsum(0.5 * (integrand[1:] + integrand[:-1])
                                                  * np.diff(s))))
    t = (length_m / 2.0 - np.asarray(x_m, dtype=float)) / u
    c = np.interp(t, s, cum.real) + 1j * np.interp(t, s, cum.imag)
    j = np.exp(-1j * yaw_rate * t) * c
    return j.real, j.imag


def steady_track_forces(vx: float, vy: float, yaw_rate: float, y_track_m: float,
                        belt_speed_mps: float, length_m: float, width_m: float,
                        pressure_pa: float, cohesion_pa: float, tan_phi: float,
                        shear_modulus_m: float, n_quad: int = 4001) -> tuple[float, float, float]:
    """The Wong-Chiang integrals F_x = b int tau_x dx, F_y = b int tau_y dx and
    M_z = b int (x tau_y - y_i tau_x) dx [N, N, N m] of one track under uniform pressure, in
    steady motion (Wong & Chiang 2001; Wong, Theory of Ground Vehicles, Ch. 7)."""
    x = np.linspace(length_m / 2.0, -length_m / 2.0, n_quad)
    jx, jy = steady_shear_displacement(x, vx, vy, yaw_rate, y_track_m, belt_speed_mps,
                                       length_m, n_quad)
    vxs = np.full_like(x, vx - yaw_rate * y_track_m - belt_speed_mps)
    vys = vy + yaw_rate * x
    dxn, dyn = shear_direction(vxs, vys, jx, jy)
    tau = janosi_stress_pa(np.hypot(jx, jy), pressure_pa, cohesion_pa, tan_phi,
                           shear_modulus_m)
    tx, ty = -tau * dxn, -tau * dyn
    h = length_m / (n_quad - 1)
    trap = lambda f: float(h * (f.sum() - 0.5 * (f[0] + f[-1])))  # noqa: E731
    return (width_m * trap(tx), width_m * trap(ty),
            width_m * trap(x * ty - y_track_m * tx))


def cell_forces(j: np.ndarray, e: np.ndarray, pressure_pa: np.ndarray, width_m, dx_m: float,
                cohesion_pa, tan_phi, shear_modulus_m) -> np.ndarray:
    """Shear force of each cell on the track, shape (2, n_tracks, n_cells) [N].

    A cell's j is the mean of its two faces, e its centre value; tau = `janosi_stress_pa`(|j|),
    directed against e (`direction_of_stress`); f = -tau e/|e| b dx (midpoint rule).
    """
    jc = 0.5 * (j[..., :-1] + j[..., 1:])
    j_abs = np.sqrt(jc[0] ** 2 + jc[1] ** 2)
    e_abs = np.sqrt(e[0] ** 2 + e[1] ** 2)
    inv = 1.0 / np.maximum(e_abs, 1e-300)
    tau = janosi_stress_pa(j_abs, pressure_pa, cohesion_pa, tan_phi,
                           shear_modulus_m) * (width_m * dx_m)
    return -(tau * inv) * e


# -- sinkage and compaction ------------------------------------------------------------------
def bekker_sinkage_m(pressure_pa, width_m: float, k_c: float, k_phi: float, n_exp: float):
    """Static sinkage z0 = (p/(k_c/b + k_phi))^(1/n) [m] (Bekker; Wong Ch. 2). Broadcasts."""
    p = np.maximum(np.asarray(pressure_pa, dtype=float), 0.0)
    return (p / (k_c / width_m + k_phi)) ** (1.0 / n_exp)


def slip_sinkage_factor(slip):
    """Lyasko's slip-sinkage factor z/z0 = (1 + i)/(1 - 0.5 i), slip i clipped to [0, 1]
    (Lyasko, "Slip sinkage effect in soil-vehicle mechanics", J. Terramech. 47 (2010) 21-31)."""
    i = np.clip(np.asarray(slip, dtype=float), 0.0, 1.0)
    return (1.0 + i) / (1.0 - 0.5 * i)


def compaction_resistance_n(sinkage_m, width_m: float, k_c: float, k_phi: float,
                            n_exp: float):
    """R_c = b (k_c/b + k_phi) z^(n+1)/(n+1) [N]: the work of cutting a rut of depth z per unit
    travel (Bekker; Wong Ch. 2 and 5). Broadcasts."""
    z = np.maximum(np.asarray(sinkage_m, dtype=float), 0.0)
    return (k_c + width_m * k_phi) * z ** (n_exp + 1.0) / (n_exp + 1.0)


def rut_resistance_n(resistance_n: float, travel_m: float, cut_front_m: float,
                     cut_rear_m: float, speed_mps: float,
                     v_reg_mps: float) -> tuple[float, float, float]:
    """Compaction resistance as a rut state: (force along +x [N], new front, new rear).

    ``travel_m`` is the track's travel along its own axis since reset; the soil between
    ``cut_rear_m`` and ``cut_front_m`` (in travel coordinates) is already rutted. Advancing past
    the front (or reversing past the rear) cuts new soil and meets the full R_c, whatever the
    speed (rate independent); inside its own rut the track meets none. ``v_reg_mps`` is a
    regularisation of the sign at rest only (a set-valued law in the limit), so a track held
    at the edge of its rut stalls instead of creeping.
    """
    if travel_m >= cut_front_m:
        f = -resistance_n * min(max(speed_mps / v_reg_mps, 0.0), 1.0)
        return f, travel_m, cut_rear_m
    if travel_m <= cut_rear_m:
        f = resistance_n * min(max(-speed_mps / v_reg_mps, 0.0), 1.0)
        return f, cut_front_m, travel_m
    return 0.0, cut_front_m, cut_rear_m


# -- side wall ------------------------------------------------------------------------------
def passive_pressure_n_per_m(height_m, unit_weight_n_m3: float, cohesion_pa,
                             friction_angle_rad, n_phi=None):
    """Rankine passive thrust per unit wall length P = 1/2 gamma h^2 N_phi + 2 c h sqrt(N_phi)
    [N/m], N_phi = tan^2(45 deg + phi/2) (Wong Ch. 2, passive earth pressure). Broadcasts;
    ``n_phi`` may be given precomputed."""
    if n_phi is None:
        n_phi = np.tan(math.pi / 4.0 + np.asarray(friction_angle_rad) / 2.0) ** 2
    h = np.maximum(np.asarray(height_m, dtype=float), 0.0)
    return 0.5 * unit_weight_n_m3 * h * h * n_phi + 2.0 * cohesion_pa * h * np.sqrt(n_phi)


def berm_height_m(area_m2, repose_rad):
    """Height of a triangular berm of cross-section A at the angle of repose alpha against a
    vertical wall: A = h^2 / (2 tan alpha), so h = sqrt(2 A tan alpha) [m]."""
    return np.sqrt(2.0 * np.maximum(np.asarray(area_m2, dtype=float), 0.0)
                   * np.tan(repose_rad))


def advance_wall(d: np.ndarray, berm: np.ndarray, vy_cell: np.ndarray, ground_speed_mps,
                 sinkage_m: np.ndarray, dx_m: float, dt_s: float) -> None:
    """Advance the side walls' penetration d [m] and the berms [m^2] (in place).

    Side 0 is the track's left wall, side 1 its right wall; shapes (2, n_tracks, n_cells).
    Both states belong to the ground beside the track, which passes the hull at -V_x:
    first-order upwinding from the entry end (front when V_x > 0), fresh soil entering. A wall
    moving into the soil on its side (v_y > 0 for the left wall) penetrates it, d += |v_y| dt,
    and sweeps z |v_y| dt of soil per unit length into that side's berm; moving away it unloads
    (d decreases, never below 0: the soil does not pull). So in a turn the front of a track
    pushes the soil on one side and its rear the soil on the other (a resisting moment).
    ``ground_speed_mps`` has shape (n_tracks,).
    """
    v = np.asarray(ground_speed_mps, dtype=float)[:, None]
    fwd, bwd = v > 1e-4, v < -1e-4
    a = np.minimum(np.abs(v) * (dt_s / dx_m), 1.0)
    if fwd.all():  # the common case, without masks (same arithmetic)
        for f in (d, berm):
            f[..., 1:] += a * (f[..., :-1] - f[..., 1:])
            f[..., :1] -= a * f[..., :1]
    else:
        d += a * (_upwind(d, fwd, bwd) - d)
        berm += a * (_upwind(berm, fwd, bwd) - berm)
    step = vy_cell * dt_s
    left = np.maximum(step, 0.0)  # outward motion of the left wall
    d[0] += step
    d[1] -= step
    np.maximum(d, 0.0, out=d)
    berm[0] += sinkage_m * left
    berm[1] += sinkage_m * (left - step)


def wall_force_n_per_m(d: np.ndarray, berm: np.ndarray, sinkage_m: np.ndarray,
                       unit_weight_n_m3: float, cohesion_pa, friction_angle_rad,
                       max_height_m: float, min_mobilisation_m: float = 5e-4,
                       n_phi=None) -> np.ndarray:
    """Lateral side-wall force per unit track length on the track [N/m], shape of one side.

    On each side, passive pressure (`passive_pressure_n_per_m`) on a wall of height h = z +
    berm height (capped at ``max_height_m``: soil spills over the track), mobilised as
    1 - e^{-d/d_b} with d_b = max(h/10, ``min_mobilisation_m``); the left soil (side 0)
    pushes the track to -y, the right soil (side 1) to +y.
    """
    h = np.minimum(sinkage_m + berm_height_m(berm, friction_angle_rad), max_height_m)
    d_b = np.maximum(0.1 * h, min_mobilisation_m)
    pres = passive_pressure_n_per_m(h, unit_weight_n_m3, cohesion_pa, friction_angle_rad, n_phi)
    mobilised = pres * (1.0 - np.exp(-d / d_b))
    return mobilised[1] - mobilised[0]
