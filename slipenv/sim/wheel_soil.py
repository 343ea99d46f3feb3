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

    σ ds/dt + V s = r ω - v,        σ db/dt + V b = v_lat,        V = max(|r ω|, |v|, |v_lat|)

whose steady state is the kinematic slip (with one reference speed V for both components, so
that (s, tan β) keeps the direction of the contact point's sliding velocity at large slip; at
ordinary slip V = |r ω| ≈ |v| and tan β = v_lat/|v|). At standstill V = 0 and the state
integrates the slip displacement, so a parked vehicle is held by a soil "spring" (the Janosi shear
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
        Below this speed the longitudinal soil damper fades in [m/s] (Pacejka §7.2: the
        relaxation model alone is an undamped spring at standstill, and its speed-dependent
        leak ratchets an oscillating parked vehicle downhill). Zero at and above this speed,
        so it never alters driving forces.
    damping_ratio : float
        Damping ratio of the soil "spring" (LuGre's σ1 term, Canudas de Wit et al. 1995).
        Sideways it acts at every speed, on the rate of the lateral shear deformation, so steady
        side slip and the force law are unchanged: undamped, a tracked vehicle turning at
        crawling speed rocks and slides at several Hz. Lengthwise it acts only below
        ``low_speed_mps``, on rω - v.
    damping_speed_mps : float
        Speed scale of the sideways damper [m/s]: weighted 1 / (1 + (V / this)⁴), about 1 at
        the tracked vehicle's 5 cm/s and about 0.01 at 0.6 m/s, where the relaxation leak
        V/σ already damps the spring.
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
        damping_ratio: float = 0.5,
        damping_speed_mps: float = 0.2,
    ) -> None:
        self.client = client
        self.body_id = body.body_id
        self.ground_id = ground_id
        self.force_model = force_model
        self.soil_map = soil_map
        self.dt_s = dt_s
        self.min_relaxation_m = min_relaxation_m
        self.inv_resistance_speed = 1.0 / resistance_speed_mps
        if not (math.isfinite(damping_ratio) and damping_ratio >= 0.0):
            raise ValueError(f"damping_ratio must be finite and >= 0, got {damping_ratio!r}")
        self.damping_ratio = float(damping_ratio)
        self.inv_low_speed = 1.0 / low_speed_mps
        self.inv_damping_speed = 1.0 / damping_speed_mps
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
        self.fixed_radius = [w.rolling_radius_m for w in spec.wheels]
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
        self.chassis_contact = False
        self.sample_soil(force=True)

    # -- soil ------------------------------------------------------------------------------
    def sample_soil(self, force: bool = False) -> None:
        """Sample the soil under every wheel and bind its force kernels (once per control step)."""
        uniform = isinstance(self.soil_map, UniformSoil)
        if uniform and not force:
            return
        if uniform:
            params = self.soil_map.params_at(np.zeros(1), np.zeros(1))
            rows = [params] * self.n
        else:
            links = p.getLinkStates(self.body_id, self.links, physicsClientId=self.client)
            xs = np.array([ls[0][0] for ls in links])
            ys = np.array([ls[0][1] for ls in links])
            params = self.soil_map.params_at(xs, ys)
            rows = [_params_row(params, k) for k in range(self.n)]
        self._soil_rows = rows
        self._h = [self.dt_s / max(float(sp.shear_modulus_m), self.min_relaxation_m)
                   for sp in rows]
        self._r_eff = [self._rolling_radius_m(sp, k) for k, sp in enumerate(rows)]
        kernels = {}
        for sp in rows:
            if id(sp) not in kernels:
                kernels[id(sp)] = _kernel(self.force_model, sp)
        self._kernels = [kernels[id(sp)] for sp in rows]
        self._damping = [self._critical_damping(k) for k in range(self.n)]

    def _critical_damping(self, k: int) -> tuple[float, float]:
        """Soil dampers of wheel ``k``: c_long [N s/m] on rω - v and d_lat [N per unit tan β].

        The spring is the slip state held still: stiffness C/σ [N/m] with C = dF/ds at s = 0 of
        the force law at the wheel's static load share (finite difference). Its damper c [N s/m]
        is ``damping_ratio`` times critical for the wheel's mass share, capped at half the
        explicit stability limit m/dt (a side force at the contact patch also rolls the body, so
        the mass it moves is less than the share: at the full limit a tracked vehicle shakes
        itself sideways at rest). Sideways it acts on the deformation rate σ dtanβ/dt, i.e.
        d_lat = c σ / dt per unit change of the state in one substep.
        """
        if not self.driven[k]:
            return 0.0, 0.0
        load = self.mass_share_kg * 9.81
        fx, _, _ = self._kernels[k](1e-3, 0.0, load)
        _, fy, _ = self._kernels[k](0.0, 1e-3, load)
        sigma = self.dt_s / self._h[k]
        cap = 0.5 * self.mass_share_kg / self.dt_s
        c_long, c_lat = (
            min(2.0 * self.damping_ratio * math.sqrt(stiffness / sigma * self.mass_share_kg), cap)
            for stiffness in (abs(fx) / 1e-3, abs(fy) / 1e-3)
        )
        return c_long, c_lat * sigma / self.dt_s

    def _rolling_radius_m(self, soil_params, k: int) -> float:
        if self.fixed_radius[k] is not None:  # a fitted model extension (slipenv diagnose)
            return self.fixed_radius[k]
        if bool(soil_params.deformable) and self.soil_radius[k] is not None:
            return self.soil_radius[k]
        return self.radius[k] * float(soil_params.rolling_radius_scale)

    # -- the substep -----------------------------------------------------------------------
    def apply(self) -> None:
        """Compute and apply the soil forces for the coming substep (the hot path)."""
        cid, bid, n = self.client, self.body_id, self.n
        contacts = p.getContactPoints(bodyA=bid, bodyB=self.ground_id, physicsClientId=cid)
        links = p.getLinkStates(bid, self.links, computeLinkVelocity=1, physicsClientId=cid)
        joints = p.getJointStates(bid, self.spin_joints, physicsClientId=cid)
        load = [0.0] * n
        acc = [None] * n  # load-weighted contact point and normal per wheel
        link_to_wheel = self.link_to_wheel
        for cp in contacts:
            f = cp[9]
            if f <= 0.0:
                continue
            k = link_to_wheel.get(cp[3])
            if k is None:
                self.chassis_contact = True
                continue
            pos, nrm = cp[6], cp[7]
            a = acc[k]
            if a is None:
                acc[k] = [f * pos[0], f * pos[1], f * pos[2], f * nrm[0], f * nrm[1], f * nrm[2]]
            else:
                a[0] += f * pos[0]
                a[1] += f * pos[1]
                a[2] += f * pos[2]
                a[3] += f * nrm[0]
                a[4] += f * nrm[1]
                a[5] += f * nrm[2]
            load[k] += f

        slip, tanb, h, r_eff, kernels = self.s, self.b, self._h, self._r_eff, self._kernels
        fx_out, fy_out, res_out = [0.0] * n, [0.0] * n, [0.0] * n
        inv_eps, inv_low, damping = self.inv_resistance_speed, self.inv_low_speed, self._damping
        inv_damp_speed = self.inv_damping_speed
        apply_force, world = p.applyExternalForce, p.WORLD_FRAME
        for k in range(n):
            w = load[k]
            if w <= 0.0:
                slip[k] = tanb[k] = 0.0
                continue
            a = acc[k]
            inv_w = 1.0 / w
            nx, ny, nz = a[3], a[4], a[5]
            inv = 1.0 / math.sqrt(nx * nx + ny * ny + nz * nz)
            nx, ny, nz = nx * inv, ny * inv, nz * inv
            cx, cy, cz = a[0] * inv_w, a[1] * inv_w, a[2] * inv_w
            ls = links[k]
            qx, qy, qz, qw = ls[1]
            # Axle = the link's y axis in world (the spin axis, invariant under spin).
            ex = 2.0 * (qx * qy - qw * qz)
            ey = 1.0 - 2.0 * (qx * qx + qz * qz)
            ez = 2.0 * (qy * qz + qw * qx)
            # Forward = axle × normal; lateral = normal × forward (to the left).
            fx_, fy_, fz_ = ey * nz - ez * ny, ez * nx - ex * nz, ex * ny - ey * nx
            inv = 1.0 / math.sqrt(fx_ * fx_ + fy_ * fy_ + fz_ * fz_)
            fx_, fy_, fz_ = fx_ * inv, fy_ * inv, fz_ * inv
            lx, ly, lz = ny * fz_ - nz * fy_, nz * fx_ - nx * fz_, nx * fy_ - ny * fx_
            vx, vy, vz = ls[6]
            v_long = vx * fx_ + vy * fy_ + vz * fz_
            if self.driven[k]:
                # Lateral slip is the sliding of the contact point, not of the wheel centre:
                # add ω × (contact - centre), which removes the chassis roll (rate × radius)
                # that would otherwise feed back into the side force.
                px, py, pz = ls[0]
                rx, ry, rz = cx - px, cy - py, cz - pz
                wx, wy, wz = ls[7]
                v_lat = ((vx + wy * rz - wz * ry) * lx + (vy + wz * rx - wx * rz) * ly
                         + (vz + wx * ry - wy * rx) * lz)
                hk = h[k]
                r_omega = r_eff[k] * joints[self.spin_index[k]][1]
                # One reference speed for both components, so that (s, tan β) points along
                # the contact point's sliding velocity (rω - v, v_lat) even at large slip: the
                # combined-slip laws split the resultant by this direction.
                v_ref = max(abs(r_omega), abs(v_long), abs(v_lat))
                s_old, t_old = slip[k], tanb[k]
                s = (s_old + hk * (r_omega - v_long)) / (1.0 + hk * v_ref)
                s = 1.0 if s > 1.0 else (-1.0 if s < -1.0 else s)
                t = (t_old + hk * v_lat) / (1.0 + hk * v_ref)
                t = 1.0 if t > 1.0 else (-1.0 if t < -1.0 else t)
                slip[k], tanb[k] = s, t
                f_long, f_lat, res = kernels[k](s, t, w)
                fx_out[k], fy_out[k] = f_long, f_lat
                # Side: shear-rate damping (LuGre's σ1 term), on the rate of the lateral shear
                # deformation σ dtanβ/dt. It vanishes in steady side slip, so the force law
                # stays exact, but damps the soil "spring" that the relaxation state is at
                # crawling speed (a turning tracked vehicle otherwise rocks at several Hz).
                c_long, d_lat = damping[k]
                # Faded out with speed, as LuGre's σ1 is (Canudas de Wit et al. 2003): the
                # relaxation leak V/σ damps the spring by itself once the wheel moves fast.
                fade = v_ref * inv_damp_speed
                fade *= fade
                f_lat -= d_lat * (t - t_old) / (1.0 + fade * fade)
                # Longitudinal: the same damper, on rω - v, but only near standstill (a braked
                # wheel); when rolling, a damper at the patch would act on the wheel's small
                # spin inertia and an explicit one would destabilise it.
                speed = max(abs(v_long), abs(r_omega), abs(v_lat)) * inv_low
                if speed < 1.0:
                    f_long += (1.0 - speed) * c_long * (r_omega - v_long)
                # Shear (traction, side force) acts at the contact patch: the motor feels r F.
                apply_force(bid, self.links[k],
                            (f_long * fx_ + f_lat * lx, f_long * fy_ + f_lat * ly,
                             f_long * fz_ + f_lat * lz),
                            (cx, cy, cz), world, physicsClientId=cid)
            else:
                res = kernels[k](0.0, 0.0, w)[2]
            # Resistance opposes travel; a linear ramp below resistance_speed_mps keeps it
            # continuous (and explicit-stable) through zero and exact above it.
            ramp = v_long * inv_eps
            r_k = res * (1.0 if ramp > 1.0 else (-1.0 if ramp < -1.0 else ramp))
            res_out[k] = abs(r_k)
            if r_k != 0.0:
                # Compaction resistance comes from normal stresses that point at the axle: it
                # acts through the wheel centre and puts no moment on the wheel.
                apply_force(bid, self.links[k], (-r_k * fx_, -r_k * fy_, -r_k * fz_), ls[0],
                            world, physicsClientId=cid)
        self.load, self.fx, self.fy, self.res = load, fx_out, fy_out, res_out

    # -- reading ---------------------------------------------------------------------------
    def contact_state(self) -> WheelContactState:
        """Per-wheel slip, load and forces of the last substep, as arrays."""
        load = np.array(self.load)
        return WheelContactState(
            slip=np.array(self.s), tan_beta=np.array(self.b), load_n=load,
            fx_n=np.array(self.fx), fy_n=np.array(self.fy), resistance_n=np.array(self.res),
            in_contact=load > 0.0,
        )

    def joint_torques(self) -> list[float]:
        """Motor torque of each spin joint at the last substep [N m]."""
        states = p.getJointStates(self.body_id, self.spin_joints, physicsClientId=self.client)
        return [js[3] for js in states]


def _kernel(model, soil):
    """A per-wheel ``(slip, tan_beta, load) -> (fx, fy, resistance)`` for ``model`` on ``soil``.

    slipenv's models give a float kernel; any other ForceModel is wrapped (correct, slower:
    one vectorised call per wheel).
    """
    if hasattr(model, "scalar_kernel"):
        return model.scalar_kernel(soil)

    def kernel(slip: float, tan_beta: float, load_n: float) -> tuple[float, float, float]:
        w = np.array([load_n])
        fx, fy = model(np.array([slip]), np.array([tan_beta]), w, soil)
        return float(fx[0]), float(fy[0]), float(model.resistance_n(w, soil)[0])

    return kernel


def _params_row(params, k: int):
    """The soil parameters of wheel ``k`` from per-wheel arrays (scalars pass through)."""
    return type(params)(*(
        (v[k] if isinstance(v, np.ndarray) and v.ndim else v) for v in params
    ))
