"""`slipenv reproduce lindgren --quick`: the JSON contract and its targets, from a
real run; the offline filter passes and the helpers on their own."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from slipenv.contracts.frame import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren.ekf import LindgrenEKF, LindgrenNoise, OracleSoil, Scheme
from slipenv.experiments import experiment, lindgren
from slipenv.experiments.lindgren import report
from slipenv.experiments.lindgren.calibration import effective_radius_m, radius_from_recording
from slipenv.experiments.lindgren.metrics import torque_slip
from slipenv.experiments.lindgren.recording import Recording
from slipenv.experiments.lindgren.report import finite
from slipenv.paths import path_by_name

REQUIRED = {
    "mean_deviation_m": {"scheme3", "scheme4"},
    "nis": {"scheme3", "scheme4", "band"},
    "autocorr_mean": {"scheme3", "scheme4"},
    "dropout_final_error_m": {"no_slip_model", "slip_model", "oracle"},
}


@pytest.fixture(scope="module")
def quick(tmp_path_factory) -> tuple[dict, dict, object]:
    """The quick experiment, seed 0, as the CLI runs it: headline and robust block (about
    80 s on 2 cores)."""
    out = tmp_path_factory.mktemp("lindgren")
    result = experiment("lindgren")(quick=True, out_dir=str(out), json_path=str(out / "r.json"),
                                    seed=0, progress=False, docs_dir=str(out / "docs"))
    return result, json.loads((out / "r.json").read_text()), out


def test_json_has_the_required_keys_and_the_papers_numbers(quick) -> None:
    _, doc, _ = quick
    for key, names in REQUIRED.items():
        assert names <= set(doc["metrics"][key]), key
        assert names <= set(doc["paper"][key]), key
    assert doc["paper"]["mean_deviation_m"] == {"scheme3": 0.243, "scheme4": 0.127}  # Table 1
    assert doc["paper"]["nis"]["band"] == [1.8831, 2.1204]  # Eq. 44, K = 1099
    assert doc["paper"]["dropout_final_error_m"]["slip_model"] == 0.21  # Fig. 7
    lo, hi = doc["metrics"]["nis"]["band"]
    assert 1.8 < lo < 2.0 < hi < 2.2  # exact 95 % band for K ~ 900, n_z = 2
    assert all(isinstance(v, float) and v >= 0.0
               for v in doc["metrics"]["dropout_final_error_m"].values())
    assert doc["config"]["quick"] is True and doc["config"]["steered_by"] == "scheme 1"


def test_quick_run_meets_the_targets(quick) -> None:
    """The targets: slip model <= 0.3 x no slip model after the laser cut; scheme 4 deviation
    <= 0.7 x scheme 3; scheme 4's NIS closer to the band (1.5 x oracle: the next tests)."""
    result, doc, _ = quick
    m = doc["metrics"]
    drop, dev = m["dropout_final_error_m"], m["mean_deviation_m"]
    assert drop["slip_model"] <= 0.3 * drop["no_slip_model"]
    assert dev["scheme4"] <= 0.7 * dev["scheme3"]
    band = m["nis"]["band"]
    assert report.nis_distance(m["nis"]["scheme4"], band) < report.nis_distance(
        m["nis"]["scheme3"], band)
    assert all(t["met"] for k, t in result["targets"].items() if "oracle" not in k)
    # whiteness (Table 2): the slip model's innovations are white, scheme 3's are biased
    assert abs(m["autocorr_mean"]["scheme4"]) < 0.02 < 0.1 < m["autocorr_mean"]["scheme3"]
    assert m["autocorr_share_inside"]["scheme4"] > 0.9 > m["autocorr_share_inside"]["scheme3"]


@pytest.mark.xfail(strict=True, reason=(
    "a target missed on the current wheel-soil injection (straight driving at "
    "~87 N m per wheel, ~11 % slip): 50 s of bearings (one turn) leave each side's split of "
    "R_w and k_s unlearnt (at steady torque only R_w (1 - T/k_s) is observable), and the "
    "left/right effective-radius error becomes heading error after the cut; with the cut at "
    "twice the time scheme 4 is within 1.5 x the oracle (next test)"))
def test_slip_model_within_one_and_a_half_oracle_after_the_cut(quick) -> None:
    drop = quick[1]["metrics"]["dropout_final_error_m"]
    assert drop["slip_model"] <= 1.5 * drop["oracle"]


def test_with_more_bearing_time_the_slip_model_reaches_the_oracle(quick) -> None:
    """The cause of the miss above: with the laser cut at twice the time, scheme 4 is within
    1.5 x the oracle, so the slip model has no bias the oracle lacks, only learning time."""
    final = quick[1]["metrics"]["dropout"]["final_error_m"]
    assert final["scheme4_cut_x2"] <= 1.5 * final["oracle_cut_x2"]
    assert final["scheme4_cut_x2"] < 0.5 * final["scheme4"]


def test_truth_side_metrics_and_plots(quick) -> None:
    """What only a simulation has: true errors (scheme 4 near the oracle) and soil truth."""
    _, doc, out = quick
    c = doc["metrics"]["circles"]
    assert c["true_error_mean_m"]["scheme4"] < 0.1 < c["true_error_mean_m"]["scheme3"]
    assert c["true_error_mean_m"]["oracle"] <= c["true_error_mean_m"]["scheme4"]
    assert c["soil_true"]["R_w_m"] == [0.283, 0.287]  # Lindgren §3.2, on soil
    drives = doc["metrics"]["dropout"]["final_error_m_per_drive"]
    assert len(drives["scheme4"]) == lindgren.QUICK.dropout_drives
    for name in ("paths.png", "dropout.png", "autocorrelation.png", "paths_robust.png",
                 "dropout_robust.png"):
        assert (out / name).stat().st_size > 10_000


def test_the_results_page_holds_the_command_the_table_and_the_figures(quick) -> None:
    result, _, out = quick
    page = (out / "docs" / "lindgren.md").read_text()
    assert f"`slipenv reproduce lindgren --quick --seed 0 --docs {out / 'docs'}`" in page
    assert "| mean deviation from scheme 1 [m], scheme3 | 0.243 |" in page  # Table 1
    slip = result["metrics"]["dropout_final_error_m"]["slip_model"]
    assert f"| final position error [m], slip_model | 0.21 | {slip:.4g} |" in page
    for name in ("paths", "dropout", "autocorrelation"):
        assert f"(img/lindgren/{name}.png)" in page
        assert (out / "docs" / "img" / "lindgren" / f"{name}.png").stat().st_size > 10_000
    assert "{" not in page  # every placeholder filled


def test_robust_block_has_the_headline_keys(quick) -> None:
    """``metrics.robust`` has the same keys as the headline metrics."""
    _, doc, _ = quick
    m = doc["metrics"]
    robust = m["robust"]
    assert set(robust) == set(m) - {"robust"}
    for key, value in robust.items():
        if key in ("circles", "dropout"):
            assert set(m[key]) <= set(value) | {"bearings_gated"}, key
        else:
            assert set(value) == set(m[key]), key
    assert set(doc["targets_robust"]) == set(doc["targets"])
    assert robust["dropout"]["seeds"] == m["dropout"]["seeds"]  # the same drives


def test_robust_block_changes_world_noise_and_radius(quick) -> None:
    """Curved law in the world, the estimator's default soil noise, a measured radius."""
    _, doc, _ = quick
    rc = doc["config"]["robust"]
    assert rc["force_model"] == "janosi"
    defaults = LindgrenNoise()
    assert rc["soil_noise"] == {"radius_var_per_m": defaults.radius_var_per_m,
                                "k_s_rel_var_per_m": defaults.k_s_rel_var_per_m}
    cal = rc["calibration"]
    true_r = np.mean(doc["metrics"]["robust"]["circles"]["soil_true"]["R_w_m"])
    assert cal["radius_m"] == pytest.approx(true_r * (1.0 - cal["slip_vs_true_radius"]))
    assert 0.0 < cal["slip_vs_true_radius"] < 0.5  # driving torque > 0: the wheels slip
    # the curved law is softer than its zero-slip slope at any torque > 0
    assert cal["k_s_secant_nm"] < min(doc["metrics"]["robust"]["circles"]["soil_true"]["k_s"])
    page = (quick[2] / "docs" / "lindgren.md").read_text()
    assert "## Robustness: a world that is not the filter's model" in page
    head = doc["metrics"]["dropout_final_error_m"]["slip_model"]
    slip = doc["metrics"]["robust"]["dropout_final_error_m"]["slip_model"]
    assert f"| final position error [m], slip_model | 0.21 | {head:.4g} | {slip:.4g} |" in page


def test_effective_radius_is_distance_over_wheel_angle() -> None:
    """A wheel of radius 0.3 m rolling 5 m without slip turns 5/0.3 rad."""
    assert effective_radius_m(5.0, [5.0 / 0.3]) == pytest.approx(0.3, rel=1e-12)
    assert effective_radius_m(5.0, [5.0 / 0.29, 5.0 / 0.31]) == pytest.approx(
        5.0 / np.mean([5.0 / 0.29, 5.0 / 0.31]))
    for bad in ((0.0, [1.0]), (1.0, [0.0]), (1.0, [math.nan]), (-1.0, [1.0])):
        with pytest.raises(ValueError):
            effective_radius_m(*bad)


def _kinematic_recording(radius: float = 0.2851) -> Recording:
    """Quantised encoders (285 counts/rad) of two slip-free wheels of ``radius`` on a 6 m
    straight: 0.25 m/s² to 0.5 m/s, then constant speed."""
    cpr, dt = 285.0, 0.05
    t = np.arange(0.0, 14.0, dt)
    s = np.where(t < 2.0, 0.125 * t**2, 0.5 + 0.5 * (t - 2.0))  # 0.25 m/s² to 0.5 m/s
    s = np.minimum(s, 6.0)
    counts = np.floor(s / radius * cpr).astype(np.int64)
    frames = [SensorFrame(float(tk), np.array([c, c]), np.zeros(2)) for tk, c in zip(
        t, counts, strict=True)]
    geom = OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=cpr)
    truth = np.column_stack([s, np.zeros_like(s), np.zeros_like(s)])
    return Recording(path=path_by_name("straight", length_m=6.0), frames=frames, t_s=t,
                     truth=truth, s_true_m=s,
                     oracle=OracleSoil((radius, radius), (700.0, 700.0)),
                     params=LindgrenNoise(), geometry=geom, beacons_xy=np.zeros((0, 2)))


def test_calibration_recovers_the_rolling_radius_of_a_kinematic_drive() -> None:
    """Quantised encoders on a slip-free 6 m straight with a start-up: R_eff = the true radius
    (within the quantisation, 1 count in ~4000), the start-up left out by the marks."""
    radius = 0.2851
    rec = _kinematic_recording(radius)
    cal = radius_from_recording(rec, settle_m=1.0)
    assert cal["radius_m"] == pytest.approx(radius, rel=5e-4)
    assert cal["distance_m"] == pytest.approx(4.0, abs=0.03)
    assert abs(cal["slip_vs_true_radius"]) < 5e-4
    with pytest.raises(ValueError, match="too short"):
        radius_from_recording(rec, settle_m=3.5)


def test_calibration_on_a_simulated_drive_recovers_the_rolling_radius(short_drive) -> None:
    """On Lindgren's linear law the wheels slip s = T/k_s (Eq. 24), so the measured effective
    radius is R_w (1 - T/k_s) with R_w the true rolling radius (Eq. 25): undoing that slip
    recovers R_w to within 1 % of the slip's own size."""
    cal = radius_from_recording(short_drive, settle_m=1.0)
    k_s = np.mean(short_drive.oracle.k_s)
    slip = float(np.mean(cal["mean_torque_nm"])) / k_s
    assert 0.005 < slip < 0.3
    r_true = float(np.mean(short_drive.oracle.wheel_radius_m))
    assert cal["radius_m"] / (1.0 - slip) == pytest.approx(r_true, rel=0.01 * slip + 2e-4)
    assert abs(cal["radius_m"] - r_true) > 0.5 * slip * r_true  # the slip is really there


def test_linear_world_has_one_torque_slip_gradient(short_drive) -> None:
    """On Lindgren's linear law T = k_s s (Eq. 24): the secant T/s of the simulated straight
    drive is the oracle's k_s (what the curved world of the robust block does not have)."""
    straight = torque_slip(short_drive)["straight"]
    assert straight["k_s_secant_nm"] == pytest.approx(np.mean(short_drive.oracle.k_s), rel=0.1)
    assert 0.0 < straight["slip"] < 0.3


def test_variant_and_setting_options_are_validated() -> None:
    from slipenv.experiments.lindgren.settings import ROBUST, Setting, Variant

    with pytest.raises(ValueError, match="Variant.scheme"):
        Variant("scheme5")
    with pytest.raises(ValueError, match="Variant.noise"):
        Variant("scheme4", {"no_such_noise": 1.0})
    with pytest.raises(ValueError, match="Variant.secant_k_s"):
        Variant("scheme4", secant_k_s=True)
    with pytest.raises(ValueError, match="Variant.cut_factor"):
        Variant("oracle", cut_factor=0.0)
    with pytest.raises(ValueError, match="Setting.variants"):
        Setting("x", None, {}, measured_radius=False, variants={"scheme4": Variant("scheme4")})
    assert "oracle_secant" in ROBUST.circle_filters
    assert "scheme4_cut_x2" not in lindgren.HEADLINE.circle_filters  # only moves the cut
    with pytest.raises(ValueError, match="calibration"):  # the secant needs a calibration
        lindgren.run_filter(_kinematic_recording(), "oracle_secant", variants=ROBUST.variants)


@pytest.fixture(scope="module")
def short_drive():
    """8 s straight, recorded as the experiment records its drives."""
    return lindgren.record(path_by_name("straight", length_m=4.0, speed_mps=0.5), seed=3)


def test_offline_pass_cuts_bearings_and_removes_inertial_data(short_drive) -> None:
    rec = short_drive
    assert len(rec.frames) == len(rec.truth) == len(rec.t_s)
    run = lindgren.run_filter(rec, "scheme4", cut_s=4.0, inertial=False)
    times = [t for t, _, _ in run.ekf.history["bearing"]]
    assert times and max(times) <= 4.0
    assert run.ekf.history["gyro"] == [] and run.ekf.history["acc"] == []
    assert run.ekf.skipped["gyro_nan"] == len(rec.frames) - 1
    assert run.est.shape == (len(rec.frames), 3) and run.P.shape == (len(rec.frames), 3, 3)
    full = lindgren.run_filter(rec, "scheme4")
    assert len(full.ekf.history["gyro"]) == len(rec.frames) - 1
    oracle = lindgren.run_filter(rec, "oracle")
    assert oracle.ekf.oracle == rec.oracle and oracle.ekf.n == 9


def test_filters_use_the_papers_ungated_association_and_uniform_soil(short_drive) -> None:
    """FILTER departs from the estimator defaults in two settings; each variant puts one back."""
    assert short_drive.params.bearing_gate_prob == 1.0
    assert short_drive.params.radius_var_per_m == lindgren.FIELD_NOISE["radius_var_per_m"]
    gated = lindgren.run_filter(short_drive, "scheme3_gated")
    assert gated.ekf.scheme == Scheme.ALL_NO_SLIP
    assert gated.ekf.params.bearing_gate_prob == LindgrenNoise().bearing_gate_prob
    soil = lindgren.run_filter(short_drive, "scheme4_default_soil_noise").ekf.params
    assert soil.radius_var_per_m == LindgrenNoise().radius_var_per_m
    assert soil.k_s_rel_var_per_m == LindgrenNoise().k_s_rel_var_per_m
    assert soil.bearing_gate_prob == 1.0


def test_gate_probability_one_disables_the_bearing_gate() -> None:
    """Lindgren §2.4: nearest-innovation association alone; a bearing far from every beacon
    is still associated and used (the default gate would reject it)."""
    beacons = np.array([[10.0, 0.0], [0.0, 10.0], [-10.0, 0.0], [0.0, -10.0]])
    geom = OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=285.0)
    start = SensorFrame(0.0, np.zeros(2), np.zeros(2))
    outlier = SensorFrame(0.05, np.zeros(2), np.zeros(2), beacon_bearings_rad=np.array([0.6]),
                          beacon_times_s=np.array([0.05]))
    used = {}
    for prob in (0.999, 1.0):
        ekf = LindgrenEKF(geom, 1, LindgrenNoise(bearing_gate_prob=prob), beacons_xy=beacons)
        ekf.reset(0.0, 0.0, 0.0, start)
        ekf.update(outlier)
        used[prob] = len(ekf.history["bearing"])
    assert used == {0.999: 0, 1.0: 1}
    with pytest.raises(ValueError, match="bearing_gate_prob"):
        LindgrenNoise(bearing_gate_prob=1.5)


def test_same_seed_same_recording(short_drive) -> None:
    again = lindgren.record(path_by_name("straight", length_m=4.0, speed_mps=0.5), seed=3)
    np.testing.assert_array_equal(again.truth, short_drive.truth)
    np.testing.assert_array_equal(again.frames[-1].enc_counts, short_drive.frames[-1].enc_counts)


def test_nis_distance_and_targets() -> None:
    assert report.nis_distance(2.0, [1.9, 2.1]) == 0.0
    assert report.nis_distance(1.6, [1.9, 2.1]) == pytest.approx(0.3)
    assert report.nis_distance(5.0, [1.9, 2.1]) == pytest.approx(2.9)
    m = {"mean_deviation_m": {"scheme3": 0.4, "scheme4": 0.3},
         "nis": {"scheme3": 2.5, "scheme4": 1.0, "band": [1.9, 2.1]},
         "dropout_final_error_m": {"no_slip_model": 2.0, "slip_model": 0.5, "oracle": 0.4}}
    met = {k: t["met"] for k, t in report.targets(m).items()}
    assert met == {"slip_model <= 0.3 no_slip_model": True,
                   "scheme4 deviation <= 0.7 scheme3": False,
                   "scheme4 NIS closer to band than scheme3": False,
                   "slip_model <= 1.5 oracle": True}


def test_json_sanitiser_makes_standard_json() -> None:
    doc = finite({"a": math.nan, "b": [np.float64(1.5), np.int64(2), math.inf], "c": None})
    assert doc == {"a": None, "b": [1.5, 2, None], "c": None}
    json.dumps(doc, allow_nan=False)
