"""Writing and reading slipenv-log/1 folders: values, NaN gaps and unknown keys survive."""

from __future__ import annotations

import json

import numpy as np
import pytest

from slipenv.logs import Log, LogFormatError, LogMeta, read_log, write_log


def test_round_trip_preserves_every_value_bit_for_bit(small_log, tmp_path):
    write_log(small_log, tmp_path / "log")
    back = read_log(tmp_path / "log")
    assert back.columns == small_log.columns
    for name, values in small_log.signals.items():
        np.testing.assert_array_equal(back.signals[name], values, err_msg=name)


def test_round_trip_keeps_unknown_meta_keys(small_log, tmp_path):
    write_log(small_log, tmp_path / "log")
    back = read_log(tmp_path / "log")
    assert back.meta.data == small_log.meta.data
    assert back.meta.data["operator"] == {"name": "test", "tags": ["a", "b"]}
    assert back.meta.data["vehicle"]["tyre"] == "agricultural"


def test_rewriting_a_read_log_gives_identical_files(small_log, tmp_path):
    write_log(small_log, tmp_path / "a")
    write_log(read_log(tmp_path / "a"), tmp_path / "b")
    for name in ("meta.json", "signals.csv"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()


def test_written_csv_has_integer_counts_and_empty_cells_for_nan(small_log, tmp_path):
    write_log(small_log, tmp_path / "log")
    lines = (tmp_path / "log" / "signals.csv").read_text().splitlines()
    header = lines[0].split(",")
    assert header[0] == "t"
    row4 = dict(zip(header, lines[4].split(","), strict=True))  # t = 0.3: no ground truth
    assert row4["enc_right"] == "60"
    assert row4["gt_x"] == row4["gt_y"] == row4["gt_yaw"] == ""


def test_meta_accessors_return_typed_si_values(small_log):
    meta = small_log.meta
    assert meta.kind == "diff_drive"
    assert meta.wheels == ["left", "right"]
    assert (meta.wheel_radius_m, meta.track_width_m, meta.counts_per_rad) == (0.25, 1.6, 100.0)
    assert meta.wheelbase_m is None and meta.mass_kg is None
    assert (meta.soil, meta.slope_deg, meta.slope_downhill_azimuth_deg) == ("rigid", 0.0, None)


def test_reader_accepts_nan_text_bom_and_extra_whitespace(tmp_path):
    folder = tmp_path / "log"
    folder.mkdir()
    meta = LogMeta.new("skid_steer", ["l", "r"], 0.1, 0.4, 50.0)
    (folder / "meta.json").write_text(json.dumps(meta.data))
    (folder / "signals.csv").write_text(
        "\ufefft, enc_l ,enc_r,gt_x,gt_y,gt_yaw\n0,0,0,0,0,0\n0.5, 3 ,-4,nan,NaN,\n",
        encoding="utf-8")
    log = read_log(folder)
    assert log.columns == ["t", "enc_l", "enc_r", "gt_x", "gt_y", "gt_yaw"]
    np.testing.assert_array_equal(log.signals["enc_l"], [0.0, 3.0])
    np.testing.assert_array_equal(log.gt_mask, [True, False])


def test_from_arrays_puts_t_first_and_stores_float64(small_log):
    meta = small_log.meta.data
    log = Log.from_arrays(meta, enc_left=[0, 1], enc_right=[0, 2], t=[0.0, 0.1],
                          gt_x=[0, 0], gt_y=[0, 0], gt_yaw=[0, 0])
    assert log.columns[0] == "t"
    assert all(v.dtype == np.float64 for v in log.signals.values())


def test_from_arrays_rejects_columns_of_different_lengths(small_log):
    with pytest.raises(LogFormatError, match=r"<arrays>.*column 'enc_right'"):
        Log.from_arrays(small_log.meta.data, t=[0.0, 0.1], enc_left=[0, 1], enc_right=[0],
                        gt_x=[0, 0], gt_y=[0, 0], gt_yaw=[0, 0])


def test_from_arrays_without_ground_truth_needs_the_explicit_flag(small_log):
    cols = {"t": [0.0, 0.1], "enc_left": [0, 1], "enc_right": [0, 2]}
    with pytest.raises(LogFormatError, match="gt_x"):
        Log.from_arrays(small_log.meta.data, **cols)
    assert len(Log.from_arrays(small_log.meta.data, require_ground_truth=False, **cols)) == 2


def test_writer_refuses_an_invalid_log(small_log, tmp_path):
    small_log.signals["t"][3] = small_log.signals["t"][2]
    with pytest.raises(LogFormatError, match=r"data row 4, column 't'"):
        write_log(small_log, tmp_path / "log")
    assert not (tmp_path / "log").exists()
