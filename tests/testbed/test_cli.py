"""`slipenv fit-soil DIR --json PATH --report DIR`."""

from __future__ import annotations

import json

import gymnasium as gym

import slipenv  # noqa: F401  (registers the envs)
from slipenv.cli import main
from slipenv.terramechanics.soil import Soil


def test_fit_soil_writes_the_report_plots_and_a_soil_gym_make_accepts(reina_bed_dir, tmp_path):
    out, report_dir = tmp_path / "fit.json", tmp_path / "report"
    assert main(["fit-soil", str(reina_bed_dir), "--json", str(out), "--report",
                 str(report_dir)]) == 0
    report = json.loads(out.read_text())
    assert report["best"] == "reina"
    for law in ("janosi", "reina", "linear"):
        entry = report["laws"][law]
        assert set(entry["heldout_rmse_n"]) == {"fx", "fy"}
        assert all(len(v) == 2 for v in entry["parameters"].values())
    assert (report_dir / "fitted_curves.png").stat().st_size > 10_000
    assert (report_dir / "residuals.png").is_file()
    assert "verdict" in (report_dir / "report.md").read_text()
    assert report["accepted"] and report["slip_angle_definition"] == "simulation"
    soil = Soil(**report["soil"])  # the documented one-liner
    assert soil.mu == report["laws"]["reina"]["parameters"]["mu"][0]
    env = gym.make("slipenv/Configurable-v0", vehicle="rover_4ws", soil=soil,
                   force_model=report["best"])
    try:
        env.reset(seed=0)
        env.step(env.action_space.sample())
    finally:
        env.close()


def test_fit_soil_bad_file_exits_2_naming_file_row_and_column(tmp_path, capsys):
    (tmp_path / "meta.json").write_text(json.dumps({"wheel_radius_m": 0.09,
                                                    "wheel_width_m": 0.1}))
    (tmp_path / "trials.csv").write_text(
        "slip_ratio,slip_angle_deg,normal_load_n,fx_n,fy_n\n0.1,0,60,3,0\n0.2,0,-60,3,0\n")
    assert main(["fit-soil", str(tmp_path), "--json", str(tmp_path / "x.json")]) == 2
    err = capsys.readouterr().err
    assert "trials.csv, row 2, column 'normal_load_n'" in err and "negative" in err
    assert not (tmp_path / "x.json").exists()


def test_fit_soil_writes_a_rejected_fit_only_as_rejected_soil_and_exits_1(peaked_bed_dir,
                                                                          tmp_path, capsys):
    out = tmp_path / "fit.json"
    assert main(["fit-soil", str(peaked_bed_dir), "--json", str(out)]) == 1
    report = json.loads(out.read_text())
    assert report["accepted"] is False and "soil" not in report
    assert Soil(**report["rejected_soil"]).mu > 0.0  # kept for inspection
    captured = capsys.readouterr()
    assert "soil: NOT accepted" in captured.out and "warning: soil not accepted" in captured.out
    err = captured.err.strip().splitlines()
    assert len(err) == 1, captured.err
    assert "soil rejected" in err[0] and "'rejected_soil'" in err[0] and str(out) in err[0]
    assert "the verdict rejects reina" in err[0]  # the report's own reason, one line
