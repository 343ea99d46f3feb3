"""`slipenv fit-soil`'s analysis: fit every law, rank them held out, describe the misfit.

The misfit of the best law is described from its residuals (measured minus predicted) binned
by slip ratio (F_x) and by slip angle (F_y): a bin is *systematic* when its mean residual is
both beyond 4 standard errors (of the declared noise, else of the within-bin scatter) and
above 2 % of the largest measured force (an absolute floor, so that a nearly noise-free bed
does not flag rounding). The law is called wrong when any bin is systematic, or when its
held-out error is over 3 times the noise the trials' std columns declare.
"""

from __future__ import annotations

import math
import pathlib
from dataclasses import fields
from typing import Any

import numpy as np

from slipenv.terramechanics.soil import Soil
from slipenv.testbed.csv_format import TestBedData
from slipenv.testbed.fit import LAWS, LawFit, fit_law, heldout_rmse, predict

__all__ = ["analyse", "describe_misfit", "plot_fits", "soil_to_json"]

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
    return out


def analyse(data: TestBedData, base: Soil, folds: int = 5, seed: int = 0,
            laws: tuple[str, ...] = LAWS) -> tuple[dict, dict[str, LawFit]]:
    """Fit each law, rank by held-out RMS error (F_x and F_y together), describe the best's
    misfit. Returns the JSON-ready report and the fits."""
    noise = [float(np.nanmedian(c)) for c in (data.fx_std_n, data.fy_std_n)
             if np.any(np.isfinite(c))]
    noise_n = max(noise) if noise else None
    fits: dict[str, LawFit] = {}
    report: dict[str, Any] = {"laws": {}}
    for law in laws:
        fit = fit_law(law, data, base)
        fits[law] = fit
        rmse = heldout_rmse(law, data, base, folds=folds, seed=seed)
        misfit = describe_misfit(fit, data)
        # RMS of F_x and F_y together against the declared per-trial noise.
        ratio = math.hypot(*rmse.values()) / math.sqrt(2.0) / noise_n if noise_n else None
        if ratio is not None and ratio > 3.0:
            misfit["findings"].append(f"held-out error is {ratio:.1f} x the declared "
                                      f"measurement noise ({noise_n:.3g} N)")
        report["laws"][law] = {"parameters": fit.parameters(), "heldout_rmse_n": rmse,
                               "heldout_over_noise": ratio, "misfit": misfit}
    best = min(report["laws"], key=lambda k: math.hypot(*report["laws"][k]["heldout_rmse_n"]
                                                         .values()))
    entry = report["laws"][best]
    ratio, findings = entry["heldout_over_noise"], entry["misfit"]["findings"]
    report.update({
        "best": best, "n_trials": data.n, "folds": min(folds, data.n),
        "noise_n": noise_n, "heldout_over_noise": ratio,
        "law_is_adequate": not findings,
        "verdict": (f"{best} fits within the noise: no systematic misfit" if not findings else
                    f"{best} predicts best but the law is wrong for these data: "
                    + "; ".join(findings)),
        "soil": soil_to_json(fits[best].soil), "force_model": best,
    })
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
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2))
    colours = plt.cm.viridis(np.linspace(0, 0.9, angles.size))
    styles = {"reina": "-", "janosi": "--", "linear": ":"}
    for a, col in zip(angles, colours, strict=True):
        near = np.isclose(np.abs(data.slip_angle_deg), a, atol=1.0)
        for ax, f in ((axes[0], data.fx_n), (axes[1], data.fy_n)):
            ax.errorbar(data.slip_ratio[near], f[near],
                        yerr=None if np.all(np.isnan(data.fx_std_n)) else
                        (data.fx_std_n if ax is axes[0] else data.fy_std_n)[near],
                        fmt="o", color=col, ms=4, label=f"{a:.0f} deg")
        zero = np.zeros_like(s_grid)
        grid = TestBedData(s_grid, np.full_like(s_grid, a), np.full_like(s_grid, w),
                           fx_n=zero, fy_n=zero, sinkage_m=zero, fx_std_n=zero,
                           fy_std_n=zero, meta=data.meta)
        for law, fit in fits.items():
            fx, fy = predict(law, fit.soil, grid)
            lw = 2.0 if law == best else 1.0
            axes[0].plot(s_grid, fx, styles.get(law, "-"), color=col, lw=lw)
            axes[1].plot(s_grid, fy, styles.get(law, "-"), color=col, lw=lw)
    axes[0].set(xlabel="slip ratio [-]", ylabel="F_x [N]",
                title=f"F_x: dots measured, lines fitted (best: {best}, thick)")
    axes[1].set(xlabel="slip ratio [-]", ylabel="F_y [N]",
                title="F_y (-: reina, --: janosi, :: linear)")
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
