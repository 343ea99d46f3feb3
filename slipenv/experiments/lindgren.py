"""Lindgren et al. §5 re-run in simulation (``slipenv reproduce lindgren``, issue #3).

Like the paper, each drive of the vehicle records the raw sensor data, and the EKF schemes run
OFFLINE over the same frames (Lindgren §5: "the raw sensor data ... run through
four different EKF schemes"), exactly as :class:`slipenv.estimators.lindgren_ekf.LindgrenEKF` exposes
them. The vehicle is ``slipenv/FarmField-v0`` (farm_2wd on field_loam, linear torque/slip law,
true rolling radius 0.283 / 0.287 m against the concrete-calibrated nominal 0.275 m, finite
k_s), steered by the baseline path follower on the env's Lindgren EKF in **scheme 1** (laser +
inertial): the paper steered with scheme 3; scheme 1 keeps the driven path independent of the
two schemes being compared.

(a) Lindgren's circles (Fig. 3): 4 m radius, 1.5 loops clockwise then counter-clockwise at
    0.5 m/s (speed assumed). Schemes 1-4 and the oracle (scheme 4 knowing the true R_w, k_s).
    Statistics over the clockwise arc at constant speed (as the paper), after the first
    ``SETTLE_M`` metres: mean deviation from scheme 1 (Table 1) and, as only a simulation can,
    the true mean error, RMSE and pose NEES; time-averaged NIS of the odometric innovations
    (Eq. 43) with its 95 % band, exact and Eq. 44 (Table 3); autocorrelation ρ̄(l), Eq. 42,
    l = 1..``LAGS``, its mean, variance and share inside ±1.96/√K (Table 2, Fig. 6).
(b) Straights with alternating 180° turns (Fig. 7): laser and odometers only (the inertial and
    inclinometer readings are removed from the recorded frames; the EKF skips them), bearings
    removed after ``CUT_S`` = 50 s; final position error of scheme 3 (no slip model), scheme 4
    (slip model) and the oracle. One drive's final error is dominated by a random walk of the
    heading (the slip model/oracle ratio ranges 0.4-4.5 from drive to drive), so (b) drives the
    path ``Config.dropout_drives`` = 12 times (seeds ``seed``, ``seed + 1``, ...) and reports
    the mean final error, every drive's value in the JSON, the first drive in the plot.

``--quick`` runs the same experiments on shorter paths (1 loop each way; 3 straights).

Filter settings. Every scheme uses the paper's measurement variances (``LindgrenNoise``
defaults) and the k_s prior of :func:`slipenv.envs.estimation.default_k_s_prior`, with two
changes (``FILTER``), each also run at the estimator's default to show its effect
(``VARIANTS``, in the JSON and the table):

* The paper's bearing association, nearest innovation with no χ² gate. With the estimator's
  gate (0.999) scheme 3, whose odometry is trusted to the encoder's variance while it is 10 %
  off in scale, rejects the bearings that would correct it: on the straights it gates half of
  them and is already 2.2 m and 20° off when the laser is cut (final error 7.9 m instead of
  4.0 m); on the circles it gates a fifth and deviates about 15 % more.
* The random walk of the soil states, ``FIELD_NOISE``: the FarmField world is one uniform
  soil, so R_w may wander by about 1 mm and k_s by about 3 % per 100 m (the defaults allow
  1 cm and 10 %, right for a field whose soil changes). This matters once the laser is cut:
  with odometry alone, speed and soil states are unobservable along a common scale
  (z ∝ v k_s / (R_w (k_s - T))), and the estimate walks along it as fast as the process noise
  lets it — upward here, on the filter's own synthetic data as well. With the defaults R_w
  drifts from 0.281 to 0.315 m in the 78 s after the cut and the heading by 20° (final error
  1.4-2.6 m against the oracle's 0.1 m).

Results (seed 0, full / quick): all four targets of issue #3 are met, the last one barely.
Slip model / oracle after the cut is 1.46 / 1.27 (mean of 12 drives; over 16 drives of the
quick path 1.15, over 12 of the full path 1.46): met on average, at its edge on the full path.
The gap is the slip model's, not the world's: after 50 s (25 m, one turn, no gyro) the learnt
effective radii R_w (1 - T / k_s) are right to about 0.1 %, which 78 s of odometry alone
turns into heading error, and the slow upward walk along the unobservable scale remains
(the slip model ends 2-5 cm ahead along the track, the oracle about 1 cm).

What remains different from the paper (none of it tuned away):

* The simulated slip is large, about 11 % at 90 N m per wheel (k_s ≈ 760 N m, prior 674), so
  the nominal radius overstates distance by 10 % and the left/right difference by 1.4 %.
  Scheme 3 deviates more than in the paper and, after the cut, drifts further than 1.97 m:
  the paper's no-slip run used "a carefully measured effective wheel radius", this one the
  concrete-calibrated nominal radius, as issue #3 asks.
* Scheme 4's NIS lies *below* the band, the paper's above it: the simulated encoders err only
  by quantisation (1/6 count² for a count difference; that is also why ρ̄(1) ≈ -0.14, the
  lag-1 correlation of differenced quantisation errors) while the filter keeps the paper's
  3.1e-6 rad² = 0.25 count². The paper's excess came from effects the simulation lacks.
* Scheme 3's autocorrelation is a near-constant 0.3 (bias, no periodic part), so its variance
  over the lags is tiny; the paper's had a periodic component (variance 0.068).
* Under constant torque (circles at constant speed) R_w and k_s are not separately
  observable, only R_w (1 - T / k_s); the JSON lists the final estimates beside the truth.
* The pose NEES of scheme 4 and of the oracle is 2-3 times n = 3: both are overconfident.
  Candidates, not separated here: lateral slip in the turns, load transfer changing k_s,
  torque noise entering Eq. 37 as if exact.
"""

from __future__ import annotations

import contextlib
import dataclasses
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path as FsPath

import gymnasium as gym
import numpy as np

from slipenv.contracts.frame import SensorFrame
from slipenv.envs.estimation import default_k_s_prior, odometry_geometry
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.consistency import chi2_mean_band, consistency_report, nees
from slipenv.estimators.lindgren_ekf import LindgrenEKF, LindgrenNoise, OracleSoil
from slipenv.paths import Path, path_by_name
from slipenv.run import baseline_controller

ENV_ID = "slipenv/FarmField-v0"
STEER_SCHEME = 1  # the env's EKF scheme the path follower steers by (laser + inertial)
SPEED_MPS = 0.5  # [m/s] path speed (assumed: Lindgren gives none), as the FarmField preset
SETTLE_M = 5.0  # [m] start of the clockwise arc left out while the slip states converge
LAGS = 100  # autocorrelation lags 1..LAGS (Fig. 6)
CUT_S = 50.0  # [s] laser cut (Lindgren §5, Fig. 7)
FIELD_NOISE = {"radius_var_per_m": 1e-8,  # [m²/m]: R_w within ~1 mm per 100 m (one soil)
               "k_s_rel_var_per_m": 1e-5}  # [1/m]: k_s within ~3 % per 100 m (load shifts)
FILTER = {**FIELD_NOISE, "bearing_gate_prob": 1.0}  # + the paper's ungated association
# Extra filters: one of FILTER's settings put back to the estimator's default, to show its effect.
VARIANTS = {"scheme3_gated": ("scheme3", ("bearing_gate_prob",)),
            "scheme4_default_soil_noise": ("scheme4", tuple(FIELD_NOISE))}
SCHEMES = ("scheme1", "scheme2", "scheme3", "scheme4", "oracle", "scheme3_gated")
DROPOUT_FILTERS = ("scheme3", "scheme4", "oracle")

PAPER = {  # Lindgren §5: Tables 1-3, text, Fig. 7
    "mean_deviation_m": {"scheme3": 0.243, "scheme4": 0.127},
    "nis": {"scheme3": 5.1860, "scheme4": 3.1836, "band": [1.8831, 2.1204]},
    "autocorr_mean": {"scheme3": 0.2068, "scheme4": 0.0081},
    "autocorr_var": {"scheme3": 0.0678, "scheme4": 0.0444},
    "autocorr_share_inside": {"scheme3": 0.0, "scheme4": 0.9709},
    "n_samples": 1099,
    "dropout_final_error_m": {"no_slip_model": 1.97, "slip_model": 0.21, "oracle": None},
}


@dataclass(frozen=True)
class Config:
    """One run's size: loops each way on the circles, straights, drives of experiment (b)."""

    circle_loops: float
    straight_legs: int
    dropout_drives: int


FULL, QUICK = Config(1.5, 4, 12), Config(1.0, 3, 12)


@dataclass
class Recording:
    """One drive: every SensorFrame, the truth, and what the filters may be told."""

    path: Path
    frames: list[SensorFrame]
    t_s: np.ndarray  # (K,) [s]
    truth: np.ndarray  # (K, 3) true (x, y, yaw) of the reference point [m, m, rad]
    s_true_m: np.ndarray  # (K,) true progress along the path [m]
    oracle: OracleSoil  # true R_w and k_s (privileged, for the oracle filter only)
    params: LindgrenNoise  # the filters' parameters: FILTER and the k_s prior
    geometry: OdometryGeometry
    beacons_xy: np.ndarray


@dataclass
class FilterRun:
    """One offline filter pass: estimated poses (K, 3), their covariances (K, 3, 3), the EKF."""

    est: np.ndarray
    P: np.ndarray
    ekf: LindgrenEKF


@contextlib.contextmanager
def _quiet_estimator():
    """Silence the EKF's first-skip warnings (the skips are counted and reported instead)."""
    log = logging.getLogger("estimators.lindgren_ekf")
    level = log.level
    log.setLevel(logging.ERROR)
    try:
        yield
    finally:
        log.setLevel(level)


def record(path: Path, seed: int, progress: bool = False) -> Recording:
    """Drive ``path`` once in FarmField-v0 (steered on scheme 1) and record every frame."""
    limit_s = path.duration_s + 20.0
    env = gym.make(ENV_ID, path=path, estimator_kwargs={"scheme": STEER_SCHEME},
                   max_episode_s=limit_s, max_episode_steps=int(limit_s * 20.0) + 1)
    with contextlib.closing(env), _quiet_estimator():  # steering EKF's skips: in its extras
        base = env.unwrapped
        policy = baseline_controller(env)
        obs, info = env.reset(seed=seed)
        policy.reset()
        frames, truth, s_true = [info["sensors"]], [info["true_pose"]], [0.0]
        bar = _bar(progress, base.max_steps, f"drive {path.name}")
        done = False
        while not done:
            action, _ = policy.predict(obs, deterministic=True)
            obs, _, terminated, truncated, info = env.step(action)
            done = terminated or truncated
            if "sensors" not in info:  # physics blow-up: nothing recorded this step
                raise RuntimeError(f"drive on {path.name} ended: {info['truncation_reason']}")
            frames.append(info["sensors"])
            truth.append(info["true_pose"])
            s_true.append(info["progress_true"] * path.length_m)
            if bar is not None:
                bar.update(1)
        if bar is not None:
            bar.close()
        spec = base.vehicle
        k_s0 = default_k_s_prior(spec)
        return Recording(
            path=path, frames=frames, t_s=np.array([f.t_s for f in frames]),
            truth=np.array(truth), s_true_m=np.array(s_true),
            oracle=base.true_soil(),
            params=LindgrenNoise(k_s0=k_s0, **FILTER),
            geometry=odometry_geometry(spec), beacons_xy=base.beacons_xy)


def run_filter(rec: Recording, name: str, cut_s: float = math.inf,
               inertial: bool = True) -> FilterRun:
    """Run one filter (``"scheme1"``..``"scheme4"``, ``"oracle"`` or a :data:`VARIANTS` name)
    over the recorded frames.

    Bearings after ``cut_s`` [s] are removed; ``inertial=False`` removes the gyro,
    accelerometer and inclinometer readings (laser and odometers only).
    """
    scheme, reset_to_default = VARIANTS.get(name, (name, ()))
    params = dataclasses.replace(
        rec.params, **{k: getattr(LindgrenNoise, k) for k in reset_to_default})
    oracle = rec.oracle if scheme == "oracle" else None
    ekf = LindgrenEKF(rec.geometry, scheme=4 if oracle else int(scheme[-1]), params=params,
                      beacons_xy=rec.beacons_xy, oracle=oracle)
    none = np.zeros(0)
    est, cov = [], []
    with _quiet_estimator():
        for k, frame in enumerate(rec.frames):
            if frame.t_s > cut_s:
                frame = dataclasses.replace(frame, beacon_bearings_rad=none, beacon_times_s=none)
            if not inertial:
                frame = dataclasses.replace(frame, gyro_z_rad_s=math.nan, acc_x_mps2=math.nan,
                                            acc_y_mps2=math.nan, roll_rad=math.nan,
                                            pitch_rad=math.nan)
            e = ekf.reset(*rec.truth[0], frame) if k == 0 else ekf.update(frame)
            est.append((e.x_m, e.y_m, e.yaw_rad))
            cov.append(e.cov)
    return FilterRun(np.array(est), np.array(cov), ekf)


def pose_errors(run: FilterRun, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position error [m], shape (K,), and (x, y, yaw) error truth - estimate, shape (K, 3)."""
    err = truth - run.est
    err[:, 2] = np.mod(err[:, 2] + np.pi, 2.0 * np.pi) - np.pi
    return np.hypot(err[:, 0], err[:, 1]), err


def circles_metrics(rec: Recording, runs: dict[str, FilterRun]) -> tuple[dict, dict]:
    """Tables 1-3 on the clockwise arc; returns (metrics, autocorrelation series for Fig. 6)."""
    cw_end = rec.path.segments[0].length_m
    w = (rec.s_true_m >= SETTLE_M) & (rec.s_true_m < cw_end)
    t0, t1 = rec.t_s[w][0], rec.t_s[w][-1]
    out: dict = {k: {} for k in ("mean_deviation_m", "true_error_mean_m", "true_rmse_m",
                                 "nees_pose", "nis", "autocorr_mean", "autocorr_var",
                                 "autocorr_share_inside", "n_samples", "bearings_gated")}
    rho = {}
    for name, run in runs.items():
        err, err3 = pose_errors(run, rec.truth)
        out["mean_deviation_m"][name] = float(np.mean(np.hypot(
            *(run.est[w, :2] - runs["scheme1"].est[w, :2]).T)))
        out["true_error_mean_m"][name] = float(np.mean(err[w]))
        out["true_rmse_m"][name] = float(np.sqrt(np.mean(err[w] ** 2)))
        out["nees_pose"][name] = float(np.mean(nees(err3[w], run.P[w])))
        out["bearings_gated"][name] = int(run.ekf.skipped.get("bearing_gated", 0))
        odo = [r for r in run.ekf.history["odo"] if t0 <= r[0] <= t1]
        if not odo:  # scheme 1 has no odometry
            continue
        rep = consistency_report(odo, name, lags=range(1, LAGS + 1))
        out["nis"][name] = rep.nis_mean
        out["autocorr_mean"][name] = rep.rho_mean
        out["autocorr_var"][name] = rep.rho_var
        out["autocorr_share_inside"][name] = rep.rho_share_inside
        out["n_samples"][name] = rep.n_samples
        rho[name] = (rep.lags, rep.rho, 1.96 / math.sqrt(rep.n_samples))
    del out["mean_deviation_m"]["scheme1"]
    k4 = out["n_samples"]["scheme4"]
    out["nis"]["band"] = list(chi2_mean_band(k4, 2, 0.05, "exact"))
    out["nis"]["band_wilson_hilferty"] = list(chi2_mean_band(k4, 2, 0.05, "wilson_hilferty"))
    # NEES samples are correlated in time: this band is what independent samples would give
    out["nees_pose"]["band_if_independent"] = list(chi2_mean_band(int(w.sum()), 3))
    out["soil_estimate_scheme4"] = _soil(runs["scheme4"])
    out["soil_true"] = {"R_w_m": list(rec.oracle.wheel_radius_m), "k_s": list(rec.oracle.k_s)}
    out["window_s"] = [float(t0), float(t1)]
    return out, rho


def dropout_experiment(path: Path, seeds: list[int], progress: bool = False) -> tuple:
    """Fig. 7 on one drive per seed: laser + odometry, bearings removed after ``CUT_S``.

    Returns (metrics, the first drive's Recording, its FilterRuns). One drive's final error is
    dominated by a random walk of the heading, so the metrics average the final errors of
    schemes 3, 4 and the oracle over the drives and list each one; the :data:`VARIANTS`, whose
    effects are large, run on the first drive only.
    """
    per_run: dict[str, list] = {k: [] for k in DROPOUT_FILTERS}
    heading: dict[str, list] = {k: [] for k in DROPOUT_FILTERS}
    first = None
    for seed in _iter(seeds, progress, "dropout drives"):
        rec = record(path, seed, progress)
        names = DROPOUT_FILTERS + (tuple(VARIANTS) if first is None else ())
        runs = {name: run_filter(rec, name, cut_s=CUT_S, inertial=False) for name in names}
        errors = {name: pose_errors(r, rec.truth) for name, r in runs.items()}
        first = first or (rec, runs, errors)
        for name in DROPOUT_FILTERS:
            per_run[name].append(float(errors[name][0][-1]))
            heading[name].append(float(np.degrees(abs(errors[name][1][-1, 2]))))
    rec, runs, errors = first
    metrics = {"final_error_m": {k: float(np.mean(v)) for k, v in per_run.items()},
               "final_error_m_per_drive": per_run,
               "final_heading_error_deg": {k: float(np.mean(v)) for k, v in heading.items()},
               "first_drive_final_error_m": {k: float(e[0][-1]) for k, e in errors.items()},
               "first_drive_soil_estimate": {k: _soil(runs[k]) for k in runs if "4" in k},
               "soil_true": {"R_w_m": list(rec.oracle.wheel_radius_m), "k_s": list(rec.oracle.k_s)},
               "seeds": list(seeds), "duration_s": float(rec.t_s[-1]), "cut_s": CUT_S}
    return metrics, rec, runs


def run(quick: bool = False, out_dir: str = "runs/reproduce_lindgren",
        json_path: str | None = None, seed: int = 0, progress: bool = True) -> dict:
    """Both experiments; prints paper vs simulation, saves plots and (optionally) the JSON."""
    from slipenv.experiments import lindgren_plots as plots
    from slipenv.experiments import lindgren_report as report

    start = time.perf_counter()
    cfg = QUICK if quick else FULL
    circles = path_by_name("lindgren_circles", radius_m=4.0, speed_mps=SPEED_MPS,
                           loops=cfg.circle_loops)
    straights = path_by_name("lindgren_straights", n_legs=cfg.straight_legs,
                             speed_mps=SPEED_MPS)
    rec_a = record(circles, seed, progress)
    runs_a = {s: run_filter(rec_a, s) for s in _iter(SCHEMES, progress, "filters (a)")}
    circ, rho = circles_metrics(rec_a, runs_a)
    seeds = [seed + i for i in range(cfg.dropout_drives)]
    drop, rec_b, runs_b = dropout_experiment(straights, seeds, progress)
    final = drop["final_error_m"]
    metrics = {
        **{k: circ[k] for k in ("mean_deviation_m", "nis", "autocorr_mean", "autocorr_var",
                                "autocorr_share_inside", "n_samples")},
        "dropout_final_error_m": {"no_slip_model": final["scheme3"],
                                  "slip_model": final["scheme4"], "oracle": final["oracle"]},
        "circles": circ, "dropout": drop,
    }
    out = FsPath(out_dir)
    saved = [plots.plot_paths(rec_a, runs_a, circ, out / "paths.png"),
             plots.plot_dropout(rec_b, runs_b, out / "dropout.png", CUT_S),
             plots.plot_autocorrelation(rho, out / "autocorrelation.png")]
    result = {"metrics": metrics, "paper": PAPER, "targets": report.targets(metrics),
              "config": {"quick": quick, "seed": seed, "steered_by": f"scheme {STEER_SCHEME}",
                         **dataclasses.asdict(cfg), "speed_mps": SPEED_MPS,
                         "settle_m": SETTLE_M, "lags": LAGS, "cut_s": CUT_S,
                         "filter": FILTER},
              "run_time_s": time.perf_counter() - start}
    print(report.format_table(metrics, PAPER, result["targets"], result["run_time_s"]))
    print("plots: " + ", ".join(str(p) for p in saved))
    if json_path:
        print(f"written: {report.write_json(result, json_path)}")
    return result


def _soil(run: FilterRun) -> dict:
    x = run.ekf.estimate().extras
    return {"R_w_m": [x["R_wl_m"], x["R_wr_m"]], "k_s": [x["k_sl"], x["k_sr"]]}


def _bar(progress: bool, total: int, desc: str):
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="step", leave=False)


def _iter(items, progress: bool, desc: str):
    if not progress:
        return items
    from tqdm import tqdm

    return tqdm(items, desc=desc, leave=False)
