"""The real-data adapters read the datasets as their sources lay them out (plain CSV) and
gzip-compressed, warn about a missing stream, and the converter says where it looked."""

from __future__ import annotations

import gzip
import math
import warnings

import numpy as np
import pytest

from slipenv.logs.borealtc import TRACK_WIDTH_M, list_borealtc_runs, load_borealtc_run
from slipenv.logs.optiodom import list_optiodom_runs, load_optiodom_run
from slipenv.logs.real import convert_real_datasets

YAW_RATE = 0.4  # [rad/s] of the small BorealTC run below


def _write(path, text, gz=False):
    path.parent.mkdir(parents=True, exist_ok=True)
    if gz:
        path = path.with_name(path.name + ".gz")
        path.write_bytes(gzip.compress(text.encode()))
    else:
        path.write_text(text)
    return path


def _boreal_pro(n=60):
    t = np.arange(n) * (2 / 13)
    vl, vr = 0.5 - 0.5 * YAW_RATE * TRACK_WIDTH_M, 0.5 + 0.5 * YAW_RATE * TRACK_WIDTH_M
    rows = [f"{float(ti)!r},2.0,2.5,{vl!r},{vr!r}" for ti in t]
    return "time,curL,curR,velL,velR\n" + "\n".join(rows) + "\n"


def _boreal_imu(duration_s, columns=("wx", "wy", "wz", "ax", "ay", "az")):
    ts = np.arange(int(duration_s * 100)) * 0.01
    values = {"wx": 0.0, "wy": 0.0, "wz": 0.6 * YAW_RATE, "ax": 0.1, "ay": 0.2, "az": 9.81}
    rows = [",".join([repr(float(t))] + [repr(values[c]) for c in columns]) for t in ts]
    return ",".join(("time", *columns)) + "\n" + "\n".join(rows) + "\n"


def _boreal_root(tmp_path, imu_gz: bool | None, **imu):
    root = tmp_path / "borealtc"
    _write(root / "SNOW" / "pro_03.csv", _boreal_pro())
    if imu_gz is not None:
        _write(root / "SNOW" / "imu_03.csv", _boreal_imu(60 * 2 / 13, **imu), gz=imu_gz)
    return root


@pytest.mark.parametrize("gz", [False, True])
def test_borealtc_imu_is_read_plain_as_in_the_source_and_gzipped(tmp_path, gz):
    (run,) = list_borealtc_runs(_boreal_root(tmp_path, gz))
    assert run.imu_path is not None and run.imu_path.name == "imu_03.csv" + ".gz" * gz
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        log = load_borealtc_run(run, align_imu=False)
    # the gyro reads 0.6 of the wheels' yaw rate (a snow-like yaw efficiency)
    np.testing.assert_allclose(log.signals["gyro_z"], 0.6 * YAW_RATE)
    np.testing.assert_allclose(log.signals["acc_y"], 0.2)
    assert log.meta.data["borealtc"]["imu_file"] == "SNOW/" + run.imu_path.name


def test_borealtc_pro_file_is_read_gzipped_too(tmp_path):
    root = tmp_path / "borealtc"
    _write(root / "ICE" / "pro_07.csv", _boreal_pro(), gz=True)
    (run,) = list_borealtc_runs(root)
    assert (run.terrain, run.index, run.pro_path.name) == ("ICE", 7, "pro_07.csv.gz")
    with pytest.warns(UserWarning, match="no IMU file"):
        log = load_borealtc_run(run)
    right = log.signals["enc_right"][-1] / log.meta.counts_per_rad * log.meta.wheel_radius_m
    assert right == pytest.approx((0.5 + 0.5 * YAW_RATE * TRACK_WIDTH_M) * log.t[-1], rel=1e-3)


def test_borealtc_run_without_imu_warns_naming_the_file_it_looked_for(tmp_path):
    (run,) = list_borealtc_runs(_boreal_root(tmp_path, None))
    with pytest.warns(UserWarning, match=r"SNOW_03: no IMU file \(.*SNOW/imu_03\.csv or "
                                         r"\.csv\.gz\)"):
        log = load_borealtc_run(run)
    assert "gyro_z" not in log.columns and "current_left" in log.columns


def test_borealtc_imu_without_the_yaw_rate_column_warns_and_keeps_the_rest(tmp_path):
    (run,) = list_borealtc_runs(_boreal_root(tmp_path, False, columns=("wx", "wy", "ax", "ay")))
    with pytest.warns(UserWarning, match=r"imu_03\.csv lacks the columns of gyro_z \(from 'wz'\)"):
        log = load_borealtc_run(run)
    assert "gyro_z" not in log.columns
    np.testing.assert_allclose(log.signals["acc_x"], 0.1)


def _optiodom_root(tmp_path, gz=False, metadata=True):
    root = tmp_path / "optiodom"
    session = root / "square" / "230620202042"
    # 20 Hz; right wheel 30 ticks, left 20 ticks per sample: it turns left
    rows = [f"{0.05 * k!r},0.0,0.0,0.0,30,20" for k in range(40)]
    _write(session / "230620202042_run-01.csv", "\n".join(rows) + "\n", gz=gz)
    if metadata:
        _write(session / "230620202042_metadata.csv",
               "type,diff\nngear,43.7\nencRes,64\nLi,0.2\nDi,0.084,0.086\nN,1\n", gz=gz)
    return root


@pytest.mark.parametrize("gz", [False, True])
def test_optiodom_run_is_read_plain_and_gzipped(tmp_path, gz):
    (run,) = list_optiodom_runs(_optiodom_root(tmp_path, gz))
    log = load_optiodom_run(run)
    assert (log.signals["enc_right"][-1], log.signals["enc_left"][-1]) == (1200, 800)
    assert log.meta.counts_per_rad == pytest.approx(43.7 * 64 / (2 * math.pi))
    assert log.meta.wheel_radius_m == pytest.approx(0.085 / 2)


def test_optiodom_run_without_its_session_metadata_is_skipped_with_a_warning(tmp_path):
    with pytest.warns(UserWarning, match="no 230620202042_metadata.csv"):
        assert list_optiodom_runs(_optiodom_root(tmp_path, metadata=False)) == []


def test_converting_a_folder_without_the_datasets_names_the_folder(tmp_path):
    with pytest.raises(FileNotFoundError, match=f"no real dataset in {tmp_path}"):
        convert_real_datasets(tmp_path / "out", tmp_path, progress=False)
    assert not (tmp_path / "out").exists()


def test_the_default_data_folder_when_absent_says_how_to_point_at_the_data(tmp_path,
                                                                          monkeypatch):
    monkeypatch.setenv("SLIPENV_REAL_DATA", str(tmp_path / "nowhere"))
    with pytest.raises(FileNotFoundError, match="SLIPENV_REAL_DATA"):
        convert_real_datasets(tmp_path / "out", progress=False)


def test_converting_one_dataset_warns_that_the_other_is_missing(tmp_path):
    root = tmp_path / "data"
    _boreal_root(root, False).rename(root / "borealtc-husky")
    with pytest.warns(UserWarning, match="optiodom-diffdrive not found"):
        written = convert_real_datasets(tmp_path / "out", root, progress=False)
    assert [p.name for p in written] == ["SNOW_03"]


def test_dataset_folders_without_run_files_are_an_error(tmp_path):
    (tmp_path / "optiodom-diffdrive").mkdir()
    (tmp_path / "borealtc-husky").mkdir()
    with pytest.raises(FileNotFoundError, match="no run files in"):
        convert_real_datasets(tmp_path / "out", tmp_path, progress=False)
