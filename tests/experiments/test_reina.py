"""``slipenv reproduce reina``: the JSON schema of the issue and sanity on a very short run.

The run drives each test for 1.2 m (about 15 s of simulated time each), through the same code
as the command; the full and ``--quick`` runs are timed in the README, not here.
"""

from __future__ import annotations

import json
import math

import pytest

from slipenv.cli import experiment_name
from slipenv.experiments import EXPERIMENT_MODULES, reina
from slipenv.experiments.reina import Settings

TESTS = {"sideways", "mounds"}
ODOMETRIES = {"plain", "compass", "scomp"}
# The big mound is moved to the short path's middle so that 1.2 m see its full bank.
SHORT = Settings(seeds=1, sideways_length_m=1.2, mounds_length_m=1.2, frames_saved=2,
                 sideways_mound=(0.6, 2.0, 2.0, 0.46))


@pytest.fixture(scope="module")
def short(tmp_path_factory):
    out = tmp_path_factory.mktemp("reina")
    path = out / "metrics.json"
    reina.run(settings=SHORT, out_dir=str(out), json_path=str(path), progress=False,
              docs_dir=str(out / "docs"))
    return json.loads(path.read_text()), out


def _schema(block: dict) -> None:
    assert set(block["slip_angle_rms_deg"]) == TESTS
    assert set(block["slip_ratio_rms"]) == TESTS
    assert set(block["final_error_m"]) == TESTS
    for t in TESTS:
        assert set(block["final_error_m"][t]) == ODOMETRIES
    assert set(block["ftrace"]) == {"frames", "false_positive", "false_negative",
                                    "misidentification"}


def test_the_json_has_exactly_the_issue_schema(short):
    result, _ = short
    _schema(result["metrics"])
    _schema(result["paper"])
    assert result["paper"]["final_error_m"]["sideways"] == {"plain": 2.84, "compass": 2.50,
                                                           "scomp": 0.14}
    assert result["paper"]["slip_angle_rms_deg"] == {"sideways": 1.4, "mounds": 1.6}


def test_a_short_run_measures_a_drift_and_scores_every_camera_frame(short):
    result, _ = short
    m, d = result["metrics"], result["details"]
    # 1.2 m at 8 cm/s is 15 s of 5 Hz frames per test at no slip, every one scored; climbing
    # the 5° plane the wheels slip (s ~ 0.2), which stretches each drive by up to 1/(1 - s).
    assert 2 * 60 <= m["ftrace"]["frames"] <= 2 * 125
    for key in ("false_positive", "false_negative", "misidentification"):
        assert 0.0 <= m["ftrace"][key] <= 1.0
    # Both tests climb the 5° plane; test 1's mound banks it by 8° to the right of the path.
    for t in TESTS:
        assert m["terrain"][t]["slope_deg"] == pytest.approx(5.0)
        assert m["terrain"][t]["downhill_azimuth_deg"] == pytest.approx(180.0)
    assert m["terrain"]["sideways"]["peak_bank_deg"] == pytest.approx(7.9, abs=0.2)
    assert len(m["terrain"]["sideways"]["placed_mounds"]) == 1
    assert m["terrain"]["mounds"]["random_mounds"]["count"] == SHORT.mound_count
    # The transverse inclination makes the rover crab downhill (to its right: β < 0).
    assert d["mean_true_slip_angle_deg"]["sideways"] < -3.0
    for t in TESTS:
        assert d["distance_m"][t] == pytest.approx(1.2, abs=0.15)
        assert math.isfinite(m["slip_angle_rms_deg"][t]) and m["slip_angle_rms_deg"][t] < 10.0
        for odo in ODOMETRIES:
            assert 0.0 <= m["final_error_m"][t][odo] < 1.0
    # Plain odometry believes the straight line; sComp corrects the sideways drift.
    side = m["final_error_m"]["sideways"]
    assert side["scomp"] < side["plain"]


def test_figures_and_the_results_page_are_written(short):
    _, out = short
    for name in ("fig15_slip_angle_sideways", "fig17_slip_angle_mounds",
                 "fig18_slip_ratio_sideways", "fig20_slip_ratio_mounds", "fig19_paths_sideways",
                 "fig21_paths_mounds", "fig13_camera_frames"):
        assert (out / f"{name}.png").stat().st_size > 1000
    page = (out / "docs" / "reina.md").read_text()
    assert "Table" in page and "img/reina/fig19_paths_sideways.png" in page


def test_reina_is_a_reproduce_name():
    assert "reina" in EXPERIMENT_MODULES
    assert experiment_name("reina") == "reina"
