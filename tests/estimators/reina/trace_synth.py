"""Synthetic rover runs for the FTrace tests: a crabbing drive, its wheel traces and frames."""

from __future__ import annotations

import math

import numpy as np

from slipenv.sensors.trace_camera import TraceCamera, TraceCameraConfig, TraceFrame
from slipenv.sensors.trace_history import history_from_poses

WHEELS = {"front_left": (0.30, 0.25), "rear_left": (-0.30, 0.25)}


def crab_drive(n_frames: int, rng: np.random.Generator, speed_mps: float = 0.08,
               rate_hz: float = 5.0, beta_max_deg: float = 15.0, substeps: int = 4,
               start_m: float = 0.0) -> tuple[np.ndarray, int]:
    """Poses (x, y, yaw) every 1/(rate·substeps) s of a drive whose slip angle drifts slowly.

    β follows a smooth random walk within ±``beta_max_deg``; the heading sways by ±1.5°.
    The drive starts ``start_m`` behind the first frame's pose so its trace can already exist;
    returns the poses and the index of the first frame's pose.
    """
    dt = 1.0 / (rate_hz * substeps)
    n_pre = int(round(start_m / (speed_mps * dt)))
    n = n_pre + n_frames * substeps
    knots = rng.uniform(-beta_max_deg, beta_max_deg, n // 800 + 2)  # a new trend every 40 s
    beta = np.radians(np.interp(np.arange(n), np.linspace(0, n, len(knots)), knots))
    yaw = np.radians(1.5) * np.sin(np.arange(n) * dt * 2 * np.pi / rng.uniform(20, 40))
    heading = yaw + beta
    x = np.concatenate([[0.0], np.cumsum(speed_mps * dt * np.cos(heading[:-1]))])
    y = np.concatenate([[0.0], np.cumsum(speed_mps * dt * np.sin(heading[:-1]))])
    return np.column_stack([x, y, yaw])[: n], n_pre


def frames(n_frames: int, seed: int, config: TraceCameraConfig | None = None,
           start_m: float = 1.0, **drive) -> list[TraceFrame]:
    """``n_frames`` rendered frames of one seeded drive (camera with calibration error)."""
    rng = np.random.default_rng(seed)
    substeps = drive.pop("substeps", 4)
    poses, n_pre = crab_drive(n_frames, rng, substeps=substeps, start_m=start_m, **drive)
    camera = TraceCamera(config or TraceCameraConfig(), calibration_rng=rng)
    out = []
    for k in range(n_frames):
        i = n_pre + k * substeps
        hist = history_from_poses(poses[: i + 1], WHEELS, 0.08, rng.uniform(0.006, 0.015)) \
            if i >= 1 else ()
        roll, pitch = rng.normal(0.0, math.radians(1.0), 2)
        pose = [poses[i, 0], poses[i, 1], 0.0, roll, pitch, poses[i, 2]]
        out.append(camera.measure(hist, pose, rng, t_s=k / 5.0))
    return out


def bending_crab_frame(beta_far_deg: float, beta_near_deg: float, turn_m: float, seed: int,
                       sinkage_m: float = 0.01) -> TraceFrame:
    """One frame behind a rover that crabs at a constant heading while its course bends.

    The body keeps yaw 0 and drives 2.5 m on a course at ``beta_far_deg`` that turns steadily
    to ``beta_near_deg`` over the last ``turn_m``. The front-left wheel's rut is the older
    course, so it runs beside the rear-left rut within a few centimetres (the rear wheel rolls
    last and overwrites it where they overlap) while the rear rut bends in the view. No
    nuisances and an exactly mounted camera, so what is measured is the two ruts' geometry.
    """
    s = np.linspace(0.0, 2.5, 501)
    course = np.radians(np.interp(s, [0.0, 2.5 - turn_m, 2.5],
                                  [beta_far_deg, beta_far_deg, beta_near_deg]))
    step = np.diff(s, prepend=0.0)
    poses = np.column_stack([np.cumsum(step * np.cos(course)), np.cumsum(step * np.sin(course)),
                             np.zeros_like(s)])
    tracks = history_from_poses(poses, WHEELS, 0.08, sinkage_m)
    config = TraceCameraConfig(p_old_trace=0.0, p_shadow=0.0, p_patch=0.0,
                               calibration_error_deg=0.0)
    rng = np.random.default_rng(seed)
    camera = TraceCamera(config)
    return camera.measure(tracks, [poses[-1, 0], poses[-1, 1], 0.0, 0.0, 0.0, 0.0], rng)
