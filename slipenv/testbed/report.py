"""`slipenv fit-soil`'s analysis: fit every law, rank them held out, describe the misfit.

The misfit of the best law is described from its residuals (measured minus predicted) binned
by slip ratio (F_x) and by slip angle (F_y): a bin is *systematic* when its mean residual is
both beyond 4 standard errors (of the declared noise, else of the within-bin scatter) and
above 2 % of the largest measured force (an absolute floor, so that a nearly noise-free bed
does not flag rounding). The law is called wrong when any bin is systematic, or when its
held-out error is over 3 times the noise the trials' std columns declare. The same test runs
on the cells of a slip ratio x slip angle grid, for F_x and F_y both: a miss confined to one
corner (large slip at a large slip angle) averages away in either one-dimensional binning.

The side-wall law (`slipenv.testbed.fit.SIDEWALL_LAW`) is offered when the data need it: when
a measured side force exceeds the largest side force every fitted standard law makes at its
load by 4 noise standard deviations, or the best law's side force falls systematically short
at the largest slip angles (a cell of the grid).

The soil is *accepted* only when the law is adequate, no fitted parameter sits at a bound (the
optimum lies beyond the range the law allows: the data want a shape it cannot make) and the
simulation has the law. Only an accepted soil is written under ``soil`` (so the documented
one-liner ``Soil(**report["soil"])`` cannot silently build a rejected one); a rejected fit's
fields go under ``rejected_soil``, with ``accepted: false`` and the reasons in ``warnings``.
A parameter the data do not determine is a warning, not a rejection: the soil still
reproduces the trials, it only cannot be trusted outside their range.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import fields
from typing import Any

import numpy as np

from slipenv.diagnose.numbers import estimate
from slipenv.terramechanics.soil import Soil
from slipenv.testbed.csv_format import TestBedData
from slipenv.testbed.fit import (
    AT_BOUND,
    LAWS,
    NOT_DETERMINED,
    PLAUSIBLE_UNIT_WEIGHT,
    SIDEWALL_LAW,
    LawFit,
    at_physical_limit,
    fit_law,
    heldout_rmse,
    predict,
)

__all__ = ["analyse", "describe_misfit", "format_parameter", "needs_sidewall", "plot_fits",
           "soil_to_json"]

_Z, _FLOOR = 4.0, 0.02


def _bins(x: np.ndarray, n_max: int = 8) -> list[np.ndarray]:
    """Index sets of up to `n_max` bins along x: one per distinct value, or quantile bins."""
    values = np.unique(np.round(x, 9))
    if values.size <= n_max:
        return [np.flatnonzero(np.isclose(x, v, atol=1e-9)) for v in values]
    edges = np.quantile(x, np.linspace(0.0, 1.0, n_max + 1))
    idx = np.clip(np.searchsorted(edges, x, side="right") - 1, 0, n_max - 1)
    return [np.flatnonzero(idx == b) for b in range(n_max) if np.any(idx == b)]


def _shape(signs: list[int], centres: list[float], measured: list[float], floor: float,
           quantity: str, axis: str) -> str:
    """Words for the sign pattern of the significant bin means along `axis` (low to high).

    `measured` is a measured curve over the bins (signed along +F_x, -F_y), to tell a peak
    (it falls after a maximum by more than `floor`) from a mere early saturation.
    """
    nz = [s for s in signs if s]
    if not nz:
        return ""
    where = ", ".join(f"{'above' if s > 0 else 'below'} at {axis} {c:.3g}"
                      for s, c in zip(signs, centres, strict=True) if s)
    top = int(np.argmax(measured))
    peak = top < len(measured) - 1 and measured[top] - measured[-1] > floor
    if peak:  # the data peak and the law misses somewhere: it cannot bend like them
        return (f"measured {quantity} peaks at {axis} {centres[top]:.3g} and falls after it: "
                f"a peak the law cannot make (measured {where})")
    if all(s > 0 for s in nz) or all(s < 0 for s in nz):
        side = "above" if nz[0] > 0 else "below"
        return (f"measured {quantity} lies {side} the law over part of the {axis} range "
                f"(an offset or a curvature the law lacks; measured {where})")
    inner, ends = signs[1:-1], (signs[0], signs[-1])
    if any(s < 0 for s in inner) and all(s >= 0 for s in ends):
        return (f"the law bulges above the measured {quantity} at intermediate {axis}: the "
                f"measured curve bends later and more sharply than the law (measured {where})")
    if nz[0] < 0 < nz[-1]:
        return (f"measured {quantity} keeps rising with {axis} where the law levels off "
                f"(measured {where})")
    if nz[0] > 0 > nz[-1]:
        return (f"measured {quantity} saturates sooner with {axis} than the law "
                f"(measured {where})")
    return f"{quantity} residuals change sign along {axis} (measured {where})"


def describe_misfit(fit: LawFit, data: TestBedData) -> dict:
    """Residual bins against slip (F_x) and slip angle (F_y), flags and a sentence each."""
    scale = max(float(np.max(np.abs(data.fx_n))), float(np.max(np.abs(data.fy_n))), 1e-9)
    noise = [float(np.nanmedian(c)) for c in (data.fx_std_n, data.fy_std_n)
             if np.any(np.isfinite(c))]
    out: dict = {"systematic": False, "findings": []}
    for key, res, meas, x, axis in (
            ("fx_vs_slip", fit.residual_fx_n, data.fx_n, data.slip_ratio, "slip"),
            ("fy_vs_slip_angle", fit.residual_fy_n, data.fy_n, np.abs(data.slip_angle_deg),
             "slip angle")):
        bins = _bins(x)
        means = [float(np.mean(res[b])) for b in bins]
        if noise:  # the declared measurement noise, when the std columns give it
            sd = max(noise)
        else:  # else the scatter about the bin means
            pooled = np.concatenate([res[b] - m for b, m in zip(bins, means, strict=True)])
            sd = math.sqrt(float(pooled @ pooled) / max(pooled.size - len(bins), 1))
        signs = []
        for b, m in zip(bins, means, strict=True):
            big = abs(m) > _Z * sd / math.sqrt(b.size) and abs(m) > _FLOOR * scale
            signs.append(int(np.sign(m)) if big else 0)
        quantity = "F_x" if key.startswith("fx") else "|F_y|"
        if key.startswith("fy"):  # F_y < 0 for beta > 0: speak of its magnitude
            signs = [-s if np.mean(data.slip_angle_deg[b]) > 0 else s
                     for s, b in zip(signs, bins, strict=True)]
        centres = [float(np.mean(x[b])) for b in bins]
        # The measured curve along x at one value of the other slip (a peak averages away
        # across slip angles); the one whose fall after its maximum is largest.
        other = np.round(np.abs(data.slip_angle_deg) if key.startswith("fx") else
                         data.slip_ratio, 6)
        sign = 1.0 if key.startswith("fx") else -np.sign(data.slip_angle_deg + 1e-300)
        curve, fall = [0.0] * len(bins), -np.inf
        for g in np.unique(other):
            c = [float(np.mean((sign * meas)[np.intersect1d(b, np.flatnonzero(other == g))]))
                 if np.any(other[b] == g) else np.nan for b in bins]
            if np.all(np.isfinite(c)) and max(c) - c[-1] > fall:
                curve, fall = c, max(c) - c[-1]
        sentence = _shape(signs, centres, curve, _FLOOR * scale, quantity, axis)
        out[key] = {"bin_centres": centres, "mean_residual_n": means,
                    "systematic_bins": [bool(s) for s in signs]}
        if sentence:
            out["systematic"] = True
            out["findings"].append(sentence)
    for key, res, quantity in (("fx_vs_slip_and_angle", fit.residual_fx_n, "F_x"),
                               ("fy_vs_slip_and_angle", fit.residual_fy_n, "|F_y|")):
        grid = _grid_misfit(res, data, noise, scale, quantity)
        out[key] = grid["cells"]
        if grid["finding"]:
            out["systematic"] = True
            out["findings"].append(grid["finding"])
    return out


def _grid_misfit(res: np.ndarray, data: TestBedData, noise: list[float], scale: float,
                 quantity: str, n_max: int = 4) -> dict:
    """The residuals' mean per cell of a slip ratio x |slip angle| grid (up to `n_max` bins
    each way) and a sentence for the cell with the largest systematic miss, if any."""
    angle = np.abs(data.slip_angle_deg)
    cells = [np.intersect1d(a, b) for a in _bins(data.slip_ratio, n_max)
             for b in _bins(angle, n_max)]
    cells = [c for c in cells if c.size]
    means = [float(np.mean(res[c])) for c in cells]
    if noise:
        sd = max(noise)
    else:
        pooled = np.concatenate([res[c] - m for c, m in zip(cells, means, strict=True)])
        sd = math.sqrt(float(pooled @ pooled) / max(pooled.size - len(cells), 1))
    rows, worst, finding = [], None, ""
    for c, m in zip(cells, means, strict=True):
        big = abs(m) > _Z * sd / math.sqrt(c.size) and abs(m) > _FLOOR * scale
        # Residuals are measured - predicted; F_y < 0 for beta > 0, so speak of |F_y|.
        above = m > 0 if quantity == "F_x" else \
            -m * np.sign(np.mean(data.slip_angle_deg[c]) + 1e-300) > 0
        rows.append({"slip": float(np.mean(data.slip_ratio[c])),
                     "slip_angle_deg": float(np.mean(angle[c])), "n": int(c.size),
                     "mean_residual_n": m, "systematic": bool(big),
                     "measured_above_law": bool(above)})
        if big and (worst is None or abs(m) > abs(worst[1])):
            worst = (c, m, above)
    if worst is not None:
        c, m, above = worst
        n_sys = sum(r["systematic"] for r in rows)
        finding = (f"measured {quantity} lies {'above' if above else 'below'} the law by "
                   f"{abs(m):.3g} N at slip {np.mean(data.slip_ratio[c]):.3g} and slip angle "
                   f"{np.mean(angle[c]):.3g} deg (the largest of {n_sys} systematic cells of "
                   "the slip x slip angle grid)")
    return {"cells": rows, "finding": finding}


def format_parameter(value: float, se: float | None, status: str, name: str = "") -> str:
    """``v ± se``, or why there is none: at a bound, or "not determined" (the wording and the
    rule of `slipenv.diagnose.numbers.estimate`: an error larger than the estimate)."""
    if status == AT_BOUND:
        if name and at_physical_limit(name, value):
            return "0 at its physical limit (no standard error)"
        return f"{value:.4g} at a bound of the fit (no standard error)"
    if se is None:
        return "not determined (the trials cannot fix it: no standard error)"
    return estimate(value, se, ".4g")


def _side_force_limit_n(fit: LawFit, data: TestBedData) -> np.ndarray:
    """Per trial, the largest |F_y| the fitted law makes at the trial's load over all slip
    ratios and the slip angles up to the largest measured: its friction limit there."""
    s = np.concatenate((np.linspace(-0.9, 0.0, 10, endpoint=False), np.linspace(0.0, 0.99, 21)))
    top = float(np.max(np.abs(data.slip_angle_deg)))
    if data.meta.get("slip_angle_definition") == "simulation":
        top = min(top, 44.9)  # the definition's range (`convert_slip_state`)
    a = np.linspace(0.0, top, 7)
    ss, aa = (x.ravel() for x in np.meshgrid(s, a))
    n, k = data.n, ss.size
    grid = TestBedData(np.tile(ss, n), np.tile(aa, n), np.repeat(data.normal_load_n, k),
                       *(np.zeros(n * k),) * 2, np.repeat(data.sinkage_m, k),
                       *(np.zeros(n * k),) * 2, meta=data.meta)
    _, fy = predict(fit.law, fit.soil, grid, extras=fit.extras)
    return np.max(np.abs(fy).reshape(n, k), axis=1)


def needs_sidewall(fits: dict[str, LawFit], best: str, misfit: dict, data: TestBedData,
                   noise_n: float | None) -> str:
    """Why the data need a side force beyond friction, or "" (see the module)."""
    sd = noise_n or 0.0
    over = np.ones(data.n, dtype=bool)
    for fit in fits.values():
        over &= np.abs(data.fy_n) > _side_force_limit_n(fit, data) + _Z * sd
    if np.any(over):
        i = int(np.argmax(np.where(over, np.abs(data.fy_n) / data.normal_load_n, -np.inf)))
        return (f"{int(over.sum())} trials' side force exceeds the friction limit of every "
                f"law (up to {abs(data.fy_n[i]) / data.normal_load_n[i]:.2g} W at slip "
                f"{data.slip_ratio[i]:.3g}, slip angle {data.slip_angle_deg[i]:.3g} deg)")
    cells = misfit.get("fy_vs_slip_and_angle", [])
    if cells:
        top = float(np.quantile(np.abs(data.slip_angle_deg), 0.75))
        short = [c for c in cells if c["systematic"] and c["slip_angle_deg"] >= top
                 and c["measured_above_law"]]
        if short and top > 0.0:
            where = ", ".join(f"slip {c['slip']:.3g}, slip angle {c['slip_angle_deg']:.3g} deg"
                              for c in short)
            return (f"{best}'s side force falls short of the measured one at the largest slip "
                    f"angles ({where})")
    return ""


def _law_entry(law: str, fit: LawFit, data: TestBedData, base: Soil, folds: int, seed: int,
               noise_n: float | None) -> dict:
    rmse = heldout_rmse(law, data, base, folds=folds, seed=seed)
    misfit = describe_misfit(fit, data)
    # RMS of F_x and F_y together against the declared per-trial noise.
    ratio = math.hypot(*rmse.values()) / math.sqrt(2.0) / noise_n if noise_n else None
    if ratio is not None and ratio > 3.0:
        misfit["findings"].append(f"held-out error is {ratio:.1f} x the declared "
                                  f"measurement noise ({noise_n:.3g} N)")
    return {"parameters": fit.parameters(), "parameter_status": fit.parameter_status(),
            "heldout_rmse_n": rmse, "heldout_over_noise": ratio, "misfit": misfit}


def analyse(data: TestBedData, base: Soil, folds: int = 5, seed: int = 0,
            laws: tuple[str, ...] = LAWS) -> tuple[dict, dict[str, LawFit]]:
    """Fit each law, rank by held-out RMS error (F_x and F_y together), describe the best's
    misfit, offer the side-wall law when the data need it, accept or reject the soil. Returns
    the JSON-ready report and the fits."""
    noise = [float(np.nanmedian(c)) for c in (data.fx_std_n, data.fy_std_n)
             if np.any(np.isfinite(c))]
    noise_n = max(noise) if noise else None
    fits: dict[str, LawFit] = {}
    report: dict[str, Any] = {"laws": {}}
    for law in laws:
        fits[law] = fit_law(law, data, base)
        report["laws"][law] = _law_entry(law, fits[law], data, base, folds, seed, noise_n)

    def ranked() -> str:
        return min(report["laws"], key=lambda k: math.hypot(*report["laws"][k]
                                                            ["heldout_rmse_n"].values()))

    best = ranked()
    need = "" if SIDEWALL_LAW in fits else needs_sidewall(
        fits, best, report["laws"][best]["misfit"], data, noise_n)
    report["sidewall_offered"] = bool(need)
    if need:
        report["sidewall_reason"] = need
        fits[SIDEWALL_LAW] = fit_law(SIDEWALL_LAW, data, base)
        report["laws"][SIDEWALL_LAW] = _law_entry(SIDEWALL_LAW, fits[SIDEWALL_LAW], data,
                                                  base, folds, seed, noise_n)
        best = ranked()
    entry, fit = report["laws"][best], fits[best]
    ratio, findings = entry["heldout_over_noise"], entry["misfit"]["findings"]
    warnings, reasons = [], []
    if findings:
        reasons.append(f"the verdict rejects {best} for these data")
    status, values = fit.parameter_status(), dict(zip(fit.names, fit.values, strict=True))
    bound = [n for n, st in status.items() if st == AT_BOUND]
    limit = [n for n in bound if at_physical_limit(n, values[n])]
    bound = [n for n in bound if n not in limit]
    if bound:
        reasons.append(f"{', '.join(f'{n} = {values[n]:.4g}' for n in bound)} at a bound of "
                       f"the fit (the data push {best} beyond the range it allows; no "
                       "standard error)")
    if limit:
        warnings.append(f"{', '.join(limit)} at {'its' if len(limit) == 1 else 'their'} "
                        "physical limit 0 (no standard error)")
    vague = [n for n, st in status.items() if st == NOT_DETERMINED]
    if vague:
        warnings.append(f"{', '.join(vague)} not determined by these trials (standard error "
                        "larger than the estimate, or none: the trials cannot fix it); the "
                        "soil reproduces the trials but not beyond their range")
    if best == SIDEWALL_LAW:
        reasons.append("slipenv's simulation has no wheel side-wall force: a soil from "
                       f"{SIDEWALL_LAW} would drop the side force beyond friction")
        gamma = fit.extras["unit_weight_n_m3"]
        low, high = PLAUSIBLE_UNIT_WEIGHT
        if not low <= gamma <= high:
            warnings.append(f"side-wall unit weight {gamma:.3g} N/m^3 is outside the "
                            f"plausible {low:.3g}-{high:.3g}: the sinkage (column sinkage_m) "
                            "is likely missing or too small")
    accepted = not reasons
    warnings = [f"soil not accepted: {r}" for r in reasons] + warnings
    report.update({
        "best": best, "n_trials": data.n, "folds": min(folds, data.n),
        "noise_n": noise_n, "heldout_over_noise": ratio,
        "law_is_adequate": not findings,
        "verdict": (f"{best} fits within the noise: no systematic misfit" if not findings else
                    f"{best} predicts best but the law is wrong for these data: "
                    + "; ".join(findings)),
        "accepted": accepted, "warnings": warnings,
        "slip_angle_definition": data.meta.get("slip_angle_definition", "reina"),
        "force_model": fits[best].law if best != SIDEWALL_LAW else "reina",
    })
    report["soil" if accepted else "rejected_soil"] = soil_to_json(fit.soil)
    return report, fits


def soil_to_json(soil: Soil) -> dict:
    """The soil as a JSON object; ``Soil(**obj)`` rebuilds it."""
    return {f.name: getattr(soil, f.name) for f in fields(soil) if f.init}


def plot_fits(data: TestBedData, fits: dict[str, LawFit], best: str,
              directory: str | pathlib.Path) -> list[pathlib.Path]:
    """Fitted curves over the measurements (F_x vs slip, F_y vs slip, one colour per slip
    angle) and the best law's residuals; PNG files in `directory`."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    angles = np.unique(np.round(np.abs(data.slip_angle_deg), 6))
    if angles.size > 6:
        angles = np.quantile(angles, np.linspace(0, 1, 6))
    s_grid = np.linspace(max(min(data.slip_ratio.min(), 0.0), -1.0), data.slip_ratio.max(), 60)
    w = float(np.median(data.normal_load_n))
    # The side-wall law's curves at the median measured sinkage (NaN: the static one).
    sink = float(np.nanmedian(data.sinkage_m)) if np.any(np.isfinite(data.sinkage_m)) \
        else math.nan
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = plt.cm.viridis(np.linspace(0, 0.9, angles.size))
    styles = {"reina": "-", "janosi": "--", "linear": ":", SIDEWALL_LAW: "-."}
    for a, col in zip(angles, colours, strict=True):
        near = np.isclose(np.abs(data.slip_angle_deg), a, atol=1.0)
        for ax, f in ((axes[0], data.fx_n), (axes[1], data.fy_n)):
            ax.errorbar(data.slip_ratio[near], f[near],
                        yerr=None if np.all(np.isnan(data.fx_std_n)) else
                        (data.fx_std_n if ax is axes[0] else data.fy_std_n)[near],
                        fmt="o", color=col, ms=4, label=f"{a:.0f} deg")
        zero = np.zeros_like(s_grid)
        grid = TestBedData(s_grid, np.full_like(s_grid, a), np.full_like(s_grid, w),
                           fx_n=zero, fy_n=zero, sinkage_m=np.full_like(s_grid, sink),
                           fx_std_n=zero, fy_std_n=zero, meta=data.meta)
        for law, fit in fits.items():
            fx, fy = predict(law, fit.soil, grid, extras=fit.extras)
            lw = 2.0 if law == best else 1.0
            axes[0].plot(s_grid, fx, styles.get(law, "-"), color=col, lw=lw)
            axes[1].plot(s_grid, fy, styles.get(law, "-"), color=col, lw=lw)
    axes[0].set(xlabel="slip ratio [-]", ylabel="F_x [N]",
                title=f"F_x: dots measured, lines fitted (best: {best}, thick)")
    axes[1].set(xlabel="slip ratio [-]", ylabel="F_y [N]",
                title="F_y (-: reina, --: janosi, :: linear, -.: reina + side wall)")
    axes[0].legend(title="slip angle", fontsize=7)
    fig.tight_layout()
    curves = directory / "fitted_curves.png"
    fig.savefig(curves, dpi=110)
    plt.close(fig)
    fig, axes = plt.subplots(1, 2, figsize=(10, 3.6))
    best_fit = fits[best]
    axes[0].plot(data.slip_ratio, best_fit.residual_fx_n, "o", ms=4)
    axes[1].plot(np.abs(data.slip_angle_deg), best_fit.residual_fy_n, "o", ms=4)
    for ax, xl in zip(axes, ("slip ratio [-]", "|slip angle| [deg]"), strict=True):
        ax.axhline(0.0, color="k", lw=0.8)
        ax.set(xlabel=xl, ylabel="measured - fitted [N]")
    axes[0].set_title(f"{best}: F_x residuals")
    axes[1].set_title(f"{best}: F_y residuals")
    fig.tight_layout()
    resid = directory / "residuals.png"
    fig.savefig(resid, dpi=110)
    plt.close(fig)
    return [curves, resid]
