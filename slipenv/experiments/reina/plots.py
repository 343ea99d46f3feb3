"""Figures of ``slipenv reproduce reina``; numbers follow Reina et al.: Figs. 15 and 17 (slip
angle, FTrace against ground truth), 18 and 20 (slip ratio, s_x(β̂) against ground truth), 19
and 21 (paths: truth, plain, compass-enhanced, sComp odometry), and Fig. 13's counterpart (camera
frames with FTrace's trace)."""

from __future__ import annotations

from pathlib import Path as FsPath

import numpy as np

from slipenv.estimators.reina import SlipRatioFit

FIGS = {"sideways": ("fig15_slip_angle_sideways", "fig18_slip_ratio_sideways",
                     "fig19_paths_sideways"),
        "mounds": ("fig17_slip_angle_mounds", "fig20_slip_ratio_mounds", "fig21_paths_mounds")}


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def _frames_figure(out: FsPath, drives: dict) -> FsPath:
    """Fig. 13 counterpart: a few camera frames with FTrace's trace (green) and the truth."""
    import cv2

    plt = _plt()
    picks = [(t, img) for t in drives for img in drives[t][0].images[1:4]][:6]
    fig, axes = plt.subplots(2, 3, figsize=(12, 6.5))
    for ax in axes.ravel():
        ax.axis("off")
    for ax, (test, (step, image, det, true_angle)) in zip(axes.ravel(), picks, strict=False):
        rgb = cv2.cvtColor(image, cv2.COLOR_GRAY2RGB)
        title = f"{test}, t = {step * drives[test][0].dt_s:.0f} s"
        if det is not None and det.found:
            from slipenv.envs.render import trace_line_px
            from slipenv.sensors.trace_camera import TraceCameraConfig

            cam_cfg = TraceCameraConfig()
            uv = trace_line_px(cam_cfg.nominal_camera(), det.angle_rad, det.offset_m,
                               cam_cfg.wheel_xy_m, cam_cfg.ground_z_m)
            a, b = (tuple(int(round(v)) for v in pt) for pt in uv)
            cv2.line(rgb, a, b, (40, 220, 40), 2, cv2.LINE_AA)
            title += (f"\nFTrace {np.degrees(det.angle_rad):+.1f}°, truth "
                      f"{np.degrees(true_angle):+.1f}° ({det.status})")
        else:
            title += "\nno trace reported"
        ax.imshow(rgb)
        ax.set_title(title, fontsize=9)
    fig.tight_layout()
    path = out / "fig13_camera_frames.png"
    fig.savefig(path, dpi=90)
    plt.close(fig)
    return path


def _finish(fig, ax, xlabel: str, ylabel: str, title: str, path: FsPath) -> FsPath:
    """Label, save and close one figure; its path."""
    ax.set_xlabel(xlabel)
    ax.set_ylabel(ylabel)
    ax.legend(loc="best", fontsize=8)
    ax.set_title(title)
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    _plt().close(fig)
    return path


def save_figures(out: FsPath, drives: dict, truths: dict, odometries: dict,
                 fit: SlipRatioFit) -> list[FsPath]:
    """Draw every figure of the first drive of each test into ``out``; return the paths."""
    plt = _plt()
    paths = []
    for test, (f_beta, f_slip, f_path) in FIGS.items():
        d, truth, odo = drives[test][0], truths[test][0], odometries[test][0]
        t = np.asarray(d.t_s)
        steps = np.asarray(d.frame_step, int)
        found = np.array([det.found for det in d.detections], bool)
        fig, ax = plt.subplots(figsize=(7, 3.5))
        ax.plot(t, np.degrees(truth["beta"]), "k-", lw=1.2, label="ground truth (1 s window)")
        ax.plot(t[steps][found], np.degrees(np.asarray(d.beta_used)[steps][found]), ".",
                ms=3, color="tab:green", label="FTrace")
        paths.append(_finish(fig, ax, "time [s]", "slip angle [deg]", f"{test}: slip angle",
                             out / f"{f_beta}.png"))

        fig, ax = plt.subplots(figsize=(7, 3.5))
        ax.plot(t, truth["s_x"], "k-", lw=1.2, label="ground truth (1 s window)")
        ax.plot(t, odo["scomp_slip_ratio"], "-", color="tab:orange", lw=1.0,
                label=f"s_x(β̂, θ), Eq. 12 + pitch (s_x0 {fit.model.s_x0:.3f}, "
                      f"k {fit.model.k_per_rad:.2f}, k_θ {fit.model.k_pitch:.2f})")
        paths.append(_finish(fig, ax, "time [s]", "slip ratio [-]", f"{test}: slip ratio",
                             out / f"{f_slip}.png"))

        fig, ax = plt.subplots(figsize=(7, 4))
        xy = d.arrays()["true_xy"]
        ax.plot(xy[:, 0], xy[:, 1], "k-", lw=1.6, label="ground truth")
        for key, style, label in (("plain", "k--", "plain odometry"),
                                  ("compass", "--", "compass-enhanced"),
                                  ("scomp", "-", "sComp")):
            ax.plot(odo[key][:, 0], odo[key][:, 1], style, lw=1.1, label=label)
        ax.set_aspect("equal", adjustable="datalim")
        paths.append(_finish(fig, ax, "x [m]", "y [m]", f"{test}: paths",
                             out / f"{f_path}.png"))
    paths.append(_frames_figure(out, drives))
    return paths
