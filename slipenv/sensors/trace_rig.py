"""The rear trace camera on a simulated vehicle: contact history from the simulator + the camera.

:class:`TraceCameraRig` reads the wheels' contact points from the simulator after every control
step (wheel centre minus the wheel radius straight down, and the Bekker static sinkage at the
wheel's current load and soil as rut depth, Wong Eq. 5.x via
:func:`slipenv.terramechanics.bekker.wheel_sinkage_float_m`), stores them in a
:class:`~slipenv.sensors.trace_history.ContactHistory`, and renders a
:class:`~slipenv.sensors.trace_camera.TraceFrame` whenever the 5 Hz camera is due (Reina §2, §4).
Physics-notes §3 option (A): the image is rasterised from the true contact path.

At 20 Hz control and 8 cm/s a wheel moves 4 mm per step, finer than the 1 cm spacing the history
keeps, so sampling per control step (not per physics substep) loses nothing the camera could see.
"""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pybullet as p

from slipenv.sensors.trace_camera import TraceCamera, TraceCameraConfig, TraceFrame
from slipenv.sensors.trace_history import ContactHistory
from slipenv.sim.simulator import Simulator, VehicleTruth
from slipenv.terramechanics.bekker import wheel_sinkage_float_m


def camera_config_for(sim: Simulator, wheel_name: str = "rear_left",
                      base: TraceCameraConfig | None = None) -> TraceCameraConfig:
    """The camera config ``base`` mounted behind ``wheel_name`` of the simulated vehicle.

    Raises
    ------
    ValueError
        If the vehicle has no wheel called ``wheel_name``.
    """
    names = [w.name for w in sim.spec.wheels]
    if wheel_name not in names:
        raise ValueError(f"the trace camera watches wheel {wheel_name!r}, but vehicle "
                         f"{sim.spec.name!r} has wheels {names}")
    wheel = sim.spec.wheels[names.index(wheel_name)]
    ref = sim.body.base_to_reference_m
    xy = (wheel.position_m[0] - ref[0], wheel.position_m[1] - ref[1])
    return replace(base or TraceCameraConfig(), wheel_name=wheel_name, wheel_xy_m=xy,
                   wheel_radius_m=wheel.radius_m, wheel_width_m=wheel.width_m)


class TraceCameraRig:
    """Contact history and rear trace camera of one simulated vehicle.

    Parameters
    ----------
    sim : Simulator
        The vehicle's simulator (read only: wheel link states, loads, soil).
    config : TraceCameraConfig
        Camera mount and nuisances (see :func:`camera_config_for`).
    """

    def __init__(self, sim: Simulator, config: TraceCameraConfig) -> None:
        self.sim, self.config = sim, config
        wheels = sim.spec.wheels
        self.history = ContactHistory([w.name for w in wheels], [w.width_m for w in wheels])
        self._radius = np.array([w.radius_m for w in wheels])
        self._width = np.array([w.width_m for w in wheels])
        self.camera = TraceCamera(config)
        self.last_frame: TraceFrame | None = None

    def reset(self, rng: np.random.Generator) -> None:
        """New episode: forget the traces and draw the mount's calibration error from ``rng``."""
        self.history.clear()
        self.camera = TraceCamera(self.config, calibration_rng=rng)
        self.last_frame = None

    def record(self) -> None:
        """Append every wheel's current contact point and sinkage to the history."""
        sim, inj = self.sim, self.sim.injector
        states = p.getLinkStates(sim.body.body_id, inj.links, physicsClientId=sim.client)
        points = np.array([s[0] for s in states], dtype=float)  # wheel centres
        points[:, 2] -= self._radius  # the contact point: one radius straight down
        load = np.asarray(inj.load, dtype=float)
        sink = np.zeros(len(load))
        for k in range(len(load)):
            soil = inj.soil_at_wheel(k)
            sink[k] = wheel_sinkage_float_m(float(load[k]), float(self._width[k]),
                                       float(2.0 * self._radius[k]), float(soil.k_c),
                                       float(soil.k_phi), float(soil.n_exp))
        points[load <= 0.0] = np.nan  # a wheel in the air leaves no trace
        if not np.isfinite(sink).all():  # (the check costs a fraction of nan_to_num)
            sink = np.nan_to_num(sink)
        self.history.append(points, sink)

    def step(self, truth: VehicleTruth, rng: np.random.Generator) -> TraceFrame | None:
        """Record the contacts; render and return a frame if the camera is due, else None."""
        self.record()
        if not self.camera.due(truth.t_s):
            return None
        x, y, z = truth.position_m
        pose = (x, y, z, truth.roll_rad, truth.pitch_rad, truth.yaw_rad)
        if not all(math.isfinite(v) for v in pose):
            return None
        self.last_frame = self.camera.measure(self.history, pose, rng, t_s=truth.t_s)
        return self.last_frame
