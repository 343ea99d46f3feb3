"""``slipenv reproduce yamauchi --quick``: the JSON the command writes, and what it shows.

The quick run (fewer repetitions, the same experiments) is run once per module through the
command line, as a user would: in the default world, the Wong-Chiang track model on
``dry_sand``.
"""

from __future__ import annotations

import json

import pytest

from slipenv.cli import main
from slipenv.envs.registration import yamauchi_observation
from slipenv.estimators.skid_steer.identification import SlipAngleModel
from slipenv.experiments import yamauchi

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


def test_the_command_runs_the_wong_chiang_track_model_on_dry_sand_by_default(quick):
    settings = quick[0]["settings"]
    assert (settings["vehicle"], settings["soil"]) == ("tracked_patako_wong_chiang", "dry_sand")


def test_save_model_outside_the_env_presets_world_is_refused_before_any_work(tmp_path):
    with pytest.raises(ValueError, match="vehicle='tracked_patako', soil='toyoura_sand'"):
        yamauchi.run(quick=True, out_dir=str(tmp_path), save_model=str(tmp_path / "m.json"),
                     progress=False)
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
    # Steered on the truth every lap completes; on odometry (even with the true β) the track
    # model's quick-run laps leave the 0.5 m corridor (0/3), counted, not hidden.
    truth = lim["path_following"]["truth"]
    assert truth["feedback"]["completed"] == len(truth["feedback"]["per_seed_mean_error_m"])
    # fed the truth the law beats feedback (0.68 per-wheel, 0.80 with the track model)
    assert lim["path_following"]["truth"]["feedforward_to_feedback_mean"] < 0.9
    assert set(lim["endo_r2"]) == TILTS and all(v <= 1.0 for v in lim["endo_r2"].values())
    assert set(lim["endo_common_mode_share"]) == TILTS
    assert all(0.0 <= v <= 1.0 for v in lim["endo_common_mode_share"].values())


@pytest.mark.xfail(strict=True, reason=(
    "Endo's n: paper 0.832 / 0.817 / 0.824 at 0 / 8 / 15°; the Wong-Chiang track model on "
    "dry_sand gives 0.818 / 0.764 / 0.917 (quick; full 0.825 / 0.769 / 0.694): within 0.05 on "
    "flat ground, not on the slopes, where Eq. 8 fits the true slips with R² 0.83 (8°) and "
    "0.48 (15°; full 0.82, 0.33) against 0.97 on flat ground, and n fitted per turning "
    "direction splits into 0.58 uphill / 1.03 downhill at 8° and 0.32 / 1.35 at 15° "
    "(metrics.limits.endo_r2, metrics.endo_n_by_direction): on the slope the two tracks' slip "
    "ratio no longer follows a power of their speed ratio, and differs turning uphill and "
    "downhill, which Eq. 8's one n cannot express"))
def test_target_endo_n_is_within_0_05_of_the_paper_at_each_tilt(quick):
    assert quick[0]["metrics"]["targets_met"]["endo_n_within_0.05_paper_at_each_tilt"]


@pytest.mark.xfail(strict=True, reason=(
    "paper: 82 % better; the Wong-Chiang track model on dry_sand 47 % (quick and full). With "
    "the true slip angle in place of Eq. 9 the odometry is still 0.52 (quick; full 0.44) of "
    "gyrodometry (metrics.limits): what remains is Endo's slip ratios, from an Eq. 8 that "
    "fits the true slips with R² 0.48 at 15° (full 0.33). Not a common-mode slip: no training "
    "sample breaks Eq. 8's sign rule (metrics.limits.endo_common_mode_share)"))
def test_target_slip_compensated_rmse_is_at_most_0_4_of_gyrodometry(quick):
    assert quick[0]["metrics"]["targets_met"]["slip_compensated_rmse_le_0.4_gyrodometry"]


@pytest.mark.xfail(strict=True, reason=(
    "paper: 9.1 -> 1.3 cm; the Wong-Chiang track model on dry_sand, full run: 9.7 -> 12.3 cm "
    "on slip-compensated odometry (ratio 1.27). On odometry with the true β the ratio is 0.89, "
    "steering on the true pose and β with the rigid-ground gains 0.80 (metrics.limits): the "
    "odometry's error (steered on slip-compensated odometry 5/5 laps with Eq. 9, 1/5 with the "
    "feed-forward in the 0.5 m corridor), and a true slip angle that swings 31° (5-95 %) "
    "around the lap, faster than the rigid-ground gains follow"))
def test_target_feedforward_halves_the_feedback_error(quick):
    assert quick[0]["metrics"]["targets_met"]["feedforward_mean_le_0.5_feedback"]


def test_figures_and_the_fitted_model_are_saved(quick):
    _, out = quick
    for name in ("fig4_endo_n", "fig5_slip_angle", "fig6_odometry", "fig8_circle"):
        assert (out / f"{name}.png").stat().st_size > 10_000
    saved = json.loads((out / "slip_model.json").read_text())
    model = SlipAngleModel.from_dict(saved["beta_model"])
    assert len(model.coef) == 4 and saved["n"] > 0.0


def test_the_results_page_holds_the_command_the_table_the_limits_and_the_figures(quick):
    result, out = quick
    page = (out / "docs" / "yamauchi_wong_chiang.md").read_text()
    assert (f"`slipenv reproduce yamauchi --vehicle tracked_patako_wong_chiang --soil dry_sand "
            f"--quick --seed 0 --docs {out / 'docs'}`") in page
    n15 = result["metrics"]["endo_n"]["15"]
    assert f"| Endo n, tilt 15° [95 % CI] | 0.824 | {n15:.3f} [" in page  # §2.4
    ratio = result["metrics"]["limits"]["odometry_ratio_to_gyrodometry"]
    assert f"| limit: slip-compensated with the true β, RMSE / gyrodometry | - | " \
           f"{ratio['slip_compensated_true_beta']:.2f}" in page
    for name in ("fig4_endo_n", "fig5_slip_angle", "fig6_odometry", "fig8_circle"):
        assert f"(img/yamauchi_wong_chiang/{name}.png)" in page
        assert (out / "docs" / "img" / "yamauchi_wong_chiang" / f"{name}.png").is_file()
    assert "{" not in page


def test_the_shipped_model_is_what_the_tracked_env_observes():
    kwargs = yamauchi_observation()
    assert kwargs["estimator"] == "slip_compensated"
    model = SlipAngleModel.from_dict(kwargs["estimator_kwargs"]["beta_model"])
    assert model.train_runs and kwargs["estimator_kwargs"]["n"] > 0.0
    assert yamauchi.MODEL_FILE.is_file()
