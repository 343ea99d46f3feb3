"""Inject the Wong-Chiang track model (``slipenv.terramechanics.track``) every physics substep.

For a tracked vehicle whose spec selects ``track_model="wong_chiang"``. The road wheels keep
carrying the normal contact (PyBullet's compliant sphere contacts); this injector replaces their
per-wheel shear by one shear field per track:

1. read the road-wheel loads (``getContactPoints``), the hull twist and the belt speeds
   (one batched query each);
2. spread the loads over ``n_cells`` cells per track (pressure p(x));
3. advance the shear displacement field j(x) and the stress-direction state, the side walls'
   penetration and berms, and the rut state;
4. compute the cell shear forces (Janosi with Mohr-Coulomb, against the sliding velocity), the
   side-wall (bulldozing) force and the compaction resistance;
5. apply each road wheel's share of the cells' shear *at that road wheel's contact point*, so
   the channel motor feels r sum F_x as the sprocket would; the residual yaw moment of the
   lateral forces about the road wheels (exactly what the lumping misses) as one torque per
   track on the hull; the compaction resistance at the track's centre line on the hull.

It exposes the reading interface of ``WheelSoilInjector`` (``contact_state``, ``reset``,
``sample_soil``, ``soil_at_wheel``, ``rolling_radius_m``) with per-road-wheel arrays, each road
wheel reporting its track's slip and its share of the forces.

The soil "spring" at rest (j integrates the sliding velocity) gets a Kelvin-Voigt damper on the
*rate of change of each cell's displacement at fixed hull position*: zero in any steady motion
(driving, steady turning), so it never alters the force law there; it only damps transients
(LuGre's sigma_1 term, Canudas de Wit et al. 1995). Its last value is ``damping_n`` (per road
wheel, [N]; ``damper_n`` of ``contact_state``) next to the shear forces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim.wheel_soil import WheelContactState
from slipenv.terramechanics.models import ForceModel
from slipenv.terramechanics.soil import SoilParams
from slipenv.terramechanics.soil_map import SoilMap, UniformSoil, soil_rows
from slipenv.terramechanics.track import (
    advance_shear,
    advance_wall,
    cell_forces,
    load_spread_matrix,
    rut_resistance_n,
    wall_force_n_per_m,
)
from slipenv.vehicles.body import VehicleBody
from slipenv.vehicles.spec import VehicleSpec

p = import_pybullet()  # the banner-free first import (see slipenv.pybullet_quiet)



@dataclass(frozen=True)
class TrackModelParams:
    """Numerical and soil-side settings of the track injector.

    Attributes
    ----------
    n_cells : int
        Cells per track for the shear field (independent of the number of road wheels).
    unit_weight_n_m3 : float
        Soil unit weight gamma [N/m^3] of the side-wall passive pressure. Default: dry Toyoura
        sand at its loosest, rho_d,min = 1.335 g/cm^3 (e_max = 0.977, G_s = 2.64; the JGS
        characterisation used throughout the Japanese soil-mechanics literature), a dry loose
        silica sand.
    direction_length_m : float
        e_max [m] of the stress-direction state (``slipenv.terramechanics.track``): the
        sliding distance over which the stress turns to a new sliding direction. 1 mm keeps
        the steady turning forces within 2 % of Wong-Chiang's (tests/terramechanics/
        test_track.py) and the standstill direction spring stable at 240 Hz.
    damping_ratio : float
        Damping ratio of the soil springs at rest (module docstring), per cell: along the
        stress, of the Janosi spring's tangent stiffness; across it, of the direction state's
        tau A/e_max; each for the cell's mass share and capped at half the explicit
        stability limit m/dt. Critical (1.0): at 0.5 the vehicle parked facing up a 15°
        slope rocks on its direction springs and ratchets 11 mm downhill in 10 s.
    resistance_speed_mps : float
        Regularisation of the rut resistance's sign at rest [m/s] (not a speed ramp: the
        resistance is rate independent above it).
    max_wall_height_m : float
        Side-wall height above which soil spills over the track [m] (the road-wheel diameter
        when ``None``).
    """

    n_cells: int = 16
    direction_length_m: float = 1e-3
    unit_weight_n_m3: float = 1.335e3 * G_MPS2
    damping_ratio: float = 1.0
    resistance_speed_mps: float = 1e-3
    max_wall_height_m: float | None = None

    def __post_init__(self) -> None:
        if not (isinstance(self.n_cells, int) and 4 <= self.n_cells <= 200):
            raise ValueError(f"n_cells must be an int in [4, 200], got {self.n_cells!r}")
        for name in ("unit_weight_n_m3", "resistance_speed_mps", "direction_length_m"):
            v = getattr(self, name)
            if not (math.isfinite(v) and v > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {v!r}")
        if not (math.isfinite(self.damping_ratio) and self.damping_ratio >= 0.0):
            raise ValueError(f"damping_ratio must be finite and >= 0, got {self.damping_ratio!r}")
        if self.max_wall_height_m is not None and not (math.isfinite(self.max_wall_height_m)
                                                       and self.max_wall_height_m > 0.0):
            raise ValueError(f"max_wall_height_m must be > 0, got {self.max_wall_height_m!r}")


class TrackSoilInjector:
    """Applies the Wong-Chiang track model to both tracks of one vehicle, once per substep.

    Parameters
    ----------
    client : int
        PyBullet client id.
    spec : VehicleSpec
        A ``skid_steer`` vehicle with ``track_length_m``; each drive channel is one track.
    body : VehicleBody
        Its PyBullet handles.
    ground_id : int
        The terrain body id.
    force_model : ForceModel
        Kept for readers (the oracle); the track model itself uses the soil's c, phi, K and
        Bekker constants.
    soil_map : SoilMap
        Soil under each track (sampled at the track centres once per control step).
    dt_s : float
        Physics substep [s].
    params : TrackModelParams
        Cells, unit weight, damping.
    """

    def __init__(self, client: int, spec: VehicleSpec, body: VehicleBody, ground_id: int,
                 force_model: ForceModel, soil_map: SoilMap, dt_s: float,
                 params: TrackModelParams | None = None) -> None:
        if spec.track_length_m is None:
            raise ValueError(f"vehicle {spec.name!r} has no track_length_m")
        if not (math.isfinite(dt_s) and dt_s > 0.0):
            raise ValueError(f"dt_s must be finite and > 0, got {dt_s!r}")
        self.params = params or TrackModelParams()
        self.client, self.body_id, self.ground_id = client, body.body_id, ground_id
        self.force_model, self.soil_map, self.dt_s = force_model, soil_map, dt_s
        self.n = len(spec.wheels)
        self.links = list(body.wheel_links)
        self.link_to_wheel = {link: k for k, link in enumerate(self.links)}
        self.spin_joints = [j for j in body.spin_joints if j is not None]
        if len(self.spin_joints) != self.n:
            raise ValueError("the track model needs every road wheel driven")
        self.radius = [w.radius_m for w in spec.wheels]
        self.mass_kg = spec.mass_kg
        h = spec.chassis_center_height_m
        n_cells = self.params.n_cells
        length = float(spec.track_length_m)
        self.length_m, self.dx_m = length, length / n_cells
        self.tracks: list[list[int]] = [
            [k for k, w in enumerate(spec.wheels) if w.channel == c] for c in spec.channels]
        nt = len(self.tracks)
        self.track_of = [0] * self.n
        for i, ks in enumerate(self.tracks):
            for k in ks:
                self.track_of[k] = i
        # Geometry in the base frame (the base inertial frame is at the chassis box centre).
        self.width = [float(np.mean([spec.wheels[k].width_m for k in ks])) for ks in self.tracks]
        self.y = np.array([np.mean([spec.wheels[k].position_m[1] for k in ks])
                           for ks in self.tracks])
        x0 = [float(np.mean([spec.wheels[k].position_m[0] for k in ks])) for ks in self.tracks]
        z_c = [float(np.mean([spec.wheels[k].position_m[2] - h - spec.wheels[k].radius_m
                              for k in ks])) for ks in self.tracks]
        self.z_c = np.array(z_c)
        offs = length / 2.0 - self.dx_m * (np.arange(n_cells) + 0.5)  # front cell first
        self.x_cell = np.array([x + offs for x in x0])  # (nt, N)
        self.spread = []  # per track: (N, n_wheels_track) load -> cell load
        self.assign = []  # per track: cell -> index of its nearest road wheel within the track
        self.lever = np.zeros((nt, n_cells))  # x_cell - x of its road wheel
        for i, ks in enumerate(self.tracks):
            xw = np.array([spec.wheels[k].position_m[0] for k in ks])
            self.spread.append(load_spread_matrix(xw, self.x_cell[i]))
            near = np.abs(self.x_cell[i][:, None] - xw[None, :]).argmin(axis=1)
            self.assign.append(near)
            self.lever[i] = self.x_cell[i] - xw[near]
        # Block matrices over all road wheels: wheel loads -> cell loads, cell -> its wheel.
        self.spread_all = np.zeros((nt * n_cells, self.n))
        self.assign_all = np.zeros((self.n, nt * n_cells))
        for i, ks in enumerate(self.tracks):
            rows_ = slice(i * n_cells, (i + 1) * n_cells)
            self.spread_all[rows_, ks] = self.spread[i]
            for c, m in enumerate(self.assign[i]):
                self.assign_all[ks[m], i * n_cells + c] = 1.0
        # Each road wheel's contact point (under its centre) in the base frame.
        self.contact_base = [(w.position_m[0], w.position_m[1], w.position_m[2] - h - w.radius_m)
                             for w in spec.wheels]
        self.y_list = [float(v) for v in self.y]
        self.x_mid = [float(v) for v in self.x_cell.mean(axis=1)]
        self.z_list = [float(v) for v in self.z_c]
        self.r_belt = [float(np.mean([self.radius[k] for k in ks])) for ks in self.tracks]
        self.max_wall_m = (self.params.max_wall_height_m if self.params.max_wall_height_m
                           is not None else 2.0 * max(self.r_belt))
        # Buffers and constants of the fused hot path (`apply`).
        self._sign = np.array([1.0, -1.0]).reshape(2, 1, 1)  # (x, y) of Omega z x (.)
        self._v_cell = np.empty((2, nt, n_cells))
        self._e_shift = np.zeros((2, nt, n_cells))
        self._kk = np.empty((2, nt, n_cells))
        self._out = np.empty((6, nt, n_cells))  # total x, y; shear x, y; wall; |damper|
        lever_rows = np.zeros((nt, nt * n_cells))
        track_rows = np.zeros((nt, nt * n_cells))
        for i in range(nt):
            lever_rows[i, i * n_cells:(i + 1) * n_cells] = self.lever[i]
            track_rows[i, i * n_cells:(i + 1) * n_cells] = 1.0
        self._reduce = np.vstack((self.assign_all, lever_rows, track_rows))
        self._contact_base = np.array(self.contact_base)
        self.reset()

    # -- state ------------------------------------------------------------------------------
    def reset(self) -> None:
        """Zero the shear field, the side walls, the berms and the rut, and the readings."""
        nt, n_cells = len(self.tracks), self.params.n_cells
        self.j = np.zeros((2, nt, n_cells + 1))  # shear displacement at the cell faces
        self.e = np.zeros((2, nt, n_cells))  # stress-direction state at the cell centres
        # Side-wall penetration and berm in one array (advected together in `apply`).
        self._wall_berm = np.zeros((2, 2, nt, n_cells))
        self.wall = self._wall_berm[0]  # left, right wall penetration [m]
        self.berm = self._wall_berm[1]  # left, right berm cross-section [m^2]
        self.travel = [0.0] * nt
        self.cut_front = [0.0] * nt
        self.cut_rear = [0.0] * nt
        self.sinkage_m = np.zeros((nt, n_cells))
        self.track_slip = [0.0] * nt
        self.track_tanb = [0.0] * nt
        self.load = [0.0] * self.n
        self.fx = [0.0] * self.n
        self.fy = [0.0] * self.n
        self.res = [0.0] * self.n
        self.damping_n = [0.0] * self.n
        self.wall_n = [0.0] * nt
        self.chassis_contact = False
        self.sample_soil(force=True)

    def sample_soil(self, force: bool = False) -> None:
        """Sample the soil at each track's centre (once per control step)."""
        uniform = isinstance(self.soil_map, UniformSoil)
        if uniform and not force:
            return
        if uniform:
            rows = soil_rows(self.soil_map, [0.0] * len(self.tracks), [0.0] * len(self.tracks))
        else:
            pos, orn = p.getBasePositionAndOrientation(self.body_id, physicsClientId=self.client)
            rot = p.getMatrixFromQuaternion(orn)
            rows = soil_rows(self.soil_map, [pos[0] + rot[1] * y for y in self.y],
                             [pos[1] + rot[4] * y for y in self.y])
        self._soil_rows = rows
        col = lambda f: np.array([[float(f(sp))] for sp in rows])  # noqa: E731
        self._c = col(lambda sp: sp.cohesion_pa)
        self._phi = col(lambda sp: sp.friction_angle_rad)
        self._tan_phi = np.tan(self._phi)
        self._k = col(lambda sp: sp.shear_modulus_m)
        self._kc = col(lambda sp: sp.k_c)
        self._kphi = col(lambda sp: sp.k_phi)
        self._n = col(lambda sp: sp.n_exp)
        self._deform = np.array([1.0 if float(sp.deformable) > 0.5 else 0.0 for sp in rows])
        w_col = np.array(self.width)[:, None]
        self._w_col = w_col
        self._inv_area = 1.0 / (w_col * self.dx_m)
        self._inv_kb = 1.0 / (self._kc / w_col + self._kphi)
        self._inv_n = 1.0 / self._n
        self._inv_k = 1.0 / self._k
        self._n_phi = np.tan(math.pi / 4.0 + self._phi / 2.0) ** 2
        self._c_area = self._c * w_col * self.dx_m
        self._rc_coef = [float((self._kc[i, 0] + self.width[i] * self._kphi[i, 0])
                               / (self._n[i, 0] + 1.0)) for i in range(len(rows))]
        self._n_plus_1 = [float(self._n[i, 0] + 1.0) for i in range(len(rows))]
        # Dampers of the soil springs, per cell (module docstring): 2 zeta sqrt(k m) for the
        # cell's mass share, capped at half the explicit limit m/dt.
        m_cell = self.mass_kg / len(self.tracks) / self.params.n_cells
        self._two_zeta_sqrt_m = 2.0 * self.params.damping_ratio * math.sqrt(m_cell)
        self._cap = 0.5 * m_cell / self.dt_s
        # Constants of the fused hot path (`apply`), per track as (nt, 1) columns.
        self._neg_half_inv_k = -0.5 * self._inv_k
        self._two_tan_phi = 2.0 * self._tan_phi  # berm height h = sqrt(2 A tan(phi))
        gamma = self.params.unit_weight_n_m3
        self._p_quad = 0.5 * gamma * self._n_phi  # Rankine: P = h (p_quad h + p_lin)
        self._p_lin = 2.0 * self._c * np.sqrt(self._n_phi)
        self._deform_list = [float(d) for d in self._deform]

    def soil_at_wheel(self, k: int) -> SoilParams:
        """The soil (floats) under road wheel ``k``'s track at the last `sample_soil`."""
        return self._soil_rows[self.track_of[k]]

    def rolling_radius_m(self, k: int) -> float:
        """Belt radius of road wheel ``k``'s track [m]: the belt moves at r_s omega."""
        return self.r_belt[self.track_of[k]]

    # -- the substep -------------------------------------------------------------------------
    def _read_state(self) -> tuple:
        """One batched PyBullet read: the base pose and axes, the hull velocities in hull
        axes, the road-wheel loads, the belt speeds and the tracks' ground speeds."""
        cid, bid = self.client, self.body_id
        contacts = p.getContactPoints(bodyA=bid, bodyB=self.ground_id, physicsClientId=cid)
        joints = p.getJointStates(bid, self.spin_joints, physicsClientId=cid)
        pos, orn = p.getBasePositionAndOrientation(bid, physicsClientId=cid)
        lin, ang = p.getBaseVelocity(bid, physicsClientId=cid)
        r = p.getMatrixFromQuaternion(orn)
        ex, ey, ez = (r[0], r[3], r[6]), (r[1], r[4], r[7]), (r[2], r[5], r[8])
        vbx = lin[0] * ex[0] + lin[1] * ex[1] + lin[2] * ex[2]
        vby = lin[0] * ey[0] + lin[1] * ey[1] + lin[2] * ey[2]
        wbx = ang[0] * ex[0] + ang[1] * ex[1] + ang[2] * ex[2]
        wby = ang[0] * ey[0] + ang[1] * ey[1] + ang[2] * ey[2]
        wbz = ang[0] * ez[0] + ang[1] * ez[1] + ang[2] * ez[2]
        load = [0.0] * self.n
        link_to_wheel = self.link_to_wheel
        for cp in contacts:
            f = cp[9]
            if f <= 0.0:
                continue
            k = link_to_wheel.get(cp[3])
            if k is None:
                self.chassis_contact = True
                continue
            load[k] += f
        # Belt speed, track ground speed (hull axes).
        u_list = [self.r_belt[i] * sum(joints[k][1] for k in ks) / len(ks)
                  for i, ks in enumerate(self.tracks)]
        vx_list = [vbx + wby * zc - wbz * yi for zc, yi in zip(self.z_list, self.y_list,
                                                                strict=True)]
        return pos, (ex, ey, ez, r), (vby, wbx, wbz), load, u_list, vx_list

    def _slip_factor(self, u_list: list[float], vx_list: list[float]):
        """The tracks' slips i = (u - V)/u in [-1, 1] (0 at rest) and Lyasko's slip-sinkage
        factors (`track.slip_sinkage_factor`), inlined (hot path)."""
        slip = []
        for ui, vi in zip(u_list, vx_list, strict=True):
            s = (ui - vi) / ui if abs(ui) > 1e-3 else (0.0 if abs(vi) < 1e-3 else -1.0)
            slip.append(min(max(s, -1.0), 1.0))
        factor = [(1.0 + i) / (1.0 - 0.5 * i) if i > 0.0 else 1.0 for i in slip]
        return slip, factor

    def apply(self) -> None:
        """Compute and apply the track forces for the coming substep (the hot path).

        The physics of `apply_reference` (the plain functions of
        `slipenv.terramechanics.track` composed) with the numpy work on these small
        (2, n_tracks, n_cells) fields fused: preallocated buffers, in-place operations, the
        Janosi exponential shared by the stress and its tangent stiffness, the walls and berms
        advected as one array, the upwinding done per track with slices instead of masks.
        """
        dt, dx, prm = self.dt_s, self.dx_m, self.params
        nt, n_cells = len(self.tracks), prm.n_cells
        pos, axes, (vby, wbx, wbz), load, u_list, vx_list = self._read_state()
        # Sliding velocity of the belt over the ground at the cell centres (hull axes).
        v_cell = self._v_cell
        v_cell[0] = np.array([vi - ui for vi, ui in zip(vx_list, u_list, strict=True)])[:, None]
        np.multiply(self.x_cell, wbz, out=v_cell[1])
        v_cell[1] += np.array([vby - wbx * zc for zc in self.z_list])[:, None]
        # Pressure and sinkage (`bekker_sinkage_m` times `slip_sinkage_factor`).
        q = (self.spread_all @ np.array(load)).reshape(nt, n_cells)
        pressure = q * self._inv_area
        slip, factor = self._slip_factor(u_list, vx_list)
        z = (pressure * self._inv_kb) ** self._inv_n
        z *= np.array([f * d for f, d in zip(factor, self._deform_list, strict=True)])[:, None]
        self.sinkage_m = z
        # Shear field j and stress-direction state e (`advance_shear`), upwinded per track.
        j, e = self.j, self.e
        jsum_old = j[..., :-1] + j[..., 1:]
        fwd = [ui > 1e-3 for ui in u_list]
        bwd = [ui < -1e-3 for ui in u_list]
        a_list = [abs(ui) * (dt / dx) for ui in u_list]
        src = (0.5 * wbz * self._sign) * jsum_old[::-1]
        src += v_cell
        e_src = (wbz * self._sign) * e[::-1]
        e_src += v_cell
        leak = np.hypot(v_cell[0], v_cell[1])
        leak *= dt / prm.direction_length_m
        leak += 1.0
        if all(fwd):
            a = np.array(a_list)[:, None]
            j[..., 1:] += a * (j[..., :-1] - j[..., 1:]) + dt * src
            j[..., 0] = 0.0
            e_shift = self._e_shift
            e_shift[..., 1:] = e[..., :-1]
            e += a * (e_shift - e) + dt * e_src
        else:
            for i in range(nt):
                _upwind_track(j[:, i], e[:, i], src[:, i], e_src[:, i], a_list[i], fwd[i],
                              bwd[i], dt)
        e /= leak
        # Cell shear forces (`cell_forces`) and the soil-spring dampers.
        jsum = j[..., :-1] + j[..., 1:]  # twice the cells' j
        strength = q * self._tan_phi
        strength += self._c_area  # (c + p tan phi) b dx
        decay = np.hypot(jsum[0], jsum[1])
        decay *= self._neg_half_inv_k
        np.exp(decay, out=decay)  # exp(-|j|/K)
        e_abs = np.hypot(e[0], e[1])
        ratio = 1.0 - decay
        ratio *= strength
        ratio /= np.maximum(e_abs, 1e-300)  # tau b dx / |e|
        ratio *= -1.0
        out = self._out
        f_shear = out[2:4]
        np.multiply(e, ratio, out=f_shear)
        tau_a = np.hypot(f_shear[0], f_shear[1])
        # Dampers (`apply_reference`): 2 zeta sqrt(k m) capped at half m/dt, per unit time;
        # k along the stress the Janosi tangent stiffness, across it tau A / e_max.
        kk = self._kk
        np.multiply(strength, decay, out=kk[0])
        kk[0] *= self._inv_k
        np.multiply(tau_a, 1.0 / prm.direction_length_m, out=kk[1])
        np.sqrt(kk, out=kk)
        kk *= self._two_zeta_sqrt_m
        np.minimum(kk, self._cap, out=kk)
        kk *= 1.0 / dt
        dj = jsum - jsum_old
        dj *= 0.5
        n_hat = f_shear * (-1.0 / np.maximum(tau_a, 1e-300))  # e/|e| (0 if no stress)
        dj_par = (dj * n_hat).sum(axis=0) * n_hat
        f_damp = kk[0] * dj_par
        dj -= dj_par
        dj *= kk[1]
        f_damp += dj
        f_damp *= -1.0
        # Side walls and berms (`advance_wall`, `wall_force_n_per_m`).
        wb = self._wall_berm
        if all(vt > 1e-4 for vt in vx_list):  # the common case, in one go
            aw = np.array([min(abs(vt) * (dt / dx), 1.0) for vt in vx_list])[:, None]
            wb[..., 1:] += aw * (wb[..., :-1] - wb[..., 1:])
            wb[..., :1] -= aw * wb[..., :1]
        else:
            for i in range(nt):
                _upwind_wall(wb[:, :, i], vx_list[i], dt / dx)
        wall, berm = self.wall, self.berm
        step = v_cell[1] * dt
        left = np.maximum(step, 0.0)  # outward motion of the left wall
        wall[0] += step
        wall[1] -= step
        np.maximum(wall, 0.0, out=wall)
        berm[0] += z * left
        left -= step
        left *= z
        berm[1] += left
        h = np.maximum(berm, 0.0)
        h *= self._two_tan_phi
        np.sqrt(h, out=h)  # berm height
        h += z
        np.minimum(h, self.max_wall_m, out=h)
        pres = self._p_quad * h
        pres += self._p_lin
        pres *= h  # Rankine passive thrust [N/m]
        np.multiply(h, 0.1, out=h)
        np.maximum(h, 5e-4, out=h)  # mobilisation length d_b
        mob = wall / h
        mob *= -1.0
        np.expm1(mob, out=mob)
        mob *= pres  # -P (1 - e^{-d/d_b})
        f_wall = out[4]
        np.subtract(mob[0], mob[1], out=f_wall)
        f_wall *= dx
        # Per road wheel: total, shear, wall and damper magnitude; per track the yaw moment of
        # the lateral forces about the road wheels and the wall force: one product.
        np.add(f_shear, f_damp, out=out[0:2])
        out[1] += f_wall
        np.hypot(f_damp[0], f_damp[1], out=out[5])
        sums = self._reduce @ out.reshape(6, -1).T  # (n + 2 n_tracks, 6)
        n = self.n
        self._apply_forces(pos, axes, sums[:n], sums[n:n + nt, 1].tolist(),
                           z.max(axis=1).tolist(), load, vx_list, vby, wbx, wbz)
        self.wall_n = sums[n + nt:, 4].tolist()
        self.track_slip = slip

    def _apply_forces(self, pos, axes, per_wheel: np.ndarray, moment: list[float],
                      z_max: list[float], load: list[float], vx_list: list[float], vby: float,
                      wbx: float, wbz: float) -> None:
        """Apply each road wheel's share of the cell forces at its contact point, each
        track's rut resistance on the hull at its centre line and its residual yaw moment;
        record the readings (``per_wheel``, (n, 6): per road wheel total x, y, shear x, y,
        wall, |damper|)."""
        cid, bid, dt, prm = self.client, self.body_id, self.dt_s, self.params
        nt = len(self.tracks)
        ex, ey, ez, r = axes
        apply_force, world = p.applyExternalForce, p.WORLD_FRAME
        px, py, pz = pos
        links = self.links
        rot = np.array(r).reshape(3, 3)  # body -> world
        points = (self._contact_base @ rot.T + pos).tolist()
        forces = (per_wheel[:, :2] @ rot[:, :2].T).tolist()
        for k in range(self.n):
            apply_force(bid, links[k], forces[k], points[k], world, physicsClientId=cid)
        res_out = [0.0] * self.n
        for i, ks in enumerate(self.tracks):
            # Compaction resistance (rut state) along the track, on the hull at its centre line.
            vt = vx_list[i]
            self.travel[i] += vt * dt
            r_c = 0.0
            if self._deform[i] > 0.0:
                r_c = self._rc_coef[i] * z_max[i] ** self._n_plus_1[i]
            v_reg = max(prm.resistance_speed_mps, 2.0 * r_c * dt / (self.mass_kg / nt))
            f_res, self.cut_front[i], self.cut_rear[i] = rut_resistance_n(
                r_c, self.travel[i], self.cut_front[i], self.cut_rear[i], vt, v_reg)
            if f_res != 0.0:
                yi, zc = self.y_list[i], self.z_list[i]
                point = (px + yi * ey[0] + zc * ez[0], py + yi * ey[1] + zc * ez[1],
                         pz + yi * ey[2] + zc * ez[2])
                apply_force(bid, -1, (f_res * ex[0], f_res * ex[1], f_res * ex[2]), point,
                            world, physicsClientId=cid)
            total_w = sum(load[k] for k in ks)
            for k in ks:
                res_out[k] = abs(f_res) * (load[k] / total_w if total_w > 0.0 else 0.0)
            mz = moment[i]
            if mz != 0.0:
                p.applyExternalTorque(bid, -1, (mz * ez[0], mz * ez[1], mz * ez[2]), world,
                                      physicsClientId=cid)
            vy_mean = vby + wbz * self.x_mid[i] - wbx * self.z_list[i]
            self.track_tanb[i] = vy_mean / vt if abs(vt) > 1e-3 else 0.0
        self.load, self.res = load, res_out
        self.fx = per_wheel[:, 2].tolist()
        self.fy = (per_wheel[:, 3] + per_wheel[:, 4]).tolist()
        self.damping_n = per_wheel[:, 5].tolist()

    def apply_reference(self) -> None:
        """`apply` written as the plain functions of `slipenv.terramechanics.track` composed
        step by step: the readable text of the substep. `apply` is the same physics with the
        numpy work fused (fewer, in-place operations on preallocated buffers); they agree to
        rounding (tests/sim/test_track_soil.py)."""
        dt, dx = self.dt_s, self.dx_m
        nt, n_cells, prm = len(self.tracks), self.params.n_cells, self.params
        pos, axes, (vby, wbx, wbz), load, u_list, vx_list = self._read_state()
        u = np.array(u_list)
        vx_track = np.array(vx_list)
        v_cell = np.empty((2, nt, n_cells))
        v_cell[0] = (vx_track - u)[:, None]
        v_cell[1] = vby + wbz * self.x_cell - wbx * self.z_c[:, None]
        # Pressure and sinkage: bekker_sinkage_m times slip_sinkage_factor, inlined.
        q = (self.spread_all @ np.array(load)).reshape(nt, n_cells)
        pressure = q * self._inv_area
        slip, factor = self._slip_factor(u_list, vx_list)
        z = (pressure * self._inv_kb) ** self._inv_n * (np.array(factor) * self._deform)[:, None]
        self.sinkage_m = z
        # Shear field and its forces; the damper on each cell's Eulerian displacement rate.
        j = self.j
        jc_old = j[..., :-1] + j[..., 1:]
        advance_shear(j, v_cell, u, wbz, dx, dt, self.e, prm.direction_length_m)
        f_shear = cell_forces(j, self.e, pressure, self._w_col, dx, self._c, self._tan_phi,
                              self._k)
        jc = 0.5 * (j[..., :-1] + j[..., 1:])
        j_abs = np.sqrt(jc[0] ** 2 + jc[1] ** 2)
        tau_a = np.sqrt(f_shear[0] ** 2 + f_shear[1] ** 2)
        # Dampers of damping_ratio (capped at half m/dt) on each cell's Eulerian displacement
        # rate: along the stress, of the Janosi spring's tangent stiffness (vanishing once the
        # soil is sheared through); across it, of the direction state's stiffness tau A/e_max.
        k_par = (self._c_area + q * self._tan_phi) * self._inv_k * np.exp(-j_abs * self._inv_k)
        k_perp = tau_a * (1.0 / prm.direction_length_m)
        c_par = np.minimum(self._two_zeta_sqrt_m * np.sqrt(k_par), self._cap) * (1.0 / dt)
        c_perp = np.minimum(self._two_zeta_sqrt_m * np.sqrt(k_perp), self._cap) * (1.0 / dt)
        dj = jc - 0.5 * jc_old
        n_hat = -f_shear / np.maximum(tau_a, 1e-300)  # the stress direction e/|e| (0 if none)
        dj_par = (dj[0] * n_hat[0] + dj[1] * n_hat[1]) * n_hat
        f_damp = -c_par * dj_par - c_perp * (dj - dj_par)
        # Side walls and berms (bulldozing).
        advance_wall(self.wall, self.berm, v_cell[1], vx_track, z, dx, dt)
        f_wall = wall_force_n_per_m(self.wall, self.berm, z, prm.unit_weight_n_m3,
                                    self._c, self._phi, self.max_wall_m,
                                    n_phi=self._n_phi) * dx
        tot = f_shear + f_damp
        tot[1] += f_wall
        moment = (self.lever * tot[1]).sum(axis=1).tolist()  # about the road wheels
        per_wheel = self.assign_all @ np.concatenate(
            (tot.reshape(2, -1), f_shear.reshape(2, -1), f_wall.reshape(1, -1),
             np.sqrt(f_damp[0] ** 2 + f_damp[1] ** 2).reshape(1, -1))).T  # (n, 6)
        self._apply_forces(pos, axes, per_wheel, moment, z.max(axis=1).tolist(), load,
                           vx_list, vby, wbx, wbz)
        self.wall_n = f_wall.sum(axis=1).tolist()
        self.track_slip = slip

    # -- reading ----------------------------------------------------------------------------
    def contact_state(self) -> WheelContactState:
        """Per road wheel: its track's slip and tan(slip angle), its load, its share of the
        track's shear (f_x) and lateral shear plus side-wall force (f_y), of the rut
        resistance, and of the soil-spring damper's force magnitude (``damper_n``) [N]."""
        load = np.array(self.load)
        return WheelContactState(
            slip=np.array([self.track_slip[i] for i in self.track_of]),
            tan_beta=np.array([self.track_tanb[i] for i in self.track_of]),
            load_n=load, fx_n=np.array(self.fx), fy_n=np.array(self.fy),
            resistance_n=np.array(self.res), in_contact=load > 0.0,
            damper_n=np.array(self.damping_n),
        )


def _upwind_track(j: np.ndarray, e: np.ndarray, src: np.ndarray, e_src: np.ndarray, a: float,
                  forward: bool, backward: bool, dt: float) -> None:
    """`advance_shear`'s upwind step for one track (in place, before the leak): ``j`` (2,
    n_cells + 1) at the faces, ``e`` (2, n_cells) at the centres, ``src``/``e_src`` their
    sources at the centres, ``a`` = |u| dt/dx; the entry face is zeroed. At rest (neither
    direction) every face integrates the mean source of its neighbouring cells."""
    if forward:
        j[:, 1:] += a * (j[:, :-1] - j[:, 1:]) + dt * src
        j[:, 0] = 0.0
        e[:, 1:] += a * (e[:, :-1] - e[:, 1:]) + dt * e_src[:, 1:]
        e[:, 0] += a * (0.0 - e[:, 0]) + dt * e_src[:, 0]
    elif backward:
        j[:, :-1] += a * (j[:, 1:] - j[:, :-1]) + dt * src
        j[:, -1] = 0.0
        e[:, :-1] += a * (e[:, 1:] - e[:, :-1]) + dt * e_src[:, :-1]
        e[:, -1] += a * (0.0 - e[:, -1]) + dt * e_src[:, -1]
    else:
        j[:, 0] += dt * src[:, 0]
        j[:, 1:-1] += dt * (0.5 * (src[:, :-1] + src[:, 1:]))
        j[:, -1] += dt * src[:, -1]
        e += dt * e_src


def _upwind_wall(wb: np.ndarray, ground_speed_mps: float, dt_over_dx: float) -> None:
    """`advance_wall`'s upwind step of one track's walls and berms ``wb`` (2, 2, n_cells), in
    place: the ground passes the hull at -V, fresh soil entering at the entry end."""
    a = min(abs(ground_speed_mps) * dt_over_dx, 1.0)
    if ground_speed_mps > 1e-4:
        wb[..., 1:] += a * (wb[..., :-1] - wb[..., 1:])
        wb[..., :1] -= a * wb[..., :1]
    elif ground_speed_mps < -1e-4:
        wb[..., :-1] += a * (wb[..., 1:] - wb[..., :-1])
        wb[..., -1:] -= a * wb[..., -1:]
