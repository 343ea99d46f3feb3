"""Ground-truth-anchored segments of one or several logs, as padded arrays for the replay.

Each segment starts on a sample with a full ground-truth pose; the replay (``replay.py``)
integrates it from there. This module only cuts and pads (:func:`log_arrays`, :func:`cut`);
the segment length is chosen by replaying (``replay.choose_duration``), which is why
``replay.build_segments`` is the entry point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipenv.diagnose import geometry
from slipenv.logs.log import Log

SUPPORTED_KINDS = ("diff_drive", "skid_steer", "rover4ws")
MIN_SEGMENT_SAMPLES = 5
DURATIONS_S = (2.0, 3.0, 4.0, 6.0, 8.0, 12.0, 15.0, 20.0, 30.0)  # [s] candidate lengths
MIN_SEGMENTS = 32  # segments wanted for the held-out comparison
MAX_END_HEADING_RAD = 0.5  # nominal replay's median heading error at a segment's end
_BETA_WINDOW_S = 0.25  # [s] half-window of the central difference giving the measured β


def wheel_sides(wheels: list[str]) -> np.ndarray:
    """Side of each wheel: 0 left, 1 right — from 'left'/'right' in the name, else by order.

    ``log-format.md`` lists the left side first, so without names the first half is left.
    """
    names = [w.lower() for w in wheels]
    if all(("left" in n) != ("right" in n) for n in names):
        return np.array([0 if "left" in n else 1 for n in names])
    if len(wheels) % 2:
        raise ValueError(f"cannot tell left from right among wheels {wheels}: name them "
                         "'...left...'/'...right...' or list an even number, left first")
    half = len(wheels) // 2
    return np.array([0] * half + [1] * half)


def wheel_x(wheels: list[str], wheelbase_m: float) -> np.ndarray:
    """Longitudinal offset of each wheel from the axle midpoint [m] (rover4ws): +L/2 for
    'front' in the name, -L/2 for 'rear'/'back', by order otherwise (front pair first)."""
    names = [w.lower() for w in wheels]
    front = ["front" in n for n in names]
    rear = ["rear" in n or "back" in n for n in names]
    if all(f != r for f, r in zip(front, rear, strict=True)):
        return np.array([0.5 * wheelbase_m if f else -0.5 * wheelbase_m for f in front])
    if len(wheels) != 4:
        raise ValueError(f"cannot tell front from rear among rover wheels {wheels}: name them "
                         "'front...'/'rear...' or list four, front pair first")
    return np.array([0.5, 0.5, -0.5, -0.5]) * wheelbase_m


def _fill(values: np.ndarray, t: np.ndarray) -> np.ndarray:
    """NaNs replaced by linear interpolation in time (held at the ends); all-NaN -> NaN."""
    ok = np.isfinite(values)
    if ok.all() or not ok.any():
        return values.copy()
    return np.interp(t, t[ok], values[ok])


def _interval_mean(values: np.ndarray) -> np.ndarray:
    """Mean of the two end samples of every interval (trapezoid rule)."""
    return 0.5 * (values[1:] + values[:-1])


@dataclass
class Segments:
    """Padded per-segment arrays of one or several logs (S segments, at most L samples).

    Interval arrays have L - 1 entries per segment; padding has zero wheel motion, so the
    replay stands still there, and ``gt_ok`` is False there.
    """

    t: np.ndarray  # (S, L) sample times [s], padded with the last time
    dt: np.ndarray  # (S, L-1) [s]
    dphi: np.ndarray  # (S, L-1, n_wheels) wheel rotation per interval [rad]
    torque: np.ndarray | None  # (S, L-1, n_wheels) [N m] or None
    roll: np.ndarray | None  # (S, L-1) logged roll [rad] or None
    pitch: np.ndarray | None  # (S, L-1) logged pitch [rad] or None (report only)
    gyro: np.ndarray | None  # (S, L-1) gyro yaw rate [rad/s] or None
    beta: np.ndarray  # (S, L-1) slip angle measured from ground truth [rad]
    pos: np.ndarray  # (S, L-1, 2) ground-truth position at interval midpoints [m]
    gt: np.ndarray  # (S, L, 3) ground truth x, y, yaw (NaN where missing)
    gt_ok: np.ndarray  # (S, L) bool
    tilt: np.ndarray  # (S, 3, 3) slope rotation of each segment's log
    radius: np.ndarray  # (S, n_wheels) nominal radii [m]
    track: np.ndarray  # (S,) nominal track width [m]
    log_index: np.ndarray  # (S,) index of the segment's log
    start: np.ndarray  # (S,) index of the first sample in its log
    sides: np.ndarray  # (n_wheels,) 0 left / 1 right
    wheels: list[str]
    kind: str
    steer: np.ndarray | None = None  # (S, L-1, n_wheels) steering angle [rad] (rover4ws)
    wheel_x: np.ndarray | None = None  # (n_wheels,) longitudinal wheel offsets [m] (rover4ws)

    def __len__(self) -> int:
        return len(self.t)

    def anchor_heading(self) -> np.ndarray:
        """In-plane heading at each segment start, from the logged yaw, shape (S,) [rad]."""
        return geometry.heading_from_yaw(self.gt[:, 0, 2], self.tilt)

    def geometric_roll(self, theta: np.ndarray) -> np.ndarray:
        """Roll [rad] implied by the declared slope at in-plane heading θ (S, L-1) [rad]."""
        return geometry.roll_from_heading(theta, self.tilt[:, None])

    def take(self, index: np.ndarray) -> Segments:
        """The segments at ``index`` (same padding)."""
        out = {}
        for name, value in self.__dict__.items():
            is_batch = isinstance(value, np.ndarray) and name not in ("sides", "wheel_x")
            out[name] = value[index] if is_batch else value
        return Segments(**out)


def check_logs(logs: list[Log]) -> None:
    """Raise ValueError unless the logs can be replayed together (kind, wheels, ground truth)."""
    if not logs:
        raise ValueError("no logs to diagnose")
    first = logs[0]
    for log in logs:
        where = log.path or "<log>"
        if log.meta.kind not in SUPPORTED_KINDS:
            raise ValueError(f"{where}: vehicle kind {log.meta.kind!r} is not supported by the "
                             f"diagnosis (supported: {', '.join(SUPPORTED_KINDS)})")
        if log.meta.kind == "rover4ws":
            try:
                wheel_x(log.wheels, float(log.meta.wheelbase_m or 0.0))
            except ValueError as exc:
                raise ValueError(f"{where}: {exc}") from None
        if log.meta.kind != first.meta.kind or log.wheels != first.wheels:
            raise ValueError(f"{where}: all logs diagnosed together must share the vehicle "
                             f"kind and wheel names ({first.meta.kind}, {first.wheels})")
        if not log.gt_mask.any():
            raise ValueError(f"{where}: no ground-truth pose (gt_x, gt_y, gt_yaw) at any sample;"
                             " the replay needs it to anchor and to compare")


def cut(arrays: list[dict], logs: list[Log], seg_s: float) -> Segments | None:
    """The logs cut into segments of ``seg_s`` [s] and padded; None when no segment fits.

    ``arrays`` are the logs' :func:`log_arrays`; a segment needs ``MIN_SEGMENT_SAMPLES``
    samples and ground truth at two of them at least.
    """
    pieces = _pieces(arrays, logs, seg_s)
    return _assemble(pieces, logs) if pieces else None


def cut_spans(arrays: list[dict], logs: list[Log], spans: list[tuple[int, int, int]]
              ) -> Segments | None:
    """Segments at explicit spans ``(log index, start, stop)`` (half-open sample ranges, any
    lengths: padded to the longest); spans with fewer than ``MIN_SEGMENT_SAMPLES`` samples or
    fewer than two ground-truth samples are dropped. None when none is left."""
    pieces = [(li, a, b, arrays[li]) for li, a, b in spans
              if b - a >= MIN_SEGMENT_SAMPLES and arrays[li]["gt_ok"][a:b].sum() >= 2]
    return _assemble(pieces, logs) if pieces else None


def _pieces(arrays: list[dict], logs: list[Log], seg_s: float) -> list[tuple]:
    out = []
    for li, (log, arr) in enumerate(zip(logs, arrays, strict=True)):
        for a, b in log.segment_bounds(seg_s):
            if b - a >= MIN_SEGMENT_SAMPLES and arr["gt_ok"][a:b].sum() >= 2:
                out.append((li, a, b, arr))
    return out


def _assemble(pieces: list[tuple], logs: list[Log]) -> Segments:
    """Pad the pieces (log index, start, stop, arrays) into a ``Segments``."""
    wheels = logs[0].wheels
    n_w = len(wheels)
    length = max(b - a for _, a, b, _ in pieces)
    s_count = len(pieces)
    has_torque = all(p[3]["torque"] is not None for p in pieces)
    has_roll = all(p[3]["roll"] is not None for p in pieces)
    has_pitch = all(p[3]["pitch"] is not None for p in pieces)
    has_gyro = all(p[3]["gyro"] is not None for p in pieces)
    has_steer = all(p[3].get("steer") is not None for p in pieces)
    t = np.zeros((s_count, length))
    dphi = np.zeros((s_count, length - 1, n_w))
    torque = np.zeros((s_count, length - 1, n_w)) if has_torque else None
    roll = np.zeros((s_count, length - 1)) if has_roll else None
    pitch = np.zeros((s_count, length - 1)) if has_pitch else None
    gyro = np.zeros((s_count, length - 1)) if has_gyro else None
    steer = np.zeros((s_count, length - 1, n_w)) if has_steer else None
    beta = np.zeros((s_count, length - 1))
    pos = np.zeros((s_count, length - 1, 2))
    gt = np.full((s_count, length, 3), np.nan)
    gt_ok = np.zeros((s_count, length), dtype=bool)
    for j, (_, a, b, arr) in enumerate(pieces):
        n = b - a
        t[j, :n], t[j, n:] = arr["t"][a:b], arr["t"][b - 1]
        dphi[j, :n - 1] = arr["dphi"][a:b - 1]
        beta[j, :n - 1] = arr["beta"][a:b - 1]
        pos[j, :n - 1] = arr["pos"][a:b - 1]
        pos[j, n - 1:] = arr["pos"][b - 2]
        gt[j, :n] = arr["gt"][a:b]
        gt_ok[j, :n] = arr["gt_ok"][a:b]
        for name, dest in (("torque", torque), ("roll", roll), ("pitch", pitch),
                           ("gyro", gyro), ("steer", steer)):
            if dest is not None:
                dest[j, :n - 1] = arr[name][a:b - 1]
    wheelbase = logs[0].meta.wheelbase_m
    return Segments(
        t=t, dt=np.diff(t, axis=1), dphi=dphi, torque=torque, roll=roll, pitch=pitch,
        gyro=gyro, beta=beta,
        pos=pos, gt=gt, gt_ok=gt_ok,
        tilt=np.stack([p[3]["tilt"] for p in pieces]),
        radius=np.stack([np.full(n_w, logs[p[0]].meta.wheel_radius_m) for p in pieces]),
        track=np.array([logs[p[0]].meta.track_width_m for p in pieces]),
        log_index=np.array([p[0] for p in pieces]), start=np.array([p[1] for p in pieces]),
        sides=wheel_sides(wheels), wheels=list(wheels), kind=logs[0].meta.kind,
        steer=steer,
        # meta validation gives every rover4ws log a wheelbase
        wheel_x=(wheel_x(list(wheels), wheelbase)
                 if logs[0].meta.kind == "rover4ws" and wheelbase is not None else None),
    )


def log_arrays(log: Log) -> dict:
    """Per-interval regressors of one log (see ``Segments``)."""
    t = log.t
    tilt = geometry.tilt_matrix(log.meta.slope_deg, log.meta.slope_downhill_azimuth_deg)
    gt = log.ground_truth()
    ok = log.gt_mask
    out: dict = {"t": t, "tilt": tilt, "gt": gt, "gt_ok": ok,
                 "dphi": np.diff(log.wheel_angles(), axis=0)}
    cols = [f"torque_{w}" for w in log.wheels]
    out["torque"] = (np.column_stack([_interval_mean(_fill(log.signals[c], t)) for c in cols])
                     if all(log.has(c) for c in cols) else None)
    for name in ("roll", "pitch"):
        out[name] = _interval_mean(_fill(log.signals[name], t)) if log.has(name) else None
    out["gyro"] = _interval_mean(_fill(log.signals["gyro_z"], t)) if log.has("gyro_z") else None
    steer = [f"steer_{w}" for w in log.wheels]
    out["steer"] = (np.column_stack([_interval_mean(_fill(log.signals[c], t)) for c in steer])
                    if log.meta.kind == "rover4ws" and all(log.has(c) for c in steer) else None)
    x = np.interp(t, t[ok], gt[ok, 0])
    y = np.interp(t, t[ok], gt[ok, 1])
    out["pos"] = np.column_stack([_interval_mean(x), _interval_mean(y)])
    out["beta"] = _measured_beta(t, x, y, np.interp(t, t[ok], np.unwrap(gt[ok, 2])), tilt)
    return out


def _measured_beta(t, x, y, yaw, tilt) -> np.ndarray:
    """Body slip angle atan2(V_y, |V_x|) from ground-truth velocity, per interval [rad].

    Velocity by central differences over ±``_BETA_WINDOW_S``, expressed in the slope plane and
    rotated into the body; 0 where the vehicle moves slower than a tenth of its median speed.
    """
    n = len(t)
    dt_med = float(np.median(np.diff(t))) if n > 1 else 1.0
    h = max(1, int(round(_BETA_WINDOW_S / dt_med)))
    lo, hi = np.maximum(np.arange(n) - h, 0), np.minimum(np.arange(n) + h, n - 1)
    span = np.maximum(t[hi] - t[lo], 1e-9)
    vx, vy = (x[hi] - x[lo]) / span, (y[hi] - y[lo]) / span
    inv = np.linalg.inv(tilt[:2, :2])
    vu, vv = inv[0, 0] * vx + inv[0, 1] * vy, inv[1, 0] * vx + inv[1, 1] * vy
    theta = geometry.heading_from_yaw(yaw, tilt)
    c, s = np.cos(theta), np.sin(theta)
    v_long, v_lat = c * vu + s * vv, -s * vu + c * vv
    speed = np.hypot(v_long, v_lat)
    moving = speed > 0.1 * max(float(np.median(speed)), 1e-6)
    beta = np.where(moving, np.arctan2(v_lat, np.abs(v_long)), 0.0)
    return _interval_mean(beta)


