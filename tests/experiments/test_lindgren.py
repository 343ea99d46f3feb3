"""`slipenv reproduce lindgren --quick`: the JSON contract of issue #3 and its targets, from a
real run; the offline filter passes and the helpers on their own."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from slipenv.contracts.frame import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren.ekf import LindgrenEKF, LindgrenNoise, Scheme
from slipenv.experiments import experiment, lindgren
from slipenv.experiments.lindgren import report
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
    """The quick experiment, seed 0, as the CLI runs it (about 35 s on 2 cores)."""
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
    """Issue #3: slip model <= 0.3 x no slip model after the laser cut; scheme 4 deviation
    <= 0.7 x scheme 3; scheme 4's NIS closer to the band; slip model within 1.5 x oracle."""
    result, doc, _ = quick
    m = doc["metrics"]
    drop, dev = m["dropout_final_error_m"], m["mean_deviation_m"]
    assert drop["slip_model"] <= 0.3 * drop["no_slip_model"]
    assert dev["scheme4"] <= 0.7 * dev["scheme3"]
    band = m["nis"]["band"]
    assert report.nis_distance(m["nis"]["scheme4"], band) < report.nis_distance(
        m["nis"]["scheme3"], band)
    assert drop["slip_model"] <= 1.5 * drop["oracle"]
    assert all(t["met"] for t in result["targets"].values())
    # whiteness (Table 2): the slip model's innovations are white, scheme 3's are biased
    assert abs(m["autocorr_mean"]["scheme4"]) < 0.02 < 0.1 < m["autocorr_mean"]["scheme3"]
    assert m["autocorr_share_inside"]["scheme4"] > 0.9 > m["autocorr_share_inside"]["scheme3"]


def test_truth_side_metrics_and_plots(quick) -> None:
    """What only a simulation has: true errors (scheme 4 near the oracle) and soil truth."""
    _, doc, out = quick
    c = doc["metrics"]["circles"]
    assert c["true_error_mean_m"]["scheme4"] < 0.1 < c["true_error_mean_m"]["scheme3"]
    assert c["true_error_mean_m"]["oracle"] <= c["true_error_mean_m"]["scheme4"]
    assert c["soil_true"]["R_w_m"] == [0.283, 0.287]  # Lindgren §3.2, on soil
    drives = doc["metrics"]["dropout"]["final_error_m_per_drive"]
    assert len(drives["scheme4"]) == lindgren.QUICK.dropout_drives
    for name in ("paths.png", "dropout.png", "autocorrelation.png"):
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
