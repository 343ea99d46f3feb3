"""Accuracy of FarmField-v0's main job: the env's own EKF under the baseline controller.

Drives ``slipenv/FarmField-v0`` (Lindgren's farm vehicle, 1.5 clockwise then 1.5
counter-clockwise 4 m circles on field loam) once per seed with ``slipenv run``'s machinery
(:func:`slipenv.run.run_episode`, :func:`slipenv.run.summarize`) and prints per seed, and as the
mean over the seeds, what the truth says of the estimate and of the driving:

* ``odometry_final_error_m``: distance between the env's estimate and the true position at the
  end of the episode;
* ``cross_track_rmse_m``: RMS of the true cross-track error (how well the controller, steering
  on the estimate, kept the vehicle on the path);
* ``lateral_bias_cw_m``, ``lateral_bias_ccw_m``: mean error of the estimate across the
  vehicle's heading (> 0: estimate left of the truth) over the clockwise and the
  counter-clockwise half, after the first 20 s (the filter's start-up): a crab that the
  filter does not model shows here with opposite signs;
* ``slip_angle_deg``: the true body slip angle β, mean over each half (the crab itself);
* the EKF's final lateral slip gain and slip angle when it has that state.

Targets (printed with the verdict): mean final error <= 3 cm, mean cross-track RMSE <= 5 cm.
``--estimator-kwargs`` replaces the preset's estimator options (A/B runs, e.g. the paper's
scheme 4 without the lateral slip state: ``'{"scheme": 4}'``). Run from the repository root::

    python benchmarks/farmfield_accuracy.py [--seeds 0 1 2 3 4] [--estimator-kwargs JSON]
        [--json PATH]

About 10-20 s per seed on one core (the first run after an edit of the filter also compiles
it).
"""

from __future__ import annotations

import argparse
import json
import math
import time

import numpy as np

from slipenv.estimators.lindgren.ekf import warm_up
from slipenv.run import EpisodeRecord, run_episode, summarize

ENV_ID = "slipenv/FarmField-v0"
CONTROLLER = "yamauchi"  # `slipenv run`'s default baseline controller
TARGET_FINAL_M = 0.03
TARGET_CROSS_TRACK_M = 0.05
SETTLE_S = 20.0  # start-up excluded from the lateral bias: the filter is still learning its soil


def lateral_bias(rec: EpisodeRecord) -> tuple[float, float, float, float]:
    """Mean across-heading error of the estimate [m] and mean true slip angle [deg], on the
    clockwise and the counter-clockwise half (by the sign of the true yaw rate)."""
    err = rec.est_pose[:, :2] - rec.true_pose[:, :2]
    yaw = rec.true_pose[:, 2]
    across = -np.sin(yaw) * err[:, 0] + np.cos(yaw) * err[:, 1]
    turn = np.diff(np.unwrap(yaw), prepend=yaw[0])
    late = rec.t_s > SETTLE_S
    out = []
    for half in (late & (turn < 0.0), late & (turn > 0.0)):
        out.append(float(np.mean(across[half])) if half.any() else math.nan)
        out.append(float(np.degrees(np.mean(rec.slip_angle_rad[half]))) if half.any()
                   else math.nan)
    return out[0], out[2], out[1], out[3]


def run_seed(seed: int, estimator_kwargs: dict | None) -> dict[str, float]:
    env_kwargs = {} if estimator_kwargs is None else {"estimator_kwargs": estimator_kwargs}
    rec = run_episode(ENV_ID, seed=seed, controller=CONTROLLER, **env_kwargs)
    stats = summarize(rec)
    cw, ccw, beta_cw, beta_ccw = lateral_bias(rec)
    row = {"seed": seed, "odometry_final_error_m": stats["odometry_final_error_m"],
           "cross_track_rmse_m": stats["cross_track_rmse_m"],
           "lateral_bias_cw_m": cw, "lateral_bias_ccw_m": ccw,
           "slip_angle_cw_deg": beta_cw, "slip_angle_ccw_deg": beta_ccw,
           "success": float(rec.success)}
    extras = rec.info_last.get("estimator_extras") or {}
    for key in ("k_beta_rad_per_g", "slip_angle_rad"):
        if key in extras:
            row[f"ekf_{key}"] = float(extras[key])
    return row


def main(argv: list[str] | None = None) -> dict:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    ap.add_argument("--estimator-kwargs", type=json.loads, default=None,
                    help="JSON estimator options in place of the preset's")
    ap.add_argument("--json", default=None, help="write the rows and means here")
    args = ap.parse_args(argv)
    warm_up()  # compile (or load) the filter before the first timed episode
    cols = ("odometry_final_error_m", "cross_track_rmse_m", "lateral_bias_cw_m",
            "lateral_bias_ccw_m", "slip_angle_cw_deg", "slip_angle_ccw_deg")
    heads = ("final err [m]", "x-track RMSE [m]", "lat bias cw [m]", "lat bias ccw [m]",
             "beta cw [deg]", "beta ccw [deg]")
    print(f"{ENV_ID}, controller {CONTROLLER}, estimator options "
          f"{args.estimator_kwargs or 'of the preset'}")
    print(f"{'seed':>4} " + " ".join(f"{h:>17}" for h in heads) + f" {'s':>5}")
    rows = []
    for seed in args.seeds:
        t0 = time.perf_counter()
        row = run_seed(seed, args.estimator_kwargs)
        rows.append(row)
        print(f"{seed:>4} " + " ".join(f"{row[c]:>17.4f}" for c in cols)
              + f" {time.perf_counter() - t0:>5.0f}", flush=True)
    mean = {c: float(np.mean([r[c] for r in rows])) for c in cols}
    print(f"{'mean':>4} " + " ".join(f"{mean[c]:>17.4f}" for c in cols))
    final_ok = mean["odometry_final_error_m"] <= TARGET_FINAL_M
    track_ok = mean["cross_track_rmse_m"] <= TARGET_CROSS_TRACK_M
    print(f"target: mean final error <= {TARGET_FINAL_M} m: "
          f"{'met' if final_ok else 'MISSED'}; mean cross-track RMSE <= "
          f"{TARGET_CROSS_TRACK_M} m: {'met' if track_ok else 'MISSED'}")
    result = {"env": ENV_ID, "controller": CONTROLLER,
              "estimator_kwargs": args.estimator_kwargs, "rows": rows, "mean": mean,
              "targets_met": {"final_error": final_ok, "cross_track_rmse": track_ok}}
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)
    return result


if __name__ == "__main__":
    main()
