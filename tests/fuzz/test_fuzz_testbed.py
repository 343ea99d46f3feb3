"""Fuzz ``read_testbed`` (what ``slipenv fit-soil`` reads) with corrupted test-bed folders: each
is read with finite values a test bed can measure, or refused with a ``ValueError`` naming the
file."""

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from slipenv.testbed.csv_format import (
    MAX_FORCE_N,
    MAX_SINKAGE_M,
    MAX_WHEEL_M,
    read_testbed,
    write_testbed,
)

from .conftest import CSV_CORRUPTIONS, FUZZ, corrupt_csv, corruptions, time_limit

META = {"wheel_radius_m": 0.092, "wheel_width_m": 0.11}
ROWS = [{"slip_ratio": s, "slip_angle_deg": a, "normal_load_n": 64.7, "fx_n": 40.0 * s,
         "fy_n": -0.5 * a, "sinkage_m": 0.01, "fx_std_n": 0.2, "fy_std_n": 0.3}
        for s in (0.05, 0.2, 0.5) for a in (0.0, 10.0)]
CELLS = st.one_of(
    st.sampled_from(["", "nan", "inf", "-inf", "1e300", "-1e7", "95", "-90", "1.5", "-0",
                     "abc", "1,5", "\"", "1e-320", "0x10", "∞", " 7 "]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.text(max_size=4),
)
META_VALUES = st.sampled_from([None, -1.0, 0.0, 1e-9, 3.0, 1e300, math.inf, "x", [], True,
                               "simulation", "wrong"])
META_KEYS = ["wheel_radius_m", "wheel_width_m", "contact_length_m", "slip_angle_definition"]


CASES = corruptions(("meta", "meta_drop", "meta_text"), CELLS, META_VALUES, META_KEYS)


def corrupt(folder: Path, case) -> None:
    kind, k, cell, meta_value, key = case
    if kind in CSV_CORRUPTIONS:
        corrupt_csv(folder / "trials.csv", kind, k, cell)
        return
    meta = folder / "meta.json"
    data = json.loads(meta.read_text())
    if kind == "meta":
        data[key] = meta_value
    elif kind == "meta_drop":
        data.pop(key, None)
    meta.write_text(json.dumps(data) if kind != "meta_text" else json.dumps(data)[:k % 40])


@FUZZ
@given(case=CASES)
def test_a_corrupted_test_bed_folder_is_read_plausibly_or_refused_naming_the_file(case):
    with tempfile.TemporaryDirectory() as tmp, time_limit():
        folder = Path(tmp)
        write_testbed(folder, ROWS, META)
        corrupt(folder, case)
        try:
            data = read_testbed(folder)
        except ValueError as exc:
            assert "trials.csv" in str(exc) or "meta.json" in str(exc), str(exc)
            return
    assert data.n >= 1
    assert np.all(np.abs(data.slip_ratio) <= 1.0) and np.all(np.abs(data.slip_angle_deg) < 90)
    for values in (data.normal_load_n, data.fx_n, data.fy_n, data.fx_std_n, data.fy_std_n):
        assert np.all(np.isnan(values) | (np.abs(values) <= MAX_FORCE_N))
    assert np.all(np.isnan(data.sinkage_m) | (np.abs(data.sinkage_m) <= MAX_SINKAGE_M))
    assert np.all(np.isfinite(data.slip_ratio) & np.isfinite(data.fx_n))
    for key in ("wheel_radius_m", "wheel_width_m", "contact_length_m"):
        assert 0.0 < data.meta[key] <= MAX_WHEEL_M and not isinstance(data.meta[key], bool)
    assert data.meta["slip_angle_definition"] in ("reina", "simulation")
