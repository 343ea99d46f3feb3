"""Lindgren et al. §5 re-run in simulation (``slipenv reproduce lindgren``, issue #3).

Like the paper, each experiment drives the vehicle once, records the raw sensor data and runs
the EKF schemes OFFLINE over the same frames (Lindgren §5: "the raw sensor data ... run through
four different EKF schemes"), exactly as :class:`estimators.lindgren_ekf.LindgrenEKF` exposes
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
    inclinometer readings are removed from the recorded frames, which the EKF skips), bearings
    removed after ``CUT_S`` = 50 s; final position error of scheme 3 (no slip model), scheme 4
    (slip model) and the oracle.

``--quick`` runs the same experiments on shorter paths (1 loop each way; 3 straights).

Filter tuning. Every scheme uses the paper's measurement variances (``LindgrenNoise``
defaults) with the k_s prior of :func:`slipenv.envs.estimation.default_k_s_prior`, except the
random walk of the soil states, ``FIELD_NOISE``: the FarmField world is one uniform soil, so
R_w may wander by about 1 mm and k_s by about 3 % per 100 m (the estimator defaults allow
1 cm and 10 %, right for a field whose soil changes). This matters only once the laser is cut:
with odometry alone, the speed and the soil states are unobservable along a common scale
(z ∝ v k_s / (R_w (k_s - T))), and the filter's estimate walks along that direction at the
rate its process noise allows — upward, in this EKF, on the filter's own synthetic data too.
With the estimator defaults R_w drifts from 0.281 to 0.315 m in the 78 s after the cut and
the heading by 20°; the JSON reports that run as ``dropout_default_soil_noise``.

What remains different from the paper (none of it tuned away):

* The simulated slip is large: about 11 % at 90 N m per wheel at 0.5 m/s (k_s ≈ 760 N m
  against the prior 674 N m), so a nominal-radius filter is off by 10 % in scale and 1.4 % in
  the left/right difference. Scheme 3 therefore deviates more than in the paper (Table 1) and,
  after the laser cut, drifts much further than the paper's 1.97 m: the paper's no-slip model
  used "a carefully measured effective wheel radius"; here it uses the concrete-calibrated
  nominal one, as issue #3 asks.
* Scheme 4's NIS lies *below* the band, the paper's above it: the simulated encoders err only
  by quantisation (variance 1/6 count² for a count difference) while the filter keeps the
  paper's 3.1e-6 rad² = 0.25 count². The paper's excess NIS came from real-world effects
  (EKF linearisation, unmodelled noise) that the simulation does not have.
* Under constant torque (circles at constant speed) R_w and k_s are not separately
  observable, only R_w (1 - T / k_s); the JSON lists the final estimates beside the truth.
* Scheme 3's χ² bearing gate (not in the paper) rejects about a fifth of its bearings on the
  circles, because its odometry is trusted with the encoder variance while its radius is 3 %
  wrong; without the gate its mean deviation drops by about 10 %. Gated counts are reported.
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import math
import time
from dataclasses import dataclass
from pathlib import Path as FsPath

import gymnasium as gym
import numpy as np

from estimators.base import wrap_angle
from estimators.consistency import chi2_mean_band, consistency_report, nees
from estimators.lindgren_ekf import LindgrenEKF, LindgrenNoise, OracleSoil
from slipenv.envs.estimation import default_k_s_prior, odometry_geometry, true_soil_for_oracle
from slipenv.paths import Path, path_by_name
from slipenv.run import baseline_controller
from slipenv.sensors.frame import SensorFrame

ENV_ID = "slipenv/FarmField-v0"
STEER_SCHEME = 1  # the env's EKF scheme the path follower steers by (laser + inertial)
SPEED_MPS = 0.5  # [m/s] path speed (assumed: Lindgren gives none), as the FarmField preset
SETTLE_M = 5.0  # [m] start of the clockwise arc left out while the slip states converge
LAGS = 100  # autocorrelation lags 1..LAGS (Fig. 6)
CUT_S = 50.0  # [s] laser cut (Lindgren §5, Fig. 7)
FIELD_NOISE = {"radius_var_per_m": 1e-8,  # [m²/m]: R_w within ~1 mm per 100 m (one soil)
               "k_s_rel_var_per_m": 1e-5}  # [1/m]: k_s within ~3 % per 100 m (load shifts)
SCHEMES = ("scheme1", "scheme2", "scheme3", "scheme4", "oracle")

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
    """Path lengths of one run: full (the paper's) or ``--quick``."""

    circle_loops: float
    straight_legs: int


FULL, QUICK = Config(circle_loops=1.5, straight_legs=4), Config(circle_loops=1.0, straight_legs=3)


@dataclass
class Recording:
    """One drive: every SensorFrame, the truth, and what the filters may be told."""

    path: Path
    frames: list[SensorFrame]
    t_s: np.ndarray  # (K,) [s]
    truth: np.ndarray  # (K, 3) true (x, y, yaw) of the reference point [m, m, rad]
    s_true_m: np.ndarray  # (K,) true progress along the path [m]
    oracle: OracleSoil  # true R_w and k_s (privileged, for the oracle filter only)
    params: LindgrenNoise  # the filters' noise set (FIELD_NOISE, k_s prior)
    default_params: LindgrenNoise  # the estimator defaults (k_s prior only)
    geometry: object
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
        spec = base.spec_vehicle
        k_s0 = default_k_s_prior(spec)
        return Recording(
            path=path, frames=frames, t_s=np.array([f.t_s for f in frames]),
            truth=np.array(truth), s_true_m=np.array(s_true),
            oracle=true_soil_for_oracle(base.sim, base.config.sensor_noise.torque_scale),
            params=LindgrenNoise(k_s0=k_s0, **FIELD_NOISE), default_params=LindgrenNoise(k_s0=k_s0),
            geometry=odometry_geometry(spec), beacons_xy=base.sensors.beacons.beacons_xy)


def run_filter(rec: Recording, scheme: str, cut_s: float = math.inf, inertial: bool = True,
               params: LindgrenNoise | None = None) -> FilterRun:
    """Run one scheme (``"scheme1"``..``"scheme4"``, ``"oracle"``) over the recorded frames.

    Bearings after ``cut_s`` [s] are removed; ``inertial=False`` removes the gyro,
    accelerometer and inclinometer readings (laser and odometers only).
    """
    oracle = rec.oracle if scheme == "oracle" else None
    number = 4 if scheme == "oracle" else int(scheme[-1])
    ekf = LindgrenEKF(rec.geometry, scheme=number, params=params or rec.params,
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
    err[:, 2] = [wrap_angle(a) for a in err[:, 2]]
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
    out["nees_pose"]["band"] = list(chi2_mean_band(int(w.sum()), 3))
    x = runs["scheme4"].ekf.estimate().extras
    out["soil_estimate_scheme4"] = {"R_w_m": [x["R_wl_m"], x["R_wr_m"]],
                                    "k_s": [x["k_sl"], x["k_sr"]]}
    out["soil_true"] = {"R_w_m": list(rec.oracle.wheel_radius_m), "k_s": list(rec.oracle.k_s)}
    out["window_s"] = [float(t0), float(t1)]
    return out, rho


def dropout_metrics(rec: Recording, runs: dict[str, FilterRun]) -> dict:
    """Final position and heading errors after the laser cut (Fig. 7)."""
    final, heading = {}, {}
    for name, run in runs.items():
        err, err3 = pose_errors(run, rec.truth)
        final[name], heading[name] = float(err[-1]), float(np.degrees(abs(err3[-1, 2])))
    return {"final_error_m": final, "final_heading_error_deg": heading,
            "duration_s": float(rec.t_s[-1]), "cut_s": CUT_S}


def run(quick: bool = False, out_dir: str = "runs/reproduce_lindgren",
        json_path: str | None = None, seed: int = 0, progress: bool = True) -> dict:
    """Both experiments; prints paper vs simulation, saves plots and (optionally) the JSON."""
    from slipenv.experiments import lindgren_plots as plots

    start = time.perf_counter()
    cfg = QUICK if quick else FULL
    circles = path_by_name("lindgren_circles", radius_m=4.0, speed_mps=SPEED_MPS,
                           loops=cfg.circle_loops)
    straights = path_by_name("lindgren_straights", n_legs=cfg.straight_legs,
                             speed_mps=SPEED_MPS)
    rec_a = record(circles, seed, progress)
    runs_a = {s: run_filter(rec_a, s) for s in _iter(SCHEMES, progress, "filters (a)")}
    circ, rho = circles_metrics(rec_a, runs_a)
    rec_b = record(straights, seed, progress)
    drop_kw = dict(cut_s=CUT_S, inertial=False)
    runs_b = {s: run_filter(rec_b, s, **drop_kw)
              for s in _iter(("scheme3", "scheme4", "oracle"), progress, "filters (b)")}
    default_b = run_filter(rec_b, "scheme4", params=rec_b.default_params, **drop_kw)
    drop = dropout_metrics(rec_b, runs_b)
    drop_default = dropout_metrics(rec_b, {"slip_model": default_b})
    final = drop["final_error_m"]
    metrics = {
        **{k: circ[k] for k in ("mean_deviation_m", "nis", "autocorr_mean", "autocorr_var",
                                "autocorr_share_inside", "n_samples")},
        "dropout_final_error_m": {"no_slip_model": final["scheme3"],
                                  "slip_model": final["scheme4"], "oracle": final["oracle"]},
        "circles": circ, "dropout": drop,
        "dropout_default_soil_noise": {"final_error_m": drop_default["final_error_m"]["slip_model"],
                                       **{k: v for k, v in default_b.ekf.estimate().extras.items()
                                          if k.startswith(("R_w", "k_s"))}},
    }
    out = FsPath(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    saved = [plots.plot_paths(rec_a, runs_a, circ, out / "paths.png"),
             plots.plot_dropout(rec_b, runs_b, out / "dropout.png", CUT_S),
             plots.plot_autocorrelation(rho, out / "autocorrelation.png")]
    result = {"metrics": metrics, "paper": PAPER, "targets": targets(metrics),
              "config": {"quick": quick, "seed": seed, "steered_by": f"scheme {STEER_SCHEME}",
                         **dataclasses.asdict(cfg), "speed_mps": SPEED_MPS,
                         "settle_m": SETTLE_M, "lags": LAGS, "cut_s": CUT_S,
                         "filter_soil_noise": FIELD_NOISE},
              "run_time_s": time.perf_counter() - start}
    print(format_table(metrics, result["targets"], result["run_time_s"]))
    print("plots: " + ", ".join(str(p) for p in saved))
    if json_path:
        FsPath(json_path).parent.mkdir(parents=True, exist_ok=True)
        with open(json_path, "w") as fh:
            json.dump(_finite(result), fh, indent=2)
        print(f"written: {json_path}")
    return result


def nis_distance(value: float, band: list[float]) -> float:
    """How far a time-averaged NIS lies outside its band (0 inside)."""
    return max(band[0] - value, value - band[1], 0.0)


def targets(m: dict) -> dict[str, dict]:
    """Issue #3's targets, each with its value, limit and whether the run met it."""
    dev, nis_, drop = m["mean_deviation_m"], m["nis"], m["dropout_final_error_m"]
    rows = {
        "slip_model <= 0.3 no_slip_model": (drop["slip_model"], 0.3 * drop["no_slip_model"]),
        "scheme4 deviation <= 0.7 scheme3": (dev["scheme4"], 0.7 * dev["scheme3"]),
        "scheme4 NIS closer to band than scheme3": (nis_distance(nis_["scheme4"], nis_["band"]),
                                                    nis_distance(nis_["scheme3"], nis_["band"])),
        "slip_model <= 1.5 oracle": (drop["slip_model"], 1.5 * drop["oracle"]),
    }
    return {k: {"value": v, "limit": lim, "met": bool(v <= lim if "<=" in k else v < lim)}
            for k, (v, lim) in rows.items()}


def format_table(m: dict, tg: dict, run_time_s: float) -> str:
    """Quantity | paper | simulation, then the targets."""
    p, c = PAPER, m["circles"]
    rows = [("(a) 4 m circles, clockwise arc", "", "")]
    for s in ("scheme3", "scheme4"):
        rows.append((f"mean deviation from scheme 1 [m], {s}",
                     p["mean_deviation_m"][s], m["mean_deviation_m"][s]))
    for s in ("scheme3", "scheme4", "oracle"):
        rows.append((f"  true mean error / NEES [m, -], {s}", None,
                     f"{c['true_error_mean_m'][s]:.3f} / {c['nees_pose'][s]:.2f}"))
    for key, label in (("nis", "NIS (Eq. 43)"), ("autocorr_mean", "autocorrelation mean"),
                       ("autocorr_var", "autocorrelation variance"),
                       ("autocorr_share_inside", "share inside ±1.96/√K")):
        for s in ("scheme3", "scheme4"):
            rows.append((f"{label}, {s}", p[key][s], m[key][s]))
    band, wh = m["nis"]["band"], m["nis"]["band_wilson_hilferty"]
    rows.append(("NIS 95 % band, exact (Eq. 44)", "1.883-2.120",
                 f"{band[0]:.3f}-{band[1]:.3f} ({wh[0]:.3f}-{wh[1]:.3f})"))
    rows.append(("K (odometric innovations)", p["n_samples"], m["n_samples"]["scheme4"]))
    rows.append((f"(b) laser cut at {CUT_S:.0f} s, laser + odometry", "", ""))
    for key in ("no_slip_model", "slip_model", "oracle"):
        rows.append((f"final position error [m], {key}", p["dropout_final_error_m"][key],
                     m["dropout_final_error_m"][key]))
    rows.append(("  slip_model with the estimator's default soil noise", None,
                 m["dropout_default_soil_noise"]["final_error_m"]))

    def cell(v) -> str:
        return "-" if v is None else (f"{v:.4g}" if isinstance(v, float) else str(v))

    width = max(len(r[0]) for r in rows)
    lines = [f"{'quantity':<{width}}  {'paper':>12}  {'simulation':>16}", "-" * (width + 32)]
    lines += [f"{q:<{width}}  {cell(a):>12}  {cell(b):>16}" if a != "" else q for q, a, b in rows]
    lines.append("targets:")
    lines += [f"  [{'met' if t['met'] else 'MISSED'}] {k}: {t['value']:.4g} vs {t['limit']:.4g}"
              for k, t in tg.items()]
    lines.append(f"run time {run_time_s:.1f} s")
    return "\n".join(lines)


def _finite(obj):
    """Replace NaN/inf by None so the JSON is standard."""
    if isinstance(obj, dict):
        return {k: _finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [_finite(v) for v in obj]
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    return obj


def _bar(progress: bool, total: int, desc: str):
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="step", leave=False)


def _iter(items, progress: bool, desc: str):
    if not progress:
        return items
    from tqdm import tqdm

    return tqdm(items, desc=desc, unit="filter", leave=False)
