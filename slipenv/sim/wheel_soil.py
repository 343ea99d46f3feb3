"""Inject the terramechanic force law at every wheel contact, every physics substep.

Per substep: one batched query each for contacts, wheel link states and spin-joint states;
scalar kinematics per wheel; the force law; one ``applyExternalForce`` per loaded wheel at its
contact patch. Tiny numpy arrays per wheel cost more than the physics (DESIGN §6), so the
substep loop is plain float arithmetic: force models that offer ``scalar(...)`` (all of
slipenv's do) are called per wheel with floats; any other :class:`ForceModel` is called once
per substep on arrays. The soil under each wheel is sampled from the soil map once per control
step (a wheel moves millimetres in one step; maps blend over decimetres).

Slip (the convention of ``slipenv.terramechanics``): s = (r ω - v) / max(|r ω|, |v|), in
[-1, 1], > 0 in drive; tan β = v_lat / |v_long|. Both are *states* with a relaxation length σ,
as in tyre models (Pacejka, Tyre and Vehicle Dynamics, §7.2.1):

    σ ds/dt + V s = r ω - v,        V = max(|r ω|, |v|)
    σ db/dt + V_y b = v_lat,        V_y = max(|v_long|, |v_lat|)

whose steady state is the kinematic slip. At standstill V = 0 and the state integrates the
slip displacement, so a parked vehicle is held by a soil "spring" (the Janosi shear
deformation) instead of creeping, and a wheel spinning at v = 0 reaches s = 1 with no
division by zero. The update is backward Euler, unconditionally stable for this linear ODE,
which keeps a light wheel smooth even when its spin time constant falls below the time step
(DESIGN §3). σ is the soil's shear deformation modulus K (Janosi), floored at
``min_relaxation_m``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pybullet as p

from slipenv.terramechanics.models import ForceModel
from slipenv.terramechanics.soil_map import SoilMap, UniformSoil
from slipenv.vehicles.body import VehicleBody
from slipenv.vehicles.spec import VehicleSpec


@dataclass
class WheelContactState:
    """Per-wheel quantities of the last substep (ground truth for ``info``).

    Arrays of shape (n_wheels,): slip ratio, tan of slip angle, normal load [N], longitudinal
    force (traction, before resistance) and lateral force [N], motion resistance [N], contact.
    """

    slip: np.ndarray
    tan_beta: np.ndarray
    load_n: np.ndarray
    fx_n: np.ndarray
    fy_n: np.ndarray
    resistance_n: np.ndarray
    in_contact: np.ndarray


class WheelSoilInjector:
    """Applies the force law at each wheel contact of one vehicle, once per substep.

    Parameters
    ----------
    client : int
        PyBullet client id.
    spec : VehicleSpec
        The vehicle.
    body : VehicleBody
        Its PyBullet handles.
    ground_id : int
        The terrain body id.
    force_model : ForceModel
        Traction / side force law (``slipenv.terramechanics.models``).
    soil_map : SoilMap
        Soil at each contact position.
    dt_s : float
        Physics substep [s].
    min_relaxation_m : float
        Lower bound of the slip relaxation length σ [m].
    resistance_speed_mps : float
        Below this speed the motion resistance ramps linearly to zero [m/s] (resistance opposes
        motion and vanishes at standstill: it is not static friction).
    low_speed_mps : float
        Below this speed a critically damped soil term fades in [m/s] (Pacejka §7.2: the
        relaxation model alone is an undamped spring at standstill, and its speed-dependent
        leak ratchets an oscillating parked vehicle downhill). Zero at and above this speed,
        so it never alters driving forces.
    """

    def __init__(
        self,
        client: int,
        spec: VehicleSpec,
        body: VehicleBody,
        ground_id: int,
        force_model: ForceModel,
        soil_map: SoilMap,
        dt_s: float,
        min_relaxation_m: float = 0.01,
        resistance_speed_mps: float = 0.02,
        low_speed_mps: float = 0.02,
    ) -> None:
        self.client = client
        self.body_id = body.body_id
        self.ground_id = ground_id
        self.force_model = force_model
        self._scalar = getattr(force_model, "scalar", None)
        self.soil_map = soil_map
        self.dt_s = dt_s
        self.min_relaxation_m = min_relaxation_m
        self.inv_resistance_speed = 1.0 / resistance_speed_mps
        self.inv_low_speed = 1.0 / low_speed_mps
        wheels_on_ground = len(spec.wheels)
        self.mass_share_kg = spec.mass_kg / wheels_on_ground
        self.n = len(spec.wheels)
        self.links = list(body.wheel_links)
        self.link_to_wheel = {link: k for k, link in enumerate(self.links)}
        self.spin_joints = [j for j in body.spin_joints if j is not None]
        joint_pos = {j: i for i, j in enumerate(self.spin_joints)}
        self.spin_index = [joint_pos.get(j, -1) if j is not None else -1 for j in body.spin_joints]
        self.driven = [w.role == "driven" for w in spec.wheels]
        self.radius = [w.radius_m for w in spec.wheels]
        self.soil_radius = [w.soil_rolling_radius_m for w in spec.wheels]
        self.reset()

    def reset(self) -> None:
        """Zero the slip states and the recorded contact state."""
        n = self.n
        self.s = [0.0] * n
        self.b = [0.0] * n
        self.load = [0.0] * n
        self.fx = [0.0] * n
        self.fy = [0.0] * n
        self.res = [0.0] * n
        self.joint_torque_sum = [0.0] * len(self.spin_joints)
        self.substeps_since_read = 0
        self.chassis_contact = False
        self.sample_soil(force=True)

    # -- soil ------------------------------------------------------------------------------
    def sample_soil(self, force: bool = False) -> None:
        """Sample the soil under every wheel (called once per control step)."""
        uniform = isinstance(self.soil_map, UniformSoil)
        if uniform and not force:
            return
        if uniform:
            params = self.soil_map.params_at(np.zeros(1), np.zeros(1))
            self._soil_arrays = params
            per_wheel = [params] * self.n
        else:
            links = p.getLinkStates(self.body_id, self.links, physicsClientId=self.client)
            xs = np.array([ls[0][0] for ls in links])
            ys = np.array([ls[0][1] for ls in links])
            params = self.soil_map.params_at(xs, ys)
            self._soil_arrays = params
            per_wheel = [_params_row(params, k) for k in range(self.n)]
        self._soil_rows = per_wheel
        self._h = [self.dt_s / max(float(sp.shear_modulus_m), self.min_relaxation_m)
                   for sp in per_wheel]
        self._r_eff = [self._rolling_radius_m(sp, k) for k, sp in enumerate(per_wheel)]
        self._damping = [self._critical_damping(k) for k in range(self.n)]

    def _critical_damping(self, k: int) -> tuple[float, float]:
        """Low-speed damping (c_long, c_lat) [N s/m] of wheel ``k``: critical for the soil spring.

        The spring is the slip state at standstill: stiffness C/σ with C = dF/ds at s = 0 of the
        force law at the wheel's static load share (finite difference). Capped at the explicit
        stability limit m/dt.
        """
        if not self.driven[k]:
            return 0.0, 0.0
        load = np.array([self.mass_share_kg * 9.81])
        eps = np.array([1e-3])
        zero = np.zeros(1)
        soil = self._soil_rows[k]
        fx, _ = self.force_model(eps, zero, load, soil)
        _, fy = self.force_model(zero, eps, load, soil)
        sigma = self.dt_s / self._h[k]
        out = []
        for stiffness in (abs(float(fx[0])) / 1e-3, abs(float(fy[0])) / 1e-3):
            c = 2.0 * math.sqrt(stiffness / sigma * self.mass_share_kg)
            out.append(min(c, self.mass_share_kg / self.dt_s))
        return out[0], out[1]

    def _rolling_radius_m(self, soil_params, k: int) -> float:
        if bool(soil_params.deformable) and self.soil_radius[k] is not None:
            return self.soil_radius[k]
        return self.radius[k] * float(soil_params.rolling_radius_scale)

    # -- the substep -----------------------------------------------------------------------
    def apply(self) -> None:
        """Compute and apply the soil forces for the coming substep."""
        cid, bid, n = self.client, self.body_id, self.n
        contacts = p.getContactPoints(bodyA=bid, bodyB=self.ground_id, physicsClientId=cid)
        links = p.getLinkStates(bid, self.links, computeLinkVelocity=1, physicsClientId=cid)
        joints = p.getJointStates(bid, self.spin_joints, physicsClientId=cid)
        load = [0.0] * n
        acc = [[0.0] * 6 for _ in range(n)]  # load-weighted contact point and normal
        link_to_wheel = self.link_to_wheel
        for cp in contacts:
            f = cp[9]
            k = link_to_wheel.get(cp[3])
            if k is None:
                if f > 0.0:
                    self.chassis_contact = True
                continue
            if f > 0.0:
                load[k] += f
                a, pos, nrm = acc[k], cp[6], cp[7]
                a[0] += f * pos[0]
                a[1] += f * pos[1]
                a[2] += f * pos[2]
                a[3] += f * nrm[0]
                a[4] += f * nrm[1]
                a[5] += f * nrm[2]
        torque_sum = self.joint_torque_sum
        for i, js in enumerate(joints):
            torque_sum[i] += js[3]
        self.substeps_since_read += 1

        slip, tanb, h, r_eff = self.s, self.b, self._h, self._r_eff
        frames = [None] * n
        for k in range(n):
            if load[k] <= 0.0:
                slip[k] = tanb[k] = 0.0
                continue
            a = acc[k]
            nx, ny, nz = a[3], a[4], a[5]
            inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
            nx, ny, nz = nx * inv, ny * inv, nz * inv
            qx, qy, qz, qw = links[k][1]
            # Axle = the link's y axis in world (the spin axis, invariant under spin).
            ex = 2.0 * (qx * qy - qw * qz)
            ey = 1.0 - 2.0 * (qx * qx + qz * qz)
            ez = 2.0 * (qy * qz + qw * qx)
            # Forward = axle × normal; lateral = normal × forward (to the left).
            fx_, fy_, fz_ = ey * nz - ez * ny, ez * nx - ex * nz, ex * ny - ey * nx
            inv = 1.0 / math.sqrt(fx_ * fx_ + fy_ * fy_ + fz_ * fz_)
            fx_, fy_, fz_ = fx_ * inv, fy_ * inv, fz_ * inv
            lx, ly, lz = ny * fz_ - nz * fy_, nz * fx_ - nx * fz_, nx * fy_ - ny * fx_
            vx, vy, vz = links[k][6]
            v_long = vx * fx_ + vy * fy_ + vz * fz_
            if self.driven[k]:
                # Lateral slip is the sliding of the contact point, not of the wheel centre:
                # add ω × (contact - centre), which removes the chassis roll (rate × radius)
                # that would otherwise feed back into the side force.
                w = load[k]
                px, py, pz = links[k][0]
                rx, ry, rz = a[0] / w - px, a[1] / w - py, a[2] / w - pz
                wx, wy, wz = links[k][7]
                v_lat = ((vx + wy * rz - wz * ry) * lx + (vy + wz * rx - wx * rz) * ly
                         + (vz + wx * ry - wy * rx) * lz)
                hk = h[k]
                r_omega = r_eff[k] * joints[self.spin_index[k]][1]
                frames[k] = (fx_, fy_, fz_, lx, ly, lz, v_long, v_lat, r_omega)
                v_ref = max(abs(r_omega), abs(v_long))
                s = (slip[k] + hk * (r_omega - v_long)) / (1.0 + hk * v_ref)
                slip[k] = 1.0 if s > 1.0 else (-1.0 if s < -1.0 else s)
                v_ref_y = max(abs(v_long), abs(v_lat))
                t = (tanb[k] + hk * v_lat) / (1.0 + hk * v_ref_y)
                tanb[k] = 1.0 if t > 1.0 else (-1.0 if t < -1.0 else t)
            else:
                frames[k] = (fx_, fy_, fz_, lx, ly, lz, v_long, 0.0, 0.0)

        fx, fy, res = self._forces(slip, tanb, load)
        self.load, self.fx, self.fy, self.res = load, fx, fy, res
        inv_eps = self.inv_resistance_speed
        inv_low, damping = self.inv_low_speed, self._damping
        links_k, wheel_states = self.links, links
        for k in range(n):
            fr = frames[k]
            if fr is None:
                continue
            v_long = fr[6]
            # Resistance opposes travel; a linear ramp below resistance_speed_mps keeps it
            # continuous (and explicit-stable) through zero and exact above it.
            ramp = v_long * inv_eps
            r_k = res[k] * (1.0 if ramp > 1.0 else (-1.0 if ramp < -1.0 else ramp))
            fw0, fw1, fw2, la0, la1, la2 = fr[0], fr[1], fr[2], fr[3], fr[4], fr[5]
            if self.driven[k]:
                f_long, f_lat = fx[k], fy[k]
                r_omega, v_lat = fr[8], fr[7]
                speed = max(abs(v_long), abs(r_omega), abs(v_lat)) * inv_low
                if speed < 1.0:
                    c_long, c_lat = damping[k]
                    fade = 1.0 - speed
                    f_long += fade * c_long * (r_omega - v_long)
                    f_lat -= fade * c_lat * v_lat
                w = load[k]
                a = acc[k]
                # Shear (traction, side force) acts at the contact patch: the motor feels r F.
                p.applyExternalForce(
                    bid, links_k[k],
                    (f_long * fw0 + f_lat * la0, f_long * fw1 + f_lat * la1,
                     f_long * fw2 + f_lat * la2),
                    (a[0] / w, a[1] / w, a[2] / w), p.WORLD_FRAME, physicsClientId=cid,
                )
            if r_k != 0.0:
                # Compaction resistance comes from normal stresses that point at the axle: it
                # acts through the wheel centre and puts no moment on the wheel.
                p.applyExternalForce(
                    bid, links_k[k], (-r_k * fw0, -r_k * fw1, -r_k * fw2),
                    wheel_states[k][0], p.WORLD_FRAME, physicsClientId=cid,
                )

    def _forces(self, slip, tanb, load) -> tuple[list, list, list]:
        scalar = self._scalar
        n = self.n
        if scalar is not None:
            rows = self._soil_rows
            fx, fy, res = [0.0] * n, [0.0] * n, [0.0] * n
            for k in range(n):
                if load[k] > 0.0:
                    fx[k], fy[k], res[k] = scalar(slip[k], tanb[k], load[k], rows[k])
            return fx, fy, res
        load_a = np.array(load)
        fx_a, fy_a = self.force_model(np.array(slip), np.array(tanb), load_a, self._soil_arrays)
        res_a = self.force_model.resistance_n(load_a, self._soil_arrays)
        mask = load_a > 0.0
        return (
            np.where(mask, fx_a, 0.0).tolist(),
            np.where(mask, fy_a, 0.0).tolist(),
            np.where(mask, res_a, 0.0).tolist(),
        )

    # -- reading ---------------------------------------------------------------------------
    def contact_state(self) -> WheelContactState:
        """Per-wheel slip, load and forces of the last substep, as arrays."""
        load = np.array(self.load)
        return WheelContactState(
            slip=np.array(self.s), tan_beta=np.array(self.b), load_n=load,
            fx_n=np.array(self.fx), fy_n=np.array(self.fy), resistance_n=np.array(self.res),
            in_contact=load > 0.0,
        )

    def read_mean_joint_torque(self) -> list[float]:
        """Mean motor torque of each spin joint since the last read [N m] (then restart)."""
        m = max(self.substeps_since_read, 1)
        out = [t / m for t in self.joint_torque_sum]
        self.joint_torque_sum = [0.0] * len(self.spin_joints)
        self.substeps_since_read = 0
        return out


def _params_row(params, k: int):
    """The soil parameters of wheel ``k`` from per-wheel arrays (scalars pass through)."""
    return type(params)(*(
        (v[k] if isinstance(v, np.ndarray) and v.ndim else v) for v in params
    ))
