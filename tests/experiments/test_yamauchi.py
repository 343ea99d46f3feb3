"""``slipenv reproduce yamauchi --quick``: the JSON the command writes, and what it shows.

The quick run (fewer repetitions, the same experiments) is run once per module through the
command line, as a user would: in the default world, the env preset's, the Wong-Chiang track
model on cohesionless Toyoura sand (``toyoura_sand``).
"""

from __future__ import annotations

import json

import pytest

from slipenv.cli import main
from slipenv.envs.registration import yamauchi_observation
from slipenv.estimators.skid_steer.identification import SlipAngleModel
from slipenv.experiments import yamauchi
from slipenv.experiments.yamauchi import Settings

TILTS = {"0", "8", "15"}


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    out = tmp_path_factory.mktemp("yamauchi")
    path = out / "metrics.json"
    assert main(["reproduce", "yamauchi", "--quick", "--quiet", "--json", str(path),
                 "--out", str(out), "--docs", str(out / "docs")]) == 0
    return json.loads(path.read_text()), out


def test_the_json_has_the_promised_keys(quick):
    result, _ = quick
    m = result["metrics"]
    assert set(m["endo_n"]) == TILTS
    assert set(m["odometry_rmse_m"]) == {"gyrodometry", "endo", "slip_compensated"}
    for law in ("feedback", "feedforward"):
        assert {"mean_error_m", "rmse_m"} <= set(m["path_following"][law])
    assert set(result["paper"]["endo_n"]) == TILTS
    assert result["paper"]["odometry_improvement_vs_gyrodometry"] == 0.82
    # the summary the issue asks for: both turning directions, both laws side by side
    assert set(m["odometry_rmse_ratio"]) == {"ccw", "cw"}
    assert set(m["odometry_rmse_ratio_endo_n_by_direction"]) == {"ccw", "cw"}
    assert set(m["endo_n_training_by_direction"]) == {f"{t}_{d}" for t in TILTS
                                                      for d in ("ccw", "cw")}
    laws = {"feedback_gyrodometry", "feedforward_slip_compensated"}
    assert set(m["circle_mean_error_cm"]) == laws and set(m["laps_completed"]) == laws
    assert m["calibrated"] and all(isinstance(v, str) and v for v in m["calibrated"].values())


def test_started_facing_downhill_the_two_turning_directions_are_mirror_images(quick):
    """The fall-line start (``metrics.limits.fall_line_start``): turning left or right from
    facing downhill are mirror images about the fall line, so Endo's n fitted per direction
    agrees at every tilt (across the slope it splits by 0.9 at 15°); the cross-validated
    odometry ratio is reported per direction."""
    m = quick[0]["metrics"]
    fall = m["limits"]["fall_line_start"]
    assert set(fall["endo_n"]) == TILTS and set(fall["odometry_rmse_ratio"]) == {"ccw", "cw"}
    for t in TILTS:
        ccw, cw = fall["endo_n_by_direction"][f"{t}_ccw"], fall["endo_n_by_direction"][f"{t}_cw"]
        assert abs(ccw - cw) < 0.1
    across = m["endo_n_by_direction"]
    assert abs(across["15_ccw"] - across["15_cw"]) > 0.5
    cv = m["odometry_rmse_ratio_cross_validated"]
    assert set(cv) == {"ccw", "cw"} and all(0.0 < v < 2.0 for v in cv.values())


def test_the_summary_restates_the_detailed_metrics(quick):
    m = quick[0]["metrics"]
    odo_cw = m["clockwise"]["odometry_rmse_m"]
    assert m["odometry_rmse_ratio"]["cw"] == pytest.approx(
        odo_cw["slip_compensated"] / odo_cw["gyrodometry"])
    odo = m["odometry_rmse_m"]
    assert m["odometry_rmse_ratio"]["ccw"] == pytest.approx(
        odo["slip_compensated"] / odo["gyrodometry"])
    pf = m["path_following"]
    assert m["circle_mean_error_cm"]["feedforward_slip_compensated"] == pytest.approx(
        100 * pf["feedforward"]["mean_error_m"])
    assert m["laps_completed"]["feedback_gyrodometry"] == pf["feedback_gyrodometry"]["completed"]


def test_each_law_drives_the_papers_three_laps_judged_in_the_envs_corridor(quick):
    m = quick[0]["metrics"]
    pf = m["path_following"]
    assert m["laps_run"] == 3
    for law, run in (("feedback_gyrodometry", "feedback_gyrodometry"),
                     ("feedforward_slip_compensated", "feedforward")):
        assert len(pf[run]["per_seed_mean_error_m"]) == 3, law  # one lap per seed, three seeds
        assert m["laps_completed"][law] == pf[run]["completed"], law
        if pf[run]["completed"] == 3:  # every lap inside the env's 0.1 m corridor
            assert pf[run]["max_error_m"] <= 0.1, law


def test_the_command_runs_the_envs_world_the_track_model_on_toyoura_sand_by_default(quick):
    settings = quick[0]["settings"]
    assert (settings["vehicle"], settings["soil"]) == ("tracked_patako_wong_chiang",
                                                       "toyoura_sand")


def test_save_model_outside_the_env_presets_world_is_refused_before_any_work(tmp_path):
    with pytest.raises(ValueError,
                       match="vehicle='tracked_patako_wong_chiang', soil='toyoura_sand'"):
        yamauchi.run(out_dir=str(tmp_path), save_model=str(tmp_path / "m.json"),
                     progress=False, settings=Settings(vehicle="tracked_patako"))
    assert not (tmp_path / "m.json").exists()


def test_n_is_reported_per_tilt_with_a_confidence_interval(quick):
    m = quick[0]["metrics"]
    for tilt in TILTS:
        lo, hi = m["endo_n_ci95"][tilt]
        assert lo < m["endo_n"][tilt] < hi
        assert 0.0 < m["endo_n"][tilt] < 1.5 and m["endo_n_samples"][tilt] > 100


def test_the_papers_n_pools_every_rotation_run_and_the_odometrys_only_the_training_runs(quick):
    """§2.4 identifies n from every rotation result of a tilt (Fig. 4); the odometry and the
    circle use an n fitted on the training runs alone, so no held-out run reaches the score."""
    result, out = quick
    m = result["metrics"]
    for tilt in TILTS:
        lo, hi = m["endo_n_training_ci95"][tilt]
        assert lo < m["endo_n_training"][tilt] < hi
        # a third of the runs held out, of mixed turn rates and so lengths: the pooled fit has
        # more samples (1.27 / 1.36 / 1.51 times, quick; the exact sum in yamauchi/)
        ratio = m["endo_n_samples"][tilt] / m["endo_n_training_samples"][tilt]
        assert 1.1 < ratio < 2.0, tilt
    saved = json.loads((out / "slip_model.json").read_text())
    assert saved["n"] == m["endo_n_training"]["15"]


def test_the_regression_is_scored_only_on_runs_it_was_not_fitted_on(quick):
    m = quick[0]["metrics"]
    trained = set(m["slip_angle_model"]["train_runs"])
    assert trained and not trained & set(m["held_out_runs"])
    assert all(f"tilt{t}_" in " ".join(m["held_out_runs"]) for t in TILTS)


def test_slip_compensation_improves_on_gyrodometry_on_held_out_runs(quick):
    odo = quick[0]["metrics"]["odometry_rmse_m"]
    assert odo["slip_compensated"] < odo["endo"] < odo["gyrodometry"]


def test_the_limits_are_measured_and_a_perfect_slip_angle_regression_does_not_hurt(quick):
    """The limit rows: the odometry with the true β, and the circle steered on it and on the
    truth. Knowing β exactly cannot make the odometry worse than a fitted Eq. 9 does, and with
    the true pose and β the feed-forward must beat feedback (the law works when fed truth)."""
    lim = quick[0]["metrics"]["limits"]
    ratio = lim["odometry_ratio_to_gyrodometry"]
    assert ratio["slip_compensated_true_beta"] <= ratio["slip_compensated"]
    assert 0.0 < ratio["slip_compensated_true_beta"] < 1.0
    for mode in ("true_beta", "truth"):
        pair = lim["path_following"][mode]
        assert {"feedback", "feedforward", "feedforward_to_feedback_mean"} <= set(pair)
        laps = len(pair["feedback"]["per_seed_mean_error_m"])
        assert 0 <= pair["feedback"]["completed"] <= laps
    # fed the truth the law beats feedback (0.85 with the track model on toyoura_sand, quick)
    assert lim["path_following"]["truth"]["feedforward_to_feedback_mean"] < 0.9
    assert set(lim["endo_r2"]) == TILTS and all(v <= 1.0 for v in lim["endo_r2"].values())
    assert set(lim["endo_common_mode_share"]) == TILTS
    # the truth in place of both Endo's slips and Eq. 9's β leaves the gyro's heading error:
    # 0.03 / 0.04 of gyrodometry (quick), against 0.40 / 0.50 with the true β alone
    for way in lim["odometry_ratio_to_gyrodometry_by_direction"].values():
        assert way["slip_compensated_true_slips_true_beta"] < 0.15
        assert way["slip_compensated_true_slips_true_beta"] < way["slip_compensated_true_beta"]
    assert all(0.0 <= v <= 1.0 for v in lim["endo_common_mode_share"].values())


def test_the_oracle_gain_steered_on_the_truth_keeps_its_lap_inside_the_envs_corridor(quick):
    """The vehicle can hold the circle: with the best triple pole of the oracle grid, steering
    on the true pose and β, Eq. 10's lap stays inside the env's 0.1 m corridor (quick: 3.9 cm
    at 2 rad/s; the rigid-ground 0.15 rad/s strays 21.8 cm), and so does Eq. 9's (6.9 cm at
    2 rad/s, against 25.3 cm)."""
    m = quick[0]["metrics"]
    oracle = m["limits"]["path_following"]["oracle_gain"]
    for law in ("feedforward", "feedback"):
        best = oracle["truth"][law]
        assert best["corridor_m"] == pytest.approx(0.1)
        assert best["completed"] == best["laps_run"] == 1, law
        assert best["worst_max_error_m"] <= best["corridor_m"], law
        # the best of its grid, and faster than the solid floor's choice
        assert best["worst_max_error_m"] == min(
            v["worst_max_error_m"] for v in best["by_pole"].values())
        assert best["pole_rps"] > m["path_following"]["pole_rps"], law
        rigid = m["limits"]["path_following"]["truth"][law]
        assert best["worst_max_error_m"] < 0.5 * rigid["max_error_m"], law


def test_the_headline_gains_come_from_the_rigid_ground_search_never_from_the_oracle(quick):
    """§3.1 set the gains on a solid floor: the headline pole is the rigid-ground search's
    best, whatever the oracle finds on the slope, and the oracle's laps on the env's
    observation at that pole are the headline laps themselves."""
    result, _ = quick
    pf = result["metrics"]["path_following"]
    search = pf["rigid_ground_rmse_m_by_pole"]
    assert f"{pf['pole_rps']:g}" == min(search, key=lambda p: search[p])
    oracle = result["metrics"]["limits"]["path_following"]["oracle_gain"]
    assert oracle["poles_rps"] == list(result["settings"]["oracle_poles_rps"])
    for law, run in (("feedback_gyrodometry", "feedback_gyrodometry"),
                     ("feedforward_slip_compensated", "feedforward")):
        best = oracle["observation"][law]
        assert best["laps_run"] == result["metrics"]["laps_run"]
        at_headline = best["by_pole"][f"{pf['pole_rps']:g}"]
        assert at_headline["mean_error_m"] == pytest.approx(pf[run]["mean_error_m"])
        assert at_headline["completed"] == pf[run]["completed"]


def test_target_endo_n_is_within_0_05_of_the_paper_at_each_tilt(quick):
    """Paper 0.832 / 0.817 / 0.824 at 0 / 8 / 15°, n identified as §2.4 did, from every
    rotation run of a tilt. Quick run: 0.852 / 0.841 / 0.827. Fitted per turning direction n
    still splits on the slope (0.58 uphill / 1.12 downhill at 8°, 0.42 / 1.29 at 15°,
    metrics.endo_n_by_direction) and Eq. 8 fits the true slips with R² 0.96 / 0.77 / 0.47
    (metrics.limits.endo_r2): the pooled n meets the paper's, the simulated tracks' uphill /
    downhill asymmetry is not the paper's. Fitted on the training two-thirds alone
    (metrics.endo_n_training, the odometry's n) it depends on the runs held out: 0.834 /
    0.774 / 0.905."""
    assert quick[0]["metrics"]["targets_met"]["endo_n_within_0.05_paper_at_each_tilt"]


@pytest.mark.xfail(strict=True, reason=(
    "paper: 0.18 of gyrodometry; the track model on toyoura_sand 0.42 counter-clockwise and "
    "0.62 clockwise (quick; full 0.67 / 0.78). Counter-clockwise / clockwise, "
    "metrics.limits.odometry_ratio_to_gyrodometry_by_direction, quick (full): the true slip "
    "angle in place of Eq. 9 leaves 0.40 / 0.50 (0.54 / 0.63), Endo's slip ratios; the true "
    "track slips with Eq. 9's β 0.16 / 0.35 (0.38 / 0.42), Eq. 9's β; both true 0.03 / 0.04 "
    "(0.04 / 0.09), the gyro's heading error. Endo's n per tilt and turning direction "
    "(training runs, metrics.odometry_rmse_ratio_endo_n_by_direction) gives 0.44 / 0.47 "
    "(0.91 / 0.50): worse turning uphill, better downhill, so the odometry keeps the pooled "
    "n. Eq. 8 fits the true slips with R² 0.47 at 15° (every rotation run): the grade's "
    "common-mode slip shifts the ratio of the two tracks' slips (only 3 % of the 15° rotation "
    "samples go as far as breaking Eq. 8's sign rule, "
    "metrics.limits.endo_common_mode_share). With each shear component from its own "
    "displacement where the soil deforms (track_shear_law='decoupled', quick): 0.25 / 0.41 "
    "with K = 28.3 mm, 0.28 / 0.52 with K = 47 mm (seed 1: 0.29 / 0.38), R² 0.91 / 0.80 / "
    "0.72 and 0.89 / 0.71 / 0.67. Cross-validated by run (3 folds, every run held out once, "
    "metrics.odometry_rmse_ratio_cross_validated) 0.45 / 0.68 (full 0.47 / 0.61): not the "
    "split's luck. Started facing downhill (metrics.limits.fall_line_start, the other reading "
    "of §2.3's field) 0.24 / 0.24 (full 0.25 / 0.15), but Endo's n is then 0.85 / 1.50 / "
    "2.06 at 0 / 8 / 15° against the paper's 0.83 / 0.82 / 0.82. The decoupled law with both "
    "moduli calibrated on the paper's n (tracked_patako_decoupled, full run: n 0.83 / 0.82 / "
    "0.81) gives 0.34 / 0.54 (cross-validated 0.33 / 0.48)"))
def test_target_slip_compensated_rmse_is_at_most_0_4_of_gyrodometry_both_ways(quick):
    assert quick[0]["metrics"]["targets_met"][
        "slip_compensated_rmse_le_0.4_gyrodometry_both_directions"]


def test_target_feedforward_halves_the_gyrodometry_feedback_error(quick):
    """The paper's comparison (9.1 -> 1.3 cm): Eq. 10 on slip-compensated odometry against
    Eq. 9 on gyrodometry, whole laps. Quick run: 13.8 against 27.8 cm, a ratio of 0.496, met
    by a hair (full run: 13.2 against 27.8 cm, 0.476)."""
    assert quick[0]["metrics"]["targets_met"]["feedforward_mean_le_0.5_feedback_gyrodometry"]


@pytest.mark.xfail(strict=True, reason=(
    "paper: three laps each with both laws; the track model on toyoura_sand completes 0/3 with "
    "either inside the env's 0.1 m corridor (quick and full): whole-lap maximum "
    "errors 0.64 m (Eq. 9 on gyrodometry) and 0.42 m (Eq. 10), averaged over the laps. The "
    "gains are set on a solid floor as the paper did, where the search is flat (lap RMSE "
    "1.11-1.47 cm over 0.15-1 rad/s) and takes the slowest pole, 0.15 rad/s; steered on the "
    "true pose and β those gains stray 0.25 m (Eq. 9) and 0.22 m (Eq. 10), the true slip "
    "angle swinging 46° (5-95 %) around the lap. The oracle gain "
    "(metrics.limits.path_following.oracle_gain: each law's best triple pole of 0.15-3 rad/s "
    "on the lap's own true maximum error, full run; quick grid 0.15/2) steered on the truth "
    "completes both laws' laps: Eq. 9 at 3 rad/s, max 5.3 cm (quick: 2 rad/s, 6.9 cm), Eq. "
    "10 at 2 rad/s, 3.9 cm (quick the same); the vehicle can hold the circle. On the env's "
    "observations (3 seeds) no pole of the grid completes a lap: the best is the rigid-ground "
    "0.15 rad/s itself, worst-lap maximum 64.1 cm (Eq. 9 on gyrodometry) and 46.8 cm (Eq. 10 "
    "on slip-compensated; quick 43.9 cm), faster poles 51-103 cm: the odometry's error, not "
    "the vehicle or the gains, keeps the laps out of the corridor. With each shear component "
    "from its own displacement where the soil deforms (track_shear_law='decoupled', quick; "
    "the same 0.15 rad/s gains from concrete, where the resultant law stays), 0/3 laps too: "
    "Eq. 9 on gyrodometry 26.7 cm, Eq. 10 23.1 cm with K = 28.3 mm (31.4 and 25.2 cm with K = "
    "47 mm), and steered on the truth 12.1 / 12.2 cm (11.3 / 10.8 cm)"))
def test_target_every_lap_is_completed_with_both_laws(quick):
    assert quick[0]["metrics"]["targets_met"]["every_lap_completed_both_laws"]


def test_figures_and_the_fitted_model_are_saved(quick):
    _, out = quick
    for name in ("fig4_endo_n", "fig5_slip_angle", "fig6_odometry", "fig8_circle"):
        assert (out / f"{name}.png").stat().st_size > 10_000
    saved = json.loads((out / "slip_model.json").read_text())
    model = SlipAngleModel.from_dict(saved["beta_model"])
    assert len(model.coef) == 4 and saved["n"] > 0.0


def test_the_results_page_holds_the_command_the_table_the_limits_and_the_figures(quick):
    result, out = quick
    page = (out / "docs" / "yamauchi.md").read_text()
    assert (f"`slipenv reproduce yamauchi --vehicle tracked_patako_wong_chiang --soil "
            f"toyoura_sand --quick --seed 0 --docs {out / 'docs'}`") in page
    n15 = result["metrics"]["endo_n"]["15"]
    assert f"| Endo n, tilt 15° [95 % CI] | 0.824 | {n15:.3f} [" in page  # §2.4
    training = result["metrics"]["endo_n_training"]
    assert f"| ↳ same, training runs only (the odometry's and circle's n), tilt 0/8/15° | - | " \
           f"{training['0']:.3f} / {training['8']:.3f} / {training['15']:.3f} |" in page
    ratio = result["metrics"]["limits"]["odometry_ratio_to_gyrodometry"]
    cw = result["metrics"]["limits"]["odometry_ratio_to_gyrodometry_by_direction"]["cw"]
    assert f"| limit: slip-compensated with the true β, RMSE / gyrodometry, ccw / cw | - | " \
           f"{ratio['slip_compensated_true_beta']:.2f} / {cw['slip_compensated_true_beta']:.2f}" \
           in page
    ratios = result["metrics"]["odometry_rmse_ratio"]
    split = result["metrics"]["odometry_rmse_ratio_endo_n_by_direction"]
    assert f"| odometry RMSE slip-compensated / gyrodometry, held-out runs, ccw / cw | 0.18 | " \
           f"{ratios['ccw']:.2f} / {ratios['cw']:.2f} |" in page
    assert f"| ↳ same, Endo n per tilt and turning direction (training runs, Eq. 9 refitted on " \
           f"its regressors) | - | {split['ccw']:.2f} / {split['cw']:.2f} |" in page
    assert "**Endo's n per turning direction: measured beside, not used.**" in page
    truth_ff = result["metrics"]["limits"]["path_following"]["oracle_gain"]["truth"][
        "feedforward"]
    assert (f"oracle gain (best triple pole of 0.15-2 rad/s on the laps' max error), Eq. 10 "
            f"steering on the truth | - | pole {truth_ff['pole_rps']:g} rad/s: mean "
            f"{100 * truth_ff['mean_error_m']:.1f}, worst-lap max "
            f"{100 * truth_ff['worst_max_error_m']:.1f} cm, 1/1 laps |") in page
    assert ("With the best gain of an oracle grid (triple poles 0.15, 2 rad/s, chosen per "
            "law on the laps' own true maximum error") in page
    assert (f"Eq. 10 at {truth_ff['pole_rps']:g} rad/s, max "
            f"{100 * truth_ff['worst_max_error_m']:.1f} cm, 1/1 lap)") in page
    for name in ("fig4_endo_n", "fig5_slip_angle", "fig6_odometry", "fig8_circle"):
        assert f"(img/yamauchi/{name}.png)" in page
        assert (out / "docs" / "img" / "yamauchi" / f"{name}.png").is_file()
    assert "{" not in page


def test_the_shipped_model_is_what_the_tracked_env_observes():
    kwargs = yamauchi_observation()
    assert kwargs["estimator"] == "slip_compensated"
    model = SlipAngleModel.from_dict(kwargs["estimator_kwargs"]["beta_model"])
    assert model.train_runs and kwargs["estimator_kwargs"]["n"] > 0.0
    assert yamauchi.MODEL_FILE.is_file()
