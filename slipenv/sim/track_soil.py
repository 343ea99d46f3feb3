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
4. compute the cell shear forces (Janosi with Mohr-Coulomb, against the sliding velocity, or
   Ishigami et al.'s decoupled components where the soil deforms:
   ``TrackModelParams.shear_law``), the
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

Cost. Steps 2-5 are one compiled call (numba, from the text of ``track``:
`track.track_substep`, with the hull frame and the force commands compiled here,
`_hull_kinematics` and `_substep`), the slip-sinkage factor the wheels' C law called by address
(``_track_io``).
Steps 1 and 5 go through Bullet's C API (``slipenv/sim/_track_io.c``, on the wheel loop's
``bullet_native.h``) where pybullet allows it (`native_queries`), checked against pybullet's
Python API bit for bit on the first substep with contact and then on every
``bullet_native.VERIFY_EVERY``-th (a mismatch or a broken guard region reads through the
Python API for good, warned once); ``SLIPENV_PYBULLET_API=1`` reads through the Python API
throughout. Both paths read and apply the same doubles, so they give the same trajectory bit
for bit. The first use after an install or an edit compiles the model (about 35 s of CPU);
numba caches it on disk, and `warm_up` does it in a parent process before workers start.
"""

from __future__ import annotations

import importlib
import math
import pathlib
from dataclasses import dataclass

import llvmlite.binding
import numpy as np
from numba import njit, types
from numba.core import config as numba_config

import slipenv.terramechanics as terramechanics
from slipenv.contracts.compiled_cache import refresh_stale_cache
from slipenv.contracts.constants import G_MPS2
from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim.bullet_native import (
    VERIFY_EVERY,
    client_table,
    python_api_forced,
    warn_native_mismatch,
)
from slipenv.sim.wheel_soil import WheelContactState
from slipenv.terramechanics.bekker import slip_sinkage_factor
from slipenv.terramechanics.models import ForceModel
from slipenv.terramechanics.soil import SoilParams
from slipenv.terramechanics.soil_map import SoilMap, UniformSoil, soil_rows
from slipenv.terramechanics.track import (
    SETTING_NAMES,
    SHEAR_LAWS,
    SOIL_ROWS,
    load_spread_matrix,
    rut_resistance_n,
    track_substep,
)
from slipenv.vehicles.body import VehicleBody
from slipenv.vehicles.spec import VehicleSpec

# the compiled substep carries the track model's code (track.py and the laws it calls)
refresh_stale_cache(__file__, *(pathlib.Path(terramechanics.__file__).with_name(name)
                               for name in ("track.py", "bekker.py", "janosi.py")))

p = import_pybullet()  # the banner-free first import (see slipenv.pybullet_quiet)
_track_io = importlib.import_module("slipenv.sim._track_io")  # built by pip install (setup.py)
# The wheels' slip-sinkage law (Lyasko, ``_laws.h``), called by the compiled substep by name
# (resolved at link time, so numba's cache stays valid); as plain Python, its binding.
llvmlite.binding.add_symbol("slipenv_track_slip_sinkage_factor",
                            _track_io.slip_sinkage_factor_address)
_lyasko = (slip_sinkage_factor if numba_config.DISABLE_JIT  # type: ignore[attr-defined]
           else types.ExternalFunction("slipenv_track_slip_sinkage_factor",
                                       types.float64(types.float64)))


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
        with the resultant law, along the stress of the Janosi spring's tangent stiffness and
        across it of the direction state's tau A/e_max; with the decoupled law, of each
        component's own tangent stiffness; each for the cell's mass share and capped at half
        the explicit stability limit m/dt. Critical (1.0): at 0.5 the vehicle parked facing up
        a 15° slope rocks on its direction springs and ratchets 11 mm downhill in 10 s.
    resistance_speed_mps : float
        Regularisation of the rut resistance's sign at rest [m/s] (not a speed ramp: the
        resistance is rate independent above it).
    max_wall_height_m : float
        Side-wall height above which soil spills over the track [m] (the road-wheel diameter
        when ``None``).
    shear_law : str
        The cells' shear law (``track.SHEAR_LAWS``): ``"resultant"`` (default), Wong-Chiang's
        tau(|j|) against the sliding direction; ``"decoupled"``, Ishigami et al.'s components
        each of its own displacement, the resultant capped at the Mohr-Coulomb strength
        (``track.decoupled_stress_pa``), each component's soil damper with that component's
        own stiffness, on the tracks whose soil deforms (``track.decoupled_cells``; the
        resultant law on rigid ground). The vehicle's ``track_shear_law`` sets it (Patako's
        preset keeps the resultant law: ``slipenv.vehicles.presets.tracked_patako_wong_chiang``
        says why).
    longitudinal_shear_modulus_ratio, lateral_shear_modulus_ratio : float
        K_x/K and K_y/K of the decoupled law (``track.decoupled_stress_pa``): the shear
        deformation moduli along and across the track over the soil's K (Ishigami et al. 2007
        identify separate K_x, K_y for a grousered wheel on Toyoura sand). 1: the soil's K.
        The vehicle's ``track_longitudinal_shear_modulus_ratio`` and
        ``track_lateral_shear_modulus_ratio`` set them; the resultant law ignores them.
    """

    n_cells: int = 16
    direction_length_m: float = 1e-3
    unit_weight_n_m3: float = 1.335e3 * G_MPS2
    damping_ratio: float = 1.0
    resistance_speed_mps: float = 1e-3
    max_wall_height_m: float | None = None
    shear_law: str = "resultant"
    longitudinal_shear_modulus_ratio: float = 1.0
    lateral_shear_modulus_ratio: float = 1.0

    def __post_init__(self) -> None:
        if self.shear_law not in SHEAR_LAWS:
            raise ValueError(f"shear_law={self.shear_law!r} must be one of {SHEAR_LAWS}")
        if not (isinstance(self.n_cells, int) and 4 <= self.n_cells <= 200):
            raise ValueError(f"n_cells must be an int in [4, 200], got {self.n_cells!r}")
        for name in ("unit_weight_n_m3", "resistance_speed_mps", "direction_length_m",
                     "longitudinal_shear_modulus_ratio", "lateral_shear_modulus_ratio"):
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

    Attributes
    ----------
    native_queries : bool
        PyBullet is read and the forces applied through Bullet's C API (module docstring).
    native_mismatch : bool
        A check of the native reader failed; it reads through the Python API from then on.
    native_verifications : int
        Substeps on which the native readings were compared with the Python API's.
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
        # Buffers of `apply` (`track.track_substep`).
        self._out = np.empty((6, nt, n_cells))  # total x, y; shear x, y; wall; |damper|
        self._cell_mass_kg = self.mass_kg / nt / n_cells
        lever_rows = np.zeros((nt, nt * n_cells))
        track_rows = np.zeros((nt, nt * n_cells))
        for i in range(nt):
            lever_rows[i, i * n_cells:(i + 1) * n_cells] = self.lever[i]
            track_rows[i, i * n_cells:(i + 1) * n_cells] = 1.0
        self._reduce = np.vstack((self.assign_all, lever_rows, track_rows))
        self._sums = np.zeros((self._reduce.shape[0], 6))
        self._compaction = np.zeros(nt)
        self._sinkage_factor = np.ones(nt)
        self._soil = np.zeros((len(SOIL_ROWS), nt))
        self._deform = np.ones(nt)
        settings = dict(dx_m=self.dx_m, dt_s=dt_s,
                        direction_length_m=self.params.direction_length_m,
                        damping_ratio=self.params.damping_ratio,
                        cell_mass_kg=self._cell_mass_kg,
                        unit_weight_n_m3=self.params.unit_weight_n_m3,
                        max_wall_height_m=self.max_wall_m,
                        shear_law=float(SHEAR_LAWS.index(self.params.shear_law)),
                        longitudinal_modulus_ratio=self.params.longitudinal_shear_modulus_ratio,
                        lateral_modulus_ratio=self.params.lateral_shear_modulus_ratio)
        self._settings = np.array([settings[k] for k in SETTING_NAMES], dtype=float)
        self._contact_base = np.array(self.contact_base)
        # PyBullet through Bullet's C API where pybullet allows it (`native_queries`).
        self._io = _track_io.TrackIO(client, self.body_id, ground_id, p.WORLD_FRAME,
                                     list(self.links), list(self.spin_joints))
        self._reading = np.zeros(14 + 2 * self.n)  # `TrackIO.read`'s layout
        self._check = np.zeros_like(self._reading)
        self._commands = np.zeros((self.n + 2 * nt, 8))  # `TrackIO.apply`'s rows
        self._commands[:self.n, 0] = self.links
        # Per substep: the hull's rotation (row-major) and (v_y, omega_x, omega_z) in hull
        # axes; per track u, V_x, V_y, slip, tan(slip angle) (`_hull_kinematics`).
        self._rot = np.zeros(9)
        self._hull = np.zeros(3)
        self._tracks_now = np.zeros((5, nt))
        self._res = np.zeros(self.n)
        self._track_of = np.array(self.track_of, dtype=np.int64)
        # Per track: belt radius, y and z of the centre line, x of the cells' middle.
        self._track_geometry = np.array([self.r_belt, self.y_list, self.z_list, self.x_mid])
        self._rut_settings = np.array([self.params.resistance_speed_mps, self.mass_kg / nt])
        self.native_queries = False
        self.native_mismatch = False
        self.native_verifications = 0
        self._verify, self._contact_substeps = True, 0
        table = None if python_api_forced() else client_table()
        if table is not None:
            try:
                self._io.bind(table.path, table.offset, table.n_clients, table.anchor_offset)
                self.native_queries = True
            except OSError:
                pass
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
        self.rut = np.zeros((3, nt))  # per track: travel, front and rear end of its rut [m]
        self.sinkage_m = np.zeros((nt, n_cells))
        self._reading[:] = 0.0
        self._tracks_now[:] = 0.0
        self._sums[:] = 0.0
        self._res[:] = 0.0
        self.chassis_contact = False
        self.sample_soil(force=True)
        self._args = (self._track_of, self._track_geometry, self._rot, self._hull,
                      self._tracks_now, self._sinkage_factor, self._deform, self.spread_all,
                      self._reduce, self.x_cell, self._soil, self._settings, self.j, self.e,
                      self.walls, self._out, self.sinkage_m, self._sums, self._compaction,
                      self._contact_base, self._rut_settings, self.rut, self._res,
                      self._commands)

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

        soil = {
            "width_m": self.width,
            "inv_cell_area_m2": [1.0 / (w * self.dx_m) for w in self.width],
            "k_c": [float(sp.k_c) for sp in rows],
            "k_phi": [float(sp.k_phi) for sp in rows],
            "n_exp": [float(sp.n_exp) for sp in rows],
            "cohesion_pa": [float(sp.cohesion_pa) for sp in rows],
            "tan_phi": [math.tan(float(sp.friction_angle_rad)) for sp in rows],
            "shear_modulus_m": [float(sp.shear_modulus_m) for sp in rows],
            "friction_angle_rad": [float(sp.friction_angle_rad) for sp in rows],
        }
        # In place: the compiled substep holds these arrays (`_args`).
        self._soil[...] = [soil[k] for k in SOIL_ROWS]
        self._deform[...] = [1.0 if float(sp.deformable) > 0.5 else 0.0 for sp in rows]

    def soil_at_wheel(self, k: int) -> SoilParams:
        """The soil (floats) under road wheel ``k``'s track at the last `sample_soil`."""
        return self._soil_rows[self.track_of[k]]

    def rolling_radius_m(self, k: int) -> float:
        """Belt radius of road wheel ``k``'s track [m]: the belt moves at r_s omega."""
        return self.r_belt[self.track_of[k]]

    # -- the substep -------------------------------------------------------------------------
    def _read_python(self, out: np.ndarray) -> None:
        """This substep's readings through pybullet's Python API, in `TrackIO.read`'s layout
        (base position, orientation, linear and angular velocity; road-wheel loads; spin
        rates; chassis contact)."""
        cid, bid, n = self.client, self.body_id, self.n
        contacts = p.getContactPoints(bid, self.ground_id, -2, -2, cid)
        pos, orn = p.getBasePositionAndOrientation(bid, cid)
        lin, ang = p.getBaseVelocity(bid, cid)
        joints = p.getJointStates(bid, self.spin_joints, cid)
        load = [0.0] * n
        chassis = 0.0
        link_to_wheel = self.link_to_wheel
        for cp in contacts:
            f = cp[9]
            if f <= 0.0:
                continue
            k = link_to_wheel.get(cp[3])
            if k is None:
                chassis = 1.0
                continue
            load[k] += f
        out[:] = (*pos, *orn, *lin, *ang, *load, *(js[1] for js in joints), chassis)

    def _acquire(self) -> np.ndarray:
        """This substep's readings: natively once verified, else through the Python API. The
        native readings are compared with the Python API's bit for bit on every substep up to
        the first with a road wheel on the ground, then on every `VERIFY_EVERY`-th substep
        with contact, and the guard regions after the structs pybullet fills on every
        substep; a failed check reads through the Python API for good (warned once)."""
        reading = self._reading
        if not self.native_queries:
            self._read_python(reading)
            return reading
        status = self._io.read(reading)
        if status.__class__ is int:
            broken, contact = None, status == 1
        else:
            broken, contact = status, bool(reading[13:13 + self.n].any())
        if not self._verify and broken is None:
            if not contact:
                return reading
            self._contact_substeps += 1
            if VERIFY_EVERY <= 0 or self._contact_substeps < VERIFY_EVERY:
                return reading
        self._contact_substeps = 0
        self._read_python(self._check)
        self.native_verifications += 1
        if broken is not None:
            why = f"the guard region after {broken} was overwritten"
        elif reading.tobytes() != self._check.tobytes():
            why = "the native readings of the track injector differ from the Python API's"
        else:
            if contact:
                self._verify = False
            return reading
        self.native_queries, self.native_mismatch = False, True
        reading[:] = self._check
        warn_native_mismatch(why)
        return reading

    def apply(self) -> None:
        """Compute and apply the track forces for the coming substep: the functions of
        `slipenv.terramechanics.track` composed (module docstring) in one compiled call,
        `_substep` (`track.track_substep` with the hull frame and the force commands)."""
        reading = self._acquire()
        if reading[-1]:
            self.chassis_contact = True
        self._submit(_substep(reading, *self._args))

    def _submit(self, count: int) -> None:
        """Apply the first ``count`` rows of the command buffer, in order: natively, or
        through pybullet's Python API (the same doubles)."""
        if self.native_queries:
            self._io.apply(self._commands, count)
            return
        cid, bid, world = self.client, self.body_id, p.WORLD_FRAME
        for row in self._commands[:count].tolist():
            if row[1] == 0.0:
                p.applyExternalForce(bid, int(row[0]), row[2:5], row[5:8], world,
                                     physicsClientId=cid)
            else:
                p.applyExternalTorque(bid, int(row[0]), row[2:5], world, physicsClientId=cid)

    # -- reading ----------------------------------------------------------------------------
    @property
    def load(self) -> list[float]:
        """Normal load of each road wheel in the last substep [N]."""
        return self._reading[13:13 + self.n].tolist()

    @property
    def fx(self) -> list[float]:
        """Each road wheel's share of its track's shear force along the hull's x [N]."""
        return self._sums[:self.n, 2].tolist()

    @property
    def fy(self) -> list[float]:
        """Each road wheel's share of the lateral shear plus side-wall force [N]."""
        return (self._sums[:self.n, 3] + self._sums[:self.n, 4]).tolist()

    @property
    def res(self) -> list[float]:
        """Each road wheel's share (by load) of its track's rut resistance magnitude [N]."""
        return self._res.tolist()

    @property
    def damping_n(self) -> list[float]:
        """Each road wheel's share of the soil dampers' force magnitude [N]."""
        return self._sums[:self.n, 5].tolist()

    @property
    def wall_n(self) -> list[float]:
        """Each track's side-wall force [N]."""
        return self._sums[self.n + len(self.tracks):, 4].tolist()

    @property
    def track_slip(self) -> list[float]:
        """Each track's slip i = (u - V)/u in [-1, 1] (0 at rest, -1 sliding with the belt
        stopped)."""
        return self._tracks_now[3].tolist()

    @property
    def track_tanb(self) -> list[float]:
        """Each track's tan(slip angle), V_y/V_x at its centre."""
        return self._tracks_now[4].tolist()

    def contact_state(self) -> WheelContactState:
        """Per road wheel: its track's slip and tan(slip angle), its load, its share of the
        track's shear (f_x) and lateral shear plus side-wall force (f_y), of the rut
        resistance, and of the soil-spring damper's force magnitude (``damper_n``) [N]."""
        load = np.array(self.load)
        return WheelContactState(
            slip=self._tracks_now[3][self._track_of], tan_beta=self._tracks_now[4][self._track_of],
            load_n=load, fx_n=np.array(self.fx), fy_n=np.array(self.fy),
            resistance_n=self._res.copy(), in_contact=load > 0.0,
            damper_n=np.array(self.damping_n),
        )


# -- the compiled glue of a substep ----------------------------------------------------------
@njit(cache=True)
def _hull_kinematics(reading: np.ndarray, track_of: np.ndarray, geometry: np.ndarray,
                     rot: np.ndarray, hull: np.ndarray, tracks_now: np.ndarray) -> None:
    """The hull's rotation and twist and each track's kinematics from a reading (in place).

    ``reading`` in `TrackIO.read`'s layout; ``geometry`` rows per track: belt radius, y and z
    of its centre line, x of its cells' middle (base frame). Writes ``rot`` (row-major,
    Bullet's quaternion-to-matrix formula, as ``getMatrixFromQuaternion``), ``hull`` (v_y,
    omega_x, omega_z in hull axes) and ``tracks_now`` rows per track: belt speed u = r_s
    times the mean spin rate of its road wheels, ground speed V_x of its centre line, lateral
    speed V_y at its height, slip (u - V_x)/u clipped to [-1, 1] (0 at rest, -1 sliding with
    the belt stopped) and tan of the slip angle at its centre.
    """
    x, y, z, w = reading[3], reading[4], reading[5], reading[6]
    s = 2.0 / (x * x + y * y + z * z + w * w)
    xs, ys, zs = x * s, y * s, z * s
    wx, wy, wz = w * xs, w * ys, w * zs
    xx, xy, xz = x * xs, x * ys, x * zs
    yy, yz, zz = y * ys, y * zs, z * zs
    rot[0], rot[1], rot[2] = 1.0 - (yy + zz), xy - wz, xz + wy
    rot[3], rot[4], rot[5] = xy + wz, 1.0 - (xx + zz), yz - wx
    rot[6], rot[7], rot[8] = xz - wy, yz + wx, 1.0 - (xx + yy)
    lx, ly, lz = reading[7], reading[8], reading[9]
    ax, ay, az = reading[10], reading[11], reading[12]
    vbx = lx * rot[0] + ly * rot[3] + lz * rot[6]
    vby = lx * rot[1] + ly * rot[4] + lz * rot[7]
    wbx = ax * rot[0] + ay * rot[3] + az * rot[6]
    wby = ax * rot[1] + ay * rot[4] + az * rot[7]
    wbz = ax * rot[2] + ay * rot[5] + az * rot[8]
    hull[0], hull[1], hull[2] = vby, wbx, wbz
    n = track_of.size
    for i in range(tracks_now.shape[1]):
        rates, count = 0.0, 0
        for k in range(n):
            if track_of[k] == i:
                rates += reading[13 + n + k]
                count += 1
        u = geometry[0, i] * rates / count
        yi, zc = geometry[1, i], geometry[2, i]
        vx = vbx + wby * zc - wbz * yi
        if abs(u) > 1e-3:
            slip = (u - vx) / u
        else:
            slip = 0.0 if abs(vx) < 1e-3 else -1.0
        vy_mean = vby + wbz * geometry[3, i] - wbx * zc
        tracks_now[0, i] = u
        tracks_now[1, i] = vx
        tracks_now[2, i] = vby - wbx * zc
        tracks_now[3, i] = min(max(slip, -1.0), 1.0)
        tracks_now[4, i] = vy_mean / vx if abs(vx) > 1e-3 else 0.0


@njit(cache=True)
def _substep(reading, track_of, geometry, rot, hull, tracks_now, sinkage_factor, deformable,
             spread, reduce, x_cell, soil, settings, j, e, walls, out, sinkage_m, sums,
             compaction_n, contact_base, rut_settings, rut, res, commands) -> int:
    """One substep from a reading: the hull frame (`_hull_kinematics`), each track's
    slip-sinkage factor (the wheels' C law), `track.track_substep`, then the force commands;
    returns their count.

    ``commands`` rows [link, 0 force / 1 torque, vector, point] in the world frame: each road
    wheel's share of its cells' forces at its contact point (``contact_base``, base frame), so
    the channel motor feels r sum F_x as the sprocket would; per track, its compaction
    resistance as a rut state (`track.rut_resistance_n`; ``rut`` rows travel, front, rear) on
    the hull at its centre line, and the residual yaw moment of the lateral forces about the
    road wheels (exactly what the lumping misses) on the hull. ``rut_settings``: the
    resistance's regularisation speed [m/s] and each track's share of the mass [kg]. ``res``
    gets each road wheel's share (by load) of its track's resistance magnitude.
    """
    n = track_of.size
    nt = tracks_now.shape[1]
    _hull_kinematics(reading, track_of, geometry, rot, hull, tracks_now)
    for i in range(nt):
        sinkage_factor[i] = _lyasko(tracks_now[3, i])
    load = reading[13:13 + n]
    track_substep(load, tracks_now[0], tracks_now[1], tracks_now[2], hull[2], sinkage_factor,
                  deformable, spread, reduce, x_cell, soil, settings, j, e, walls, out,
                  sinkage_m, sums, compaction_n)
    px, py, pz = reading[0], reading[1], reading[2]
    for k in range(n):
        fx, fy = sums[k, 0], sums[k, 1]
        cx, cy, cz = contact_base[k, 0], contact_base[k, 1], contact_base[k, 2]
        for a in range(3):
            commands[k, 1] = 0.0
            commands[k, 2 + a] = fx * rot[3 * a] + fy * rot[3 * a + 1]
            commands[k, 5 + a] = (cx * rot[3 * a] + cy * rot[3 * a + 1]
                                  + cz * rot[3 * a + 2]) + reading[a]
    count = n
    dt = settings[1]
    for i in range(nt):
        vt = tracks_now[1, i]
        rut[0, i] += vt * dt
        r_c = compaction_n[i]
        v_reg = max(rut_settings[0], 2.0 * r_c * dt / rut_settings[1])
        f_res, rut[1, i], rut[2, i] = rut_resistance_n(r_c, rut[0, i], rut[1, i], rut[2, i],
                                                       vt, v_reg)
        if f_res != 0.0:
            yi, zc = geometry[1, i], geometry[2, i]
            row = commands[count]
            row[0], row[1] = -1.0, 0.0
            row[2], row[3], row[4] = f_res * rot[0], f_res * rot[3], f_res * rot[6]
            row[5] = px + yi * rot[1] + zc * rot[2]
            row[6] = py + yi * rot[4] + zc * rot[5]
            row[7] = pz + yi * rot[7] + zc * rot[8]
            count += 1
        total_w = 0.0
        for k in range(n):
            if track_of[k] == i:
                total_w += load[k]
        for k in range(n):
            if track_of[k] == i:
                res[k] = abs(f_res) * (load[k] / total_w if total_w > 0.0 else 0.0)
        mz = sums[n + i, 1]
        if mz != 0.0:
            row = commands[count]
            row[0], row[1] = -1.0, 1.0
            row[2], row[3], row[4] = mz * rot[2], mz * rot[5], mz * rot[8]
            row[5], row[6], row[7] = 0.0, 0.0, 0.0
            count += 1
    return count


def warm_up() -> None:
    """Compile the track model's substep now, or load it from numba's on-disk cache.

    The first call after an install or an edit of `slipenv.terramechanics.track` (or of the
    `janosi` and `bekker` laws it compiles, or of this module) compiles it (about 20 s of CPU);
    later ones load it (a fraction of a second). Call it in a parent process before starting
    worker processes that build tracked vehicles: numba's cache is not safe against several
    processes writing it at the same time, so they should find it written.
    """
    nt, nc, n = 2, 4, 2
    reading = np.zeros(14 + 2 * n)
    reading[6] = 1.0  # the identity quaternion
    reading[13:13 + n] = 1.0
    track_of = np.arange(n, dtype=np.int64)
    geometry = np.ones((4, nt))
    rot, hull, tracks_now = np.zeros(9), np.zeros(3), np.zeros((5, nt))
    settings = np.array([0.03, 1 / 240, 1e-3, 1.0, 0.5, 1.3e4, 0.1, 0.0])
    _substep(
        reading, track_of, geometry, rot, hull, tracks_now, np.ones(nt), np.ones(nt),
        np.full((nt * nc, n), 0.5), np.ones((n + 2 * nt, nt * nc)), np.zeros((nt, nc)),
        np.ones((len(SOIL_ROWS), nt)), settings, np.zeros((2, nt, nc + 1)),
        np.zeros((2, nt, nc)), np.zeros((2, 2, nt, nc)), np.zeros((6, nt, nc)),
        np.zeros((nt, nc)), np.zeros((n + 2 * nt, 6)), np.zeros(nt), np.zeros((n, 3)),
        np.array([1e-3, 1.0]), np.zeros((3, nt)), np.zeros(n), np.zeros((n + 2 * nt, 8)))
