"""A diagnosed model carried to other logs of the same robot (``slipenv diagnose --model``):
kinematic logs of one robot whose true geometry is known, logged under different headers."""

from __future__ import annotations

import json

import pytest

from slipenv.cli import main
from slipenv.diagnose.calibration import calibration
from slipenv.diagnose.carry import carried_model, score
from slipenv.diagnose.fit import Problem, fit
from slipenv.diagnose.kinematic import KinematicTruth, kinematic_log
from slipenv.diagnose.replay import build_segments
from slipenv.logs import write_log

R_M, W_M = 0.1, 0.5  # the robot's true wheel radius and the headers' track width [m]
TRUTH = KinematicTruth(R_M, R_M, 1.06 * W_M)  # its true width is 6 % above the headers'


def _width_report(log) -> dict:
    """A report naming the track width fitted on ``log``, as the diagnosis writes it."""
    problem = Problem.from_segments(build_segments([log]))
    f = fit(problem, ("track_width",))
    width, se = float(f.x[0]), float(f.cov[0, 0]) ** 0.5
    return {"cause": "track_width", "also": [], "parameters": {"track_width_m": [width, se]},
            "calibration": calibration(problem, f), "vehicle_kind": problem.seg.kind,
            "wheels": list(problem.seg.wheels)}


@pytest.fixture(scope="module")
def report() -> dict:
    return _width_report(kinematic_log(3, TRUTH, duration_s=90.0, radius_m=R_M, track_m=W_M))


def _later_logs() -> list:
    """The same robot logged twice more: under the right header radius, and under one 1.5 %
    too large (another wheel diameter written into its meta.json)."""
    return [kinematic_log(seed, TRUTH, duration_s=90.0, radius_m=r, track_m=W_M,
                          slip_sigma=0.002)
            for seed, r in ((4, R_M), (5, 1.015 * R_M))]


def test_the_carried_model_is_the_calibration_in_absolute_values(report):
    model = carried_model(report)
    assert model["rolling_radius"].left_m == model["rolling_radius"].right_m == R_M
    assert abs(model["track_width"].width_m / (1.06 * W_M) - 1.0) < 2e-3


def test_a_report_naming_no_cause_carries_nothing():
    assert carried_model({"cause": "none", "also": [], "parameters": {}}) == {}


def test_the_model_of_one_log_cuts_the_final_error_of_later_logs_whatever_their_header(report):
    result = score(report, _later_logs())
    for row in result["logs"]:
        assert row["after"]["final_position_error_m"] < 0.2 * row["before"][
            "final_position_error_m"], row
        assert abs(row["after"]["final_heading_error_deg"]) < 0.2 * abs(
            row["before"]["final_heading_error_deg"]), row
    assert result["cut"] > 0.8


def test_logs_of_another_vehicle_kind_are_refused_naming_the_kind(report):
    rover = kinematic_log(6, None, kind="rover4ws", duration_s=20.0)
    with pytest.raises(ValueError, match="rover4ws log, but the model was fitted on a "
                                         "diff_drive"):
        score(report, [rover])


def test_the_command_writes_the_score_and_refuses_a_file_that_is_no_report(report, tmp_path,
                                                                            capsys):
    model = tmp_path / "model.json"
    model.write_text(json.dumps(report, default=float))
    for k, log in enumerate(_later_logs()):
        write_log(log, tmp_path / "later" / f"run-{k}")
    out = tmp_path / "score.json"
    assert main(["diagnose", str(tmp_path / "later"), "--model", str(model),
                 "--json", str(out), "--quiet"]) == 0
    written = json.loads(out.read_text())
    assert [row["name"] for row in written["logs"]] == ["run-0", "run-1"]
    assert written["cut"] > 0.8
    assert "cut" in capsys.readouterr().out
    assert main(["diagnose", str(tmp_path / "later"), "--model", str(out), "--quiet"]) == 2
    assert "not a diagnosis report" in capsys.readouterr().err
    assert main(["diagnose", str(tmp_path / "later"), "--model", str(model),
                 "--report", str(tmp_path / "rep"), "--quiet"]) == 2
    assert "--report writes a diagnosis" in capsys.readouterr().err
    assert main(["diagnose", "--example", "borealtc", "--model", str(model), "--quiet"]) == 2
    assert "no ground-truth pose" in capsys.readouterr().err
