"""The physics layer: one PyBullet client holding a terrain and a vehicle with soil forces.

``Simulator`` knows nothing of sensors, estimators, paths or rewards. It takes channel
speed commands, advances ``substeps`` physics steps (injecting the force law before each),
and reports :class:`VehicleTruth`.
"""

from __future__ import annotations

import math
import os
import sys
import weakref
from dataclasses import dataclass

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim.injector import Injector
from slipenv.sim.track_soil import TrackModelParams, TrackSoilInjector
from slipenv.sim.wheel_soil import WheelSoilInjector
from slipenv.terrain.terrain import TerrainSpec, build_terrain
from slipenv.terramechanics.models import ForceModel
from slipenv.terramechanics.soil_map import SoilMap
from slipenv.vehicles.body import build_vehicle
from slipenv.vehicles.spec import VehicleSpec

p = import_pybullet()  # the banner-free first import (see slipenv.pybullet_quiet)

_PARKING_HEIGHT_M = 1e4  # [m] where a body waits, clear of any terrain, while rewound


@dataclass(frozen=True)
class VehicleTruth:
    """Ground truth after a control step (world frame: x east, y north, z up; REP 103).

    Attributes
    ----------
    t_s : float
        Simulation time [s].
    position_m : tuple[float, float, float]
        Reference point (wheel-centre plane, midway between the contact lines) [m].
    yaw_rad, pitch_rad, roll_rad : float
        Z-Y-X Euler angles of the chassis [rad] (pitch > 0 nose down, roll > 0 left up).
    velocity_body_mps : tuple[float, float, float]
        Velocity of the reference point in the body frame [m/s].
    yaw_rate_rad_s : float
        Angular rate about body z [rad/s].
    specific_force_body_mps2 : tuple[float, float, float]
        Acceleration minus gravity in the body frame (what an accelerometer reads) [m/s^2].
    channel_angle_rad : np.ndarray
        Cumulative true wheel rotation of each drive channel [rad].
    channel_torque_nm : np.ndarray
        Motor torque per channel at the end of the step, summed over its wheels [N m].
    yaw_increment_rad : float | None
        Rotation about body z over the control step that ended here [rad], from the
        orientations at its start and end (`body_z_rotation_rad`): what a rate-integrating
        gyro accumulates over its sample interval. ``None`` where no step was run (after
        ``reset``).
    interval_s : float
        Length of that step [s] (0 with no increment).
    """

    t_s: float
    position_m: tuple[float, float, float]
    yaw_rad: float
    pitch_rad: float
    roll_rad: float
    velocity_body_mps: tuple[float, float, float]
    yaw_rate_rad_s: float
    specific_force_body_mps2: tuple[float, float, float]
    channel_angle_rad: np.ndarray
    channel_torque_nm: np.ndarray
    yaw_increment_rad: float | None = None
    interval_s: float = 0.0

    @property
    def mean_yaw_rate_rad_s(self) -> float:
        """Mean body-z rate over the step that ended here [rad/s] (what a rate-integrating
        gyro reads); the instantaneous rate where no step was integrated."""
        if self.yaw_increment_rad is None or self.interval_s <= 0.0:
            return self.yaw_rate_rad_s
        return self.yaw_increment_rad / self.interval_s

    @property
    def slip_angle_rad(self) -> float:
        """Body slip angle atan2(v_y, v_x) [rad] (0 when standing)."""
        vx, vy, _ = self.velocity_body_mps
        return math.atan2(vy, vx) if math.hypot(vx, vy) > 1e-3 else 0.0


class PhysicsBlowUp(RuntimeError):
    """The physics produced a non-finite or absurd state."""


class Simulator:
    """A terrain and a vehicle in one PyBullet client, with the soil force law injected.

    Parameters
    ----------
    vehicle : VehicleSpec
    terrain : TerrainSpec
    force_model : ForceModel
    soil_map : SoilMap
    physics_hz : float
        Physics substep rate [Hz].
    control_hz : float
        Control (env step) rate [Hz]; must divide ``physics_hz``.
    gui : bool
        Open the PyBullet GUI (``render_mode="human"``).
    inject : bool
        Whether to apply the soil forces (``False`` gives the bare world used by the benchmark).
    multi_pass : bool
        Per-wheel soil law: a wheel in the rut of the wheel ahead meets only the compaction
        below that rut (``WheelSoilInjector``'s ``multi_pass``; Wong §2.4). Default False.
        A Wong-Chiang track's rut state already does this along the track and takes no such
        option (``SlipEnvConfig`` refuses the combination, where the options are checked).
    castor_own_geometry : bool
        Castors meet the compaction of their own wheel (``WheelSoilInjector``'s
        ``castor_own_geometry``). Default False.
    """

    def __init__(
        self,
        vehicle: VehicleSpec,
        terrain: TerrainSpec,
        force_model: ForceModel,
        soil_map: SoilMap,
        physics_hz: float = 240.0,
        control_hz: float = 20.0,
        gui: bool = False,
        inject: bool = True,
        multi_pass: bool = False,
        castor_own_geometry: bool = False,
    ) -> None:
        ratio = physics_hz / control_hz
        if control_hz <= 0 or physics_hz <= 0 or abs(ratio - round(ratio)) > 1e-9:
            raise ValueError(
                f"physics_hz ({physics_hz}) must be a positive multiple of control_hz "
                f"({control_hz})"
            )
        self.multi_pass = multi_pass
        self.castor_own_geometry = castor_own_geometry
        self._quat: tuple[float, float, float, float] | None = None  # at the last truth()
        self.spec = vehicle
        self.substeps = int(round(ratio))
        self.dt_s = 1.0 / physics_hz
        self.control_dt_s = 1.0 / control_hz
        if gui and sys.platform.startswith("linux") and not os.environ.get("DISPLAY"):
            raise RuntimeError(
                "render_mode='human' opens the PyBullet GUI, which needs a display (DISPLAY is "
                "not set); use render_mode='rgb_array' on a headless machine"
            )
        self.client = p.connect(p.GUI if gui else p.DIRECT)
        if self.client < 0:
            raise RuntimeError("could not connect to PyBullet" + (" GUI" if gui else ""))
        # A simulator dropped without close() (a notebook, a sweep) must not keep its client
        # (~40 MiB) connected: the finalizer holds the client id only, never ``self``.
        self._finalizer = weakref.finalize(self, _disconnect, self.client)
        p.setGravity(0, 0, -G_MPS2, physicsClientId=self.client)
        p.setTimeStep(self.dt_s, physicsClientId=self.client)
        self.terrain = build_terrain(terrain, self.client)
        self.force_model, self.soil_map = force_model, soil_map
        self.inject = inject
        self.body = build_vehicle(vehicle, self.client, (0, 0, 1.0), (0, 0, 0, 1))
        self._prev_vel: tuple[float, float, float] | None = None
        self._build_injector()
        self.t_s = 0.0

    def _build_injector(self) -> None:
        """(Re)create the vehicle's soil force injector (fresh soil and slip states)."""
        vehicle = self.spec
        self.injector: Injector
        if vehicle.track_model == "wong_chiang":
            self.injector = TrackSoilInjector(
                self.client, vehicle, self.body, self.terrain.body_id, self.force_model,
                self.soil_map, self.dt_s, TrackModelParams(
                    shear_law=vehicle.track_shear_law,
                    longitudinal_shear_modulus_ratio=(
                        vehicle.track_longitudinal_shear_modulus_ratio),
                    lateral_shear_modulus_ratio=vehicle.track_lateral_shear_modulus_ratio))
        else:
            self.injector = WheelSoilInjector(
                self.client, vehicle, self.body, self.terrain.body_id, self.force_model,
                self.soil_map, self.dt_s, multi_pass=self.multi_pass,
                castor_own_geometry=self.castor_own_geometry)
        self._channel_joints = [
            [self.body.spin_joints[i] for i, w in enumerate(vehicle.wheels) if w.channel == c]
            for c in vehicle.channels
        ]
        self._all_spin = [j for js in self._channel_joints for j in js]
        self._steer = [j for j in self.body.steer_joints if j is not None]
        self._steer_wheels = [i for i, j in enumerate(self.body.steer_joints) if j is not None]

    def _rewind_body(self) -> None:
        """Put the body back as built, for a new episode.

        The body is built once per client: removing and re-creating it at every reset leaked
        native memory (its shapes are never freed: ~22 KB per FarmField reset). A reset
        instead lifts the body clear of the ground and runs collision detection, which drops
        its contact manifolds, whose cached impulses would otherwise warm-start the solver
        differently after each episode and break same-seed determinism (``restoreState``
        does not restore them); then every joint and velocity is zeroed.
        """
        cid, bid = self.client, self.body.body_id
        p.resetBasePositionAndOrientation(bid, (0.0, 0.0, _PARKING_HEIGHT_M), (0, 0, 0, 1),
                                          physicsClientId=cid)
        p.resetBaseVelocity(bid, (0, 0, 0), (0, 0, 0), physicsClientId=cid)
        for j in range(p.getNumJoints(bid, physicsClientId=cid)):
            p.resetJointState(bid, j, 0.0, 0.0, physicsClientId=cid)
        p.performCollisionDetection(physicsClientId=cid)  # no overlap: manifolds dropped
        p.resetBasePositionAndOrientation(bid, (0.0, 0.0, 1.0), (0, 0, 0, 1),
                                          physicsClientId=cid)

    # -- episode ----------------------------------------------------------------------------
    def reset(self, x_m: float, y_m: float, yaw_rad: float, settle_s: float = 0.5) -> VehicleTruth:
        """Place the vehicle at (x, y, yaw) on the ground, brakes on, and let it settle."""
        self._rewind_body()
        self._build_injector()
        nrm = self.terrain.normal(x_m, y_m)
        quat = _orientation_on_ground(yaw_rad, nrm)
        # The reference point lies in the driven wheels' centre plane: one rolling radius
        # above the ground along its normal (plus 2 mm so the wheels drop onto it).
        lift = self.body.contact_radius_m + 0.002
        target = [x_m + nrm[0] * lift, y_m + nrm[1] * lift,
                  self.terrain.height(x_m, y_m) + nrm[2] * lift]
        rot = np.reshape(p.getMatrixFromQuaternion(quat), (3, 3))
        offset = rot @ np.asarray(self.body.base_to_reference_m)
        p.resetBasePositionAndOrientation(
            self.body.body_id, (np.asarray(target) - offset).tolist(), quat,
            physicsClientId=self.client,
        )
        self.t_s = 0.0
        self._angle_offset = np.zeros(len(self.spec.channels))
        self.command(np.zeros(len(self.spec.channels)), [0.0] * len(self.spec.wheels))
        for _ in range(int(round(settle_s / self.dt_s))):
            self._substep()
        self.injector.chassis_contact = False
        self.t_s = 0.0
        self._angle_offset = self._channel_angles()
        self._prev_vel = None
        return self.truth()

    def command(self, channel_speed_rad_s, steer_rad) -> None:
        """Set the motor targets: speed per channel [rad/s], steering per wheel [rad]."""
        pairs = zip(channel_speed_rad_s, self._channel_joints, strict=True)
        speeds = [float(s) for s, js in pairs for _ in js]
        p.setJointMotorControlArray(
            self.body.body_id, self._all_spin, p.VELOCITY_CONTROL, targetVelocities=speeds,
            forces=[self.spec.max_wheel_torque_nm] * len(speeds), physicsClientId=self.client,
        )
        if self._steer:
            p.setJointMotorControlArray(
                self.body.body_id, self._steer, p.POSITION_CONTROL,
                targetPositions=[float(steer_rad[i]) for i in self._steer_wheels],
                forces=[50.0 * self.spec.max_wheel_torque_nm] * len(self._steer),
                physicsClientId=self.client,
            )

    def step(self, channel_speed_rad_s, steer_rad) -> VehicleTruth:
        """One control step: command, run the substeps, return the truth.

        Raises
        ------
        PhysicsBlowUp
            If the state becomes non-finite or absurd (|v| > 100 m/s).
        """
        self.command(channel_speed_rad_s, steer_rad)
        if self.inject:
            self.injector.sample_soil()
        start = self._quat
        if start is None:
            start = p.getBasePositionAndOrientation(self.body.body_id,
                                                    physicsClientId=self.client)[1]
        for _ in range(self.substeps):
            self._substep()
        truth = self.truth(start)
        vx, vy, vz = truth.velocity_body_mps
        values = (*truth.position_m, vx, vy, vz, truth.yaw_rate_rad_s)
        if not all(math.isfinite(v) for v in values) or math.sqrt(vx * vx + vy * vy) > 100.0:
            raise PhysicsBlowUp(f"non-finite or absurd vehicle state at t = {self.t_s:.3f} s")
        return truth

    def _substep(self) -> None:
        if self.inject:
            self.injector.apply()
        p.stepSimulation(physicsClientId=self.client)
        self.t_s += self.dt_s

    # -- truth ------------------------------------------------------------------------------
    def _channel_angles(self) -> np.ndarray:
        return self._channel_angles_and_torques()[0]

    def _channel_angles_and_torques(self) -> tuple[np.ndarray, np.ndarray]:
        """Per channel: the mean spin angle of its joints [rad] and the sum of their motor
        torques [N m], from one joint-state query."""
        states = p.getJointStates(self.body.body_id, self._all_spin, physicsClientId=self.client)
        angles, torques, i = [], [], 0
        for js in self._channel_joints:
            n = len(js)
            angles.append(sum(states[i + k][0] for k in range(n)) / n)
            torques.append(sum(states[i + k][3] for k in range(n)))
            i += n
        return np.array(angles), np.array(torques)

    def truth(self, step_start_quat: tuple[float, float, float, float] | None = None
              ) -> VehicleTruth:
        """Ground truth now (accelerations from the velocity change over the last step).

        ``step_start_quat`` is the orientation at the start of the control step just run;
        with it the truth carries the step's rotation about body z (``None`` outside a
        step)."""
        cid, bid = self.client, self.body.body_id
        pos, quat = p.getBasePositionAndOrientation(bid, physicsClientId=cid)
        self._quat = quat
        # One control step's net rotation: 8e-7 rad per step from the substeps' sum on the
        # rover's mounds (the non-commuting part of roll and pitch changing within 50 ms),
        # 500 times below the gyro's noise, at no cost per substep.
        yaw_increment_rad = (None if step_start_quat is None
                             else body_z_rotation_rad(step_start_quat, quat))
        lin, ang = p.getBaseVelocity(bid, physicsClientId=cid)
        # Row-major: rot[3 i + j] is the world i component of body axis j. Written out in
        # floats: about 5 us a step, where numpy's 3-vectors (and np.cross) take 30 to 60 us.
        r00, r01, r02, r10, r11, r12, r20, r21, r22 = p.getMatrixFromQuaternion(quat)
        f0, f1, f2 = self.body.base_to_reference_m
        ref_w = [r00 * f0 + r01 * f1 + r02 * f2, r10 * f0 + r11 * f1 + r12 * f2,
                 r20 * f0 + r21 * f1 + r22 * f2]
        position = (pos[0] + ref_w[0], pos[1] + ref_w[1], pos[2] + ref_w[2])
        # Velocity of the reference point: v + ω × r_ref.
        v_ref = (
            lin[0] + ang[1] * ref_w[2] - ang[2] * ref_w[1],
            lin[1] + ang[2] * ref_w[0] - ang[0] * ref_w[2],
            lin[2] + ang[0] * ref_w[1] - ang[1] * ref_w[0],
        )
        def to_body(v: tuple[float, float, float]) -> tuple[float, float, float]:
            v0, v1, v2 = v
            return (r00 * v0 + r10 * v1 + r20 * v2, r01 * v0 + r11 * v1 + r21 * v2,
                    r02 * v0 + r12 * v1 + r22 * v2)

        v_body = to_body(v_ref)
        yaw_rate = to_body(ang)[2]
        if self._prev_vel is None:
            acc = (0.0, 0.0, 0.0)
        else:
            acc = tuple((v_ref[i] - self._prev_vel[i]) / self.control_dt_s for i in range(3))
        self._prev_vel = v_ref
        specific = to_body((acc[0], acc[1], acc[2] + G_MPS2))
        roll, pitch, yaw = p.getEulerFromQuaternion(quat)
        angles, channel_torque = self._channel_angles_and_torques()
        return VehicleTruth(
            t_s=self.t_s,
            position_m=position,
            yaw_rad=yaw,
            pitch_rad=pitch,
            roll_rad=roll,
            velocity_body_mps=v_body,
            yaw_rate_rad_s=yaw_rate,
            specific_force_body_mps2=specific,
            channel_angle_rad=angles - self._angle_offset,
            channel_torque_nm=np.array(channel_torque),
            yaw_increment_rad=yaw_increment_rad,
            interval_s=0.0 if yaw_increment_rad is None else self.control_dt_s,
        )

    def close(self) -> None:
        """Disconnect the PyBullet client (idempotent)."""
        finalizer = getattr(self, "_finalizer", None)
        if finalizer is not None:
            finalizer()  # runs _disconnect once, then is dead
        self.client = None


def body_z_rotation_rad(q0, q1) -> float:
    """Rotation about body z from orientation ``q0`` to ``q1`` (quaternions x, y, z, w) [rad].

    The z component, in the body axes, of the rotation vector of q0^-1 q1: a rotation by ψ
    about the body z axis (|ψ| < π) gives ψ whatever the tilt, a roll or pitch gives 0. Summed
    over small steps it is the integral of the body-z rate, which a yaw gyro measures (the
    rotation vector of a strapdown attitude update, Bortz 1971).
    """
    x0, y0, z0, w0 = q0
    x1, y1, z1, w1 = q1
    # Hamilton product conj(q0) q1
    w = w0 * w1 + x0 * x1 + y0 * y1 + z0 * z1
    x = w0 * x1 - x0 * w1 - y0 * z1 + z0 * y1
    y = w0 * y1 + x0 * z1 - y0 * w1 - z0 * x1
    z = w0 * z1 - x0 * y1 + y0 * x1 - z0 * w1
    s = math.sqrt(x * x + y * y + z * z)
    if s == 0.0:
        return 0.0
    if w < 0.0:  # q and -q are the same rotation: take the one of angle <= π
        w, z = -w, -z
    return 2.0 * math.atan2(s, w) * z / s


def _disconnect(client: int) -> None:
    if p.isConnected(client):
        p.disconnect(client)


def _orientation_on_ground(yaw_rad: float, normal) -> tuple[float, float, float, float]:
    """Quaternion with body z along the ground normal and body x at heading ``yaw``."""
    nx, ny, nz = normal
    hx, hy = math.cos(yaw_rad), math.sin(yaw_rad)
    # Project the heading onto the ground plane.
    dot = hx * nx + hy * ny
    fx, fy, fz = hx - dot * nx, hy - dot * ny, -dot * nz
    inv = 1.0 / math.sqrt(fx * fx + fy * fy + fz * fz)
    fx, fy, fz = fx * inv, fy * inv, fz * inv
    lx, ly, lz = ny * fz - nz * fy, nz * fx - nx * fz, nx * fy - ny * fx
    m = np.array([[fx, lx, nx], [fy, ly, ny], [fz, lz, nz]])
    return _quat_from_matrix(m)


def _quat_from_matrix(m: np.ndarray) -> tuple[float, float, float, float]:
    tr = m[0, 0] + m[1, 1] + m[2, 2]
    if tr > 0:
        s = math.sqrt(tr + 1.0) * 2
        return ((m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, 0.25 * s)
    i = int(np.argmax(np.diag(m)))
    j, k = (i + 1) % 3, (i + 2) % 3
    s = math.sqrt(1.0 + m[i, i] - m[j, j] - m[k, k]) * 2
    q = [0.0, 0.0, 0.0, 0.0]
    q[i] = 0.25 * s
    q[j] = (m[j, i] + m[i, j]) / s
    q[k] = (m[k, i] + m[i, k]) / s
    q[3] = (m[k, j] - m[j, k]) / s
    return q[0], q[1], q[2], q[3]
