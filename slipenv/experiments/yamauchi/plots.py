"""Figures of ``slipenv reproduce yamauchi``.

Figure numbers follow Yamauchi et al.: Fig. 4 (Endo's n, log-log), Fig. 5 (slip angle estimate
against truth), Fig. 6 (position estimates against truth), Fig. 8 (circle on the 15° slope).
"""

from __future__ import annotations

from pathlib import Path as FsPath

import numpy as np

from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.skid_steer import EndoOdometry, SlipCompensatedOdometry
from slipenv.paths import circle

from .odometry import replay
from .paper import ENDO_N
from .slips import slip_run


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save_figures(out: FsPath, cfg, geom, fits, samples, main, episodes, n_by_tilt) -> list:
    """Write fig4/5/6/8 PNGs into ``out``; return their paths."""
    plt = _plt()
    paths = []
    # Fig. 4: log|α_l/α_r| against log|v_r/v_l| per tilt, with the fitted and the paper's n.
    fig, ax = plt.subplots(figsize=(5.5, 4.5))
    for i, (tilt, fit) in enumerate(fits.items()):
        s = samples[tilt]
        with np.errstate(divide="ignore", invalid="ignore"):
            x = np.log(np.abs(s["v_r"] / s["v_l"]))
            y = np.log(np.abs(s["alpha_l"] / s["alpha_r"]))
        ok = np.isfinite(x) & np.isfinite(y)
        ax.plot(x[ok][::3], y[ok][::3], ".", ms=2, color=f"C{i}", alpha=0.4)
        xs = np.linspace(0.0, np.nanmax(np.abs(x[ok])), 10)
        ax.plot(xs, fit.n * xs, color=f"C{i}", label=f"{tilt:g}°: n = {fit.n:.3f} "
                f"(paper {ENDO_N[f'{tilt:g}']})")
    ax.set_xlabel("log |v_r / v_l|")
    ax.set_ylabel("log |α_l / α_r|")
    ax.set_title("Fig. 4: Endo's n per tilt")
    ax.legend(fontsize=8)
    paths.append(_save(fig, out / "fig4_endo_n.png", plt))

    # Fig. 5: β̂ against true β along held-out counter-clockwise runs.
    runs = main["test_runs"]
    fig, axes = plt.subplots(1, len(cfg.tilts_deg), figsize=(4.5 * len(cfg.tilts_deg), 3.8),
                             squeeze=False)
    for ax, tilt in zip(axes[0], cfg.tilts_deg, strict=True):
        for j, run in enumerate(r for r in runs if r.tilt_deg == tilt):
            sr = slip_run(run, geom, n_by_tilt[tilt], cfg)
            pred = main["model"].predict(*sr.features.T)
            ax.plot(np.degrees(sr.features[:, 1]), np.degrees(sr.beta), ".", ms=2,
                    color=f"C{j}", alpha=0.5)
            ax.plot(np.degrees(sr.features[:, 1]), np.degrees(pred), "-", color=f"C{j}",
                    lw=1, label=f"{run.rate_dps:g}°/s")
        ax.set_title(f"Fig. 5: tilt {tilt:g}° (held out)")
        ax.set_xlabel("angular displacement [deg]")
        ax.set_ylabel("slip angle [deg] (dots true, line Eq. 9)")
        ax.legend(fontsize=7)
    paths.append(_save(fig, out / "fig5_slip_angle.png", plt))

    # Fig. 6: position estimates of held-out runs at the steepest tilts, fastest turn.
    picks = [r for r in runs if r.tilt_deg in cfg.tilts_deg[-2:]]
    picks = sorted(picks, key=lambda r: (r.tilt_deg, -r.rate_dps))
    chosen = [next(r for r in picks if r.tilt_deg == t) for t in cfg.tilts_deg[-2:]
              if any(r.tilt_deg == t for r in picks)]
    fig, axes = plt.subplots(1, len(chosen), figsize=(5.0 * len(chosen), 4.5), squeeze=False)
    for ax, run in zip(axes[0], chosen, strict=True):
        n = n_by_tilt[run.tilt_deg]
        ax.plot(*run.pose[:, :2].T, "k", lw=2, label="ground truth")
        for est, label in ((Gyrodometry(geom), "gyrodometry"), (EndoOdometry(geom, n), "Endo"),
                           (SlipCompensatedOdometry(geom, n, main["model"]),
                            "slip-compensated")):
            ax.plot(*replay(est, run)[0].T, lw=1.2, label=label)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"Fig. 6: {run.tilt_deg:g}°, {run.rate_dps:g}°/s ({run.name})")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m] (downhill -y)")
        ax.legend(fontsize=7)
    paths.append(_save(fig, out / "fig6_odometry.png", plt))

    # Fig. 8: the circle on the 15° slope, first seed of each controller.
    keys = [k for k in ("feedback_gyrodometry", "feedback", "feedforward") if k in episodes]
    fig, axes = plt.subplots(1, len(keys), figsize=(4.6 * len(keys), 4.6), squeeze=False)
    ref = circle(cfg.circle_radius_m, cfg.speed_mps).sample(0.01)
    for ax, key in zip(axes[0], keys, strict=True):
        ep = episodes[key][0]
        ax.plot(ref.x_m, ref.y_m, "k--", lw=1, label="target")
        ax.plot(*ep["true_xy"].T, "C0", lw=2, label="ground truth")
        ax.plot(*ep["est_xy"].T, "C3", lw=1, label="estimate")
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_title(f"Fig. 8: {key}\nmean error {100 * ep['mean_error_m']:.1f} cm")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m] (downhill -y)")
        ax.legend(fontsize=7)
    paths.append(_save(fig, out / "fig8_circle.png", plt))
    return paths


def _save(fig, path: FsPath, plt) -> FsPath:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path

