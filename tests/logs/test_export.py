"""Simulated episodes exported as slipenv-log/1 logs (``slipenv.logs.export``)."""

from __future__ import annotations

import warnings

import gymnasium as gym
import numpy as np
import pytest

import slipenv  # noqa: F401  (registers the envs)
from slipenv.contracts.frame import SensorFrame
from slipenv.logs import LogFormatError, read_log, write_log
from slipenv.logs.export import LogRecorder, export_episode, meta_for
from slipenv.terrain.terrain import TerrainSpec
from slipenv.vehicles.presets import farm_2wd, rover_4ws


@pytest.fixture(scope="module")
def farm_log():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make("slipenv/FarmField-v0", estimator="dead_reckoning", estimator_kwargs={},
                       beacons=None)
    try:
        yield export_episode(env, actions=[[0.5, 0.2]] * 30, seed=3)
    finally:
        env.close()


def test_episode_becomes_a_valid_log(farm_log, tmp_path):
    log = farm_log
    assert len(log) == 31  # the reset sample and 30 steps
    assert log.meta.kind == "diff_drive" and log.wheels == ["left", "right"]
    for col in ("cmd_left", "enc_left", "torque_left", "gyro_z", "acc_x", "roll", "pitch",
                "heading", "gt_x", "gt_y", "gt_yaw"):
        assert log.has(col), col
    assert np.all(np.diff(log.t) > 0)
    enc = log.signals["enc_right"]
    assert np.array_equal(enc, np.round(enc)) and enc[-1] > enc[0]
    assert log.meta.counts_per_rad == 285.0 and log.meta.wheel_radius_m == 0.275
    back = read_log(write_log(log, tmp_path / "farm"))
    for col in log.columns:
        np.testing.assert_array_equal(back.signals[col], log.signals[col])


def test_commands_and_motion_are_consistent(farm_log):
    log = farm_log
    # the commanded wheel speeds (rad/s) are what the encoders then turn at, roughly
    rate = np.diff(log.signals["enc_left"][10:]) / 285.0 / np.diff(log.t[10:])
    assert rate.mean() == pytest.approx(log.signals["cmd_left"][11:].mean(), rel=0.1)
    travelled = np.hypot(*(np.array([log.signals["gt_x"][-1], log.signals["gt_y"][-1]])
                           - [log.signals["gt_x"][0], log.signals["gt_y"][0]]))
    assert travelled > 0.3


def test_policy_and_column_groups():
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make("slipenv/HuskySand-v0")
    try:
        log = export_episode(env, policy=lambda obs: np.array([0.3, 0.0], dtype=np.float32),
                             seed=0, max_steps=10, columns=["imu"])
    finally:
        env.close()
    assert len(log) == 11 and log.meta.kind == "skid_steer"
    assert log.has("gyro_z") and "torque_left" not in log.columns and "roll" not in log.columns
    assert "cmd_left" not in log.columns


def test_meta_declares_the_slope_and_nominal_geometry():
    meta = meta_for(farm_2wd(), TerrainSpec(kind="slope", slope_deg=8.0,
                                            downhill_azimuth_deg=-30.0), soil="field_loam")
    assert meta.slope_deg == 8.0 and meta.slope_downhill_azimuth_deg == -30.0
    assert meta.soil == "field_loam" and meta.track_width_m == 1.6
    flat = meta_for(farm_2wd())
    assert flat.slope_deg == 0.0 and flat.slope_downhill_azimuth_deg is None


def test_rover_logs_carry_steering():
    spec = rover_4ws()
    rec = LogRecorder(meta_for(spec))
    frame = SensorFrame(t_s=0.0, enc_counts=np.zeros(4, dtype=np.int64),
                        wheel_torque_nm=np.zeros(4))
    rec.record(frame, (0.0, 0.0, 0.0), [0.0] * 4, [0.1, 0.1, -0.1, -0.1])
    rec.record(SensorFrame(t_s=0.05, enc_counts=np.ones(4, dtype=np.int64),
                           wheel_torque_nm=np.zeros(4)), None)
    log = rec.to_log()
    assert log.signals["steer_front_left"][0] == pytest.approx(0.1)
    assert np.isnan(log.signals["gt_x"][1])


def test_recorder_errors():
    with pytest.raises(ValueError, match="unknown column group"):
        LogRecorder(meta_for(farm_2wd()), columns=["lidar"])
    with pytest.raises(ValueError, match="nothing recorded"):
        LogRecorder(meta_for(farm_2wd())).to_log()
    rec = LogRecorder(meta_for(farm_2wd()))
    frame = SensorFrame(t_s=0.0, enc_counts=np.zeros(2, dtype=np.int64),
                        wheel_torque_nm=np.zeros(2))
    rec.record(frame, None)
    with pytest.raises(LogFormatError, match="ground-truth"):
        rec.to_log()
    with pytest.raises(ValueError, match="exactly one"):
        export_episode(None)


def test_the_export_recorder_rides_along_any_rollout():
    from slipenv.logs.export import ExportRecorder
    from slipenv.rollout import TrajectoryRecorder, rollout

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        env = gym.make("slipenv/HuskySand-v0")
    export, traj = ExportRecorder(columns=["cmd"], seed=2), TrajectoryRecorder()
    try:
        result = rollout(env, lambda obs: np.array([0.4, -0.2], dtype=np.float32), seed=2,
                         max_steps=12, recorders=[export, traj])
    finally:
        env.close()
    log, path = export.to_log(), traj.trajectory()
    assert result.steps == 12 and len(log) == 13 and len(path) == 12  # + the reset sample
    np.testing.assert_array_equal(log.signals["gt_x"][1:], path.true_pose[:, 0])
    np.testing.assert_array_equal(log.t[1:], path.t_s)
    assert log.meta.data["simulation"]["seed"] == 2
    # the commands are the action through the nominal kinematics: a right turn at 0.4 v_max
    assert np.all(log.signals["cmd_left"][1:] > log.signals["cmd_right"][1:])


def test_an_unknown_column_group_fails_before_the_episode_runs():
    from slipenv.logs.export import ExportRecorder

    with pytest.raises(ValueError, match="unknown column group"):
        ExportRecorder(columns=["lidar"])
