"""Malformed logs raise LogFormatError naming the file, the row (or line) and the column."""

from __future__ import annotations

import json
from collections.abc import Callable
from pathlib import Path

import pytest

from slipenv.logs import LogFormatError, read_log, write_log


def _edit_csv(fn: Callable[[list[list[str]]], None]) -> Callable[[Path], None]:
    def edit(folder: Path) -> None:
        path = folder / "signals.csv"
        rows = [line.split(",") for line in path.read_text().splitlines()]
        fn(rows)
        path.write_text("\n".join(",".join(r) for r in rows) + "\n")
    return edit


def _edit_meta(fn: Callable[[dict], None]) -> Callable[[Path], None]:
    def edit(folder: Path) -> None:
        path = folder / "meta.json"
        data = json.loads(path.read_text())
        fn(data)
        path.write_text(json.dumps(data, indent=2))
    return edit


def _cell(row: int, column: int, value: str) -> Callable[[list[list[str]]], None]:
    def fn(rows: list[list[str]]) -> None:
        rows[row][column] = value  # rows[0] is the header, rows[k] is data row k
    return fn


def _drop_column(name: str) -> Callable[[list[list[str]]], None]:
    def fn(rows: list[list[str]]) -> None:
        k = rows[0].index(name)
        for r in rows:
            del r[k]
    return fn


def _set(keys: tuple[str, ...], value: object) -> Callable[[dict], None]:
    def fn(data: dict) -> None:
        for key in keys[:-1]:
            data = data[key]
        data[keys[-1]] = value
    return fn


def _bad_json(folder: Path) -> None:
    path = folder / "meta.json"
    path.write_text(path.read_text().replace('"slipenv-log/1",', '"slipenv-log/1"', 1))


def _delete(name: str) -> Callable[[Path], None]:
    return lambda folder: (folder / name).unlink()


def _blank_ground_truth(rows: list[list[str]]) -> None:
    for name in ("gt_x", "gt_y", "gt_yaw"):
        k = rows[0].index(name)
        for r in rows[1:]:
            r[k] = ""


def _drop_wheels(data: dict) -> None:
    del data["vehicle"]["wheels"]


# Columns of the synthetic log: t, enc_left, enc_right, gyro_z, gt_x, gt_y, gt_yaw, current_left
# (id, edit, file, location in the message, column/key in the message)
CASES = [
    ("missing column", _edit_csv(_drop_column("enc_right")), "signals.csv", "line 1",
     "column 'enc_right'"),
    ("time not increasing", _edit_csv(_cell(4, 0, "0.2")), "signals.csv",
     "data row 4 (line 5)", "column 't'"),
    ("non-integer counts", _edit_csv(_cell(2, 1, "2.5")), "signals.csv",
     "data row 2 (line 3)", "column 'enc_left'"),
    ("unknown kind", _edit_meta(_set(("vehicle", "kind"), "tank")), "meta.json", "line 4",
     "key 'vehicle.kind'"),
    ("nan in t", _edit_csv(_cell(3, 0, "nan")), "signals.csv", "data row 3 (line 4)",
     "column 't'"),
    ("empty count", _edit_csv(_cell(6, 2, "")), "signals.csv", "data row 6 (line 7)",
     "column 'enc_right'"),
    ("ragged row", _edit_csv(lambda rows: rows[5].pop()), "signals.csv",
     "data row 5 (line 6)", "column 'current_left'"),
    ("non-numeric cell", _edit_csv(_cell(7, 3, "fast")), "signals.csv",
     "data row 7 (line 8)", "column 'gyro_z'"),
    ("bad json", _bad_json, "meta.json", "line 3", "character 3"),
    ("wrong format string", _edit_meta(_set(("format",), "slipenv-log/2")), "meta.json",
     "line 2", "key 'format'"),
    ("wheels missing", _edit_meta(_drop_wheels), "meta.json", "line 3", "key 'vehicle.wheels'"),
    ("negative wheel radius", _edit_meta(_set(("vehicle", "wheel_radius_m"), -0.2)),
     "meta.json", "line 9", "key 'vehicle.wheel_radius_m'"),
    ("zero track width", _edit_meta(_set(("vehicle", "track_width_m"), 0)), "meta.json",
     "line 10", "key 'vehicle.track_width_m'"),
    ("no ground truth values", _edit_csv(_blank_ground_truth), "signals.csv", "line 1",
     "column 'gt_x'"),
    ("missing signals.csv", _delete("signals.csv"), "signals.csv", "", ""),
    ("missing meta.json", _delete("meta.json"), "meta.json", "", ""),
]


@pytest.mark.parametrize(("edit", "file", "where", "column"),
                         [c[1:] for c in CASES], ids=[c[0] for c in CASES])
def test_malformed_log_error_names_file_row_and_column(small_log, tmp_path, edit, file, where,
                                                       column):
    folder = write_log(small_log, tmp_path / "log")
    edit(folder)
    with pytest.raises(LogFormatError) as info:
        read_log(folder)
    message = str(info.value)
    assert str(folder / file) in message
    assert where in message
    assert column in message
    assert info.value.path == folder / file


def test_error_carries_row_line_and_column_attributes(small_log, tmp_path):
    folder = write_log(small_log, tmp_path / "log")
    _edit_csv(_cell(2, 1, "2.5"))(folder)
    with pytest.raises(LogFormatError) as info:
        read_log(folder)
    err = info.value
    assert (err.row, err.line, err.column) == (2, 3, "enc_left")
    assert isinstance(err, ValueError)


def test_rover4ws_requires_steering_columns_and_wheelbase(small_log, tmp_path):
    folder = write_log(small_log, tmp_path / "log")
    _edit_meta(_set(("vehicle", "kind"), "rover4ws"))(folder)
    with pytest.raises(LogFormatError, match="wheelbase_m"):
        read_log(folder)
    _edit_meta(_set(("vehicle", "wheelbase_m"), 1.2))(folder)
    with pytest.raises(LogFormatError, match=r"line 1, column 'steer_left'"):
        read_log(folder)


def test_blank_line_inside_the_data_is_rejected(small_log, tmp_path):
    folder = write_log(small_log, tmp_path / "log")
    path = folder / "signals.csv"
    lines = path.read_text().splitlines()
    path.write_text("\n".join([*lines[:5], "", *lines[5:]]) + "\n")
    with pytest.raises(LogFormatError, match=r"line 6.*blank line"):
        read_log(folder)
