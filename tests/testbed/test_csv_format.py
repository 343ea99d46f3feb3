"""The test-bed CSV format: round trip and errors naming file, row and column."""

from __future__ import annotations

import json

import numpy as np
import pytest

from slipenv.testbed.csv_format import SIGN_CONVENTIONS, read_testbed, write_testbed

META = {"wheel_radius_m": 0.092, "wheel_width_m": 0.11}
ROW = {"slip_ratio": 0.2, "slip_angle_deg": 10.0, "normal_load_n": 64.7, "fx_n": 9.0,
       "fy_n": -20.0}


def write_csv(tmp_path, text, meta=META):
    (tmp_path / "trials.csv").write_text(text)
    (tmp_path / "meta.json").write_text(json.dumps(meta))
    return tmp_path


def test_round_trip_keeps_values_and_spells_out_the_sign_conventions(tmp_path):
    rows = [ROW, {**ROW, "slip_ratio": 0.4, "sinkage_m": 0.01, "fx_std_n": 0.2}]
    write_testbed(tmp_path, rows, META)
    data = read_testbed(tmp_path)
    np.testing.assert_array_equal(data.slip_ratio, [0.2, 0.4])
    np.testing.assert_array_equal(data.fy_n, [-20.0, -20.0])
    assert np.isnan(data.sinkage_m[0]) and data.sinkage_m[1] == 0.01
    assert np.all(np.isnan(data.fy_std_n))
    assert data.meta["sign_conventions"] == SIGN_CONVENTIONS
    assert data.meta["contact_length_m"] == pytest.approx(0.046)  # default r/2
    assert data.tan_beta == pytest.approx(np.tan(np.radians([10.0, 10.0])))


def test_missing_column_names_file_header_row_and_column(tmp_path):
    write_csv(tmp_path, "slip_ratio,slip_angle_deg,normal_load_n,fx_n\n0.1,0,60,3\n")
    with pytest.raises(ValueError, match=r"trials\.csv, row 0 \(header\).*'fy_n'"):
        read_testbed(tmp_path)


@pytest.mark.parametrize("column,value,message", [
    ("slip_ratio", "1.5", r"outside \[-1, 1\]"),
    ("slip_ratio", "-1.01", r"outside \[-1, 1\]"),
    ("normal_load_n", "-3", "negative"),
    ("fx_n", "abc", "not a number"),
    ("fy_n", "nan", "not a finite number"),
])
def test_bad_value_names_file_row_and_column(tmp_path, column, value, message):
    header = "slip_ratio,slip_angle_deg,normal_load_n,fx_n,fy_n"
    good = "0.1,5,60,3,-8"
    bad = dict(zip(header.split(","), good.split(","), strict=True))
    bad[column] = value
    write_csv(tmp_path, f"{header}\n{good}\n{','.join(bad.values())}\n")
    with pytest.raises(ValueError, match=rf"trials\.csv, row 2, column '{column}'.*{message}"):
        read_testbed(tmp_path)


def test_meta_without_wheel_width_is_rejected(tmp_path):
    write_csv(tmp_path, "slip_ratio,slip_angle_deg,normal_load_n,fx_n,fy_n\n0.1,0,60,3,0\n",
              meta={"wheel_radius_m": 0.1})
    with pytest.raises(ValueError, match=r"meta\.json: key 'wheel_width_m'"):
        read_testbed(tmp_path)


def test_missing_files_are_named(tmp_path):
    with pytest.raises(ValueError, match=r"meta\.json: missing"):
        read_testbed(tmp_path)
    (tmp_path / "meta.json").write_text(json.dumps(META))
    with pytest.raises(ValueError, match=r"trials\.csv: missing"):
        read_testbed(tmp_path)
