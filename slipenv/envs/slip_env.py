"""The slipenv Gymnasium environment: a vehicle following a path on soil that makes it slip.

Layers (one-way): :class:`~slipenv.sim.simulator.Simulator` (PyBullet + injected force law)
-> :class:`~slipenv.sensors.onboard.SensorSuite` -> estimator (``estimators/``) -> observation.
Reward and termination use ground truth; ground truth goes in ``info``.
"""

from __future__ import annotations

import math
import os
import sys
import weakref
from typing import TYPE_CHECKING, Any, cast

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from slipenv.contracts import OBS_HIGH, OBS_LOW, PoseEstimate, build_observation, wrap_angle
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.factory import (
    build_estimator,
    check_action,
    check_estimator_name,
    make_force_model,
    make_path,
    make_soil_map,
    make_vehicle,
)
from slipenv.envs.render import render_camera_panel, render_map
from slipenv.paths import Path, sample_path
from slipenv.sensors.noise import SensorNoise
from slipenv.sensors.onboard import SensorSuite
from slipenv.sensors.trace_camera import TraceCameraConfig, TraceFrame
from slipenv.sensors.trace_rig import TraceCameraRig, camera_config_for
from slipenv.sim.simulator import PhysicsBlowUp, Simulator, VehicleTruth
from slipenv.terrain.terrain import TerrainSpec
from slipenv.vehicles.kinematics import twist_to_commands
from slipenv.vehicles.spec import VehicleSpec

if TYPE_CHECKING:  # the estimators package imports scipy.stats and numba: 1.5 s
    from slipenv.estimators.base import Estimator


def _checked_action(action: Any) -> tuple[float, float]:
    """The action's two values as floats, checked as :func:`check_action` checks them.

    A float32 or float64 array of shape (2,) with finite values (what agents send) is read
    directly: ``tolist`` gives the same doubles as ``astype(np.float64)``; anything else goes
    through ``check_action`` (its errors name the problem).
    """
    if type(action) is np.ndarray and action.shape == (2,) and action.dtype in _FAST_DTYPES:
        a0, a1 = action.tolist()
        if math.isfinite(a0) and math.isfinite(a1):
            return a0, a1
    a0, a1 = check_action(action).tolist()
    return a0, a1


_FAST_DTYPES = (np.dtype(np.float32), np.dtype(np.float64))


def _columns(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``np.column_stack((a, b))`` of two vectors, without its generic checks."""
    out = np.empty((len(a), 2), dtype=np.result_type(a, b))
    out[:, 0] = a
    out[:, 1] = b
    return out


def episode_steps(max_episode_s: float, control_hz: float) -> int:
    """Steps of an episode of ``max_episode_s`` at ``control_hz``: the time limit rounded up
    to a whole step, where a product within 1e-9 of an integer counts as that integer (40 s at
    20 Hz is 800 steps, not 801 from the rounding of 1/20)."""
    steps = max_episode_s * control_hz
    return max(1, round(steps) if abs(steps - round(steps)) < 1e-9 else math.ceil(steps))


def render_modes() -> list[str]:
    """``["rgb_array"]``, plus ``"human"`` where a display is available (the GUI needs one)."""
    headless = sys.platform.startswith("linux") and not os.environ.get("DISPLAY")
    return ["rgb_array"] if headless else ["human", "rgb_array"]


class SlipEnv(gym.Env):
    """Path following on deformable soil with slip-aware odometry.

    Description
        A PyBullet vehicle (farm 2WD, tracked skid-steer, 4WD/4WS rover or Husky) drives on
        flat, sloped or mounded terrain whose soil acts through a terramechanic force law
        (Janosi/Okello, Lindgren's linear torque-slip law or Reina's combined-slip law) injected
        at every wheel contact. The agent commands a body twist; the vehicle's motors track the
        resulting wheel speeds, and the soil decides how much of that becomes motion.

    Observation (``Box(12,)``, float32) — from the *estimator*, never from ground truth:

        ===  ======================  =====  ==============================================
        idx  name                    unit   meaning
        ===  ======================  =====  ==============================================
        0    x_m                     m      estimated x of the reference point
        1    y_m                     m      estimated y
        2    cos_yaw                 -      cos of estimated heading
        3    sin_yaw                 -      sin of estimated heading
        4    speed_mps               m/s    estimated forward speed
        5    yaw_rate_rps            rad/s  estimated yaw rate
        6    slip_angle_est_rad      rad    estimated body slip angle β̂ (0 if not modelled)
        7    cross_track_m           m      distance to the path, > 0 left of it (estimated)
        8    heading_error_rad       rad    estimated heading minus path heading
        9    path_curvature_1pm      1/m    path curvature at the projection, > 0 turns left
        10   ref_speed_mps           m/s    reference speed at the projection
        11   progress                -      fraction of the path done (estimated), 0..1
        ===  ======================  =====  ==============================================

    Action (``Box(-1, 1, (2,))``, float32): ``[v / v_max, Ω / Ω_max]``, a body twist turned
    into wheel (track, steering) commands by the vehicle's nominal kinematics.

    Reward: a weighted sum of named terms (weights ``reward_weights``, values in
    ``info["reward_terms"]``), all from ground truth: ``cross_track`` = -(e/1 m)^2,
    ``heading`` = -e_ψ^2, ``progress`` = path length gained / (reference speed · dt),
    ``effort`` = -|Δaction|^2.

    Randomness: every draw comes from the env's generator, seeded by ``reset(seed)``: the
    start pose is jittered (``start_jitter``, default within 2 cm and ±1° of the path's start)
    and the sensors' noise (``sensor_noise``) reaches the observation through the estimator, so
    different seeds give different episodes and one seed gives the same one bit for bit.

    Episode end: terminated when the true progress reaches the path end or the true
    cross-track error exceeds the corridor (``max_cross_track_m``; by default 0.4 of the
    path's smallest turning radius, at most 2 m); truncated at ``max_episode_s`` or on a
    physics blow-up (``info["truncation_reason"]``).

    Rear trace camera (Reina §2): with ``estimator="scomp"`` the env mounts a 5 Hz camera
    behind the rear-left wheel (:mod:`slipenv.sensors.trace_rig`), runs FTrace on every frame
    and feeds its slip angle to sComp odometry, so observation index 6 is FTrace's β̂ and
    indices 0-5 come from sComp. ``info["trace_detection"]`` holds FTrace's last
    :class:`~slipenv.estimators.reina.TraceDetection` (``None`` while it reports no trace).
    With ``camera_in_info=True`` the step that renders a frame also puts the
    :class:`~slipenv.sensors.trace_camera.TraceFrame` (grey image and its true trace) in
    ``info["trace_frame"]`` (``None`` on the other steps). In ``rgb_array`` mode ``render()``
    then returns the map and the last camera frame side by side, (480, 1280, 3), FTrace's
    trace drawn in green (yellow while held); ``env.unwrapped.trace_frame`` is the last raw
    frame.

    Arguments: every field of :class:`~slipenv.envs.config.SlipEnvConfig` as a kwarg, plus
    ``render_mode`` (``"rgb_array"`` or ``"human"``).

    Version history: v0 — first release.
    """

    # The class lists every mode (so ``gym.make(id, render_mode="human")`` reaches the env,
    # which says that the GUI needs a display); an instance lists the modes available on this
    # machine (``human`` only with a display), which is what ``check_env`` tries one by one.
    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 20}

    def __init__(self, render_mode: str | None = None, config: SlipEnvConfig | None = None,
                 **kwargs: Any) -> None:
        # ``human`` is accepted even where it is not advertised: the simulator then says
        # that the GUI needs a display.
        if render_mode not in (None, "human", "rgb_array"):
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        self.config = SlipEnvConfig.from_kwargs(config, **kwargs)
        cfg = self.config
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_modes": render_modes(),
                         "render_fps": int(cfg.control_hz)}
        check_estimator_name(cfg.estimator)
        self._vehicle = make_vehicle(cfg.vehicle)
        self._path = self._make_path(cfg)
        soil_map = make_soil_map(cfg.soil, cfg.soil_map)
        force_model = make_force_model(cfg.force_model, self._vehicle, cfg.force_model_kwargs)
        beacons = self._make_beacons(cfg)
        # SlipEnvConfig stores its terrain and sensor noise as specs (it converts the names
        # and dicts it accepts).
        terrain, noise = cast(TerrainSpec, cfg.terrain), cast(SensorNoise, cfg.sensor_noise)
        self._sim = Simulator(
            self._vehicle, terrain, force_model, soil_map, physics_hz=cfg.physics_hz,
            control_hz=cfg.control_hz, gui=render_mode == "human", multi_pass=cfg.multi_pass,
            castor_own_geometry=cfg.castor_own_geometry,
        )
        self._dt_s = self._sim.control_dt_s
        self._corridor_m = cfg.corridor_m(self._path)
        self.max_steps = episode_steps(cfg.max_episode_s, cfg.control_hz)
        self._sensors = SensorSuite(self._vehicle.counts_per_rad, noise, beacons=beacons)
        self.observation_space = spaces.Box(OBS_LOW, OBS_HIGH, dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.estimator: Estimator | None = None
        self._truth: VehicleTruth | None = None
        self._trace: list[tuple[float, float]] = []  # true (x, y) per step, for render()
        self._trace_est: list[tuple[float, float]] = []
        self._path_xy: np.ndarray | None = None
        self._camera_config: TraceCameraConfig | None = None
        self._rig: TraceCameraRig | None = None
        self._trace_frame_now: TraceFrame | None = None
        # Build the estimator once now so that bad ``estimator_kwargs`` fail at make time.
        if hasattr(self._build_estimator(), "update_trace") and self._camera_config is not None:
            self._rig = TraceCameraRig(self._sim, self._camera_config)

    # -- read-only surface for experiments and tools ----------------------------------------
    @property
    def vehicle(self) -> VehicleSpec:
        """The vehicle's spec (geometry, motors, sensors' resolution)."""
        return self._vehicle

    @property
    def path(self) -> Path:
        """The reference path of the task."""
        return self._path

    @property
    def max_cross_track_m(self) -> float:
        """Half-width of the corridor [m] success is judged in: the config's
        ``max_cross_track_m``, or the corridor that fits the path
        (:func:`slipenv.envs.config.corridor_for`)."""
        return self._corridor_m

    @property
    def control_dt_s(self) -> float:
        """Control period: simulated time of one ``step`` [s]."""
        return self._dt_s

    @property
    def substeps_per_step(self) -> int:
        """Physics substeps per ``step`` (the force law runs at every one)."""
        return self._sim.substeps

    @property
    def physics_client_id(self) -> int:
        """The PyBullet client of this env's world (for benchmarks and rendering)."""
        return self._sim.client

    @property
    def trace_frame(self) -> TraceFrame | None:
        """The rear trace camera's last frame (``estimator="scomp"``), else None."""
        return None if self._rig is None else self._rig.last_frame

    @property
    def beacons_xy(self) -> np.ndarray | None:
        """Surveyed beacon positions, shape (n, 2) [m], or None without a beacon scanner."""
        beacons = self._sensors.beacons
        return None if beacons is None else beacons.beacons_xy.copy()

    def true_soil(self):
        """The soil the wheels are on now, in the estimators' terms (for oracle filters only;
        see :func:`slipenv.envs.estimation.true_soil_for_oracle`)."""
        from slipenv.envs.estimation import true_soil_for_oracle

        noise = cast(SensorNoise, self.config.sensor_noise)
        return true_soil_for_oracle(self._sim, noise.torque_scale)

    # -- construction hooks (overridable by subclasses) ------------------------------------
    def _make_path(self, cfg: SlipEnvConfig) -> Path:
        if isinstance(cfg.path, Path):
            return cfg.path
        return make_path(cfg.path, cfg.path_kwargs)

    def _make_beacons(self, cfg: SlipEnvConfig):
        if cfg.beacons is None or cfg.beacons is False:
            return None
        from slipenv.sensors.beacons import BeaconScanner

        if cfg.beacons is True:
            return BeaconScanner()
        if isinstance(cfg.beacons, BeaconScanner):
            return cfg.beacons
        return BeaconScanner(beacons_xy=np.asarray(cfg.beacons, dtype=float))

    def _jittered_start(self) -> tuple[float, float, float]:
        """The path's start pose moved by the seeded ``start_jitter`` (uniform over a disc in
        position, uniform in yaw)."""
        x0, y0, yaw0 = self._path.start_pose()
        radius_m, yaw_deg = self.config.start_jitter
        u = self.np_random.uniform(0.0, 1.0, size=3)
        r, bearing = radius_m * math.sqrt(u[0]), 2.0 * math.pi * u[1]
        return (x0 + r * math.cos(bearing), y0 + r * math.sin(bearing),
                wrap_angle(yaw0 + math.radians(yaw_deg) * (2.0 * u[2] - 1.0)))

    def _build_estimator(self) -> Estimator:
        return build_estimator(self.config.estimator, self.config.estimator_kwargs,
                               self._vehicle, self._estimator_context())

    # -- gymnasium API ---------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        self._check_open("reset")
        super().reset(seed=seed)
        x0, y0, yaw0 = self._jittered_start()
        truth = self._sim.reset(x0, y0, yaw0)
        self._truth = truth
        self._sensors.reset()
        frame = self._sensors.measure(truth, self.np_random)
        self.estimator = estimator = self._build_estimator()
        estimate = estimator.reset(x0, y0, yaw0, frame)
        if self._rig is not None:
            self._rig.reset(self.np_random)
            self._camera_step(truth)
        self._steps = 0
        self._s_est = self._s_true = 0.0
        self._last_action = (0.0, 0.0)  # the last clipped action
        self._trace, self._trace_est = [], []
        self._record(truth, estimate)
        obs = self._observe(estimate)
        return obs, self._info(truth, estimate, frame, {})

    def step(self, action):
        self._check_open("step")
        a0, a1 = _checked_action(action)
        if self.estimator is None:
            raise RuntimeError("call reset() before step()")
        a0, a1 = min(max(a0, -1.0), 1.0), min(max(a1, -1.0), 1.0)
        spec = self._vehicle
        speeds, steer = twist_to_commands(
            spec, a0 * spec.max_speed_mps, a1 * spec.max_yaw_rate_rad_s
        )
        self._steps += 1
        try:
            truth = self._sim.step(speeds, steer)
        except PhysicsBlowUp as exc:
            obs = self._observe(self._last_estimate)
            info = {"truncation_reason": f"physics blow-up: {exc}", "reward_terms": {}}
            return obs, 0.0, False, True, info
        self._truth = truth
        frame = self._sensors.measure(truth, self.np_random)
        if self._rig is not None:
            self._camera_step(truth)
        estimate = self.estimator.update(frame)
        self._record(truth, estimate)
        obs = self._observe(estimate)

        x, y, _ = truth.position_m
        proj = self._path.project(x, y, s_hint=self._s_true)
        gained = max(proj.s - self._s_true, 0.0)
        self._s_true = proj.s
        heading_err = wrap_angle(truth.yaw_rad - proj.heading_rad)
        d0, d1 = a0 - self._last_action[0], a1 - self._last_action[1]  # Δaction
        terms = {
            "cross_track": -(proj.cross_track_m**2),
            "heading": -(heading_err**2),
            "progress": gained / max(proj.speed_mps * self._dt_s, 1e-6),
            "effort": -(d0 * d0 + d1 * d1),
        }
        weights = self.config.reward_weights
        reward = float(sum(weights.get(k, 0.0) * v for k, v in terms.items()))
        self._last_action = (a0, a1)
        done_path = self._s_true >= self._path.length_m - 1e-3
        lost = abs(proj.cross_track_m) > self._corridor_m
        truncated = self._steps >= self.max_steps and not (done_path or lost)
        extra = {
            "reward_terms": terms,
            "cross_track_true_m": proj.cross_track_m,
            "heading_error_true_rad": heading_err,
            "progress_true": self._s_true / self._path.length_m,
            "is_success": bool(done_path),
        }
        if lost:
            extra["termination_reason"] = "left the path corridor"
        if truncated:
            extra["truncation_reason"] = "time limit"
        return obs, reward, bool(done_path or lost), bool(truncated), self._info(
            truth, estimate, frame, extra)

    def render(self):
        """``rgb_array``: a (480, 640, 3) uint8 north-up map with the reference path (blue),
        the true trace (red), the estimate's trace (orange) and the chassis at its true pose
        (see :mod:`slipenv.envs.render`); ``None`` before ``reset`` or in other modes."""
        if self.render_mode != "rgb_array" or self._truth is None:
            return None
        if self._path_xy is None:
            samples = sample_path(self._path, ds_m=max(self._path.length_m / 2000.0, 0.01))
            self._path_xy = np.stack([samples.x_m, samples.y_m], axis=1)
        x, y, _ = self._truth.position_m
        length_m, width_m, _ = self._vehicle.chassis_size_m
        view = render_map(self._path_xy, np.array(self._trace), np.array(self._trace_est),
                          (x, y, self._truth.yaw_rad), (length_m, width_m))
        if self._rig is None:
            return view
        frame = self._rig.last_frame
        panel = render_camera_panel(
            None if frame is None else frame.image, self._rig.camera.camera,
            getattr(self.estimator, "last_detection", None), self._rig.config.ground_z_m,
            view.shape[:2], self._rig.config.wheel_xy_m)
        return np.concatenate([view, panel], axis=1)

    def close(self) -> None:
        """Disconnect the physics client (idempotent; a dropped env is also released by the
        simulator's finalizer)."""
        sim = getattr(self, "_sim", None)  # absent if construction failed before it
        if sim is not None:
            sim.close()
        self._closed = True

    def _check_open(self, call: str) -> None:
        # Without this, the disconnected PyBullet client surfaces as a TypeError about None.
        if getattr(self, "_closed", False):
            raise RuntimeError(f"env is closed: {call}() after close(); make a new env")

    # -- helpers ---------------------------------------------------------------------------
    def _estimator_context(self) -> dict:
        """What an estimator may be told beyond the nominal geometry: the control period, the
        surveyed beacon positions, and (for ``*_oracle`` estimators only) the true soil."""
        beacons = self._sensors.beacons
        # A weak reference: an estimator that kept the context must not keep the env (and its
        # physics client) alive through a reference cycle.
        true_soil = weakref.WeakMethod(self.true_soil)

        def soil() -> Any:
            method = true_soil()
            if method is None:
                raise ReferenceError("the env that made this estimator no longer exists")
            return method()

        return {
            "dt_s": self._dt_s,
            "beacons_xy": None if beacons is None else beacons.beacons_xy,
            "true_soil": soil,
            "trace_camera": self._mount_camera,
        }

    def _mount_camera(self, config: TraceCameraConfig, wheel: str) -> TraceCameraConfig:
        """The rear trace camera ``config`` mounted behind ``wheel`` of this vehicle (called by
        estimators that need the camera; the env then renders it for them)."""
        self._camera_config = camera_config_for(self._sim, wheel, config)
        return self._camera_config

    def _camera_step(self, truth: VehicleTruth) -> None:
        """Record the wheel traces; at the camera's rate render a frame and run FTrace on it."""
        assert self._rig is not None and self.estimator is not None
        trace = self._rig.step(truth, self.np_random)
        self._trace_frame_now = trace
        if trace is not None:
            self.estimator.update_trace(trace.image)

    def _record(self, truth: VehicleTruth, estimate: PoseEstimate) -> None:
        if self.render_mode == "rgb_array":
            self._trace.append(truth.position_m[:2])
            self._trace_est.append((estimate.x_m, estimate.y_m))

    def _observe(self, estimate: PoseEstimate) -> np.ndarray:
        self._last_estimate = estimate
        proj = self._path.project(estimate.x_m, estimate.y_m, s_hint=self._s_est)
        self._s_est = proj.s
        try:
            return build_observation(estimate.x_m, estimate.y_m, estimate.yaw_rad,
                                     estimate.speed_mps, estimate.yaw_rate_rps, proj,
                                     estimate.slip_angle_rad)
        except FloatingPointError as exc:
            raise FloatingPointError(f"the estimator diverged: {exc}") from None

    def _info(self, truth: VehicleTruth, estimate: PoseEstimate, frame, extra: dict) -> dict:
        contact = self._sim.injector.contact_state()
        x, y, _ = truth.position_m
        info = {
            "t_s": truth.t_s,
            "true_pose": np.array([x, y, truth.yaw_rad]),
            "true_velocity_body_mps": np.array(truth.velocity_body_mps[:2]),
            "true_yaw_rate_rps": truth.yaw_rate_rad_s,
            "true_slip_angle_rad": truth.slip_angle_rad,
            "true_roll_pitch_rad": np.array([truth.roll_rad, truth.pitch_rad]),
            "wheel_slip": contact.slip,
            "wheel_slip_angle_rad": np.arctan(contact.tan_beta),
            "wheel_load_n": contact.load_n,
            "wheel_force_n": _columns(contact.fx_n, contact.fy_n),
            "wheel_resistance_n": contact.resistance_n,
            "wheel_damper_n": contact.damper_n,
            "estimated_pose": np.array([estimate.x_m, estimate.y_m, estimate.yaw_rad]),
            "estimator_extras": dict(estimate.extras),
            "sensors": frame,
        }
        if self._rig is not None:
            detection = getattr(self.estimator, "last_detection", None)
            info["trace_detection"] = detection if detection is not None and detection.found \
                else None
            if self.config.camera_in_info:
                info["trace_frame"] = self._trace_frame_now
        info.update(extra)
        return info
