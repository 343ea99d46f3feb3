"""Inject the Wong-Chiang track model (``slipenv.terramechanics.track``) every physics substep.

For a tracked vehicle whose spec selects ``track_model="wong_chiang"``. The road wheels keep
carrying the normal contact (PyBullet's compliant sphere contacts); this injector replaces their
per-wheel shear by one shear field per track. Every term of the model is a plain function of
``slipenv.terramechanics.track``, tested there on its own; `TrackSoilInjector.apply` only reads
PyBullet, composes those functions and applies the result:

1. read the road-wheel loads (``getContactPoints``), the hull twist and the belt speeds
   (one batched query each);
2. spread the loads over ``n_cells`` cells per track (pressure p(x)) and compute the sinkage
   (Bekker, Lyasko's slip sinkage);
3. advance the shear displacement field j(x) and the stress-direction state, the side walls'
   penetration and berms, and the rut state;
4. compute the cell shear forces (Janosi with Mohr-Coulomb, against the sliding velocity), the
   soil-spring dampers, the side-wall (bulldozing) force and the compaction resistance;
5. apply each road wheel's share of the cells' forces *at that road wheel's contact point*, so
   the channel motor feels r sum F_x as the sprocket would; the residual yaw moment of the
   lateral forces about the road wheels (exactly what the lumping misses) as one torque per
   track on the hull; the compaction resistance at the track's centre line on the hull.

It implements the injector protocol ``slipenv.sim.injector.Injector`` (``chassis_contact``,
``links``, ``load``, ``force_model``, ``sample_soil``, ``apply``, ``soil_at_wheel``,
``rolling_radius_m``, ``contact_state``) with per-road-wheel arrays, each road wheel reporting
its track's slip and its share of the forces.

The soil "spring" at rest (j integrates the sliding velocity) gets a Kelvin-Voigt damper on the
rate of change of each cell's displacement at fixed hull position
(``track.soil_damper_forces``): zero in any steady motion, it only damps transients. Its last
value is ``damping_n`` (per road wheel, [N]; ``damper_n`` of ``contact_state``) next to the
shear forces.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim.wheel_soil import WheelContactState
from slipenv.terramechanics.bekker import compaction_resistance_n, pressure_sinkage_m
from slipenv.terramechanics.models import ForceModel
from slipenv.terramechanics.soil import SoilParams
from slipenv.terramechanics.soil_map import SoilMap, UniformSoil, soil_rows
from slipenv.terramechanics.track import (
    advance_shear,
    advance_wall,
    cell_forces,
    load_spread_matrix,
    rut_resistance_n,
    sliding_velocity,
    slip_sinkage_factor,
    soil_damper_forces,
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
        Damping ratio of the soil springs at rest (``track.soil_damper_forces``), per cell:
        along the stress, of the Janosi spring's tangent stiffness; across it, of the
        direction state's tau A/e_max; each for the cell's mass share and capped at half the
        explicit stability limit m/dt. Critical (1.0): at 0.5 the vehicle parked facing up a 15°
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
    """Applies the Wong-Chiang track model to both tracks of one vehicle, once per substep
    (a ``slipenv.sim.injector.Injector``).

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
        # Buffers of `apply`.
        self._v_cell = np.empty((2, nt, n_cells))
        self._out = np.empty((6, nt, n_cells))  # total x, y; shear x, y; wall; |damper|
        self._cell_mass_kg = self.mass_kg / nt / n_cells
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
        # Side-wall penetration and berm cross-section (`track.advance_wall`).
        self.walls = np.zeros((2, 2, nt, n_cells))
        self.wall = self.walls[0]  # left, right wall penetration [m]
        self.berm = self.walls[1]  # left, right berm cross-section [m^2]
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

        def per_track(values: list[float]):
            """One float when the tracks agree (cheaper to broadcast), else a (nt, 1) column."""
            if all(v == values[0] for v in values):
                return float(values[0])
            return np.array(values)[:, None]

        self._c = per_track([float(sp.cohesion_pa) for sp in rows])
        phi = [float(sp.friction_angle_rad) for sp in rows]
        self._phi = per_track(phi)
        self._tan_phi = per_track([math.tan(v) for v in phi])
        self._n_phi = per_track([math.tan(math.pi / 4.0 + v / 2.0) ** 2 for v in phi])
        self._k = per_track([float(sp.shear_modulus_m) for sp in rows])
        self._kc = per_track([float(sp.k_c) for sp in rows])
        self._kphi = per_track([float(sp.k_phi) for sp in rows])
        self._n = per_track([float(sp.n_exp) for sp in rows])
        self._deform = np.array([1.0 if float(sp.deformable) > 0.5 else 0.0 for sp in rows])
        self._rigid_tracks = bool((self._deform == 0.0).any())
        self._w = per_track(self.width)
        self._inv_area = 1.0 / (self._w * self.dx_m)

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

    def _slip(self, u_list: list[float], vx_list: list[float]) -> list[float]:
        """The tracks' slips i = (u - V)/u in [-1, 1] (0 at rest, -1 sliding with the belt
        stopped)."""
        slip = []
        for ui, vi in zip(u_list, vx_list, strict=True):
            s = (ui - vi) / ui if abs(ui) > 1e-3 else (0.0 if abs(vi) < 1e-3 else -1.0)
            slip.append(min(max(s, -1.0), 1.0))
        return slip

    def apply(self) -> None:
        """Compute and apply the track forces for the coming substep: the functions of
        `slipenv.terramechanics.track` composed (module docstring)."""
        dt, dx, prm = self.dt_s, self.dx_m, self.params
        nt, n_cells = len(self.tracks), prm.n_cells
        pos, axes, (vby, wbx, wbz), load, u_list, vx_list = self._read_state()
        c, tan_phi, k, width = self._c, self._tan_phi, self._k, self._w
        v_cell = sliding_velocity(vx_list, u_list, [vby - wbx * zc for zc in self.z_list], wbz,
                                  self.x_cell, out=self._v_cell)
        pressure = (self.spread_all @ load).reshape(nt, n_cells)  # cell loads
        pressure *= self._inv_area
        slip = self._slip(u_list, vx_list)
        z = pressure_sinkage_m(pressure, width, self._kc, self._kphi, self._n)
        z *= slip_sinkage_factor(slip)[:, None]
        if self._rigid_tracks:
            z *= self._deform[:, None]  # no sinkage on rigid ground
        self.sinkage_m = z
        j, e = self.j, self.e
        j_old = j[..., :-1] + j[..., 1:]  # twice the cells' displacement before the step
        advance_shear(j, e, v_cell, u_list, wbz, dx, dt, prm.direction_length_m)
        out = self._out
        f_shear, stiffness = cell_forces(j, e, pressure, width, dx, c, tan_phi, k,
                                         out=out[2:4])
        dj = j[..., :-1] + j[..., 1:]
        dj -= j_old
        dj *= 0.5
        f_damp = soil_damper_forces(dj, f_shear, stiffness, prm.direction_length_m,
                                    prm.damping_ratio, self._cell_mass_kg, dt)
        advance_wall(self.walls, v_cell[1], vx_list, z, dx, dt)
        f_wall = out[4]
        np.multiply(wall_force_n_per_m(self.walls, z, prm.unit_weight_n_m3, c, self._phi,
                                       self.max_wall_m, n_phi=self._n_phi), dx, out=f_wall)
        # Per road wheel: total, shear, wall and damper magnitude; per track the yaw moment of
        # the lateral forces about the road wheels and the wall force: one product.
        np.add(f_shear, f_damp, out=out[0:2])
        out[1] += f_wall
        np.hypot(f_damp[0], f_damp[1], out=out[5])
        sums = self._reduce @ out.reshape(6, -1).T  # (n + 2 n_tracks, 6)
        r_c = compaction_resistance_n(z.max(axis=1, keepdims=True), width, self._kc,
                                      self._kphi, self._n)
        self._apply_forces(pos, axes, sums, np.ravel(r_c).tolist(), load, vx_list, vby, wbx,
                           wbz)
        self.track_slip = slip

    def _apply_forces(self, pos, axes, sums: np.ndarray, compaction_n: list[float],
                      load: list[float], vx_list: list[float], vby: float, wbx: float,
                      wbz: float) -> None:
        """Apply each road wheel's share of the cell forces at its contact point, each
        track's rut resistance (its compaction resistance ``compaction_n`` as a rut state)
        on the hull at its centre line and its residual yaw moment; record the readings.
        ``sums`` (n + 2 n_tracks, 6): per road wheel its total x, y, shear x, y, wall and
        |damper| force, then per track the yaw moment (column 1), then per track the wall
        force (column 4)."""
        cid, bid, dt, prm = self.client, self.body_id, self.dt_s, self.params
        nt = len(self.tracks)
        ex, ey, ez, r = axes
        apply_force, world = p.applyExternalForce, p.WORLD_FRAME
        px, py, pz = pos
        links = self.links
        n = self.n
        rot = np.array(r).reshape(3, 3)  # body -> world
        points = (self._contact_base @ rot.T + pos).tolist()
        forces = (sums[:n, :2] @ rot[:, :2].T).tolist()
        rows = sums.tolist()
        for k in range(n):
            apply_force(bid, links[k], forces[k], points[k], world, physicsClientId=cid)
        res_out = [0.0] * n
        for i, ks in enumerate(self.tracks):
            # Compaction resistance (rut state) along the track, on the hull at its centre line.
            vt = vx_list[i]
            self.travel[i] += vt * dt
            r_c = compaction_n[i]
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
            mz = rows[n + i][1]
            if mz != 0.0:
                p.applyExternalTorque(bid, -1, (mz * ez[0], mz * ez[1], mz * ez[2]), world,
                                      physicsClientId=cid)
            vy_mean = vby + wbz * self.x_mid[i] - wbx * self.z_list[i]
            self.track_tanb[i] = vy_mean / vt if abs(vt) > 1e-3 else 0.0
        self.load, self.res = load, res_out
        self.fx = [row[2] for row in rows[:n]]
        self.fy = [row[3] + row[4] for row in rows[:n]]
        self.damping_n = [row[5] for row in rows[:n]]
        self.wall_n = [row[4] for row in rows[n + nt:]]

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

