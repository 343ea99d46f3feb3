"""Adapters for the real datasets, checked against the numbers in the source files."""

from __future__ import annotations

import math
import shutil

import numpy as np
import pytest

from slipenv.logs import LogFormatError, read_log, write_log
from slipenv.logs.borealtc import (
    COUNTS_PER_RAD,
    WHEEL_RADIUS_M,
    estimate_imu_lag,
    list_borealtc_runs,
    load_borealtc_run,
    window_mean,
)
from slipenv.logs.optiodom import list_optiodom_runs, load_optiodom_run
from slipenv.logs.real import convert_real_datasets


def _optiodom_run(root, path_type, session, run):
    runs = list_optiodom_runs(root / "optiodom-diffdrive")
    return next(r for r in runs if (r.path_type, r.session, r.run) == (path_type, session, run))


def _boreal_run(root, terrain, index):
    runs = list_borealtc_runs(root / "borealtc-husky")
    return next(r for r in runs if (r.terrain, r.index) == (terrain, index))


def test_optiodom_listing_finds_all_102_runs_by_path_type(real_root):
    runs = list_optiodom_runs(real_root / "optiodom-diffdrive")
    counts = {p: sum(r.path_type == p for r in runs) for p in ("square", "circular", "ivanjko")}
    assert counts == {"square": 28, "circular": 32, "ivanjko": 42}
    assert len({r.session for r in runs}) == 14


def test_optiodom_run_has_documented_lengths_counts_and_geometry(real_root):
    log = load_optiodom_run(_optiodom_run(real_root, "square", "230620202042", 1))
    assert len(log) == 1814
    np.testing.assert_allclose(np.diff(log.t), 0.05, atol=1e-9)  # 20 Hz
    assert log.t[-1] == pytest.approx(90.65)
    # column 6 is the left wheel: a clockwise square turns the left wheel further
    assert (log.signals["enc_left"][-1], log.signals["enc_right"][-1]) == (38254, 24871)
    assert log.gt_mask.all()
    assert log.signals["gt_yaw"][-1] == pytest.approx(-6.28220535716447)  # one CW loop
    assert log.meta.counts_per_rad == pytest.approx(43.7 * 64 / (2 * math.pi))
    assert (log.meta.wheel_radius_m, log.meta.track_width_m) == (0.042, 0.2)
    assert log.meta.data["source"]["license"].startswith("MIT")


def test_optiodom_dead_reckoned_heading_with_nominal_parameters_drifts_over_one_degree(
        real_root):
    log = load_optiodom_run(_optiodom_run(real_root, "square", "230620202042", 1))
    r, b = log.meta.wheel_radius_m, log.meta.track_width_m
    heading = r * (log.wheel_angle("right") - log.wheel_angle("left")) / b
    drift_deg = math.degrees(heading[-1] - log.signals["gt_yaw"][-1])
    assert 1.0 < abs(drift_deg) < 3.0  # -1.81 deg after 90 s
    assert log.signals["gt_x"][0] == log.signals["gt_y"][0] == 0.0  # relative to the start


def test_optiodom_log_survives_write_and_read(real_root, tmp_path):
    log = load_optiodom_run(_optiodom_run(real_root, "ivanjko", "250620201618", 4))
    back = read_log(write_log(log, tmp_path / "log"))
    assert back.meta.data == log.meta.data
    np.testing.assert_array_equal(back.signals["enc_left"], log.signals["enc_left"])


def test_borealtc_run_becomes_a_valid_skid_steer_log_without_ground_truth(real_root, tmp_path):
    run = _boreal_run(real_root, "FLOORING", 1)
    log = load_borealtc_run(run)
    assert log.meta.kind == "skid_steer" and log.wheels == ["left", "right"]
    assert len(log) == 131
    np.testing.assert_allclose(np.diff(log.t), 2 / 13, atol=1e-9)  # 6.5 Hz
    assert {"current_left", "current_right", "gyro_z", "acc_x", "acc_y"} <= set(log.columns)
    assert not log.gt_mask.any()
    folder = write_log(log, tmp_path / "log", require_ground_truth=False)
    with pytest.raises(LogFormatError, match="column 'gt_x'"):
        read_log(folder)
    back = read_log(folder, require_ground_truth=False)
    np.testing.assert_array_equal(back.signals["current_right"], log.signals["current_right"])
    assert back.meta.data["source"]["license"] == "CC0 1.0 (dataset)"


def test_borealtc_counts_integrate_the_logged_side_speeds(real_root):
    run = _boreal_run(real_root, "FLOORING", 1)
    pro = np.genfromtxt(run.pro_path, delimiter=",", names=True)
    log = load_borealtc_run(run)
    for side, key in (("left", "velL"), ("right", "velR")):
        distance = np.trapezoid(pro[key], pro["time"])  # [m]
        counts = log.signals[f"enc_{side}"][-1]
        assert counts == pytest.approx(distance / WHEEL_RADIUS_M * COUNTS_PER_RAD, abs=0.5)


def test_borealtc_imu_is_averaged_onto_the_wheel_time_base(real_root):
    log = load_borealtc_run(_boreal_run(real_root, "ASPHALT", 2), align_imu=False)
    imu = np.loadtxt(_boreal_run(real_root, "ASPHALT", 2).imu_path, delimiter=",", skiprows=1)
    first = imu[(imu[:, 0] < log.t[0] + 1 / 13), 3]  # interval of sample 0: [-1/13, 1/13)
    assert log.signals["gyro_z"][0] == pytest.approx(first.mean())
    assert np.isnan(log.signals["gyro_z"][-1])  # IMU ends at 9.49 s, wheels at 9.85 s


def test_borealtc_mixed_run_keeps_terrain_labels_and_has_no_imu(real_root):
    with pytest.warns(UserWarning, match="MIXED_00: no IMU file"):
        log = load_borealtc_run(_boreal_run(real_root, "MIXED", 0))
    labels = log.meta.data["borealtc"]["terrain_labels"]
    assert [lab[2] for lab in labels[:4]] == ["unlabelled", "FLOORING", "unlabelled", "ASPHALT"]
    assert labels[1][0] == pytest.approx(41.846, abs=1e-3)
    assert "gyro_z" not in log.columns


def test_imu_lag_estimate_recovers_a_known_shift():
    t = np.arange(400) * (2 / 13)  # wheel samples [s]
    yaw_rate = np.sin(0.4 * t) + 0.5 * np.sin(1.3 * t)
    ts = np.arange(-300, 6500) * 0.01  # IMU [s], its clock 0.8 s ahead of the wheels'
    gyro = np.interp(ts - 0.8, t, 0.6 * yaw_rate)
    lag, corr0, corr = estimate_imu_lag(ts, gyro, t, yaw_rate)
    assert lag == pytest.approx(0.8, abs=0.03)
    assert corr > 0.99 > corr0


def test_window_mean_is_nan_where_no_source_sample_falls():
    # windows [-0.1, 0.1), [0.1, 2.6), [2.6, 7.4): half-way points, left edge included
    out = window_mean(np.array([0.0, 0.1, 0.2]), np.array([1.0, 2.0, 3.0]),
                      np.array([0.0, 0.2, 5.0]))
    np.testing.assert_allclose(out[:2], [1.0, 2.5])
    assert np.isnan(out[2])


def test_convert_real_datasets_writes_readable_logs_for_each_dataset(real_root, tmp_path):
    root = tmp_path / "data"
    src_session = real_root / "optiodom-diffdrive" / "ivanjko" / "250620201618"
    dst_session = root / "optiodom-diffdrive" / "ivanjko" / "250620201618"
    dst_session.mkdir(parents=True)
    for name in ("250620201618_metadata.csv", "250620201618_run-05.csv"):
        shutil.copy(src_session / name, dst_session / name)
    (root / "borealtc-husky" / "ICE").mkdir(parents=True)
    for name in ("pro_11.csv", "imu_11.csv.gz"):
        shutil.copy(real_root / "borealtc-husky" / "ICE" / name,
                    root / "borealtc-husky" / "ICE" / name)
    written = convert_real_datasets(tmp_path / "out", root, progress=False)
    assert [p.relative_to(tmp_path / "out").as_posix() for p in written] == [
        "optiodom/ivanjko_250620201618_run-05", "borealtc/ICE_11"]
    assert len(read_log(written[0])) == 225
    assert len(read_log(written[1], require_ground_truth=False)) == 111


def test_optiodom_files_with_a_byte_order_mark_read_the_same(real_root, tmp_path):
    run = _optiodom_run(real_root, "ivanjko", "250620201618", 5)
    session = tmp_path / "ivanjko" / run.session
    session.mkdir(parents=True)
    for src in (run.csv_path, run.metadata_path):
        (session / src.name).write_bytes(b"\xef\xbb\xbf" + src.read_bytes())
    (copy,) = list_optiodom_runs(tmp_path)
    original, with_bom = load_optiodom_run(run), load_optiodom_run(copy)
    assert with_bom.meta.track_width_m == original.meta.track_width_m
    for name, values in original.signals.items():
        np.testing.assert_array_equal(with_bom.signals[name], values)
