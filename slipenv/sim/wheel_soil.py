"""Inject the terramechanic force law at every wheel contact, every physics substep.

The substep runs in C (``slipenv/sim/_wheel_loop.c``, the ``apply`` of every injector): one
batched query each for contacts, wheel link states and spin-joint states (through Bullet's C
API once verified against pybullet's Python API, `native_queries`); per wheel, the contact
frame, the slip state, the force law and the soil dampers; one ``applyExternalForce`` per
loaded wheel at its contact patch and one at its centre for the resistance. The physics is not
written here nor in the loop: every law is a function of
``slipenv/terramechanics/_laws.h``, the one implementation, which the Python API of
`slipenv.terramechanics` binds too (`slip_dynamics` gives the sources and equations of the
slip relaxation step, the two soil dampers and the rate-independent motion resistance). A
force model that is not one of slipenv's (a user's law: no `ForceModel.kernel_constants`) is
called back as its Python kernel (`slipenv.terramechanics.wheel_kernel`). This class binds
the per-wheel constants once per control step, when it samples the soil under each wheel from
the soil map (a wheel moves millimetres in one step; maps blend over decimetres).

Slip follows the convention of ``slipenv.terramechanics.contact``, the slip angle that of each
wheel's force law (`models.slip_angle_convention`: Reina's v_lat/v_x for Reina's law, the
sliding velocity's for the shear laws, `slip_dynamics.relax_slip`); the slip states relax over
the contact's own length (`slip_dynamics.contact_relaxation_length_m`): for a wheel the front
arc r acos(1 - z/r) at its Bekker sinkage z under the static load share (Wong Ch. 5; Pacejka
§7.2.1, sigma ~ a), floored at ``min_relaxation_m``. The road wheels of the old per-wheel track
law get their own arc too: with half the track length (0.24 m) each road wheel's separate state
became a soft spring and the lateral damper carried 3.2 % of the force on Yamauchi's circle
(0.8 % with the arc); the track's memory along its length belongs to the track model.

Motion resistance (compaction + rolling) is rate-independent: an elasto-plastic Coulomb element
per wheel (`slip_dynamics.rut_resistance_n`): full R against the travel at any speed, and at
rest whatever holds the wheel, at most R. Driven wheels resist along their heading; castors
(ideal swivels) along their contact velocity (`slip_dynamics.rut_resistance_vector_n`).
Optionally (``multi_pass``) a wheel running in the rut of the wheel ahead compacts only the
soil below that rut (`bekker.rut_following_compaction_n`). With a force model's
``slip_sinkage="accumulated"`` each driven wheel carries one more state, the depth it has dug
below its static rut (`dug`): it grows with the distance the rim slides and relaxes over the
distance the wheel rolls, over the same patch length as the slip (`models.dug_depth_step`),
and the soil dug is bulldozed ahead of the wheel as part of its resistance
(`models.dug_depth_resistance`); a wheel off the ground leaves its rut (the state is zeroed).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim.bullet_native import PYBULLET_API_ENV, client_table, python_api_forced
from slipenv.sim.compiled import wheel_loop_module
from slipenv.terramechanics.bekker import rut_load_ratio, wheel_sinkage_float_m
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import ForceModel, slip_angle_convention, wheel_kernel
from slipenv.terramechanics.slip_dynamics import (
    contact_relaxation_length_m,
    critical_damping_ns_per_m,
)
from slipenv.terramechanics.soil import SoilParams
from slipenv.terramechanics.soil_map import SoilMap, UniformSoil, soil_rows
from slipenv.vehicles.body import VehicleBody
from slipenv.vehicles.spec import VehicleSpec

p = import_pybullet()  # the banner-free first import (see slipenv.pybullet_quiet)

_DS = 1e-3  # [-] slip step of the finite-difference slip stiffness


@dataclass
class WheelContactState:
    """Per-wheel quantities of the last substep (ground truth for ``info``).

    Arrays of shape (n_wheels,): slip ratio, tan of slip angle (the relaxed state, in the
    wheel's law's convention: `models.slip_angle_convention`), normal load [N], longitudinal
    force (traction, before resistance) and lateral force [N], motion resistance [N], contact,
    and ``damper_n`` [N]: the numerical dampers' share of the force applied at the wheel, |soil
    longitudinal damper| + |soil lateral damper| + |pre-sliding damper of the resistance
    element|. ``fx_n`` and ``fy_n`` are the force law's values without the soil dampers;
    ``resistance_n`` is the applied resistance, whose damper part is zero once the wheel
    slides (moves more than ``resistance_stick_m``).
    """

    slip: np.ndarray
    tan_beta: np.ndarray
    load_n: np.ndarray
    fx_n: np.ndarray
    fy_n: np.ndarray
    resistance_n: np.ndarray
    in_contact: np.ndarray
    damper_n: np.ndarray


def _read(name: str) -> Any:
    """A read-only property: the compiled loop's per-wheel field `name`, as a list."""
    def get(self: WheelSoilInjector) -> Any:
        return getattr(self._loop, name)
    return property(get, doc=f"Per-wheel ``{name}`` of the last substep (read-only).")


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
    resistance_stick_m : float
        Pre-sliding displacement x_0 [m] of the motion-resistance element
        (`slip_dynamics.rut_resistance_n`): the resistance reaches its full, rate-independent
        value R after this much travel, and a wheel held by less than R moves at most this far.
        A numerical regulariser of Coulomb's law (Dupont et al. 2002), kept well below the
        contact length.
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
        ``low_speed_mps``, on rω - v. The pre-sliding damper of the resistance element uses the
        same ratio.
    damping_speed_mps : float
        Speed scale of the sideways damper [m/s]: weighted 1 / (1 + (V_b / this)⁴), V_b the
        leak speed of the lateral slip state (`slip_dynamics.relax_slip`), about 1 at the
        tracked vehicle's 5 cm/s and about 0.01 at 0.6 m/s, where the relaxation leak V_b/σ
        already damps the spring.
    multi_pass : bool
        If True, a wheel running in the rut of the wheel ahead of it (same side, its contact
        within half a width of that wheel's line) meets only the compaction of the soil below
        that rut (`bekker.rut_following_compaction_n`). Default False.
    castor_own_geometry : bool
        If True, a castor's motion resistance is the Bekker compaction of its own wheel (its
        radius, width and contact length; `ForceModel.with_geometry`), not of the driven
        wheels' geometry the force model was built for. Default False (see
        ``SlipEnvConfig.castor_own_geometry`` for why).
    native_queries : bool or None
        Read PyBullet and apply the forces through Bullet's C API, which pybullet exports,
        instead of through pybullet's Python functions (`slipenv.sim.bullet_native`): the same
        server commands without building tuples. The loop verifies its native readings against
        the Python API (`slipenv.sim.bullet_native` says when) and keeps the Python API if
        they differ. None (default) when available and ``SLIPENV_PYBULLET_API`` is not set,
        True to require it (ValueError if it cannot), False for the Python API.
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
        resistance_stick_m: float = 1e-3,
        low_speed_mps: float = 0.02,
        damping_ratio: float = 0.5,
        damping_speed_mps: float = 0.2,
        multi_pass: bool = False,
        castor_own_geometry: bool = False,
        native_queries: bool | None = None,
    ) -> None:
        for key, value in (("dt_s", dt_s), ("min_relaxation_m", min_relaxation_m),
                           ("resistance_stick_m", resistance_stick_m),
                           ("low_speed_mps", low_speed_mps),
                           ("damping_speed_mps", damping_speed_mps)):
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{key} must be finite and > 0, got {value!r}")
        if not (math.isfinite(damping_ratio) and damping_ratio >= 0.0):
            raise ValueError(f"damping_ratio must be finite and >= 0, got {damping_ratio!r}")
        if native_queries is not None and not isinstance(native_queries, bool):
            raise ValueError(f"native_queries must be True, False or None, got "
                             f"{native_queries!r}")
        self.client = client
        self.body_id = body.body_id
        self.ground_id = ground_id
        self.force_model = force_model
        self.soil_map = soil_map
        self.dt_s = dt_s
        self.min_relaxation_m = min_relaxation_m
        self.resistance_stick_m = resistance_stick_m
        self.low_speed_mps = low_speed_mps
        self.damping_ratio = float(damping_ratio)
        self.damping_speed_mps = damping_speed_mps
        self.mass_share_kg = spec.mass_kg / len(spec.wheels)
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
        self.width = [w.width_m for w in spec.wheels]
        self.multi_pass = bool(multi_pass)
        self._f_r = float(getattr(force_model, "rolling_resistance_coeff", 0.0))
        self.leaders = _rut_leaders(spec) if self.multi_pass else [(-1, -1)] * self.n
        self._models = _wheel_models(spec, force_model, castor_own_geometry)
        self._forward_angle = [slip_angle_convention(m) == "reina" for m in self._models]
        self._loop = wheel_loop_module().WheelLoop(
            p, self.body_id, self.ground_id, self.client, list(self.links),
            list(self.spin_joints), self.dt_s, self.resistance_stick_m, self.damping_speed_mps,
            self.low_speed_mps, self.multi_pass)
        self._bind_native(native_queries)
        # The substep is the C loop itself: no Python frame per substep.
        self.apply = self._loop.apply  # type: ignore[method-assign]
        self.reset()

    def _bind_native(self, native_queries: bool | None) -> None:
        """Switch the compiled loop to Bullet's C API (`native_queries`)."""
        if native_queries is False:
            return
        table = None if python_api_forced() else client_table()
        if table is not None:
            try:
                self._loop.bind_native(*table)
                return
            except OSError as exc:
                reason = str(exc)
        elif python_api_forced():
            reason = f"{PYBULLET_API_ENV} is set"
        else:
            reason = "pybullet's client table was not found in its symbol table"
        if native_queries:
            raise ValueError(f"native_queries=True but native PyBullet access is unavailable "
                             f"({reason})")

    @property
    def native_queries(self) -> bool:
        """True if the substeps read PyBullet through Bullet's C API (`native_queries`)."""
        return bool(self._loop.native)

    # The per-wheel state and the last substep's values live in the loop (read here as lists).
    s = _read("s")
    b = _read("b")
    load = _read("load")
    fx = _read("fx")
    fy = _read("fy")
    res = _read("res")
    damper = _read("damper")
    rut = _read("rut")
    dug = _read("dug")
    rut_vec = _read("rut_vec")
    resistance_force_n = _read("resistance_force_n")

    @property
    def chassis_contact(self) -> bool:
        """Whether a body other than a wheel touched the ground since it was last cleared."""
        return bool(self._loop.chassis_contact)

    @chassis_contact.setter
    def chassis_contact(self, value: bool) -> None:
        self._loop.chassis_contact = bool(value)

    def reset(self) -> None:
        """Zero the slip states and the recorded contact state."""
        self._loop.reset()
        self.sample_soil(force=True)

    # -- soil ------------------------------------------------------------------------------
    def sample_soil(self, force: bool = False) -> None:
        """Sample the soil under every wheel and bind its force kernels (once per control step)."""
        uniform = isinstance(self.soil_map, UniformSoil)
        if uniform and not force:
            return
        if uniform:
            rows = soil_rows(self.soil_map, [0.0] * self.n, [0.0] * self.n)
        else:
            links = p.getLinkStates(self.body_id, self.links, physicsClientId=self.client)
            rows = soil_rows(self.soil_map, [ls[0][0] for ls in links],
                             [ls[0][1] for ls in links])
        self._soil_rows = rows
        self._sigma = [self._relaxation_m(sp, k) for k, sp in enumerate(rows)]
        self._h = [self.dt_s / sigma for sigma in self._sigma]
        self._r_eff = [self._rolling_radius_m(sp, k) for k, sp in enumerate(rows)]
        kernels: dict[tuple[int, int], Any] = {}
        for model, sp in zip(self._models, rows, strict=True):
            if (id(model), id(sp)) not in kernels:
                kernels[id(model), id(sp)] = wheel_kernel(model, sp)
        self._kernels = [kernels[id(m), id(sp)] for m, sp in zip(self._models, rows, strict=True)]
        self._damping = [self._soil_damping(k) for k in range(self.n)]
        self._rut_ratio = [self._rut_load_ratios(k, sp) for k, sp in enumerate(rows)]
        self._rut_damping = [self._resistance_damping(k) for k in range(self.n)]
        set_wheel = self._loop.set_wheel
        laws: dict[tuple[int, int], Any] = {}
        for k, (model, sp) in enumerate(zip(self._models, rows, strict=True)):
            law = laws.get((id(model), id(sp)))
            if law is None:
                # slipenv's models run their C law; a user's law is called back (its kernel).
                hook = getattr(model, "kernel_constants", None)
                law = hook(sp) if hook is not None else None
                laws[id(model), id(sp)] = law = law if law is not None else self._kernels[k]
            set_wheel(k, self.driven[k], self.spin_index[k], self._r_eff[k], self._h[k],
                      *self._damping[k], self._rut_damping[k], *self.leaders[k],
                      *self._rut_ratio[k], law, self._f_r, self._forward_angle[k])

    def soil_at_wheel(self, k: int) -> SoilParams:
        """The soil (floats) under wheel ``k`` at the last `sample_soil` (read-only)."""
        return self._soil_rows[k]

    def relaxation_length_m(self, k: int) -> float:
        """Slip relaxation length σ [m] of wheel ``k`` on its current soil (read-only)."""
        return float(self._sigma[k])

    def static_sinkage_m(self, k: int) -> float:
        """Bekker sinkage z [m] of wheel ``k`` under its static load share (Wong Ch. 5)."""
        sp = self._soil_rows[k]
        load = self.mass_share_kg * G_MPS2
        return _wheel_sinkage_m(load, self.width[k], 2.0 * self.radius[k], _bekker_row(sp))

    def _relaxation_m(self, soil_params: SoilParams, k: int) -> float:
        """σ of wheel ``k``: the front contact arc at its static sinkage (road wheels too)."""
        load = self.mass_share_kg * G_MPS2
        z = _wheel_sinkage_m(load, self.width[k], 2.0 * self.radius[k], _bekker_row(soil_params))
        return contact_relaxation_length_m(self.radius[k], z, self.min_relaxation_m)

    def _resistance_damping(self, k: int) -> float:
        """Pre-sliding damper c [N s/m] of wheel ``k``'s resistance element: ``damping_ratio``
        of critical for the spring R/x_0 at the static load share (capped as the soil dampers)."""
        load = self.mass_share_kg * G_MPS2
        res = self._kernels[k](0.0, 0.0, load)[2]
        cap = 0.5 * self.mass_share_kg / self.dt_s
        return critical_damping_ns_per_m(res, self.resistance_stick_m, self.mass_share_kg,
                                         self.damping_ratio, cap)

    def rolling_radius_m(self, k: int) -> float:
        """Effective rolling radius r_eff [m] of wheel ``k`` on its current soil (read-only)."""
        return float(self._r_eff[k])

    def _soil_damping(self, k: int) -> tuple[float, float]:
        """Soil dampers of wheel ``k``: c_long [N s/m] on rω - v and d_lat [N per unit Δtan β].

        The spring is the slip state held still: stiffness C/σ [N/m] with C = dF/ds at s = 0 of
        the force law at the wheel's static load share (finite difference). Its damper
        (`critical_damping_ns_per_m`) is ``damping_ratio`` times critical for the wheel's mass
        share, capped at half the explicit stability limit m/dt (a side force at the contact
        patch also rolls the body, so the mass it moves is less than the share: at the full
        limit a tracked vehicle shakes itself sideways at rest). Sideways it acts on the
        deformation rate σ dtanβ/dt, i.e. d_lat = c σ / dt per unit change of the state in one
        substep (`lateral_soil_damping_n`).
        """
        if not self.driven[k]:
            return 0.0, 0.0
        load = self.mass_share_kg * G_MPS2
        fx, _, _ = self._kernels[k](_DS, 0.0, load)
        _, fy, _ = self._kernels[k](0.0, _DS, load)
        sigma = self.dt_s / self._h[k]
        cap = 0.5 * self.mass_share_kg / self.dt_s
        c_long, c_lat = (critical_damping_ns_per_m(stiffness, sigma, self.mass_share_kg,
                                                   self.damping_ratio, cap)
                         for stiffness in (abs(fx) / _DS, abs(fy) / _DS))
        return c_long, c_lat * sigma / self.dt_s

    def _rolling_radius_m(self, soil_params: SoilParams, k: int) -> float:
        fixed, on_soil = self.fixed_radius[k], self.soil_radius[k]
        if fixed is not None:  # a fitted model extension (slipenv diagnose)
            return fixed
        if bool(soil_params.deformable) and on_soil is not None:
            return on_soil
        return self.radius[k] * float(soil_params.rolling_radius_scale)

    # -- the substep -----------------------------------------------------------------------
    def apply(self) -> None:
        """Compute and apply the soil forces for the coming substep (the hot path).

        Runs the compiled loop (``_wheel_loop.c``; each instance binds the loop's own
        ``apply`` over this method, so no Python frame runs per substep). Per loaded wheel: the
        contact frame, then for a driven wheel the slip relaxation step, the force law and the
        two soil dampers, applied at the contact patch; for every wheel the motion resistance,
        applied at the wheel centre (compaction resistance comes from normal stresses that
        point at the axle, so it puts no moment on the wheel).
        """
        self._loop.apply()

    def _rut_load_ratios(self, k: int, soil_params: SoilParams) -> tuple[float, float]:
        """(forward, reverse): the load ratio of wheel ``k``'s leader's rut on its soil
        (`bekker.rut_load_ratio`) between the geometries their compaction laws use; 1.0
        without a leader."""
        out = []
        for leader in self.leaders[k]:
            if leader < 0:
                out.append(1.0)
                continue
            (b_f, d_f), (b_l, d_l) = self._law_geometry(k), self._law_geometry(leader)
            out.append(rut_load_ratio(b_f, d_f, b_l, d_l, float(soil_params.k_c),
                                      float(soil_params.k_phi)))
        return out[0], out[1]

    def _law_geometry(self, k: int) -> tuple[float, float]:
        """(width, diameter) [m] of the compaction law wheel ``k`` meets: its model's geometry
        (the driven wheels' unless `castor_own_geometry`), else its own wheel."""
        geometry = getattr(self._models[k], "geometry", None)
        if geometry is None:
            return self.width[k], 2.0 * self.radius[k]
        return geometry.width_m, 2.0 * geometry.radius_m

    # -- reading ---------------------------------------------------------------------------
    def contact_state(self) -> WheelContactState:
        """Per-wheel slip, load and forces of the last substep, as arrays."""
        load = np.array(self.load)
        return WheelContactState(
            slip=np.array(self.s), tan_beta=np.array(self.b), load_n=load,
            fx_n=np.array(self.fx), fy_n=np.array(self.fy), resistance_n=np.array(self.res),
            in_contact=load > 0.0, damper_n=np.array(self.damper),
        )


def _bekker_row(params: SoilParams) -> tuple[float, float, float, float]:
    """(k_c, k_phi, n, deformable) of one soil, in floats."""
    return (float(params.k_c), float(params.k_phi), float(params.n_exp),
            float(params.deformable))


def _wheel_sinkage_m(load_n: float, width_m: float, diameter_m: float,
                     bekker: tuple[float, float, float, float]) -> float:
    """Bekker static sinkage of a rigid wheel (`bekker.wheel_sinkage_m`, Wong Ch. 5), in floats,
    times the soil's ``deformable`` (0 on rigid ground)."""
    k_c, k_phi, n, deformable = bekker
    if deformable <= 0.0 or load_n <= 0.0:
        return 0.0
    return deformable * wheel_sinkage_float_m(load_n, width_m, diameter_m, k_c, k_phi, n)


def _wheel_models(spec: VehicleSpec, force_model: ForceModel,
                  castor_own_geometry: bool) -> list[ForceModel]:
    """The force model of each wheel: `force_model` itself for the driven wheels (it was built
    for their geometry) and, unless ``castor_own_geometry``, for the castors; with it, a castor
    gets the same law on its own contact geometry, whose Bekker compaction differs (a narrow,
    small castor sinks deeper per newton: Wong Ch. 5), when the model can be rebound
    (`ForceModel.with_geometry`)."""
    rebind = getattr(force_model, "with_geometry", None)
    geometry = getattr(force_model, "geometry", None)
    out: list[ForceModel] = []
    for w in spec.wheels:
        if w.role == "driven" or not castor_own_geometry or rebind is None or geometry is None:
            out.append(force_model)
            continue
        own = ContactGeometry(radius_m=w.radius_m, width_m=w.width_m,
                              contact_length_m=w.contact_length_m)
        out.append(force_model if own == geometry else rebind(own))
    return out


def _rut_leaders(spec: VehicleSpec) -> list[tuple[int, int]]:
    """Per wheel: (index of the wheel ahead in its rut when driving forward, when reversing),
    -1 for none. A wheel follows another when its centre line lies within half of the other's
    width of it (chassis frame); the nearest such wheel ahead (behind) leads. None for tracks
    (their road wheels already share one rut: `ContactGeometry.rut_share`)."""
    n = len(spec.wheels)
    if spec.track_length_m is not None:
        return [(-1, -1)] * n
    out = []
    for k, wk in enumerate(spec.wheels):
        xk, yk = wk.position_m[0], wk.position_m[1]
        ahead = [(wj.position_m[0] - xk, j) for j, wj in enumerate(spec.wheels)
                 if j != k and abs(wj.position_m[1] - yk) < 0.5 * wj.width_m]
        front = min(((dx, j) for dx, j in ahead if dx > 0.0), default=(0.0, -1))[1]
        back = max(((dx, j) for dx, j in ahead if dx < 0.0), default=(0.0, -1))[1]
        out.append((front, back))
    return out
