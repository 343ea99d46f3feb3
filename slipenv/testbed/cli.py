"""``slipenv fit-soil DIR --json PATH --report DIR``: fit force laws to test-bed data.

Registered by :mod:`slipenv.cli` with ``add_parser(sub)``; ``main(args)`` returns the exit code.
DIR holds ``trials.csv`` and ``meta.json`` (format: `slipenv.testbed.csv_format`). Bad input
raises `ValueError` naming the file, row and column (exit code 2, one line on stderr). A fit
whose soil is not accepted still writes its report, then exits with status 1 and one line on
stderr saying so and where ``rejected_soil`` was written, so a script cannot take it for a soil.

The written soil loads with one line (present only when the fit is accepted; a rejected fit's
soil is under ``rejected_soil``, with ``"accepted": false`` and the reasons in ``warnings``)::

    soil = Soil(**json.load(open(PATH))["soil"])   # from slipenv.terramechanics.soil
    env = gymnasium.make("slipenv/Configurable-v0", soil=soil, force_model=report["best"])
"""

from __future__ import annotations

import argparse
import json
import pathlib
import sys
from typing import Any

__all__ = ["add_parser", "main"]


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Add the ``fit-soil`` subcommand to ``sub`` (an ``add_subparsers()`` result)."""
    p = sub.add_parser("fit-soil", help="fit slipenv's force laws (janosi, reina, linear) to "
                                        "single-wheel test-bed data; write a soil")
    p.add_argument("directory", help="test-bed directory with trials.csv and meta.json")
    p.add_argument("--json", dest="json_path", required=True,
                   help="where to write the fit report (JSON)")
    p.add_argument("--report", dest="report_dir", default=None,
                   help="directory for the plots and report.md")
    p.add_argument("--base-soil", default="lunar_simulant",
                   help="preset whose unfitted fields (Bekker constants, ...) the soil keeps")
    p.add_argument("--folds", type=int, default=5, help="folds of the held-out comparison")
    p.add_argument("--seed", type=int, default=0, help="seed of the fold assignment")
    return p


def main(args: argparse.Namespace) -> int:
    """Run ``slipenv fit-soil``; 0 when the soil is accepted, 1 when it is rejected (the
    report is written either way; bad input raises ValueError: exit 2)."""
    from slipenv.cli_outputs import output_dir, output_file, partial_results
    from slipenv.terramechanics.presets import soil_by_name
    from slipenv.testbed.csv_format import read_testbed
    from slipenv.testbed.report import analyse, plot_fits

    if args.folds < 2:
        raise ValueError(f"--folds={args.folds} must be >= 2")
    base = soil_by_name(args.base_soil)
    json_path = output_file(args.json_path, "--json")
    if args.report_dir:
        output_dir(args.report_dir, "--report")
    data = read_testbed(args.directory)
    report, fits = analyse(data, base, folds=args.folds, seed=args.seed)
    report["source"] = str(pathlib.Path(args.directory))
    with partial_results(args.report_dir):
        if args.report_dir:
            plots = plot_fits(data, fits, report["best"], args.report_dir)
            report["plots"] = [str(x) for x in plots]
            (pathlib.Path(args.report_dir) / "report.md").write_text(_markdown(report))
        json_path.write_text(json.dumps(report, indent=2) + "\n")
    print(_markdown(report), end="")
    if not report.get("accepted"):
        print(f"fit-soil: soil rejected ({_first_reason(report)}); its fields are under "
              f"'rejected_soil' in {json_path}", file=sys.stderr)
        return 1
    return 0


def _first_reason(report: dict) -> str:
    """Why the soil was not accepted, from the report's first warning (one line)."""
    prefix = "soil not accepted: "
    for warning in report.get("warnings", []):
        if warning.startswith(prefix):
            return warning[len(prefix):].splitlines()[0]
    return "the verdict rejects the law"


def _markdown(report: dict) -> str:
    lines = [f"fit-soil: {report['n_trials']} trials, {report['folds']}-fold held out",
             "", "| law | held-out RMSE F_x [N] | F_y [N] | parameters (value ± SE) |",
             "|---|---|---|---|"]
    from slipenv.testbed.report import format_parameter

    for law, entry in report["laws"].items():
        status = entry.get("parameter_status", {})
        params = ", ".join(f"{k} = {format_parameter(v, e, status.get(k, ''), k)}"
                           for k, (v, e) in entry["parameters"].items())
        r = entry["heldout_rmse_n"]
        mark = " (best)" if law == report["best"] else ""
        lines.append(f"| {law}{mark} | {r['fx']:.3g} | {r['fy']:.3g} | {params} |")
    lines += ["", f"verdict: {report['verdict']}"]
    if report.get("sidewall_offered"):
        lines.append(f"side-wall law offered: {report['sidewall_reason']}")
    lines.append("soil: accepted (written under 'soil')" if report.get("accepted") else
                 "soil: NOT accepted (written under 'rejected_soil' only)")
    lines += [f"warning: {w}" for w in report.get("warnings", [])]
    return "\n".join(lines) + "\n"
