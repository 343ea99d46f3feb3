"""The real-data findings of ``docs/real_data.md``: OptiOdom and BorealTC through the diagnosis.

1. Converts both datasets to slipenv-log/1 (``slipenv.logs.real``) under ``--out``.
2. OptiOdom, all runs together (what ``slipenv diagnose runs/real/optiodom`` prints): each run
   is predicted by models fitted on other runs (folds by run).
3. OptiOdom, per session: the same within each recording session.
4. OptiOdom, across path types: the effect chosen on all runs, fitted on the runs of one path
   type only and scored on the runs of the other types (never used for fitting).
5. OptiOdom, single runs (``--single``): every circle and square run whose nominal dead
   reckoning drifts more than 3° in heading over the run, diagnosed alone; the model fitted on
   that one run applied to the *other* sessions' circle runs (whole-run dead reckoning from
   the first logged pose): the mean cut of their final position error.
6. OptiOdom, whole sessions (``--sessions``): the model diagnosed on one session folder (all
   its runs together) applied to the *other* sessions' circle (arc) runs, dead-reckoned whole:
   the cut of their mean final position error, per session and on average (the target is
   at least 50 %); and the same with only what the session determines for arcs applied (a
   session that turns on the spot determines the distance scale, not the turn scale of arcs).
7. BorealTC (no ground truth): yaw efficiency per terrain (``slipenv.diagnose.proprio``).
8. OptiOdom square runs (``--pivots``): where the robot turns on the spot, relative to the
   OptiTrack body origin (each pivot's logged poses fitted as origin = centre + R(ψ) d: |d|
   is the origin's offset from the turning centre), and, per half of every square run that
   drifts more than 3°, the pivot turn scale (logged turn over wheel turn during pivots):
   whether the two halves of one run agree on the turn, which the single-run test needs.

    python benchmarks/real_data.py --out runs/real
    python benchmarks/real_data.py --out runs/real --single     # only step 5 (about 1 minute)
    python benchmarks/real_data.py --out runs/real --sessions   # only step 6
    python benchmarks/real_data.py --out runs/real --pivots     # only step 8 (seconds)
"""

from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np

from slipenv.diagnose import proprio
from slipenv.diagnose.cli import diagnose, load_logs
from slipenv.diagnose.effects.rolling_radius import RollingRadius
from slipenv.diagnose.extension import parse_model
from slipenv.diagnose.fit import Problem, fit
from slipenv.diagnose.numbers import determined
from slipenv.diagnose.replay import build_segments, simulate
from slipenv.diagnose.segments import cut_spans, log_arrays, wheel_sides
from slipenv.logs.real import convert_real_datasets

DRIFT_DEG = 3.0  # [deg] a run "visibly drifts" beyond this nominal heading error at its end


def whole_run(log, model: dict) -> tuple[float, float]:
    """(heading error [deg], position error [m]) at the end of the run, dead-reckoned whole
    from its first logged pose with ``model`` (``{}``: nominal)."""
    arr = log_arrays(log)
    ok = np.flatnonzero(arr["gt_ok"])
    seg = cut_spans([arr], [log], [(0, int(ok[0]), int(ok[-1]) + 1)])
    pred = simulate(seg, model)
    last = np.flatnonzero(seg.gt_ok[0])[-1]
    dyaw = (pred[0, last, 2] - seg.gt[0, last, 2] + np.pi) % (2 * np.pi) - np.pi
    return float(np.degrees(dyaw)), float(np.hypot(*(pred[0, last, :2] - seg.gt[0, last, :2])))


def single_runs(logs) -> None:
    """Step 5: the single-run table and its summary."""
    info = [log.meta.data["optiodom"] for log in logs]
    arcs = [(log, i["session"]) for log, i in zip(logs, info, strict=True)
            if i["path_type"] == "circular"]
    print("\n| run | nominal heading drift [°] | cause (also) | track_width_m / radii | "
          "turn scale c_θ | separable | other sessions' circle runs: final position error "
          "cut |\n|---|---|---|---|---|---|---|")
    named, total, cuts = 0, 0, []
    per_session: dict[tuple[str, str], list] = defaultdict(lambda: [0, 0, []])
    for log, i in zip(logs, info, strict=True):
        if i["path_type"] not in ("circular", "square"):
            continue
        drift = whole_run(log, {})[0]
        if abs(drift) <= DRIFT_DEG:
            continue
        total += 1
        rep, _ = diagnose([log], i["file"])
        causes = [rep["cause"], *rep["also"]]
        geometric = bool({"rolling_radius", "track_width"} & set(causes))
        named += geometric
        session = per_session[(i["path_type"], i["session"])]
        session[0] += 1
        session[1] += geometric
        cal = rep.get("calibration")
        cut = "–"
        if cal:
            model = parse_model(rep).effects
            others = [lg for lg, sess in arcs if sess != i["session"]]
            before = [whole_run(lg, {})[1] for lg in others]
            after = [whole_run(lg, model)[1] for lg in others]
            rel = 1.0 - np.mean(after) / np.mean(before)
            cuts.append(rel)
            session[2].append(rel)
            cut = f"{1e3 * np.mean(before):.0f} → {1e3 * np.mean(after):.0f} mm ({100 * rel:.0f} %)"
        params = ", ".join(f"{k} = {v[0]:.4f} ± {v[1]:.4f}" for k, v in rep["parameters"].items())
        scale = (f"{cal['determined']['turn_scale'][0]:.4f} ± "
                 f"{cal['determined']['turn_scale'][1]:.4f}" if cal else "–")
        print(f"| {i['path_type']} {i['session']} run {i['run']} | {drift:+.1f} | "
              f"{rep['cause']}{' (' + ', '.join(rep['also']) + ')' if rep['also'] else ''} | "
              f"{params or '–'} | {scale} | {cal['separable'] if cal else '–'} | {cut} |",
              flush=True)
    print(f"\n{named}/{total} single runs drifting > {DRIFT_DEG:g}° get a geometric cause; "
          f"their models cut the other sessions' circle-run final position error by "
          f"{100 * np.mean(cuts):.0f} % on average (median {100 * np.median(cuts):.0f} %)")
    print("\n| session (path) | runs drifting > 3° | geometric cause named | one-run models: "
          "other sessions' circle runs' final position error cut, mean (range) |\n"
          "|---|---|---|---|")
    for (path, name), (runs, hits, rels) in sorted(per_session.items(),
                                                   key=lambda kv: kv[0][1]):
        cut = (f"{100 * np.mean(rels):.0f} % ({100 * min(rels):.0f} to {100 * max(rels):.0f} %)"
               if rels else "–")
        print(f"| {name} ({path}) | {runs} | {hits} | {cut} |")


def arc_fraction(logs) -> float:
    """Share of the nominal turn angle of ``logs`` turned on arcs (the inner wheel rolling
    forward: turn radius above half the track), not on the spot."""
    arc = total = 0.0
    for log in logs:
        arr = log_arrays(log)
        ok = np.flatnonzero(arr["gt_ok"])
        seg = cut_spans([arr], [log], [(0, int(ok[0]), int(ok[-1]) + 1)])
        d = seg.radius[:, None, :] * seg.dphi
        left = d[..., seg.sides == 0].mean(axis=-1)[0]
        right = d[..., seg.sides == 1].mean(axis=-1)[0]
        turn = np.abs(right - left) / float(np.median(seg.track))
        arc += float(turn[left * right > 0].sum())
        total += float(turn.sum())
    return arc / max(total, 1e-12)


def determined_for_arcs(rep: dict, arcs: float) -> tuple[dict, str]:
    """The part of a session's geometric model that its runs determine for arc runs.

    The turn scale c_θ a session determines is that of the turns it drove: a session turning
    on the spot (``arcs`` < 0.5: pivot turns scrub the castors and turn about a point off the
    axle midpoint) does not determine the turn scale of arcs, only the distance scale c_d
    (its straights). Its model is applied as c_d on both wheel radii (turn scale nominal);
    any other model is applied whole.
    """
    model = parse_model(rep).effects
    cal = rep.get("calibration")
    if arcs >= 0.5 or not cal:
        return model, "whole model"
    c_d, se = cal["determined"]["distance_scale"]
    if not determined(c_d - 1.0, se):
        return {}, f"c_d = {c_d:.4f} ± {se:.4f} not determined: nominal"
    r = c_d * cal["nominal"]["wheel_radius_m"]
    return ({"rolling_radius": RollingRadius(r, r)},
            f"c_d = {c_d:.4f} ± {se:.4f} only (turn scale nominal)")


def session_models(logs) -> None:
    """Step 6: each session's model applied to the other sessions' circle runs, whole and
    as far as the session determines it for arcs (:func:`determined_for_arcs`)."""
    sessions = defaultdict(list)
    for log in logs:
        sessions[log.meta.data["optiodom"]["session"]].append(log)
    arcs = [(log, log.meta.data["optiodom"]["session"]) for log in logs
            if log.meta.data["optiodom"]["path_type"] == "circular"]
    print("\n| session fitted on | runs | turned on arcs | cause (also) | parameters | "
          "determined (c_θ, c_d) | other sessions' circle runs | final position error, "
          "nominal → fitted [mm] | cut | determined part applied | cut |\n"
          "|---|---|---|---|---|---|---|---|---|---|---|")
    cuts, cuts_det = [], []
    by_path: dict[str, list[float]] = defaultdict(list)
    for name, runs in sorted(sessions.items()):
        try:
            rep, _ = diagnose(runs, name)
        except ValueError as exc:
            print(f"| {name} | {len(runs)} | | not diagnosed: {exc} | | | | | | | |")
            continue
        others = [lg for lg, sess in arcs if sess != name]
        causes = [c for c in [rep["cause"], *rep["also"]] if c != "none"]
        params = ", ".join(f"{k} = {v[0]:.4f} ± {v[1]:.4f}" for k, v in rep["parameters"].items())
        share = arc_fraction(runs)
        if not causes or not others:
            print(f"| {name} | {len(runs)} | {100 * share:.0f} % | {rep['cause']} | – | – | "
                  f"{len(others)} | – | – | – | – |")
            continue
        cal = rep.get("calibration")
        det = ("; ".join(f"{k} {v[0]:.4f} ± {v[1]:.4f}" for k, v in cal["determined"].items())
               if cal else "–")
        before = np.mean([whole_run(lg, {})[1] for lg in others])
        after = np.mean([whole_run(lg, parse_model(rep).effects)[1] for lg in others])
        model, how = determined_for_arcs(rep, share)
        after_det = np.mean([whole_run(lg, model)[1] for lg in others])
        rel, rel_det = 1.0 - after / before, 1.0 - after_det / before
        cuts.append(rel)
        cuts_det.append(rel_det)
        by_path[runs[0].meta.data["optiodom"]["path_type"]].append(rel)
        print(f"| {name} | {len(runs)} | {100 * share:.0f} % | {rep['cause']}"
              f"{' (' + ', '.join(rep['also']) + ')' if rep['also'] else ''} | {params} | "
              f"{det} | {len(others)} | {1e3 * before:.0f} → {1e3 * after:.0f} | "
              f"{100 * rel:.0f} % | {how}: {1e3 * after_det:.0f} mm | {100 * rel_det:.0f} % |",
              flush=True)
    if cuts:
        print(f"\nsession models cut the other sessions' circle-run final position error by "
              f"{100 * np.mean(cuts):.0f} % on average (min {100 * np.min(cuts):.0f} %, "
              f"{len(cuts)} sessions with a cause); applied as far as determined for arcs: "
              f"{100 * np.mean(cuts_det):.0f} % (min {100 * np.min(cuts_det):.0f} %)")
        counts = defaultdict(int)
        for runs in sessions.values():
            counts[runs[0].meta.data["optiodom"]["path_type"]] += 1
        for path, rel in sorted(by_path.items()):
            print(f"  {path} sessions: {len(rel)} of {counts[path]} name a cause; their models "
                  f"cut it by {100 * np.mean(rel):.0f} % on average (min "
                  f"{100 * np.min(rel):.0f} %, max {100 * np.max(rel):.0f} %)")


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
        drift = whole_run(log, {})[0]
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
                        help="only the whole-session models on other sessions' circle runs")
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
    single_runs(logs)
    session_models(logs)
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
