"""Shared fixtures of the diagnosis tests: hidden-effect logs from the physics, made once.

Seeds are fixed so a failure can be reproduced; ``SLIPENV_DIAGNOSE_SEED=<int>`` shifts them
(``random`` draws a new shift, printed in the test header) to test on logs never seen before.
``benchmarks/diagnose_hit_rate.py`` measures the hit rate over many fresh logs.
"""

from __future__ import annotations

import os
import warnings

import numpy as np
import pytest

from slipenv.diagnose import synth
from slipenv.diagnose.fit import Problem
from slipenv.diagnose.replay import build_segments
from slipenv.diagnose.select import select

_RAW = os.environ.get("SLIPENV_DIAGNOSE_SEED", "0")
# "random": a fresh shift from OS entropy (printed in the header so a failure can be rerun).
SEED_SHIFT = (int(np.random.default_rng().integers(1, 10**6)) if _RAW == "random"
              else int(_RAW))
DURATION_S = 60.0  # [s] short logs keep the suite fast; the benchmark uses 5-minute logs

# (effect, kind, seed): the cases every run checks
CASES = [
    ("none", "diff_drive", 1), ("none", "skid_steer", 2),
    ("rolling_radius", "diff_drive", 3), ("track_width", "diff_drive", 4),
    ("gyro_bias", "skid_steer", 5), ("torque_slip", "diff_drive", 6),
    ("turning_slip", "skid_steer", 7), ("torque_slip", "rover4ws", 8),
]


def pytest_report_header(config):
    return f"slipenv diagnose tests: seed shift {SEED_SHIFT} (SLIPENV_DIAGNOSE_SEED)"


class Diagnosed:
    """A generated log and its diagnosis."""

    def __init__(self, effect: str, kind: str, seed: int) -> None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.synth = synth.generate(seed + SEED_SHIFT, effect, kind, duration_s=DURATION_S)
            self.seg = build_segments([self.synth.log])
            self.problem = Problem.from_segments(self.seg)
            self.selection = select(self.problem, logs=[self.synth.log])

    def parameters(self) -> dict[str, list[float]]:
        out: dict[str, list[float]] = {}
        for fit in self.selection.fits.values():
            out.update(fit.report(self.seg))
        return out


@pytest.fixture(scope="session")
def diagnosed():
    """``diagnosed(effect, kind, seed)`` -> Diagnosed, each case built once per session."""
    cache: dict[tuple, Diagnosed] = {}

    def get(effect: str, kind: str, seed: int) -> Diagnosed:
        key = (effect, kind, seed)
        if key not in cache:
            cache[key] = Diagnosed(effect, kind, seed)
        return cache[key]

    return get


@pytest.fixture(scope="session")
def synth_log_dir(tmp_path_factory, diagnosed):
    """A rolling-radius log written to disk (for the CLI tests)."""
    from slipenv.logs import write_log

    case = diagnosed("rolling_radius", "diff_drive", 3)
    return write_log(case.synth.log, tmp_path_factory.mktemp("logs") / "rolling_radius")
