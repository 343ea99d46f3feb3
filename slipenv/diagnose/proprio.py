"""What logs without ground truth can support: yaw rate against wheel speeds, current against load.

With no pose truth (BorealTC) the replay cannot be compared with where the vehicle went, so
position effects (rolling radius, torque slip, slope side slip, soil patches, Endo's split of
the forward speed) cannot be identified. Two independent measurements remain:

- the gyro measures the true yaw rate; the wheels give the nominal one, Ω_kin = (v_R - v_L)/W.
  Their ratio η = Ω_gyro / Ω_kin is the skid-steer *yaw efficiency*: W/η is the effective
  track width (``track_width``, skid-steer turning geometry). Whether the loss depends on the
  speed ratio (``turning_slip``) is tested by a second term, Ω_gyro = Ω_kin (η - η_ρ |ρ|),
  ρ = (v_R - v_L)/(v_R + v_L). The gyro's bias comes from the samples where the wheels stand
  still. The gyro itself is the reference: a gyro scale error would pass for a width change.
- motor current (a torque proxy) against speed and turning: a harder-to-turn or softer ground
  needs more current; reported, not fitted to the vocabulary (no calibrated torque).

Held-out: each run's samples are split into 10 s blocks; fits use the even blocks of every
run and are scored on the odd ones; and, across runs, fits on the even-numbered runs of a
terrain are scored on its odd-numbered runs (``held_out_runs``).
"""

from __future__ import annotations

import math
from collections import defaultdict
from pathlib import Path

import numpy as np

from slipenv.diagnose.numbers import determined, num
from slipenv.diagnose.segments import wheel_sides
from slipenv.logs.log import Log

BLOCK_S = 10.0  # [s] held-out block length
MIN_TURN_RAD_S = 0.05  # [rad/s] nominal yaw rate below which a sample does not inform η
STILL_MPS = 0.01  # [m/s] wheel speed below which the vehicle stands still (gyro bias)
# Plausible effective track width over the nominal one, W_eff/W = 1/η: a tyre's contact line
# moves a wheel width at most inwards; skid-steer turning losses give up to several W (BorealTC's
# Husky: 1.5 W on hard floors, 5-6 W pooled on snow, docs/real_data.md). 10 W (η = 0.1) is
# beyond any of them: a gyro that hardly follows the wheels, a wrong axis or wheel mapping.
PLAUSIBLE_WIDTH_RATIO = (0.67, 10.0)
CANNOT = ["rolling_radius (no position truth: distance travelled is unobserved)",
          "torque_slip and soil_patch (no calibrated torque and no position truth)",
          "slope_side_slip, combined_slip (no position truth: sideways motion is unobserved)",
          "Endo's exponent n of turning_slip (it splits the forward speed, which is unobserved)",
          "a gyro scale error (the gyro is the yaw reference)"]


def _signals(log: Log) -> dict[str, np.ndarray] | None:
    """Per-interval wheel-side speeds [m/s], yaw rates [rad/s], currents [A] and block ids."""
    if not log.has("gyro_z"):
        return None
    sides = wheel_sides(log.wheels)
    speeds = log.wheel_speeds()[1:] * log.meta.wheel_radius_m
    v_l, v_r = speeds[:, sides == 0].mean(1), speeds[:, sides == 1].mean(1)
    g = log.signals["gyro_z"]
    gyro = 0.5 * (g[1:] + g[:-1])
    t = 0.5 * (log.t[1:] + log.t[:-1])
    out = {"v_l": v_l, "v_r": v_r, "gyro": gyro, "t": t,
           "kin": (v_r - v_l) / log.meta.track_width_m,
           "block": np.floor((t - log.t[0]) / BLOCK_S).astype(int)}
    for side in ("left", "right"):
        c = log.signals.get(f"current_{side}")
        out[f"current_{side}"] = (0.5 * (c[1:] + c[:-1]) if c is not None
                                  else np.full(len(t), np.nan))
    return out


def _fit(kin: np.ndarray, rho: np.ndarray, gyro: np.ndarray, blocks: np.ndarray,
         with_rho: bool) -> tuple[np.ndarray, np.ndarray]:
    """Least squares gyro ≈ kin (η - η_ρ |ρ|) + b; values and block-robust covariance."""
    cols = [kin] + ([-kin * np.abs(rho)] if with_rho else []) + [np.ones_like(kin)]
    a = np.column_stack(cols)
    x, *_ = np.linalg.lstsq(a, gyro, rcond=None)
    r = gyro - a @ x
    ata = np.linalg.pinv(a.T @ a)
    scores = np.zeros((blocks.max() + 1, a.shape[1]))
    np.add.at(scores, blocks, a * r[:, None])
    g = max(len(np.unique(blocks)), 2)
    cov = ata @ (scores.T @ scores) @ ata * g / max(g - a.shape[1], 1)
    return x, cov


def analyse(logs: list[Log], where: str) -> dict:
    """Yaw-efficiency and current analysis of logs without ground truth (grouped by terrain)."""
    groups: dict[str, list[tuple[Log, dict]]] = defaultdict(list)
    skipped = []
    for log in logs:
        sig = _signals(log)
        if sig is None:
            skipped.append(str(log.path))
            continue
        terrain = (log.meta.data.get("borealtc") or {}).get("terrain") or \
            log.meta.terrain_description or "all"
        groups[terrain].append((log, sig))
    if not groups:
        raise ValueError(f"{where}: no ground-truth pose and no gyro_z column: there is "
                         "nothing to compare the wheel motion with")
    results = {name: _analyse_group(items) for name, items in sorted(groups.items())}
    pooled = _analyse_group([it for items in groups.values() for it in items]) if groups else {}
    cause = "none"
    if pooled.get("significant"):
        cause = "track_width"
    also = ["turning_slip"] if cause != "none" and pooled.get("turning_significant") else []
    params = {}
    if cause != "none":
        params["track_width_m"] = pooled["effective_track_width_m"]
    warnings = [f"{name}: {w}" for name, g in sorted(results.items())
                for w in g.get("warnings", [])]
    return {
        "format": "slipenv-diagnosis/1", "log": where, "cause": cause, "also": also,
        "parameters": params,
        "determined": {"track_width_m": bool(pooled.get("determined", False))},
        "warnings": warnings,
        "gain": {"metric": "yaw_rate_rmse_rad_s", "before": pooled.get("rmse_before"),
                 "after": pooled.get("rmse_after"), "relative": pooled.get("relative"),
                 "evaluated_on": "held-out (odd 10 s blocks)"},
        "candidates": [{"cause": "track_width", "score": pooled.get("relative"),
                        "gain_relative": pooled.get("relative")},
                       {"cause": "turning_slip", "score": pooled.get("turning_relative"),
                        "gain_relative": pooled.get("turning_relative"),
                        "note": "yaw part only (Endo's n is unobservable)"}],
        "ground_truth": "none", "groups": results, "cannot_conclude": CANNOT,
        "skipped_without_gyro": skipped,
    }


def _analyse_group(items: list[tuple[Log, dict]]) -> dict:
    cat: dict[str, list[np.ndarray]] = {
        k: [] for k in ("kin", "gyro", "v_l", "v_r", "block", "current_left", "current_right",
                        "run")}
    offset = 0
    for r, (_, sig) in enumerate(items):
        for k in cat:
            if k == "run":
                cat[k].append(np.full(len(sig["kin"]), r))
            else:
                cat[k].append(sig[k] + (offset if k == "block" else 0))
        offset += int(sig["block"].max()) + 1
    d = {k: np.concatenate(v) for k, v in cat.items()}
    ok = np.isfinite(d["gyro"]) & np.isfinite(d["kin"])
    still = ok & (np.abs(d["v_l"]) < STILL_MPS) & (np.abs(d["v_r"]) < STILL_MPS)
    bias = float(np.mean(d["gyro"][still])) if still.sum() > 20 else None
    turn = ok & (np.abs(d["kin"]) > MIN_TURN_RAD_S)
    if turn.sum() < 50:
        return {"runs": len(items), "samples_turning": int(turn.sum()), "gyro_bias_rad_s": bias,
                "note": "too little turning to estimate the yaw efficiency"}
    s = d["v_l"] + d["v_r"]
    rho = np.where(np.abs(s) > 1e-6, (d["v_r"] - d["v_l"]) / np.where(s == 0, 1, s), 1.0)
    rho = np.clip(rho, -5.0, 5.0)
    kin, gyro, blocks = d["kin"][turn], d["gyro"][turn], d["block"][turn]
    rho = rho[turn]
    train, test = blocks % 2 == 0, blocks % 2 == 1
    x, cov = _fit(kin[train], rho[train], gyro[train], blocks[train], False)
    x2, _ = _fit(kin[train], rho[train], gyro[train], blocks[train], True)
    before = float(np.sqrt(np.mean((gyro[test] - kin[test]) ** 2)))
    after = float(np.sqrt(np.mean((gyro[test] - x[0] * kin[test] - x[1]) ** 2)))
    pred2 = kin[test] * (x2[0] - x2[1] * np.abs(rho[test])) + x2[2]
    after2 = float(np.sqrt(np.mean((gyro[test] - pred2) ** 2)))
    xa, cova = _fit(kin, rho, gyro, blocks, False)
    eta, eta_se = float(xa[0]), float(math.sqrt(cova[0, 0]))
    runs = d["run"][turn]
    per_run = []
    for r, (log, _) in enumerate(items):
        m = runs == r
        if m.sum() >= 50 and float(np.std(kin[m])) > 0.1:  # the run really turns
            xr, _ = _fit(kin[m], rho[m], gyro[m], blocks[m], False)
            per_run.append([log.path.name if log.path else str(r), float(xr[0]), int(m.sum())])
    cross = None
    train_runs, test_runs = runs % 2 == 0, runs % 2 == 1
    if train_runs.sum() >= 50 and test_runs.sum() >= 50:  # fit on even runs, score on odd
        xc, _ = _fit(kin[train_runs], rho[train_runs], gyro[train_runs], blocks[train_runs],
                     False)
        b = float(np.sqrt(np.mean((gyro[test_runs] - kin[test_runs]) ** 2)))
        a = float(np.sqrt(np.mean((gyro[test_runs] - xc[0] * kin[test_runs] - xc[1]) ** 2)))
        cross = {"before": b, "after": a, "relative": 1.0 - a / b}
    w = items[0][0].meta.track_width_m
    w_eff, w_se = (w / eta, w * eta_se / eta**2) if eta != 0 else (math.inf, math.inf)
    ok = determined(w_eff, w_se)
    low, high = PLAUSIBLE_WIDTH_RATIO
    plausible = bool(ok and low * w <= w_eff <= high * w)
    warnings = []
    if not ok:
        warnings.append(f"effective track width not determined (yaw efficiency {eta:.3g} ± "
                        f"{eta_se:.2g}: the gyro's yaw rate hardly follows the wheels')")
    elif not plausible:
        warnings.append(f"effective track width {w_eff:.3g} m is implausible for a nominal "
                        f"{w:.3g} m track (outside {low:g}-{high:g} times): check the gyro axis "
                        "and sign, the wheel names and the encoder scale; not determined")
    straight = (np.abs(d["kin"]) < 0.05) & (0.5 * np.abs(d["v_l"] + d["v_r"]) > 0.2)
    both = np.stack([d["current_left"], d["current_right"]])
    count = np.isfinite(both).sum(axis=0)
    current = np.where(count > 0, np.nansum(both, axis=0) / np.maximum(count, 1), np.nan)
    turning = np.abs(d["kin"]) > 0.3
    return {
        "runs": len(items), "samples_turning": int(turn.sum()),
        "yaw_efficiency": [eta, eta_se],
        "effective_track_width_m": [w_eff, w_se],
        "determined": plausible, "warnings": warnings,
        "gyro_bias_rad_s": bias,
        "rmse_before": before, "rmse_after": after, "relative": 1.0 - after / before,
        "turning_relative": 1.0 - after2 / after if after > 0 else 0.0,
        "eta_rho_term": float(x2[1]),
        "significant": bool(plausible and abs(1.0 - eta) > 3 * eta_se and after < 0.9 * before),
        "turning_significant": bool(after2 < 0.95 * after),
        "current_straight_median_a": _median(current[straight]),
        "current_turning_median_a": _median(current[turning]),
        "per_run_yaw_efficiency": per_run, "held_out_runs": cross,
    }


def _median(x: np.ndarray) -> float | None:
    x = x[np.isfinite(x)]
    return float(np.median(x)) if x.size else None


def summary(result: dict) -> str:
    """Terminal lines: per group η, effective width, held-out gain, currents."""
    lines = ["no ground-truth pose: yaw rate (gyro) against wheel speeds, current against load",
             f"{'group':<12} {'runs':>4} {'yaw eff.':>14} {'W_eff [m]':>14} {'held-out':>9} "
             f"{'I_straight':>10} {'I_turn':>7}"]
    for name, g in result["groups"].items():
        if "yaw_efficiency" not in g:
            lines.append(f"{name:<12} {g['runs']:>4}  {g.get('note', '')}")
            continue
        e, w = g["yaw_efficiency"], g["effective_track_width_m"]
        cur = [num(v, ".2f") if v is not None else "-" for v in
               (g["current_straight_median_a"], g["current_turning_median_a"])]
        width = (f"{num(w[0], '>7.3f')}±{num(w[1], '<6.3f')}" if g.get("determined")
                 else f"{'not determined':>14}")
        lines.append(f"{name:<12} {g['runs']:>4} {num(e[0], '>7.3f')}±{num(e[1], '<6.3f')} "
                     f"{width} {num(100 * g['relative'], '>8.0f')}% {cur[0]:>10} {cur[1]:>7}")
    lines += [f"warning: {w}" for w in result.get("warnings", [])]
    lines.append("cannot be concluded without ground truth: "
                 + "; ".join(result["cannot_conclude"]))
    return "\n".join(lines)


def write_report(folder: str | Path, result: dict) -> Path:
    """``report.md`` for a log (folder) without ground truth."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    text = ["# Proprioceptive diagnosis (no ground truth)", "", "```", summary(result), "```",
            "", "Yaw efficiency η = gyro yaw rate / wheel yaw rate (v_R - v_L)/W, fitted on even "
            "10 s blocks and scored on odd ones; W/η is the effective track width.", "",
            "## What cannot be concluded", ""] + [f"- {c}" for c in result["cannot_conclude"]]
    (folder / "report.md").write_text("\n".join(text) + "\n", encoding="utf-8")
    return folder
