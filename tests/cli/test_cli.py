"""The command line, exercised through its real entry point."""

from __future__ import annotations

import json

from slipenv.cli import main


def test_run_prints_the_table_and_writes_the_trajectory_plot(tmp_path, capsys):
    out = tmp_path / "run"
    metrics = tmp_path / "metrics.json"
    code = main(["run", "slipenv/HuskySand-v0", "--max-steps", "60", "--quiet",
                 "--out", str(out), "--json", str(metrics)])
    assert code == 0
    text = capsys.readouterr().out
    for row in ("cross_track_rmse_m", "wheel_slip_mean", "odometry_final_error_m",
                "dead_reckoning_final_error_m"):
        assert row in text
    png = out / "trajectory.png"
    assert png.exists() and png.stat().st_size > 10_000
    data = json.loads(metrics.read_text())
    assert data["metrics"]["wheel_slip_mean"] > 0.05  # loose sand slips


def test_bench_writes_the_documented_json_schema(tmp_path):
    path = tmp_path / "bench.json"
    assert main(["bench", "slipenv/HuskySand-v0", "--steps", "20", "--repeats", "1",
                 "--quiet", "--json", str(path)]) == 0
    doc = json.loads(path.read_text())
    entry = doc["envs"]["slipenv/HuskySand-v0"]
    for key in ("env_steps_per_s", "substeps_per_step", "bare_substeps_per_s", "ratio"):
        assert entry[key] > 0
    start = doc["startup"]  # measured in a fresh interpreter: import, then the first step
    assert 0 < start["import_s"] < start["first_make_s"]["slipenv/HuskySand-v0"] + 5
    assert set(start["compiled"]) == {"wheel_loop", "lindgren_ekf", "track_model"}
    expected = entry["env_steps_per_s"] * entry["substeps_per_step"] / entry["bare_substeps_per_s"]
    assert entry["ratio"] == round(expected, 3) or abs(entry["ratio"] - expected) < 2e-3


def test_list_names_every_registered_env(capsys):
    assert main(["list"]) == 0
    assert "slipenv/FarmField-v0" in capsys.readouterr().out


def test_an_unknown_env_id_is_a_clear_error(capsys):
    assert main(["run", "slipenv/Nope-v0", "--quiet"]) == 2
    assert "unknown env id" in capsys.readouterr().err


def test_a_bad_option_value_is_a_clear_error_not_a_traceback(capsys):
    assert main(["reproduce", "nonsense"]) == 2
    assert "unknown experiment" in capsys.readouterr().err
