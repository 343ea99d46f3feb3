"""Reina Figs. 7-11 from the virtual test bed: a sweep of slip ratio and slip angle, plotted.

``python -m slipenv.testbed.figures OUTDIR`` runs Reina's sweep (slip 0.05-0.8, slip angle
0-25 deg, W = 6.6 kg, lunar simulant, slipenv's Reina model) and writes ``reina_figs_7_11.png``
with the law's curves over the bed's measurements.
"""

from __future__ import annotations

import math
import pathlib
import sys

import numpy as np

from slipenv.terramechanics.models import ReinaForceModel
from slipenv.terramechanics.presets import LUNAR_SIMULANT
from slipenv.terramechanics.reina import reina_forces
from slipenv.testbed.bed import REINA_WHEEL, Trial, VirtualTestBed

__all__ = ["reina_sweep", "plot_reina_figures"]

SLIPS = (0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8)
ANGLES_DEG = (0.0, 5.0, 10.0, 15.0, 20.0, 25.0)


def reina_sweep(soil=LUNAR_SIMULANT, convention: str = "simulation") -> list[Trial]:
    """The bed sweep over `SLIPS` x `ANGLES_DEG` with slipenv's (net) Reina model."""
    model = ReinaForceModel(REINA_WHEEL.geometry(), rolling_resistance_coeff=0.0)
    with VirtualTestBed(model, soil) as bed:
        return bed.sweep(SLIPS, ANGLES_DEG, convention=convention)


def plot_reina_figures(trials: list[Trial], directory, soil=LUNAR_SIMULANT) -> pathlib.Path:
    """F_x vs slip (Figs. 7, 9), F_y vs slip (Figs. 8, 10), F_y vs slip angle, and the friction
    ellipses (Fig. 11): bed measurements as dots, Reina's law (Eq. 5-9) as lines."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    directory = pathlib.Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    w = float(np.mean([t.normal_load_n for t in trials]))
    k = w / soil.reference_load_n

    def law(s, angle_deg):
        return reina_forces(s, math.tan(math.radians(angle_deg)), w, soil.mu, soil.c_x_n * k,
                            soil.c_y_n * k, soil.a_x, soil.a_y)

    angles = sorted({t.slip_angle_deg for t in trials})
    slips = sorted({t.slip_ratio for t in trials})
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    grid = np.linspace(0.0, max(slips), 80)
    colours = plt.cm.viridis(np.linspace(0, 0.9, len(angles)))
    for a, col in zip(angles, colours, strict=True):
        rows = [t for t in trials if t.slip_angle_deg == a]
        curve = np.array([law(s, a) for s in grid])
        ax[0, 0].plot(grid, curve[:, 0], color=col, label=f"{a:g} deg")
        ax[0, 0].plot([t.slip_ratio for t in rows], [t.fx_n for t in rows], "o", color=col)
        ax[0, 1].plot(grid, -curve[:, 1], color=col)
        ax[0, 1].plot([t.slip_ratio for t in rows], [-t.fy_n for t in rows], "o", color=col)
        ax[1, 1].plot(curve[:, 0], -curve[:, 1], color=col)
        ax[1, 1].plot([t.fx_n for t in rows], [-t.fy_n for t in rows], "o", color=col)
    b_grid = np.linspace(0.0, max(angles), 60)
    for s in slips[::2]:
        rows = [t for t in trials if t.slip_ratio == s]
        curve = np.array([law(s, b) for b in b_grid])
        ax[1, 0].plot(b_grid, -curve[:, 1], color="0.3", lw=0.8)
        ax[1, 0].plot([t.slip_angle_deg for t in rows], [-t.fy_n for t in rows], "o", ms=4,
                      label=f"s = {s:g}")
        ax[1, 1].plot(curve[:, 0], -curve[:, 1], "-.", color="0.5", lw=0.8)
    ax[0, 0].set(xlabel="slip ratio [-]", ylabel="F_x [N]", title="Figs. 7, 9: F_x vs slip")
    ax[0, 1].set(xlabel="slip ratio [-]", ylabel="-F_y [N]", title="Figs. 8, 10: F_y vs slip")
    ax[1, 0].set(xlabel="slip angle [deg]", ylabel="-F_y [N]", title="F_y vs slip angle")
    ax[1, 1].set(xlabel="F_x [N]", ylabel="-F_y [N]",
                 title="Fig. 11: friction ellipses (-. constant slip)")
    ax[0, 0].legend(title="slip angle", fontsize=7)
    ax[1, 0].legend(fontsize=7)
    fig.suptitle(f"Virtual test bed (dots) vs Reina's law (lines), W = {w:.1f} N")
    fig.tight_layout()
    path = directory / "reina_figs_7_11.png"
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


if __name__ == "__main__":  # pragma: no cover - a convenience entry point
    print(plot_reina_figures(reina_sweep(), sys.argv[1] if len(sys.argv) > 1 else "."))
