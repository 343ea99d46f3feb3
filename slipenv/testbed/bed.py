"""A virtual single-wheel test bed in PyBullet, like Reina's §3 rig (Reina Fig. 6).

A static base carries, in series: a prismatic x joint (the carriage, speed-controlled at the
ground speed V), a prismatic y joint (held at zero speed: its motor force is the lateral load
the carriage must resist), a free prismatic z joint carrying the ballast that sets the vertical
load W, and the wheel's revolute spin joint (speed-controlled), its axle yawed by the slip angle
beta. The soil acts on the wheel through slipenv's own injector (`slipenv.sim.wheel_soil`) and
PyBullet's friction is zero, so the only horizontal forces on the wheel are the force law's.
The forces are read where the real rig's six-axis sensor sits: at the carriage, as the motor
forces of the x and y joints, rotated into the wheel's heading frame.

Imposed kinematics (Reina Eq. 3-4, driving): the carriage moves along world +x at V; the wheel
heads at yaw -beta, so its contact point slides to its left at v_lat = V sin(beta) and forward
at v_x = V cos(beta), tan(beta) = v_lat/v_x; the wheel spins at omega = v_x/(r (1 - s)).

What the simulation feeds the force law: its slip states relax to s (Eq. 3) and to the law's
own slip angle (`slipenv.terramechanics.slip_dynamics`, `models.slip_angle_convention`): for
Reina's law tan(beta) = v_lat/v_x (Eq. 4), so at steady state the carriage forces are Reina's
law at the imposed (s, beta); for the Janosi and linear laws tan(beta) = v_lat/max(r omega, v_x),
the direction of the sliding velocity, i.e. (1 - s) tan(beta) in drive. The bed records both the
imposed slip angle and the state the law saw (`Trial.law_tan_beta`). A trial can also be run in
the sliding-velocity convention (``convention="simulation"``): the imposed tan(beta) is then
v_lat/(r omega), which probes the shear laws at exactly (s, beta).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim.wheel_soil import WheelSoilInjector
from slipenv.terrain.terrain import TerrainSpec, build_terrain
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.soil import Soil
from slipenv.terramechanics.soil_map import UniformSoil
from slipenv.vehicles.body import VehicleBody
from slipenv.vehicles.spec import VehicleSpec, WheelSpec

p = import_pybullet()

__all__ = ["BedWheel", "REINA_WHEEL", "Trial", "VirtualTestBed"]


@dataclass(frozen=True)
class BedWheel:
    """The wheel on the bed and its vertical load.

    Attributes
    ----------
    radius_m, width_m : float
        Wheel radius and width [m], > 0.
    contact_length_m : float
        Contact patch length [m] the Janosi/linear laws use, > 0.
    load_n : float
        Vertical load W [N] (wheel + ballast weight), > 0.
    """

    radius_m: float = 0.092
    width_m: float = 0.110
    contact_length_m: float = 0.05
    load_n: float = 6.6 * G_MPS2

    def __post_init__(self) -> None:
        for name in ("radius_m", "width_m", "contact_length_m", "load_n"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"BedWheel.{name} must be finite and > 0, got {value!r}")

    def geometry(self) -> ContactGeometry:
        """The contact geometry force models are built with."""
        return ContactGeometry(radius_m=self.radius_m, width_m=self.width_m,
                               contact_length_m=self.contact_length_m)


REINA_WHEEL = BedWheel()
"""Reina §3.2: r = 92 mm, b = 110 mm, W = 6.6 kg (contact length assumed 5 cm)."""


@dataclass(frozen=True)
class Trial:
    """One steady trial: imposed slip, measured mean forces and their spread.

    Sign conventions (also the CSV's, `slipenv.testbed.csv_format`): slip_ratio > 0 driving;
    slip_angle_deg = atan(v_lat/v_x) with v_lat the wheel's sliding velocity to its left;
    fx_n > 0 pushes the wheel forward along its heading; fy_n > 0 pushes it to its left (so
    fy_n < 0 for slip_angle_deg > 0: the soil opposes the sliding).
    """

    slip_ratio: float
    slip_angle_deg: float
    normal_load_n: float
    fx_n: float
    fy_n: float
    fx_std_n: float
    fy_std_n: float
    law_slip: float
    law_tan_beta: float

    @property
    def law_slip_angle_deg(self) -> float:
        """The slip angle the simulated soil's force law was evaluated at [deg], in the law's
        convention (see module)."""
        return math.degrees(math.atan(self.law_tan_beta))


class VirtualTestBed:
    """Drag one wheel at imposed slip ratio and slip angle; read the forces at the carriage.

    Parameters
    ----------
    force_model : ForceModel
        The soil's force law (`slipenv.terramechanics.models`), built for ``wheel.geometry()``.
    soil : Soil or soil map
        The soil in the bin.
    wheel : BedWheel
        Wheel and load; default Reina's.
    dt_s : float
        Physics step [s].
    """

    def __init__(self, force_model, soil, wheel: BedWheel = REINA_WHEEL,
                 dt_s: float = 1.0 / 240.0) -> None:
        if isinstance(soil, Soil):
            soil = UniformSoil(soil)
        if not hasattr(soil, "params_at"):
            raise ValueError(f"soil must be a Soil or a soil map, got {soil!r}")
        self.wheel, self.dt_s, self.force_model = wheel, float(dt_s), force_model
        self.client = c = p.connect(p.DIRECT)
        p.setGravity(0, 0, -G_MPS2, physicsClientId=c)
        p.setTimeStep(self.dt_s, physicsClientId=c)
        self._ground = build_terrain(TerrainSpec(), c)
        self._soil = soil
        self._body: int | None = None
        self._injector: WheelSoilInjector | None = None
        self._beta: float | None = None

    def _build(self, slip_angle_rad: float) -> tuple[int, WheelSoilInjector]:
        """(Re)build the rig with the axle yawed by -beta (the wheel heads at -beta); its
        body and injector."""
        c, w = self.client, self.wheel
        if self._body is not None:
            p.removeBody(self._body, physicsClientId=c)
        col = p.createCollisionShape(p.GEOM_SPHERE, radius=w.radius_m, physicsClientId=c)
        wheel_kg = 0.5
        ballast_kg = w.load_n / G_MPS2 - wheel_kg
        if ballast_kg <= 0.0:
            raise ValueError(f"BedWheel.load_n={w.load_n!r} must exceed the wheel's own weight")
        yaw = p.getQuaternionFromEuler((0.0, 0.0, -slip_angle_rad))
        self._body = body = p.createMultiBody(
            baseMass=0.0, basePosition=[0, 0, w.radius_m + 0.2],
            linkMasses=[0.5, 0.5, ballast_kg, wheel_kg],
            linkCollisionShapeIndices=[-1, -1, -1, col],
            linkVisualShapeIndices=[-1, -1, -1, -1],
            linkPositions=[[0, 0, 0], [0, 0, 0], [0, 0, 0], [0, 0, -0.2]],
            linkOrientations=[[0, 0, 0, 1], [0, 0, 0, 1], [0, 0, 0, 1], yaw],
            linkInertialFramePositions=[[0, 0, 0]] * 4,
            linkInertialFrameOrientations=[[0, 0, 0, 1]] * 4,
            linkParentIndices=[0, 1, 2, 3],
            linkJointTypes=[p.JOINT_PRISMATIC, p.JOINT_PRISMATIC, p.JOINT_PRISMATIC,
                            p.JOINT_REVOLUTE],
            linkJointAxis=[[1, 0, 0], [0, 1, 0], [0, 0, 1], [0, 1, 0]],
            physicsClientId=c,
        )
        for link in range(-1, 4):
            p.changeDynamics(body, link, lateralFriction=0.0, linearDamping=0.0,
                             angularDamping=0.0, physicsClientId=c)
        p.setJointMotorControl2(body, 2, p.VELOCITY_CONTROL, force=0.0, physicsClientId=c)
        spec = VehicleSpec(
            name="test_bed", kind="diff_drive", chassis_mass_kg=1.0,
            chassis_size_m=(0.1, 0.1, 0.1), chassis_center_height_m=0.0,
            wheels=(WheelSpec("wheel", (0.0, 0.0, 0.0), w.radius_m, w.width_m, wheel_kg,
                              "wheel", contact_length_m=w.contact_length_m),),
            channels=("wheel",), track_width_m=1.0, wheel_radius_nominal_m=w.radius_m,
            max_wheel_speed_rad_s=100.0, max_wheel_torque_nm=1e3, max_speed_mps=1.0,
            max_yaw_rate_rad_s=1.0)
        handles = VehicleBody(body, [3], [3], [None], (0.0, 0.0, 0.0), w.radius_m)
        self._injector = injector = WheelSoilInjector(c, spec, handles, self._ground.body_id,
                                                      self.force_model, self._soil, self.dt_s)
        self._beta = slip_angle_rad
        return body, injector

    def trial(self, slip_ratio: float, slip_angle_deg: float, speed_mps: float = 0.05,
              settle_s: float = 5.0, average_s: float = 1.0,
              convention: str = "reina") -> Trial:
        """Run one steady trial and average the carriage forces over its last ``average_s``.

        Parameters
        ----------
        slip_ratio : float
            Imposed s in [0, 1) (driving; Reina Eq. 3: s = 1 - v_x/(r omega)).
        slip_angle_deg : float
            Imposed slip angle beta [deg], |beta| < 80.
        speed_mps : float
            Speed of the wheel centre over the ground [m/s], > 0 (Reina's rig: <= 10 cm/s).
        settle_s, average_s : float
            Time to reach steady state, then time averaged over [s]. At 5 cm/s 5 s is about
            seven slip relaxation lengths (the contact arc, 3.6 cm on the bed's wheel).
        convention : str
            ``"reina"``: tan(beta) = v_lat/v_x (Reina Eq. 4, the real rig, and the slip angle
            Reina's law takes). ``"simulation"``: tan(beta) = v_lat/max(r omega, v_x), the
            sliding-velocity slip angle the Janosi and linear laws take (module docstring),
            so those laws are probed at exactly (s, beta).
        """
        if not (0.0 <= slip_ratio < 1.0):
            raise ValueError(f"slip_ratio={slip_ratio!r} must be in [0, 1) (driving)")
        if not abs(slip_angle_deg) < 80.0:
            raise ValueError(f"slip_angle_deg={slip_angle_deg!r} must be in (-80, 80)")
        if not speed_mps > 0.0:
            raise ValueError(f"speed_mps={speed_mps!r} must be > 0")
        if convention not in ("reina", "simulation"):
            raise ValueError(f"convention={convention!r} must be 'reina' or 'simulation'")
        tan_b = math.tan(math.radians(slip_angle_deg))
        # Velocities in the wheel's heading frame per unit rim speed r omega.
        v_x = 1.0 - slip_ratio
        v_lat = tan_b * v_x if convention == "reina" else tan_b
        rim = speed_mps / math.hypot(v_x, v_lat)  # r omega [m/s]
        beta = math.atan2(v_lat, v_x)  # direction of travel relative to the heading
        body, inj = self._build(beta)
        c = self.client
        # The injector's rolling radius may differ from r (soil's rolling_radius_scale).
        omega = rim / inj.rolling_radius_m(0)
        p.setJointMotorControl2(body, 0, p.VELOCITY_CONTROL, targetVelocity=speed_mps,
                                force=1e4, physicsClientId=c)
        p.setJointMotorControl2(body, 1, p.VELOCITY_CONTROL, targetVelocity=0.0, force=1e4,
                                physicsClientId=c)
        p.setJointMotorControl2(body, 3, p.VELOCITY_CONTROL, targetVelocity=omega, force=1e4,
                                physicsClientId=c)
        n_avg = max(1, int(round(average_s / self.dt_s)))
        n = int(round(settle_s / self.dt_s)) + n_avg
        samples = np.empty((n_avg, 5))
        cos_b, sin_b = math.cos(beta), math.sin(beta)
        for i in range(n):
            inj.apply()
            p.stepSimulation(physicsClientId=c)
            if i >= n - n_avg:
                # Carriage motor forces = minus the soil's horizontal force on the wheel.
                fx_w = -p.getJointState(body, 0, physicsClientId=c)[3]
                fy_w = -p.getJointState(body, 1, physicsClientId=c)[3]
                # Heading (cos b, -sin b), left (sin b, cos b) in the world.
                samples[i - (n - n_avg)] = (fx_w * cos_b - fy_w * sin_b,
                                            fx_w * sin_b + fy_w * cos_b, inj.load[0],
                                            inj.s[0], inj.b[0])
        mean, std = samples.mean(axis=0), samples.std(axis=0)
        return Trial(float(slip_ratio), float(slip_angle_deg), float(mean[2]), float(mean[0]),
                     float(mean[1]), float(std[0]), float(std[1]), float(mean[3]),
                     float(mean[4]))

    def sweep(self, slips, slip_angles_deg, **kw) -> list[Trial]:
        """`trial` at every (slip, slip angle) pair, slips varying fastest."""
        return [self.trial(float(s), float(b), **kw) for b in slip_angles_deg for s in slips]

    def close(self) -> None:
        """Disconnect the bed's PyBullet client."""
        if self.client is not None:
            p.disconnect(self.client)
            self.client = None

    def __enter__(self) -> VirtualTestBed:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def write_trials(directory, trials: list[Trial], wheel: BedWheel = REINA_WHEEL,
                 noise_n: float = 0.0, seed: int = 0, slip_angle_definition: str = "reina"):
    """Write bed trials in the test-bed CSV format (`slipenv.testbed.csv_format`).

    Parameters
    ----------
    directory : path
        Output directory (``trials.csv``, ``meta.json``).
    trials : list of Trial
        From `VirtualTestBed.trial` / `sweep`.
    wheel : BedWheel
        The bed's wheel (radius, width, contact length go to ``meta.json``).
    noise_n : float
        Standard deviation [N] of a seeded Gaussian sensor noise added to each trial's mean
        forces (the virtual bed itself is nearly noise-free); written as fx_std_n, fy_std_n.
    seed : int
        Seed of the noise generator.
    slip_angle_definition : str
        The ``convention`` the trials were run with (``"reina"`` or ``"simulation"``).
    """
    from slipenv.testbed.csv_format import write_testbed

    if not (math.isfinite(noise_n) and noise_n >= 0.0):
        raise ValueError(f"noise_n={noise_n!r} must be finite and >= 0")
    rng = np.random.default_rng(seed)
    rows = []
    for t in trials:
        ex, ey = rng.normal(0.0, noise_n, 2) if noise_n > 0 else (0.0, 0.0)
        rows.append({"slip_ratio": t.slip_ratio, "slip_angle_deg": t.slip_angle_deg,
                     "normal_load_n": t.normal_load_n, "fx_n": t.fx_n + ex, "fy_n": t.fy_n + ey,
                     "fx_std_n": math.hypot(t.fx_std_n, noise_n),
                     "fy_std_n": math.hypot(t.fy_std_n, noise_n)})
    meta = {"wheel_radius_m": wheel.radius_m, "wheel_width_m": wheel.width_m,
            "contact_length_m": wheel.contact_length_m,
            "slip_angle_definition": slip_angle_definition,
            "notes": "generated by slipenv's virtual single-wheel test bed"}
    return write_testbed(directory, rows, meta)
