"""``slipenv fit-soil DIR --json PATH --report DIR``: fit force laws to test-bed data.

Registered by :mod:`slipenv.cli` with ``add_parser(sub)``; ``main(args)`` returns the exit code.
DIR holds ``trials.csv`` and ``meta.json`` (format: `slipenv.testbed.csv_format`). Bad input
raises `ValueError` naming the file, row and column (exit code 2, one line on stderr).

The written soil loads with one line::

    soil = Soil(**json.load(open(PATH))["soil"])   # from slipenv.terramechanics.soil
    env = gymnasium.make("slipenv/Configurable-v0", soil=soil, force_model=report["best"])
"""

from __future__ import annotations

import argparse
import json
import pathlib
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
    """Run ``slipenv fit-soil``; 0 on success (bad input raises ValueError: exit 2)."""
    from slipenv.terramechanics.presets import soil_by_name
    from slipenv.testbed.csv_format import read_testbed
    from slipenv.testbed.report import analyse, plot_fits

    if args.folds < 2:
        raise ValueError(f"--folds={args.folds} must be >= 2")
    base = soil_by_name(args.base_soil)
    json_path = pathlib.Path(args.json_path)
    if json_path.is_dir():
        raise ValueError(f"--json {json_path} is a directory")
    data = read_testbed(args.directory)
    report, fits = analyse(data, base, folds=args.folds, seed=args.seed)
    report["source"] = str(pathlib.Path(args.directory))
    if args.report_dir:
        plots = plot_fits(data, fits, report["best"], args.report_dir)
        report["plots"] = [str(x) for x in plots]
        (pathlib.Path(args.report_dir) / "report.md").write_text(_markdown(report))
    json_path.parent.mkdir(parents=True, exist_ok=True)
    json_path.write_text(json.dumps(report, indent=2) + "\n")
    print(_markdown(report), end="")
    return 0


def _markdown(report: dict) -> str:
    lines = [f"fit-soil: {report['n_trials']} trials, {report['folds']}-fold held out",
             "", "| law | held-out RMSE F_x [N] | F_y [N] | parameters (value ± SE) |",
             "|---|---|---|---|"]
    for law, entry in report["laws"].items():
        params = ", ".join(f"{k} = {v:.4g} ± {e:.2g}" for k, (v, e) in
                           entry["parameters"].items())
        r = entry["heldout_rmse_n"]
        mark = " (best)" if law == report["best"] else ""
        lines.append(f"| {law}{mark} | {r['fx']:.3g} | {r['fy']:.3g} | {params} |")
    lines += ["", f"verdict: {report['verdict']}"]
    return "\n".join(lines) + "\n"
