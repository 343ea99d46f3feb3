"""Trajectory errors in evo's conventions, and export in the TUM format evo reads.

Poses are planar ``(x, y, yaw)`` in the world frame. Estimate and truth share that frame
(the estimator starts from the true initial pose), so APE is computed **without alignment**
(``evo_ape tum truth.tum est.tum`` without ``--align``).

APE (absolute pose error, translation part; evo ``APE`` with ``PoseRelation.translation_part``)
    e_i = ‖t(P_i) − t(Q_i)‖, reported as RMSE, mean and max [m].
RPE (relative pose error, translation part; evo ``RPE`` with ``delta`` in frames)
    E_i = (Q_i⁻¹ Q_{i+Δ})⁻¹ (P_i⁻¹ P_{i+Δ}),  e_i = ‖t(E_i)‖,
    with P the estimate, Q the truth, Δ a number of steps (``delta_steps``); reported as RMSE
    [m per Δ steps]. In SE(2) this equals evo's SE(3) value for poses with z = 0.

TUM format: one line per pose, ``t x y z qx qy qz qw`` (time [s], position [m], unit
quaternion), space separated; here z = 0 and the quaternion is the yaw rotation about z.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np


def _check_poses(name: str, poses: np.ndarray) -> np.ndarray:
    poses = np.asarray(poses, dtype=float)
    if poses.ndim != 2 or poses.shape[1] != 3:
        raise ValueError(f"{name} must have shape (n, 3) = (x, y, yaw), got {poses.shape}")
    return poses


def ape_translation(estimate: np.ndarray, truth: np.ndarray) -> np.ndarray:
    """Per-pose translation error ‖t(P_i) − t(Q_i)‖ [m], no alignment.

    Parameters
    ----------
    estimate, truth : np.ndarray, shape (n, 3)
        Poses ``(x [m], y [m], yaw [rad])`` at the same time stamps.
    """
    estimate, truth = _check_poses("estimate", estimate), _check_poses("truth", truth)
    if estimate.shape != truth.shape:
        raise ValueError(f"estimate {estimate.shape} and truth {truth.shape} differ in length")
    return np.hypot(estimate[:, 0] - truth[:, 0], estimate[:, 1] - truth[:, 1])


def _relative(poses: np.ndarray, delta: int) -> tuple[np.ndarray, np.ndarray]:
    """Translation (n-Δ, 2) and rotation (n-Δ,) of P_i⁻¹ P_{i+Δ} in SE(2)."""
    d = poses[delta:, :2] - poses[:-delta, :2]
    c, s = np.cos(poses[:-delta, 2]), np.sin(poses[:-delta, 2])
    local = np.stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]], axis=1)
    return local, poses[delta:, 2] - poses[:-delta, 2]


def rpe_translation(estimate: np.ndarray, truth: np.ndarray, delta_steps: int) -> np.ndarray:
    """Per-pair translation part of E_i = (Q_i⁻¹ Q_{i+Δ})⁻¹ (P_i⁻¹ P_{i+Δ}) [m].

    Returns an empty array when the trajectory is shorter than ``delta_steps + 1`` poses.
    """
    estimate, truth = _check_poses("estimate", estimate), _check_poses("truth", truth)
    if delta_steps < 1:
        raise ValueError(f"delta_steps must be >= 1, got {delta_steps}")
    if estimate.shape != truth.shape:
        raise ValueError(f"estimate {estimate.shape} and truth {truth.shape} differ in length")
    if len(truth) <= delta_steps:
        return np.zeros(0)
    t_p, _ = _relative(estimate, delta_steps)
    t_q, r_q = _relative(truth, delta_steps)
    # (Q_rel)⁻¹ P_rel: translation R(-θ_q) (t_p − t_q).
    d = t_p - t_q
    c, s = np.cos(r_q), np.sin(r_q)
    return np.hypot(c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1])


def rmse(values: np.ndarray) -> float:
    """Root mean square, NaN for an empty array."""
    values = np.asarray(values, dtype=float)
    return float(np.sqrt(np.mean(values**2))) if values.size else float("nan")


def to_tum(t_s: np.ndarray, poses: np.ndarray) -> str:
    """Planar poses as TUM lines ``t x y z qx qy qz qw`` (z = 0, yaw-only quaternion)."""
    poses = _check_poses("poses", poses)
    t_s = np.asarray(t_s, dtype=float)
    if t_s.shape != (len(poses),):
        raise ValueError(f"t_s must have shape ({len(poses)},), got {t_s.shape}")
    half = 0.5 * poses[:, 2]
    rows = np.column_stack([t_s, poses[:, 0], poses[:, 1], np.zeros(len(poses)),
                            np.zeros(len(poses)), np.zeros(len(poses)), np.sin(half),
                            np.cos(half)])
    # repr-exact floats so a re-read trajectory scores identically.
    return "".join(" ".join(repr(float(v)) for v in row) + "\n" for row in rows)


def write_tum(path: str | Path, t_s: np.ndarray, poses: np.ndarray) -> Path:
    """Write a TUM trajectory file; returns its path."""
    out = Path(path)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(to_tum(t_s, poses))
    return out


def read_tum(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """Read a TUM file written by :func:`write_tum`: ``(t_s (n,), poses (n, 3))``.

    Raises
    ------
    ValueError
        If a line does not have 8 numbers (the message names the file and line).
    """
    rows = []
    for k, line in enumerate(Path(path).read_text().splitlines(), start=1):
        if not line.strip() or line.startswith("#"):
            continue
        parts = line.split()
        if len(parts) != 8:
            raise ValueError(f"{path}: line {k} has {len(parts)} fields, TUM needs 8")
        rows.append([float(v) for v in parts])
    data = np.array(rows, dtype=float).reshape(-1, 8)
    yaw = 2.0 * np.arctan2(data[:, 6], data[:, 7])
    yaw = np.arctan2(np.sin(yaw), np.cos(yaw))
    return data[:, 0], np.column_stack([data[:, 1], data[:, 2], yaw])
