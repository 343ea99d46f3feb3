"""One log of a few minutes: slow geometric drifts are named (long-horizon route), several
causes together, a clean log stays ``none``, and the calibration block reads like a config."""

from __future__ import annotations

import json
import warnings
from pathlib import Path

import numpy as np
import pytest

from slipenv.diagnose import horizon
from slipenv.diagnose.cli import diagnose
from slipenv.diagnose.kinematic import KinematicTruth, kinematic_log
from slipenv.diagnose.report import write_human_report, write_json

Z_LIMIT = 3.0
OPTIODOM = Path(__file__).resolve().parents[3] / "shared" / "data" / "real" / "optiodom-diffdrive"


def _diagnose(log):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose([log], "<kinematic>")


def _named(report) -> list[str]:
    return [report["cause"], *report["also"]]


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_one_percent_track_width_on_a_two_minute_log_is_named(seed):
    truth = KinematicTruth(0.1, 0.1, 0.505)  # nominal 0.5 m: 1 % wider
    report, _ = _diagnose(kinematic_log(seed, truth, duration_s=120.0))
    assert "track_width" in _named(report), report["candidates"]
    value, se = report["parameters"]["track_width_m"]
    assert abs(value - truth.track_width_m) <= Z_LIMIT * se + 1e-4


@pytest.mark.parametrize("seed", [21, 22, 23, 24, 25])
def test_clean_two_minute_log_gives_none(seed):
    report, _ = _diagnose(kinematic_log(seed, None, duration_s=120.0))
    assert report["cause"] == "none" and report["also"] == [], report["candidates"]


def test_two_hidden_effects_are_both_named_with_joint_covariance():
    truth = KinematicTruth(0.1, 0.1015, 0.51)  # right wheel 1.5 % larger, track 2 % wider
    report, (sel, _) = _diagnose(kinematic_log(31, truth, duration_s=120.0))
    assert {"track_width", "rolling_radius"} <= set(_named(report)), report["candidates"]
    params = report["parameters"]
    for name, true in (("track_width_m", 0.51), ("radius_right_m", 0.1015),
                       ("radius_left_m", 0.1)):
        value, se = params[name]
        assert abs(value - true) <= Z_LIMIT * se + 2e-4 * true, (name, value, se, true)
    cov = report["covariance"]["pose"]
    assert len(cov["names"]) == 3 and np.shape(cov["matrix"]) == (3, 3)
    assert np.all(np.linalg.eigvalsh(np.array(cov["matrix"])) > 0)
    # the extension carried to the simulation holds both effects
    from slipenv.diagnose.extension import parse_model

    assert {"track_width", "rolling_radius"} <= set(parse_model(report).effects)


def test_calibration_block_gives_controller_values_and_says_what_is_separable(tmp_path):
    truth = KinematicTruth(0.1, 0.1, 0.505)
    mixed, (sel, problem) = _diagnose(kinematic_log(11, truth, duration_s=120.0))
    cal = mixed["calibration"]
    ddc = cal["diff_drive_controller"]
    assert ddc["wheel_separation"] == pytest.approx(0.505, rel=2e-3)
    assert ddc["wheel_radius"] == pytest.approx(0.1, rel=2e-3)
    assert cal["separable"] is True
    assert cal["determined"]["turn_scale"][0] == pytest.approx(0.5 / 0.505, rel=2e-3)
    circle, _ = _diagnose(kinematic_log(12, truth, duration_s=120.0, route="circle"))
    assert {"track_width", "rolling_radius"} & set(_named(circle))
    assert circle["calibration"]["separable"] is False  # one way round: ratio ~ width
    # the turn scale is determined either way, and precisely
    scale, se = circle["calibration"]["determined"]["turn_scale"]
    assert abs(scale - 0.5 / 0.505) <= Z_LIMIT * se + 1e-3
    folder = write_human_report(tmp_path / "rep", mixed, sel, problem,
                                logs=[kinematic_log(11, truth, duration_s=120.0)])
    text = (folder / "report.md").read_text()
    assert "wheel_separation:" in text and (folder / "dead_reckoning.png").stat().st_size > 0
    json.loads(write_json(mixed, tmp_path / "r.json").read_text())


def test_sign_flip_is_exact_for_few_blocks():
    assert horizon.sign_flip(np.ones(10)) == pytest.approx(1 / 1024)
    assert horizon.sign_flip(-np.ones(10)) == pytest.approx(1.0)
    assert horizon.sign_flip(np.zeros(4)) == 1.0


@pytest.mark.skipif(not OPTIODOM.is_dir(), reason=(
    f"the real OptiOdom logs are not at {OPTIODOM} (they sit in shared/data/real beside the "
    "checkout; the kinematic tests above cover the method)"))
@pytest.mark.parametrize("name", ["circular_250620202119_run-05",
                                  "square_230620202144_run-06"])
def test_single_real_optiodom_drifting_run_gets_a_geometric_cause(name):
    from slipenv.logs.optiodom import list_optiodom_runs, load_optiodom_run

    run = next(r for r in list_optiodom_runs(OPTIODOM) if r.name == name)
    report, _ = _diagnose(load_optiodom_run(run))
    assert {"rolling_radius", "track_width"} & set(_named(report)), report["candidates"]
    assert report["calibration"]["wheel_separation_m"][0] == pytest.approx(0.2025, abs=0.002)
