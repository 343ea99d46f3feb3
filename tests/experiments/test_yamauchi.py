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
    laws = {"feedback_gyrodometry", "feedforward_slip_compensated"}
    assert set(m["circle_mean_error_cm"]) == laws and set(m["laps_completed"]) == laws
    assert m["calibrated"] and all(isinstance(v, str) and v for v in m["calibrated"].values())


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
    assert all(0.0 <= v <= 1.0 for v in lim["endo_common_mode_share"].values())


@pytest.mark.xfail(strict=True, reason=(
    "Endo's n: paper 0.832 / 0.817 / 0.824 at 0 / 8 / 15°; the track model on toyoura_sand "
    "gives 0.834 / 0.774 / 0.905 (quick; full 0.839 / 0.777 / 0.703): within 0.05 on flat "
    "ground, not on the slopes, where Eq. 8 fits the true slips with R² 0.74 (8°) and 0.49 "
    "(15°; full 0.34) against 0.96 "
    "on flat ground, and n fitted per turning direction splits into 0.56 uphill / 1.09 "
    "downhill at 8° and 0.42 / 1.28 at 15° (metrics.limits.endo_r2, "
    "metrics.endo_n_by_direction): on the slope the simulated tracks slip differently turning "
    "uphill and downhill, so the pooled n depends on which runs it pools (15°: 0.905 quick, "
    "0.703 full, 0.806 on another 12-run set). Measured on that set (15°, 0.39 / 1.29): "
    "without slip-sinkage, compaction or side walls each moves by at most 0.04; with gravity's "
    "in-plane components cancelled on the hull (an oracle) 0.82 / 0.88, with only the component "
    "along the heading cancelled 1.19 / 0.38 (also at ground level: pitch transfer plays no "
    "part), with only the cross-slope one cancelled -0.07 / 1.68: the split is the grade along "
    "the heading, W sin 15° sin psi, carried as a common-mode slip (outer track 0.28 turning "
    "uphill, 0.07 downhill, 0.17 on flat ground at 20°/s), large because a track sliding "
    "sideways in the turn with its stress against the resultant sliding velocity develops "
    "little longitudinal force per unit slip. With each shear component from its own "
    "displacement (Ishigami et al. 2007), capped at Mohr-Coulomb (oracle, quick): n 1.03 / "
    "1.02 / 1.06, split 0.96 / 1.15 at 15°"))
def test_target_endo_n_is_within_0_05_of_the_paper_at_each_tilt(quick):
    assert quick[0]["metrics"]["targets_met"]["endo_n_within_0.05_paper_at_each_tilt"]


@pytest.mark.xfail(strict=True, reason=(
    "paper: 0.18 of gyrodometry; the track model on toyoura_sand 0.42 counter-clockwise and "
    "0.62 clockwise (quick; full 0.67 / 0.78). With the true slip angle in place of Eq. 9 the "
    "counter-clockwise odometry is still 0.40 of gyrodometry (metrics.limits): what remains is "
    "Endo's slip ratios, from an Eq. 8 that fits the true slips with R² 0.49 at 15°: the "
    "grade's common-mode slip shifts the ratio of the two tracks' slips (only 3 % of the 15° "
    "training samples go as far as breaking Eq. 8's sign rule, "
    "metrics.limits.endo_common_mode_share). With each shear component from its own "
    "displacement (Ishigami et al. 2007), capped at Mohr-Coulomb (oracle, quick): 0.17 / 0.36, "
    "R² 0.94 / 0.89 / 0.74"))
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
    "errors 0.64 m (Eq. 9 on gyrodometry) and 0.42 m (Eq. 10). Steered on the true pose and "
    "β with the same rigid-ground gains (triple pole 0.15 rad/s) the feed-forward lap still "
    "reaches 0.22 m (metrics.limits.path_following.truth): the lap misses the corridor "
    "whatever the odometry, the true slip angle swinging 46° (5-95 %) around it, faster than "
    "the rigid-ground gains follow (the firm-ground search is flat: 1.1-1.5 cm RMSE for "
    "every pole from 0.15 to 1 rad/s; with the env baseline's 0.6 rad/s, steered on the "
    "truth, the lap averages 4.9 cm with Eq. 9 and 1.9 cm with Eq. 10, "
    "tests/envs/test_tracked_env.py). With each shear component from its own displacement "
    "(Ishigami et al. 2007), capped at Mohr-Coulomb (oracle, quick), steered on the truth: "
    "3.7 cm with Eq. 9, 1.2 cm with Eq. 10 (paper 9.1 -> 1.3), still 0/3 laps on odometry"))
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
    ratio = result["metrics"]["limits"]["odometry_ratio_to_gyrodometry"]
    assert f"| limit: slip-compensated with the true β, RMSE / gyrodometry | - | " \
           f"{ratio['slip_compensated_true_beta']:.2f}" in page
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
