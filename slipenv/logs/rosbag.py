"""Import ROS 1 (``.bag``) and ROS 2 (folder with ``.db3``/``.mcap``) bags into slipenv-log/1.

Uses the pure-Python ``rosbags`` library (``AnyReader``); no ROS installation is needed. All
signals are resampled onto the wheel joint-state stamps, which become the log's time base
(``t = 0`` at the first joint state; the absolute origin is kept in ``meta.json``):

- joint states, ``sensor_msgs/JointState`` positions [rad] -> ``enc_<wheel>`` [counts]
  (``round(position * counts_per_rad)``) and, for rover4ws, ``steer_<wheel>`` [rad];
- IMU, ``sensor_msgs/Imu`` -> ``gyro_z`` [rad/s], ``acc_x``, ``acc_y`` [m/s^2],
  ``roll``, ``pitch`` [rad];
- ground truth, ``nav_msgs/Odometry``, ``geometry_msgs/PoseStamped`` or
  ``geometry_msgs/PoseWithCovarianceStamped`` -> ``gt_x``, ``gt_y`` [m], ``gt_yaw`` [rad];
- wheel commands, ``sensor_msgs/JointState`` velocities or ``std_msgs/Float64MultiArray``
  (``data`` in wheel order) [rad/s] -> ``cmd_<wheel>``.

Continuous signals are linearly interpolated and left NaN outside their source's time span
or across source gaps longer than ``TopicMapping.max_gap_s``; commands are held (zero-order)
from the last message. Angles from quaternions are Z-Y-X (yaw, pitch, roll) Euler angles,
which match the log's REP 103 conventions; yaw is unwrapped (continuous) before resampling
and stays continuous in the log. An IMU whose ``orientation_covariance[0]`` is -1 (REP 145:
no orientation) gives no roll/pitch.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from rosbags.highlevel import AnyReader
from rosbags.typesys import Stores, get_typestore

from slipenv.logs.log import Log
from slipenv.logs.meta import LogMeta

JOINT_STATE = "sensor_msgs/msg/JointState"
IMU = "sensor_msgs/msg/Imu"
FLOAT64_ARRAY = "std_msgs/msg/Float64MultiArray"
POSE_TYPES = ("nav_msgs/msg/Odometry", "geometry_msgs/msg/PoseStamped",
              "geometry_msgs/msg/PoseWithCovarianceStamped")


class BagImportError(ValueError):
    """A bag that cannot be mapped onto a log (missing topic, joint or message type)."""


@dataclass(frozen=True)
class TopicMapping:
    """Which bag topics and joints give which log columns.

    Attributes
    ----------
    joint_states : str
        ``sensor_msgs/JointState`` topic with the wheel positions [rad]; its stamps are the
        log's time base. Messages lacking any mapped joint are skipped.
    wheel_joints : Mapping[str, str]
        Log wheel name (from ``vehicle.wheels``) -> joint name in ``joint_states``.
    imu : str, optional
        ``sensor_msgs/Imu`` topic.
    ground_truth : str, optional
        Odometry or pose topic with the ground-truth pose.
    wheel_commands : str, optional
        Commanded wheel speeds [rad/s]: a JointState (``velocity``) or a Float64MultiArray
        whose ``data`` follows the order of ``vehicle.wheels``.
    command_joints : Mapping[str, str], optional
        Joint names in a JointState command topic; defaults to ``wheel_joints``.
    steer_joints : Mapping[str, str], optional
        Wheel name -> steering joint in ``joint_states`` (rover4ws) giving ``steer_<wheel>``.
    max_gap_s : float
        Longest source gap [s] bridged by linear interpolation.
    """

    joint_states: str
    wheel_joints: Mapping[str, str]
    imu: str | None = None
    ground_truth: str | None = None
    wheel_commands: str | None = None
    command_joints: Mapping[str, str] | None = None
    steer_joints: Mapping[str, str] | None = None
    max_gap_s: float = 0.5


def import_rosbag(
    bag_path: str | Path,
    mapping: TopicMapping,
    meta: Mapping[str, Any] | LogMeta,
    *,
    require_ground_truth: bool = True,
) -> Log:
    """Read a ROS 1 or ROS 2 bag into a validated ``Log``.

    Parameters
    ----------
    bag_path : str or Path
        A ROS 1 ``.bag`` file, or a ROS 2 bag folder (or a ``.db3``/``.mcap`` file in it).
    mapping : TopicMapping
        Topics and joint names.
    meta : Mapping or LogMeta
        The vehicle description for ``meta.json``; ``counts_per_rad`` converts joint
        positions [rad] to counts. A ``rosbag_import`` key recording the bag, topics and
        absolute time origin [ns] is added.
    require_ground_truth : bool
        See ``slipenv.logs.read_log``.

    Returns
    -------
    Log
    """
    meta = meta.copy() if isinstance(meta, LogMeta) else LogMeta(meta)
    wheels = meta.wheels
    if set(mapping.wheel_joints) != set(wheels):
        raise BagImportError(f"wheel_joints maps {sorted(mapping.wheel_joints)}, "
                             f"meta wheels are {wheels}")
    path = _bag_path(bag_path)
    raw = _collect(path, mapping, wheels)
    if not raw["joints"]:
        raise BagImportError(f"{path}: no message on {mapping.joint_states} names all of "
                             f"{sorted(mapping.wheel_joints.values())}")
    stamps, js = _sorted_unique(raw["joints"])
    origin = int(stamps[0])
    t = (stamps - origin) * 1e-9
    cols: dict[str, np.ndarray] = {"t": t}
    n_w = len(wheels)
    for k, w in enumerate(wheels):
        cols[f"enc_{w}"] = np.round(js[:, k] * meta.counts_per_rad)
    for k, w in enumerate(mapping.steer_joints or {}):
        cols[f"steer_{w}"] = js[:, n_w + k]
    gap = mapping.max_gap_s
    if raw["cmd"]:
        ts, y = _sorted_unique(raw["cmd"])
        for k, w in enumerate(wheels):
            cols[f"cmd_{w}"] = _hold((ts - origin) * 1e-9, y[:, k], t)
    if raw["imu"]:
        ts, y = _sorted_unique(raw["imu"])
        for k, name in enumerate(("gyro_z", "acc_x", "acc_y", "roll", "pitch")):
            if np.isfinite(y[:, k]).any():
                cols[name] = _interp((ts - origin) * 1e-9, y[:, k], t, gap)
    if raw["gt"]:
        ts, y = _sorted_unique(raw["gt"])
        y[:, 2] = np.unwrap(y[:, 2])
        for k, name in enumerate(("gt_x", "gt_y", "gt_yaw")):
            cols[name] = _interp((ts - origin) * 1e-9, y[:, k], t, gap)
    meta.data["rosbag_import"] = {
        "bag": str(path), "time_origin_ns": origin,
        "topics": {k: v for k, v in (("joint_states", mapping.joint_states),
                                     ("imu", mapping.imu),
                                     ("ground_truth", mapping.ground_truth),
                                     ("wheel_commands", mapping.wheel_commands)) if v},
    }
    return Log.from_arrays(meta, require_ground_truth=require_ground_truth, **cols)


def quaternion_to_euler(x: float, y: float, z: float, w: float) -> tuple[float, float, float]:
    """Z-Y-X Euler angles ``(roll, pitch, yaw)`` [rad] of a unit quaternion."""
    roll = np.arctan2(2.0 * (w * x + y * z), 1.0 - 2.0 * (x * x + y * y))
    pitch = np.arcsin(np.clip(2.0 * (w * y - z * x), -1.0, 1.0))
    yaw = np.arctan2(2.0 * (w * z + x * y), 1.0 - 2.0 * (y * y + z * z))
    return float(roll), float(pitch), float(yaw)


def _bag_path(bag_path: str | Path) -> Path:
    path = Path(bag_path)
    if path.is_file() and path.suffix in (".db3", ".mcap"):
        path = path.parent  # a ROS 2 bag is its folder (metadata.yaml + storage files)
    if not path.exists():
        raise FileNotFoundError(path)
    return path


def _stamp_ns(msg: Any, bag_ns: int) -> int:
    """Header stamp [ns], or the bag's receive time for unstamped (or zero-stamped) messages."""
    header = getattr(msg, "header", None)
    if header is not None:
        ns = int(header.stamp.sec) * 1_000_000_000 + int(header.stamp.nanosec)
        if ns > 0:
            return ns
    return bag_ns


def _collect(path: Path, mapping: TopicMapping, wheels: list[str]) -> dict[str, list]:
    """One pass over the bag: per role, a list of ``(stamp_ns, values)``."""
    roles = {"joints": mapping.joint_states, "imu": mapping.imu, "gt": mapping.ground_truth,
             "cmd": mapping.wheel_commands}
    out: dict[str, list] = {role: [] for role in roles}
    joints = [mapping.wheel_joints[w] for w in wheels] + list(
        (mapping.steer_joints or {}).values())
    cmd_joints = [(mapping.command_joints or mapping.wheel_joints)[w] for w in wheels]
    with AnyReader([path], default_typestore=get_typestore(Stores.ROS2_HUMBLE)) as reader:
        available = {c.topic: c.msgtype for c in reader.connections}
        for role, topic in roles.items():
            if topic is not None and topic not in available:
                raise BagImportError(f"{path}: topic {topic!r} ({role}) not in the bag; "
                                     f"topics: {sorted(available)}")
        wanted = {t for t in roles.values() if t is not None}
        conns = [c for c in reader.connections if c.topic in wanted]
        for conn, bag_ns, rawdata in reader.messages(connections=conns):
            msg = reader.deserialize(rawdata, conn.msgtype)
            stamp = _stamp_ns(msg, bag_ns)
            for role, topic in roles.items():
                if topic != conn.topic:
                    continue
                values = _extract(role, conn.msgtype, msg, joints, cmd_joints, len(wheels))
                if values is not None:
                    out[role].append((stamp, values))
    return out


def _extract(role: str, msgtype: str, msg: Any, joints: list[str], cmd_joints: list[str],
             n_wheels: int) -> list[float] | None:
    if role == "joints" or (role == "cmd" and msgtype == JOINT_STATE):
        if msgtype != JOINT_STATE:
            raise BagImportError(f"joint states must be {JOINT_STATE}, got {msgtype}")
        names = list(msg.name)
        wanted = joints if role == "joints" else cmd_joints
        values = msg.position if role == "joints" else msg.velocity
        if not set(wanted) <= set(names) or len(values) != len(names):
            return None
        return [float(values[names.index(j)]) for j in wanted]
    if role == "cmd":
        if msgtype != FLOAT64_ARRAY:
            raise BagImportError(f"wheel commands must be {JOINT_STATE} or {FLOAT64_ARRAY}, "
                                 f"got {msgtype}")
        return [float(v) for v in msg.data[:n_wheels]] if len(msg.data) >= n_wheels else None
    if role == "imu":
        if msgtype != IMU:
            raise BagImportError(f"IMU must be {IMU}, got {msgtype}")
        q = msg.orientation
        roll, pitch, _ = quaternion_to_euler(q.x, q.y, q.z, q.w)
        if msg.orientation_covariance[0] == -1.0:
            roll = pitch = float("nan")
        return [msg.angular_velocity.z, msg.linear_acceleration.x, msg.linear_acceleration.y,
                roll, pitch]
    if msgtype not in POSE_TYPES:
        raise BagImportError(f"ground truth must be one of {POSE_TYPES}, got {msgtype}")
    pose = msg.pose if msgtype == "geometry_msgs/msg/PoseStamped" else msg.pose.pose
    q = pose.orientation
    return [pose.position.x, pose.position.y, quaternion_to_euler(q.x, q.y, q.z, q.w)[2]]


def _sorted_unique(samples: list[tuple[int, list[float]]]) -> tuple[np.ndarray, np.ndarray]:
    """Stamps [ns] sorted, keeping the first of equal stamps, and their values (m, k)."""
    stamps = np.array([s for s, _ in samples], dtype=np.int64)
    values = np.array([v for _, v in samples], dtype=np.float64)
    order = np.argsort(stamps, kind="stable")
    stamps, values = stamps[order], values[order]
    keep = np.concatenate([[True], np.diff(stamps) > 0])
    return stamps[keep], values[keep]


def _interp(ts: np.ndarray, y: np.ndarray, t: np.ndarray, max_gap_s: float) -> np.ndarray:
    """Linear interpolation of ``y(ts)`` at ``t``; NaN outside ``ts`` and across long gaps."""
    out = np.interp(t, ts, y)
    hi = np.clip(np.searchsorted(ts, t, side="left"), 0, len(ts) - 1)
    lo = np.clip(hi - 1, 0, len(ts) - 1)
    exact = ts[hi] == t
    bad = (t < ts[0]) | (t > ts[-1]) | (~exact & (ts[hi] - ts[lo] > max_gap_s))
    out[bad] = np.nan
    return out


def _hold(ts: np.ndarray, y: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Zero-order hold of ``y(ts)`` at ``t``; NaN before the first sample."""
    idx = np.searchsorted(ts, t, side="right") - 1
    out = y[np.clip(idx, 0, None)].copy()
    out[idx < 0] = np.nan
    return out
