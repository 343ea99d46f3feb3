"""``slipenv reproduce lindgren``: both experiments in both blocks (headline and robust), the
printed table, plots, JSON, page."""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass
from pathlib import Path as FsPath
from typing import Any

from slipenv.paths import Path, path_by_name

from ..progress import iterate
from ..results import publish
from . import plots, report
from .calibration import calibrate
from .docs import write_results_page
from .filters import run_filter
from .metrics import circles_metrics, dropout_experiment
from .paper import PAPER
from .recording import record
from .settings import (
    CIRCLE_RADIUS_M,
    CUT_S,
    FIELD_NOISE,
    FILTER,
    FULL,
    HEADLINE,
    LAGS,
    QUICK,
    ROBUST,
    SETTLE_M,
    SPEED_MPS,
    STEER_SCHEME,
    Setting,
)


@dataclass
class Block:
    """One block's results: its metrics (the JSON's), the recordings and filter runs the
    plots need, and its calibration (None without a measured radius)."""

    metrics: dict
    circles: tuple  # (Recording, {name: FilterRun}, circles metrics, autocorrelation series)
    dropout: tuple  # (first drive's Recording, its {name: FilterRun})
    calibration: dict | None


def run_block(setting: Setting, circles: Path, straights: Path, seeds: list[int],
              progress: bool = True) -> Block:
    """Both experiments in ``setting``'s world, on the circle drive ``seeds[0]`` and one
    straights drive per seed; with ``setting.measured_radius`` the no-slip schemes get the
    radius measured on a straight calibration drive (seed ``seeds[0]``) in the same world."""
    calibration = (calibrate(setting, seeds[0], progress) if setting.measured_radius
                   else None)
    rec_a = record(circles, seeds[0], progress, setting, calibration)
    runs_a = {s: run_filter(rec_a, s, variants=setting.variants)
              for s in iterate(setting.circle_filters, progress, f"filters (a), {setting.name}")}
    circ, rho = circles_metrics(rec_a, runs_a)
    drop, rec_b, runs_b = dropout_experiment(straights, seeds, progress, setting, calibration)
    final = drop["final_error_m"]
    metrics = {
        **{k: {n: v for n, v in circ[k].items() if n not in setting.variants}
           for k in ("mean_deviation_m", "nis", "autocorr_mean", "autocorr_var",
                     "autocorr_share_inside", "n_samples")},
        "dropout_final_error_m": {"no_slip_model": final["scheme3"],
                                  "slip_model": final["scheme4"], "oracle": final["oracle"]},
        "circles": circ, "dropout": drop,
    }
    return Block(metrics, (rec_a, runs_a, circ, rho), (rec_b, runs_b), calibration)


def _plots(block: Block, out: FsPath, suffix: str) -> list[FsPath]:
    rec_a, runs_a, circ, rho = block.circles
    rec_b, runs_b = block.dropout
    saved = [plots.plot_paths(rec_a, runs_a, circ, out / f"paths{suffix}.png"),
             plots.plot_dropout(rec_b, runs_b, out / f"dropout{suffix}.png", CUT_S)]
    if not suffix:
        saved.append(plots.plot_autocorrelation(rho, out / "autocorrelation.png"))
    return saved


def run(quick: bool = False, out_dir: str = "runs/reproduce_lindgren",
        json_path: str | None = None, seed: int = 0, progress: bool = True,
        docs_dir: str | None = None) -> dict:
    """Run both experiments in both blocks; print paper vs simulation; save plots, the JSON
    and the page.

    The headline block (:data:`~.settings.HEADLINE`) drives the world with the filter's own
    linear law and gives the filters the uniform-field settings; the robust block
    (:data:`~.settings.ROBUST`) drives the same paths with the same seeds and
    beacons in the curved Janosi/Okello world, with the estimator's default soil random walk
    and a measured radius for the no-slip filter.

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
        ``{"metrics", "paper", "targets", "targets_robust", "config", "run_time_s"}``;
        ``metrics["robust"]`` holds the robust block's metrics, with the headline's keys.
    """
    start = time.perf_counter()
    cfg = QUICK if quick else FULL
    circles = path_by_name("lindgren_circles", radius_m=CIRCLE_RADIUS_M, speed_mps=SPEED_MPS,
                           loops=cfg.circle_loops)
    straights = path_by_name("lindgren_straights", n_legs=cfg.straight_legs,
                             speed_mps=SPEED_MPS)
    seeds = [seed + i for i in range(cfg.dropout_drives)]
    head = run_block(HEADLINE, circles, straights, seeds, progress)
    robust = run_block(ROBUST, circles, straights, seeds, progress)
    metrics = {**head.metrics, "robust": robust.metrics}
    out = FsPath(out_dir)
    saved = _plots(head, out, "") + _plots(robust, out, "_robust")
    rec_a = head.circles[0]
    result: dict[str, Any] = {
              "metrics": metrics, "paper": PAPER, "targets": report.targets(metrics),
              "targets_robust": report.targets(robust.metrics),
              "config": {"quick": quick, "seed": seed, "steered_by": f"scheme {STEER_SCHEME}",
                         **dataclasses.asdict(cfg), "speed_mps": SPEED_MPS,
                         "settle_m": SETTLE_M, "lags": LAGS, "cut_s": CUT_S,
                         "filter": FILTER, "k_s_prior": rec_a.params.k_s0,
                         "nominal_wheel_radius_m": rec_a.geometry.wheel_radius_m,
                         "robust": {"force_model": ROBUST.force_model,
                                    "filter": dict(ROBUST.noise),
                                    "soil_noise": {k: getattr(robust.circles[0].params, k)
                                                   for k in FIELD_NOISE},
                                    "calibration": robust.calibration}},
              "run_time_s": time.perf_counter() - start}
    publish(result, report.format_table(metrics, PAPER, result["targets"], result["run_time_s"],
                                        result["targets_robust"]),
            saved, json_path, docs_dir, write_results_page)
    return result
