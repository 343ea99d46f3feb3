"""The test-bed measurement format: ``trials.csv`` plus ``meta.json`` in one directory.

``trials.csv`` has one row per steady trial (a header row, comma-separated, SI units):

=================  ========  ==============================================================
column             required  meaning
=================  ========  ==============================================================
slip_ratio         yes       s [-] in [-1, 1]; s = 1 - v_x/(r omega) > 0 driving (Reina Eq. 3)
slip_angle_deg     yes       beta [deg] = atan(v_lat/v_x) (Reina Eq. 4), |beta| < 90; v_lat
                             is the wheel's sliding velocity to its LEFT
normal_load_n      yes       vertical load W [N], >= 0
fx_n               yes       longitudinal force on the wheel [N], > 0 pushes it forward
                             along its heading (net force at the carriage: drawbar pull)
fy_n               yes       lateral force on the wheel [N], > 0 pushes it to its left; the
                             soil opposes sliding, so fy_n < 0 when slip_angle_deg > 0
sinkage_m          no        wheel sinkage [m], >= 0
fx_std_n, fy_std_n no        standard deviation of fx_n, fy_n within the trial [N], >= 0
=================  ========  ==============================================================

``meta.json``: ``{"wheel_radius_m": r, "wheel_width_m": b, "contact_length_m": L (optional,
default r/2), "slip_angle_definition": "reina" (Eq. 4, default) | "simulation", "notes": ...}``
and a ``"sign_conventions"`` text the writer fills in. ``slip_angle_definition`` says what
``slip_angle_deg`` measures: ``"reina"``, tan beta = v_lat/v_x (Reina Eq. 4, a real rig's
geometric angle); ``"simulation"``, tan beta = v_lat/max(|r omega|, |v_x|), the direction of
the contact point's sliding velocity (in drive (1 - s) times Reina's), below 45 deg. fit-soil
converts each trial to the slip state the simulation feeds each law
(`slipenv.testbed.fit.convert_slip_state`). A bad file raises `ValueError` naming the
file, the row (1 = first data row) and the column; so does a value no test bed measures (a
force or load beyond 1e6 N, sinkage beyond 4 m, a wheel size beyond 2 m: a unit mistake or a
corrupted cell).
"""

from __future__ import annotations

import csv
import json
import math
import pathlib
from dataclasses import dataclass

import numpy as np

__all__ = ["REQUIRED_COLUMNS", "OPTIONAL_COLUMNS", "SIGN_CONVENTIONS", "TestBedData",
           "read_testbed", "write_testbed"]

REQUIRED_COLUMNS = ("slip_ratio", "slip_angle_deg", "normal_load_n", "fx_n", "fy_n")
OPTIONAL_COLUMNS = ("sinkage_m", "fx_std_n", "fy_std_n")
SIGN_CONVENTIONS = (
    "slip_ratio s = 1 - v_x/(r omega) (> 0 driving); slip_angle_deg = atan(v_lat/v_x) with "
    "v_lat the wheel's sliding velocity to its left; fx_n > 0 pushes the wheel forward along "
    "its heading; fy_n > 0 pushes it to its left (fy_n < 0 for slip_angle_deg > 0)")
CSV_NAME, META_NAME = "trials.csv", "meta.json"


@dataclass(frozen=True)
class TestBedData:
    """Validated test-bed measurements: arrays of shape (n,), NaN where an optional column is
    absent; `meta` is the parsed ``meta.json``."""

    __test__ = False  # not a pytest class

    slip_ratio: np.ndarray
    slip_angle_deg: np.ndarray
    normal_load_n: np.ndarray
    fx_n: np.ndarray
    fy_n: np.ndarray
    sinkage_m: np.ndarray
    fx_std_n: np.ndarray
    fy_std_n: np.ndarray
    meta: dict

    @property
    def n(self) -> int:
        """Number of trials."""
        return int(self.slip_ratio.size)

    @property
    def tan_beta(self) -> np.ndarray:
        """tan of the slip angle [-]."""
        return np.tan(np.radians(self.slip_angle_deg))


# Largest magnitudes a test-bed trial can hold (as ``slipenv.logs.bounds``: wide enough for a
# mining truck's wheel, so that only a corrupted cell, a unit mistake or an overflow trips them).
MAX_FORCE_N = 1e6  # a 100 t load on one wheel
MAX_SINKAGE_M = 4.0  # twice the largest tyre's radius
MAX_WHEEL_M = 2.0  # radius, width, contact length: the largest tyres (``VehicleSpec`` too)


def _check_value(col: str, x: float, where: str) -> None:
    if not math.isfinite(x):
        raise ValueError(f"{where}, column {col!r}: {x!r} is not a finite number")
    limit = MAX_SINKAGE_M if col == "sinkage_m" else MAX_FORCE_N
    if col not in ("slip_ratio", "slip_angle_deg") and abs(x) > limit:
        raise ValueError(f"{where}, column {col!r}: {x!r} is beyond {limit:g} (not a "
                         f"test-bed trial: a unit mistake or a corrupted cell)")
    if col == "slip_ratio" and not -1.0 <= x <= 1.0:
        raise ValueError(f"{where}, column 'slip_ratio': {x!r} is outside [-1, 1]")
    if col == "slip_angle_deg" and not abs(x) < 90.0:
        raise ValueError(f"{where}, column 'slip_angle_deg': {x!r} is outside (-90, 90)")
    if col in ("normal_load_n", "sinkage_m", "fx_std_n", "fy_std_n") and x < 0.0:
        raise ValueError(f"{where}, column {col!r}: {x!r} is negative")


def _read_meta(path: pathlib.Path) -> dict:
    if not path.is_file():
        raise ValueError(f"{path}: missing (test-bed meta data: wheel radius and width)")
    try:
        meta = json.loads(path.read_text())
    except json.JSONDecodeError as exc:
        raise ValueError(f"{path}: not valid JSON ({exc})") from None
    if not isinstance(meta, dict):
        raise ValueError(f"{path}: must hold a JSON object")
    for key in ("wheel_radius_m", "wheel_width_m"):
        _check_size(path, key, meta.get(key))
    _check_size(path, "contact_length_m",
                meta.setdefault("contact_length_m", 0.5 * meta["wheel_radius_m"]))
    definition = meta.setdefault("slip_angle_definition", "reina")
    if definition not in ("reina", "simulation"):
        raise ValueError(f"{path}: key 'slip_angle_definition' must be 'reina' or "
                         f"'simulation', got {definition!r}")
    return meta


def _check_size(path: pathlib.Path, key: str, value) -> None:
    if not (isinstance(value, int | float) and not isinstance(value, bool)
            and math.isfinite(value) and 0.0 < value <= MAX_WHEEL_M):
        raise ValueError(f"{path}: key {key!r} must be a number in (0, {MAX_WHEEL_M:g}] m, "
                         f"got {value!r}")


def read_testbed(directory: str | pathlib.Path) -> TestBedData:
    """Read and validate ``trials.csv`` and ``meta.json`` from `directory`.

    Raises
    ------
    ValueError
        Naming the file, row (1 = first data row) and column: a missing required column, a
        value that is not a number, a slip outside [-1, 1], a negative load, sinkage or std.
    """
    directory = pathlib.Path(directory)
    meta = _read_meta(directory / META_NAME)
    path = directory / CSV_NAME
    if not path.is_file():
        raise ValueError(f"{path}: missing (one row per trial, columns {REQUIRED_COLUMNS})")
    with path.open(newline="") as fh:
        reader = csv.DictReader(fh)
        header = [h.strip() for h in (reader.fieldnames or [])]
        missing = [c for c in REQUIRED_COLUMNS if c not in header]
        if missing:
            raise ValueError(f"{path}, row 0 (header): missing column(s) "
                             f"{', '.join(repr(c) for c in missing)}")
        present = [c for c in REQUIRED_COLUMNS + OPTIONAL_COLUMNS if c in header]
        cols: dict[str, list[float]] = {c: [] for c in present}
        for i, raw in enumerate(reader, start=1):
            row = {(k or "").strip(): v for k, v in raw.items()}
            where = f"{path}, row {i}"
            for c in present:
                text = (row.get(c) or "").strip()
                if text == "" and c in OPTIONAL_COLUMNS:
                    cols[c].append(math.nan)
                    continue
                try:
                    x = float(text)
                except ValueError:
                    raise ValueError(f"{where}, column {c!r}: {text!r} is not a number") from None
                _check_value(c, x, where)
                cols[c].append(x)
    n = len(cols["slip_ratio"])
    if n == 0:
        raise ValueError(f"{path}: no data rows")
    arrays = {c: np.array(cols[c], dtype=float) if c in cols else np.full(n, np.nan)
              for c in REQUIRED_COLUMNS + OPTIONAL_COLUMNS}
    return TestBedData(**arrays, meta=meta)


def write_testbed(directory: str | pathlib.Path, rows: list[dict], meta: dict) -> pathlib.Path:
    """Write `rows` (dicts with the CSV's columns) and `meta` to `directory`; returns it.

    `meta` needs ``wheel_radius_m`` and ``wheel_width_m``; ``sign_conventions`` is added.
    """
    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    columns = list(REQUIRED_COLUMNS) + [c for c in OPTIONAL_COLUMNS
                                        if any(c in r for r in rows)]
    with (directory / CSV_NAME).open("w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns, extrasaction="ignore")
        writer.writeheader()
        for r in rows:
            writer.writerow({c: (repr(float(r[c])) if c in r else "") for c in columns})
    full = {**meta, "sign_conventions": SIGN_CONVENTIONS}
    (directory / META_NAME).write_text(json.dumps(full, indent=2) + "\n")
    _read_meta(directory / META_NAME)  # the writer checks what it wrote
    return directory
