"""A diagnosis never prints inf or NaN, an estimate whose standard error
exceeds it is "not determined", an implausible no-ground-truth estimate is declared so, and a
failing least-squares fit is an error naming the log."""

from __future__ import annotations

import json
import re
import warnings

import numpy as np
import pytest

from slipenv.cli import main
from slipenv.diagnose import fit as fit_module
from slipenv.diagnose import proprio
from slipenv.diagnose.cli import diagnose, summary
from slipenv.diagnose.kinematic import KinematicTruth, kinematic_log
from slipenv.diagnose.numbers import better, determined, estimate, num
from slipenv.diagnose.report import markdown, write_json
from slipenv.logs import Log, LogMeta, write_log

NON_FINITE = re.compile(r"\b(inf|nan|infinity)\b", re.IGNORECASE)


def _quiet_diagnose(log):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose([log], "<kinematic>")


def _with_meta(log: Log, **vehicle) -> Log:
    data = json.loads(json.dumps(log.meta.data))
    data["vehicle"].update(vehicle)
    return Log.from_arrays(LogMeta(data), **log.signals)


@pytest.mark.parametrize(("value", "se", "ok"), [
    (0.505, 0.0002, True), (74.552, 161.127, False), (-0.01, 0.02, False),
    (1.0, float("inf"), False), (float("nan"), 0.1, False), (0.0, 0.0, True),
])
def test_an_estimate_is_determined_only_if_its_error_is_below_its_magnitude(value, se, ok):
    assert determined(value, se) is ok
    text = estimate(value, se)
    assert not NON_FINITE.search(text)
    assert ("±" in text) is ok


def test_numbers_never_print_inf_or_nan():
    for v in (float("inf"), -float("inf"), float("nan"), None, "x"):
        assert num(v) == "n/a" and better(v) == "n/a"
    assert better(-1.117) == "111.7 % worse" and better(0.25) == "25.0 % better"


def test_summary_and_markdown_of_a_report_with_non_finite_numbers_print_none_of_them():
    inf, nan = float("inf"), float("nan")
    report = {"cause": "track_width", "also": [], "parameters": {"track_width_m": [74.6, 161.1],
                                                                  "radius_left_m": [nan, inf]},
              "determined": {"track_width_m": False, "radius_left_m": False},
              "gain": {"metric": "position_rmse_m", "before": inf, "after": inf,
                       "relative": nan},
              "segments": {"count": 3, "duration_s": 3.0, "folds": 2, "fold_by": "log"},
              "candidates": [{"cause": "track_width", "score": nan, "gain_relative": nan,
                              "p_value": nan, "drift": inf, "significant": False}],
              "thresholds": {"alpha": 0.01, "min_gain": 0.02, "min_drift": 0.001},
              "consistency": {"nominal": {"nis_mean": inf, "nis_band_95": [nan, inf],
                                          "autocorrelation": [nan],
                                          "autocorrelation_band": inf}},
              "log": "x", "warnings": []}
    for text in (summary(report, 1.0), markdown(report, {}, None)):
        assert not NON_FINITE.search(text), text
        assert "not determined" in text.lower()
    assert "74.6" not in summary(report)  # not printed as a number


def test_json_report_holds_null_for_non_finite_values(tmp_path):
    path = write_json({"a": float("inf"), "b": [np.float64("nan"), 1.0]}, tmp_path / "r.json")
    assert json.loads(path.read_text()) == {"a": None, "b": [None, 1.0]}


def test_a_determined_calibration_is_flagged_determined_in_json():
    report, _ = _quiet_diagnose(kinematic_log(3, KinematicTruth(0.1, 0.1, 0.505),
                                              duration_s=60.0))
    assert report["cause"] == "track_width"
    assert report["determined"] == {"track_width_m": True}
    assert report["calibration"]["config_determined"] is True
    assert report["warnings"] == []


def test_a_wrong_nominal_geometry_is_warned_and_its_config_not_offered():
    # meta.json says 9 m between the wheels of a 0.505 m robot: whatever the fit finds is no
    # calibration of this vehicle
    log = _with_meta(kinematic_log(1, KinematicTruth(0.1, 0.1, 0.505), duration_s=60.0),
                     track_width_m=9.0)
    report, _ = _quiet_diagnose(log)
    text = summary(report, 1.0)
    assert not NON_FINITE.search(text)
    assert report["warnings"] and "meta.json" in report["warnings"][0]
    assert "track_width_m" in report["warnings"][0]
    assert report["calibration"]["config_determined"] is False
    assert "NOT determined" in text and "warning:" in text
    gain = report["gain"]["relative"]
    assert ("worse" in text) == (gain < 0)


def _gyro_only_log(seed: int, eta: float, noise: float, track_m: float = 0.57) -> Log:
    """A kinematic log without ground truth whose gyro reads eta × the wheels' yaw rate."""
    log = kinematic_log(seed, None, duration_s=60.0, track_m=track_m)
    sig = log.signals
    r, c = log.meta.wheel_radius_m, log.meta.counts_per_rad
    rate = np.gradient(np.stack([sig["enc_left"], sig["enc_right"]]) / c, sig["t"], axis=1)
    kin = r * (rate[1] - rate[0]) / track_m
    rng = np.random.default_rng(seed)
    cols = {k: v for k, v in sig.items() if not k.startswith("gt_")}
    return Log.from_arrays(log.meta, require_ground_truth=False,
                           gyro_z=eta * kin + rng.normal(0.0, noise, kin.size), **cols)


@pytest.mark.parametrize(("eta", "noise", "why"), [
    (0.0076, 0.002, "implausible"),  # W_eff ≈ 75 m on a 0.57 m track (the Husky)
    (0.0, 0.05, "not determined"),  # the gyro does not follow the wheels at all
])
def test_no_ground_truth_mode_declares_an_implausible_width_not_determined(eta, noise, why):
    result = proprio.analyse([_gyro_only_log(5, eta, noise)], "<gyro-only>")
    assert result["cause"] == "none" and result["parameters"] == {}
    assert result["determined"] == {"track_width_m": False}
    assert any(why in w for w in result["warnings"]), result["warnings"]
    text = proprio.summary(result)
    assert "not determined" in text and not NON_FINITE.search(text)


def test_no_ground_truth_mode_still_finds_a_plausible_width():
    result = proprio.analyse([_gyro_only_log(6, 0.7, 0.002)], "<gyro-only>")
    assert result["cause"] == "track_width" and result["determined"]["track_width_m"]
    w, se = result["parameters"]["track_width_m"]
    assert abs(w - 0.57 / 0.7) < max(3 * se, 0.01)
    assert result["warnings"] == []


def test_a_failing_least_squares_fit_is_an_error_naming_the_log(tmp_path, monkeypatch, capsys):
    folder = tmp_path / "run_7"
    write_log(kinematic_log(2, KinematicTruth(0.1, 0.1, 0.505), duration_s=30.0), folder)

    def broken(*args, **kwargs):
        raise ValueError("Residuals are not finite in the initial point.")

    monkeypatch.setattr(fit_module, "least_squares", broken)
    assert main(["diagnose", str(folder), "--quiet"]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "run_7" in err and "least-squares" in err and "not finite" in err


def test_a_fold_model_the_simulation_cannot_take_is_not_replayed_and_the_report_says_so():
    """The human report's PyBullet replay extends the world by each fold's fit; a fit with a
    negative torque stiffness (the bounds allow it) is refused by the world, so those
    segments have no extended replay, the note names why, and nothing prints NaN."""
    from slipenv.diagnose.fit import Fit, Problem
    from slipenv.diagnose.replay import build_segments
    from slipenv.diagnose.select import Candidate, Selection
    from slipenv.diagnose.simreplay import pybullet_overlay

    log = kinematic_log(5, None, duration_s=20.0, route="mixed")
    seg = build_segments([log])
    names = ["torque_slip.compliance_left_per_nm", "torque_slip.compliance_right_per_nm"]
    bad = Fit(("torque_slip",), names, np.array([-0.01, -0.01]), np.zeros((2, 2)), 0.0, 1)
    cand = Candidate(("torque_slip",), "pose", fold_fits=[bad])
    folds = np.zeros(len(seg), dtype=int)
    sel = Selection(cause="torque_slip", also=[], candidates=[cand], baseline={},
                    final={"pose": cand}, fits={}, folds=folds)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        sim = pybullet_overlay(log, sel, Problem.from_segments(seg))
    assert sim["segments"] > 0 and np.isfinite(sim["rmse_nominal_m"])
    # every replayed segment has an extended track, all of it missing (none was replayed)
    assert len(sim["extended"]) == sim["segments"]
    assert all(np.isnan(e).all() for e in sim["extended"])
    assert "cannot be applied to the simulation" in sim["note"]
    assert "k_s_<wheel>_nm" in sim["note"]
    assert num(sim["rmse_extended_m"]) == "n/a"


def test_the_transfer_section_judges_a_slip_law_kept_on_segments_by_material_harm():
    from slipenv.diagnose.report import transfer_markdown

    half = {"effects": ["slope_side_slip"], "error_ratio": 0.92,
            "per_part_error_ratio": [0.49, 1.03], "drift": 0.003, "turn_drift": 0.0,
            "final_position_error_m": {"before": [0.13, 0.24], "after": [0.10, 0.18]}}
    tr = {"held_out_by": "half", "parts": 2, "decision": "slope_side_slip kept",
          "tested": [{**half, "effects": ["track_width"], "makes_a_part_worse": True,
                      "makes_parts_materially_worse": True}],
          "named_cause": {**half, "makes_a_part_worse": True,
                          "makes_parts_materially_worse": True},
          "named_cause_on_segments": {**half, "makes_a_part_worse": True,
                                      "makes_parts_materially_worse": False}}
    rows = {line.split(" | ")[0]: line for line in transfer_markdown(tr) if line.startswith("| ")}
    assert rows["| slope_side_slip"].endswith("no: worse on the held-out parts |")
    assert rows["| slope_side_slip (fitted on segments)"].endswith(
        "no: not material (a part worse, by less than a material drift) |")
