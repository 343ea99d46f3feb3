"""The results pages ``docs/reproductions/yamauchi*.md``: the prose that explains the experiment,
its departure from the paper and what limits the result, every measured number filled in from
the run."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path as FsPath

from slipenv.vehicles.presets import tracked_patako_decoupled

from ..docs_page import command_line, copy_figures, figure_list, markdown_table, write_page
from .paper import ENDO_N
from .report import markdown_rows
from .settings import (
    DEFAULT_SOIL,
    DEFAULT_VEHICLE,
    ENV_ID,
    REPRODUCTION_SOIL,
    REPRODUCTION_VEHICLE,
    TARGETS,
    page_name,
    world_of,
)

CAPTIONS = {
    "fig4_endo_n": "Fig. 4 counterpart: Endo's n per tilt (log-log fit)",
    "fig5_slip_angle": "Fig. 5 counterpart: Eq. 9's slip angle against the truth, held-out runs",
    "fig6_odometry": "Fig. 6 counterpart: gyrodometry, Endo and slip-compensated odometry",
    "fig8_circle": "Fig. 8 counterpart: the circle on the 15° slope, first seed of each law",
}

SETUP = """\
{world} repeats the paper's experiments:

1. **Rotation runs (§2.3)**: heading across the slope (downhill to the right), track speeds for
   {speed_cm:g} cm/s and {rates} °/s, until the vehicle has turned {rotation:g}°, on slopes of
   {tilts}°, turning left and right, {repeats} runs per tilt, rate and direction. Ground-truth
   slips from the simulator's body velocity and the encoders (`true_slips`, the paper's
   motion capture).
2. **Endo's n per tilt** by log-log least squares with a 95 % interval (Eq. 8, Fig. 4) over
   every rotation run of the tilt, both directions, as the paper identified it ("from the
   results shown logarithmically in Figure 4 for each condition"): the `Endo n` rows and
   `metrics.endo_n`, the measure the paper's n is compared with.
3. **The slip-angle regression of Eq. 9** fitted on training runs, scored on held-out runs
   (split by run, never by sample, {test_pct:.0f} % held out) against the true slip angle
   (Fig. 5). The odometry and the circle use an n fitted on the same training runs only
   ({n_training}; `metrics.endo_n_training`), so that no held-out run reaches the odometry
   it is scored on; the paper's split serves only Eq. 9's regression.
4. **Gyrodometry, Endo and slip-compensated odometry** replayed on the held-out runs' sensor
   frames; position RMSE against truth (Fig. 6).
5. **Circle r = {radius:g} m at {speed_cm:g} cm/s on {circle_tilt:g}° (§3.1, Fig. 8)** with the
   path-following law of Eq. 9 and with the β feed-forward of Eq. 10, both on the
   slip-compensated observation, gains tuned once on flat rigid ground (triple pole chosen
   among {poles} rad/s: {pole:g}); plus the paper's conventional set-up (Eq. 9 on
   gyrodometry); {seeds} seeds each.{oracle_step}

**Departure from the paper: one slip-angle regression per turning direction.** Eq. 9's
regressors carry the turning direction only in the sign of the angular displacement, but on a
slope part of the slip angle is even in it (the turning centre moves towards the more loaded
end of the tracks, uphill or downhill), so a fit to both directions averages that part away.
The counter-clockwise model is the one the (counter-clockwise) circle uses{shipped}
(held-out improvement over gyrodometry {cw_pct:.0f} % clockwise, {ccw_pct:.0f} %
counter-clockwise). Endo's n is fitted on both directions, as Endo's relation is symmetric in
them.
{n_split_paragraph}"""

N_SPLIT = """
**Endo's n per turning direction: measured beside, not used.** Fitted per tilt and turning
direction on the training runs, Endo's n splits on the slope ({n_split}): a counter-clockwise
rotation run turns the nose uphill, a clockwise one downhill. The slip-compensated odometry
with that n (the direction from the sign of the track-speed difference, the step's commanded
turn; Eq. 9 refitted on its regressors) is {split_ccw:.2f} / {split_cw:.2f} of gyrodometry
counter-clockwise / clockwise on the held-out runs, against {pooled_ccw:.2f} / {pooled_cw:.2f}
with the pooled n: {verdict_ccw} counter-clockwise, {verdict_cw} clockwise. The odometry keeps
the paper's one n per tilt. Eq. 8's fit picks the n that best predicts the ratio of the two
tracks' slips, while the position depends on their sum (the forward speed, Eq. 1): the best
fit of the ratio need not be the best odometry. On the circle the vehicle turns one way
through every heading, uphill and downhill, so its turning direction would not pick the n
either.
"""

LIMITS_HEAD = """\
## What limits the result

Measured, not argued (`metrics.limits` in the JSON, the table's `limit:` rows): the odometry
replayed with the *true* slip angle in place of Eq. 9, which leaves only Endo's slip ratios as
error, and the circle steered on that odometry and on the true pose and β.
"""

EXTRAPOLATION = """\
- **Extrapolation.** The fitted Eq. 9 is evaluated only inside its training range
  (`SlipAngleModel.feature_range`): on the circle the angular displacement reaches 2π, far
  beyond the training rotations' {rotation:g}°.
"""

LIMITS_MEASURED = LIMITS_HEAD + """
- **Endo's n.** Eq. 8 has one n per tilt for both turning directions. Fitted per direction
  (counter-clockwise turns the nose uphill, clockwise downhill) it is {n_by_direction}: on a
  slope the tracks slip differently turning uphill and downhill, and the pooled n is a
  compromise between the two, which moves with the runs it pools: over every rotation run
  {n_all}, over the training runs alone {n_training}.
- **Odometry.** The true β leaves the slip-compensated odometry at {true_beta_ratio:.2f} of
  gyrodometry counter-clockwise (the fitted Eq. 9: {fitted_ratio:.2f}; the paper: 0.18,
  target ≤ 0.4): with a perfect slip-angle regression what remains is Endo's slip
  ratios.{split_sentence}{n_dir_sentence}{cm_sentence}{cv_sentence}{start_bullet}
- **Circle.** On the odometry with the true β the feed-forward changes the mean error by a
  factor {true_beta_ff:.2f} against feedback, and steered on the truth with the gains tuned on
  rigid ground by {truth_ff:.2f} (the target asks ≤ 0.5); the true slip angle of the turning
  vehicle swings by {swing:.0f}° (5-95 % range) around a lap.{oracle_sentence}{search_sentence}
""" + EXTRAPOLATION + """
"""
"""The limits of a run: only what its numbers say."""

CALIBRATION_HEAD = """\
## What was calibrated, on which measurement

Parameters no source fixes were set from the paper's measured inputs and then frozen
(`metrics.calibrated`); the odometry improvement (82 %) and the circle (9.1 -> 1.3 cm) are
validation only, never fitted or used to choose:

"""

DEFAULT_WORLD = """\
The `tracked_patako_wong_chiang` vehicle on `toyoura_sand` (`slipenv/TrackedSlopeCircle-v0`)"""

VEHICLE_MODELS = {
    "tracked_patako": "Janosi shear injected under each road wheel",
    "tracked_patako_wong_chiang": (
        "one Janosi shear field along each track, advected with the belt (Wong & Chiang "
        "2001), stress against the sliding velocity, pressure from the road-wheel loads, "
        "Bekker sinkage with Lyasko's slip-sinkage, compaction resistance as a rut state, "
        "Rankine side-wall (bulldozing) pressure with a berm that grows with the swept volume "
        "(`slipenv/terramechanics/track.py`, `slipenv/sim/track_soil.py`)"),
}
"""One sentence on each tracked vehicle's soil model (per-wheel law or Wong-Chiang track)."""
_DECOUPLED = tracked_patako_decoupled()
VEHICLE_MODELS["tracked_patako_decoupled"] = (
    "the Wong-Chiang track model with Ishigami et al.'s decoupled shear law (each component "
    "Janosi's law of its own displacement, the resultant capped at the Mohr-Coulomb strength, "
    "where the soil deforms; the resultant law on rigid ground) and its two moduli calibrated "
    "on the paper's Endo n (`benchmarks/yamauchi_shear_calibration.py`): "
    f"K_x = {_DECOUPLED.track_longitudinal_shear_modulus_ratio:g} K along the track, "
    f"K_y = {_DECOUPLED.track_lateral_shear_modulus_ratio:g} K across it")

SOIL_NOTES = {
    "dry_sand": "Wong's dry sand (LLL), cohesive (c = 1.04 kPa)",
    "toyoura_sand": ("the paper's loosely poured Toyoura sand: cohesionless, φ and K from the "
                     "Tohoku group's Toyoura set (Ishigami), the Bekker constants of the "
                     "closest sourced dry loose silica sand, Wong's LLL dry sand "
                     "(`slipenv/terramechanics/presets.py` gives each source)"),
}


def soil_sentence(name: str) -> str:
    """The soil preset ``name`` with its Bekker and strength constants, from the preset."""
    from slipenv.terramechanics.presets import soil_by_name

    soil = soil_by_name(name)
    note = SOIL_NOTES.get(name)
    return (f"soil `{name}`{': ' + note if note else ''} (c = {soil.cohesion_pa / 1e3:g} kPa, "
            f"φ = {math.degrees(soil.friction_angle_rad):g}°, K = "
            f"{100 * soil.shear_modulus_m:g} cm, n = {soil.n_exp:g}, k_c = "
            f"{soil.k_c / 1e3:g} kN/m^(n+1), k_φ = {soil.k_phi / 1e3:g} kN/m^(n+2))")


def world_text(vehicle: str | None, soil: str | None) -> str:
    """The opening words of the setup: the vehicle and soil of the run."""
    v, s = world_of(vehicle, soil)
    if (v, s) == (DEFAULT_VEHICLE, DEFAULT_SOIL):
        return DEFAULT_WORLD
    return f"The `{v}` vehicle on `{s}` (`{ENV_ID}` with its world replaced)"


def world_details(vehicle: str | None, soil: str | None) -> str:
    """The world of a run: its vehicle's soil model and its soil's constants, one bullet
    each."""
    v, s = world_of(vehicle, soil)
    model = VEHICLE_MODELS.get(v)
    opening = ("The env preset's world, the reproduction's default"
               if (v, s) == (REPRODUCTION_VEHICLE, REPRODUCTION_SOIL)
               else "The same experiments as [yamauchi.md](yamauchi.md), with the world changed")
    return (f"{opening}:\n\n"
            f"- vehicle `{v}`{': ' + model if model else ''};\n- {soil_sentence(s)}.")


def n_split_paragraph(m: dict) -> str:
    """The paragraph on Endo's n per turning direction, scored beside the pooled n; empty when
    the run has no such score (one turning direction)."""
    split = m.get("odometry_rmse_ratio_endo_n_by_direction") or {}
    pooled = m.get("odometry_rmse_ratio") or {}
    n_split = m.get("endo_n_training_by_direction") or {}
    if not (split and pooled and n_split) or None in n_split.values():
        return ""

    def verdict(d: str) -> str:
        return "better" if split[d] < pooled[d] else "worse"

    return N_SPLIT.format(
        n_split=", ".join(f"{t}° {n_split[t + '_ccw']:.2f} / {n_split[t + '_cw']:.2f}"
                          for t in m["endo_n"]) + " counter-clockwise / clockwise",
        split_ccw=split["ccw"], split_cw=split["cw"], pooled_ccw=pooled["ccw"],
        pooled_cw=pooled["cw"], verdict_ccw=verdict("ccw"), verdict_cw=verdict("cw"))


def split_sentence(lim: dict) -> str:
    """Which part of the odometry's error is Endo's slip ratios and which Eq. 9's β, both
    turning directions; empty without the true-slip limits."""
    both = lim.get("odometry_ratio_to_gyrodometry_by_direction") or {}
    if set(both) != {"ccw", "cw"} or "slip_compensated_true_slips" not in both["ccw"]:
        return ""

    def pair(key: str) -> str:
        return f"{both['ccw'][key]:.2f} / {both['cw'][key]:.2f}"

    def reached(key: str) -> str:
        return "meets" if all(v[key] <= 0.4 for v in both.values()) else "misses"

    return (" Counter-clockwise / clockwise: with Endo's slip ratios and Eq. 9's β "
            f"{pair('slip_compensated')}; with the true β {pair('slip_compensated_true_beta')} "
            f"(the error of Endo's slip ratios, {reached('slip_compensated_true_beta')} the "
            "target); with the true track slips (Eq. 1 with the true forward speed, Eq. 7 with "
            f"the gyro) and Eq. 9's β {pair('slip_compensated_true_slips')} (the error of "
            f"Eq. 9's β, {reached('slip_compensated_true_slips')} the target); with both true "
            f"{pair('slip_compensated_true_slips_true_beta')}, the gyro's heading error.")


def cv_sentence(m: dict, cfg: dict) -> str:
    """The odometry ratio cross-validated by run beside the one split's; empty without it."""
    cv, one = m.get("odometry_rmse_ratio_cross_validated"), m.get("odometry_rmse_ratio")
    if not cv or not one:
        return ""
    return (f" Which runs one split holds out moves the ratio: {cfg.get('cv_folds', 3)}-fold "
            "cross-validated by run (every run held out once, the same fits per fold) it is "
            f"{cv['ccw']:.2f} / {cv['cw']:.2f} counter-clockwise / clockwise, against "
            f"{one['ccw']:.2f} / {one['cw']:.2f} on the headline split.")


def start_bullet(fall: dict | None, m: dict) -> str:
    """The rotation runs started facing downhill, the other reading of §2.3's field, in
    words; empty for a run without them."""
    if not fall:
        return ""
    n, r, down_dir = fall["endo_n"], fall["odometry_rmse_ratio"], fall["endo_n_by_direction"]
    steep = max(n, key=float)
    across_dir = m.get("endo_n_by_direction") or {}

    def ways(by_dir: dict) -> tuple | None:
        pair = (by_dir.get(f"{steep}_ccw"), by_dir.get(f"{steep}_cw"))
        return None if None in pair else pair

    down, across = ways(down_dir), ways(across_dir)
    n_ok = all(abs(v - ENDO_N[t]) <= TARGETS["endo_n_tolerance"] for t, v in n.items()
               if t in ENDO_N)
    odo_ok = all(v <= TARGETS["odometry_ratio_max"] for v in r.values())
    causes = []
    if across and abs(across[0] - across[1]) > 0.1:
        causes.append(f"across the slope the uphill and downhill turns split n ({across[0]:.2f}"
                      f" / {across[1]:.2f} at {steep}°)")
    if n[steep] - n[min(n, key=float)] > 0.1:
        causes.append("facing downhill n grows with the tilt")
    met = m.get("targets_met") or {}
    across_ok = (met.get("endo_n_within_0.05_paper_at_each_tilt", False)
                 and met.get("slip_compensated_rmse_le_0.4_gyrodometry_both_directions", False))
    verdict = (" Facing downhill the runs " + ("meet" if n_ok else "miss") + " the n target and "
               + ("meet" if odo_ok else "miss") + " the odometry target.")
    if causes and not across_ok and not (n_ok and odo_ok):
        verdict += " Neither reading of the field gives both: " + "; ".join(causes) + "."
    return ("\n- **Start heading.** §2.3 sets the robot \"parallel to the long side\" of a 2 × 1 m "
            "field tilted \"by jacking up one side\", without saying which side: the runs above "
            "start across the slope. Started facing downhill instead "
            "(`metrics.limits.fall_line_start`, the same runs otherwise), Endo's n is "
            + " / ".join(f"{v:.2f}" for v in n.values()) + " at " + "/".join(n) + "°"
            + ("" if down is None else
               f" (counter-clockwise / clockwise {down[0]:.2f} / {down[1]:.2f} at {steep}°)")
            + " against the paper's " + " / ".join(f"{ENDO_N[t]:.3f}" for t in n if t in ENDO_N)
            + f", and the held-out slip-compensated odometry {r['ccw']:.2f} / {r['cw']:.2f} of "
            f"gyrodometry counter-clockwise / clockwise.{verdict}")


def _law_result(g: dict) -> str:
    """One law's oracle gain in words: its pole, worst-lap maximum error and laps."""
    return (f"at {g['pole_rps']:g} rad/s, max {100 * g['worst_max_error_m']:.1f} cm, "
            f"{g['completed']}/{g['laps_run']} lap{'s' if g['laps_run'] > 1 else ''}")


def _worst_at(g: dict, pole: float) -> str:
    """A law's worst-lap maximum error [cm] at ``pole`` of the oracle grid."""
    return f"{100 * g['by_pole'][f'{pole:g}']['worst_max_error_m']:.1f}"


def oracle_sentence(oracle: dict | None) -> str:
    """What the oracle gain (each law's best triple pole of the oracle grid, on the laps' own
    true maximum error) says of the circle: can the vehicle hold it on the truth, can any gain
    hold it on the env's observations; empty for a run without it."""
    if not oracle or not {"truth", "observation"} <= set(oracle):
        return ""
    truth, obs = oracle["truth"], oracle["observation"]
    fb, ff = truth["feedback"], truth["feedforward"]
    ob_fb, ob_ff = obs["feedback_gyrodometry"], obs["feedforward_slip_compensated"]
    corridor = f"the {fb['corridor_m']:g} m corridor"
    poles = ", ".join(f"{p:g}" for p in oracle["poles_rps"])
    holds = {name: g["completed"] == g["laps_run"] for name, g in (("Eq. 9", fb), ("Eq. 10", ff))}
    obs_any = max(v["completed"] for g in (ob_fb, ob_ff) for v in g["by_pole"].values())
    if all(holds.values()):
        truth_words = ("both laws complete their laps", "so the vehicle can hold the circle")
    elif any(holds.values()):
        law = next(k for k, v in holds.items() if v)
        truth_words = (f"only {law} completes its laps",
                       f"so the vehicle can hold the circle with {law}")
    else:
        truth_words = ("neither law completes every lap",
                       f"so no gain of the grid keeps every lap inside {corridor} even on the "
                       "truth")
    obs_words = ("no gain of the grid completes a lap" if obs_any == 0 else
                 f"the best gain of the grid completes at most {obs_any} of its laps")
    out = (f" With the best gain of an oracle grid (triple poles {poles} rad/s, chosen per law "
           "on the laps' own true maximum error, `metrics.limits.path_following.oracle_gain`; "
           f"never used for the headline gains), steered on the truth, {truth_words[0]} "
           f"(Eq. 9 {_law_result(fb)}; Eq. 10 {_law_result(ff)}), {truth_words[1]}. On the "
           "env's observations (Eq. 9 on gyrodometry, Eq. 10 on slip-compensated odometry, "
           f"{ob_fb['laps_run']} seeds) {obs_words} (best: Eq. 9 {_law_result(ob_fb)}; "
           f"Eq. 10 {_law_result(ob_ff)}; with the truth's best poles the laps stray up to "
           f"{_worst_at(ob_fb, fb['pole_rps'])} / {_worst_at(ob_ff, ff['pole_rps'])} cm)")
    if all(holds.values()) and obs_any == 0:
        return out + (", so the odometry's error, not the vehicle or the gains, keeps the laps "
                      f"from {corridor}.")
    return out + "."


def search_sentence(pf: dict) -> str:
    """The rigid-ground gain search that chooses the headline pole (§3.1), with its spread
    over the poles; empty for a run without it."""
    search = pf.get("rigid_ground_rmse_m_by_pole")
    if not search:
        return ""
    lo, hi = 100 * min(search.values()), 100 * max(search.values())
    slowest = pf["pole_rps"] == min(float(p) for p in search)
    return (" The headline gains stay those chosen on a solid floor, as the paper set them "
            "(§3.1): there Eq. 9 on gyrodometry (on concrete) puts every pole of "
            + ", ".join(search) + f" rad/s within {hi - lo:.1f} cm of lap RMSE ({lo:.1f}-"
            f"{hi:.1f} cm){': the search is flat' if hi - lo < 0.5 * lo else ''}, and it "
            f"chose {pf['pole_rps']:g} rad/s{', the slowest' if slowest else ''}.")


def page_body(result: dict, figures: Sequence[str], command: str) -> str:
    """The page's Markdown, every number from ``result``."""
    m, cfg = result["metrics"], result["settings"]
    lim, pf = m["limits"], m["path_following"]
    odo, cw = m["odometry_rmse_m"], (m.get("clockwise") or {}).get("odometry_rmse_m")
    by_dir = ", ".join(f"{k.replace('_', '° ')} {v:.2f}" if v is not None else f"{k} -"
                       for k, v in m["endo_n_by_direction"].items())
    training = m.get("endo_n_training") or {}
    values = dict(
        n_all=" / ".join(f"{v:.2f}" for v in m["endo_n"].values()) + " at "
        + "/".join(m["endo_n"]) + "°",
        n_training=(" / ".join(f"{v:.2f}" for v in training.values()) + " at "
                    + "/".join(training) + "°") if training else "not reported",
        speed_cm=100 * cfg["speed_mps"], rates="/".join(f"{r:g}" for r in cfg["turn_rates_dps"]),
        rotation=cfg["rotation_deg"], tilts=", ".join(f"{t:g}" for t in cfg["tilts_deg"]),
        repeats=cfg["repeats"], test_pct=100 * cfg["test_fraction"],
        radius=cfg["circle_radius_m"], circle_tilt=cfg["circle_tilt_deg"],
        poles=", ".join(f"{p:g}" for p in cfg["poles_rps"]), pole=pf["pole_rps"],
        seeds=cfg["circle_seeds"],
        cw_pct=100 * (1 - cw["slip_compensated"] / cw["gyrodometry"]) if cw else float("nan"),
        ccw_pct=100 * m["odometry_improvement_vs_gyrodometry"],
        true_beta_ratio=lim["odometry_ratio_to_gyrodometry"]["slip_compensated_true_beta"],
        fitted_ratio=odo["slip_compensated"] / odo["gyrodometry"], n_by_direction=by_dir,
        true_beta_ff=lim["path_following"]["true_beta"]["feedforward_to_feedback_mean"],
        truth_ff=lim["path_following"]["truth"]["feedforward_to_feedback_mean"],
        swing=lim["path_following"]["truth"]["feedback"]["slip_angle_swing_deg"],
    )
    values["n_split_paragraph"] = n_split_paragraph(m)
    values["split_sentence"] = split_sentence(lim)
    values["oracle_sentence"] = oracle_sentence(lim["path_following"].get("oracle_gain"))
    values["oracle_step"] = "" if not values["oracle_sentence"] else (
        " As a limit, each law's best triple pole of a wider grid (an oracle, chosen on the "
        "slope's own laps) is run steering on the truth and on the observation.")
    values["search_sentence"] = search_sentence(pf)
    r2 = lim.get("endo_r2")
    values["n_dir_sentence"] = "" if not r2 else (
        " Eq. 8 with the n of every rotation run explains R² = "
        + ", ".join(f"{v:.2f} at {t}°" for t, v in r2.items())
        + " of the true slips' log ratio against the log speed ratio: where it is low, the "
        "ratio of the two tracks' slips does not follow a power of their speed ratio, and "
        "Endo's odometry infers the wrong slips from the gyro.")
    share = lim.get("endo_common_mode_share")
    values["cm_sentence"] = "" if not share else (
        " Of the rotation samples with both slips above 1 %, "
        + ", ".join(f"{100 * v:.0f} % at {t}°" for t, v in share.items())
        + " have true slips that break Eq. 8's sign rule (both tracks slipping the same way "
        "relative to their belts, a common-mode slip a ratio of the two cannot express).")
    values["cv_sentence"] = cv_sentence(m, cfg)
    values["start_bullet"] = start_bullet(lim.get("fall_line_start"), m)
    default = world_of(cfg.get("vehicle"), cfg.get("soil")) == (DEFAULT_VEHICLE, DEFAULT_SOIL)
    values["world"] = world_text(cfg.get("vehicle"), cfg.get("soil"))
    values["shipped"] = ((" and the one shipped\nin `slipenv/data`" if default else "")
                         + "; the clockwise one is fitted and scored the same way and reported "
                         "beside it")
    run = "quick" if result["quick"] else "full"
    met = sum(bool(v) for v in m["targets_met"].values())
    parts = [
        "# Yamauchi et al. re-run in simulation" + ("" if default else ": `{}` on `{}`".format(
            *world_of(cfg.get("vehicle"), cfg.get("soil")))),
        "Yamauchi, Nagatani, Hashimoto and Fujino, \"Slip compensated odometry for a tracked "
        "vehicle when rotating on a loose weak slope\": slip-compensated odometry (§2, Eq. 1-9) "
        "and slip-angle feed-forward path following (§3, Eq. 9-10).",
        f"Generated by `{command}` ({run} run, seed {result['seed']}, "
        f"{m['run_time_s']:.0f} s). Code: `slipenv/experiments/yamauchi/`.",
        "## What is run", world_details(cfg.get("vehicle"), cfg.get("soil")),
        SETUP.format(**values),
        "## Paper against simulation",
        markdown_table(("quantity", "paper", "simulation"), markdown_rows(result)),
        f"Targets (the paper's odometry and circle results, and Endo's n): {met} of "
        f"{len(m['targets_met'])} met.",
        LIMITS_MEASURED.format(**values),
        CALIBRATION_HEAD + "\n".join(f"- **{k}**: {v}." for k, v in
                                      (m.get("calibrated") or {}).items()),
        "## Figures", figure_list(figures, CAPTIONS),
    ]
    return "\n\n".join(p.strip() for p in parts if p)


def world_options(settings: dict) -> tuple[str, ...]:
    """The ``--vehicle``/``--soil`` flags that select the run's world, always both (the
    command's default world is not the env preset's: ``None`` is spelt out)."""
    vehicle, soil = world_of(settings.get("vehicle"), settings.get("soil"))
    return ("--vehicle", vehicle, "--soil", soil)


def write_results_page(result: dict, figures: Sequence[str | FsPath],
                       docs_dir: str | FsPath) -> FsPath:
    """Write ``docs_dir/NAME.md`` and copy the figures to ``docs_dir/img/NAME/``; ``NAME`` is
    :func:`~.settings.page_name` of the run's world (``yamauchi`` for the env preset's)."""
    cfg = result["settings"]
    name = page_name(cfg.get("vehicle"), cfg.get("soil"))
    command = command_line("yamauchi", result["quick"], result["seed"], docs_dir,
                           world_options(cfg))
    relative = copy_figures(figures, docs_dir, name)
    return write_page(docs_dir, name, command, page_body(result, relative, command),
                      package="yamauchi")
