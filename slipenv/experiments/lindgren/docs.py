"""The results page ``docs/reproductions/lindgren.md``: the prose that explains the experiment
and its departures from the paper, with every measured number filled in from the run."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path as FsPath

import numpy as np

from ..docs_page import command_line, copy_figures, figure_list, markdown_table, write_page
from .report import markdown_rows, target_lines
from .settings import CIRCLE_RADIUS_M

CAPTIONS = {
    "paths": "Fig. 4 counterpart: schemes 1-4 on the circles against the true path",
    "dropout": "Fig. 7 counterpart: first straights drive, laser cut (scheme 3; scheme 4 and "
               "oracle)",
    "autocorrelation": "Fig. 6 counterpart: autocorrelation of the odometric innovations",
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
  lets it. With the defaults the first straights drive ends {soil_drop:.2f} m off instead of
  {field_drop:.2f} m (issue 16 asks for a robustness run without this setting).
"""

DIFFERENCES = """\
## What remains different from the paper

None of it is tuned away.

- **The simulated slip is large** (true k_s {k_s_true} N m against the prior {k_s0:.0f}; true
  rolling radii {R_true} m against the nominal {R_nom:.3f} m), so scheme 3 deviates more than in
  the paper and, after the cut, drifts differently from the paper's 1.97 m: the paper's no-slip
  run used "a carefully measured effective wheel radius", this one the concrete-calibrated
  nominal radius, as issue #3 asks.
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
- **After the cut** the slip model / oracle ratio of the mean final error is {ratio:.2f}: after
  {cut:g} s (one turn, no gyro) the learnt effective radii carry a small residual error, which
  {after:.0f} s of odometry alone turn into heading error, plus the slow walk along the
  unobservable scale.
"""


def _fmt(values: Sequence[float], digits: int) -> str:
    return " / ".join(f"{v:.{digits}f}" for v in values)


def page_body(result: dict, figures: Sequence[str], command: str) -> str:
    """The page's Markdown, every number from ``result``."""
    m, cfg, paper = result["metrics"], result["config"], result["paper"]
    c, d = m["circles"], m["dropout"]
    per = d["final_error_m_per_drive"]
    ratios = np.asarray(per["scheme4"]) / np.maximum(np.asarray(per["oracle"]), 1e-12)
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
        soil_drop=f1["scheme4_default_soil_noise"], field_drop=f1["scheme4"],
        k_s_true=_fmt(soil_true["k_s"], 0), nis4=m["nis"]["scheme4"],
        nis_where=("below" if m["nis"]["scheme4"] < m["nis"]["band"][0] else
                   "above" if m["nis"]["scheme4"] > m["nis"]["band"][1] else "inside"),
        band_lo=m["nis"]["band"][0], band_hi=m["nis"]["band"][1],
        rho3=m["autocorr_mean"]["scheme3"], rho3_var=m["autocorr_var"]["scheme3"],
        R_est=_fmt(soil_est["R_w_m"], 4), k_s_est=_fmt(soil_est["k_s"], 0),
        nees4=c["nees_pose"]["scheme4"], nees_o=c["nees_pose"]["oracle"],
        ratio=drop["slip_model"] / drop["oracle"], after=d["duration_s"] - d["cut_s"],
    )
    met = sum(t["met"] for t in result["targets"].values())
    run = "quick" if cfg["quick"] else "full"
    parts = [
        "# Lindgren et al. §5 re-run in simulation",
        "Lindgren, Hague, Probert Smith and Marchant, \"Relating torque and slip in an "
        "odometric model for an autonomous agricultural vehicle\", §5 (Tables 1-3, Fig. 3-7).",
        f"Generated by `{command}` ({run} run, seed {cfg['seed']}, "
        f"{result['run_time_s']:.0f} s). Code: `slipenv/experiments/lindgren/`.",
        "## What is run", SETUP.format(**values),
        "## Paper against simulation",
        markdown_table(("quantity", "paper", "simulation"), markdown_rows(m, paper)),
        f"Targets of issue #3 ({met} of {len(result['targets'])} met):",
        "\n".join(f"- {line}" for line in target_lines(result["targets"])),
        FILTERS.format(**values), DIFFERENCES.format(**values),
        "## Figures", figure_list(figures, CAPTIONS),
    ]
    return "\n\n".join(p.strip() for p in parts)


def write_results_page(result: dict, figures: Sequence[str | FsPath],
                       docs_dir: str | FsPath) -> FsPath:
    """Write ``docs_dir/lindgren.md`` and copy the figures to ``docs_dir/img/lindgren/``."""
    cfg = result["config"]
    command = command_line("lindgren", cfg["quick"], cfg["seed"], docs_dir)
    relative = copy_figures(figures, docs_dir, "lindgren")
    return write_page(docs_dir, "lindgren", command, page_body(result, relative, command))
