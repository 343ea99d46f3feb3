"""The diagnosis report: JSON (``log-format.md``, ``slipenv-diagnosis/1``) and a human report.

The human report is a folder with ``report.md`` (read it first: the cause, its parameters, the
held-out gain, the candidates) and plots: ``overlay.png`` (trajectory: logged, nominal replay,
extended replay), ``residuals_time.png`` (held-out errors over time), ``regressors.png``
(per-window residuals against torque, yaw rate, roll, pitch, speed, position), ``candidates.png``
(held-out error of every effect), for a soil patch or map ``soil.png`` (the route coloured by
the fitted compliance) and, when the PyBullet replay ran, ``pybullet.png``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from slipenv.diagnose import calibration, geometry, replay
from slipenv.diagnose.effects import effect, shown_parameters
from slipenv.diagnose.fit import Problem
from slipenv.diagnose.numbers import (
    better,
    determined_map,
    estimate,
    implausible_geometry,
    num,
    percent,
)
from slipenv.diagnose.segments import Segments
from slipenv.diagnose.select import ALPHA, MIN_DRIFT, MIN_GAIN, N_FOLDS, Selection
from slipenv.estimators.consistency import consistency_report
from slipenv.logs.log import Log

FORMAT = "slipenv-diagnosis/1"
_WINDOW_S = 0.5  # [s] window of the per-window residuals plotted against regressors


def _rmse(pred: np.ndarray, seg: Segments, pos: bool) -> float:
    if pos:
        err = (pred[..., :2] - seg.gt[..., :2])[seg.gt_ok]
        return float(np.sqrt(np.mean(np.sum(err**2, axis=-1))))
    yaw = pred[..., 2] if pred.ndim == 3 else pred
    return float(np.sqrt(np.mean(replay.heading_residuals(seg, yaw)[seg.gt_ok] ** 2)))


def gains(sel: Selection, problem: Problem) -> dict[str, Any]:
    """Held-out error before/after for the pose channel and, with a gyro, the gyro channel."""
    seg = problem.seg
    out: dict[str, Any] = {}
    base = sel.baseline["pose"].pred
    after = sel.final["pose"].pred if "pose" in sel.final else base
    for name, pos in (("position_rmse_m", True), ("heading_rmse_rad", False)):
        b, a = _rmse(base, seg, pos), _rmse(after, seg, pos)
        out[name] = {"metric": name, "before": b, "after": a,
                     "relative": 1.0 - a / b if b > 0 else 0.0, "evaluated_on": "held-out"}
    if "gyro" in sel.baseline:
        b = _rmse(sel.baseline["gyro"].pred, seg, False)
        a = _rmse(sel.final["gyro"].pred, seg, False) if "gyro" in sel.final else b
        out["gyro_heading_rmse_rad"] = {"metric": "gyro_heading_rmse_rad", "before": b,
                                        "after": a, "relative": 1.0 - a / b if b > 0 else 0.0,
                                        "evaluated_on": "held-out"}
    return out


def long_gain(sel: Selection) -> dict[str, Any] | None:
    """Position RMSE of each half of a single log replayed whole, by the nominal model and
    by the final model fitted on the other half (the long-horizon route's held-out gain)."""
    final = sel.final.get("pose")
    nominal = sel.long_baseline["pose"][1] if "pose" in sel.long_baseline else None
    if sel.halves is None or final is None or final.long_half is None or nominal is None:
        return None
    ok = sel.halves.seg[-1].gt_ok
    base = nominal.res[-1][..., :2][ok]
    after = final.long_half.res[-1][..., :2][ok]
    b = float(np.sqrt(np.mean(np.sum(base**2, axis=-1))))
    a = float(np.sqrt(np.mean(np.sum(after**2, axis=-1))))
    return {"metric": "position_rmse_m", "before": b, "after": a,
            "relative": 1.0 - a / b if b > 0 else 0.0,
            "evaluated_on": "held-out half of the log replayed whole (fit on the other half)"}


def transfer_gain(sel: Selection) -> dict[str, Any] | None:
    """Position RMSE of the held-out parts (runs, or halves) replayed whole, by the nominal
    model and by the pose model the transfer route chose (fitted on the other parts); None
    unless that route chose the pose model."""
    chosen = sel.transfer.get("chosen")
    if chosen is None:
        return None
    pos = chosen["position_rmse_m"]
    b = float(np.sqrt(np.mean(np.square(pos["before"]))))
    a = float(np.sqrt(np.mean(np.square(pos["after"]))))
    by = "run" if chosen["held_out_by"] == "run" else "half of a run"
    return {"metric": "position_rmse_m", "before": b, "after": a,
            "relative": 1.0 - a / b if b > 0 else 0.0,
            "evaluated_on": f"held-out {by} replayed whole (fitted on the others)"}


def consistency(sel: Selection, problem: Problem) -> dict[str, Any]:
    """NIS and whiteness of the segment-end pose residuals, nominal vs extended.

    Each segment's last ground-truth residual, in the frame of its starting pose (along,
    across), is one innovation-like sample; segments are in time order. The covariance S is
    that of the extended model's held-out residuals (the noise the diagnosis leaves
    unexplained), so the extended model's time-averaged NIS is 2 by construction and the
    nominal model's says how many times larger its errors are; the autocorrelation over
    consecutive segments shows a systematic (not white) residual.
    """
    seg = problem.seg
    last = np.array([np.flatnonzero(row)[-1] for row in seg.gt_ok])
    idx = np.arange(len(seg))
    yaw0 = seg.gt[:, 0, 2]
    out: dict[str, Any] = {}
    ends = {}
    for name, cand in (("nominal", sel.baseline["pose"]), ("extended", sel.final.get("pose"))):
        pred = (cand or sel.baseline["pose"]).pred
        e = pred[idx, last, :2] - seg.gt[idx, last, :2]
        c, s = np.cos(yaw0), np.sin(yaw0)
        ends[name] = np.column_stack([c * e[:, 0] + s * e[:, 1], -s * e[:, 0] + c * e[:, 1]])
    cov = np.cov(ends["extended"].T) + np.eye(2) * 1e-12
    lags = range(1, max(2, min(5, len(seg) // 4) + 1))
    for name, y in ends.items():
        rep = consistency_report((y, np.repeat(cov[None], len(y), axis=0)), name, lags=lags)
        out[name] = {"nis_mean": rep.nis_mean, "nis_band_95": list(rep.band_exact),
                     "autocorrelation_lags": rep.lags.tolist(), "autocorrelation": rep.rho.tolist(),
                     "autocorrelation_band": 1.96 / math.sqrt(rep.n_samples),
                     "mean_end_error_m": np.mean(y, axis=0).tolist()}
    return out


def confounded(sel: Selection, kind: str) -> list[dict[str, str]]:
    """Effects whose physics shows as a named cause on this vehicle kind (``Effect.confounds``,
    measured on the generator's worlds) and that explain the log on their own (significant):
    the confounded alternative of that cause, with what was measured."""
    chosen = {sel.cause, *sel.also} - {"none"}
    out = []
    for c in sel.candidates:
        name = c.effects[0] if len(c.effects) == 1 else None
        if name is None or name in chosen or c.untestable or not c.significant:
            continue
        conf = effect(name).confound(kind)
        if conf is not None and conf.shows_as in chosen:
            out.append({"cause": conf.shows_as, "alternative": name, "why": conf.why})
    return out


def build_report(sel: Selection, problem: Problem, logs: list[Log], where: str) -> dict:
    """The JSON report of ``log-format.md`` plus extra keys (effects, thresholds, checks)."""
    seg = problem.seg
    g = gains(sel, problem)
    params: dict[str, list[float]] = {}
    per_effect: dict[str, dict] = {}
    for fit in sel.fits.values():
        params.update(fit.report(seg))
        values, errors = fit.params, fit.se
        for name in fit.effects:
            per_effect[name] = effect(name).to_contract(values[name], errors[name], seg.wheels,
                                                        seg.sides)
    chosen = [sel.cause, *sel.also] if sel.cause != "none" else []
    only_gyro = bool(chosen) and all(effect(e).channel == "gyro" for e in chosen)
    gain = dict(g["gyro_heading_rmse_rad"] if only_gyro else g["position_rmse_m"])
    lg = long_gain(sel)
    if lg is not None:
        g["position_rmse_m_long_horizon"] = lg
        final = sel.final.get("pose")
        if not only_gyro and final is not None and not final.short_significant:
            gain = dict(lg)  # found on the long-horizon route: its held-out gain
    tg = transfer_gain(sel)
    if tg is not None:
        g["position_rmse_m_transfer"] = tg
        if not only_gyro:
            gain = dict(tg)  # the pose model was chosen by its transfer: that gain
    candidates = []
    for c in sel.candidates:
        entry: dict[str, Any] = {"cause": c.name}
        if c.untestable:
            entry.update(score=None, gain_relative=None, untestable=c.untestable)
        else:
            entry.update(score=c.error_ratio, gain_relative=c.gain_relative, p_value=c.p_value,
                         drift=c.drift, significant=c.significant, n_params=c.n_params,
                         channel=c.channel)
            if c.long is not None:
                entry["long_horizon"] = {"gain_relative": c.long.gain_relative,
                                         "p_value": c.long.p_value, "drift": c.long.drift,
                                         "turn_drift": c.long.turn_drift,
                                         "significant": c.long_significant}
        candidates.append(entry)
    covariance = {ch: {"names": f.names, "matrix": f.cov.tolist()}
                  for ch, f in sel.fits.items()}
    cal = calibration.calibration(problem, sel.fits.get("pose"))
    nominal = {"wheel_radius_m": float(np.median(seg.radius)),
               "track_width_m": float(np.median(seg.track))}
    warnings = implausible_geometry(params, nominal)
    if cal and warnings:
        cal["config_determined"] = False
    return {
        "format": FORMAT, "log": where, "cause": sel.cause, "also": sel.also,
        "confounded": [{**c, "determined": per_effect.get(c["cause"], {})}
                       for c in confounded(sel, seg.kind)],
        "parameters": params,
        "determined": determined_map(params),
        "gain": gain, "candidates": candidates,
        "covariance": covariance,
        **({"calibration": cal} if cal else {}),
        "effects": per_effect,
        "gains": g,
        "nominal": nominal, "warnings": warnings,
        "vehicle_kind": seg.kind, "wheels": seg.wheels,
        "segments": {"count": len(seg), "duration_s": float(np.median(seg.t[:, -1] - seg.t[:, 0])),
                     "folds": int(sel.folds.max()) + 1,
                     "fold_by": "log" if int(seg.log_index.max()) > 0 else "interleaved segments"},
        "consistency": consistency(sel, problem),
        "thresholds": {"alpha": ALPHA, "min_gain": MIN_GAIN, "min_drift": MIN_DRIFT,
                       "n_folds": N_FOLDS},
        "transfer": sel.transfer or None,
        "long_horizon": (None if sel.horizons is None else
                         {"horizons_s": sel.horizons.lengths_s,
                          "blocks": int(max(b.max() for b in sel.horizons.block)) + 1}),
        "score": "held-out mean squared error over the nominal model's (lower is better)",
        "logs": [str(log.path) if log.path else "<memory>" for log in logs],
    }


def write_json(report: dict, path: str | Path) -> Path:
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(_plain(report), indent=2, allow_nan=False) + "\n")
    return path


def _plain(value: Any) -> Any:
    """JSON-safe copy: numpy scalars to floats, NaN/inf to None."""
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_plain(v) for v in value]
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value


def window_residuals(problem: Problem) -> dict[str, np.ndarray]:
    """Nominal-model residual rates over ~0.5 s windows, and the regressors at each window.

    Per window: along-track residual divided by the nominal travel (an apparent slip),
    yaw-rate residual, across-track residual over travel (an apparent slip angle); and the
    window's torque, nominal yaw rate, roll, pitch, speed and position (roll and pitch from
    the declared slope and the logged heading when not logged).
    """
    seg = problem.seg
    dt = float(np.median(seg.dt[seg.dt > 0]))
    w = max(1, int(round(_WINDOW_S / dt)))
    rows: list[list[float]] = []
    d = seg.radius[:, None, :] * seg.dphi
    left, right = d[..., seg.sides == 0].mean(-1), d[..., seg.sides == 1].mean(-1)
    ds, dth = 0.5 * (left + right), (right - left) / seg.track[:, None]
    tq = seg.torque.mean(-1) if seg.torque is not None else np.full(ds.shape, np.nan)
    theta = geometry.heading_from_yaw(seg.gt[:, :-1, 2], seg.tilt[:, None])
    roll = seg.roll if seg.roll is not None else geometry.roll_from_heading(theta,
                                                                            seg.tilt[:, None])
    pitch = seg.pitch if seg.pitch is not None else geometry.pitch_from_heading(
        theta, seg.tilt[:, None])
    for j in range(len(seg)):
        ok = np.flatnonzero(seg.gt_ok[j])
        for a in ok[:-1]:
            b = a + w
            if b >= seg.gt.shape[1] or not seg.gt_ok[j, b] or (a - ok[0]) % w:
                continue
            yaw = np.unwrap(seg.gt[j, a:b + 1, 2])
            travel, turn = ds[j, a:b].sum(), dth[j, a:b].sum()
            dx, dy = seg.gt[j, b, :2] - seg.gt[j, a, :2]
            mid = 0.5 * (yaw[0] + yaw[-1])
            along, across = math.cos(mid) * dx + math.sin(mid) * dy, -math.sin(mid) * dx + \
                math.cos(mid) * dy
            span = seg.t[j, b] - seg.t[j, a]
            if abs(travel) < 1e-6 or span <= 0:
                continue
            rows.append([(travel - along) / abs(travel), (yaw[-1] - yaw[0] - turn) / span,
                         across / abs(travel), _mean(tq[j, a:b]), turn / span,
                         _mean(roll[j, a:b]), _mean(pitch[j, a:b]), travel / span,
                         *seg.pos[j, a]])
    names = ["slip", "yaw_rate_residual", "slip_angle", "torque", "yaw_rate", "roll", "pitch",
             "speed", "x", "y"]
    arr = np.array(rows) if rows else np.zeros((0, len(names)))
    return {n: arr[:, k] for k, n in enumerate(names)}


def _mean(x: np.ndarray) -> float:
    """Mean of the finite values (NaN, without a warning, when there are none)."""
    x = x[np.isfinite(x)]
    return float(x.mean()) if x.size else float("nan")


def write_human_report(folder: str | Path, report: dict, sel: Selection, problem: Problem,
                       sim_overlay: dict | None = None, logs: list[Log] | None = None) -> Path:
    """Plots and ``report.md`` in ``folder`` (created); with ``logs``, the whole-log dead
    reckoning before/after (``dead_reckoning.png``)."""
    from slipenv.diagnose import plots

    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    figs = {"overlay": plots.overlay(folder / "overlay.png", sel, problem),
            "residuals_time": plots.residuals_time(folder / "residuals_time.png", sel, problem),
            "regressors": plots.regressors(folder / "regressors.png", window_residuals(problem)),
            "candidates": plots.candidates(folder / "candidates.png", sel)}
    if logs and "pose" in sel.fits and sel.fits["pose"].effects:
        whole = plots.dead_reckoning(folder / "dead_reckoning.png", logs, sel.fits["pose"])
        if whole is not None:
            figs["dead_reckoning"] = whole
    fitted = sel.fits.get("pose")
    if fitted is not None and any(effect(name).local for name in fitted.effects):
        figs["soil"] = plots.soil(folder / "soil.png", problem, fitted)
    if sim_overlay:
        figs["pybullet"] = plots.pybullet(folder / "pybullet.png", sim_overlay)
    (folder / "report.md").write_text(markdown(report, figs, sim_overlay), encoding="utf-8")
    return folder


def transfer_markdown(tr: dict | None) -> list[str]:
    """The transfer section of ``report.md``: what a model fitted on some parts of the logs
    does to the others, replayed whole."""
    if not tr or not tr.get("tested"):
        return []
    part = "run" if tr["held_out_by"] == "run" else "half of a run"
    lines = ["## Transfer", "",
             f"Each geometric model fitted on the whole dead-reckoned paths of all but one "
             f"{part} ({tr['parts']} parts) and replayed whole over the one left out: its "
             "error over the nominal model's (lower is better).", "",
             "| model | held-out path error ratio | per part | final position error, nominal "
             "→ model [m] | drift | transfers |", "|---|---|---|---|---|---|"]
    rows = [("+".join(t["effects"]), t) for t in tr["tested"]]
    if "named_cause" in tr and tr["named_cause"]["effects"] not in \
            [t["effects"] for t in tr["tested"]]:
        rows.append(("+".join(tr["named_cause"]["effects"]), tr["named_cause"]))
    if "named_cause_on_segments" in tr:
        # the named slip law as it is named: fitted on the segments outside the part
        t = tr["named_cause_on_segments"]
        rows.append(("+".join(t["effects"]) + " (fitted on segments)", t))
    for label, t in rows:
        end = t["final_position_error_m"]
        worse = t["makes_parts_materially_worse"]
        lines.append(
            f"| {label} | {num(t['error_ratio'], '.3f')} | "
            f"{', '.join(num(r, '.2f') for r in t['per_part_error_ratio'])} | "
            f"{num(float(np.mean(end['before'])), '.4f')} → "
            f"{num(float(np.mean(end['after'])), '.4f')} | "
            f"{num(max(t['drift'], t['turn_drift']), '.4f')} | "
            + ("no: worse on the held-out parts" if worse else
               ("yes" if t.get("transfers") else "no: not material")
               + (" (a part worse, by less than a material drift)"
                  if t["makes_a_part_worse"] else "")) + " |")
    for v in tr.get("versus", []):
        # the parsimony test: a richer model is kept only beyond the held-out uncertainty
        lines += ["", f"{'+'.join(v['richer'])} against {'+'.join(v['simpler'])}: held-out "
                  f"error lower by {num(v['mean_fall'], '.3f')} ± "
                  f"{num(v['standard_error'], '.3f')} of the nominal error (mean ± standard "
                  f"error over the parts), lower on {v['lower_on_parts']} of {v['parts']} "
                  f"parts{' and' if v['lower_in_sum'] else ', not'} in sum: "
                  + ("the richer model is kept" if v["richer_wins"] else "the simpler stays")
                  + "."]
    lines += ["", f"Decision: {tr.get('decision', '–')}.", ""]
    return lines


def markdown(report: dict, figs: dict[str, Path], sim: dict | None) -> str:
    """The text of ``report.md``."""
    g = report["gain"]
    lines = [f"# Diagnosis of `{report['log']}`", ""]
    cause = report["cause"]
    if cause == "none":
        lines += ["**Cause: none** — no effect of the vocabulary improves the held-out "
                  "replay enough to count (see the thresholds below); the nominal model "
                  "explains the log up to noise.", ""]
    else:
        also = f" (also: {', '.join(report['also'])})" if report["also"] else ""
        lines += [f"**Cause: {cause}**{also} — {effect(cause).meaning}.", ""]
        shown, extra = shown_parameters(report["parameters"], [cause, *report["also"]])
        lines += ["| parameter | value ± standard error |", "|---|---|"]
        lines += [f"| `{k}` | {estimate(v[0], v[1])} |" for k, v in shown.items()]
        lines += [""] + (["```", *extra, "```", ""] if extra else [])
        for c in report.get("confounded", []):
            what = ", ".join(f"`{k}` = {estimate(v[0], v[1])}"
                             for k, v in c.get("determined", {}).items())
            lines += [f"**Confounded**: `{c['alternative']}` explains the log too; "
                      f"{c['why']}. What the log determines is {c['cause']}'s "
                      f"{what or 'parameters'}.", ""]
        undetermined = [k for k, ok in report.get("determined", {}).items() if not ok]
        if undetermined:
            lines += [f"**Not determined** by this log: {', '.join(undetermined)} (standard "
                      "error larger than the estimate; JSON `determined` is false).", ""]
    lines += [f"**Warning**: {w}." for w in report.get("warnings", [])]
    if report.get("warnings"):
        lines += [""]
    if report.get("calibration"):
        lines += calibration.markdown(report["calibration"])
    how = ("each segment predicted by a model fitted without it"
           if g.get("evaluated_on") == "held-out" else g.get("evaluated_on", ""))
    lines += [f"Held-out {g['metric']}: **{num(g['before'])} → {num(g['after'])}** "
              f"({better(g['relative'])}), {how}.", ""]
    lines += transfer_markdown(report.get("transfer"))
    seg = report["segments"]
    lines += [f"{seg['count']} segments of about {seg['duration_s']:.1f} s, each replayed from "
              f"the logged pose at its start; {seg['folds']} folds ({seg['fold_by']}).", "",
              "## Candidates", "",
              "| effect | held-out error ratio | gain | p | drift | long-horizon gain, p, drift "
              "| significant |",
              "|---|---|---|---|---|---|---|"]
    for c in report["candidates"]:
        if c.get("untestable"):
            lines.append(f"| {c['cause']} | – | – | – | – | – | not testable: "
                         f"{c['untestable']} |")
        else:
            lh = c.get("long_horizon")
            long = (f"{percent(lh['gain_relative'], '.0f')}, {num(lh['p_value'], '.2g')}, "
                    f"{num(max(lh['drift'], lh['turn_drift']), '.4f')}" if lh else "–")
            lines.append(f"| {c['cause']} | {num(c['score'], '.3f')} | "
                         f"{percent(c['gain_relative'], '.0f')} "
                         f"| {num(c['p_value'], '.2g')} | {num(c['drift'], '.4f')} | {long} | "
                         f"{'yes' if c['significant'] else 'no'} |")
    t = report["thresholds"]
    lines += ["", f"Significant = one-sided paired sign-flip p < {t['alpha']}, held-out mean "
              f"squared error down by ≥ {100 * t['min_gain']:.0f} %, and a material drift "
              f"(≥ {100 * t['min_drift']:.1f} % of the distance a segment covers) — either on the "
              "short segments, or on the long-horizon route: the log cut into blocks in time, "
              "each replayed whole by a model fitted without it (sign-flip test over blocks of "
              "the held-out score), gain and drift read on one half of the log replayed whole "
              "by a model fitted on the other.", "",
              "## Consistency of the segment-end residuals", "",
              "| model | time-averaged NIS | 95 % band | lag-1 autocorrelation | band |",
              "|---|---|---|---|---|"]
    for name, c in report["consistency"].items():
        lines.append(f"| {name} | {num(c['nis_mean'], '.2f')} | "
                     f"{num(c['nis_band_95'][0], '.2f')}–{num(c['nis_band_95'][1], '.2f')} | "
                     f"{num(c['autocorrelation'][0], '+.2f')} | "
                     f"±{num(c['autocorrelation_band'], '.2f')} |")
    lines += ["", "S is the extended model's residual covariance: the nominal model's NIS says "
              "how many times its end errors exceed what remains unexplained.", "",
              "## Plots", ""]
    captions = {"overlay": "logged path, nominal replay and extended replay (held-out)",
                "residuals_time": "held-out position and heading error over time",
                "regressors": "nominal residuals per 0.5 s window against candidate regressors",
                "candidates": "held-out error of every effect relative to the nominal model",
                "dead_reckoning": "whole-log dead reckoning from the first logged pose, nominal "
                                  "and with the fitted model (fitted on the whole log)",
                "soil": "where the fitted model softens the ground: the route coloured by "
                        "the torque compliance it gives each interval",
                "pybullet": "PyBullet replay (physics, logged wheel motion) before/after"}
    lines += [f"- `{p.name}` — {captions[k]}" for k, p in figs.items()]
    if sim:
        lines += ["", "## PyBullet replay", "", sim.get("note", ""), "",
                  f"Position RMSE over the replayed segments: nominal world "
                  f"{num(sim['rmse_nominal_m'])} m, extended world "
                  f"{num(sim['rmse_extended_m'])} m."]
    return "\n".join(lines) + "\n"
