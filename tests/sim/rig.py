"""A single-wheel test bed in PyBullet, like Reina's: a carriage drags one wheel at a set slip.

Static base -> prismatic x (carriage, speed-controlled) -> prismatic z (free, carries the
ballast that sets the normal load) -> revolute y (the wheel, speed-controlled). The carriage
motor's force is minus the drawbar pull the soil develops on the wheel.
"""

from __future__ import annotations

import numpy as np
import pybullet as p

from slipenv.sim.wheel_soil import WheelSoilInjector
from slipenv.terrain.terrain import TerrainSpec, build_terrain
from slipenv.vehicles.body import VehicleBody
from slipenv.vehicles.spec import VehicleSpec, WheelSpec

RADIUS_M, WIDTH_M, CONTACT_M = 0.09, 0.08, 0.05
DT_S = 1.0 / 240.0


def single_wheel_spec() -> VehicleSpec:
    wheel = WheelSpec("wheel", (0.0, 0.0, 0.0), RADIUS_M, WIDTH_M, 0.5, "wheel",
                      contact_length_m=CONTACT_M)
    return VehicleSpec(
        name="single_wheel_rig", kind="diff_drive", chassis_mass_kg=1.0,
        chassis_size_m=(0.1, 0.1, 0.1), chassis_center_height_m=0.0, wheels=(wheel,),
        channels=("wheel",), track_width_m=1.0, wheel_radius_nominal_m=RADIUS_M,
        max_wheel_speed_rad_s=50.0, max_wheel_torque_nm=500.0, max_speed_mps=1.0,
        max_yaw_rate_rad_s=1.0,
    )


class SingleWheelRig:
    """Drag one wheel at ground speed v and wheel speed ω; read the drawbar pull."""

    def __init__(self, force_model, soil_map, ballast_kg: float = 6.1) -> None:
        self.client = p.connect(p.DIRECT)
        c = self.client
        p.setGravity(0, 0, -9.81, physicsClientId=c)
        p.setTimeStep(DT_S, physicsClientId=c)
        self.ground = build_terrain(TerrainSpec(), c)
        wheel_col = p.createCollisionShape(p.GEOM_SPHERE, radius=RADIUS_M, physicsClientId=c)
        self.body = p.createMultiBody(
            baseMass=0.0, basePosition=[0, 0, RADIUS_M + 0.2],
            linkMasses=[1.0, ballast_kg, 0.5],
            linkCollisionShapeIndices=[-1, -1, wheel_col],
            linkVisualShapeIndices=[-1, -1, -1],
            linkPositions=[[0, 0, 0], [0, 0, 0], [0, 0, -0.2]],
            linkOrientations=[[0, 0, 0, 1]] * 3,
            linkInertialFramePositions=[[0, 0, 0]] * 3,
            linkInertialFrameOrientations=[[0, 0, 0, 1]] * 3,
            linkParentIndices=[0, 1, 2],
            linkJointTypes=[p.JOINT_PRISMATIC, p.JOINT_PRISMATIC, p.JOINT_REVOLUTE],
            linkJointAxis=[[1, 0, 0], [0, 0, 1], [0, 1, 0]],
            physicsClientId=c,
        )
        for link in (-1, 0, 1, 2):
            p.changeDynamics(self.body, link, lateralFriction=0.0, linearDamping=0.0,
                             angularDamping=0.0, physicsClientId=c)
        # The vertical slide is free: no motor.
        p.setJointMotorControl2(self.body, 1, p.VELOCITY_CONTROL, force=0.0, physicsClientId=c)
        self.spec = single_wheel_spec()
        handles = VehicleBody(self.body, [2], [2], [None], (0.0, 0.0, 0.0), RADIUS_M)
        self.injector = WheelSoilInjector(c, self.spec, handles, self.ground.body_id,
                                          force_model, soil_map, DT_S)
        self.load_n = (ballast_kg + 0.5) * 9.81

    def drag(self, ground_speed_mps: float, wheel_rate_rad_s: float, seconds: float = 3.0,
             average_s: float = 1.0) -> dict:
        """Run at fixed speeds; mean drawbar pull, load and slip over the last ``average_s``."""
        c = self.client
        p.setJointMotorControl2(self.body, 0, p.VELOCITY_CONTROL,
                                targetVelocity=ground_speed_mps, force=1e4, physicsClientId=c)
        p.setJointMotorControl2(self.body, 2, p.VELOCITY_CONTROL,
                                targetVelocity=wheel_rate_rad_s, force=1e4, physicsClientId=c)
        n = int(seconds / DT_S)
        n_avg = int(average_s / DT_S)
        pulls, loads, slips, thrusts, res = [], [], [], [], []
        for i in range(n):
            self.injector.apply()
            p.stepSimulation(physicsClientId=c)
            if i >= n - n_avg:
                # Carriage motor force = -(horizontal force of the soil on the wheel).
                pulls.append(-p.getJointState(self.body, 0, physicsClientId=c)[3])
                loads.append(self.injector.load[0])
                slips.append(self.injector.s[0])
                thrusts.append(self.injector.fx[0])
                res.append(self.injector.res[0])
        return {"drawbar_pull_n": float(np.mean(pulls)), "load_n": float(np.mean(loads)),
                "slip": float(np.mean(slips)), "thrust_n": float(np.mean(thrusts)),
                "resistance_n": float(np.mean(res))}

    def drive_torque(self, ground_speed_mps: float, torque_nm: float, seconds: float = 3.0,
                     average_s: float = 1.0) -> dict:
        """Carriage at a fixed speed, the wheel driven by a constant torque [N m] (its speed
        free); mean slip, thrust and load over the last ``average_s``."""
        c = self.client
        p.setJointMotorControl2(self.body, 0, p.VELOCITY_CONTROL,
                                targetVelocity=ground_speed_mps, force=1e4, physicsClientId=c)
        p.setJointMotorControl2(self.body, 2, p.VELOCITY_CONTROL, force=0.0, physicsClientId=c)
        n, n_avg = int(seconds / DT_S), int(average_s / DT_S)
        slips, thrusts, loads = [], [], []
        for i in range(n):
            p.setJointMotorControl2(self.body, 2, p.TORQUE_CONTROL, force=torque_nm,
                                    physicsClientId=c)
            self.injector.apply()
            p.stepSimulation(physicsClientId=c)
            if i >= n - n_avg:
                slips.append(self.injector.s[0])
                thrusts.append(self.injector.fx[0])
                loads.append(self.injector.load[0])
        return {"slip": float(np.mean(slips)), "thrust_n": float(np.mean(thrusts)),
                "load_n": float(np.mean(loads))}

    def close(self) -> None:
        p.disconnect(self.client)
