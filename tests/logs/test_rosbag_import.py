"""ROS 1 and ROS 2 bags written here with known motion import into logs with the same values."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from rosbags.rosbag1 import Writer as Writer1
from rosbags.rosbag2 import StoragePlugin
from rosbags.rosbag2 import Writer as Writer2
from rosbags.typesys import Stores, get_typestore

from slipenv.logs import LogMeta, read_log, write_log
from slipenv.logs.rosbag import BagImportError, TopicMapping, import_rosbag

ORIGIN_NS = 1_700_000_000 * 10**9  # absolute time of the first joint state
CPR = 100.0  # [counts/rad]
ROLL, PITCH = 0.05, -0.02  # [rad] constant attitude in the IMU orientation
GT_GAP = (1.0, 1.6)  # [s] no ground-truth messages in this window (longer than max_gap_s)


def theta(t):  # wheel angles [rad] (left, right)
    return 2.1 * t, 3.3 * t + 0.5


def gt_pose(t):  # x [m], y [m], yaw [rad]: yaw crosses +pi at t = 0.5 s
    return 0.5 * t, 0.1 * t, math.pi - 0.2 + 0.4 * t


def quaternion(roll, pitch, yaw):
    cr, sr = math.cos(roll / 2), math.sin(roll / 2)
    cp, sp = math.cos(pitch / 2), math.sin(pitch / 2)
    cy, sy = math.cos(yaw / 2), math.sin(yaw / 2)
    return (sr * cp * cy - cr * sp * sy, cr * sp * cy + sr * cp * sy,
            cr * cp * sy - sr * sp * cy, cr * cp * cy + sr * sp * sy)


class BagBuilder:
    """Builds messages for one typestore (ROS 1 headers carry a ``seq``)."""

    def __init__(self, store: Stores) -> None:
        self.ts = get_typestore(store)
        self.ros1 = store == Stores.ROS1_NOETIC
        self.T = self.ts.types

    def header(self, t: float, frame: str = "base_link"):
        ns = ORIGIN_NS + round(t * 1e9)
        stamp = self.T["builtin_interfaces/msg/Time"](sec=ns // 10**9, nanosec=ns % 10**9)
        extra = {"seq": 0} if self.ros1 else {}
        return self.T["std_msgs/msg/Header"](stamp=stamp, frame_id=frame, **extra)

    def pose(self, t: float):
        x, y, yaw = gt_pose(t)
        qx, qy, qz, qw = quaternion(0.0, 0.0, yaw)
        T = self.T
        return T["geometry_msgs/msg/Pose"](
            position=T["geometry_msgs/msg/Point"](x=x, y=y, z=0.0),
            orientation=T["geometry_msgs/msg/Quaternion"](x=qx, y=qy, z=qz, w=qw))

    def messages(self, gt_type: str, cmd_type: str):
        """Yield (topic, msgtype, time [s], message) for 2 s of motion."""
        T, z36, z9 = self.T, np.zeros(36), np.zeros(9)
        for k in range(101):  # joint states at 50 Hz, extra caster joint, shuffled order
            t = 0.02 * k
            left, right = theta(t)
            yield "/joint_states", "sensor_msgs/msg/JointState", t, T[
                "sensor_msgs/msg/JointState"](
                header=self.header(t), name=["right_wheel", "caster", "left_wheel"],
                position=np.array([right, 7.0, left]), velocity=np.zeros(3),
                effort=np.zeros(3))
        for k in range(-2, 208):  # IMU at 100 Hz, offset 3 ms, spanning the joint states
            t = 0.01 * k + 0.003
            qx, qy, qz, qw = quaternion(ROLL, PITCH, 1.0)
            vec = T["geometry_msgs/msg/Vector3"]
            yield "/imu", "sensor_msgs/msg/Imu", t, T["sensor_msgs/msg/Imu"](
                header=self.header(t), orientation=T["geometry_msgs/msg/Quaternion"](
                    x=qx, y=qy, z=qz, w=qw), orientation_covariance=z9,
                angular_velocity=vec(x=0.0, y=0.0, z=0.4 + 0.1 * t),
                angular_velocity_covariance=z9,
                linear_acceleration=vec(x=0.2 * t, y=-0.1, z=9.81),
                linear_acceleration_covariance=z9)
        for k in range(-1, 63):  # ground truth at 30 Hz with a gap
            t = k / 30.0
            if GT_GAP[0] < t < GT_GAP[1]:
                continue
            if gt_type == "nav_msgs/msg/Odometry":
                twist = T["geometry_msgs/msg/TwistWithCovariance"](
                    twist=T["geometry_msgs/msg/Twist"](
                        linear=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0),
                        angular=T["geometry_msgs/msg/Vector3"](x=0.0, y=0.0, z=0.0)),
                    covariance=z36)
                msg = T[gt_type](header=self.header(t, "map"), child_frame_id="base_link",
                                 pose=T["geometry_msgs/msg/PoseWithCovariance"](
                                     pose=self.pose(t), covariance=z36), twist=twist)
            else:
                msg = T[gt_type](header=self.header(t, "map"), pose=self.pose(t))
            yield "/gt", gt_type, t, msg
        for k in range(-1, 20):  # wheel commands at 10 Hz: left = 1 + k, right = 2 + k
            t = 0.1 * k + 0.05
            if cmd_type == "std_msgs/msg/Float64MultiArray":
                layout = T["std_msgs/msg/MultiArrayLayout"](dim=[], data_offset=0)
                msg = T[cmd_type](layout=layout, data=np.array([1.0 + k, 2.0 + k]))
            else:
                msg = T[cmd_type](header=self.header(t), name=["left_wheel", "right_wheel"],
                                  position=np.zeros(0), velocity=np.array([1.0 + k, 2.0 + k]),
                                  effort=np.zeros(0))
            yield "/cmd", cmd_type, t, msg


def write_bag(path: Path, store: Stores, gt_type: str, cmd_type: str, **writer_kw) -> Path:
    builder = BagBuilder(store)
    writer = Writer1(path) if builder.ros1 else Writer2(path, version=9, **writer_kw)
    serialize = builder.ts.serialize_ros1 if builder.ros1 else builder.ts.serialize_cdr
    msgs = sorted(builder.messages(gt_type, cmd_type), key=lambda m: m[2])
    with writer:
        conns = {}
        for topic, msgtype, t, msg in msgs:
            if topic not in conns:
                conns[topic] = writer.add_connection(topic, msgtype, typestore=builder.ts)
            writer.write(conns[topic], ORIGIN_NS + round(t * 1e9), serialize(msg, msgtype))
    return path


MAPPING = TopicMapping(joint_states="/joint_states",
                       wheel_joints={"left": "left_wheel", "right": "right_wheel"},
                       imu="/imu", ground_truth="/gt", wheel_commands="/cmd")
META = LogMeta.new("diff_drive", ["left", "right"], 0.3, 1.2, CPR)
BAGS = {
    "ros1 bag, Odometry, Float64MultiArray": (
        "run.bag", Stores.ROS1_NOETIC, "nav_msgs/msg/Odometry",
        "std_msgs/msg/Float64MultiArray", {}),
    "ros2 sqlite3, PoseStamped, JointState": (
        "run_db3", Stores.ROS2_HUMBLE, "geometry_msgs/msg/PoseStamped",
        "sensor_msgs/msg/JointState", {"storage_plugin": StoragePlugin.SQLITE3}),
    "ros2 mcap, Odometry, JointState": (
        "run_mcap", Stores.ROS2_HUMBLE, "nav_msgs/msg/Odometry",
        "sensor_msgs/msg/JointState", {"storage_plugin": StoragePlugin.MCAP}),
}


@pytest.mark.parametrize("case", list(BAGS), ids=list(BAGS))
def test_bag_round_trip_recovers_the_known_motion(tmp_path, case):
    name, store, gt_type, cmd_type, kw = BAGS[case]
    bag = write_bag(tmp_path / name, store, gt_type, cmd_type, **kw)
    log = import_rosbag(bag, MAPPING, META)
    t = log.t
    np.testing.assert_allclose(t, 0.02 * np.arange(101), atol=1e-9)
    left, right = theta(t)
    np.testing.assert_array_equal(log.signals["enc_left"], np.round(left * CPR))
    np.testing.assert_array_equal(log.signals["enc_right"], np.round(right * CPR))
    np.testing.assert_allclose(log.signals["gyro_z"], 0.4 + 0.1 * t, atol=1e-9)
    np.testing.assert_allclose(log.signals["acc_x"], 0.2 * t, atol=1e-9)
    np.testing.assert_allclose(log.signals["acc_y"], -0.1, atol=1e-12)
    np.testing.assert_allclose(log.signals["roll"], ROLL, atol=1e-12)
    np.testing.assert_allclose(log.signals["pitch"], PITCH, atol=1e-12)
    in_gap = (t > GT_GAP[0] + 1e-6) & (t < GT_GAP[1] - 1e-6)  # last/first truth at 1.0/1.6 s
    np.testing.assert_array_equal(log.gt_mask, ~in_gap)
    x, y, yaw = gt_pose(t)
    ok = log.gt_mask
    np.testing.assert_allclose(log.signals["gt_x"][ok], x[ok], atol=1e-9)
    np.testing.assert_allclose(log.signals["gt_y"][ok], y[ok], atol=1e-9)
    np.testing.assert_allclose(log.signals["gt_yaw"][ok], yaw[ok], atol=1e-9)  # continuous
    k = np.floor((t - 0.05) / 0.1 + 1e-9)  # index of the last command sent at or before t
    np.testing.assert_array_equal(log.signals["cmd_left"], 1.0 + k)
    np.testing.assert_array_equal(log.signals["cmd_right"], 2.0 + k)
    assert log.meta.data["rosbag_import"]["time_origin_ns"] == ORIGIN_NS
    back = read_log(write_log(log, tmp_path / "log"))
    np.testing.assert_array_equal(back.signals["gt_yaw"], log.signals["gt_yaw"])


def test_missing_topic_is_reported_with_the_topics_present(tmp_path):
    bag = write_bag(tmp_path / "run.bag", Stores.ROS1_NOETIC, "nav_msgs/msg/Odometry",
                    "std_msgs/msg/Float64MultiArray")
    mapping = TopicMapping("/joint_states", {"left": "left_wheel", "right": "right_wheel"},
                           imu="/imu/data")
    with pytest.raises(BagImportError, match=r"'/imu/data'.*'/joint_states'"):
        import_rosbag(bag, mapping, META)


def test_unknown_wheel_joint_is_reported(tmp_path):
    bag = write_bag(tmp_path / "run.bag", Stores.ROS1_NOETIC, "nav_msgs/msg/Odometry",
                    "std_msgs/msg/Float64MultiArray")
    mapping = TopicMapping("/joint_states", {"left": "left_wheel", "right": "rear_wheel"})
    with pytest.raises(BagImportError, match="rear_wheel"):
        import_rosbag(bag, mapping, META, require_ground_truth=False)
