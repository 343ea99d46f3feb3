"""``slipenv reproduce lindgren``: both experiments in both blocks (headline and ablation), the
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
from .regime import field_preset, operating_point
from .settings import (
    ABLATION,
    BLOCKS,
    CIRCLE_RADIUS_M,
    CUT_S,
    FIELD_NOISE,
    FILTER,
    FULL,
    HEADLINE,
    LAGS,
    NO_SLIP_SCHEME,
    QUICK,
    SETTLE_M,
    SLIP_SCHEMES,
    SPEED_MPS,
    STEER_SCHEME,
    Setting,
)

# The circle statistics reported per scheme and, under "no_slip_model" / "slip_model", for the
# no-slip scheme and the block's slip model: the mean error against the truth, the paper's
# deviation from scheme 1, the odometric NIS and its whiteness.
PER_SCHEME = ("mean_deviation_m", "deviation_from_scheme1_m", "nis", "autocorr_mean",
              "autocorr_var", "autocorr_share_inside", "n_samples")


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
    slip = best_slip_scheme(final, circ["n_samples"])
    names = {"no_slip_model": NO_SLIP_SCHEME, "slip_model": slip}
    metrics = {
        **{k: {**{n: v for n, v in circ[k].items() if n not in setting.variants},
               **{alias: circ[k].get(s) for alias, s in names.items()}}
           for k in PER_SCHEME},
        "dropout_final_error_m": {"no_slip_model": final[NO_SLIP_SCHEME],
                                  "slip_model": final[slip], "oracle": final["oracle"]},
        "slip_model_scheme": slip,
        "slip_model_schemes_final_error_m": {s: final[s] for s in SLIP_SCHEMES},
        "world": setting.world,
        "circles": circ, "dropout": drop,
    }
    if calibration is not None:
        metrics["operating_point"] = operating_point(
            calibration, sum(rec_a.oracle.k_s) / len(rec_a.oracle.k_s), field_preset())
    return Block(metrics, (rec_a, runs_a, circ, rho), (rec_b, runs_b), calibration)


def best_slip_scheme(final_error_m: dict, n_odometry: dict) -> str:
    """The slip-model scheme (:data:`~.settings.SLIP_SCHEMES`) with the lowest mean final
    error after the laser cut, among those that used odometry on the circles (``n_odometry``:
    odometric innovations in the circles' window per scheme; a scheme that rejected all of
    them acted as scheme 1 there, not as a slip model); the first listed on a tie."""
    used = [s for s in SLIP_SCHEMES if n_odometry.get(s)] or list(SLIP_SCHEMES)
    return min(used, key=lambda s: final_error_m[s])


def _plots(block: Block, out: FsPath, suffix: str) -> list[FsPath]:
    rec_a, runs_a, circ, rho = block.circles
    rec_b, runs_b = block.dropout
    slip = block.metrics["slip_model_scheme"]
    saved = [plots.plot_paths(rec_a, runs_a, circ, out / f"paths{suffix}.png", slip),
             plots.plot_dropout(rec_b, runs_b, out / f"dropout{suffix}.png", CUT_S, slip)]
    if not suffix:
        saved.append(plots.plot_autocorrelation(rho, out / "autocorrelation.png", slip))
    return saved


def run(quick: bool = False, out_dir: str = "runs/reproduce_lindgren",
        json_path: str | None = None, seed: int = 0, progress: bool = True,
        docs_dir: str | None = None) -> dict:
    """Run both experiments in both blocks; print paper vs simulation; save plots, the JSON
    and the page.

    The headline block (:data:`~.settings.HEADLINE`) drives the world the filter does not
    assume: the curved Janosi/Okello law on the field loam, the estimator's default process
    noise, per-wheel radii measured on a calibration drive for the no-slip filter. The
    ablation block (:data:`~.settings.ABLATION`) drives the same paths with the same seeds
    and beacons in a world with the filter's own linear law, the filters set as in the
    headline.

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
        ``{"metrics": {"headline", "ablation"}, "paper", "targets": {"headline",
        "ablation"}, "config", "run_time_s"}``.
    """
    start = time.perf_counter()
    cfg = QUICK if quick else FULL
    circles = path_by_name("lindgren_circles", radius_m=CIRCLE_RADIUS_M, speed_mps=SPEED_MPS,
                           loops=cfg.circle_loops)
    straights = path_by_name("lindgren_straights", n_legs=cfg.straight_legs,
                             speed_mps=SPEED_MPS)
    seeds = [seed + i for i in range(cfg.dropout_drives)]
    blocks = {b.name: run_block(b, circles, straights, seeds, progress) for b in BLOCKS}
    metrics = {name: b.metrics for name, b in blocks.items()}
    out = FsPath(out_dir)
    saved = (_plots(blocks[HEADLINE.name], out, "")
             + _plots(blocks[ABLATION.name], out, f"_{ABLATION.name}"))
    rec_a = blocks[HEADLINE.name].circles[0]
    result: dict[str, Any] = {
        "metrics": metrics, "paper": PAPER,
        "targets": {name: report.targets(m) for name, m in metrics.items()},
        "config": {"quick": quick, "seed": seed, "steered_by": f"scheme {STEER_SCHEME}",
                   **dataclasses.asdict(cfg), "speed_mps": SPEED_MPS,
                   "settle_m": SETTLE_M, "lags": LAGS, "cut_s": CUT_S,
                   "filter": FILTER, "k_s_prior": rec_a.params.k_s0,
                   "slip_schemes": list(SLIP_SCHEMES),
                   "nominal_wheel_radius_m": rec_a.geometry.wheel_radius_m,
                   "preset": field_preset(),
                   "blocks": {b.name: {"world": b.world,
                                       "force_model": b.force_model or "linear (env preset)",
                                       "filter": dict(b.noise),
                                       "soil_noise": {k: getattr(blocks[b.name].circles[0]
                                                                 .params, k)
                                                      for k in FIELD_NOISE},
                                       "calibration": blocks[b.name].calibration}
                              for b in BLOCKS}},
        "run_time_s": time.perf_counter() - start}
    publish(result, report.format_table(metrics, PAPER, result["targets"], result["run_time_s"]),
            saved, json_path, docs_dir, write_results_page)
    return result
