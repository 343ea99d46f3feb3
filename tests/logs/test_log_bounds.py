"""Physically impossible values are errors naming file, row (or key) and column."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from slipenv.logs import LogFormatError, read_log, write_log
from slipenv.logs.bounds import SIGNAL_BOUNDS


def set_cell(folder: Path, column: str, row: int, value: str) -> None:
    path = folder / "signals.csv"
    lines = path.read_text().splitlines()
    header = lines[0].split(",")
    if column not in header:
        lines = [lines[0] + f",{column}"] + [line + ",0" for line in lines[1:]]
        header.append(column)
    cells = lines[row].split(",")
    cells[header.index(column)] = value
    lines[row] = ",".join(cells)
    path.write_text("\n".join(lines) + "\n")


def set_meta(folder: Path, section: str, key: str, value) -> None:
    path = folder / "meta.json"
    data = json.loads(path.read_text())
    data[section][key] = value
    path.write_text(json.dumps(data, indent=2))


@pytest.mark.parametrize(("column", "value"), [
    ("gt_x", "1e300"), ("enc_right", "1e308"), ("torque_left", "1e30"),
    ("torque_right", "-1e30"), ("gyro_z", "5000"), ("acc_x", "1e6"), ("roll", "7.0"),
    ("pitch", "2.0"), ("t", "1e12"), ("cmd_left", "1e5"), ("heading", "1e9"),
])
def test_an_impossible_signal_names_file_row_and_column(small_log, tmp_path, column, value):
    write_log(small_log, tmp_path)
    set_cell(tmp_path, column, 3, value)
    with pytest.raises(LogFormatError, match="implausible") as err:
        read_log(tmp_path)
    assert err.value.column == column and err.value.row == 3 and err.value.line == 4
    assert "signals.csv" in str(err.value)


@pytest.mark.parametrize(("section", "key", "value"), [
    ("terrain", "slope_deg", 95.0), ("vehicle", "track_width_m", 1e9),
    ("vehicle", "wheel_radius_m", 100.0), ("vehicle", "mass_kg", 1e12),
    ("terrain", "slope_deg", -5.0),
])
def test_an_impossible_meta_value_names_the_key_and_line(small_log, tmp_path, section, key,
                                                         value):
    write_log(small_log, tmp_path)
    set_meta(tmp_path, section, key, value)
    with pytest.raises(LogFormatError, match="implausible") as err:
        read_log(tmp_path)
    assert err.value.column == f"{section}.{key}" and err.value.line is not None


def test_values_at_the_edge_of_the_bounds_are_accepted(small_log, tmp_path):
    small_log.signals["gt_x"] = small_log.signals["gt_x"] + 5e6  # a UTM northing
    write_log(small_log, tmp_path)
    set_cell(tmp_path, "torque_left", 2, "2500.0")
    set_meta(tmp_path, "terrain", "slope_deg", 30.0)
    log = read_log(tmp_path)
    assert log.signals["gt_x"][0] > 5e6 - 1.0


@pytest.mark.parametrize(("column", "value", "unit"), [
    ("gt_x", "1.9e7", "m/s"), ("gt_y", "-1e7", "m/s"), ("enc_right", str(2**52), "rad/s"),
])
def test_a_jump_within_the_range_but_faster_than_any_vehicle_names_row_and_column(
        small_log, tmp_path, column, value, unit):
    write_log(small_log, tmp_path)
    set_cell(tmp_path, column, 3, value)
    with pytest.raises(LogFormatError, match=f"jump .* implausible .*{unit}") as err:
        read_log(tmp_path)
    assert err.value.column == column and err.value.row == 3
    assert "signals.csv" in str(err.value)


def test_a_ground_truth_gap_is_not_a_jump(small_log, tmp_path):
    # NaN cells are skipped: the rate is taken to the previous measured sample
    write_log(small_log, tmp_path)
    for row in (2, 3, 4):
        set_cell(tmp_path, "gt_x", row, "")
    assert np.isnan(read_log(tmp_path).signals["gt_x"][2])


def test_every_bounded_column_has_a_positive_finite_limit():
    for _, limit, unit in SIGNAL_BOUNDS:
        assert np.isfinite(limit) and limit > 0 and unit
