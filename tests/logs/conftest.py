"""Shared fixtures for the log tests: a small valid log, and the real datasets if present."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from slipenv.logs import Log, LogMeta
from slipenv.logs.real import default_data_root

COUNTS_PER_RAD = 100.0  # [counts/rad] of the synthetic logs


def synthetic_log(n: int = 10, dt: float = 0.1) -> Log:
    """Diff-drive log: wheels turning at 1 and 2 rad/s, ground truth missing for t in [0.3, 0.5]."""
    t = np.arange(n) * dt
    gt_x = 0.5 * t
    gt_x[(t > 0.25) & (t < 0.55)] = np.nan
    meta = LogMeta.new("diff_drive", ["left", "right"], wheel_radius_m=0.25, track_width_m=1.6,
                       counts_per_rad=COUNTS_PER_RAD, notes="synthetic",
                       operator={"name": "test", "tags": ["a", "b"]})
    meta.data["vehicle"]["tyre"] = "agricultural"  # unknown key inside a known object
    return Log.from_arrays(
        meta.data,
        t=t,
        enc_left=np.round(1.0 * t * COUNTS_PER_RAD),
        enc_right=np.round(2.0 * t * COUNTS_PER_RAD),
        gyro_z=np.sin(t) / 3.0,
        gt_x=gt_x,
        gt_y=np.where(np.isnan(gt_x), np.nan, 0.1 * t),
        gt_yaw=np.where(np.isnan(gt_x), np.nan, 1e-3 + t / 7.0),
        current_left=np.full(n, 2.5),
    )


@pytest.fixture
def small_log() -> Log:
    return synthetic_log()


@pytest.fixture(scope="session")
def real_root() -> Path:
    root = default_data_root()
    if not (root / "optiodom-diffdrive").is_dir() or not (root / "borealtc-husky").is_dir():
        pytest.skip(f"real datasets not found under {root}")
    return root
