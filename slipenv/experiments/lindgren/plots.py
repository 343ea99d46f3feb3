"""Figures of ``slipenv reproduce lindgren``: the simulated counterparts of Lindgren Fig. 4, 6, 7.

Each function takes what :mod:`.metrics` computed and writes one PNG.
"""

from __future__ import annotations

from pathlib import Path as FsPath

import numpy as np

TITLES = {  # Lindgren Fig. 4 captions; panel (d) is the block's slip model
    "scheme1": "(a) scheme 1: laser + inertial",
    "scheme2": "(b) scheme 2: dead reckoning only",
    "scheme3": "(c) scheme 3: all sensors, slip unmodelled",
}


def _pyplot():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _reference(ax, path) -> None:
    samples = path.sample(0.05)
    ax.plot(samples.x_m, samples.y_m, color="0.6", ls="--", lw=0.8, label="commanded path")


def plot_paths(rec, runs: dict, circ: dict, out_png: str | FsPath,
               slip: str = "scheme4") -> FsPath:
    """Fig. 4: the path of schemes 1-3 and the slip model ``slip`` against the true path, on
    Lindgren's circles."""
    plt = _pyplot()
    fig, axes = plt.subplots(2, 2, figsize=(11, 10))
    titles = {**TITLES, slip: f"(d) {slip}: all sensors, slip model"}
    for ax, (name, title) in zip(axes.ravel(), titles.items(), strict=True):
        _reference(ax, rec.path)
        ax.plot(rec.truth[:, 0], rec.truth[:, 1], color="k", lw=1.6, label="true path")
        ax.plot(runs[name].est[:, 0], runs[name].est[:, 1], color="C3", lw=1.0,
                label=f"{name} estimate")
        dev = circ["deviation_from_scheme1_m"].get(name)
        err = circ["mean_deviation_m"][name]
        note = (f"clockwise arc: true error {err:.3f} m"
                + ("" if dev is None else f", deviation from (a) {dev:.3f} m"))
        ax.set_title(f"{title}\n{note}", fontsize=10)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="upper right", fontsize=7)
    fig.tight_layout()
    return _save(fig, out_png)


def plot_dropout(rec, runs: dict, out_png: str | FsPath, cut_s: float,
                 slip: str = "scheme4") -> FsPath:
    """Fig. 7 for one drive: laser + odometry, laser cut at ``cut_s``; (a) no slip model,
    (b) slip model ``slip``, with the oracle (true R_w and k_s) beside it."""
    plt = _pyplot()
    k_cut = int(np.searchsorted(rec.t_s, cut_s))
    fig, axes = plt.subplots(1, 2, figsize=(13, 6))
    panels = (("(a) slip neglected (scheme 3)", ("scheme3",)),
              (f"(b) slip modelled ({slip}) and oracle", (slip, "oracle")))
    for ax, (title, names) in zip(axes, panels, strict=True):
        _reference(ax, rec.path)
        ax.plot(rec.truth[:, 0], rec.truth[:, 1], color="k", lw=1.6, label="true path")
        for name, color in zip(names, ("C3", "C2"), strict=False):
            est = runs[name].est
            err = float(np.hypot(*(est[-1, :2] - rec.truth[-1, :2])))
            ax.plot(est[:, 0], est[:, 1], color=color, lw=1.1,
                    label=f"{name}: final error {err:.2f} m")
        ax.plot(*rec.truth[k_cut, :2], "bx", ms=12, mew=2, label=f"laser cut ({cut_s:.0f} s)")
        ax.set_title(title, fontsize=10)
        ax.set_aspect("equal", adjustable="datalim")
        ax.set_xlabel("x [m]")
        ax.set_ylabel("y [m]")
        ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    return _save(fig, out_png)


def plot_autocorrelation(rho: dict, out_png: str | FsPath, slip: str = "scheme4") -> FsPath:
    """Fig. 6: ρ̄(l) of the odometric innovations (Eq. 42) with the ±1.96/√K interval, for
    scheme 3 and the slip model ``slip``."""
    plt = _pyplot()
    names = [n for n in ("scheme3", slip) if n in rho]
    fig, axes = plt.subplots(len(names), 1, figsize=(9, 3.2 * len(names)), sharex=True)
    for ax, name, tag in zip(np.atleast_1d(axes), names, "ab", strict=False):
        lags, r, bound = rho[name]
        inside = float(np.mean(np.abs(r) <= bound))
        ax.plot(lags, r, "o-", ms=2.5, lw=0.8, color="C0")
        for b in (-bound, bound):
            ax.axhline(b, color="C3", ls="--", lw=0.8)
        ax.axhline(0.0, color="k", lw=0.5)
        label = "slip unmodelled" if name == "scheme3" else "slip modelled"
        ax.set_title(f"({tag}) {label} ({name}): mean {np.mean(r):.3f}, "
                     f"{100 * inside:.1f} % inside ±{bound:.3f}", fontsize=10)
        ax.set_ylabel("ρ̄(l)")
    np.atleast_1d(axes)[-1].set_xlabel("lag l [odometer updates]")
    fig.tight_layout()
    return _save(fig, out_png)


def _save(fig, out_png: str | FsPath) -> FsPath:
    out = FsPath(out_png)
    out.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(out, dpi=110)
    import matplotlib.pyplot as plt

    plt.close(fig)
    return out
