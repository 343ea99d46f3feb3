"""The statistics of the two experiments: Tables 1-3 on the circles, Fig. 7 on the straights.

(a) Circles (Lindgren Fig. 3-6): over the clockwise arc at constant speed, after the first
``SETTLE_M`` metres, the mean position error against the truth (``mean_deviation_m``: the
project judges on the truth), the paper's Table 1 measure beside it, the mean deviation from
scheme 1 (``deviation_from_scheme1_m``: the paper had no ground truth and took scheme 1, laser
and inertial, as its reference), and the RMSE and pose NEES against the truth; the
time-averaged NIS of the odometric innovations (Eq. 43) with its 95 % band, exact and by
Eq. 44 (Table 3); the autocorrelation ρ̄(l) of Eq. 42 for l = 1..``LAGS``, its mean, variance
and share inside ±1.96/√K (Table 2, Fig. 6).

(b) Straights (Fig. 7): laser and odometers only, bearings removed after ``CUT_S``; the final
position error of scheme 3 (no slip model), scheme 4 (slip model) and the oracle, averaged
over several drives because one drive's final error is dominated by a random walk of the
heading.
"""

from __future__ import annotations

import math

import numpy as np

from slipenv.estimators.consistency import chi2_mean_band, consistency_report, nees
from slipenv.paths import Path

from ..progress import iterate
from .filters import FilterRun, pose_errors, run_filter, soil_estimate
from .recording import Recording, record
from .settings import CUT_S, DROPOUT_FILTERS, HEADLINE, LAGS, SETTLE_M, SLIP_SCHEMES, Setting


def circles_metrics(rec: Recording, runs: dict[str, FilterRun]) -> tuple[dict, dict]:
    """Tables 1-3 on the clockwise arc; returns (metrics, autocorrelation series for Fig. 6).

    ``mean_deviation_m`` is each scheme's mean position error against the true path (scheme 1
    too), ``deviation_from_scheme1_m`` its mean distance from scheme 1's estimate (Table 1's
    measure; scheme 1 itself left out).
    """
    cw_end = rec.path.segments[0].length_m
    w = (rec.s_true_m >= SETTLE_M) & (rec.s_true_m < cw_end)
    t0, t1 = rec.t_s[w][0], rec.t_s[w][-1]
    out: dict = {k: {} for k in ("mean_deviation_m", "deviation_from_scheme1_m", "true_rmse_m",
                                 "nees_pose", "nis", "autocorr_mean", "autocorr_var",
                                 "autocorr_share_inside", "n_samples", "bearings_gated",
                                 "odometry_rejected")}
    rho = {}
    for name, run in runs.items():
        err, err3 = pose_errors(run, rec.truth)
        out["deviation_from_scheme1_m"][name] = float(np.mean(np.hypot(
            *(run.est[w, :2] - runs["scheme1"].est[w, :2]).T)))
        out["mean_deviation_m"][name] = float(np.mean(err[w]))
        out["true_rmse_m"][name] = float(np.sqrt(np.mean(err[w] ** 2)))
        out["nees_pose"][name] = float(np.mean(nees(err3[w], run.P[w])))
        out["bearings_gated"][name] = int(run.ekf.skipped.get("bearing_gated", 0))
        if not run.ekf.uses_odometry:  # scheme 1
            continue
        odo = [r for r in run.ekf.history["odo"] if t0 <= r[0] <= t1]
        if not odo:  # every odometry update in the window rejected: no statistics
            for key in ("nis", "autocorr_mean", "autocorr_var", "autocorr_share_inside"):
                out[key][name] = None
            out["n_samples"][name] = 0
            out["odometry_rejected"][name] = dict(run.ekf.skipped)
            continue
        rep = consistency_report(odo, name, lags=range(1, LAGS + 1))
        out["nis"][name] = rep.nis_mean
        out["autocorr_mean"][name] = rep.rho_mean
        out["autocorr_var"][name] = rep.rho_var
        out["autocorr_share_inside"][name] = rep.rho_share_inside
        out["n_samples"][name] = rep.n_samples
        rho[name] = (rep.lags, rep.rho, 1.96 / math.sqrt(rep.n_samples))
    del out["deviation_from_scheme1_m"]["scheme1"]
    k4 = out["n_samples"]["scheme4"]
    out["nis"]["band"] = list(chi2_mean_band(k4, 2, 0.05, "exact")) if k4 else [None, None]
    out["nis"]["band_wilson_hilferty"] = (list(chi2_mean_band(k4, 2, 0.05, "wilson_hilferty"))
                                          if k4 else [None, None])
    # NEES samples are correlated in time: this band is what independent samples would give
    out["nees_pose"]["band_if_independent"] = list(chi2_mean_band(int(w.sum()), 3))
    out["soil_estimate_scheme4"] = soil_estimate(runs["scheme4"])
    out["soil_estimate"] = {s: soil_estimate(runs[s]) for s in SLIP_SCHEMES if s in runs}
    out["soil_true"] = {"R_w_m": list(rec.oracle.wheel_radius_m), "k_s": list(rec.oracle.k_s)}
    out["window_s"] = [float(t0), float(t1)]
    return out, rho


TURNING_RPS = 0.05  # [rad/s] yaw rate above which a frame counts as turning


def torque_slip(rec: Recording) -> dict:
    """Median measured torque and true slip of the driven wheels: straight, and in the turns
    the inner and the outer wheel.

    Driving slip s = 1 - v_w / (ω R_w) (Wong's definition; Lindgren Eq. 25) from the truth:
    v_w the wheel's forward speed (reference point's forward speed minus yaw rate times the
    wheel's lateral offset), ω the encoder rate, R_w the true rolling radius. Frames below
    0.1 m/s wheel speed are left out; a frame turns when |yaw rate| >= ``TURNING_RPS``. On
    Lindgren's linear law the secant T/s is the same k_s for every wheel and motion; on a
    curved law it falls as the torque rises, so the outer wheel of a turn slips more than a
    line fitted on the straights says.

    Returns
    -------
    dict
        ``{"straight" | "turn_inner" | "turn_outer": {"torque_nm", "slip",
        "k_s_secant_nm"}}``, both sides pooled (NaN where under 10 frames).
    """
    g, t = rec.geometry, rec.t_s
    x, y, yaw = rec.truth.T
    yaw_rate = np.gradient(np.unwrap(yaw), t)
    v = np.gradient(x, t) * np.cos(yaw) + np.gradient(y, t) * np.sin(yaw)
    counts = np.array([f.enc_counts for f in rec.frames], dtype=float)
    torque = np.array([f.wheel_torque_nm for f in rec.frames], dtype=float)
    sides = (list(g.left), list(g.right))
    lateral = ([float(np.mean(g.wheel_xy_m[ix, 1])) for ix in sides]
               if g.wheel_xy_m is not None else [0.5 * g.track_width_m, -0.5 * g.track_width_m])
    pooled: dict[str, tuple[list, list]] = {m: ([], []) for m in ("straight", "turn_inner",
                                                                  "turn_outer")}
    for ix, offset, radius in zip(sides, lateral, rec.oracle.wheel_radius_m, strict=True):
        spin = np.gradient(counts[:, ix].mean(axis=1), t) / g.counts_per_rad
        v_w = v - yaw_rate * offset
        ok = (v_w > 0.1) & (spin > 0.0)
        slip = 1.0 - v_w / np.where(ok, spin * radius, 1.0)
        tq = torque[:, ix].mean(axis=1)
        turning = np.abs(yaw_rate) >= TURNING_RPS
        outer = yaw_rate * offset < 0.0  # turning left (ω > 0), the right wheel (y < 0) is outer
        for motion, sel in (("straight", ok & ~turning), ("turn_inner", ok & turning & ~outer),
                            ("turn_outer", ok & turning & outer)):
            pooled[motion][0].extend(tq[sel])
            pooled[motion][1].extend(slip[sel])
    out = {}
    for motion, (tq_, slip_) in pooled.items():
        many = len(tq_) >= 10
        T = float(np.median(tq_)) if many else math.nan
        s_ = float(np.median(slip_)) if many else math.nan
        out[motion] = {"torque_nm": T, "slip": s_,
                       "k_s_secant_nm": T / s_ if many and s_ > 0.0 else math.nan}
    return out


def dropout_experiment(path: Path, seeds: list[int], progress: bool = False,
                       setting: Setting = HEADLINE, calibration: dict | None = None) -> tuple:
    """Fig. 7 on one drive per seed: laser + odometry, bearings removed after ``CUT_S``.

    Returns (metrics, the first drive's Recording, its FilterRuns). The metrics average the
    final errors of schemes 3, the slip-model schemes, the oracle and the block's variants
    (``setting.variants``) over the drives and list each one; ``error_at_cut_m`` is the mean
    position error when the bearings stopped; ``nees_after_cut`` the pose NEES (x, y, yaw
    against the truth) averaged over the frames after the cut and then over the drives, with
    the 95 % band a mean of that many independent χ²(3) samples would have (the samples of one
    drive are correlated in time, so the band is a floor on the width, and a mean far above
    it is an overconfident filter); ``max_tilt_deg`` the largest |pitch| or |roll| state of
    the drive [°] (no inclinometer on these drives: only the process model bounds them),
    averaged over the drives. ``setting`` and ``calibration`` go to
    :func:`~.recording.record`.
    """
    if not seeds:
        raise ValueError("dropout_experiment needs at least one seed")
    names = DROPOUT_FILTERS + tuple(setting.variants)

    def cut_factor(name: str) -> float:
        return setting.variants[name].cut_factor if name in setting.variants else 1.0

    per_run: dict[str, list] = {k: [] for k in names}
    heading: dict[str, list] = {k: [] for k in names}
    at_cut: dict[str, list] = {k: [] for k in names}
    nees_after: dict[str, list] = {k: [] for k in names}
    tilt: dict[str, list] = {k: [] for k in names}
    n_after = 0
    first: tuple[Recording, dict[str, FilterRun],
                 dict[str, tuple[np.ndarray, np.ndarray]]] | None = None
    for seed in iterate(seeds, progress, f"dropout drives, {setting.name}"):
        rec = record(path, seed, progress, setting, calibration)
        runs = {name: run_filter(rec, name, cut_s=CUT_S * cut_factor(name), inertial=False,
                                 variants=setting.variants) for name in names}
        errors = {name: pose_errors(r, rec.truth) for name, r in runs.items()}
        first = first or (rec, runs, errors)
        for name in names:
            per_run[name].append(float(errors[name][0][-1]))
            # where the error stood when the bearings stopped: before or after the cut?
            k_cut = min(int(np.searchsorted(rec.t_s, CUT_S * cut_factor(name))),
                        len(rec.t_s) - 1)
            at_cut[name].append(float(errors[name][0][k_cut]))
            after = rec.t_s > CUT_S * cut_factor(name)
            nees_after[name].append(float(np.mean(nees(errors[name][1][after],
                                                       runs[name].P[after])))
                                    if after.any() else math.nan)
            heading[name].append(float(np.degrees(abs(errors[name][1][-1, 2]))))
            tilt[name].append(float(np.degrees(np.max(np.abs(runs[name].tilt)))))
        n_after += int(np.count_nonzero(rec.t_s > CUT_S))
    assert first is not None  # seeds is not empty
    rec, runs, errors = first
    metrics = {"final_error_m": {k: float(np.mean(v)) for k, v in per_run.items()},
               "final_error_m_per_drive": per_run,
               "final_heading_error_deg": {k: float(np.mean(v)) for k, v in heading.items()},
               "error_at_cut_m": {k: float(np.mean(v)) for k, v in at_cut.items()},
               "nees_after_cut": {k: float(np.mean(v)) for k, v in nees_after.items()},
               "nees_after_cut_per_drive": nees_after,
               "max_tilt_deg": {k: float(np.mean(v)) for k, v in tilt.items()},
               "nees_after_cut_band_if_independent": list(chi2_mean_band(max(n_after, 1), 3)),
               "first_drive_final_error_m": {k: float(e[0][-1]) for k, e in errors.items()},
               "first_drive_soil_estimate": {k: soil_estimate(runs[k]) for k in runs
                                             if k.startswith((*SLIP_SCHEMES, "oracle"))},
               "first_drive_torque_slip": torque_slip(rec),
               "soil_true": {"R_w_m": list(rec.oracle.wheel_radius_m),
                             "k_s": list(rec.oracle.k_s)},
               "seeds": list(seeds), "duration_s": float(rec.t_s[-1]), "cut_s": CUT_S}
    return metrics, rec, runs
