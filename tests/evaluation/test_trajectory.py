"""evo-style APE/RPE on planar poses, and the TUM format."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.evaluation.trajectory import (
    ape_translation,
    read_tum,
    rmse,
    rpe_translation,
    to_tum,
    write_tum,
)


def _circle(n: int = 50) -> np.ndarray:
    th = np.linspace(0.0, 1.5 * math.pi, n)
    return np.column_stack([np.cos(th), np.sin(th), th + math.pi / 2])


def test_ape_of_a_constant_world_offset_is_the_offset_and_rpe_is_zero():
    truth = _circle()
    est = truth + np.array([0.3, -0.4, 0.0])
    np.testing.assert_allclose(ape_translation(est, truth), 0.5, atol=1e-12)
    np.testing.assert_allclose(rpe_translation(est, truth, 5), 0.0, atol=1e-12)


def test_rpe_of_a_per_step_forward_drift_is_that_drift_times_delta():
    # Straight line along x at heading 0; the estimate over-counts 1 cm per step.
    n = 40
    truth = np.column_stack([np.arange(n) * 0.1, np.zeros(n), np.zeros(n)])
    est = np.column_stack([np.arange(n) * 0.11, np.zeros(n), np.zeros(n)])
    np.testing.assert_allclose(rpe_translation(est, truth, 4), 0.04, atol=1e-12)
    assert rmse(ape_translation(est, truth)) == pytest.approx(
        math.sqrt(np.mean((np.arange(n) * 0.01) ** 2)), rel=1e-12)


def test_rpe_is_expressed_in_the_truth_frame_not_the_world_frame():
    # Truth heads along +y (yaw 90°); estimate drifts 1 cm/step sideways (world +x): the
    # relative error is the same 1 cm/step whatever the heading (rotation invariance).
    n = 30
    truth = np.column_stack([np.zeros(n), np.arange(n) * 0.1, np.full(n, math.pi / 2)])
    est = truth + np.column_stack([np.arange(n) * 0.01, np.zeros(n), np.zeros(n)])
    np.testing.assert_allclose(rpe_translation(est, truth, 3), 0.03, atol=1e-12)


def test_rpe_is_empty_for_a_trajectory_shorter_than_delta_and_rejects_delta_zero():
    truth = _circle(4)
    assert rpe_translation(truth, truth, 10).size == 0
    with pytest.raises(ValueError, match="delta_steps"):
        rpe_translation(truth, truth, 0)


def test_tum_lines_have_eight_fields_with_a_unit_yaw_quaternion_and_round_trip(tmp_path):
    poses = _circle(20)
    t = np.arange(20) * 0.05
    text = to_tum(t, poses)
    rows = np.array([[float(v) for v in line.split()] for line in text.splitlines()])
    assert rows.shape == (20, 8)
    np.testing.assert_allclose(rows[:, 3:6], 0.0)  # z, qx, qy
    np.testing.assert_allclose(np.hypot(rows[:, 6], rows[:, 7]), 1.0, atol=1e-12)
    path = write_tum(tmp_path / "traj.tum", t, poses)
    t2, poses2 = read_tum(path)
    np.testing.assert_array_equal(t2, t)
    np.testing.assert_array_equal(poses2[:, :2], poses[:, :2])
    wrapped = np.arctan2(np.sin(poses[:, 2]), np.cos(poses[:, 2]))
    np.testing.assert_allclose(poses2[:, 2], wrapped, atol=1e-12)


def test_read_tum_names_the_line_with_a_wrong_field_count(tmp_path):
    bad = tmp_path / "bad.tum"
    bad.write_text("0 0 0 0 0 0 0 1\n1 2 3\n")
    with pytest.raises(ValueError, match="line 2 has 3 fields"):
        read_tum(bad)
