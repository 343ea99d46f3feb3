"""From recorded drives to Reina's Tables 4-5: slip angle and slip ratio errors, the s_x(β)
fit, the three odometries replayed on the same sensor frames, FTrace's counters.

Ground truth (Reina Eq. 13-14): the slip angle β_g = atan2(ẏ, ẋ) - ψ and the slip ratio
s_x = 1 - V_x/(r ω̄), both from the true motion averaged over ``truth_window_s`` (the laser
tracker's ground truth of the paper is smoothed as well; the instantaneous body velocity of the
simulated rover bounces on the heightfield at several Hz). ω̄ is the encoders' mean wheel
rotation over the same window. The climb angle the slip model's pitch term takes is the
inclinometer's (not the truth), averaged over the same window.
"""

from __future__ import annotations

import math

import numpy as np

from slipenv.estimators.dead_reckoning import DeadReckoning
from slipenv.estimators.reina import (
    CompassOdometry,
    FTraceScore,
    SCompOdometry,
    SlipRatioFit,
    SlipRatioModel,
    final_position_error,
    fit_slip_ratio_model,
)

from .drive import Drive


def windowed_truth(d: Drive, geometry, window_s: float, min_speed_mps: float = 0.02
                   ) -> dict:
    """True slip angle and slip ratio over trailing windows of ``window_s``, per step.

    Returns arrays per step (NaN until a full window has passed or where the rover is slower
    than ``min_speed_mps``): ``beta`` [rad], ``s_x`` [-], and ``climb`` [rad], the
    inclinometer's climb angle (nose up positive) averaged over the window.
    """
    a = d.arrays()
    n = len(a["t_s"])
    w = max(int(round(window_s / d.dt_s)), 1)
    wheels = list(geometry.left) + list(geometry.right)
    wheel_angle = np.array([np.mean(np.asarray(f.enc_counts, float)[wheels]) for f in d.frames]
                           ) / geometry.counts_per_rad
    # SensorFrame.pitch_rad > 0 lowers the nose: the climb angle is its negative.
    climb_now = -np.array([float(f.pitch_rad) for f in d.frames])
    beta, s_x, climb = np.full(n, np.nan), np.full(n, np.nan), np.full(n, np.nan)
    xy, yaw = a["true_xy"], a["true_yaw"]
    for k in range(w, n):
        dxy = xy[k] - xy[k - w]
        dist = float(np.hypot(*dxy))
        if dist / (w * d.dt_s) < min_speed_mps:
            continue
        psi = math.atan2(math.sin(yaw[k]) + math.sin(yaw[k - w]),
                         math.cos(yaw[k]) + math.cos(yaw[k - w]))
        course = math.atan2(dxy[1], dxy[0])
        b = math.atan2(math.sin(course - psi), math.cos(course - psi))
        beta[k] = b
        climb[k] = float(np.mean(climb_now[k - w:k + 1]))
        roll = geometry.wheel_radius_m * (wheel_angle[k] - wheel_angle[k - w])
        if roll > 1e-6:
            s_x[k] = 1.0 - dist * math.cos(b) / roll
    return {"beta": beta, "s_x": s_x, "climb": climb}


def fit_slip_model(drives: list[Drive], truths: list[dict], pitch: bool = True
                   ) -> SlipRatioFit:
    """Eq. 12 fitted to the ground truth of the given drives (Reina §4.3.1: test 1).

    With ``pitch`` the model gets the pitch term (Reina §3.3: s_x0 grows with the slope, to be
    followed "by measuring the current pitch angle"), fitted on the inclinometer's climb angle.
    """
    b = np.concatenate([t["beta"] for t in truths])
    s = np.concatenate([t["s_x"] for t in truths])
    c = np.concatenate([t["climb"] for t in truths])
    ok = np.isfinite(b) & np.isfinite(s) & (np.isfinite(c) | (not pitch))
    return fit_slip_ratio_model(b[ok], s[ok], pitch_rad=c[ok] if pitch else None)


def replay(d: Drive, geometry, model: SlipRatioModel) -> dict:
    """Plain, compass-enhanced and sComp odometry on the drive's sensor frames, (n, 2) each.

    sComp takes the slip angle the env's sComp used at each step (FTrace's, held between
    camera frames), with ``model`` as s_x(β).
    """
    x0, y0, yaw0 = d.start
    plain, compass = DeadReckoning(geometry), CompassOdometry(geometry)
    scomp = SCompOdometry(geometry, model)
    out: dict[str, list] = {"plain": [], "compass": [], "scomp": [], "scomp_slip_ratio": []}
    for est, name in ((plain, "plain"), (compass, "compass"), (scomp, "scomp")):
        e = est.reset(x0, y0, yaw0, d.frames[0])
        out[name].append((e.x_m, e.y_m))
    out["scomp_slip_ratio"].append(scomp.slip_ratio)
    for frame, beta in zip(d.frames[1:], d.beta_used[1:], strict=True):
        scomp.set_slip_angle(beta)
        for est, name in ((plain, "plain"), (compass, "compass"), (scomp, "scomp")):
            e = est.update(frame)
            out[name].append((e.x_m, e.y_m))
        out["scomp_slip_ratio"].append(scomp.slip_ratio)
    return {k: np.asarray(v) for k, v in out.items()}


def score_ftrace(drives: list[Drive], threshold_deg: float) -> FTraceScore:
    """Table 4's counters over every camera frame of the drives."""
    score = FTraceScore(math.radians(threshold_deg))
    for d in drives:
        for det, present, angle in zip(d.detections, d.frame_present, d.frame_angle,
                                       strict=True):
            score.add(det, bool(present), float(angle))
    return score


def rms(x: np.ndarray) -> float:
    """Root mean square of the finite entries (NaN if none)."""
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x * x))) if x.size else math.nan


def drive_metrics(d: Drive, truth: dict, odo: dict) -> dict:
    """One drive's slip-angle and slip-ratio errors (at camera frames) and final errors."""
    steps = np.asarray(d.frame_step, int)
    found = np.array([det.found for det in d.detections], bool)
    beta_est = np.asarray(d.beta_used)[steps]
    beta_err = np.where(found, beta_est - truth["beta"][steps], np.nan)
    s_err = odo["scomp_slip_ratio"][steps] - truth["s_x"][steps]
    true_xy = d.arrays()["true_xy"]
    return {
        "beta_err": beta_err, "s_err": s_err,
        "final_error_m": {k: final_position_error(odo[k], true_xy)
                          for k in ("plain", "compass", "scomp")},
        "distance_m": float(np.sum(np.hypot(*np.diff(true_xy, axis=0).T))),
        "mean_true_beta_deg": math.degrees(float(np.nanmean(truth["beta"]))),
    }
