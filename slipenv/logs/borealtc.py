"""Adapter: BorealTC Husky A200 proprioceptive runs -> slipenv-log/1 (skid_steer, no truth).

Source: github.com/norlab-ulaval/BorealTC (commit fe64e386, ``data/borealtc/``); LaRocque,
Guimont-Martin, Duclos, Giguère, Pomerleau, "Proprioception Is All You Need: Terrain
Classification for Boreal Forests", IROS 2024, arXiv:2403.16877. Dataset license CC0 1.0;
the attribution travels in each log's ``meta.json``.

Per run ``<TERRAIN>/pro_XX.csv`` (``time`` [s], ``curL, curR`` [A], ``velL, velR`` [m/s], about
6.5 Hz; the MIXED run adds a per-sample ``terrain`` label) and ``<TERRAIN>/imu_XX.csv``
(``time`` [s], ``wx, wy, wz`` [rad/s], ``ax, ay, az`` [m/s^2], 100 Hz), some IMU files missing.
Both are read as the source repository lays them out (plain CSV) or gzip-compressed
(``.csv.gz``); a run without an IMU file, or an IMU file without a needed column, is
converted without those columns and a ``UserWarning`` names the file.

Conversion, and what is assumed:

- The log's time base is the wheel (``pro``) samples. Side speeds are divided by the nominal
  wheel radius and integrated (trapezoid) into cumulative counts at a *synthetic* resolution,
  ``COUNTS_PER_RAD`` = 1000 counts/rad (0.17 mm of travel, far below the source's speed
  quantum of 1/127 m/s); wheels ``left``/``right`` are the Husky's two sides.
- Geometry is nominal, from Clearpath's Husky A200 spec: wheel radius 0.165 m, track width
  0.555 m, mass 50 kg.
- Motor currents become extra columns ``current_left``, ``current_right`` [A].
- The IMU is assumed aligned with the body (x forward, y left, z up). ``gyro_z``, ``acc_x``,
  ``acc_y`` are the means of the 100 Hz samples over each wheel sample's interval (the
  half-way points to its neighbours), which avoids aliasing at 6.5 Hz.
- Both files' ``time`` starts at 0, but in several runs the two streams are offset by up to
  about 1.7 s (IMU yaw rate and wheel yaw rate correlate much better when shifted). With
  ``align_imu=True`` the shift maximising that correlation (within +-2 s) is applied when the
  run turns enough and the shift clearly helps; it is recorded in ``meta.json``.
- There is no ground-truth pose, so the logs are outside the contract's requirement and
  must be read with ``read_log(..., require_ground_truth=False)``.
"""

from __future__ import annotations

import csv
import gzip
import re
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import TextIO

import numpy as np

from slipenv.logs.errors import LogFormatError
from slipenv.logs.log import Log
from slipenv.logs.meta import LogMeta

WHEEL_RADIUS_M = 0.165  # [m] Husky A200 nominal (Clearpath spec), assumed
TRACK_WIDTH_M = 0.555  # [m] Husky A200 nominal (Clearpath spec), assumed
MASS_KG = 50.0  # [kg] Husky A200 nominal (Clearpath spec), assumed
COUNTS_PER_RAD = 1000.0  # [counts/rad] synthetic: counts are integrated from wheel speeds
MAX_LAG_S = 2.0  # [s] IMU time-shift search range
SOURCE = {
    "dataset": "BorealTC (data/borealtc)",
    "url": "https://github.com/norlab-ulaval/BorealTC",
    "commit": "fe64e386694528899db299e78a859dcab82f6b01",
    "authors": ["LaRocque", "Guimont-Martin", "Duclos", "Giguère", "Pomerleau"],
    "paper": "Proprioception Is All You Need: Terrain Classification for Boreal Forests, "
             "IROS 2024, arXiv:2403.16877",
    "license": "CC0 1.0 (dataset)",
}


@dataclass(frozen=True)
class BorealRun:
    """One BorealTC run: ``terrain`` folder, run index, ``pro`` file and IMU file (or None)."""

    terrain: str
    index: int
    pro_path: Path
    imu_path: Path | None

    @property
    def name(self) -> str:
        return f"{self.terrain}_{self.index:02d}"


IMU_COLUMNS = {"gyro_z": "wz", "acc_x": "ax", "acc_y": "ay"}
"""Log column -> IMU file column it is averaged from."""


def list_borealtc_runs(root: str | Path) -> list[BorealRun]:
    """All runs under ``root`` (the dataset folder), sorted by terrain and index.

    ``pro_XX`` and ``imu_XX`` files are found plain (``.csv``, the source repository's layout)
    or gzip-compressed (``.csv.gz``); the plain file wins when both are there.
    """
    found: dict[tuple[str, int], tuple[Path, str]] = {}
    for pro in sorted(Path(root).glob("*/pro_*.csv*")):
        match = re.fullmatch(r"pro_(\d+)\.csv(\.gz)?", pro.name)
        if match is None:
            continue
        key = (pro.parent.name, int(match[1]))
        if key not in found or not match[2]:
            found[key] = pro, match[1]
    runs = []
    for (terrain, index), (pro, number) in sorted(found.items()):
        imu = next((p for p in (pro.with_name(f"imu_{number}.csv"),
                                pro.with_name(f"imu_{number}.csv.gz")) if p.is_file()), None)
        runs.append(BorealRun(terrain, index, pro, imu))
    return runs


def _open_text(path: Path) -> TextIO:
    """A plain or gzip-compressed CSV file as text (a byte-order mark skipped)."""
    if path.suffix == ".gz":
        return gzip.open(path, "rt", encoding="utf-8-sig", newline="")
    return path.open(encoding="utf-8-sig", newline="")


def read_imu(path: Path) -> dict[str, np.ndarray]:
    """The columns of an ``imu_XX.csv[.gz]`` file by header name (``time``, ``wz``, ...)."""
    with _open_text(path) as fh:
        header = [h.strip() for h in fh.readline().split(",")]
        try:
            table = np.loadtxt(fh, delimiter=",", ndmin=2)
        except ValueError as exc:
            raise LogFormatError(path, f"unreadable IMU table ({exc})") from None
    if table.shape[1] != len(header):
        raise LogFormatError(path, f"{table.shape[1]} columns but {len(header)} header names")
    return {name: table[:, k] for k, name in enumerate(header)}


def load_borealtc_run(run: BorealRun, *, align_imu: bool = True) -> Log:
    """Convert one run into a skid_steer log without ground truth (see the module notes).

    Parameters
    ----------
    run : BorealRun
    align_imu : bool
        Shift the IMU time base to best match the wheel yaw rate (see module notes).

    Returns
    -------
    Log
        Columns ``t, enc_left, enc_right, current_left, current_right`` and, with an IMU file,
        ``gyro_z, acc_x, acc_y``. Validated with ``require_ground_truth=False``.
    """
    pro, labels = _read_pro(run.pro_path)
    t = pro["time"]
    cols: dict[str, np.ndarray] = {"t": t}
    for side, key in (("left", "L"), ("right", "R")):
        omega = pro[f"vel{key}"] / WHEEL_RADIUS_M  # [rad/s]
        angle = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(t))])
        cols[f"enc_{side}"] = np.round(angle * COUNTS_PER_RAD)
    if "curL" in pro:
        cols["current_left"], cols["current_right"] = pro["curL"], pro["curR"]
    borealtc: dict[str, object] = {"terrain": run.terrain, "run": run.index,
                                   "pro_file": f"{run.terrain}/{run.pro_path.name}",
                                   "imu_file": None}
    imu = _imu_streams(run)
    if imu and run.imu_path is not None:
        ts = imu["time"]
        lag, corr0, corr = 0.0, float("nan"), float("nan")
        if align_imu and "wz" in imu:
            yaw_rate_wheels = (pro["velR"] - pro["velL"]) / TRACK_WIDTH_M
            lag, corr0, corr = estimate_imu_lag(ts, imu["wz"], t, yaw_rate_wheels)
        for name, source in IMU_COLUMNS.items():
            if source in imu:
                cols[name] = window_mean(ts, imu[source], t + lag)
        borealtc.update(imu_file=f"{run.terrain}/{run.imu_path.name}", imu_time_shift_s=lag,
                        imu_yaw_rate_corr_unshifted=corr0, imu_yaw_rate_corr_shifted=corr)
    if labels:
        borealtc["terrain_labels"] = labels
    meta = LogMeta.new(
        "skid_steer", ["left", "right"], WHEEL_RADIUS_M, TRACK_WIDTH_M, COUNTS_PER_RAD,
        mass_kg=MASS_KG,
        terrain_description=f"BorealTC {run.terrain} (outdoor, boreal forest campaign)",
        notes=(f"BorealTC run {run.name}, converted by slipenv. Source: {SOURCE['url']} "
               f"(commit {SOURCE['commit'][:8]}, data/borealtc/); {SOURCE['paper']}; authors: "
               f"{', '.join(SOURCE['authors'])}. License: {SOURCE['license']}. No ground truth. "
               "Geometry and mass are nominal Husky A200 values (assumed); encoder counts are "
               "synthetic, integrated from the logged side speeds at 1000 counts/rad; "
               "current_* columns are motor currents [A]."),
        source=dict(SOURCE),
        ground_truth="none",
        assumed=["vehicle.wheel_radius_m", "vehicle.track_width_m", "vehicle.mass_kg",
                 "vehicle.counts_per_rad (synthetic)", "IMU axes aligned with body"],
        borealtc={k: _json_float(v) for k, v in borealtc.items()},
    )
    return Log.from_arrays(meta, require_ground_truth=False, **cols)


def _imu_streams(run: BorealRun) -> dict[str, np.ndarray]:
    """The run's IMU columns; empty, with a warning naming the file, when it has none."""
    if run.imu_path is None:
        folder = run.pro_path.parent
        warnings.warn(f"BorealTC run {run.name}: no IMU file ({folder / f'imu_{run.index:02d}'}"
                      ".csv or .csv.gz); the log has no gyro_z, acc_x, acc_y", stacklevel=3)
        return {}
    imu = read_imu(run.imu_path)
    if "time" not in imu:
        warnings.warn(f"BorealTC run {run.name}: {run.imu_path} has no 'time' column; the log "
                      "has no gyro_z, acc_x, acc_y", stacklevel=3)
        return {}
    missing = [f"{name} (from '{src}')" for name, src in IMU_COLUMNS.items() if src not in imu]
    if missing:
        warnings.warn(f"BorealTC run {run.name}: {run.imu_path} lacks the columns of "
                      f"{', '.join(missing)}; the log has none of them", stacklevel=3)
    return imu


def window_mean(ts: np.ndarray, y: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Mean of ``y(ts)`` over each target sample's interval (half-way to its neighbours).

    Interval i is ``[lo_i, hi_i)`` with ``lo_i``, ``hi_i`` the half-way points to the
    neighbouring targets (mirrored at both ends), so every source sample counts once.

    Parameters
    ----------
    ts, y : ndarray, shape (m,)
        Source times [s] (increasing) and values.
    t : ndarray, shape (n,)
        Target times [s] (increasing).

    Returns
    -------
    ndarray, shape (n,)
        NaN where an interval holds no source sample.
    """
    edges = np.empty(len(t) + 1)
    if len(t) > 1:
        edges[1:-1] = 0.5 * (t[1:] + t[:-1])
        edges[0], edges[-1] = 2 * t[0] - edges[1], 2 * t[-1] - edges[-2]
    else:
        edges[:] = [-np.inf, np.inf]
    idx = np.searchsorted(ts, edges, side="left")
    csum = np.concatenate([[0.0], np.cumsum(y)])
    count = np.diff(idx)
    with np.errstate(invalid="ignore", divide="ignore"):
        out = (csum[idx[1:]] - csum[idx[:-1]]) / count
    out[count == 0] = np.nan
    return out


def estimate_imu_lag(ts: np.ndarray, gyro_z: np.ndarray, t: np.ndarray,
                     yaw_rate_wheels: np.ndarray) -> tuple[float, float, float]:
    """Time shift of the IMU clock that best aligns its yaw rate with the wheels' [s].

    Searches shifts in [-``MAX_LAG_S``, ``MAX_LAG_S``] (0.02 s steps) for the highest
    correlation between ``gyro_z`` and ``(v_R - v_L) / B``. The shift is kept only if the run
    turns (std of the wheel yaw rate > 0.1 rad/s), the best correlation is at least 0.5 and
    it beats the unshifted one by more than 0.02; otherwise 0.

    Returns
    -------
    lag_s : float
        IMU time = wheel time + ``lag_s``.
    corr_unshifted, corr_shifted : float
        Correlations at 0 and at ``lag_s`` (NaN when the run does not turn enough).
    """
    if np.std(yaw_rate_wheels) <= 0.1:
        return 0.0, float("nan"), float("nan")

    def corr(lag: float) -> float:
        g = window_mean(ts, gyro_z, t + lag)
        ok = np.isfinite(g)
        return float(np.corrcoef(g[ok], yaw_rate_wheels[ok])[0, 1]) if ok.sum() > 10 else -1.0

    lags = np.round(np.arange(-MAX_LAG_S, MAX_LAG_S + 1e-9, 0.02), 2)
    scores = np.array([corr(lag) for lag in lags])
    best = int(np.argmax(scores))
    c0 = corr(0.0)
    if scores[best] >= 0.5 and scores[best] > c0 + 0.02:
        return float(lags[best]), c0, float(scores[best])
    return 0.0, c0, c0


def _read_pro(path: Path) -> tuple[dict[str, np.ndarray], list[list[object]]]:
    """Numeric columns of a ``pro_XX.csv`` and, if present, terrain label intervals."""
    with _open_text(path) as fh:
        reader = csv.DictReader(fh)
        rows = list(reader)
        names = [n.strip() for n in reader.fieldnames or []]
    missing = [k for k in ("time", "velL", "velR") if k not in names]
    if missing:
        raise LogFormatError(path, f"no {', '.join(map(repr, missing))} column (BorealTC "
                             "pro_XX files hold time, curL, curR, velL, velR)")
    keys = ["time", "velL", "velR"]
    absent = [k for k in ("curL", "curR") if k not in names]
    if absent:
        warnings.warn(f"{path}: no {' or '.join(absent)} column; the log has no motor "
                      "currents", stacklevel=3)
    else:
        keys += ["curL", "curR"]
    try:
        cols = {k: np.array([float(r[k]) for r in rows]) for k in keys}
    except (TypeError, ValueError):
        line = next(i for i, r in enumerate(rows, 2) if not _numeric(r, keys))
        raise LogFormatError(path, "missing or non-numeric value", line=line) from None
    labels: list[list[object]] = []
    if rows and "terrain" in rows[0]:
        for r, t in zip(rows, cols["time"], strict=True):
            label = r["terrain"].strip() or "unlabelled"
            if labels and labels[-1][2] == label:
                labels[-1][1] = float(t)
            else:
                labels.append([float(t), float(t), label])
    return cols, labels


def _numeric(row: dict[str, str], keys: list[str]) -> bool:
    try:
        [float(row[k]) for k in keys]
    except (TypeError, ValueError):
        return False
    return True


def _json_float(value: object) -> object:
    """NaN is not JSON: store it as null."""
    return None if isinstance(value, float) and np.isnan(value) else value
