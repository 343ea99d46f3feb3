"""``slipenv reproduce yamauchi``: identification, odometry replays and circles, in order."""

from __future__ import annotations

import dataclasses
import json
import math
import time
from pathlib import Path as FsPath
from typing import Any

import numpy as np

from slipenv.envs.estimation import odometry_geometry
from slipenv.estimators.skid_steer.identification import evaluate_runs, fit_slip_angle_runs
from slipenv.vehicles.presets import tracked_patako

from ..progress import iterate
from ..results import publish
from . import model_file
from .circle import best_gain, circle_episode, mean_episodes
from .docs import world_options, write_results_page
from .odometry import odometry_errors
from .paper import ENDO_N, PAPER
from .plots import save_figures
from .report import format_table
from .rotation import collect_runs, split_runs
from .settings import (
    CALIBRATED,
    DEFAULT_SOIL,
    DEFAULT_VEHICLE,
    FULL,
    QUICK,
    TARGETS,
    WORLD_CALIBRATED,
    Settings,
    is_env_world,
    world_of,
)
from .slips import fit_n, slip_run


def score_direction(cfg: Settings, train: list, test: list, geom, direction: int,
                    n_by_tilt: dict, n_clockwise_by_tilt: dict | None = None) -> dict:
    """Eq. 9 fitted on the training runs turning ``direction``, scored on the held-out ones,
    and the odometries replayed on those, with Endo's n per tilt (``n_clockwise_by_tilt``:
    a second n for clockwise steps)."""
    cw = n_clockwise_by_tilt or {}
    tr = [slip_run(r, geom, n_by_tilt[r.tilt_deg], cfg, cw.get(r.tilt_deg))
          for r in train if r.direction == direction]
    te_runs = [r for r in test if r.direction == direction]
    te = [slip_run(r, geom, n_by_tilt[r.tilt_deg], cfg, cw.get(r.tilt_deg)) for r in te_runs]
    model = fit_slip_angle_runs(tr)
    squared = odometry_errors(te_runs, geom, n_by_tilt, model, n_clockwise_by_tilt)
    rmse = {k: float(np.sqrt(v.mean())) for k, v in squared.items()}
    limits = {k: rmse.pop(k) for k in list(rmse) if k.startswith("slip_compensated_true")}
    return {"model": model, "beta_rmse_rad": evaluate_runs(model, te), "test_runs": te_runs,
            "odometry_rmse_m": rmse, "true_beta_rmse_m": limits["slip_compensated_true_beta"],
            "limits_rmse_m": limits, "squared_errors_m2": squared}


def cross_validated_ratio(cfg: Settings, runs: list, geom, rng: np.random.Generator
                          ) -> dict[str, float]:
    """Slip-compensated / gyrodometry position RMSE per turning direction, ``cfg.cv_folds``-fold
    cross-validated by run: the runs of every (tilt, direction) group dealt into folds at
    random, each fold held out once while Endo's n (per tilt) and Eq. 9 (per direction) are
    fitted on the others, the squared errors of every held-out run pooled. The same
    protocol as the headline split, with every run scored once, so the ratio does not hang on
    which third of the runs one split holds out."""
    folds: list[list] = [[] for _ in range(cfg.cv_folds)]
    for t in cfg.tilts_deg:
        for d in cfg.directions:
            group = [r for r in runs if r.tilt_deg == t and r.direction == d]
            for k, i in enumerate(rng.permutation(len(group))):
                folds[k % cfg.cv_folds].append(group[i])
    pooled: dict[int, dict[str, list]] = {d: {} for d in cfg.directions}
    for held in folds:
        names = {r.name for r in held}
        train = [r for r in runs if r.name not in names]
        n_by_tilt = {t: fit_n([r for r in train if r.tilt_deg == t], geom,
                              cfg.smooth_steps)[0].n for t in cfg.tilts_deg}
        for d in cfg.directions:
            errors = score_direction(cfg, train, held, geom, d, n_by_tilt)["squared_errors_m2"]
            for key in ("slip_compensated", "gyrodometry"):
                pooled[d].setdefault(key, []).append(errors[key])
    return {"ccw" if d > 0 else "cw": math.sqrt(
        np.concatenate(v["slip_compensated"]).mean() / np.concatenate(v["gyrodometry"]).mean())
        for d, v in pooled.items()}


def fall_line_start(cfg: Settings, geom, rng: np.random.Generator, progress: bool) -> dict:
    """The rotation runs started facing downhill (``start_heading_deg`` -90), the other reading
    of §2.3's field (module `settings`): Endo's n per tilt (every run) and per turning
    direction, and the held-out slip-compensated / gyrodometry ratio per direction, split and
    scored as the headline."""
    runs = collect_runs(dataclasses.replace(cfg, start_heading_deg=-90.0), rng, progress)
    train, test = split_runs(runs, cfg, rng)
    ident = identify(cfg, train, test, geom)
    return {"endo_n": {f"{t:g}": f.n for t, f in ident["fits"].items()},
            "endo_n_by_direction": ident["n_by_direction"],
            "odometry_rmse_ratio": {
                d: v["odometry_rmse_m"]["slip_compensated"] / v["odometry_rmse_m"]["gyrodometry"]
                for d, v in ident["by_dir"].items()}}


def identify(cfg: Settings, train: list, test: list, geom) -> dict:
    """Endo's n per tilt as the paper identified it, and one Eq. 9 regression per turning
    direction, scored on the held-out runs.

    The paper's n (§2.4, Fig. 4) comes from every rotation result of a tilt: ``fits``,
    ``samples`` and ``n_by_direction`` (a diagnostic) pool the training and held-out runs.
    The odometry and the circle use ``n_training``, fitted on the training runs only, so that
    nothing of a held-out run reaches the odometry it is scored with.

    One regression per direction departs from the paper: on a slope part of the slip angle is
    even in the turning direction, which Eq. 9's regressors carry only as a sign. Endo's n per
    tilt and direction, also from the training runs alone (``training_fits_by_direction``),
    is scored beside it (``by_dir[...]["n_by_direction"]``). The odometry keeps the pooled n,
    Eq. 8's one n per tilt: on the held-out runs the per-direction n did worse turning uphill
    (counter-clockwise) and better turning downhill (the results page gives both).
    """
    runs = train + test
    fits, samples, training = {}, {}, {}
    for t in cfg.tilts_deg:
        fits[t], samples[t] = fit_n([r for r in runs if r.tilt_deg == t], geom,
                                    cfg.smooth_steps)
        training[t] = fit_n([r for r in train if r.tilt_deg == t], geom, cfg.smooth_steps)[0]
    n_by_tilt = {t: f.n for t, f in training.items()}
    # diagnostic: Endo's relation does not know which way is uphill
    n_by_direction: dict[str, Any] = {}
    training_by_direction: dict[str, Any] = {}
    for t in cfg.tilts_deg:
        for d in cfg.directions:
            key = f"{t:g}_{'ccw' if d > 0 else 'cw'}"
            for out, pool in ((n_by_direction, runs), (training_by_direction, train)):
                try:
                    out[key] = fit_n([r for r in pool if r.tilt_deg == t and r.direction == d],
                                     geom, cfg.smooth_steps)[0]
                except ValueError:
                    out[key] = None
    n_by_direction = {k: None if f is None else f.n for k, f in n_by_direction.items()}
    by_dir = {}
    split = None
    if set(cfg.directions) == {1, -1} and None not in training_by_direction.values():
        split = ({t: training_by_direction[f"{t:g}_ccw"].n for t in cfg.tilts_deg},
                 {t: training_by_direction[f"{t:g}_cw"].n for t in cfg.tilts_deg})
    for d in cfg.directions:
        entry = score_direction(cfg, train, test, geom, d, n_by_tilt)
        if split is not None:
            entry["n_by_direction"] = score_direction(cfg, train, test, geom, d, *split)
        by_dir["ccw" if d > 0 else "cw"] = entry
    return {"fits": fits, "samples": samples, "training_fits": training,
            "n_by_tilt": n_by_tilt, "n_by_direction": n_by_direction,
            "training_fits_by_direction": training_by_direction, "by_dir": by_dir}


def common_mode_share(samples: dict, min_slip: float = 1e-2,
                      min_speed_mps: float = 1e-3) -> float:
    """Share of the rotation samples (both slips >= ``min_slip``, both track speeds >=
    ``min_speed_mps``, as `fit_endo_n` uses) whose true slips break Eq. 8's sign rule
    sgn(α_l/α_r) = -sgn(v_r v_l): both tracks slip the same way relative to their belts, a
    common-mode slip that Endo's relation (a ratio of the two) cannot express."""
    vl, vr = np.asarray(samples["v_l"]), np.asarray(samples["v_r"])
    al, ar = np.asarray(samples["alpha_l"]), np.asarray(samples["alpha_r"])
    with np.errstate(invalid="ignore"):
        usable = (np.isfinite(al) & np.isfinite(ar) & (np.abs(al) >= min_slip)
                  & (np.abs(ar) >= min_slip) & (np.abs(vl) >= min_speed_mps)
                  & (np.abs(vr) >= min_speed_mps))
        broken = usable & (np.sign(al * ar) != -np.sign(vl * vr))
    return float(broken.sum() / max(int(usable.sum()), 1))


def endo_r2(samples: dict, n: float, min_slip: float = 1e-2,
            min_speed_mps: float = 1e-3) -> float:
    """How much of the true slips' log ratio y = log|α_l/α_r| Eq. 8 explains with the fitted
    n, y = n log|v_r/v_l|: R² = 1 - Σ(y - n x)² / Σ(y - ȳ)² over the samples `fit_endo_n`
    uses (both slips and speeds large enough, Eq. 8's sign). 1: the two tracks' slips are a
    power of their speed ratio, as Endo found; near 0: the ratio of the slips does not follow
    the speed ratio, and Endo's odometry infers the wrong slips from the gyro."""
    vl, vr = np.asarray(samples["v_l"]), np.asarray(samples["v_r"])
    al, ar = np.asarray(samples["alpha_l"]), np.asarray(samples["alpha_r"])
    with np.errstate(invalid="ignore", divide="ignore"):
        keep = (np.isfinite(al) & np.isfinite(ar) & (np.abs(al) >= min_slip)
                & (np.abs(ar) >= min_slip) & (np.abs(vl) >= min_speed_mps)
                & (np.abs(vr) >= min_speed_mps) & (np.sign(al * ar) == -np.sign(vl * vr)))
        x = np.log(np.abs(vr[keep] / vl[keep]))
        y = np.log(np.abs(al[keep] / ar[keep]))
    if y.size < 2:
        return float("nan")
    return float(1.0 - np.sum((y - n * x) ** 2) / np.sum((y - y.mean()) ** 2))


def follow_circle(cfg: Settings, sc_kwargs: dict, seed: int, progress: bool) -> tuple:
    """§3.1: gains tuned on flat rigid ground, then the three set-ups on the slope, the two
    limits and each law's oracle gain. Returns (path_following metrics, episodes by set-up,
    limit metrics)."""
    # Gains tuned once on flat rigid ground (§3.1: "determined on a solid floor in advance").
    tuning = {p: circle_episode(cfg, p, False, "gyrodometry", {}, seed, 0.0, "concrete")
              for p in iterate(cfg.poles_rps, progress, "gain search (concrete)")}
    pole = min(tuning, key=lambda p: tuning[p]["rmse_m"])
    circle_seeds = [seed + i for i in range(cfg.circle_seeds)]
    laps: dict[tuple, dict] = {}

    def lap(p: float, ff: bool, est: str, kw: dict, s: int, steer_on: str = "observation"):
        """One lap on the slope; the oracle's grid repeats laps already run at the headline
        pole, which are deterministic in their arguments, so each is run once."""
        key = (p, ff, est, s, steer_on)
        if key not in laps:
            laps[key] = circle_episode(cfg, p, ff, est, kw, s, cfg.circle_tilt_deg,
                                       steer_on=steer_on)
        return laps[key]

    setups = {"feedback": (False, "slip_compensated", sc_kwargs),
              "feedforward": (True, "slip_compensated", sc_kwargs),
              "feedback_gyrodometry": (False, "gyrodometry", {})}
    episodes = {k: [lap(pole, ff, est, kw, s) for s in circle_seeds]
                for k, (ff, est, kw) in iterate(list(setups.items()), progress, "circles")}
    following = {k: mean_episodes(v) for k, v in episodes.items()}
    # What limits the lap: the same two laws with a perfect slip-angle regression (Endo's
    # slip ratios still in the odometry), and with perfect odometry. Steering on the truth, a
    # seed changes nothing (it draws only sensor noise), so one seed is run.
    limit_plan = [(mode, law, s) for mode in ("true_beta", "truth")
                  for law in ("feedback", "feedforward")
                  for s in (circle_seeds if mode == "true_beta" else circle_seeds[:1])]
    limit_laps: dict[tuple[str, str], list[dict]] = {}
    for mode, law, s in iterate(limit_plan, progress, "circle limits"):
        limit_laps.setdefault((mode, law), []).append(lap(
            pole, law == "feedforward", "slip_compensated", sc_kwargs, s, mode))
    # The oracle controller: each law's best triple pole of a wider grid, chosen on the lap's
    # own true error, steering on the truth and on the env's observation (the two set-ups of
    # the laps target). Never used to choose the headline gains.
    oracle_setups = {("truth", "feedback"): (False, "slip_compensated", sc_kwargs, "truth"),
                     ("truth", "feedforward"): (True, "slip_compensated", sc_kwargs, "truth"),
                     ("observation", "feedback_gyrodometry"): (False, "gyrodometry", {},
                                                               "observation"),
                     ("observation", "feedforward_slip_compensated"):
                         (True, "slip_compensated", sc_kwargs, "observation")}
    oracle_plan = [(k, p, s) for k, (*_, on) in oracle_setups.items() for p in cfg.oracle_poles_rps
                   for s in (circle_seeds[:1] if on == "truth" else circle_seeds)]
    oracle_laps: dict[tuple[str, str], dict[float, list[dict]]] = {}
    for k, p, s in iterate(oracle_plan, progress, "circle oracle gains"):
        ff, est, kw, on = oracle_setups[k]
        oracle_laps.setdefault(k, {}).setdefault(p, []).append(lap(p, ff, est, kw, s, on))
    for ref in ("feedback", "feedback_gyrodometry"):
        key = "rmse_improvement" + ("" if ref == "feedback" else "_vs_gyrodometry_feedback")
        following[key] = 1.0 - following["feedforward"]["rmse_m"] / following[ref]["rmse_m"]
    following["pole_rps"] = pole
    # from_poles: k_eta = p^3/v, k_phi = 3 p^2, k_omega = 3 p.
    following["gains"] = {"k_eta": pole**3 / cfg.speed_mps, "k_phi": 3.0 * pole**2,
                          "k_omega": 3.0 * pole}
    following["rigid_ground_rmse_m_by_pole"] = {f"{p:g}": tuning[p]["rmse_m"] for p in tuning}
    limits: dict[str, Any] = {mode: {law: mean_episodes(limit_laps[mode, law])
                                     for law in ("feedback", "feedforward")}
                              for mode in ("true_beta", "truth")}
    for pair in limits.values():
        pair["feedforward_to_feedback_mean"] = (pair["feedforward"]["mean_error_m"]
                                                / pair["feedback"]["mean_error_m"])
    oracle: dict[str, Any] = {"poles_rps": list(cfg.oracle_poles_rps)}
    for (on, law), by_pole in oracle_laps.items():
        oracle.setdefault(on, {})[law] = best_gain(by_pole)
    limits["oracle_gain"] = oracle
    return following, episodes, limits


def run(quick: bool = False, out_dir: str = "runs/reproduce_yamauchi",
        json_path: str | None = None, seed: int = 0, progress: bool = True,
        save_model: str | None = None, settings: Settings | None = None,
        docs_dir: str | None = None) -> dict:
    """Run the experiment; print paper vs simulation; save figures, the fitted model and JSON.

    Parameters
    ----------
    quick : bool
        Fewer repetitions (:data:`~.settings.QUICK`), the same experiments.
    out_dir : str
        Folder for the figures and ``slip_model.json`` (the counter-clockwise fit).
    json_path : str, optional
        Write the result as JSON.
    seed : int
        Seeds the run plan (start headings, sensor noise, train/test split) and the circles.
    progress : bool
        Show progress bars.
    save_model : str, optional
        Also write the counter-clockwise model to this path (a maintainer refreshing
        ``slipenv/data/yamauchi_slip_model.json`` in a source checkout;
        :func:`~.model_file.save_model` refuses an installed package). Only in the env
        preset's world (``vehicle="tracked_patako_wong_chiang", soil="toyoura_sand"``, the
        default), the one the tracked env observes in.
    settings : Settings, optional
        Overrides ``quick``. By default :data:`~.settings.FULL` or :data:`~.settings.QUICK`,
        the env preset's world: the Wong-Chiang track model on ``toyoura_sand``.
    docs_dir : str, optional
        Write the results page ``docs_dir/yamauchi.md`` (figures copied beside it); in
        another world than the env preset's (``settings.vehicle``/``soil``),
        ``docs_dir/yamauchi_<world>.md`` (:func:`~.settings.page_name`).
    """
    cfg = settings or (QUICK if quick else FULL)
    if save_model is not None and not is_env_world(cfg.vehicle, cfg.soil):
        raise ValueError("save_model writes the model the tracked env observes with: run in "
                         f"its world (vehicle={DEFAULT_VEHICLE!r}, soil={DEFAULT_SOIL!r}), "
                         f"not {cfg.vehicle} on {cfg.soil}")
    model_out = None if save_model is None else model_file.model_path(save_model)  # fail early
    t0 = time.perf_counter()
    rng = np.random.default_rng(seed)
    geom = odometry_geometry(tracked_patako())
    out = FsPath(out_dir)
    out.mkdir(parents=True, exist_ok=True)

    runs = collect_runs(cfg, rng, progress)
    train, test = split_runs(runs, cfg, rng)
    ident = identify(cfg, train, test, geom)
    fits, n_by_tilt, by_dir = ident["fits"], ident["n_by_tilt"], ident["by_dir"]
    cross_validated = (cross_validated_ratio(cfg, runs, geom, rng)
                       if set(cfg.directions) == {1, -1} else None)
    fall_line = (fall_line_start(cfg, geom, rng, progress)
                 if cfg.start_heading_deg == 0.0 and max(cfg.tilts_deg) > 0.0 else None)
    main = by_dir["ccw"]
    model, n_circle = main["model"], n_by_tilt[cfg.circle_tilt_deg]
    flags = " ".join(world_options({"vehicle": cfg.vehicle, "soil": cfg.soil}))
    saved = model_file.model_record(model, n_circle, (
        f"slipenv reproduce yamauchi {flags}{' --quick' if quick else ''} --seed {seed}: "
        f"Eq. 9 on counter-clockwise rotation runs, Endo n at {cfg.circle_tilt_deg:g} deg"))
    (out / "slip_model.json").write_text(json.dumps(saved, indent=2))
    if model_out is not None:
        model_file.save_model(saved, model_out)
    following, episodes, circle_limits = follow_circle(
        cfg, {"beta_model": model.to_dict(), "n": n_circle}, seed, progress)

    odo = main["odometry_rmse_m"]
    limits = {
        "odometry_rmse_m": dict(main["limits_rmse_m"]),
        "odometry_ratio_to_gyrodometry": {
            "slip_compensated": odo["slip_compensated"] / odo["gyrodometry"],
            **{k: v / odo["gyrodometry"] for k, v in main["limits_rmse_m"].items()}},
        # the same, each turning direction: which part of the error is Endo's slip ratios
        # (true β), which Eq. 9's slip angle (true slips); both true leaves the gyro's
        "odometry_ratio_to_gyrodometry_by_direction": {
            d: {"slip_compensated": v["odometry_rmse_m"]["slip_compensated"]
                / v["odometry_rmse_m"]["gyrodometry"],
                **{k: x / v["odometry_rmse_m"]["gyrodometry"]
                   for k, x in v["limits_rmse_m"].items()}}
            for d, v in by_dir.items()},
        "path_following": circle_limits,
        "endo_common_mode_share": {f"{t:g}": common_mode_share(ident["samples"][t])
                                   for t in cfg.tilts_deg},
        "endo_r2": {f"{t:g}": endo_r2(ident["samples"][t], fits[t].n) for t in cfg.tilts_deg},
        "fall_line_start": fall_line,
    }
    metrics = {
        "endo_n": {f"{t:g}": f.n for t, f in fits.items()},
        "endo_n_ci95": {f"{t:g}": list(f.ci95) for t, f in fits.items()},
        "endo_n_samples": {f"{t:g}": f.n_samples for t, f in fits.items()},
        "endo_n_by_direction": ident["n_by_direction"],
        "endo_n_training": {f"{t:g}": f.n for t, f in ident["training_fits"].items()},
        "endo_n_training_ci95": {f"{t:g}": list(f.ci95)
                                 for t, f in ident["training_fits"].items()},
        "endo_n_training_samples": {f"{t:g}": f.n_samples
                                    for t, f in ident["training_fits"].items()},
        "endo_n_training_by_direction": {
            k: None if f is None else f.n
            for k, f in ident["training_fits_by_direction"].items()},
        "slip_angle_rmse_deg": math.degrees(main["beta_rmse_rad"]),
        "slip_angle_model": model.to_dict(),
        "odometry_rmse_m": odo,
        "odometry_improvement_vs_gyrodometry": 1.0 - odo["slip_compensated"] / odo["gyrodometry"],
        "clockwise": {"slip_angle_rmse_deg": math.degrees(by_dir["cw"]["beta_rmse_rad"]),
                      "odometry_rmse_m": by_dir["cw"]["odometry_rmse_m"]}
        if "cw" in by_dir else None,
        "held_out_runs": [r.name for r in test],
        "path_following": following,
        "limits": limits,
    }
    # The summary: the paper's comparisons, both turning directions side by side.
    ratios = {d: v["odometry_rmse_m"]["slip_compensated"] / v["odometry_rmse_m"]["gyrodometry"]
              for d, v in by_dir.items()}
    metrics["odometry_rmse_ratio"] = ratios
    metrics["odometry_rmse_ratio_cross_validated"] = cross_validated
    # Endo's n per tilt and turning direction (training runs), Eq. 9 refitted on its
    # regressors: scored beside the pooled n the odometry keeps
    split = {d: v["n_by_direction"] for d, v in by_dir.items() if "n_by_direction" in v}
    metrics["endo_n_by_direction_odometry"] = {
        d: {"odometry_rmse_m": v["odometry_rmse_m"],
            "slip_angle_rmse_deg": math.degrees(v["beta_rmse_rad"]),
            "true_beta_rmse_m": v["true_beta_rmse_m"]} for d, v in split.items()} or None
    metrics["odometry_rmse_ratio_endo_n_by_direction"] = {
        d: v["odometry_rmse_m"]["slip_compensated"] / v["odometry_rmse_m"]["gyrodometry"]
        for d, v in split.items()} or None
    metrics["circle_mean_error_cm"] = {
        "feedback_gyrodometry": 100.0 * following["feedback_gyrodometry"]["mean_error_m"],
        "feedforward_slip_compensated": 100.0 * following["feedforward"]["mean_error_m"]}
    metrics["laps_completed"] = {
        "feedback_gyrodometry": following["feedback_gyrodometry"]["completed"],
        "feedforward_slip_compensated": following["feedforward"]["completed"]}
    metrics["laps_run"] = cfg.circle_seeds
    metrics["calibrated"] = {**CALIBRATED, **WORLD_CALIBRATED.get(world_of(cfg.vehicle,
                                                                          cfg.soil)[0], {})}
    n_paper = ENDO_N
    metrics["targets_met"] = {
        "endo_n_within_0.05_paper_at_each_tilt": all(
            abs(f.n - n_paper[f"{t:g}"]) <= TARGETS["endo_n_tolerance"] for t, f in fits.items()
            if f"{t:g}" in n_paper),
        "slip_compensated_rmse_le_0.4_gyrodometry_both_directions":
            all(r <= TARGETS["odometry_ratio_max"] for r in ratios.values()),
        "feedforward_mean_le_0.5_feedback_gyrodometry":
            following["feedforward"]["mean_error_m"]
            <= TARGETS["feedforward_ratio_max"]
            * following["feedback_gyrodometry"]["mean_error_m"],
        "every_lap_completed_both_laws":
            all(v == cfg.circle_seeds for v in metrics["laps_completed"].values()),
    }
    metrics["run_time_s"] = time.perf_counter() - t0
    result = {"metrics": metrics, "paper": PAPER,
              "settings": {k: getattr(cfg, k) for k in cfg.__dataclass_fields__},
              "quick": quick, "seed": seed}
    figures = save_figures(out, cfg, geom, fits, ident["samples"], main, episodes, n_by_tilt)
    publish(result, format_table(result), figures, json_path, docs_dir, write_results_page,
            notes=[f"model: {model_out}"] if model_out is not None else [])
    return result

