"""``slipenv diagnose``: the JSON report of log-format.md, the human report, and bad input."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pytest

from slipenv.cli import main
from slipenv.diagnose import cli as diagnose_cli
from slipenv.logs import Log, LogMeta, read_log, write_log


def run(*argv) -> int:
    return main(["diagnose", *map(str, argv), "--quiet"])


def test_writes_json_matching_the_schema_and_a_report(synth_log_dir, tmp_path, capsys):
    out, folder = tmp_path / "d.json", tmp_path / "report"
    assert run(synth_log_dir, "--json", out, "--report", folder) == 0
    rep = json.loads(out.read_text())
    assert rep["format"] == "slipenv-diagnosis/1"
    assert rep["log"] == str(synth_log_dir)
    assert rep["cause"] == "rolling_radius"
    assert isinstance(rep["also"], list)
    for name, pair in rep["parameters"].items():
        assert name in ("radius_left_m", "radius_right_m")
        assert len(pair) == 2 and all(isinstance(v, float) for v in pair) and pair[1] > 0
    g = rep["gain"]
    assert set(g) == {"metric", "before", "after", "relative", "evaluated_on"}
    # the model was chosen by its transfer: the gain is that of one half of the log replayed
    # whole by the model fitted on the other half
    assert g["metric"] == "position_rmse_m" and g["evaluated_on"].startswith("held-out half")
    assert g["after"] < g["before"] and g["relative"] == pytest.approx(1 - g["after"] / g["before"])
    assert rep["candidates"][0]["cause"] == "rolling_radius"
    assert all({"cause", "score", "gain_relative"} <= set(c) for c in rep["candidates"])
    for name in ("report.md", "overlay.png", "residuals_time.png", "regressors.png",
                 "candidates.png", "pybullet.png"):
        assert (folder / name).stat().st_size > 0, name
    text = (folder / "report.md").read_text()
    assert "Cause: rolling_radius" in text and "held-out" in text
    assert "cause: rolling_radius" in capsys.readouterr().out


def test_model_from_the_report_loads_into_the_simulation(synth_log_dir, tmp_path):
    from slipenv.diagnose import apply_model
    from slipenv.envs.config import SlipEnvConfig

    out = tmp_path / "d.json"
    assert run(synth_log_dir, "--json", out) == 0
    cfg = apply_model(SlipEnvConfig(vehicle="farm_2wd"), json.loads(out.read_text()))
    radii = [w.rolling_radius_m for w in cfg.vehicle.wheels if w.role == "driven"]
    assert all(r is not None and r != 0.275 for r in radii)


def test_ground_truth_missing_in_stretches_still_diagnoses(synth_log_dir, tmp_path):
    log = read_log(synth_log_dir)
    sig = dict(log.signals)
    n = len(log)
    for name in ("gt_x", "gt_y", "gt_yaw"):
        sig[name] = sig[name].copy()
        sig[name][n // 5: n // 3] = np.nan
        sig[name][n // 2: n // 2 + 40] = np.nan
    folder = write_log(Log(log.meta, sig), tmp_path / "gappy")
    out = tmp_path / "d.json"
    assert run(folder, "--json", out) == 0
    assert json.loads(out.read_text())["cause"] == "rolling_radius"


def _small_log(kind="diff_drive", n=40, gt=True) -> Log:
    t = np.arange(n) * 0.05
    meta = LogMeta.new(kind, ["left", "right"], 0.3, 1.0, 100.0,
                       wheelbase_m=1.0 if kind == "rover4ws" else None)
    cols = dict(t=t, enc_left=np.round(t * 300), enc_right=np.round(t * 300))
    if kind == "rover4ws":
        cols.update(steer_left=np.zeros(n), steer_right=np.zeros(n))
    if gt:
        cols.update(gt_x=0.9 * t, gt_y=np.zeros(n), gt_yaw=np.zeros(n))
    return Log.from_arrays(meta, require_ground_truth=gt, **cols)


@pytest.mark.parametrize(("make", "message"), [
    (lambda p: p / "missing", "no such log folder"),
    (lambda p: p, "no log folders in it"),
    (lambda p: _write(p, _small_log(n=100)), "at least 4"),
    # rover logs are diagnosed, but the replay must know the front from the rear
    (lambda p: _write(p, _small_log("rover4ws", n=400)), "front from rear"),
    (lambda p: _corrupt_meta(_write(p, _small_log(n=400))), "meta.json"),
    (lambda p: _corrupt_signals(_write(p, _small_log(n=400))), "non-numeric value"),
])
def test_malformed_input_is_a_clear_error(tmp_path, capsys, make, message):
    target = make(tmp_path)
    assert run(target) == 2
    assert message in capsys.readouterr().err


def _write(folder, log):
    return write_log(log, folder / "log")


def _corrupt_meta(folder):
    (folder / "meta.json").write_text('{"format": "slipenv-log/1", "vehicle": ')
    return folder


def _corrupt_signals(folder):
    lines = (folder / "signals.csv").read_text().splitlines()
    cells = lines[5].split(",")
    cells[1] = "ten"
    lines[5] = ",".join(cells)
    (folder / "signals.csv").write_text("\n".join(lines) + "\n")
    return folder


def test_log_without_ground_truth_gets_the_proprioceptive_analysis(tmp_path, capsys):
    n = 2000
    t = np.arange(n) * 0.05
    rng = np.random.default_rng(0)
    wl = 2.0 + np.repeat(rng.uniform(-1.5, 1.5, n // 100), 100)
    wr = 2.0 - (wl - 2.0)
    kin = 0.3 * (wr - wl) / 1.0
    meta = LogMeta.new("skid_steer", ["left", "right"], 0.3, 1.0, 1000.0)
    log = Log.from_arrays(meta, require_ground_truth=False, t=t,
                          enc_left=np.round(np.cumsum(wl) * 0.05 * 1000),
                          enc_right=np.round(np.cumsum(wr) * 0.05 * 1000),
                          gyro_z=0.6 * kin + rng.normal(0, 0.01, n))
    folder = write_log(log, tmp_path / "nogt", require_ground_truth=False)
    out = tmp_path / "p.json"
    assert run(folder, "--json", out, "--report", tmp_path / "r") == 0
    rep = json.loads(out.read_text())
    assert rep["ground_truth"] == "none" and rep["cause"] == "track_width"
    assert rep["parameters"]["track_width_m"][0] == pytest.approx(1.0 / 0.6, rel=0.05)
    assert rep["cannot_conclude"]
    assert (tmp_path / "r" / "report.md").is_file()
    shutil.rmtree(tmp_path / "r")


def test_folder_of_logs_is_diagnosed_together(synth_log_dir, tmp_path):
    log = read_log(synth_log_dir)
    half = len(log) // 2
    root = tmp_path / "runs"
    for k, (a, b) in enumerate(((0, half), (half, len(log)))):
        write_log(Log(log.meta, {c: v[a:b] for c, v in log.signals.items()}), root / f"run{k}")
    out = tmp_path / "d.json"
    assert run(root, "--json", out) == 0
    rep = json.loads(out.read_text())
    assert rep["segments"]["fold_by"] == "log" and len(rep["logs"]) == 2


def test_log_without_ground_truth_or_gyro_is_a_clear_error(tmp_path, capsys):
    folder = write_log(_small_log(n=400, gt=False), tmp_path / "bare", require_ground_truth=False)
    assert run(folder) == 2
    assert "nothing to compare" in capsys.readouterr().err


def test_a_soil_maps_regions_are_shown_one_line_each_not_a_line_per_corner():
    from slipenv.diagnose.cli import summary
    from slipenv.diagnose.effects.soil_map import MAX_RECTS

    # in a frame turned 90 deg: region 0 one rectangle, region 1 a rectangle and a disc;
    # the rest unused
    boxes = [(0.0, -2.0, 4.0, 0.0, 0, 0), (1.0, 1.0, 2.0, 3.0, 1, 0), (2.0, 1.0, 3.0, 2.0, 1, 1)]
    boxes += [(0.0, 0.0, 1.0, 1.0, 0, 0)] * (MAX_RECTS - len(boxes))
    corners = {f"map_rect{k}_{e}": [v, 0.0] for k, box in enumerate(boxes)
               for e, v in zip(("u0_m", "v0_m", "u1_m", "v1_m", "region", "shape"), box,
                               strict=True)}
    params = {"map_angle_rad": [np.pi / 2, 0.0], "map_rects": [3.0, 0.0], **corners,
              "c_region0_per_nm": [2e-3, 1e-4], "c_region1_per_nm": [5e-3, 2e-4],
              "c_region2_per_nm": [0.0, 0.0]}
    report = {"log": "field", "cause": "soil_map", "also": [], "parameters": params,
              "gain": {"metric": "position_rmse_m", "before": 0.2, "after": 0.1,
                       "relative": 0.5}, "segments": {"count": 40}}
    text = summary(report, 1.0)
    assert "map_rect" not in text and "c_region2" not in text
    assert "c_region1_per_nm = 0.005 ± 0.0002" in text
    assert "2 region(s) of 3 shape(s), rectangles turned 90.0 deg" in text
    # region 0's centre (2, -1) in the map frame is (1, 2) in the world, its size 4 x 2 m
    assert "region 0 (c_region0_per_nm): (1.00, 2.00) m, 4.00 x 2.00 m" in text
    assert "region 1 (c_region1_per_nm): (-2.00, 1.50) m, 1.00 x 2.00 m; " \
        "disc (-1.50, 2.50) m, radius 0.50 m" in text


def _still_log(gt=True, noise_m=0.0, n=2000) -> Log:
    """A vehicle standing still for 100 s: encoders flat, gyro and truth at sensor noise."""
    rng = np.random.default_rng(0)
    t = np.arange(n) * 0.05
    meta = LogMeta.new("diff_drive", ["left", "right"], 0.3, 1.0, 100.0)
    cols = dict(t=t, enc_left=np.zeros(n), enc_right=np.zeros(n),
                gyro_z=rng.normal(0.0, 1e-3, n) if noise_m else np.zeros(n))
    if gt:
        cols.update(gt_x=rng.normal(0.0, noise_m, n), gt_y=rng.normal(0.0, noise_m, n),
                    gt_yaw=rng.normal(0.0, noise_m, n))
    return Log.from_arrays(meta, require_ground_truth=gt, **cols)


@pytest.mark.filterwarnings("error")
@pytest.mark.parametrize(("gt", "noise_m"), [(True, 0.0), (True, 3e-3), (False, 0.0)])
def test_a_log_where_the_vehicle_never_moves_is_refused_in_one_line(tmp_path, capsys, gt,
                                                                    noise_m):
    folder = write_log(_still_log(gt, noise_m), tmp_path / "still", require_ground_truth=gt)
    out = tmp_path / "d.json"
    assert run(folder, "--json", out, "--report", tmp_path / "r") == 2
    captured = capsys.readouterr()
    assert captured.err.strip().splitlines() == [
        f"slipenv diagnose: error: {folder}: the vehicle does not move in this log (wheels and "
        "ground truth move less than 5 cm and 3 deg): nothing to diagnose"]
    assert "0.0 % better" not in captured.out
    assert not out.exists() and _holds_nothing(tmp_path / "r")


def _holds_nothing(folder) -> bool:
    """True for a missing or empty folder (the output check may have made it)."""
    return not folder.exists() or not any(folder.iterdir())


def test_a_vehicle_turning_on_the_spot_or_pushed_counts_as_moving():
    n, t = 400, np.arange(400) * 0.05
    meta = LogMeta.new("diff_drive", ["left", "right"], 0.3, 1.0, 100.0)
    spin = 0.5 * t * 100  # [counts]: 0.5 rad/s of wheel rotation, opposite sides
    turning = Log.from_arrays(meta, t=t, enc_left=np.round(-spin), enc_right=np.round(spin),
                              gt_x=np.zeros(n), gt_y=np.zeros(n), gt_yaw=0.3 * t)
    pushed = Log.from_arrays(meta, t=t, enc_left=np.zeros(n), enc_right=np.zeros(n),
                             gt_x=0.1 * t, gt_y=np.zeros(n), gt_yaw=np.zeros(n))
    assert diagnose_cli.moves(turning) and diagnose_cli.moves(pushed)
    assert not diagnose_cli.moves(_still_log(noise_m=3e-3))


@pytest.mark.parametrize(("option", "target", "message"), [
    ("--report", "file", "is a file, not a folder"),
    ("--report", "file/report", "is a file, not a folder)"),
    ("--json", "folder", "is a folder, not a file"),
    ("--json", "file/d.json", "is a file, not a folder)"),
])
def test_output_paths_are_checked_before_any_work(tmp_path, capsys, monkeypatch, option,
                                                  target, message):
    def no_work(*args, **kwargs):
        raise AssertionError("the diagnosis started before the output check")

    monkeypatch.setattr(diagnose_cli, "load_logs", no_work)
    (tmp_path / "file").write_text("x")
    (tmp_path / "folder").mkdir()
    assert run(path_of_example(), option, tmp_path / target) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(f"slipenv diagnose: error: {option} ")
    assert err[0].endswith(message)


def path_of_example():
    from slipenv.logs.examples import path

    return path("synthetic")


@pytest.mark.parametrize("existing", [False, True])
def test_ctrl_c_while_the_report_is_written_leaves_no_partial_report(synth_log_dir, tmp_path,
                                                                     capsys, monkeypatch,
                                                                     existing):
    from slipenv.diagnose import plots

    folder, out = tmp_path / "report", tmp_path / "d.json"
    if existing:  # a finished report from an earlier run stays as it was
        folder.mkdir()
        (folder / "report.md").write_text("earlier report\n")
    overlay = plots.overlay

    def interrupted(path, *args, **kwargs):
        overlay(path, *args, **kwargs)  # one figure is on disk when the user presses Ctrl-C
        raise KeyboardInterrupt

    monkeypatch.setattr(plots, "overlay", interrupted)
    monkeypatch.setattr("slipenv.diagnose.simreplay.pybullet_overlay", lambda *a, **k: None)
    assert run(synth_log_dir, "--json", out, "--report", folder) == 130
    assert capsys.readouterr().err.strip().splitlines() == [
        "slipenv diagnose: interrupted; nothing written"]
    assert not out.exists()
    if existing:
        assert [p.name for p in folder.iterdir()] == ["report.md"]
        assert (folder / "report.md").read_text() == "earlier report\n"
    else:
        assert _holds_nothing(folder)
    assert [p.name for p in tmp_path.iterdir() if "partial" in p.name] == []
