"""Odometry calibration from a geometric diagnosis: the values a robot's config takes.

When the diagnosis names ``rolling_radius`` and/or ``track_width``, the fitted geometry is
also given as a differential-drive controller takes it (ROS ``diff_drive_controller``:
``wheel_radius``, ``wheel_separation``, ``left/right_wheel_radius_multiplier``), with standard
errors from the fit's covariance (delta method).

What one log can separate. The heading rate of the replay is (r_R Δφ_R - r_L Δφ_L)/W: on a
log whose turns all have the same wheel-speed ratio (a circle driven one way) the left/right
radius ratio and the track width change it in the same way and cannot be told apart; only
the *turn scale* c_θ (the factor the fitted geometry puts on the nominal turn of this log)
and the *distance scale* c_d are determined. Here the joint fit of radii and width is made:
its variance inflation of the width, VIF = (se joint / se alone)², says whether the log
separates them (VIF < ``MAX_VIF``); either way c_θ and c_d are reported with their standard
errors, which stay small when the split does not.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from slipenv.diagnose.effects.base import Term
from slipenv.diagnose.effects.rolling_radius import RollingRadius
from slipenv.diagnose.effects.track_width import TrackWidth
from slipenv.diagnose.fit import Fit, Problem, fit
from slipenv.diagnose.numbers import determined, estimate, num

GEOMETRIC = ("rolling_radius", "track_width")
MAX_VIF = 25.0  # variance inflation above which radii ratio and width are called confounded


def _geometry(f: Fit, seg) -> tuple[np.ndarray, np.ndarray]:
    """(r_L, r_R, W) of a fit (nominal where it fits no such effect) and their covariance."""
    r0, w0 = float(np.median(seg.radius)), float(np.median(seg.track))
    keys = ("rolling_radius.left_m", "rolling_radius.right_m", "track_width.width_m")
    values = np.array([r0, r0, w0])
    index = []
    for k, key in enumerate(keys):
        if key in f.names:
            values[k] = f.x[f.names.index(key)]
            index.append((k, f.names.index(key)))
    cov = np.zeros((3, 3))
    for a, i in index:
        for b, j in index:
            cov[a, b] = f.cov[i, j]
    return values, cov


def _scales(theta: np.ndarray, seg) -> np.ndarray:
    """(c_θ, c_d): the fitted geometry's turn and distance over the nominal's, on this log."""
    r0, w0 = float(np.median(seg.radius)), float(np.median(seg.track))
    left = seg.dphi[..., seg.sides == 0].mean(axis=-1)
    right = seg.dphi[..., seg.sides == 1].mean(axis=-1)
    turn0 = np.abs(r0 * (right - left) / w0).sum()
    dist0 = np.abs(0.5 * r0 * (right + left)).sum()
    r_l, r_r, w = theta
    sign = np.sign(right - left)
    turn = (sign * (r_r * right - r_l * left) / w).sum()
    dist = (np.sign(right + left) * 0.5 * (r_r * right + r_l * left)).sum()
    return np.array([turn / max(turn0, 1e-12), dist / max(dist0, 1e-12)])


def _delta_se(func, theta: np.ndarray, cov: np.ndarray) -> np.ndarray:
    """Standard errors of ``func(theta)`` by the delta method (central differences)."""
    base = func(theta)
    jac = np.zeros((base.size, theta.size))
    for k in range(theta.size):
        h = 1e-6 * max(abs(theta[k]), 1e-6)
        up, down = theta.copy(), theta.copy()
        up[k] += h
        down[k] -= h
        jac[:, k] = (func(up) - func(down)) / (2 * h)
    return np.sqrt(np.maximum(np.diag(jac @ cov @ jac.T), 0.0))


def variance_inflation(problem: Problem) -> float:
    """VIF = (se joint / se alone)² of the track width fitted with both wheel radii against
    alone, on ``problem``'s segments: large (beyond ``MAX_VIF``) when the log cannot tell the
    radius ratio from the width (its turns all have about the same wheel-speed ratio)."""
    joint = fit(problem, GEOMETRIC)
    alone = fit(problem, ("track_width",))
    var_alone = float(alone.cov[0, 0])
    return float(joint.cov[2, 2] / var_alone) if var_alone > 0 else float("inf")


def calibration(problem: Problem, chosen: Fit | None) -> dict[str, Any] | None:
    """The calibration block of the report, or None unless ``chosen`` has a geometric effect.

    Parameters
    ----------
    problem : Problem
    chosen : Fit
        The pose channel's final model fitted on all segments.
    """
    if chosen is None or not set(GEOMETRIC) & set(chosen.effects):
        return None
    seg = problem.seg
    theta, cov = _geometry(chosen, seg)
    se = np.sqrt(np.maximum(np.diag(cov), 0.0))
    r_mean = 0.5 * (theta[0] + theta[1])
    se_mean = 0.5 * float(np.sqrt(cov[0, 0] + cov[1, 1] + 2 * cov[0, 1]))
    scales = _scales(theta, seg)
    scales_se = _delta_se(lambda th: _scales(th, seg), theta, cov)
    vif = variance_inflation(problem)
    separable = vif < MAX_VIF
    ratio = theta[1] / theta[0]
    ratio_se = float(_delta_se(lambda th: np.array([th[1] / th[0]]), theta, cov)[0])
    vif_text = f"{vif:.1f}" if np.isfinite(vif) else "unbounded"
    note = ("this log separates the wheel-radius ratio from the track width "
            f"(variance inflation {vif_text})" if separable else
            "on this log the left/right wheel-radius ratio and the track width are confounded "
            f"(variance inflation {vif_text} of the width when both are fitted: its turns all "
            "have about the same wheel-speed ratio); the split between them is not determined, "
            "only the turn scale and distance scale are — drive turns both ways, or straight "
            "runs, to separate them")
    config_ok = all(determined(v, e) for v, e in
                    ((r_mean, se_mean), (theta[2], se[2]), (theta[0], se[0]), (theta[1], se[1])))
    return {
        "config_determined": bool(config_ok),
        "diff_drive_controller": {
            "wheel_radius": float(r_mean), "wheel_separation": float(theta[2]),
            "left_wheel_radius_multiplier": float(theta[0] / r_mean),
            "right_wheel_radius_multiplier": float(theta[1] / r_mean),
            "wheel_separation_multiplier": 1.0,
        },
        "wheel_radius_m": [float(r_mean), se_mean],
        "wheel_separation_m": [float(theta[2]), float(se[2])],
        "left_wheel_radius_m": [float(theta[0]), float(se[0])],
        "right_wheel_radius_m": [float(theta[1]), float(se[1])],
        "right_left_radius_ratio": [float(ratio), ratio_se],
        "nominal": {"wheel_radius_m": float(np.median(seg.radius)),
                    "wheel_separation_m": float(np.median(seg.track))},
        "determined": {"turn_scale": [float(scales[0]), float(scales_se[0])],
                       "distance_scale": [float(scales[1]), float(scales_se[1])]},
        "separable": bool(separable), "variance_inflation": vif, "note": note,
        "fitted_effects": list(chosen.effects),
    }


def _terms(r_left: float, r_right: float, width: float) -> dict[str, Term]:
    return {"rolling_radius": RollingRadius(float(r_left), float(r_right)),
            "track_width": TrackWidth(float(width))}


def replay_terms(cal: dict[str, Any]) -> dict[str, Term]:
    """The calibration block as replay terms (``replay.simulate``): the robot's geometry as a
    config holds it, in absolute values.

    A robot whose config takes the calibration dead-reckons every later log with these radii
    and this separation, whatever nominal a log's header states. The radius or width the
    diagnosis did not change is the fitting logs' nominal, which their held-out test kept; a
    log recorded with another nominal (a session logged with another wheel diameter) is
    replayed with the calibrated value, not its own.
    """
    return _terms(cal["left_wheel_radius_m"][0], cal["right_wheel_radius_m"][0],
                  cal["wheel_separation_m"][0])


def geometry_terms(f: Fit, seg) -> dict[str, Term]:
    """The geometry of fit ``f`` on ``seg`` as :func:`replay_terms` gives a calibration's:
    absolute radii and width, ``seg``'s nominal for what ``f`` does not fit."""
    return _terms(*_geometry(f, seg)[0])


def markdown(cal: dict[str, Any]) -> list[str]:
    """Lines of the human report's calibration section."""
    ddc = cal["diff_drive_controller"]
    nom = cal["nominal"]
    turn, dist = cal["determined"]["turn_scale"], cal["determined"]["distance_scale"]
    return [
        "## Odometry calibration", "",
        "Values for a differential-drive controller's config (ROS `diff_drive_controller`):",
        "", "```yaml",
        f"wheel_radius: {num(ddc['wheel_radius'], '.6f')}        # nominal "
        f"{num(nom['wheel_radius_m'], '.6f')}",
        f"wheel_separation: {num(ddc['wheel_separation'], '.6f')}    # nominal "
        f"{num(nom['wheel_separation_m'], '.6f')}",
        f"left_wheel_radius_multiplier: {num(ddc['left_wheel_radius_multiplier'], '.6f')}",
        f"right_wheel_radius_multiplier: {num(ddc['right_wheel_radius_multiplier'], '.6f')}",
        "wheel_separation_multiplier: 1.0", "```", "",
        *([] if cal.get("config_determined", True) else
          ["**Not determined by this log**: a standard error below exceeds its value; do not "
           "put these numbers into a config.", ""]),
        "| quantity | value ± standard error |", "|---|---|",
        *[f"| {k} | {estimate(cal[k][0], cal[k][1])} |" for k in
          ("wheel_radius_m", "wheel_separation_m", "left_wheel_radius_m", "right_wheel_radius_m",
           "right_left_radius_ratio")],
        f"| turn scale c_θ | {estimate(turn[0], turn[1], spec='.5f')} |",
        f"| distance scale c_d | {estimate(dist[0], dist[1], spec='.5f')} |", "",
        f"What this log separates: {cal['note']}.", "",
        "To see what these values do to logs they were not fitted on (another session of "
        "this robot): `slipenv diagnose OTHER_LOG_DIR --model REPORT.json`, with this "
        "diagnosis's `--json` report.", "",
    ]
