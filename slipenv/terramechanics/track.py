"""A skid-steer track on deformable soil: the Wong-Chiang shear field and its companions.

Plain functions of (state, kinematics, soil) for one track, or for the two tracks of a vehicle
at once (arrays of shape (n_tracks, n_cells)). They are the model's only text: the simulator
(``slipenv.sim.track_soil``) composes them once per physics substep, and the tests check them
against the closed forms. The local soil laws they share with the wheels (Mohr-Coulomb,
Janosi-Hanamoto, Bekker) are `janosi`'s and `bekker`'s, imported here. The fields are small,
so in numpy the cost would be the per-call overhead: the functions are loops over the cells,
compiled with numba from this text (``@njit(cache=True)``; `track_substep` composes them into
one compiled call per substep; ``slipenv.sim.track_soil.warm_up`` compiles or loads them).
``NUMBA_DISABLE_JIT=1`` runs the same text as plain Python.

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
    tau = (c + p tan phi)(1 - exp(-|j|/K)) (`janosi.shear_strength_pa`,
    `janosi.janosi_stress_pa`; per cell in `cell_forces`), directed against the local sliding
    velocity (Wong & Chiang's choice): the ``"resultant"`` shear law (`SHEAR_LAWS`, the
    default). The ``"decoupled"`` law (Ishigami, Miwa, Nagatani & Yoshida, J. Field Robotics
    24(3) (2007) 233-250, for the longitudinal and lateral shear of a wheel on Toyoura sand)
    takes each component from its own displacement, tau_x = tau_max (1 - exp(-|j_x|/K))
    sgn(j_x) and tau_y likewise, against the displacement, with the resultant capped at the
    Mohr-Coulomb strength tau_max (`decoupled_stress_pa`): a track sliding mostly sideways keeps
    the longitudinal stress of its longitudinal displacement. It is a law of a soil's shear
    deformation, so it applies where the soil deforms (`decoupled_cells`: the flag that also
    switches Bekker sinkage on); on rigid ground the contact is the tread's Coulomb friction,
    isotropic and against the sliding velocity, and the cells keep the resultant law there.
    The resultant law's direction is carried by a short "bristle" state e per belt element,
    de/dt = v_j - |v_j| e/e_max (the LuGre / brush-model form, Canudas de Wit et al. 1995):
    in sliding it aligns with v_j within a sliding distance of a few e_max, so the steady
    forces are Wong-Chiang's (tested within 5 %); at rest it is an elastic spring. A stress
    that jumped with the sign of v_j would be an infinitely stiff damper, which an explicit
    step at 240 Hz cannot integrate (the vehicle chatters and ratchets downhill); the
    decoupled law's sign is the displacement's, continuous through j = 0.
    At rest the soil springs get Kelvin-Voigt dampers on each cell's displacement rate
    (`soil_damper_forces`; LuGre's sigma_1 term), zero in any steady motion: along and across
    the stress for the resultant law (its Janosi spring and its direction spring), per
    component for the decoupled law (each component's own spring).
Normal pressure: the road-wheel loads, spread piecewise-linearly over the cells
    (`load_spread_matrix`, hat functions that conserve the load exactly).
Sinkage (Bekker's pressure-sinkage law, Wong Ch. 2): z0 = (p/(k_c/b + k_phi))^(1/n) per cell
    (`bekker.pressure_sinkage_m`), times Lyasko's
    slip-sinkage factor (1 + i)/(1 - 0.5 i) (`slip_sinkage_factor`; Lyasko, J. Terramech. 47
    (2010) 21-31).
Compaction resistance (Bekker; Wong Ch. 2 and 5): R_c = b (k_c/b + k_phi) z^(n+1)/(n+1) per
    track (`bekker.compaction_resistance_n` of its deepest cell), acting only while the
    track advances into soil it has not yet cut (a rut *state*: `rut_resistance_n`): rate
    independent, zero in its own rut, so a stalled track does not creep.
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
from numba import njit

from slipenv.contracts.compiled_cache import refresh_stale_cache
from slipenv.terramechanics.bekker import compaction_resistance_n, pressure_sinkage_m
from slipenv.terramechanics.bekker import slip_sinkage_factor as bekker_slip_sinkage
from slipenv.terramechanics.janosi import janosi_stress_pa, shear_strength_pa

# the track's kernels carry the compiled Bekker and Janosi laws they call
refresh_stale_cache(__file__, "bekker.py", "janosi.py")

__all__ = [
    "DIRECTION_SPEED_MPS",
    "UPWIND_SPEED_MPS",
    "GROUND_SPEED_MPS",
    "load_spread_matrix",
    "sliding_velocity",
    "shear_direction",
    "advance_shear",
    "steady_shear_displacement",
    "steady_track_forces",
    "SHEAR_LAWS",
    "decoupled_stress_pa",
    "decoupled_cells",
    "cell_forces",
    "soil_damper_forces",
    "slip_sinkage_factor",
    "rut_resistance_n",
    "passive_pressure_n_per_m",
    "passive_coefficient",
    "berm_height_m",
    "advance_wall",
    "wall_force_n_per_m",
    "SOIL_ROWS",
    "SETTING_NAMES",
    "track_substep",
]

DIRECTION_SPEED_MPS = 2e-3
"""[m/s] Below this sliding speed the stress direction blends from -v_j to -j (at rest the soil
is a spring along its displacement; the sliding direction is undefined)."""

UPWIND_SPEED_MPS = 1e-3
"""[m/s] Belt speeds below this are "at rest" for the shear field: no advection, every face
integrates its neighbouring cells' source (the soil spring)."""

GROUND_SPEED_MPS = 1e-4
"""[m/s] Ground speeds below this leave the side walls and berms where they are."""

_TINY = 1e-300  # guards the unit vectors of a zero displacement or stress

# The shared soil laws, compiled from their one text (`janosi`, `bekker`) for the cell loops.
_strength = njit(cache=True)(shear_strength_pa)
_janosi = njit(cache=True)(janosi_stress_pa)
_pressure_sinkage = njit(cache=True)(pressure_sinkage_m)
_compaction = njit(cache=True)(compaction_resistance_n)

SOIL_ROWS = ("width_m", "inv_cell_area_m2", "k_c", "k_phi", "n_exp", "cohesion_pa", "tan_phi",
             "shear_modulus_m", "friction_angle_rad")
"""Rows of :func:`track_substep`'s ``soil`` array (one column per track): track width b,
1/(b dx), Bekker's k_c, k_phi and n, cohesion c, tan phi, Janosi's K, phi."""
(S_WIDTH, S_INV_AREA, S_KC, S_KPHI, S_N, S_C, S_TAN_PHI, S_K, S_PHI) = range(len(SOIL_ROWS))
SETTING_NAMES = ("dx_m", "dt_s", "direction_length_m", "damping_ratio", "cell_mass_kg",
                 "unit_weight_n_m3", "max_wall_height_m", "shear_law",
                 "longitudinal_modulus_ratio", "lateral_modulus_ratio")
"""Entries of :func:`track_substep`'s ``settings`` array: cell length, substep, e_max, the
dampers' zeta and cell mass, the soil's unit weight, the wall height where soil spills, the
shear law's index in `SHEAR_LAWS`, the decoupled law's K_x/K and K_y/K (K the soil's)."""
(P_DX, P_DT, P_E_MAX, P_ZETA, P_CELL_MASS, P_GAMMA, P_MAX_WALL,
 P_SHEAR_LAW, P_LONGITUDINAL_K, P_LATERAL_K) = range(len(SETTING_NAMES))
SHEAR_LAWS = ("resultant", "decoupled")
"""The track's shear laws (module docstring): ``"resultant"``, Wong-Chiang's tau(|j|) against
the sliding velocity; ``"decoupled"``, Ishigami et al.'s per-component law
(`decoupled_stress_pa`)."""


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
    return m


# -- shear ---------------------------------------------------------------------------------
@njit(cache=True)
def sliding_velocity(track_speed_mps: np.ndarray, belt_speed_mps: np.ndarray,
                     lateral_speed_mps: np.ndarray, yaw_rate_rad_s: float, x_cell_m: np.ndarray,
                     out: np.ndarray | None = None) -> np.ndarray:
    """Sliding velocity of the belt over the ground at the cell centres [m/s], (2, n_tracks,
    n_cells): v_j = (V_x,i - u_i, V_y,i + Omega x) (Wong & Chiang 2001; Wong Ch. 7).

    ``track_speed_mps`` V_x,i = V_x - Omega y_i (the ground speed of track i's centre line
    along the hull's x), ``belt_speed_mps`` u_i, ``lateral_speed_mps`` V_y,i (the hull's
    lateral speed at the track's height), arrays of length n_tracks; ``x_cell_m`` (n_tracks,
    n_cells) the cell centres. Written into ``out`` when given.
    """
    nt, nc = x_cell_m.shape
    if out is None:
        out = np.empty((2, nt, nc))
    for i in range(nt):
        slide = track_speed_mps[i] - belt_speed_mps[i]
        for c in range(nc):
            out[0, i, c] = slide
            out[1, i, c] = x_cell_m[i, c] * yaw_rate_rad_s + lateral_speed_mps[i]
    return out


def shear_direction(vx, vy, jx, jy, v_reg: float = DIRECTION_SPEED_MPS):
    """Unit vector (dx, dy) *along which the soil resists*: the stress is -tau (dx, dy).

    (dx, dy) is the sliding velocity's direction v_j/|v_j| (Wong & Chiang) for |v_j| >= v_reg;
    below, the sliding velocity's weight |v_j|/v_reg blends it with the displacement's direction
    j/|j| (at rest the soil acts as a spring along its displacement). Zero where both vanish.
    This is the steady law of :func:`steady_track_forces`; the simulation carries the direction
    as a state instead (:func:`advance_shear`, :func:`cell_forces`).
    """
    vx, vy, jx, jy = (np.asarray(a, dtype=float) for a in (vx, vy, jx, jy))
    speed = np.hypot(vx, vy)
    jn = np.hypot(jx, jy)
    w = np.minimum(speed / v_reg, 1.0)
    inv_j = np.where(jn > 0.0, 1.0 / np.maximum(jn, _TINY), 0.0)
    # v/v_reg has length w; the displacement part has length (1 - w).
    inv_v = np.where(speed < v_reg, 1.0 / v_reg, 1.0 / np.maximum(speed, _TINY))
    dx = vx * inv_v + (1.0 - w) * jx * inv_j
    dy = vy * inv_v + (1.0 - w) * jy * inv_j
    norm = np.hypot(dx, dy)
    inv = np.where(norm > 0.0, 1.0 / np.maximum(norm, _TINY), 0.0)
    return dx * inv, dy * inv


def decoupled_stress_pa(jx_m: float, jy_m: float, strength_pa: float, shear_modulus_m: float,
                        lateral_shear_modulus_m: float) -> tuple[float, float, float, float]:
    """Ishigami et al.'s decoupled shear stress (tau_x, tau_y) [Pa] of a displacement (j_x, j_y)
    [m], along the displacement (the soil resists with -tau), and each component's tangent
    stiffness d tau_x/d j_x, d tau_y/d j_y [Pa/m].

    Each component is Janosi's law of its own displacement, tau_x = tau_max (1 - exp(-|j_x|/K_x))
    sgn(j_x), tau_y = tau_max (1 - exp(-|j_y|/K_y)) sgn(j_y) (Ishigami, Miwa, Nagatani &
    Yoshida, J. Field Robotics 24(3) (2007), the shear stresses of a wheel's contact with
    separate moduli K_x, K_y: ``shear_modulus_m`` and ``lateral_shear_modulus_m``), and
    the resultant is capped at the Mohr-Coulomb strength tau_max = c + p tan phi (Wong Eq.
    2.54; ``strength_pa``): independent components would otherwise reach sqrt 2 tau_max on a
    diagonal, more than the soil can carry. The sign comes from the displacement itself, not
    from the sliding direction, so the law is a function of j alone (a spring at rest). Pure
    longitudinal or lateral displacement gives the resultant law's tau(|j|).

    The stiffnesses are the diagonal of the law's Jacobian, each component's derivative by its
    own displacement (what a damper per component needs, `soil_damper_forces`): below the cap
    (tau_max - |tau_x|)/K_x = tau_max e^{-|j_x|/K_x}/K_x, tau_max/K_x at j = 0; on the cap,
    where tau = tau_max g/|g| with g the uncapped (tau_x, tau_y)/tau_max, d tau_x/d j_x =
    tau_max g_x' g_y^2/|g|^3 with g_x' = e^{-|j_x|/K_x}/K_x (the other component holds the
    cap's share), and likewise for y.
    """
    inv_kx = 1.0 / shear_modulus_m
    inv_ky = 1.0 / lateral_shear_modulus_m
    decay_x = math.exp(-abs(jx_m) * inv_kx)
    decay_y = math.exp(-abs(jy_m) * inv_ky)
    gx = math.copysign(-math.expm1(-abs(jx_m) * inv_kx), jx_m)
    gy = math.copysign(-math.expm1(-abs(jy_m) * inv_ky), jy_m)
    mag2 = gx * gx + gy * gy
    if mag2 > 1.0:  # the soil carries no more than its strength
        inv_mag = 1.0 / math.sqrt(mag2)
        bend = strength_pa * inv_mag * inv_mag * inv_mag
        return (strength_pa * gx * inv_mag, strength_pa * gy * inv_mag,
                bend * decay_x * inv_kx * gy * gy, bend * decay_y * inv_ky * gx * gx)
    return (strength_pa * gx, strength_pa * gy, strength_pa * decay_x * inv_kx,
            strength_pa * decay_y * inv_ky)


_decoupled = njit(cache=True)(decoupled_stress_pa)


@njit(cache=True)
def decoupled_cells(shear_law: float, deformable: float) -> bool:
    """Whether a track's cells take the decoupled law: ``shear_law`` (the index in
    `SHEAR_LAWS`) names it and the soil under the track deforms (``deformable`` > 0.5, the
    flag that switches Bekker sinkage on; a soil map may blend it).

    Ishigami et al.'s components are the shear deformation of a soil layer under the contact,
    each displacement component building its own stress (J. Field Robotics 24(3) (2007)). On
    rigid ground there is no such layer: the stress is the tread's Coulomb friction, isotropic
    and against the sliding velocity, Wong-Chiang's resultant law with the tread's millimetre
    K. There the decoupled components would both saturate in a turn and point the stress along
    a diagonal whatever the sliding direction.
    """
    return shear_law == 1.0 and deformable > 0.5


@njit(cache=True)
def advance_shear(j: np.ndarray, e: np.ndarray, v_cell: np.ndarray, belt_speed_mps: np.ndarray,
                  yaw_rate_rad_s: float, dx_m: float, dt_s: float,
                  direction_length_m: float) -> None:
    """One explicit step of dj/dt - u dj/dx = v_j - Omega z x j on cell faces, and of the
    stress-direction state e (in place).

    Parameters
    ----------
    j : ndarray, shape (2, n_tracks, n_cells + 1)
        Shear displacement (x, y components) [m] at the faces, face 0 at the front (x = L/2),
        face n at the rear.
    e : ndarray, shape (2, n_tracks, n_cells)
        The stress-direction state [m] at the cell centres (the stress is -tau e/|e|,
        :func:`cell_forces`), advected the same way with the source v_j - |v_j| e / e_max -
        Omega z x e (the relaxation implicit): it turns to a new sliding direction within a
        sliding distance of a few e_max, and at rest it is an elastic spring.
    v_cell : ndarray, shape (2, n_tracks, n_cells)
        Sliding velocity of the belt over the ground at the cell centres [m/s]
        (:func:`sliding_velocity`).
    belt_speed_mps : ndarray, shape (n_tracks,)
        u_i: belt speed along the ground run, > 0 when it moves rearwards (forward drive).
    yaw_rate_rad_s : float
        Omega [rad/s] (the rotation term keeps j in the ground frame while stored in hull axes;
        it produces Wong-Chiang's cos/sin terms).
    dx_m, dt_s : float
        Cell length [m] and time step [s] (|u| dt/dx < 1 for stability).
    direction_length_m : float
        e_max [m], the sliding distance over which the stress direction turns.

    Upwinding: for u > 0 the front face is the entry (j = 0) and face f takes the flux from
    face f-1 with the source of the cell between them (midpoint rule: exact for the linear v_j
    of a rigid hull); for u < 0 mirrored; at |u| below ``UPWIND_SPEED_MPS`` every face
    integrates the mean source of its neighbouring cells. Every source is taken from the
    fields before the step.
    """
    nt, nc = e.shape[1], e.shape[2]
    courant = dt_s / dx_m
    rot = 0.5 * yaw_rate_rad_s * dt_s  # Omega z x j at a cell: the mean of its faces
    rot_e = yaw_rate_rad_s * dt_s
    leak_scale = dt_s / direction_length_m
    src = np.empty((2, nc))
    e_src = np.empty((2, nc))
    for i in range(nt):
        # Sources, times dt: v_j plus the rotation of j (face means at the cells) and of e.
        for c in range(nc):
            dvx = dt_s * v_cell[0, i, c]
            dvy = dt_s * v_cell[1, i, c]
            src[0, c] = rot * (j[1, i, c] + j[1, i, c + 1]) + dvx
            src[1, c] = -rot * (j[0, i, c] + j[0, i, c + 1]) + dvy
            e_src[0, c] = rot_e * e[1, i, c] + dvx
            e_src[1, c] = -rot_e * e[0, i, c] + dvy
        u = belt_speed_mps[i]
        a = abs(u) * courant
        for k in range(2):
            if u > UPWIND_SPEED_MPS:  # entry at the front face: sweep rearwards from the rear
                for f in range(nc, 0, -1):
                    j[k, i, f] += a * (j[k, i, f - 1] - j[k, i, f]) + src[k, f - 1]
                j[k, i, 0] = 0.0
                for c in range(nc - 1, 0, -1):
                    e[k, i, c] += a * (e[k, i, c - 1] - e[k, i, c]) + e_src[k, c]
                e[k, i, 0] += e_src[k, 0] - a * e[k, i, 0]
            elif u < -UPWIND_SPEED_MPS:  # mirrored: entry at the rear face
                for f in range(nc):
                    j[k, i, f] += a * (j[k, i, f + 1] - j[k, i, f]) + src[k, f]
                j[k, i, nc] = 0.0
                for c in range(nc - 1):
                    e[k, i, c] += a * (e[k, i, c + 1] - e[k, i, c]) + e_src[k, c]
                e[k, i, nc - 1] += e_src[k, nc - 1] - a * e[k, i, nc - 1]
            else:  # at rest: each face integrates the mean source of its neighbouring cells
                j[k, i, 0] += src[k, 0]
                for f in range(1, nc):
                    j[k, i, f] += 0.5 * (src[k, f - 1] + src[k, f])
                j[k, i, nc] += src[k, nc - 1]
                for c in range(nc):
                    e[k, i, c] += e_src[k, c]
        for c in range(nc):
            leak = math.hypot(v_cell[0, i, c], v_cell[1, i, c]) * leak_scale + 1.0
            e[0, i, c] /= leak
            e[1, i, c] /= leak


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
                        shear_modulus_m: float, n_quad: int = 4001,
                        shear_law: str = "resultant",
                        lateral_shear_modulus_m: float | None = None
                        ) -> tuple[float, float, float]:
    """The Wong-Chiang integrals F_x = b int tau_x dx, F_y = b int tau_y dx and
    M_z = b int (x tau_y - y_i tau_x) dx [N, N, N m] of one track under uniform pressure, in
    steady motion (Wong & Chiang 2001; Wong, Theory of Ground Vehicles, Ch. 7), with the stress
    of ``shear_law`` (`SHEAR_LAWS`): tau(|j|) against the sliding velocity, or the decoupled
    components against the displacement (`decoupled_stress_pa`)."""
    if shear_law not in SHEAR_LAWS:
        raise ValueError(f"shear_law={shear_law!r} must be one of {SHEAR_LAWS}")
    x = np.linspace(length_m / 2.0, -length_m / 2.0, n_quad)
    jx, jy = steady_shear_displacement(x, vx, vy, yaw_rate, y_track_m, belt_speed_mps,
                                       length_m, n_quad)
    strength = shear_strength_pa(pressure_pa, cohesion_pa, tan_phi)
    if shear_law == "decoupled":
        k_y = shear_modulus_m if lateral_shear_modulus_m is None else lateral_shear_modulus_m
        stress = [decoupled_stress_pa(a, b, float(strength), shear_modulus_m, k_y)[:2]
                  for a, b in zip(jx, jy, strict=True)]
        tx, ty = -np.array(stress).T
    else:
        vxs = np.full_like(x, vx - yaw_rate * y_track_m - belt_speed_mps)
        vys = vy + yaw_rate * x
        dxn, dyn = shear_direction(vxs, vys, jx, jy)
        tau = janosi_stress_pa(np.hypot(jx, jy), strength, shear_modulus_m)
        tx, ty = -tau * dxn, -tau * dyn
    h = length_m / (n_quad - 1)
    trap = lambda f: float(h * (f.sum() - 0.5 * (f[0] + f[-1])))  # noqa: E731
    return (width_m * trap(tx), width_m * trap(ty),
            width_m * trap(x * ty - y_track_m * tx))


@njit(cache=True)
def cell_forces(j: np.ndarray, e: np.ndarray, pressure_pa: np.ndarray, width_m: np.ndarray,
                dx_m: float, cohesion_pa: np.ndarray, tan_phi: np.ndarray,
                shear_modulus_m: np.ndarray, out: np.ndarray | None = None,
                decoupled: np.ndarray | None = None,
                lateral_stiffness: np.ndarray | None = None,
                longitudinal_modulus_ratio: float = 1.0,
                lateral_modulus_ratio: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Shear force of each cell on the track and its tangent stiffness.

    A cell's j is the mean of its two faces, e its centre value; the stress tau(|j|) is
    Janosi-Hanamoto's (`janosi_stress_pa`) with the Mohr-Coulomb strength
    (`shear_strength_pa`), directed against e; the force
    f = -tau e/|e| b dx (midpoint rule) [N], shape (2, n_tracks, n_cells), written into
    ``out`` when given. The stiffness k = b dx d tau/d|j| = b dx (q_max - tau)/K [N/m], shape
    (n_tracks, n_cells), is what :func:`soil_damper_forces` needs. The soil (``width_m``,
    ``cohesion_pa``, ``tan_phi``, ``shear_modulus_m``) is given per track, arrays of length
    n_tracks. On the tracks whose ``decoupled`` flag (length n_tracks, `decoupled_cells`) is
    set the stress is Ishigami et al.'s decoupled law instead (`decoupled_stress_pa`: each
    component of its own displacement, against j; e unused), f = -tau b dx, and the stiffness
    is each component's own, b dx d tau_x/d j_x returned and b dx d tau_y/d j_y written into
    ``lateral_stiffness`` (n_tracks, n_cells) when given (0 on the other tracks), with the
    moduli K_x = ``longitudinal_modulus_ratio`` K and K_y = ``lateral_modulus_ratio`` K.
    """
    nt, nc = e.shape[1], e.shape[2]
    if out is None:
        out = np.empty((2, nt, nc))
    stiffness = np.empty((nt, nc))
    for i in range(nt):
        area = width_m[i] * dx_m
        spring = area / shear_modulus_m[i]
        own = decoupled is not None and decoupled[i]
        for c in range(nc):
            jx = (j[0, i, c] + j[0, i, c + 1]) * 0.5
            jy = (j[1, i, c] + j[1, i, c + 1]) * 0.5
            strength = _strength(pressure_pa[i, c], cohesion_pa[i], tan_phi[i])
            if own:
                tx, ty, kx, ky = _decoupled(jx, jy, float(strength),
                                            shear_modulus_m[i] * longitudinal_modulus_ratio,
                                            shear_modulus_m[i] * lateral_modulus_ratio)
                stiffness[i, c] = kx * area
                if lateral_stiffness is not None:
                    lateral_stiffness[i, c] = ky * area
                out[0, i, c] = -tx * area
                out[1, i, c] = -ty * area
                continue
            if lateral_stiffness is not None:
                lateral_stiffness[i, c] = 0.0
            j_abs = math.hypot(j[0, i, c] + j[0, i, c + 1], j[1, i, c] + j[1, i, c + 1]) * 0.5
            tau = _janosi(j_abs, strength, shear_modulus_m[i])
            stiffness[i, c] = (strength - tau) * spring
            scale = tau * -area / max(math.hypot(e[0, i, c], e[1, i, c]), _TINY)
            out[0, i, c] = e[0, i, c] * scale
            out[1, i, c] = e[1, i, c] * scale
    return out, stiffness


@njit(cache=True)
def soil_damper_forces(dj_m: np.ndarray, shear_force_n: np.ndarray,
                       stiffness_n_per_m: np.ndarray, direction_length_m: float,
                       damping_ratio: float, cell_mass_kg: float, dt_s: float,
                       lateral_stiffness_n_per_m: np.ndarray | None = None,
                       decoupled: np.ndarray | None = None) -> np.ndarray:
    """Kelvin-Voigt dampers of the soil springs at rest, per cell [N], shape of ``dj_m``.

    The damper acts on the change ``dj_m`` (2, n_tracks, n_cells) of each cell's displacement
    over the step at a fixed hull position: zero in any steady motion (driving, steady
    turning), so it never alters the force law there; it only damps transients (LuGre's
    sigma_1 term, Canudas de Wit et al., IEEE TAC 40 (1995) 419-425). Each damping
    coefficient is 2 zeta sqrt(k m) for the cell's mass share m and the spring's tangent
    stiffness k, capped at half the explicit stability limit m/dt.

    The resultant law's springs (``lateral_stiffness_n_per_m`` not given): along the stress
    (``shear_force_n``, from :func:`cell_forces`) k is the Janosi tangent
    ``stiffness_n_per_m``, across it the direction state's |f|/e_max; a cell without stress
    has only the across part, which is then zero. The decoupled law's (given): its springs are
    the two components, each of its own displacement, so each component of ``dj_m`` is damped
    with its own tangent, x with ``stiffness_n_per_m`` and y with ``lateral_stiffness_n_per_m``
    (`decoupled_stress_pa`); the law has no direction spring. With ``decoupled`` (per track,
    `decoupled_cells`) given too, only the flagged tracks' cells are damped per component,
    the others as the resultant law's.
    """
    nt, nc = dj_m.shape[1], dj_m.shape[2]
    force = np.empty((2, nt, nc))
    gain = 2.0 * damping_ratio * math.sqrt(cell_mass_kg)
    cap = 0.5 * cell_mass_kg / dt_s
    per_step = -1.0 / dt_s
    inv_e = 1.0 / direction_length_m
    for i in range(nt):
        own = lateral_stiffness_n_per_m is not None and (decoupled is None or decoupled[i])
        for c in range(nc):
            if own and lateral_stiffness_n_per_m is not None:
                x_rate = min(math.sqrt(stiffness_n_per_m[i, c]) * gain, cap) * per_step
                y_rate = min(math.sqrt(lateral_stiffness_n_per_m[i, c]) * gain, cap) * per_step
                force[0, i, c] = dj_m[0, i, c] * x_rate
                force[1, i, c] = dj_m[1, i, c] * y_rate
                continue
            fx, fy = shear_force_n[0, i, c], shear_force_n[1, i, c]
            tau = math.hypot(fx, fy)
            # damping coefficients / dt, along and across the stress
            along_rate = min(math.sqrt(stiffness_n_per_m[i, c]) * gain, cap) * per_step
            across_rate = min(math.sqrt(tau * inv_e) * gain, cap) * per_step
            inv_tau = -1.0 / max(tau, _TINY)  # along the stress (0 if none)
            nx, ny = fx * inv_tau, fy * inv_tau
            along = dj_m[0, i, c] * nx + dj_m[1, i, c] * ny
            ax, ay = along * nx, along * ny
            force[0, i, c] = (dj_m[0, i, c] - ax) * across_rate + ax * along_rate
            force[1, i, c] = (dj_m[1, i, c] - ay) * across_rate + ay * along_rate
    return force


# -- sinkage and compaction ------------------------------------------------------------------
def slip_sinkage_factor(slip):
    """Lyasko's slip-sinkage factor z/z0 = (1 + i)/(1 - 0.5 i), slip i clipped to [0, 1]
    (Lyasko, "Slip sinkage effect in soil-vehicle mechanics", J. Terramech. 47 (2010) 21-31),
    element by element: the wheels' C law (`bekker.slip_sinkage_factor`), one slip per track."""
    slip = np.asarray(slip, dtype=float)
    return np.array([bekker_slip_sinkage(float(i)) for i in slip.ravel()]).reshape(slip.shape)


@njit(cache=True)
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
@njit(cache=True)
def passive_pressure_n_per_m(height_m: float, unit_weight_n_m3: float, cohesion_pa: float,
                             n_phi: float) -> float:
    """Rankine passive thrust per unit wall length P = 1/2 gamma h^2 N_phi + 2 c h sqrt(N_phi)
    [N/m] of a wall of height h (negative counts as 0), N_phi = tan^2(45 deg + phi/2)
    (`passive_coefficient`; Wong Ch. 2, passive earth pressure)."""
    h = max(height_m, 0.0)
    return (h * (0.5 * unit_weight_n_m3 * n_phi) + 2.0 * cohesion_pa * math.sqrt(n_phi)) * h


@njit(cache=True)
def passive_coefficient(friction_angle_rad: float) -> float:
    """Rankine's passive earth pressure coefficient N_phi = tan^2(45 deg + phi/2) (Wong Ch. 2)."""
    return math.tan(math.pi / 4.0 + friction_angle_rad / 2.0) ** 2


@njit(cache=True)
def berm_height_m(area_m2: float, repose_rad: float) -> float:
    """Height of a triangular berm of cross-section A at the angle of repose alpha against a
    vertical wall: A = h^2 / (2 tan alpha), so h = sqrt(2 A tan alpha) [m]."""
    return math.sqrt(max(area_m2, 0.0) * (2.0 * math.tan(repose_rad)))


@njit(cache=True)
def advance_wall(walls: np.ndarray, vy_cell: np.ndarray, ground_speed_mps: np.ndarray,
                 sinkage_m: np.ndarray, dx_m: float, dt_s: float) -> None:
    """Advance the side walls' penetration d [m] and the berms [m^2] (in place).

    ``walls`` has shape (2, 2, n_tracks, n_cells): ``walls[0]`` the penetration d,
    ``walls[1]`` the berm cross-section, each with side 0 the track's left wall and side 1 its
    right wall. Both states belong to the ground beside the track, which passes the hull at
    -V_x: first-order upwinding from the entry end (front when V_x > 0), fresh soil entering.
    A wall moving into the soil on its side (v_y > 0 for the left wall) penetrates it, d +=
    |v_y| dt, and sweeps z |v_y| dt of soil per unit length into that side's berm; moving away
    it unloads (d decreases, never below 0: the soil does not pull). So in a turn the front of
    a track pushes the soil on one side and its rear the soil on the other (a resisting
    moment). ``ground_speed_mps`` (V_x of each track) has length n_tracks, ``vy_cell`` and
    ``sinkage_m`` shape (n_tracks, n_cells).
    """
    nt, nc = vy_cell.shape
    courant = dt_s / dx_m
    for i in range(nt):
        v = ground_speed_mps[i]
        a = min(abs(v) * courant, 1.0)
        for q in range(2):
            for s in range(2):
                w = walls[q, s, i]
                if v > GROUND_SPEED_MPS:  # from the front: sweep from the rear
                    for c in range(nc - 1, 0, -1):
                        w[c] += a * (w[c - 1] - w[c])
                    w[0] -= a * w[0]
                elif v < -GROUND_SPEED_MPS:
                    for c in range(nc - 1):
                        w[c] += a * (w[c + 1] - w[c])
                    w[nc - 1] -= a * w[nc - 1]
        for c in range(nc):
            step = vy_cell[i, c] * dt_s
            left = max(step, 0.0)  # outward motion of the left wall
            walls[0, 0, i, c] = max(walls[0, 0, i, c] + step, 0.0)
            walls[0, 1, i, c] = max(walls[0, 1, i, c] - step, 0.0)
            walls[1, 0, i, c] += sinkage_m[i, c] * left
            walls[1, 1, i, c] += (left - step) * sinkage_m[i, c]  # the right wall's


@njit(cache=True)
def wall_force_n_per_m(walls: np.ndarray, sinkage_m: np.ndarray, unit_weight_n_m3: float,
                       cohesion_pa: np.ndarray, friction_angle_rad: np.ndarray,
                       max_height_m: float, min_mobilisation_m: float = 5e-4) -> np.ndarray:
    """Lateral side-wall force per unit track length on the track [N/m], (n_tracks, n_cells).

    On each side, passive pressure (`passive_pressure_n_per_m`) on a wall of height h = z +
    berm height (`berm_height_m`, capped at ``max_height_m``: soil spills over the track),
    mobilised as 1 - e^{-d/d_b} with d_b = max(h/10, ``min_mobilisation_m``); the left soil
    (side 0) pushes the track to -y, the right soil (side 1) to +y. ``walls`` as in
    :func:`advance_wall`; the soil (``cohesion_pa``, ``friction_angle_rad``) per track.
    """
    nt, nc = sinkage_m.shape
    force = np.empty((nt, nc))
    for i in range(nt):
        phi = friction_angle_rad[i]
        n_phi = passive_coefficient(phi)
        for c in range(nc):
            args = (sinkage_m[i, c], phi, max_height_m, unit_weight_n_m3, cohesion_pa[i], n_phi,
                    min_mobilisation_m)
            force[i, c] = (_side_force(walls[0, 0, i, c], walls[1, 0, i, c], *args)
                           - _side_force(walls[0, 1, i, c], walls[1, 1, i, c], *args))
    return force


@njit(cache=True)
def _side_force(penetration_m: float, berm_m2: float, sinkage_m: float, phi: float,
                max_height_m: float, unit_weight_n_m3: float, cohesion_pa: float, n_phi: float,
                min_mobilisation_m: float) -> float:
    """-P (1 - e^{-d/d_b}) of one side wall [N/m] (:func:`wall_force_n_per_m`)."""
    h = min(berm_height_m(berm_m2, phi) + sinkage_m, max_height_m)
    pres = passive_pressure_n_per_m(h, unit_weight_n_m3, cohesion_pa, n_phi)
    d_b = max(h * 0.1, min_mobilisation_m)  # the mobilisation length
    return math.expm1(-(penetration_m / d_b)) * pres


# -- one substep -----------------------------------------------------------------------------
@njit(cache=True)
def track_substep(load_n: np.ndarray, belt_speed_mps: np.ndarray, track_speed_mps: np.ndarray,
                  lateral_speed_mps: np.ndarray, yaw_rate_rad_s: float,
                  slip_sinkage: np.ndarray, deformable: np.ndarray, spread: np.ndarray,
                  reduce: np.ndarray, x_cell_m: np.ndarray, soil: np.ndarray,
                  settings: np.ndarray, j: np.ndarray, e: np.ndarray,
                  walls: np.ndarray, out: np.ndarray, sinkage_m: np.ndarray, sums: np.ndarray,
                  compaction_n: np.ndarray) -> None:
    """The functions above composed for one substep of the tracks of a vehicle (in place).

    Inputs: the road-wheel loads ``load_n`` [N]; per track the belt speed u_i, the ground speed
    V_x,i of its centre line and its lateral speed V_y,i [m/s] (:func:`sliding_velocity`), its
    slip-sinkage factor (:func:`slip_sinkage_factor`) and 1 on deformable soil, 0 on rigid;
    the yaw rate [rad/s]. Constant over the substep: ``spread`` (n_tracks n_cells, n_wheels)
    the road-wheel loads' shares of each cell (:func:`load_spread_matrix` per track),
    ``reduce`` (n_sums, n_tracks n_cells) the weighted sums wanted of the cell outputs,
    ``x_cell_m`` (n_tracks, n_cells) the cell centres, ``soil`` (`SOIL_ROWS` rows, one column
    per track) and ``settings`` (`SETTING_NAMES`).

    Steps: cell pressures from the loads (``spread``, per unit cell area); Bekker's
    sinkage times the slip-sinkage factor; the shear field and direction state
    (:func:`advance_shear`); the cell shear forces (:func:`cell_forces`, with the shear law
    ``settings`` names on each track whose soil deforms, `decoupled_cells`, the resultant law
    on rigid ground) and the soil dampers on the change of the cells' displacement
    (:func:`soil_damper_forces`); the side walls (:func:`advance_wall`,
    :func:`wall_force_n_per_m`); the compaction resistance of each track's deepest cell
    (`bekker.compaction_resistance_n`).

    Outputs: ``out`` (6, n_tracks, n_cells): per cell the total force x, y on the track, the
    shear force x, y, the side-wall force and the damper force's magnitude [N];
    ``sinkage_m`` (n_tracks, n_cells); ``sums`` (n_sums, 6) = ``reduce`` applied to each of
    the six outputs; ``compaction_n`` per track [N].
    """
    nt, nc = sinkage_m.shape
    width, kc, kphi, n_exp = soil[S_WIDTH], soil[S_KC], soil[S_KPHI], soil[S_N]
    dx, dt = settings[P_DX], settings[P_DT]
    pressure = np.empty((nt, nc))
    for i in range(nt):
        for c in range(nc):
            row = i * nc + c
            q = 0.0
            for k in range(load_n.size):
                if spread[row, k] != 0.0:  # each cell takes the loads of two road wheels
                    q += spread[row, k] * load_n[k]
            pressure[i, c] = q * soil[S_INV_AREA, i]
            z = _pressure_sinkage(pressure[i, c], width[i], kc[i], kphi[i], n_exp[i])
            sinkage_m[i, c] = z * slip_sinkage[i] * deformable[i]
    j_old = j[:, :, :-1] + j[:, :, 1:]  # twice the cells' displacement before the step
    v_cell = sliding_velocity(track_speed_mps, belt_speed_mps, lateral_speed_mps,
                              yaw_rate_rad_s, x_cell_m)
    advance_shear(j, e, v_cell, belt_speed_mps, yaw_rate_rad_s, dx, dt, settings[P_E_MAX])
    decoupled = np.empty(nt, dtype=np.bool_)
    for i in range(nt):
        decoupled[i] = decoupled_cells(settings[P_SHEAR_LAW], deformable[i])
    lateral = np.empty((nt, nc))
    f_shear, stiffness = cell_forces(j, e, pressure, width, dx, soil[S_C], soil[S_TAN_PHI],
                                     soil[S_K], out[2:4], decoupled, lateral,
                                     settings[P_LONGITUDINAL_K], settings[P_LATERAL_K])
    dj = j[:, :, :-1] + j[:, :, 1:]
    dj -= j_old
    dj *= 0.5
    f_damp = soil_damper_forces(dj, f_shear, stiffness, settings[P_E_MAX], settings[P_ZETA],
                                settings[P_CELL_MASS], dt, lateral, decoupled)
    advance_wall(walls, v_cell[1], track_speed_mps, sinkage_m, dx, dt)
    f_wall = wall_force_n_per_m(walls, sinkage_m, settings[P_GAMMA], soil[S_C], soil[S_PHI],
                                settings[P_MAX_WALL])
    for i in range(nt):
        for c in range(nc):
            out[0, i, c] = f_shear[0, i, c] + f_damp[0, i, c]
            out[1, i, c] = f_shear[1, i, c] + f_damp[1, i, c] + f_wall[i, c] * dx
            out[4, i, c] = f_wall[i, c] * dx
            out[5, i, c] = math.hypot(f_damp[0, i, c], f_damp[1, i, c])
        deepest = sinkage_m[i].max()
        compaction_n[i] = _compaction(deepest, width[i], kc[i], kphi[i], n_exp[i])
    flat = out.reshape(6, nt * nc)
    for r in range(sums.shape[0]):
        for col in range(6):
            sums[r, col] = 0.0
        for m in range(nt * nc):
            weight = reduce[r, m]
            if weight != 0.0:  # each sum takes the cells of one road wheel or one track
                for col in range(6):
                    sums[r, col] += weight * flat[col, m]

