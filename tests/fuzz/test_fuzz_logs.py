"""Fuzz ``read_log`` with corrupted logs: each is read with finite, plausible values or
refused with a ``LogFormatError`` (a ``ValueError``) naming the file."""

from __future__ import annotations

import json
import math
import tempfile
from pathlib import Path

import numpy as np
from hypothesis import given
from hypothesis import strategies as st

from slipenv.logs import LogFormatError, read_log, write_log
from slipenv.logs.bounds import signal_bound

from ..logs.conftest import synthetic_log
from .conftest import CSV_CORRUPTIONS, FUZZ, corrupt_csv, corruptions, time_limit

CELLS = st.one_of(
    st.sampled_from(["", "nan", "NaN", "inf", "-inf", "1e300", "1e308", "-1e30", "95", "0x10",
                     "1,5", "abc", "\"", "1e-320", "3.5", "-0", " 7 ", "1_000", "∞"]),
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.text(max_size=4),
)
META_VALUES = st.sampled_from([None, -1.0, 0.0, 95.0, 1e9, 1e300, "x", [], {}, True, 2,
                               "rover4ws", ["left"], ["l", "l"]])
META_KEYS = [("vehicle", "kind"), ("vehicle", "wheels"), ("vehicle", "wheel_radius_m"),
             ("vehicle", "track_width_m"), ("vehicle", "counts_per_rad"),
             ("vehicle", "mass_kg"), ("vehicle", "wheelbase_m"), ("terrain", "slope_deg"),
             ("terrain", "slope_downhill_azimuth_deg"), ("format", None), ("notes", None)]


CASES = corruptions(("meta", "meta_drop", "bytes"), CELLS, META_VALUES, META_KEYS)


def corrupt(folder: Path, case) -> None:
    kind, k, cell, meta_value, (section, key) = case
    signals, meta = folder / "signals.csv", folder / "meta.json"
    if kind in CSV_CORRUPTIONS:
        corrupt_csv(signals, kind, k, cell)
    elif kind == "bytes":
        data = bytearray(signals.read_bytes())
        data[k % len(data)] = 0xFF
        signals.write_bytes(bytes(data))
    else:
        data = json.loads(meta.read_text())
        target = data if key is None else data.setdefault(section, {})
        name = section if key is None else key
        if kind == "meta":
            target[name] = meta_value
        else:
            target.pop(name, None)
        meta.write_text(json.dumps(data))


@FUZZ
@given(case=CASES)
def test_a_corrupted_log_is_read_plausibly_or_refused_naming_the_file(case):
    with tempfile.TemporaryDirectory() as tmp, time_limit():
        folder = Path(tmp) / "log"
        write_log(synthetic_log(), folder)
        corrupt(folder, case)
        try:
            log = read_log(folder)
        except LogFormatError as exc:
            assert isinstance(exc, ValueError)
            assert "signals.csv" in str(exc) or "meta.json" in str(exc) or str(folder) in str(
                exc)
            return
        for name, values in log.signals.items():
            assert not np.any(np.isinf(values)), name
            bound = signal_bound(name, log.meta.wheels)
            if bound is not None:
                assert np.all(np.isnan(values) | (np.abs(values) <= bound[0])), name
        assert math.isfinite(log.meta.track_width_m) and log.meta.track_width_m <= 20.0
