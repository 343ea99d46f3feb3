"""The slipenv Gymnasium environment: a vehicle following a path on soil that makes it slip.

Layers (one-way): :class:`~slipenv.sim.simulator.Simulator` (PyBullet + injected force law)
-> :class:`~slipenv.sensors.onboard.SensorSuite` -> estimator (``estimators/``) -> observation.
Reward and termination use ground truth; ground truth goes in ``info``.
"""

from __future__ import annotations

import math
from typing import Any

import gymnasium as gym
import numpy as np
import pybullet as p
from gymnasium import spaces

from slipenv.contracts import OBS_HIGH, OBS_LOW, PoseEstimate, build_observation, wrap_angle
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.estimation import make_estimator
from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.paths import Path, path_by_name
from slipenv.sensors.onboard import SensorSuite
from slipenv.sim.simulator import PhysicsBlowUp, Simulator, VehicleTruth
from slipenv.vehicles.kinematics import twist_to_commands
from slipenv.vehicles.spec import VehicleSpec


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

    Episode end: terminated when the true progress reaches the path end or the true
    cross-track error exceeds ``max_cross_track_m``; truncated at ``max_episode_s`` or on a
    physics blow-up (``info["truncation_reason"]``).

    Arguments: every field of :class:`~slipenv.envs.config.SlipEnvConfig` as a kwarg, plus
    ``render_mode`` (``"rgb_array"`` or ``"human"``).

    Version history: v0 — first release.
    """

    metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 20}

    def __init__(self, render_mode: str | None = None, config: SlipEnvConfig | None = None,
                 **kwargs: Any) -> None:
        if render_mode not in (None, *self.metadata["render_modes"]):
            raise ValueError(
                f"render_mode must be one of {self.metadata['render_modes']} or None, "
                f"got {render_mode!r}"
            )
        self.config = SlipEnvConfig.from_kwargs(config, **kwargs)
        if self.config.model:
            # A fitted model extension (``slipenv diagnose``) rewrites the world's configuration.
            from slipenv.diagnose.extension import apply_model

            self.config = apply_model(self.config, self.config.model)
        cfg = self.config
        self.render_mode = render_mode
        self.metadata = {**self.metadata, "render_fps": int(cfg.control_hz)}
        from slipenv.envs.estimation import ESTIMATORS

        if cfg.estimator not in ESTIMATORS:
            raise ValueError(
                f"unknown estimator {cfg.estimator!r}; known estimators: {sorted(ESTIMATORS)}"
            )
        self._vehicle = make_vehicle(cfg.vehicle)
        self._path = self._make_path(cfg)
        soil_map = make_soil_map(cfg.soil, cfg.soil_map)
        force_model = make_force_model(cfg.force_model, self._vehicle)
        self._sim = Simulator(
            self._vehicle, cfg.terrain, force_model, soil_map, physics_hz=cfg.physics_hz,
            control_hz=cfg.control_hz, gui=render_mode == "human",
        )
        self._dt_s = self._sim.control_dt_s
        self.max_steps = int(math.ceil(cfg.max_episode_s / self._dt_s))
        self._sensors = SensorSuite(self._vehicle.counts_per_rad, cfg.sensor_noise,
                                   beacons=self._make_beacons(cfg))
        self.observation_space = spaces.Box(OBS_LOW, OBS_HIGH, dtype=np.float32)
        self.action_space = spaces.Box(-1.0, 1.0, shape=(2,), dtype=np.float32)
        self.estimator = None
        self._truth: VehicleTruth | None = None

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
    def beacons_xy(self) -> np.ndarray | None:
        """Surveyed beacon positions, shape (n, 2) [m], or None without a beacon scanner."""
        beacons = self._sensors.beacons
        return None if beacons is None else beacons.beacons_xy.copy()

    def true_soil(self):
        """The soil the wheels are on now, in the estimators' terms (for oracle filters only;
        see :func:`slipenv.envs.estimation.true_soil_for_oracle`)."""
        from slipenv.envs.estimation import true_soil_for_oracle

        return true_soil_for_oracle(self._sim, self.config.sensor_noise.torque_scale)

    # -- construction hooks (overridable by subclasses) ------------------------------------
    def _make_path(self, cfg: SlipEnvConfig) -> Path:
        if isinstance(cfg.path, Path):
            return cfg.path
        return path_by_name(cfg.path, **cfg.path_kwargs)

    def _make_beacons(self, cfg: SlipEnvConfig):
        if cfg.beacons is None or cfg.beacons is False:
            return None
        from slipenv.sensors.beacons import BeaconScanner

        if cfg.beacons is True or cfg.beacons == "default":
            return BeaconScanner()
        if isinstance(cfg.beacons, BeaconScanner):
            return cfg.beacons
        return BeaconScanner(beacons_xy=np.asarray(cfg.beacons, dtype=float))

    # -- gymnasium API ---------------------------------------------------------------------
    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        x0, y0, yaw0 = self._path.start_pose()
        truth = self._sim.reset(x0, y0, yaw0)
        self._truth = truth
        self._sensors.reset()
        frame = self._sensors.measure(truth, self.np_random)
        self.estimator = make_estimator(
            self.config.estimator, self._vehicle, self._estimator_context(),
            **self.config.estimator_kwargs,
        )
        estimate = self.estimator.reset(x0, y0, yaw0, frame)
        self._steps = 0
        self._s_est = self._s_true = 0.0
        self._last_action = np.zeros(2, dtype=np.float32)
        obs = self._observe(estimate)
        return obs, self._info(truth, estimate, frame, {})

    def step(self, action):
        action = np.asarray(action, dtype=np.float64).reshape(-1)
        if action.shape != (2,):
            raise ValueError(f"action must have shape (2,), got {np.shape(action)}")
        if not np.all(np.isfinite(action)):
            raise ValueError(f"action contains NaN or inf: {action.tolist()}")
        if self.estimator is None:
            raise RuntimeError("call reset() before step()")
        a = np.clip(action, -1.0, 1.0)
        spec = self._vehicle
        speeds, steer = twist_to_commands(
            spec, float(a[0]) * spec.max_speed_mps, float(a[1]) * spec.max_yaw_rate_rad_s
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
        estimate = self.estimator.update(frame)
        obs = self._observe(estimate)

        x, y, _ = truth.position_m
        proj = self._path.project(x, y, s_hint=self._s_true)
        gained = max(proj.s - self._s_true, 0.0)
        self._s_true = proj.s
        heading_err = wrap_angle(truth.yaw_rad - proj.heading_rad)
        terms = {
            "cross_track": -(proj.cross_track_m**2),
            "heading": -(heading_err**2),
            "progress": gained / max(proj.speed_mps * self._dt_s, 1e-6),
            "effort": -float(np.sum((a - self._last_action) ** 2)),
        }
        weights = self.config.reward_weights
        reward = float(sum(weights.get(k, 0.0) * v for k, v in terms.items()))
        self._last_action = a.astype(np.float32)
        done_path = self._s_true >= self._path.length_m - 1e-3
        lost = abs(proj.cross_track_m) > self.config.max_cross_track_m
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
        if self.render_mode != "rgb_array" or self._truth is None:
            return None
        x, y, z = self._truth.position_m
        size = max(self._vehicle.chassis_size_m)
        view = p.computeViewMatrixFromYawPitchRoll(
            [x, y, z], 4.0 * size, math.degrees(self._truth.yaw_rad) - 90.0, -30.0, 0.0, 2,
            physicsClientId=self._sim.client,
        )
        proj = p.computeProjectionMatrixFOV(60.0, 4 / 3, 0.05, 100.0,
                                            physicsClientId=self._sim.client)
        _, _, rgba, _, _ = p.getCameraImage(
            320, 240, view, proj, renderer=p.ER_TINY_RENDERER, physicsClientId=self._sim.client
        )
        return np.asarray(rgba, dtype=np.uint8).reshape(240, 320, 4)[:, :, :3]

    def close(self) -> None:
        if getattr(self, "sim", None) is not None:
            self._sim.close()
            self._sim = None

    # -- helpers ---------------------------------------------------------------------------
    def _estimator_context(self) -> dict:
        """What an estimator may be told beyond the nominal geometry: the control period, the
        surveyed beacon positions, and (for ``*_oracle`` estimators only) the true soil."""
        beacons = self._sensors.beacons
        return {
            "dt_s": self._dt_s,
            "beacons_xy": None if beacons is None else beacons.beacons_xy,
            "true_soil": self.true_soil,
        }

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
            "wheel_force_n": np.stack([contact.fx_n, contact.fy_n], axis=1),
            "wheel_resistance_n": contact.resistance_n,
            "estimated_pose": np.array([estimate.x_m, estimate.y_m, estimate.yaw_rad]),
            "estimator_extras": dict(estimate.extras),
            "sensors": frame,
        }
        info.update(extra)
        return info
