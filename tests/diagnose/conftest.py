"""Shared fixtures of the diagnosis tests: hidden-effect logs from the physics, made once.

Seeds are fixed so a failure can be reproduced; ``SLIPENV_DIAGNOSE_SEED=<int>`` shifts them
(``random`` draws a new shift, printed in the test header) to test on logs never seen before.
``benchmarks/diagnose_hit_rate.py`` measures the hit rate over many fresh logs.

Under pytest-xdist each log and each diagnosis is made once per run, not once per worker:
pytest-xdist hands a worker consecutive tests, and where the tests of one case fall to both
workers the second one loads the first one's result (or waits for it) instead of repeating a
diagnosis of up to a minute.
"""

from __future__ import annotations

import os
import pickle
import warnings
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import TypeVar

import numpy as np
import pytest

from slipenv.diagnose import synth
from slipenv.diagnose.cli import diagnose
from slipenv.diagnose.fit import Problem
from slipenv.diagnose.kinematic import KinematicTruth, kinematic_log
from slipenv.diagnose.replay import build_segments
from slipenv.diagnose.select import select
from slipenv.logs.log import Log

try:
    import fcntl
except ImportError:  # not POSIX: each xdist worker makes its own
    fcntl = None

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


T = TypeVar("T")


def _run_folder(tmp_path_factory: pytest.TempPathFactory, name: str) -> Path | None:
    """The folder the run's xdist workers share for ``name`` (None: one process, or no
    ``fcntl`` to lock with)."""
    if fcntl is None or "PYTEST_XDIST_WORKER" not in os.environ:
        return None
    folder = tmp_path_factory.getbasetemp().parent / name  # the workers' common parent
    folder.mkdir(exist_ok=True)
    return folder


def _once_per_run(folder: Path | None, key: tuple, build: Callable[[], T]) -> T:
    """``build()``, or what a worker of this run built for ``key`` and pickled to ``folder``;
    a worker asking while another builds waits for it."""
    if folder is None:
        return build()
    path = folder / ("-".join(map(str, (*key, SEED_SHIFT))) + ".pickle")
    with open(path.with_suffix(".lock"), "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)  # released when the file closes
        if path.exists():
            return pickle.loads(path.read_bytes())
        value = build()
        try:
            data = pickle.dumps(value)
        except (pickle.PicklingError, TypeError, AttributeError):
            return value  # not shareable: a worker asking later builds its own
        part = path.with_suffix(".part")
        part.write_bytes(data)
        part.replace(path)
        return value


def _generate(effect: str, kind: str, seed: int) -> synth.SynthLog:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return synth.generate(seed + SEED_SHIFT, effect, kind, duration_s=DURATION_S)


class Diagnosed:
    """A generated log and its diagnosis."""

    def __init__(self, log: synth.SynthLog) -> None:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            self.synth = log
            self.seg = build_segments([self.synth.log])
            self.problem = Problem.from_segments(self.seg)
            self.selection = select(self.problem, logs=[self.synth.log])

    def parameters(self) -> dict[str, list[float]]:
        out: dict[str, list[float]] = {}
        for fit in self.selection.fits.values():
            out.update(fit.report(self.seg))
        return out


@pytest.fixture(scope="session")
def synthesized(tmp_path_factory):
    """``synthesized(effect, kind, seed)`` -> SynthLog, each case generated once per run.
    For tests of the log alone: its diagnosis (``diagnosed``) costs up to a minute more."""
    cache: dict[tuple, synth.SynthLog] = {}
    folder = _run_folder(tmp_path_factory, "synthesized")

    def get(effect: str, kind: str, seed: int) -> synth.SynthLog:
        key = (effect, kind, seed)
        if key not in cache:
            cache[key] = _once_per_run(folder, key, lambda: _generate(*key))
        return cache[key]

    return get


@pytest.fixture(scope="session")
def diagnosed(synthesized, tmp_path_factory):
    """``diagnosed(effect, kind, seed)`` -> Diagnosed, each case built once per run."""
    cache: dict[tuple, Diagnosed] = {}
    folder = _run_folder(tmp_path_factory, "diagnosed")

    def get(effect: str, kind: str, seed: int) -> Diagnosed:
        key = (effect, kind, seed)
        if key not in cache:
            cache[key] = _once_per_run(folder, key, lambda: Diagnosed(synthesized(*key)))
        return cache[key]

    return get


@pytest.fixture(scope="session")
def synth_log_dir(tmp_path_factory, synthesized):
    """A rolling-radius log written to disk (for the CLI tests)."""
    from slipenv.logs import write_log

    log = synthesized("rolling_radius", "diff_drive", 3).log
    return write_log(log, tmp_path_factory.mktemp("logs") / "rolling_radius")


@dataclass
class Traced:
    """A diagnosis in one process and what its forward selection did."""

    log: Log
    report: dict
    joined: list[list[str]]  # per forward-selection step, the effects joined to the cause
    judged_long: list[tuple[str, ...]]  # every candidate judged on the long route, in turn


@pytest.fixture(scope="session")
def traced_radius_diagnosis(tmp_path_factory) -> Traced:
    """The half-minute kinematic log whose right wheel is 1.5 % larger, with a torque column
    (every effect is testable, soil maps included, and forward selection fits joint models),
    diagnosed in one process, once per run."""
    return _once_per_run(_run_folder(tmp_path_factory, "traced"), ("radius_with_torque",),
                         _trace_radius_diagnosis)


def _trace_radius_diagnosis() -> Traced:
    from slipenv.diagnose import select as selection

    log = kinematic_log(31, KinematicTruth(0.1, 0.1015, 0.5), duration_s=30.0, with_torque=True)
    joined: list[list[str]] = []
    judged_long: list[tuple[str, ...]] = []
    step, judge_long = selection._step, selection._judge_long

    def judging(problem, hz, cand, reference, **kw):
        judged_long.append(cand.effects)
        judge_long(problem, hz, cand, reference, **kw)

    with pytest.MonkeyPatch.context() as patch, warnings.catch_warnings():
        warnings.simplefilter("ignore")
        patch.setattr(selection, "_step", lambda *a: joined.append(list(a[5])) or step(*a))
        patch.setattr(selection, "_judge_long", judging)
        report, _ = diagnose([log], "<kinematic>", jobs=1)
    return Traced(log, report, joined, judged_long)
