"""The real-data findings of ``docs/real_data.md``: OptiOdom and BorealTC through the diagnosis.

1. Converts both datasets to slipenv-log/1 (``slipenv.logs.real``) under ``--out``.
2. OptiOdom, all runs together (what ``slipenv diagnose runs/real/optiodom`` prints): each run
   is predicted by models fitted on other runs (folds by run).
3. OptiOdom, per session: the same within each recording session.
4. OptiOdom, across path types: the effect chosen on all runs, fitted on the runs of one path
   type only and scored on the runs of the other types (never used for fitting).
5. OptiOdom, single runs (``--single``): every circle and square run whose drift shows in
   both halves (nominal heading drift beyond 3° over the run, at least 1.5° the same way in
   each half, each half dead-reckoned from its own first pose), diagnosed alone; the model
   of that one run applied to the *other* sessions' circle and square runs (whole-run dead
   reckoning from the first logged pose): the cut of their mean final position error, beside
   the oracle (the width alone, and the width and radii, fitted on the whole dead-reckoned
   path of the same run). A model carries as a robot's config takes it (the report's
   calibration block): absolute radii and separation, the fitting logs' nominal for what the
   diagnosis (or the oracle) did not fit, whatever nominal the other sessions' headers state.
6. OptiOdom, whole sessions (``--sessions``): the model diagnosed on one session folder (all
   its runs together) applied to the *other* sessions' circle and square runs the same way,
   per session (the target is a cut of at least 50 %), beside the oracle fitted on the whole
   paths of the session's runs.
7. BorealTC (no ground truth): yaw efficiency per terrain (``slipenv.diagnose.proprio``).
8. OptiOdom square runs (``--pivots``): where the robot turns on the spot, relative to the
   OptiTrack body origin (each pivot's logged poses fitted as origin = centre + R(ψ) d: |d|
   is the origin's offset from the turning centre), and, per half of every square run that
   drifts more than 3°, the pivot turn scale (logged turn over wheel turn during pivots):
   whether the two halves of one run agree on the turn, which the single-run test needs.

    python benchmarks/real_data.py --out runs/real
    python benchmarks/real_data.py --out runs/real --single     # only step 5 (about 1 minute)
    python benchmarks/real_data.py --out runs/real --sessions   # only step 6
    python benchmarks/real_data.py --out runs/real --transfer   # steps 6 and 5
    python benchmarks/real_data.py --out runs/real --pivots     # only step 8 (seconds)
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from slipenv.diagnose import proprio
from slipenv.diagnose.calibration import geometry_terms
from slipenv.diagnose.carry import carried_model
from slipenv.diagnose.cli import diagnose, load_logs
from slipenv.diagnose.fit import Problem, fit
from slipenv.diagnose.horizon import whole_runs
from slipenv.diagnose.replay import build_segments, simulate
from slipenv.diagnose.segments import cut_spans, log_arrays, wheel_sides
from slipenv.logs.real import convert_real_datasets

DRIFT_DEG = 3.0  # [deg] a run "visibly drifts" beyond this nominal heading error at its end
HALF_DRIFT_DEG = 1.5  # [deg] ... and each half by at least this much, the same way


SCREENED = ("circular", "square")  # path types whose runs are screened and are the targets


class Targets:
    """The circle and square runs of every session, each dead-reckoned whole from its first
    logged pose: the final position error a model leaves on the *other* sessions' runs."""

    def __init__(self, logs) -> None:
        runs = [log for log in logs if log.meta.data["optiodom"]["path_type"] in SCREENED]
        seg = whole_runs(runs)
        assert seg is not None and len(seg) == len(runs)  # every OptiOdom run has its truth
        self.seg = seg
        self.session = np.array([log.meta.data["optiodom"]["session"] for log in runs])
        self.last = np.array([np.flatnonzero(row)[-1] for row in self.seg.gt_ok])
        self.nominal = self.end_errors({})

    def end_errors(self, model: dict) -> np.ndarray:
        pred = simulate(self.seg, model)
        i = np.arange(len(self.seg))
        return np.hypot(*(pred[i, self.last, :2] - self.seg.gt[i, self.last, :2]).T)

    def cut(self, model: dict, session: str) -> tuple[float, float, float]:
        """(nominal mean final error [m], with ``model`` [m], relative cut) over the runs of
        the sessions other than ``session``."""
        other = self.session != session
        before = float(self.nominal[other].mean())
        after = float(self.end_errors(model)[other].mean()) if model else before
        return before, after, 1.0 - after / before


def oracle(runs, effects: tuple[str, ...] = ("track_width",)) -> dict:
    """``effects`` fitted on the whole dead-reckoned paths of ``runs`` (each run replayed whole
    from its first logged pose): the best such a fit does on the same data."""
    parts = whole_runs(runs)
    short = Problem.from_segments(build_segments(runs))
    # carried as the diagnosis's calibration: what the fit leaves is the fitting runs' nominal
    return geometry_terms(fit(Problem(parts, short.heading_scale_m, short.travel_m), effects),
                          parts)


def half_drifts(log) -> tuple[float, float, float]:
    """Nominal heading drift [deg] at the end of the whole run and of each half, each
    dead-reckoned from its own first logged pose."""
    arr = log_arrays(log)
    ok = np.flatnonzero(arr["gt_ok"])
    mid = int(ok[ok.size // 2])
    spans = [(0, int(ok[0]), int(ok[-1]) + 1), (0, int(ok[0]), mid + 1),
             (0, mid, int(ok[-1]) + 1)]
    seg = cut_spans([arr], [log], spans)
    pred = simulate(seg, {})
    out = []
    for k in range(3):
        last = np.flatnonzero(seg.gt_ok[k])[-1]
        out.append(float(np.degrees((pred[k, last, 2] - seg.gt[k, last, 2] + np.pi)
                                    % (2 * np.pi) - np.pi)))
    return out[0], out[1], out[2]


def both_halves(log) -> tuple[bool, float]:
    """(drift shows in both halves, whole-run drift [deg]): whole-run drift beyond
    ``DRIFT_DEG`` and each half at least ``HALF_DRIFT_DEG`` the same way."""
    whole, first, second = half_drifts(log)
    ok = (abs(whole) > DRIFT_DEG and all(np.sign(h) == np.sign(whole)
                                          and abs(h) >= HALF_DRIFT_DEG for h in (first, second)))
    return ok, whole


def _causes(rep: dict) -> list[str]:
    return [c for c in [rep["cause"], *rep["also"]] if c != "none"]


def _pct(x: float) -> str:
    return f"{100 * x:.0f} %"


def single_runs(logs, targets: Targets | None = None) -> None:
    """Step 5: the single-run table and its summary."""
    targets = targets or Targets(logs)
    print("\n| run | nominal heading drift [°] | cause (also) | parameters | other sessions' "
          "circle and square runs: final error, nominal → one-run model | cut | oracle cut "
          "(width) | oracle cut (width + radii) |\n|---|---|---|---|---|---|---|---|")
    rows = []
    for log in logs:
        i = log.meta.data["optiodom"]
        if i["path_type"] not in SCREENED:
            continue
        ok, drift = both_halves(log)
        if not ok:
            continue
        rep, _ = diagnose([log], i["file"])
        causes = _causes(rep)
        before, after, rel = targets.cut(carried_model(rep), i["session"])
        o_w = targets.cut(oracle([log]), i["session"])[2]
        o_wr = targets.cut(oracle([log], ("track_width", "rolling_radius")), i["session"])[2]
        rows.append((i["path_type"], causes, rel, o_w, o_wr))
        params = ", ".join(f"{k} = {v[0]:.4f} ± {v[1]:.4f}" for k, v in rep["parameters"].items())
        print(f"| {i['path_type']} {i['session']} run {i['run']} | {drift:+.1f} | "
              f"{rep['cause']}{' (' + ', '.join(rep['also']) + ')' if rep['also'] else ''} | "
              f"{params or '–'} | {1e3 * before:.0f} → {1e3 * after:.0f} mm | {_pct(rel)} | "
              f"{_pct(o_w)} | {_pct(o_wr)} |", flush=True)
    geo = {"rolling_radius", "track_width"}
    circles = [r for r in rows if r[0] == "circular"]
    squares = [r for r in rows if r[0] == "square"]
    named = sum(bool(geo & set(r[1])) for r in circles)
    other = sum(bool(set(r[1]) - geo) for r in squares)
    sq_cut = sum(r[2] >= 0.30 for r in squares)
    print(f"\nsingle runs whose drift shows in both halves (> {DRIFT_DEG:g}° over the run, "
          f">= {HALF_DRIFT_DEG:g}° the same way in each half): {len(rows)}")
    print(f"  circles named geometric: {named}/{len(circles)} (target >= 80 %)")
    print(f"  squares with a non-geometric cause: {other}/{len(squares)} (target 0)")
    print(f"  squares whose one-run model cuts the other sessions' error >= 30 %: "
          f"{sq_cut}/{len(squares)} (target >= 70 %); oracle (width): "
          f"{sum(r[3] >= 0.30 for r in squares)}/{len(squares)}, oracle (width + radii): "
          f"{sum(r[4] >= 0.30 for r in squares)}/{len(squares)}")
    if rows:
        print(f"  median transfer over these runs: {_pct(np.median([r[2] for r in rows]))} "
              f"(target >= 40 %); oracle (width) {_pct(np.median([r[3] for r in rows]))}, "
              f"oracle (width + radii) {_pct(np.median([r[4] for r in rows]))}")
        for path, rs in (("circle", circles), ("square", squares)):
            if rs:
                print(f"  {path} runs: median transfer {_pct(np.median([r[2] for r in rs]))}, "
                      f"oracle (width) {_pct(np.median([r[3] for r in rs]))}")


def arc_fraction(logs) -> float:
    """Share of the nominal turn angle of ``logs`` turned on arcs (the inner wheel rolling
    forward: turn radius above half the track), not on the spot."""
    arc = total = 0.0
    for log in logs:
        seg = whole_runs([log])
        assert seg is not None
        d = seg.radius[:, None, :] * seg.dphi
        left = d[..., seg.sides == 0].mean(axis=-1)[0]
        right = d[..., seg.sides == 1].mean(axis=-1)[0]
        turn = np.abs(right - left) / float(np.median(seg.track))
        arc += float(turn[left * right > 0].sum())
        total += float(turn.sum())
    return arc / max(total, 1e-12)


def session_models(logs, targets: Targets | None = None) -> None:
    """Step 6: each session's model applied to the other sessions' circle and square runs,
    dead-reckoned whole, beside the oracle (the width, and the width and radii, fitted on the
    whole paths of the session's runs)."""
    targets = targets or Targets(logs)
    sessions = defaultdict(list)
    for log in logs:
        sessions[log.meta.data["optiodom"]["session"]].append(log)
    print("\n| session fitted on | path | runs | turned on arcs | cause (also) | parameters | "
          "transfer inside the session (held-out error ratio; richer vs simpler: fall of "
          "the held-out error ± its standard error, parts lower) | other sessions' circle and "
          "square runs: final error, nominal → session model | cut | oracle cut (width) | "
          "oracle cut (width + radii) |\n|---|---|---|---|---|---|---|---|---|---|---|")
    rows = []
    for name, runs in sorted(sessions.items()):
        path = runs[0].meta.data["optiodom"]["path_type"]
        try:
            rep, _ = diagnose(runs, name)
        except ValueError as exc:
            print(f"| {name} | {path} | {len(runs)} | | not diagnosed: {exc} | | | | | | |")
            continue
        before, after, rel = targets.cut(carried_model(rep), name)
        o_w = targets.cut(oracle(runs), name)[2]
        o_wr = targets.cut(oracle(runs, ("track_width", "rolling_radius")), name)[2]
        rows.append((name, path, rel, o_w, o_wr))
        params = ", ".join(f"{k} = {v[0]:.4f} ± {v[1]:.4f}" for k, v in rep["parameters"].items())
        tr = rep.get("transfer") or {}
        inside = "; ".join(f"{'+'.join(t['effects'])} {t['error_ratio']:.2f}"
                           + (" (materially worse on a part)" if t["makes_parts_materially_worse"]
                              else " (worse on a part, not materially)"
                              if t["makes_a_part_worse"] else "")
                           for t in tr.get("tested", []))
        # the parsimony test: the richer model's fall of the held-out error (mean ± standard
        # error over the held-out parts, on the nominal error's scale), parts it lowers
        inside += "".join(f"; {'+'.join(v['richer'])} vs {'+'.join(v['simpler'])}: "
                          f"{v['mean_fall']:+.3f} ± {v['standard_error']:.3f}, "
                          f"{v['lower_on_parts']}/{v['parts']}"
                          f"{' (kept)' if v['richer_wins'] else ''}"
                          for v in tr.get("versus", []))
        print(f"| {name} | {path} | {len(runs)} | {_pct(arc_fraction(runs))} | {rep['cause']}"
              f"{' (' + ', '.join(rep['also']) + ')' if rep['also'] else ''} | "
              f"{params or '–'} | {inside or '–'} | {1e3 * before:.0f} → {1e3 * after:.0f} mm | "
              f"{_pct(rel)} | {_pct(o_w)} | {_pct(o_wr)} |", flush=True)
    if not rows:
        return
    hit = sum(r[2] >= 0.5 for r in rows)
    print(f"\nsession models cutting the other sessions' circle and square final error by "
          f">= 50 %: {hit}/{len(rows)} sessions (target >= 80 %); oracle (width) "
          f"{sum(r[3] >= 0.5 for r in rows)}/{len(rows)}, oracle (width + radii) "
          f"{sum(r[4] >= 0.5 for r in rows)}/{len(rows)}")
    for path in sorted({r[1] for r in rows}):
        rs = [r for r in rows if r[1] == path]
        print(f"  {path} sessions: {sum(r[2] >= 0.5 for r in rs)}/{len(rs)}, median cut "
              f"{_pct(np.median([r[2] for r in rs]))} (oracle width "
              f"{_pct(np.median([r[3] for r in rs]))}, width + radii "
              f"{_pct(np.median([r[4] for r in rs]))})")


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


PIVOT_RATIO = 0.9  # |g_R - g_L| / (|g_R| + |g_L|) above this: turning on the spot
MIN_PIVOT_SAMPLES = 15  # samples of one pivot (0.75 s at 20 Hz)
MIN_PIVOT_TURN_RAD = np.pi / 3  # a shorter arc leaves the centre and the offset confounded


def _wheel_turn(log) -> tuple[np.ndarray, np.ndarray]:
    """(nominal wheel yaw increment [rad], speed ratio) of each interval."""
    rim = np.diff(log.wheel_angles(), axis=0) * log.meta.wheel_radius_m
    sides = wheel_sides(list(log.wheels))
    left, right = rim[:, sides == 0].mean(axis=1), rim[:, sides == 1].mean(axis=1)
    return (right - left) / log.meta.track_width_m, \
        np.abs(right - left) / np.maximum(np.abs(right) + np.abs(left), 1e-12)


def pivot_offsets(log) -> np.ndarray:
    """Offset d (x, y along and across the body) [m] of the logged origin from the turning
    centre, one row per pivot of 60° or more: least squares of origin = c + R(ψ) d."""
    _, ratio = _wheel_turn(log)
    idx = np.flatnonzero(ratio > PIVOT_RATIO)
    out = []
    for run in np.split(idx, np.flatnonzero(np.diff(idx) > 3) + 1):
        if len(run) < MIN_PIVOT_SAMPLES:
            continue
        k = np.arange(run[0], run[-1] + 2)
        x, y, psi = (log.signals[c][k] for c in ("gt_x", "gt_y", "gt_yaw"))
        ok = np.isfinite(x) & np.isfinite(y) & np.isfinite(psi)
        if ok.sum() < MIN_PIVOT_SAMPLES or np.ptp(np.unwrap(psi[ok])) < MIN_PIVOT_TURN_RAD:
            continue
        c, s = np.cos(psi[ok]), np.sin(psi[ok])
        one, zero = np.ones(ok.sum()), np.zeros(ok.sum())
        a = np.vstack([np.column_stack([one, zero, c, -s]), np.column_stack([zero, one, s, c])])
        sol, *_ = np.linalg.lstsq(a, np.concatenate([x[ok], y[ok]]), rcond=None)
        out.append(sol[2:])
    return np.array(out).reshape(-1, 2)


def pivot_turn_scales(log) -> tuple[float, float]:
    """Logged turn over nominal wheel turn during pivots, in each half of the run."""
    dpsi_wheels, ratio = _wheel_turn(log)
    dpsi = np.diff(np.unwrap(log.signals["gt_yaw"]))
    first = np.arange(dpsi.size) < dpsi.size // 2
    out = []
    for half in (first, ~first):
        m = half & (ratio > PIVOT_RATIO) & np.isfinite(dpsi)
        out.append(float(dpsi[m].sum() / dpsi_wheels[m].sum()))
    return out[0], out[1]


def pivots(logs) -> None:
    """Step 8: the pivot-centre offsets per square session and the per-half turn scales."""
    squares = [log for log in logs if log.meta.data["optiodom"]["path_type"] == "square"]
    print("\n| square session | pivots | origin offset from the turning centre [mm] |"
          "\n|---|---|---|")
    by_session = defaultdict(list)
    for log in squares:
        by_session[log.meta.data["optiodom"]["session"]].append(pivot_offsets(log))
    for name, parts in sorted(by_session.items()):
        d = 1e3 * np.concatenate(parts)
        print(f"| {name} | {len(d)} | along {d[:, 0].mean():+.1f} ± {d[:, 0].std():.1f}, "
              f"across {d[:, 1].mean():+.1f} ± {d[:, 1].std():.1f} |")
    print("\n| square run (drift > 3°) | nominal heading drift [°] | pivot turn scale, "
          "first half | second half | difference |\n|---|---|---|---|---|")
    for log in squares:
        i = log.meta.data["optiodom"]
        drift = half_drifts(log)[0]
        if abs(drift) <= DRIFT_DEG:
            continue
        a, b = pivot_turn_scales(log)
        print(f"| {i['session']} run {i['run']} | {drift:+.1f} | {a:.4f} | {b:.4f} | "
              f"{100 * abs(a - b):.2f} % |")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="runs/real", help="folder for the converted logs")
    parser.add_argument("--single", action="store_true", help="only the single-run table")
    parser.add_argument("--pivots", action="store_true",
                        help="only the square runs' pivot-turn measurements")
    parser.add_argument("--sessions", action="store_true",
                        help="only the whole-session models on the other sessions' runs")
    parser.add_argument("--transfer", action="store_true",
                        help="only the session and single-run transfer tables (steps 5, 6)")
    args = parser.parse_args(argv)
    out = Path(args.out)
    convert_real_datasets(out, progress=False)
    logs = load_logs(out / "optiodom")
    if args.single:
        single_runs(logs)
        return 0
    if args.sessions:
        session_models(logs)
        return 0
    if args.transfer:
        targets = Targets(logs)
        session_models(logs, targets)
        single_runs(logs, targets)
        return 0
    if args.pivots:
        pivots(logs)
        return 0
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
    targets = Targets(logs)
    single_runs(logs, targets)
    session_models(logs, targets)
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
