"""The real-data findings of ``docs/real_data.md``: OptiOdom and BorealTC through the diagnosis.

1. Converts both datasets to slipenv-log/1 (``slipenv.logs.real``) under ``--out``.
2. OptiOdom, all runs together (what ``slipenv diagnose runs/real/optiodom`` prints): each run
   is predicted by models fitted on other runs (folds by run).
3. OptiOdom, per session: the same within each recording session.
4. OptiOdom, across path types: the effect chosen on all runs, fitted on the runs of one path
   type only and scored on the runs of the other types (never used for fitting).
5. BorealTC (no ground truth): yaw efficiency per terrain (``slipenv.diagnose.proprio``).

    python benchmarks/real_data.py --out runs/real
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from slipenv.diagnose import proprio
from slipenv.diagnose.cli import diagnose, load_logs
from slipenv.diagnose.fit import Problem, fit
from slipenv.diagnose.replay import build_segments, simulate
from slipenv.logs.real import convert_real_datasets


def position_rmse(seg, params: dict) -> float:
    err = (simulate(seg, params)[..., :2] - seg.gt[..., :2])[seg.gt_ok]
    return float(np.sqrt(np.mean(np.sum(err**2, axis=-1))))


def cross_path(logs, effects: tuple[str, ...]) -> list[tuple]:
    """Fit ``effects`` on one path type's runs, score on the other types' runs."""
    by_type = defaultdict(list)
    for log in logs:
        by_type[log.meta.data["optiodom"]["path_type"]].append(log)
    rows = []
    for name, train in sorted(by_type.items()):
        test = [log for t, ls in by_type.items() if t != name for log in ls]
        seg_train = build_segments(train, 30.0)
        f = fit(Problem.from_segments(seg_train), effects)
        seg_test = build_segments(test, 30.0)
        before, after = position_rmse(seg_test, {}), position_rmse(seg_test, f.params)
        rows.append((name, len(train), len(test), f.report(seg_train), before, after))
    return rows


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="runs/real", help="folder for the converted logs")
    args = parser.parse_args(argv)
    out = Path(args.out)
    convert_real_datasets(out, progress=False)
    logs = load_logs(out / "optiodom")
    report, _ = diagnose(logs, str(out / "optiodom"))
    (out / "optiodom_diagnosis.json").write_text(json.dumps(report, indent=2, default=float))
    g = report["gains"]
    print(f"OptiOdom, {len(logs)} runs: cause {report['cause']} also {report['also']}")
    for k, v in report["parameters"].items():
        print(f"  {k} = {v[0]:.5f} ± {v[1]:.5f}")
    for k in ("position_rmse_m", "heading_rmse_rad"):
        print(f"  held-out {k}: {g[k]['before']:.4f} -> {g[k]['after']:.4f} "
              f"({100 * g[k]['relative']:.0f} % better)")
    print("\n| session | path | runs | nominal Li [m] | cause | parameters | held-out position "
          "RMSE [mm] |\n|---|---|---|---|---|---|---|")
    sessions = defaultdict(list)
    for log in logs:
        sessions[log.meta.data["optiodom"]["session"]].append(log)
    for name, runs in sorted(sessions.items()):
        try:
            rep, _ = diagnose(runs, name)
        except ValueError as exc:
            print(f"| {name} | – | {len(runs)} | – | not diagnosed: {exc} | | |")
            continue
        params = ", ".join(f"{k} = {v[0]:.4f} ± {v[1]:.4f}" for k, v in rep["parameters"].items())
        gp = rep["gain"]
        print(f"| {name} | {runs[0].meta.data['optiodom']['path_type']} | {len(runs)} | "
              f"{runs[0].meta.track_width_m:g} | {rep['cause']} | {params or '–'} | "
              f"{1e3 * gp['before']:.1f} → {1e3 * gp['after']:.1f} |")
    effects = tuple(e for e in [report["cause"], *report["also"]] if e != "none")
    if effects:
        print(f"\nacross path types ({'+'.join(effects)} fitted on one type, scored on the "
              "others):\n\n| fitted on | runs | scored on runs | parameters | position RMSE "
              "[mm] nominal → extended |\n|---|---|---|---|---|")
        for name, n_train, n_test, params, before, after in cross_path(logs, effects):
            p = ", ".join(f"{k} = {v[0]:.4f} ± {v[1]:.4f}" for k, v in params.items())
            print(f"| {name} | {n_train} | {n_test} | {p} | {1e3 * before:.1f} → "
                  f"{1e3 * after:.1f} ({100 * (1 - after / before):.0f} %) |")
    boreal = load_logs(out / "borealtc", require_ground_truth=False)
    result = proprio.analyse(boreal, str(out / "borealtc"))
    (out / "borealtc_diagnosis.json").write_text(json.dumps(result, indent=2, default=float))
    print("\nBorealTC\n" + proprio.summary(result))
    for name, grp in result["groups"].items():
        runs = [round(r[1], 2) for r in grp.get("per_run_yaw_efficiency", [])]
        held = grp.get("held_out_runs") or {}
        print(f"  {name}: per-run yaw efficiency {runs}; fit on even runs, scored on odd runs: "
              f"{100 * held.get('relative', float('nan')):.0f} % better")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
