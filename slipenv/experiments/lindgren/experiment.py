"""``slipenv reproduce lindgren``: both experiments, the printed table, plots, JSON, page."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path as FsPath

from slipenv.paths import path_by_name

from ..progress import iterate
from . import plots, report
from .docs import write_results_page
from .filters import run_filter
from .metrics import circles_metrics, dropout_experiment
from .paper import PAPER
from .recording import record
from .settings import (
    CIRCLE_RADIUS_M,
    CUT_S,
    FILTER,
    FULL,
    LAGS,
    QUICK,
    SCHEMES,
    SETTLE_M,
    SPEED_MPS,
    STEER_SCHEME,
)


def run(quick: bool = False, out_dir: str = "runs/reproduce_lindgren",
        json_path: str | None = None, seed: int = 0, progress: bool = True,
        docs_dir: str | None = None) -> dict:
    """Run both experiments; print paper vs simulation; save plots, the JSON and the page.

    Parameters
    ----------
    quick : bool
        Shorter paths (:data:`~.settings.QUICK`), the same experiments.
    out_dir : str
        Folder for the plots.
    json_path : str, optional
        Write the result (metrics, paper values, targets, configuration) as JSON.
    seed : int
        Seed of the circle drive and of the first straights drive (then ``seed + 1``, ...).
    progress : bool
        Show progress bars.
    docs_dir : str, optional
        Write the results page ``docs_dir/lindgren.md`` (figures copied beside it).

    Returns
    -------
    dict
        ``{"metrics", "paper", "targets", "config", "run_time_s"}``.
    """
    start = time.perf_counter()
    cfg = QUICK if quick else FULL
    circles = path_by_name("lindgren_circles", radius_m=CIRCLE_RADIUS_M, speed_mps=SPEED_MPS,
                           loops=cfg.circle_loops)
    straights = path_by_name("lindgren_straights", n_legs=cfg.straight_legs,
                             speed_mps=SPEED_MPS)
    rec_a = record(circles, seed, progress)
    runs_a = {s: run_filter(rec_a, s) for s in iterate(SCHEMES, progress, "filters (a)")}
    circ, rho = circles_metrics(rec_a, runs_a)
    seeds = [seed + i for i in range(cfg.dropout_drives)]
    drop, rec_b, runs_b = dropout_experiment(straights, seeds, progress)
    final = drop["final_error_m"]
    metrics = {
        **{k: circ[k] for k in ("mean_deviation_m", "nis", "autocorr_mean", "autocorr_var",
                                "autocorr_share_inside", "n_samples")},
        "dropout_final_error_m": {"no_slip_model": final["scheme3"],
                                  "slip_model": final["scheme4"], "oracle": final["oracle"]},
        "circles": circ, "dropout": drop,
    }
    out = FsPath(out_dir)
    saved = [plots.plot_paths(rec_a, runs_a, circ, out / "paths.png"),
             plots.plot_dropout(rec_b, runs_b, out / "dropout.png", CUT_S),
             plots.plot_autocorrelation(rho, out / "autocorrelation.png")]
    result = {"metrics": metrics, "paper": PAPER, "targets": report.targets(metrics),
              "config": {"quick": quick, "seed": seed, "steered_by": f"scheme {STEER_SCHEME}",
                         **dataclasses.asdict(cfg), "speed_mps": SPEED_MPS,
                         "settle_m": SETTLE_M, "lags": LAGS, "cut_s": CUT_S,
                         "filter": FILTER, "k_s_prior": rec_a.params.k_s0,
                         "nominal_wheel_radius_m": rec_a.geometry.wheel_radius_m},
              "run_time_s": time.perf_counter() - start}
    print(report.format_table(metrics, PAPER, result["targets"], result["run_time_s"]))
    print("plots: " + ", ".join(str(p) for p in saved))
    if json_path:
        print(f"written: {report.write_json(result, json_path)}")
    if docs_dir is not None:
        print(f"page: {write_results_page(result, saved, docs_dir)}")
    return result
