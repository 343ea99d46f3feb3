"""Matplotlib figures of the human diagnosis report (Agg backend, one PNG each)."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from slipenv.diagnose import replay  # noqa: E402
from slipenv.diagnose.fit import Fit, Problem  # noqa: E402
from slipenv.diagnose.numbers import num  # noqa: E402
from slipenv.diagnose.select import Selection  # noqa: E402
from slipenv.logs.log import Log  # noqa: E402

_MAX_SEGMENTS = 40  # segments drawn in the overlay (the first ones of the first log)


def _save(fig, path: Path) -> Path:
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def overlay(path: Path, sel: Selection, problem: Problem) -> Path:
    """Logged path with the nominal and extended (held-out) replay of each segment."""
    seg = problem.seg
    show = np.flatnonzero(seg.log_index == seg.log_index[0])[:_MAX_SEGMENTS]
    ext = sel.final.get("pose")
    fig, ax = plt.subplots(figsize=(7, 6))
    for k, j in enumerate(show):
        ok = seg.gt_ok[j]
        ax.plot(seg.gt[j, ok, 0], seg.gt[j, ok, 1], "k-", lw=2.0, alpha=0.35,
                label="logged (ground truth)" if k == 0 else None)
        nom = sel.baseline["pose"].pred[j]
        n = ok.nonzero()[0][-1] + 1
        ax.plot(nom[:n, 0], nom[:n, 1], "-", color="tab:red", lw=1,
                label="nominal replay" if k == 0 else None)
        if ext is not None:
            ax.plot(ext.pred[j, :n, 0], ext.pred[j, :n, 1], "-", color="tab:green", lw=1,
                    label=f"extended replay ({ext.name})" if k == 0 else None)
        ax.plot(*seg.gt[j, 0, :2], "k.", ms=3)
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title("each segment replayed from the logged pose at its start (dots)")
    ax.legend(loc="best", fontsize=8)
    return _save(fig, path)


def residuals_time(path: Path, sel: Selection, problem: Problem) -> Path:
    """Held-out position and heading errors over time, nominal and extended."""
    seg = problem.seg
    fig, axes = plt.subplots(2, 1, figsize=(9, 5), sharex=True)
    models = [("nominal", sel.baseline["pose"], "tab:red")]
    if "pose" in sel.final:
        models.append((f"extended ({sel.final['pose'].name})", sel.final["pose"], "tab:green"))
    first = seg.log_index == seg.log_index[0]
    for name, cand, color in models:
        res = replay.pose_residuals(seg, cand.pred)
        for k, j in enumerate(np.flatnonzero(first)):
            ok = seg.gt_ok[j]
            t = seg.t[j, ok]
            axes[0].plot(t, np.hypot(res[j, ok, 0], res[j, ok, 1]), color=color, lw=0.8,
                         label=name if k == 0 else None)
            axes[1].plot(t, np.degrees(res[j, ok, 2]), color=color, lw=0.8)
    axes[0].set_ylabel("position error [m]")
    axes[1].set_ylabel("heading error [°]")
    axes[1].set_xlabel("t [s] (first log)")
    axes[0].legend(fontsize=8)
    axes[0].set_title("held-out replay errors; each segment restarts from the logged pose")
    return _save(fig, path)


def regressors(path: Path, win: dict[str, np.ndarray]) -> Path:
    """Nominal residual rates against the candidate regressors."""
    pairs = [("torque", "slip", "wheel torque [N m]", "apparent slip [-]"),
             ("speed", "slip", "speed [m/s]", "apparent slip [-]"),
             ("pitch", "slip", "pitch [rad] (> 0 nose down)", "apparent slip [-]"),
             ("yaw_rate", "yaw_rate_residual", "nominal yaw rate [rad/s]",
              "yaw-rate residual [rad/s]"),
             ("speed", "yaw_rate_residual", "speed [m/s]", "yaw-rate residual [rad/s]"),
             ("roll", "slip_angle", "roll [rad]", "apparent slip angle [rad]"),
             ("yaw_rate", "slip_angle", "nominal yaw rate [rad/s]", "apparent slip angle [rad]")]
    fig, axes = plt.subplots(2, 4, figsize=(16, 7))
    for ax, (x, y, xl, yl) in zip(axes.flat, pairs, strict=False):
        ok = np.isfinite(win[x]) & np.isfinite(win[y])
        if ok.any():
            ax.plot(win[x][ok], win[y][ok], ".", ms=2, alpha=0.5)
        else:
            ax.text(0.5, 0.5, "not logged", ha="center", transform=ax.transAxes)
        ax.set_xlabel(xl)
        ax.set_ylabel(yl)
    ax = axes.flat[7]
    if len(win["x"]):
        lim = np.nanpercentile(np.abs(win["slip"]), 95) or 1.0
        sc = ax.scatter(win["x"], win["y"], c=np.clip(win["slip"], -lim, lim), s=3,
                        cmap="coolwarm", vmin=-lim, vmax=lim)
        fig.colorbar(sc, ax=ax, label="apparent slip [-]")
        ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    fig.suptitle("nominal-model residuals per 0.5 s window (a cause shows as a trend)")
    return _save(fig, path)


def candidates(path: Path, sel: Selection) -> Path:
    """Held-out error of each testable effect relative to the nominal model."""
    rows = [c for c in sel.candidates if not c.untestable]
    fig, ax = plt.subplots(figsize=(7, 0.45 * len(rows) + 1.2))
    y = np.arange(len(rows))
    colors = ["tab:green" if c.significant else "tab:gray" for c in rows]
    ax.barh(y, [c.error_ratio for c in rows], color=colors)
    ax.axvline(1.0, color="k", lw=0.8)
    ax.set_yticks(y, [f"{c.name} (p={num(c.p_value, '.1g')})" for c in rows], fontsize=8)
    ax.invert_yaxis()
    ax.set_xlabel("held-out mean squared error / nominal (green: significant)")
    return _save(fig, path)


def pybullet(path: Path, sim: dict) -> Path:
    """PyBullet replay of the first segments: logged vs nominal and extended worlds."""
    fig, ax = plt.subplots(figsize=(7, 6))
    for k, (gt, nom, ext) in enumerate(zip(sim["logged"], sim["nominal"], sim["extended"],
                                           strict=True)):
        ax.plot(gt[:, 0], gt[:, 1], "k-", lw=2, alpha=0.35, label="logged" if k == 0 else None)
        ax.plot(nom[:, 0], nom[:, 1], "-", color="tab:red", lw=1,
                label="PyBullet, nominal world" if k == 0 else None)
        ax.plot(ext[:, 0], ext[:, 1], "-", color="tab:green", lw=1,
                label="PyBullet, extended world" if k == 0 else None)
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=8)
    ax.set_title("PyBullet driven by the logged wheel motion, per segment")
    return _save(fig, path)


def dead_reckoning(path: Path, logs: list[Log], fitted: Fit) -> Path | None:
    """Each log (up to 6) dead-reckoned whole from its first logged pose: logged path, nominal
    model, and the fitted model ``fitted`` (in-sample: fitted on all logs). None (no figure)
    when none of those logs holds enough ground truth to draw."""
    from slipenv.diagnose.segments import cut_spans, log_arrays

    shown = logs[:6]
    arrays = [log_arrays(log) for log in shown]
    spans = []
    for li, arr in enumerate(arrays):
        ok = np.flatnonzero(arr["gt_ok"])
        spans.append((li, int(ok[0]), int(ok[-1]) + 1))
    seg = cut_spans(arrays, shown, spans)
    if seg is None:
        return None
    fig, axes = plt.subplots(1, 2, figsize=(13, 5.5))
    nominal, extended = replay.simulate(seg, {}), replay.simulate(seg, fitted.params)
    for j in range(len(seg)):
        ok = seg.gt_ok[j]
        n = np.flatnonzero(ok)[-1] + 1
        first = j == 0
        axes[0].plot(seg.gt[j, ok, 0], seg.gt[j, ok, 1], "k-", lw=2, alpha=0.35,
                     label="logged (ground truth)" if first else None)
        axes[0].plot(nominal[j, :n, 0], nominal[j, :n, 1], "-", color="tab:red", lw=1,
                     label="nominal dead reckoning" if first else None)
        axes[0].plot(extended[j, :n, 0], extended[j, :n, 1], "-", color="tab:green", lw=1,
                     label=f"calibrated ({'+'.join(fitted.effects)})" if first else None)
        t = seg.t[j, ok] - seg.t[j, 0]
        for pred, color in ((nominal, "tab:red"), (extended, "tab:green")):
            err = replay.heading_residuals(seg, pred[..., 2])[j, ok]
            axes[1].plot(t, np.degrees(err), color=color, lw=1)
    axes[0].set_aspect("equal", adjustable="datalim")
    axes[0].set_xlabel("x [m]")
    axes[0].set_ylabel("y [m]")
    axes[0].legend(fontsize=8)
    axes[0].set_title("whole log from its first logged pose")
    axes[1].set_xlabel("t [s]")
    axes[1].set_ylabel("heading error [°] (red nominal, green calibrated)")
    axes[1].axhline(0.0, color="k", lw=0.5)
    return _save(fig, path)


def soil(path: Path, problem: Problem, fitted) -> Path:
    """Where the fitted model softens the ground: the logged route coloured by the torque
    compliance c = s / T [1/(N m)] the model ``fitted`` (a ``fit.Fit``) gives each interval,
    mean over the wheels (Lindgren Eq. 24)."""
    seg = problem.seg
    slip = replay.slips(seg, fitted.params)
    torque = seg.torque if seg.torque is not None else np.zeros_like(slip)
    ok = np.abs(torque) > 1e-9
    c = np.divide(slip, torque, out=np.zeros_like(slip), where=ok).sum(axis=-1) / \
        np.maximum(ok.sum(axis=-1), 1)
    moving = ok.any(axis=-1)
    fig, ax = plt.subplots(figsize=(7, 6))
    dots = ax.scatter(seg.pos[..., 0][moving], seg.pos[..., 1][moving], c=c[moving], s=4,
                      cmap="viridis")
    fig.colorbar(dots, ax=ax, label="fitted torque compliance c = s/T [1/(N m)]")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"where {'+'.join(fitted.effects)} softens the ground along the route")
    return _save(fig, path)
