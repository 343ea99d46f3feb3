"""``slipenv diagnose LOG_DIR [--json PATH] [--report DIR] [--seed N] [--jobs N] [--quiet]``.

``LOG_DIR`` is one slipenv-log/1 folder, or a folder of them (diagnosed together: one vehicle,
several runs; the held-out comparison then predicts each run with models fitted on other
runs). Logs without any ground-truth pose get the proprioceptive analysis of
``proprio.py`` instead (yaw rate against wheel speeds with the gyro as reference).
"""

from __future__ import annotations

import time
from pathlib import Path
from typing import TYPE_CHECKING

from slipenv.logs.errors import LogFormatError
from slipenv.logs.io import META_FILE, read_log
from slipenv.logs.log import GT_COLUMNS, Log

if TYPE_CHECKING:  # as in diagnose(): the fitting stack (scipy) loads only when a fit runs
    from slipenv.diagnose.fit import Problem
    from slipenv.diagnose.select import Selection


def load_logs(path: str | Path, require_ground_truth: bool = True) -> list[Log]:
    """The log at ``path``, or every log folder directly inside it (sorted by name).

    Raises
    ------
    LogFormatError
        If ``path`` is not a folder, holds no log, or a log breaks the contract.
    """
    folder = Path(path)
    if not folder.is_dir():
        raise LogFormatError(folder, "no such log folder")
    if (folder / META_FILE).is_file():
        return [read_log(folder, require_ground_truth=require_ground_truth)]
    subs = sorted(p for p in folder.iterdir() if (p / META_FILE).is_file())
    if not subs:
        raise LogFormatError(folder, "not a log folder (no meta.json) and no log folders in it")
    return [read_log(p, require_ground_truth=require_ground_truth) for p in subs]


def _has_truth(folder: Path) -> bool:
    """True unless every log under ``folder`` lacks all ground-truth columns."""
    logs = load_logs(folder, require_ground_truth=False)
    return any(all(log.has(c) for c in GT_COLUMNS) for log in logs)


def diagnose(logs: list[Log], where: str, *, progress: bool = False, jobs: int = 1
             ) -> tuple[dict, tuple[Selection, Problem]]:
    """Run the diagnosis on ``logs``; (JSON report, context for the human report).
    ``jobs``: processes the fits run on (``workers.py``; the report does not depend on it)."""
    from concurrent.futures.process import BrokenProcessPool

    import numpy as np

    from slipenv.diagnose.fit import FitError, Problem
    from slipenv.diagnose.replay import build_segments
    from slipenv.diagnose.report import build_report
    from slipenv.diagnose.select import select
    from slipenv.diagnose.workers import check_jobs, one_blas_thread

    jobs = check_jobs(jobs)
    try:
        with one_blas_thread():  # the same numbers on every machine (``workers.py``)
            problem = Problem.from_segments(build_segments(logs))
            sel = select(problem, progress=progress, logs=logs, jobs=jobs)
            return build_report(sel, problem, logs, where), (sel, problem)
    except (FitError, np.linalg.LinAlgError, FloatingPointError) as exc:
        names = ", ".join(str(log.path) if log.path else "<memory>" for log in logs)
        raise DiagnosisError(f"{where}: the diagnosis of {names} failed: {exc}") from exc
    except BrokenProcessPool as exc:  # a worker killed (out of memory, a signal)
        raise DiagnosisError(f"{where}: a worker process of the diagnosis ended abruptly "
                             f"({exc}); --jobs 1 runs every fit in this process") from exc


class DiagnosisError(ValueError):
    """A diagnosis that could not be computed; the message names the log(s)."""


def main(args) -> int:
    """Entry point of ``slipenv diagnose`` (see ``slipenv.cli``); returns the exit code."""
    from slipenv.diagnose import report as rep

    start = time.perf_counter()
    folder = Path(args.log_dir)
    quiet = bool(getattr(args, "quiet", False))
    if folder.is_dir() and not _has_truth(folder):
        from slipenv.diagnose import proprio

        result = proprio.analyse(load_logs(folder, require_ground_truth=False), str(folder))
        if args.json:
            rep.write_json(result, args.json)
        if args.report:
            proprio.write_report(args.report, result)
        print(proprio.summary(result))
        return 0
    logs = load_logs(folder)
    jobs = getattr(args, "jobs", None)
    if jobs is None:
        from slipenv.diagnose.workers import available_cores

        jobs = available_cores()
    report, (sel, problem) = diagnose(logs, str(folder), progress=not quiet, jobs=jobs)
    sim = None
    if args.report:
        from slipenv.diagnose.simreplay import pybullet_overlay

        sim = pybullet_overlay(logs[0], sel, problem, seed=int(getattr(args, "seed", 0) or 0),
                               progress=not quiet)
        if sim is not None:
            report["pybullet_replay"] = {k: v for k, v in sim.items()
                                         if k in ("rmse_nominal_m", "rmse_extended_m",
                                                  "segments", "note")}
    if args.json:
        rep.write_json(report, args.json)
    if args.report:
        rep.write_human_report(args.report, report, sel, problem, sim, logs=logs)
    print(summary(report, time.perf_counter() - start))
    return 0


def summary(report: dict, seconds: float | None = None) -> str:
    """A few lines for the terminal (never ``inf``/``nan``; see ``numbers.py``)."""
    from slipenv.diagnose.effects import shown_parameters
    from slipenv.diagnose.numbers import better, estimate, num

    g = report["gain"]
    lines = [f"cause: {report['cause']}"
             + (f" (also: {', '.join(report['also'])})" if report["also"] else "")]
    shown, extra = shown_parameters(report["parameters"], [report["cause"], *report["also"]])
    lines += [f"  {k} = {estimate(v[0], v[1])}" for k, v in shown.items()]
    lines += [f"  {line}" for line in extra]
    lines += [f"confounded with {c['alternative']}: {c['why']}"
              for c in report.get("confounded", [])]
    lines.append(f"held-out {g['metric']}: {num(g['before'])} -> {num(g['after'])} "
                 f"({better(g['relative'])})")
    cal = report.get("calibration")
    if cal:
        ddc = cal["diff_drive_controller"]
        turn = cal["determined"]["turn_scale"]
        ok = cal.get("config_determined", True)
        lines.append(("odometry config: " if ok else "odometry config (NOT determined by this "
                      "log, do not use): ")
                     + f"wheel_radius {num(ddc['wheel_radius'], '.6g')} m, "
                     f"wheel_separation {num(ddc['wheel_separation'], '.6g')} m, radius "
                     f"multipliers L {num(ddc['left_wheel_radius_multiplier'], '.5f')} / R "
                     f"{num(ddc['right_wheel_radius_multiplier'], '.5f')}")
        lines.append(f"  turn scale {estimate(turn[0], turn[1], '.5f')}; "
                     + ("radius ratio and track width separable on this log" if cal["separable"]
                        else "radius ratio and track width confounded on this log"))
    undetermined = [k for k, ok in report.get("determined", {}).items() if not ok]
    if undetermined:
        lines.append(f"warning: {', '.join(undetermined)} not determined by this log "
                     "(standard error larger than the estimate)")
    lines += [f"warning: {w}" for w in report.get("warnings", [])]
    if seconds is not None:
        lines.append(f"({report['segments']['count']} segments, {seconds:.1f} s)")
    return "\n".join(lines)
