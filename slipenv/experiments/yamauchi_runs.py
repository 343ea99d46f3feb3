"""The runs of ``slipenv reproduce yamauchi``: rotation runs, slip identification data, odometry
replays and circle episodes (Yamauchi et al. §2.3-3.1), each in the PyBullet world through the
registered ``slipenv/TrackedSlopeCircle-v0`` env; the orchestration is in
:mod:`slipenv.experiments.yamauchi`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gymnasium as gym
import numpy as np

import slipenv  # noqa: F401  (registers the envs)
from slipenv.contracts import wrap_angle
from slipenv.contracts.observation import build_observation
from slipenv.controllers.yamauchi import YamauchiController
from slipenv.envs.estimation import odometry_geometry
from slipenv.estimators.endo import EndoOdometry
from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.identification import SlipRun, fit_endo_n, train_test_split_runs, true_slips
from slipenv.estimators.yamauchi import SlipCompensatedOdometry
from slipenv.paths import circle, straight

ENV_ID = "slipenv/TrackedSlopeCircle-v0"
ORACLE_MAX_SLIP_ANGLE_RAD = 1.5  # [rad] the true β is not clipped like a regression's (1 rad)


@dataclass(frozen=True)
class Settings:
    """What the experiment runs; ``quick`` has fewer repetitions, the same experiments."""

    tilts_deg: tuple[float, ...] = (0.0, 8.0, 15.0)
    turn_rates_dps: tuple[float, ...] = (10.0, 20.0, 30.0)  # §2.3
    directions: tuple[int, ...] = (1, -1)  # counter-clockwise, clockwise
    repeats: int = 4  # runs per (tilt, rate, direction)
    speed_mps: float = 0.05  # §2.3
    rotation_deg: float = 90.0  # §2.3: "about 90 degrees"
    heading_jitter_deg: float = 5.0  # start heading ± this, uniform (set by hand in the paper)
    max_rotation_s: float = 30.0
    test_fraction: float = 1.0 / 3.0
    smooth_steps: int = 5  # centred window of the slip derivatives [control steps]
    min_speed_mps: float = 0.01  # the slip angle of a vehicle at rest is undefined
    circle_tilt_deg: float = 15.0  # §3.1
    circle_radius_m: float = 0.25  # §3.1
    circle_seeds: int = 5  # §3.1 ran each law three times
    poles_rps: tuple[float, ...] = (0.15, 0.25, 0.4, 0.6, 1.0)  # rigid-ground gain search


QUICK = Settings(repeats=2, circle_seeds=3, poles_rps=(0.15, 0.3, 0.6))


@dataclass
class RotationRun:
    """One rotation run: sensor frames and ground truth at each control step (k samples)."""

    name: str
    tilt_deg: float
    rate_dps: float
    direction: int
    frames: list
    t_s: np.ndarray  # (k,)
    pose: np.ndarray  # (k, 3) x, y, yaw [m, m, rad]
    v_body: np.ndarray  # (k, 2) body-frame velocity of the reference point [m/s]
    yaw_rate: np.ndarray  # (k,) [rad/s]
    slip_angle: np.ndarray  # (k,) true body slip angle [rad] (the simulator's definition)


class _NoSlipAngle:
    """A β model that predicts 0: runs SlipCompensatedOdometry just for its regressors."""

    def predict(self, roll, angular_displacement, rotation_radius):
        return np.zeros(np.shape(roll))


class TrueSlipAngle:
    """An oracle in Eq. 9's slot: predicts whatever true slip angle the caller last set.

    Only the experiment's *limit* measurements use it, to separate what the slip-angle
    regression costs from what Endo's slip ratios cost; no estimator or env observation sees
    ground truth.
    """

    def __init__(self) -> None:
        self.beta_rad = 0.0

    def predict(self, roll, angular_displacement, rotation_radius):
        return np.full(np.shape(roll), self.beta_rad)


STEER_ON = ("observation", "true_beta", "truth")
"""What a circle episode steers on: the env's observation (what a user gets); slip-compensated
odometry with the true β in place of Eq. 9 (a limit: perfect slip-angle regression, Endo's
slip ratios); the true pose and β (a limit: perfect odometry)."""


def make_world(tilt_deg: float, soil: str = "toyoura_sand", **kwargs) -> gym.Env:
    """The tracked vehicle on a slope of ``tilt_deg`` (downhill -y) or flat ground."""
    terrain = ({"kind": "slope", "slope_deg": float(tilt_deg), "downhill_azimuth_deg": -90.0}
               if tilt_deg > 0.0 else "flat")
    return gym.make(ENV_ID, terrain=terrain, soil=soil, **kwargs)


def rotation_run(cfg: Settings, tilt_deg: float, rate_dps: float, direction: int, seed: int,
                 heading_rad: float, name: str) -> RotationRun:
    """Drive a constant twist (5 cm/s, ±rate) from rest until the true heading turned 90°."""
    env = make_world(tilt_deg, path=straight(5.0, cfg.speed_mps, heading_rad),
                     estimator="gyrodometry", estimator_kwargs={}, max_cross_track_m=10.0)
    spec = env.unwrapped.vehicle
    action = np.array([cfg.speed_mps / spec.max_speed_mps,
                       direction * math.radians(rate_dps) / spec.max_yaw_rate_rad_s],
                      dtype=np.float32)
    _, info = env.reset(seed=seed)
    rows, turned = [info], 0.0
    for _ in range(int(cfg.max_rotation_s / env.unwrapped.control_dt_s)):
        _, _, terminated, truncated, info = env.step(action)
        turned += wrap_angle(info["true_pose"][2] - rows[-1]["true_pose"][2])
        rows.append(info)
        if abs(turned) >= math.radians(cfg.rotation_deg) or terminated or truncated:
            break
    env.close()
    return RotationRun(
        name=name, tilt_deg=tilt_deg, rate_dps=rate_dps, direction=direction,
        frames=[r["sensors"] for r in rows], t_s=np.array([r["t_s"] for r in rows]),
        pose=np.array([r["true_pose"] for r in rows]),
        v_body=np.array([r["true_velocity_body_mps"] for r in rows]),
        yaw_rate=np.array([r["true_yaw_rate_rps"] for r in rows]),
        slip_angle=np.array([r["true_slip_angle_rad"] for r in rows]),
    )


def _window(k: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    idx = np.arange(k)
    return np.clip(idx - w // 2, 0, k - 1), np.clip(idx + w // 2, 0, k - 1)


def run_slips(run: RotationRun, geom, w: int) -> dict[str, np.ndarray]:
    """Input track speeds (encoders) and true slips of a run, as derivatives over ``w`` steps.

    Like the paper's motion-capture derivatives, both the encoder speeds and the true body
    velocity are taken over the same centred window.
    """
    angles = np.array([f.enc_counts for f in run.frames], dtype=float) / geom.counts_per_rad
    k = len(run.t_s)
    i0, i1 = _window(k, w)
    dt = np.maximum(run.t_s[i1] - run.t_s[i0], 1e-9)
    left = angles[:, list(geom.left)].mean(axis=1)
    right = angles[:, list(geom.right)].mean(axis=1)
    omega_l, omega_r = (left[i1] - left[i0]) / dt, (right[i1] - right[i0]) / dt
    box = np.ones(w) / w
    smooth = [np.convolve(np.pad(x, w // 2, mode="edge"), box, mode="valid")[:k]
              for x in (run.v_body[:, 0], run.v_body[:, 1], run.yaw_rate)]
    alpha_l, alpha_r, beta = true_slips(omega_l, omega_r, geom.wheel_radius_m, smooth[0],
                                        smooth[2], smooth[1], geom.track_width_m)
    r = geom.wheel_radius_m
    return {"v_l": r * omega_l, "v_r": r * omega_r, "alpha_l": alpha_l, "alpha_r": alpha_r,
            "beta": beta, "speed": np.hypot(smooth[0], smooth[1])}


def fit_n(runs: list[RotationRun], geom, w: int):
    """Endo's n (Eq. 8) by log-log least squares over the samples of ``runs``."""
    s = [run_slips(r, geom, w) for r in runs]
    cat = {k: np.concatenate([x[k] for x in s]) for k in ("v_l", "v_r", "alpha_l", "alpha_r")}
    return fit_endo_n(cat["v_l"], cat["v_r"], cat["alpha_l"], cat["alpha_r"]), cat


def replay(estimator, run: RotationRun,
           oracle: TrueSlipAngle | None = None) -> tuple[np.ndarray, list[dict]]:
    """Feed a run's sensor frames to ``estimator`` from the true start pose: (k, 2) xy, extras.

    With ``oracle`` (the estimator's β model), it is set to each frame's true slip angle
    before that frame is fed.
    """
    x, y, yaw = run.pose[0]
    est = estimator.reset(x, y, yaw, run.frames[0])
    xy, extras = [(est.x_m, est.y_m)], [dict(est.extras)]
    for k, frame in enumerate(run.frames[1:], start=1):
        if oracle is not None:
            oracle.beta_rad = float(run.slip_angle[k])
        est = estimator.update(frame)
        xy.append((est.x_m, est.y_m))
        extras.append(dict(est.extras))
    return np.array(xy), extras


def slip_run(run: RotationRun, geom, n: float, cfg: Settings) -> SlipRun:
    """Eq. 9 regressors computed online exactly as the odometry does, and the true β."""
    _, extras = replay(SlipCompensatedOdometry(geom, n, _NoSlipAngle()), run)
    x = np.array([[e["roll_rad"], e["angular_displacement_rad"], e["rotation_radius_m"]]
                  for e in extras[1:]])
    truth = run_slips(run, geom, cfg.smooth_steps)
    keep = truth["speed"][1:] >= cfg.min_speed_mps
    return SlipRun(run.name, x[keep], truth["beta"][1:][keep])


def odometry_errors(runs, geom, n_by_tilt, model) -> dict[str, np.ndarray]:
    """Squared position errors [m²] pooled over ``runs``: the three odometries, and the limit.

    ``slip_compensated_true_beta`` is the slip-compensated odometry with the true slip angle in
    place of Eq. 9: what a perfect regression would leave, i.e. the cost of Endo's slip ratios.
    """
    out: dict[str, list] = {"gyrodometry": [], "endo": [], "slip_compensated": [],
                            "slip_compensated_true_beta": []}
    for run in runs:
        n = n_by_tilt[run.tilt_deg]
        oracle = TrueSlipAngle()
        for key, est in (("gyrodometry", Gyrodometry(geom)), ("endo", EndoOdometry(geom, n)),
                         ("slip_compensated", SlipCompensatedOdometry(geom, n, model)),
                         ("slip_compensated_true_beta", SlipCompensatedOdometry(
                             geom, n, oracle, max_slip_angle_rad=ORACLE_MAX_SLIP_ANGLE_RAD))):
            xy, _ = replay(est, run, oracle if key.endswith("true_beta") else None)
            out[key].append(np.sum((xy - run.pose[:, :2]) ** 2, axis=1))
    return {k: np.concatenate(v) for k, v in out.items()}


def circle_episode(cfg: Settings, pole_rps: float, feedforward: bool, estimator: str,
                   estimator_kwargs: dict, seed: int, tilt_deg: float,
                   soil: str = "toyoura_sand", steer_on: str = "observation") -> dict:
    """One circle (§3.1) driven by the Yamauchi law through ``predict``, as a user would.

    ``steer_on`` (:data:`STEER_ON`) selects what the law sees. ``"observation"`` is the env's
    observation from ``estimator``. The two limits build it from the info the env reports:
    ``"true_beta"`` from slip-compensated odometry on the sensor frames with the true β
    (Endo's n from ``estimator_kwargs["n"]``), ``"truth"`` from the true pose, speed and β.
    """
    if steer_on not in STEER_ON:
        raise ValueError(f"steer_on must be one of {STEER_ON}, got {steer_on!r}")
    env = make_world(tilt_deg, soil, path=circle(cfg.circle_radius_m, cfg.speed_mps),
                     estimator=estimator, estimator_kwargs=estimator_kwargs)
    base = env.unwrapped
    policy = YamauchiController.from_poles(
        pole_rps, cfg.speed_mps, v_max_mps=base.vehicle.max_speed_mps,
        omega_max_rps=base.vehicle.max_yaw_rate_rad_s, dt_s=base.control_dt_s,
        use_feedforward=feedforward)
    obs, info = env.reset(seed=seed)
    policy.reset()
    oracle, odometry, est = TrueSlipAngle(), None, None
    if steer_on == "true_beta":
        odometry = SlipCompensatedOdometry(
            odometry_geometry(base.vehicle), estimator_kwargs["n"], oracle,
            max_slip_angle_rad=ORACLE_MAX_SLIP_ANGLE_RAD)
        est = odometry.reset(*info["true_pose"], info["sensors"])
    true_xy, est_xy, ct = [], [], []
    end = "time limit"
    while True:
        if steer_on != "observation":
            obs = _limit_observation(base.path, info, est)
        action, _ = policy.predict(obs, deterministic=True)
        obs, _, terminated, truncated, info = env.step(action)
        oracle.beta_rad = info["true_slip_angle_rad"]
        if odometry is not None:
            est = odometry.update(info["sensors"])
        true_xy.append(info["true_pose"][:2])
        est_xy.append(info["estimated_pose"][:2] if steer_on == "observation"
                      else info["true_pose"][:2] if est is None else (est.x_m, est.y_m))
        ct.append(info["cross_track_true_m"])
        if terminated or truncated:
            end = info.get("termination_reason") or info.get("truncation_reason") or "done"
            break
    env.close()
    ct = np.abs(np.array(ct))
    return {"mean_error_m": float(ct.mean()), "rmse_m": float(np.sqrt(np.mean(ct**2))),
            "max_error_m": float(ct.max()), "completed": bool(info.get("is_success")),
            "end": end, "true_xy": np.array(true_xy), "est_xy": np.array(est_xy)}


def _limit_observation(path, info: dict, est):
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


def progress_bar(items, progress: bool, desc: str):
    if not progress:
        return items
    from tqdm import tqdm

    return tqdm(items, desc=desc, leave=False)


def collect_runs(cfg: Settings, rng: np.random.Generator, progress: bool) -> list[RotationRun]:
    """Every rotation run of the experiment (seeded start-heading jitter and sensor noise)."""
    plan = [(t, w, d, i) for t in cfg.tilts_deg for w in cfg.turn_rates_dps
            for d in cfg.directions for i in range(cfg.repeats)]
    seeds = rng.integers(0, 2**31 - 1, size=len(plan))
    jitter = rng.uniform(-1.0, 1.0, size=len(plan)) * math.radians(cfg.heading_jitter_deg)
    steps = zip(progress_bar(plan, progress, "rotation runs"), seeds, jitter, strict=True)
    return [rotation_run(cfg, t, w, d, int(s), float(h),
                         f"tilt{t:g}_rate{w:g}_{'ccw' if d > 0 else 'cw'}_{i}")
            for (t, w, d, i), s, h in steps]


def split_runs(runs, cfg: Settings, rng) -> tuple[list, list]:
    """Hold out ``test_fraction`` of the runs of every (tilt, direction) group, by run."""
    train, test = [], []
    for t in cfg.tilts_deg:
        for d in cfg.directions:
            group = [r for r in runs if r.tilt_deg == t and r.direction == d]
            a, b = train_test_split_runs(group, cfg.test_fraction, rng)
            train += a
            test += b
    return train, test
