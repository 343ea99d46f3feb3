"""A diagnosed model carried to other logs of the same robot: what it does to their paths.

``slipenv diagnose LOG_DIR --model REPORT`` scores the model of an earlier diagnosis (its
``--json`` report) on the logs of ``LOG_DIR`` instead of diagnosing them: every log is
dead-reckoned whole, from its first to its last ground-truth pose, with the nominal geometry
of its own ``meta.json`` and with the model, and the final position error, the final heading
error and the position RMSE of both are compared. This is the test a user makes before
putting a calibration into a robot's config: does the model of one session fix the others?

The model carries as a robot's config takes it (:func:`carried_model`): the named effects,
with the geometry of the report's calibration block in absolute values — fitted radii and
separation, and the fitting logs' nominal for what the diagnosis left unchanged — not each
scored log's header, which may state another nominal.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from slipenv.diagnose.calibration import replay_terms
from slipenv.diagnose.effects import effect
from slipenv.diagnose.effects.base import Term
from slipenv.diagnose.extension import parse_model
from slipenv.diagnose.horizon import whole_runs
from slipenv.diagnose.replay import simulate


def read_report(path: str | Path) -> dict:
    """The diagnosis report (``slipenv diagnose --json``) at ``path``.

    Raises
    ------
    ValueError
        If the file is missing, not JSON, or not a diagnosis report (no ``cause``); the
        message names the file.
    """
    p = Path(path)
    try:
        report = json.loads(p.read_text())
    except FileNotFoundError:
        raise ValueError(f"--model {str(p)!r}: no such file") from None
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as exc:
        raise ValueError(f"--model {str(p)!r}: not a JSON diagnosis report ({exc})") from exc
    if not isinstance(report, dict) or "cause" not in report:
        raise ValueError(f"--model {str(p)!r}: not a diagnosis report (no 'cause'; write one "
                         "with slipenv diagnose LOG_DIR --json PATH)")
    return report


def carried_model(report: dict) -> dict[str, Term]:
    """The replay model a robot takes from ``report``: its named effects, their geometry as
    the calibration block states it (absolute radii and separation: the fitting logs'
    nominal where the diagnosis changed nothing). ``{}`` when the report names no cause.

    Raises
    ------
    ValueError
        If the report is malformed (:func:`slipenv.diagnose.extension.parse_model`).
    """
    effects = dict(parse_model(report).effects)
    if effects and report.get("calibration"):
        effects.update(replay_terms(report["calibration"]))
    return effects


def check_logs(report: dict, logs: list) -> None:
    """ValueError unless ``logs`` come from the kind of vehicle, with the wheels, the report
    was fitted on (a model of one vehicle says nothing about another; the report's wheels
    as :func:`~slipenv.diagnose.extension.parse_model` reads them)."""
    ext = parse_model(report)
    kind, wheels = ext.vehicle_kind, set(ext.wheels)
    for log in logs:
        name = str(log.path) if log.path else "<memory>"
        if kind is not None and log.meta.kind != kind:
            raise ValueError(f"{name}: a {log.meta.kind} log, but the model was fitted on a "
                             f"{kind}: a model applies only to the kind of vehicle it was "
                             "fitted on")
        if wheels and set(log.wheels) != wheels:
            raise ValueError(f"{name}: wheels {sorted(log.wheels)}, but the model was fitted "
                             f"on wheels {sorted(wheels)}")


def score(report: dict, logs: list) -> dict[str, Any]:
    """Every log of ``logs`` dead-reckoned whole, nominal and with the model of ``report``.

    Returns
    -------
    dict
        ``model`` (effect: parameters), ``logs`` (per log: ``name``, ``before`` and
        ``after``, each ``final_position_error_m``, ``final_heading_error_deg``,
        ``position_rmse_m``), ``mean_final_position_error_m`` ``[before, after]`` and its
        ``cut`` (1 - after / before).

    Raises
    ------
    ValueError
        For a malformed report, logs of another vehicle, or logs without two ground-truth
        poses.
    """
    check_logs(report, logs)
    model = carried_model(report)
    seg = whole_runs(logs)
    if seg is None or len(seg) != len(logs):
        have = set() if seg is None else set(seg.log_index.tolist())
        missing = [str(log.path) if log.path else "<memory>"
                   for i, log in enumerate(logs) if i not in have]
        raise ValueError(f"logs without two ground-truth poses cannot be scored: {missing}")
    rows = []
    runs = {tag: simulate(seg, m) for tag, m in (("before", {}), ("after", model))}
    for k, log in enumerate(logs):
        ok = seg.gt_ok[k]
        last = int(np.flatnonzero(ok)[-1])
        row: dict[str, Any] = {"name": log.path.name if log.path else f"log {k}"}
        for tag, pred in runs.items():
            err = pred[k, :, :2] - seg.gt[k, :, :2]
            dyaw = (pred[k, last, 2] - seg.gt[k, last, 2] + np.pi) % (2 * np.pi) - np.pi
            row[tag] = {"final_position_error_m": float(np.hypot(*err[last])),
                        "final_heading_error_deg": float(np.degrees(dyaw)),
                        "position_rmse_m": float(np.sqrt(np.mean(np.sum(err[ok] ** 2,
                                                                        axis=-1))))}
        rows.append(row)
    before = float(np.mean([r["before"]["final_position_error_m"] for r in rows]))
    after = float(np.mean([r["after"]["final_position_error_m"] for r in rows]))
    return {"model": {name: {f: float(getattr(term, f)) for f in effect(name).fields()}
                      for name, term in model.items()},
            "logs": rows, "mean_final_position_error_m": [before, after],
            "cut": 1.0 - after / max(before, 1e-12)}


def summary(result: dict) -> str:
    """Lines for the terminal: the model, each log before -> after, the mean cut."""
    lines = ["model: " + (", ".join(f"{name} {params}" for name, params in
                                    result["model"].items()) or "none (the report names no "
                          "cause: every log keeps its nominal model)")]
    for row in result["logs"]:
        b, a = row["before"], row["after"]
        lines.append(f"  {row['name']}: final position error "
                     f"{1e3 * b['final_position_error_m']:.0f} -> "
                     f"{1e3 * a['final_position_error_m']:.0f} mm, heading "
                     f"{b['final_heading_error_deg']:+.2f} -> "
                     f"{a['final_heading_error_deg']:+.2f} deg")
    before, after = result["mean_final_position_error_m"]
    lines.append(f"mean final position error {1e3 * before:.1f} -> {1e3 * after:.1f} mm "
                 f"(cut {100 * result['cut']:.0f} %)")
    return "\n".join(lines)
