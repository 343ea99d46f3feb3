"""``slipenv diagnose (LOG_DIR | --example [NAME]) [--json PATH] [--report DIR] [--seed N]
[--jobs N] [--quiet] [--model REPORT]``.

``LOG_DIR`` is one slipenv-log/1 folder, or a folder of them (diagnosed together: one vehicle,
several runs; the held-out comparison then predicts each run with models fitted on other
runs). ``--example NAME`` diagnoses one of the logs shipped in the package
(``slipenv.logs.examples``). Logs without any ground-truth pose get the proprioceptive
analysis of ``proprio.py`` instead (yaw rate against wheel speeds with the gyro as reference).
A log in which the vehicle does not move is refused: it cannot tell one model from another.

Outputs are checked before any work (``slipenv.cli_outputs``). The reports are written in a
staging folder beside their target and moved into place only when complete, so a Ctrl-C never
leaves a report that looks finished: the staging folder is removed (after a hard kill its
``.partial`` name says what it is).

``--model REPORT`` scores the model of an earlier diagnosis (its ``--json`` report) on the
logs instead of diagnosing them (``carry.py``): each log dead-reckoned whole, nominal and with
the model carried as the robot's config takes it; ``--json`` then writes that score.
"""

from __future__ import annotations

import argparse
import os
import shutil
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from slipenv.cli_types import non_negative_int, positive_int
from slipenv.logs.errors import LogFormatError
from slipenv.logs.io import META_FILE, read_log
from slipenv.logs.log import GT_COLUMNS, Log

DESCRIPTION = """\
Replay a slipenv-log/1 log (or a folder of logs of one vehicle), fit every effect of the
vocabulary and name the cause held-out data support; --json and --report write the results.
Logs without ground truth get a proprioceptive analysis (gyro against wheel speeds). A log in
which the vehicle does not move is refused: it cannot tell one model from another."""

STILL_TRAVEL_M = 0.05
"""[m] Below this span of every wheel's travel and of the ground-truth position, the vehicle
does not move (about a tyre's contact patch; encoder jitter and OptiTrack noise stay below)."""
STILL_YAW_RAD = 0.05
"""[rad] Below this span of the ground-truth heading (3 deg), the vehicle does not turn."""

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


def moves(log: Log) -> bool:
    """Whether the vehicle moves in ``log``: a wheel turns through more than
    ``STILL_TRAVEL_M`` of travel, or the ground truth moves more than ``STILL_TRAVEL_M`` or
    turns more than ``STILL_YAW_RAD`` (spans between the 1st and 99th percentiles, so a stray
    sample or sensor noise does not count as motion)."""
    def span(x: np.ndarray) -> float:
        x = x[np.isfinite(x)]
        return float(np.subtract(*np.percentile(x, [99, 1]))) if x.size else 0.0

    r = log.meta.wheel_radius_m
    if any(span(log.wheel_angle(w)) * r > STILL_TRAVEL_M for w in log.wheels):
        return True
    return any(log.has(c) and span(log.signals[c]) > limit
               for c, limit in (("gt_x", STILL_TRAVEL_M), ("gt_y", STILL_TRAVEL_M),
                                ("gt_yaw", STILL_YAW_RAD)))


def refuse_still(logs: list[Log], where: str) -> None:
    """``DiagnosisError`` if the vehicle moves in none of ``logs``: nothing to diagnose."""
    if not any(moves(log) for log in logs):
        which = "this log" if len(logs) == 1 else f"any of these {len(logs)} logs"
        raise DiagnosisError(
            f"{where}: the vehicle does not move in {which} (wheels and ground truth move "
            f"less than {STILL_TRAVEL_M * 100:.0f} cm and {np.degrees(STILL_YAW_RAD):.0f} deg): "
            "nothing to diagnose")


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

    jobs = check_jobs(jobs)  # the arguments first, then the data
    refuse_still(logs, where)
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


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """The ``diagnose`` sub-parser (``sub`` is ``ArgumentParser.add_subparsers()``)."""
    from slipenv.logs.examples import DESCRIPTIONS, NAMES

    examples = ", ".join(f"{name} ({text})" for name, text in DESCRIPTIONS.items())
    p = sub.add_parser("diagnose", help="diagnose a measured log (slipenv-log/1)",
                       description=DESCRIPTION)
    # SUPPRESS: no "(default: None)" in --help for what is either given or not
    p.add_argument("log_dir", nargs="?", default=argparse.SUPPRESS, metavar="LOG_DIR",
                   help="folder with meta.json and signals.csv, or a folder of such folders")
    p.add_argument("--example", nargs="?", const="synthetic", choices=NAMES, default=None,
                   metavar="NAME",
                   help=f"diagnose a log shipped with slipenv instead of LOG_DIR (%(const)s "
                        f"without NAME): {examples}")
    p.add_argument("--json", default=None, help="write the diagnosis report to this JSON file")
    p.add_argument("--report", default=None,
                   help="folder for the human report (plots + text; None: no report)")
    p.add_argument("--seed", type=non_negative_int, default=0, help="random seed of the fit")
    p.add_argument("--jobs", type=positive_int, default=None,
                   help="processes the fits run on (None: every core this process may use); "
                        "the diagnosis is the same whatever the number")
    p.add_argument("--quiet", action="store_true", help="no progress bars")
    p.add_argument("--model", default=None, metavar="REPORT",
                   help="instead of a diagnosis, score the model of an earlier one (its --json "
                        "report) on these logs: each dead-reckoned whole, nominal and with the "
                        "model (its calibration as absolute geometry); --json writes the score")
    return p


def log_folder(args) -> Path:
    """The folder to diagnose: ``LOG_DIR`` or the example's (``ValueError`` if neither/both)."""
    example, given = getattr(args, "example", None), getattr(args, "log_dir", None)
    if example is not None:
        if given is not None:
            raise ValueError(f"give LOG_DIR or --example, not both ({given!r} and "
                             f"--example {example})")
        from slipenv.logs.examples import path

        return path(example)
    if given is None:
        raise ValueError("give a log folder (LOG_DIR) or --example NAME")
    folder = Path(given)
    if not folder.exists():
        raise ValueError(f"no such log folder: {given!r}")
    if not folder.is_dir():
        raise ValueError(f"{given!r} is not a folder")
    return folder


def main(args) -> int:
    """Entry point of ``slipenv diagnose`` (see ``slipenv.cli``); returns the exit code.

    ``slipenv.cli`` has checked the output paths before calling this. A Ctrl-C propagates
    (``slipenv.cli.main`` prints the one line, status 130) once the staged reports are
    removed: the JSON path and the report folder then hold nothing of this run.
    """
    from slipenv.diagnose import report as rep

    start = time.perf_counter()
    folder = log_folder(args)
    json_path = None if args.json is None else Path(args.json)
    report_dir = None if args.report is None else Path(args.report)
    quiet = bool(getattr(args, "quiet", False))
    model_path = getattr(args, "model", None)
    if model_path is not None:
        return _score_model(model_path, folder, json_path, report_dir)
    if not _has_truth(folder):
        from slipenv.diagnose import proprio

        logs = load_logs(folder, require_ground_truth=False)
        refuse_still(logs, str(folder))
        result = proprio.analyse(logs, str(folder))
        with _staged(json_path, report_dir) as (json_tmp, report_tmp):
            if json_tmp is not None:
                rep.write_json(result, json_tmp)
            if report_tmp is not None:
                proprio.write_report(report_tmp, result)
        print(proprio.summary(result))
        return 0
    logs = load_logs(folder)
    jobs = getattr(args, "jobs", None)
    if jobs is None:
        from slipenv.diagnose.workers import available_cores

        jobs = available_cores()
    report, (sel, problem) = diagnose(logs, str(folder), progress=not quiet, jobs=jobs)
    sim = None
    if report_dir is not None:
        from slipenv.diagnose.simreplay import pybullet_overlay

        sim = pybullet_overlay(logs[0], sel, problem,
                               seed=int(getattr(args, "seed", 0) or 0), progress=not quiet)
        if sim is not None:
            report["pybullet_replay"] = {k: v for k, v in sim.items()
                                         if k in ("rmse_nominal_m", "rmse_extended_m",
                                                  "segments", "note")}
    with _staged(json_path, report_dir) as (json_tmp, report_tmp):
        if json_tmp is not None:
            rep.write_json(report, json_tmp)
        if report_tmp is not None:
            rep.write_human_report(report_tmp, report, sel, problem, sim, logs=logs)
    print(summary(report, time.perf_counter() - start))
    return 0


def _score_model(model_path: str, folder: Path, json_path: Path | None,
                 report_dir: Path | None) -> int:
    """``--model``: the model of ``model_path`` scored on the logs of ``folder``."""
    from slipenv.diagnose import carry
    from slipenv.diagnose import report as rep

    if report_dir is not None:
        raise ValueError("--report writes a diagnosis; with --model nothing is diagnosed: "
                         "use --json PATH for the score")
    report = carry.read_report(model_path)
    if not _has_truth(folder):
        raise ValueError(f"{folder}: these logs have no ground-truth pose; --model scores a "
                         "model against the ground truth")
    logs = load_logs(folder)
    result = carry.score(report, logs)
    with _staged(json_path, None) as (json_tmp, _):
        if json_tmp is not None:
            rep.write_json({"model_from": str(model_path), "logs_from": str(folder), **result},
                           json_tmp)
    print(carry.summary(result))
    return 0


@contextmanager
def _staged(json_path: Path | None, report_dir: Path | None
            ) -> Iterator[tuple[Path | None, Path | None]]:
    """Temporary targets beside ``json_path`` and ``report_dir``, moved into place when the
    block ends normally and removed when it does not (Ctrl-C, an error)."""
    made: list[Path] = []
    try:
        json_tmp = report_tmp = None
        if json_path is not None:  # created by write_json, with the user's usual permissions
            json_tmp = json_path.parent / f".{json_path.name}.partial-{os.getpid()}"
            made.append(json_tmp)
        if report_dir is not None:
            report_tmp = Path(tempfile.mkdtemp(prefix=f".{report_dir.name}.partial-",
                                               dir=report_dir.parent))
            made.append(report_tmp)
        yield json_tmp, report_tmp
        if report_tmp is not None and report_dir is not None:
            # report.md last: a report folder whose report.md is new is complete
            entries = sorted(report_tmp.iterdir(), key=lambda p: p.name == "report.md")
            for entry in entries:
                target = report_dir / entry.name
                if target.is_dir() and not target.is_symlink():
                    shutil.rmtree(target)
                os.replace(entry, target)
        if json_tmp is not None and json_path is not None:
            os.replace(json_tmp, json_path)
    finally:
        for tmp in made:
            if tmp.is_dir():
                shutil.rmtree(tmp, ignore_errors=True)
            else:
                tmp.unlink(missing_ok=True)


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
    tr = report.get("transfer") or {}
    if tr.get("decision"):
        part = "run" if tr["held_out_by"] == "run" else "half"
        lines.append(f"transfer (fitted on the whole paths of the others, each {part} held out "
                     f"in turn): {tr['decision']}")
        lines += [f"  {'+'.join(v['richer'])} against {'+'.join(v['simpler'])}: held-out error "
                  f"lower by {num(v['mean_fall'], '.3f')} ± {num(v['standard_error'], '.3f')} "
                  f"of the nominal, on {v['lower_on_parts']}/{v['parts']} parts: "
                  + ("kept" if v["richer_wins"] else "not kept")
                  for v in tr.get("versus", [])]
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
