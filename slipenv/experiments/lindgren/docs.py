"""The results page ``docs/reproductions/lindgren.md``: the prose that explains the experiment
and its departures from the paper, with every measured number filled in from the run."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path as FsPath

import numpy as np

from ..docs_page import command_line, copy_figures, figure_list, markdown_table, write_page
from .report import markdown_rows, target_lines
from .settings import CALIBRATION_SETTLE_M, CIRCLE_RADIUS_M

CAPTIONS = {
    "paths": "Fig. 4 counterpart: schemes 1-4 on the circles against the true path",
    "dropout": "Fig. 7 counterpart: first straights drive, laser cut (scheme 3; scheme 4 and "
               "oracle)",
    "autocorrelation": "Fig. 6 counterpart: autocorrelation of the odometric innovations",
    "paths_robust": "Robust block: schemes 1-4 on the circles, curved Janosi/Okello world",
    "dropout_robust": "Robust block: first straights drive, laser cut, curved Janosi/Okello "
                      "world, default soil random walk, measured radius for scheme 3",
}

SETUP = """\
Like the paper, each drive of the vehicle records the raw sensor data, and the EKF schemes run
offline over the same frames (Lindgren §5: "the raw sensor data ... run through four different
EKF schemes"), exactly as `slipenv.estimators.LindgrenEKF` exposes them. The vehicle is
`slipenv/FarmField-v0` (farm_2wd on field_loam, Lindgren's linear torque/slip law, finite
k_s; true rolling radii {R_true} m against the concrete-calibrated nominal {R_nom:.3f} m),
steered by the baseline path follower on the env's Lindgren EKF in **scheme {steer}** (laser +
inertial): the paper steered with scheme 3; scheme 1 keeps the driven path independent of the
two schemes being compared.

- **(a) Lindgren's circles (Fig. 3)**: {radius:g} m radius, {loops:g} loop(s) clockwise then
  counter-clockwise at {speed:g} m/s (speed assumed: the paper gives none). Schemes 1-4 and the
  oracle (scheme 4 knowing the true R_w and k_s). Statistics over the clockwise arc at constant
  speed (as the paper), after the first {settle:g} m: Table 1's mean deviation from scheme 1
  and, as only a simulation can, the true mean error and pose NEES; the NIS of the odometric
  innovations (Eq. 43) with its 95 % band, exact and by Eq. 44 (Table 3); the autocorrelation
  ρ̄(l), Eq. 42, l = 1..{lags}, its mean, variance and share inside ±1.96/√K (Table 2, Fig. 6).
- **(b) Straights with alternating 180° turns (Fig. 7)**: laser and odometers only (the
  inertial and inclinometer readings are removed from the recorded frames; the EKF skips
  them), bearings removed after {cut:g} s; final position error of scheme 3 (no slip model),
  scheme 4 (slip model) and the oracle. One drive's final error is dominated by a random walk
  of the heading (here the slip model / oracle ratio ranges {ratio_lo:.2f}-{ratio_hi:.2f} from
  drive to drive), so (b) drives the path {drives} times (seeds {seed}, {seed1}, ...) and
  reports the mean final error; every drive's value is in the JSON, the first drive in the
  plot.

`--quick` runs the same experiments on shorter paths (1 loop each way; 3 straights).
"""

FILTERS = """\
## Filter settings

Every scheme uses the paper's measurement variances (`LindgrenNoise` defaults) and the k_s
prior of `slipenv.envs.estimation.default_k_s_prior` ({k_s0:.0f} N m here), with two changes
(`FILTER` in `slipenv/experiments/lindgren/settings.py`), each also run at the estimator's
default to show its effect (the table's rows "with the estimator's ..."):

- **The paper's bearing association**, nearest innovation with no χ² gate. With the
  estimator's gate (0.999) scheme 3, whose odometry is trusted to the encoder's variance while
  it is off in scale by the slip, rejects the bearings that would correct it: on the circles
  it gated {gated} of the bearings here and deviates {gated_dev:.3f} m instead of
  {ungated_dev:.3f} m; on the first straights drive it ends {gated_drop:.2f} m off instead of
  {ungated_drop:.2f} m.
- **The random walk of the soil states**: the FarmField world is one uniform soil, so R_w may
  wander by about 1 mm and k_s by about 3 % per 100 m (the defaults allow 1 cm and 10 %, right
  for a field whose soil changes). This matters once the laser is cut: with odometry alone,
  speed and soil states are unobservable along a common scale
  (z ∝ v k_s / (R_w (k_s - T))), and the estimate walks along it as fast as the process noise
  lets it. With the defaults the straights drives end {soil_drop:.2f} m off on average instead
  of {field_drop:.2f} m (the robust block below runs without this setting).
"""

ROBUST = """\
## Robustness: a world that is not the filter's model

The headline leans on its setting: the world injects Lindgren's linear torque/slip
law, the exact structure scheme 4 assumes; the soil random walk is cut to what a uniform
field needs; and scheme 3 gets the concrete radius. The robust block (column "robust" in the
table above; `ROBUST` in `slipenv/experiments/lindgren/settings.py`, `metrics.robust` in the
JSON) drives the same paths with the same seeds and beacons and changes all three:

- **The world** injects the curved Janosi/Okello law (`force_model="janosi"`, Lindgren
  Eq. 18-20) on the same field loam, whose slope at zero slip is the linear law's k_s.
- **Every filter** has the estimator's default soil random walk (R_w {rw_var:.0e} m²/m, k_s
  {ks_var:.0e}/m relative), not the uniform-field cut; the paper's ungated bearing association
  is kept.
- **Scheme 3 (and 2) get a measured effective radius**, as the paper's operators did: a
  {cal_m:g} m straight drive on this soil, R_eff = d / Δθ between marks {settle:g} m in from
  either end (`calibration.py`): d = {cal_d:.3f} m over {cal_angle:.2f} rad gives
  R_eff = {R_eff:.4f} m, against true rolling radii {R_true_r} m (the drive's slip,
  {cal_slip:.1f} % at {cal_torque:.1f} N m per wheel) and the concrete-calibrated
  {R_nom:.3f} m.

{verdict} The robust "1.5 × oracle" target compares with an oracle that knows the true radii
and the law's slope at zero slip, not the law: on the curved law it is no oracle, so that row
says little.

What the slip model is missing here, measured on the same robust frames:

- **The soil random walk after the cut.** Scheme 4 with the uniform-field random walk ends
  {field4:.3f} m off on average instead of {robust4:.3f} m (first drive {field4_1:.3f} m
  against {robust4_1:.3f} m): {walk_verdict}. With odometry alone, speed and soil states are
  unobservable along a common scale (z ∝ v k_s / (R_w (k_s - T))), and the random walk sets
  how fast the estimate may wander along it; the filter has no way to tell a uniform field
  from a changing one.
- **The curvature of the law.** No constant k_s is true on the curved law. On the first
  straights drive the driven wheels carry {T_straight:.0f} N m at {s_straight:.1f} % slip on
  the straights (secant T/s {k_straight:.0f} N m); in the turns the outer wheel
  {T_turn_outer:.0f} N m at {s_turn_outer:.1f} % ({k_turn_outer:.0f} N m) and the inner one
  {T_turn_inner:.0f} N m at {s_turn_inner:.1f} % ({k_turn_inner:.0f} N m). In the headline's
  linear world, measured the same way: {hk_straight:.0f}, {hk_turn_outer:.0f} and
  {hk_turn_inner:.0f} N m. The law's slope at zero slip, which the oracle is given, is
  {k_tangent} N m; the oracle ends {oracle:.3f} m off after the cut (headline world
  {oracle_head:.3f} m), and given the secant measured on the calibration drive,
  {k_secant:.0f} N m, {oracle_sec:.3f} m: {secant_verdict}. Scheme 4 learns one k_s per
  side ({k_est} N m on the circles), a line through the origin fitted to the torques it saw.
- **The measured radius** ({R_eff:.4f} m) is right only at the calibration drive's torque:
  scheme 3 ends {robust3:.3f} m off with it and {nominal3:.3f} m with the nominal radius
  ({radius_verdict}).
"""

DIFFERENCES = """\
## What remains different from the paper

None of it is tuned away.

- **The simulated slip is large** (true k_s {k_s_true} N m against the prior {k_s0:.0f}; true
  rolling radii {R_true} m against the nominal {R_nom:.3f} m), so scheme 3 deviates more than in
  the paper and, after the cut, drifts differently from the paper's 1.97 m: the paper's no-slip
  run used "a carefully measured effective wheel radius", this one the concrete-calibrated
  nominal radius, as the headline targets ask (the robust block above gives it a measured one).
- **Scheme 4's NIS** is {nis4:.2f}, {nis_where} the band {band_lo:.3f}-{band_hi:.3f} (paper
  3.18, above its band). The simulated encoders err only by quantisation (1/6 count² for a
  count difference, whose lag-1 autocorrelation is negative) while the filter keeps the
  paper's 3.1e-6 rad² = 0.25 count²; the paper's excess came from effects the simulation
  lacks.
- **Scheme 3's autocorrelation** has mean {rho3:.3f} and variance {rho3_var:.2g} over the lags:
  a bias with no periodic part, where the paper's had a periodic component (variance 0.068).
- **Under constant torque** (circles at constant speed) R_w and k_s are not separately
  observable, only R_w (1 - T / k_s): scheme 4 ends at R_w {R_est} m, k_s {k_s_est} N m
  against the true {R_true} m, {k_s_true} N m.
- **The pose NEES** of scheme 4 is {nees4:.2f} and of the oracle {nees_o:.2f} against n = 3:
  both are overconfident. Candidates, not separated here: lateral slip in the turns, load
  transfer changing k_s, torque noise entering Eq. 37 as if exact.
- **After the cut** the slip model / oracle ratio of the mean final error is {ratio:.2f}
  (target ≤ 1.5; final heading error {head4:.1f}° against the oracle's {heado:.1f}°). Under
  steady torque only each side's R_w (1 - T / k_s) is observable, and {cut:g} s of bearings
  cover one turn; the left/right error left in the learnt effective radii, and their further
  walk along the unobservable scale, are turned by {after:.0f} s of odometry alone into
  heading error. With the laser cut at {cut2:g} s instead (more of the path and its turns
  seen with bearings; the odometry-only stretch is then {after2:.0f} s, so compare the
  ratios) scheme 4 ends {s4x2:.3f} m off against the oracle's {ox2:.3f} m (ratio
  {ratio2:.2f}): {cut_verdict}.
"""


def _fmt(values: Sequence[float], digits: int) -> str:
    return " / ".join(f"{v:.{digits}f}" for v in values)


def page_body(result: dict, figures: Sequence[str], command: str) -> str:
    """The page's Markdown, every number from ``result``."""
    m, cfg, paper = result["metrics"], result["config"], result["paper"]
    c, d = m["circles"], m["dropout"]
    per = d["final_error_m_per_drive"]
    ratios = np.asarray(per["scheme4"]) / np.maximum(np.asarray(per["oracle"]), 1e-12)
    ratio2 = d["final_error_m"]["scheme4_cut_x2"] / max(d["final_error_m"]["oracle_cut_x2"],
                                                        1e-12)
    f1 = d["first_drive_final_error_m"]
    drop = m["dropout_final_error_m"]
    soil_true, soil_est = c["soil_true"], c["soil_estimate_scheme4"]
    values = dict(
        R_true=_fmt(soil_true["R_w_m"], 3), R_nom=cfg["nominal_wheel_radius_m"],
        steer=cfg["steered_by"].split()[-1], radius=CIRCLE_RADIUS_M, loops=cfg["circle_loops"],
        speed=cfg["speed_mps"], settle=cfg["settle_m"], lags=cfg["lags"], cut=cfg["cut_s"],
        ratio_lo=float(ratios.min()), ratio_hi=float(ratios.max()), drives=len(d["seeds"]),
        seed=cfg["seed"], seed1=cfg["seed"] + 1, k_s0=cfg["k_s_prior"],
        gated=c["bearings_gated"]["scheme3_gated"],
        gated_dev=c["mean_deviation_m"]["scheme3_gated"],
        ungated_dev=c["mean_deviation_m"]["scheme3"],
        gated_drop=f1["scheme3_gated"], ungated_drop=f1["scheme3"],
        soil_drop=d["final_error_m"]["scheme4_default_soil_noise"],
        field_drop=d["final_error_m"]["scheme4"],
        k_s_true=_fmt(soil_true["k_s"], 0), nis4=m["nis"]["scheme4"],
        nis_where=("below" if m["nis"]["scheme4"] < m["nis"]["band"][0] else
                   "above" if m["nis"]["scheme4"] > m["nis"]["band"][1] else "inside"),
        band_lo=m["nis"]["band"][0], band_hi=m["nis"]["band"][1],
        rho3=m["autocorr_mean"]["scheme3"], rho3_var=m["autocorr_var"]["scheme3"],
        R_est=_fmt(soil_est["R_w_m"], 4), k_s_est=_fmt(soil_est["k_s"], 0),
        nees4=c["nees_pose"]["scheme4"], nees_o=c["nees_pose"]["oracle"],
        ratio=drop["slip_model"] / drop["oracle"], after=d["duration_s"] - d["cut_s"],
        head4=d["final_heading_error_deg"]["scheme4"],
        heado=d["final_heading_error_deg"]["oracle"], cut2=2.0 * d["cut_s"],
        after2=max(d["duration_s"] - 2.0 * d["cut_s"], 0.0),
        s4x2=d["final_error_m"]["scheme4_cut_x2"], ox2=d["final_error_m"]["oracle_cut_x2"],
        ratio2=ratio2,
        cut_verdict=("the miss is the learning time before the cut, not a bias of the slip "
                     "model" if ratio2 <= 1.5 else
                     "more bearing time alone does not close the gap"),
    )
    met = sum(t["met"] for t in result["targets"].values())
    robust = m.get("robust")
    run = "quick" if cfg["quick"] else "full"
    parts = [
        "# Lindgren et al. §5 re-run in simulation",
        "Lindgren, Hague, Probert Smith and Marchant, \"Relating torque and slip in an "
        "odometric model for an autonomous agricultural vehicle\", §5 (Tables 1-3, Fig. 3-7).",
        f"Generated by `{command}` ({run} run, seed {cfg['seed']}, "
        f"{result['run_time_s']:.0f} s). Code: `slipenv/experiments/lindgren/`.",
        "## What is run", SETUP.format(**values),
        "## Paper against simulation",
        markdown_table(("quantity", "paper", "headline", "robust"), markdown_rows(m, paper)),
        f"Targets, headline ({met} of {len(result['targets'])} met):",
        "\n".join(f"- {line}" for line in target_lines(result["targets"])),
        *([] if robust is None else [
            f"Targets, robust ("
            f"{sum(t['met'] for t in result['targets_robust'].values())} of "
            f"{len(result['targets_robust'])} met):",
            "\n".join(f"- {line}" for line in target_lines(result["targets_robust"]))]),
        FILTERS.format(**values),
        *([] if robust is None else [robust_section(result)]),
        DIFFERENCES.format(**values),
        "## Figures", figure_list(figures, CAPTIONS),
    ]
    return "\n\n".join(p.strip() for p in parts)


def verdict(robust: dict, targets: dict) -> str:
    """Whether the slip model still wins in the robust block, from its numbers."""
    dev, drop = robust["mean_deviation_m"], robust["dropout_final_error_m"]
    circles = targets["scheme4 deviation <= 0.7 scheme3"]["met"]
    cut = targets["slip_model <= 0.3 no_slip_model"]["met"]
    on_circles = (f"on the circles scheme 4 deviates {dev['scheme4']:.3f} m from scheme 1 "
                  f"against scheme 3's {dev['scheme3']:.3f} m")
    after_cut = (f"after the laser cut it ends {drop['slip_model']:.3f} m off against the "
                 f"no-slip model's {drop['no_slip_model']:.3f} m (target ≤ 0.3 ×, ratio "
                 f"{drop['slip_model'] / max(drop['no_slip_model'], 1e-12):.2f})")
    if circles and cut:
        return f"**The slip model still wins clearly**: {on_circles}, and {after_cut}."
    if circles:
        return (f"**The slip model wins on the circles but not clearly after the cut**: "
                f"{on_circles}; {after_cut}.")
    if cut:
        return (f"**The slip model wins after the cut but not on the circles**: {after_cut}; "
                f"{on_circles}.")
    return f"**The slip model does not win here**: {on_circles}; {after_cut}."


def _torque_slip(metrics: dict, prefix: str) -> dict:
    """The first straights drive's torque, slip [%] and secant k_s, straight and in the
    turns (inner, outer wheel), as format fields (``prefix`` + name)."""
    ts = metrics["dropout"]["first_drive_torque_slip"]
    out = {}
    for motion in ("straight", "turn_inner", "turn_outer"):
        out[f"{prefix}T_{motion}"] = ts[motion]["torque_nm"]
        out[f"{prefix}s_{motion}"] = 100.0 * ts[motion]["slip"]
        out[f"{prefix}k_{motion}"] = ts[motion]["k_s_secant_nm"]
    return out


def robust_section(result: dict) -> str:
    """The robust block's section, every number from ``result``."""
    m, cfg = result["metrics"], result["config"]
    r, rc = m["robust"], cfg["robust"]
    cal, d = rc["calibration"], r["dropout"]
    final, f1 = d["final_error_m"], d["first_drive_final_error_m"]
    soil = r["circles"]["soil_true"]
    return ROBUST.format(
        rw_var=rc["soil_noise"]["radius_var_per_m"], ks_var=rc["soil_noise"]["k_s_rel_var_per_m"],
        cal_m=cal["drive_m"], settle=CALIBRATION_SETTLE_M, cal_d=cal["distance_m"],
        cal_angle=float(np.mean(cal["wheel_angle_rad"])), R_eff=cal["radius_m"],
        R_true_r=_fmt(soil["R_w_m"], 3), cal_slip=100.0 * cal["slip_vs_true_radius"],
        cal_torque=float(np.mean(cal["mean_torque_nm"])), R_nom=cfg["nominal_wheel_radius_m"],
        verdict=verdict(r, result["targets_robust"]),
        field4=final["scheme4_field_soil_noise"], robust4=final["scheme4"],
        field4_1=f1["scheme4_field_soil_noise"], robust4_1=f1["scheme4"],
        k_secant=cal["k_s_secant_nm"] or float("nan"), k_tangent=_fmt(soil["k_s"], 0),
        oracle=final["oracle"], oracle_head=m["dropout"]["final_error_m"]["oracle"],
        oracle_sec=final["oracle_secant"], **_torque_slip(r, ""), **_torque_slip(m, "h"),
        k_est=_fmt(r["circles"]["soil_estimate_scheme4"]["k_s"], 0),
        robust3=final["scheme3"], nominal3=final["scheme3_nominal_radius"],
        secant_verdict=("one line through the origin, even the one that fits the straights, "
                        "does not fit the turns"
                        if final["oracle_secant"] > 3.0 * m["dropout"]["final_error_m"]["oracle"]
                        else "a line through the origin at the straights' secant nearly does"),
        walk_verdict=("the default walk accounts for most of the loss"
                      if final["scheme4_field_soil_noise"] < 0.5 * final["scheme4"] else
                      "the random walk is not what loses it"),
        radius_verdict=("the measured radius helps the no-slip filter"
                        if final["scheme3"] < final["scheme3_nominal_radius"] else
                        "the measured radius does not help it: the straights' slip is not the "
                        "turns'"))


def write_results_page(result: dict, figures: Sequence[str | FsPath],
                       docs_dir: str | FsPath) -> FsPath:
    """Write ``docs_dir/lindgren.md`` and copy the figures to ``docs_dir/img/lindgren/``."""
    cfg = result["config"]
    command = command_line("lindgren", cfg["quick"], cfg["seed"], docs_dir)
    relative = copy_figures(figures, docs_dir, "lindgren")
    return write_page(docs_dir, "lindgren", command, page_body(result, relative, command))
