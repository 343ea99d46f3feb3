"""The circle of Yamauchi §3.1 (r = 0.25 m at 5 cm/s on the 15° slope, Fig. 8) driven by the
path-following law, Eq. 9 (feedback) or Eq. 10 (β feed-forward), through ``predict`` as a
user would, in one :func:`slipenv.rollout.rollout` with the public
:class:`slipenv.rollout.TrajectoryRecorder`.

Two *limit* set-ups measure what bounds the result: :class:`LimitObservation` replaces the
env's observation by one built from the true-β odometry or from the truth; :func:`best_gain`
picks a law's oracle gain, the best of a grid of triple poles judged on the laps' true error.
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from slipenv.contracts import PoseEstimate
from slipenv.contracts.observation import build_observation
from slipenv.controllers.yamauchi import YamauchiController
from slipenv.envs.config import corridor_for
from slipenv.envs.estimation import odometry_geometry
from slipenv.envs.slip_env import SlipEnv
from slipenv.estimators.skid_steer import SlipCompensatedOdometry
from slipenv.paths import circle
from slipenv.rollout import TrajectoryRecorder, rollout

from .odometry import TrueSlipAngle, true_beta_odometry
from .settings import STEER_ON, Settings
from .world import make_world

WHOLE_LAP_M = 1.0
"""Corridor [m] of a circle episode (four radii): no lap ends early, whatever its error."""


def limit_observation(path, info: dict, est) -> np.ndarray:
    """The observation of a limit episode.

    ``est`` is the true-β odometry's last estimate, or None to steer on the truth.
    """
    if est is None:
        x, y, yaw = info["true_pose"]
        speed, rate = info["true_velocity_body_mps"][0], info["true_yaw_rate_rps"]
        beta = info["true_slip_angle_rad"]
    else:
        x, y, yaw, speed, rate = est.x_m, est.y_m, est.yaw_rad, est.speed_mps, est.yaw_rate_rps
        beta = est.slip_angle_rad
    return build_observation(x, y, yaw, speed, rate, path.project(x, y), beta)


class LimitObservation(gym.Wrapper):
    """Replaces the observation by a limit's (:data:`~.settings.STEER_ON`), from ``info``.

    ``"true_beta"``: slip-compensated odometry on the sensor frames with the true β in place of
    Eq. 9 (Endo's exponent ``n``); ``"truth"``: the true pose, speed and β. ``info
    ["estimated_pose"]`` becomes the pose the law steers on, so recorders see that estimate.
    """

    def __init__(self, env: gym.Env, steer_on: str, n: float | None = None) -> None:
        super().__init__(env)
        base = env.unwrapped
        if not isinstance(base, SlipEnv):
            raise TypeError(f"LimitObservation wraps a SlipEnv, got {type(base).__name__}")
        self._base = base
        if steer_on not in STEER_ON[1:]:
            raise ValueError(f"steer_on must be one of {STEER_ON[1:]}, got {steer_on!r}")
        if steer_on == "true_beta" and n is None:
            raise ValueError("steer_on='true_beta' needs Endo's n")
        self.steer_on, self.n = steer_on, n
        self._oracle = TrueSlipAngle()
        self._odometry: SlipCompensatedOdometry | None = None
        self._est: PoseEstimate | None = None

    def _observe(self, info: dict) -> tuple[np.ndarray, dict]:
        obs = limit_observation(self._base.path, info, self._est)
        pose = (info["true_pose"] if self._est is None
                else (self._est.x_m, self._est.y_m, self._est.yaw_rad))
        return obs, {**info, "estimated_pose": np.asarray(pose, dtype=float)}

    def reset(self, **kwargs):
        _, info = self.env.reset(**kwargs)
        self._oracle.beta_rad = 0.0
        self._odometry = self._est = None
        if self.steer_on == "true_beta":
            assert self.n is not None  # __init__ refuses true_beta without n
            self._odometry = true_beta_odometry(
                odometry_geometry(self._base.vehicle), self.n, self._oracle)
            self._est = self._odometry.reset(*info["true_pose"], info["sensors"])
        return self._observe(info)

    def step(self, action):
        _, reward, terminated, truncated, info = self.env.step(action)
        self._oracle.beta_rad = info["true_slip_angle_rad"]
        if self._odometry is not None:
            self._est = self._odometry.update(info["sensors"])
        obs, info = self._observe(info)
        return obs, reward, terminated, truncated, info


def circle_episode(cfg: Settings, pole_rps: float, feedforward: bool, estimator: str,
                   estimator_kwargs: dict, seed: int, tilt_deg: float,
                   soil: str | None = None, steer_on: str = "observation") -> dict:
    """One lap of the circle; the law's gains from a triple pole at ``pole_rps`` [rad/s].

    ``steer_on`` (:data:`~.settings.STEER_ON`) selects what the law sees: the env's
    observation from ``estimator``, or a limit (Endo's n from ``estimator_kwargs["n"]``).
    Returns the true cross-track statistics [m] over the whole lap, whether the lap was
    completed inside the env's corridor (0.1 m on Yamauchi's circle, ``corridor_m``), how it
    ended and the true and steered-on xy tracks.

    The episode runs in a corridor of :data:`WHOLE_LAP_M` so that the error statistics cover
    the whole lap (the paper's 9.1 and 1.3 cm are lap averages); a lap counts as completed
    when it reached the end and never left the env's own corridor, which is what the env's
    ``success`` would have been.
    """
    if steer_on not in STEER_ON:
        raise ValueError(f"steer_on must be one of {STEER_ON}, got {steer_on!r}")
    env = make_world(tilt_deg, soil if soil is not None else cfg.soil, cfg.vehicle,
                     path=circle(cfg.circle_radius_m, cfg.speed_mps),
                     estimator=estimator, estimator_kwargs=estimator_kwargs,
                     max_cross_track_m=WHOLE_LAP_M)
    if steer_on != "observation":
        env = LimitObservation(env, steer_on, estimator_kwargs.get("n"))
    base = env.unwrapped
    assert isinstance(base, SlipEnv)  # make_world makes a slipenv id
    corridor_m = corridor_for(base.path)  # the env's own, 0.1 m on Yamauchi's circle
    policy = YamauchiController.from_poles(
        pole_rps, cfg.speed_mps, v_max_mps=base.vehicle.max_speed_mps,
        omega_max_rps=base.vehicle.max_yaw_rate_rad_s, dt_s=base.control_dt_s,
        use_feedforward=feedforward)
    rec = TrajectoryRecorder()
    result = rollout(env, policy, seed=seed, recorders=[rec])
    env.close()
    traj = rec.trajectory()
    ct = np.abs(traj.cross_track_true_m)
    beta_deg = np.degrees(traj.slip_angle_rad)
    return {"mean_error_m": float(ct.mean()), "rmse_m": float(np.sqrt(np.mean(ct**2))),
            "max_error_m": float(ct.max()),
            "completed": bool(result.success and ct.max() <= corridor_m),
            "corridor_m": float(corridor_m),
            # how far the true slip angle swings around the lap (5-95 % range) [deg]
            "slip_angle_swing_deg": float(np.subtract(*np.percentile(beta_deg, [95, 5]))),
            "end": result.end_reason, "true_xy": traj.true_pose[:, :2],
            "est_xy": traj.est_pose[:, :2]}


def mean_episodes(eps: list[dict]) -> dict:
    """Mean error, RMSE and max error [m] and the slip angle's swing [deg] averaged over laps;
    each lap's mean error; laps completed."""
    keys = ("mean_error_m", "rmse_m", "max_error_m", "slip_angle_swing_deg")
    out: dict[str, Any] = {k: float(np.mean([e[k] for e in eps])) for k in keys}
    out["per_seed_mean_error_m"] = [e["mean_error_m"] for e in eps]
    out["completed"] = int(sum(e["completed"] for e in eps))
    return out


def best_gain(laps_by_pole: dict[float, list[dict]]) -> dict:
    """The oracle controller of a law: the triple pole [rad/s] whose worst lap has the smallest
    true maximum cross-track error [m], the quantity that decides whether every lap stays in
    the corridor (ties: the first pole of the grid).

    ``laps_by_pole`` maps each pole to its laps (:func:`circle_episode` results). Returns the
    chosen pole, its laps averaged (:func:`mean_episodes`) with their worst maximum error, the
    env's corridor they were judged in, and per pole (keyed ``f"{pole:g}"``) the mean error,
    worst maximum error and laps completed.
    Chosen on the laps it reports: a bound on what any gain of the grid can do, not a tuning.
    """
    if not laps_by_pole or not all(laps_by_pole.values()):
        raise ValueError("best_gain needs at least one lap at each of at least one pole")
    worst = {p: max(e["max_error_m"] for e in eps) for p, eps in laps_by_pole.items()}
    pole = min(worst, key=lambda p: worst[p])
    by_pole = {f"{p:g}": {"mean_error_m": float(np.mean([e["mean_error_m"] for e in eps])),
                          "worst_max_error_m": worst[p],
                          "completed": int(sum(e["completed"] for e in eps))}
               for p, eps in laps_by_pole.items()}
    return {"pole_rps": pole, **mean_episodes(laps_by_pole[pole]),
            "worst_max_error_m": worst[pole], "laps_run": len(laps_by_pole[pole]),
            "corridor_m": laps_by_pole[pole][0]["corridor_m"], "by_pole": by_pole}
