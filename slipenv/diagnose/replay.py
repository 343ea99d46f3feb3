"""Kinematic replay: the logged wheel motion integrated into pose, segment by segment.

The workhorse of the diagnosis. Each segment starts on a ground-truth sample (re-anchored: the
replay starts from the logged pose there) and integrates the encoder increments with the
nominal kinematics of the log's ``meta.json`` — wheel radii, track width, counts per radian,
slope geometry — plus any effect of the vocabulary (``effects.py``) switched on by a parameter.
All segments are integrated at once on padded arrays (segments × samples), so one replay of a
5-minute, 20 Hz log costs well under a millisecond.

Per sample interval k (from sample k to k+1), with parameters ``p`` (internal names, see
``effects.py``; absent names take their nominal value):

1. rim travel of each wheel, d_i = r_side(i) Δφ_i  (``rolling_radius``: r per side);
2. longitudinal slip s_i (``torque_slip``: T_i c_side, c = 1/k_s; ``soil_patch``: the same inside
   a disc; ``combined_slip``: s_x0 + k_β softplus(|β| - β0)), ground travel g_i = d_i - s_i |d_i|
   (slip in the sense of travel, contact-law convention of ``slipenv.terramechanics.contact``);
3. left/right means g_L, g_R; ``turning_slip`` moves them by Endo's split of a yaw discrepancy
   c = -κ (g_R - g_L): g_L -= f c, g_R += (1 - f) c (Yamauchi Eq. 7-8; ``estimators.endo``);
4. forward travel ds = (g_L + g_R)/2, in-plane turn dθ = (g_R - g_L)/W (``track_width``: W);
5. lateral travel dl = |ds| tan β with β = β_roll roll + β_0 (``slope_side_slip``, Yamauchi);
6. midpoint integration in the slope plane, mapped to the world by ``geometry.tilt_matrix``.

The gyro channel replays heading from the gyro alone (``gyro_bias`` b subtracted), for
comparison with the ground-truth heading.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from estimators.endo import endo_left_share
from slipenv.diagnose import geometry
from slipenv.logs.log import Log

SUPPORTED_KINDS = ("diff_drive", "skid_steer")
MIN_SEGMENT_SAMPLES = 5
_SOFTPLUS_RAD = 0.01  # [rad] corner width of the combined-slip hinge (Reina Eq. 12 smoothed)
_ENDO_EPS_MPS = 1e-3  # [m/s] regularising speed in Endo's split (estimators.endo)
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

    def __len__(self) -> int:
        return len(self.t)

    def take(self, index: np.ndarray) -> Segments:
        """The segments at ``index`` (same padding)."""
        out = {}
        for name, value in self.__dict__.items():
            is_batch = isinstance(value, np.ndarray) and name != "sides"
            out[name] = value[index] if is_batch else value
        return Segments(**out)


def segment_duration_s(logs: list[Log]) -> float:
    """Segment length: about 16 segments per log, within 2-15 s [s]."""
    span = min(float(log.t[-1] - log.t[0]) for log in logs)
    return float(np.clip(span / 16.0, 2.0, 15.0))


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
        if log.meta.kind != first.meta.kind or log.wheels != first.wheels:
            raise ValueError(f"{where}: all logs diagnosed together must share the vehicle "
                             f"kind and wheel names ({first.meta.kind}, {first.wheels})")
        if not log.gt_mask.any():
            raise ValueError(f"{where}: no ground-truth pose (gt_x, gt_y, gt_yaw) at any sample;"
                             " the replay needs it to anchor and to compare")


def build_segments(logs: list[Log], segment_s: float | None = None) -> Segments:
    """Cut the logs into ground-truth-anchored segments and pad them into arrays.

    Raises
    ------
    ValueError
        If a log cannot be replayed (``check_logs``) or no segment of ``segment_s`` fits.
    """
    check_logs(logs)
    seg_s = segment_s or segment_duration_s(logs)
    wheels = logs[0].wheels
    pieces = []
    for li, log in enumerate(logs):
        arrays = _log_arrays(log)
        for a, b in log.segment_bounds(seg_s):
            if b - a >= MIN_SEGMENT_SAMPLES and arrays["gt_ok"][a:b].sum() >= 2:
                pieces.append((li, a, b, arrays))
    if not pieces:
        raise ValueError(f"no segment of {seg_s:.1f} s with ground truth at both ends fits in "
                         "the log(s); the log is too short or its ground truth too sparse")
    n_w = len(wheels)
    length = max(b - a for _, a, b, _ in pieces)
    s_count = len(pieces)
    has_torque = all(p[3]["torque"] is not None for p in pieces)
    has_roll = all(p[3]["roll"] is not None for p in pieces)
    has_gyro = all(p[3]["gyro"] is not None for p in pieces)
    t = np.zeros((s_count, length))
    dphi = np.zeros((s_count, length - 1, n_w))
    torque = np.zeros((s_count, length - 1, n_w)) if has_torque else None
    roll = np.zeros((s_count, length - 1)) if has_roll else None
    gyro = np.zeros((s_count, length - 1)) if has_gyro else None
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
        for name, dest in (("torque", torque), ("roll", roll), ("gyro", gyro)):
            if dest is not None:
                dest[j, :n - 1] = arr[name][a:b - 1]
    return Segments(
        t=t, dt=np.diff(t, axis=1), dphi=dphi, torque=torque, roll=roll, gyro=gyro, beta=beta,
        pos=pos, gt=gt, gt_ok=gt_ok,
        tilt=np.stack([p[3]["tilt"] for p in pieces]),
        radius=np.stack([np.full(n_w, logs[p[0]].meta.wheel_radius_m) for p in pieces]),
        track=np.array([logs[p[0]].meta.track_width_m for p in pieces]),
        log_index=np.array([p[0] for p in pieces]), start=np.array([p[1] for p in pieces]),
        sides=wheel_sides(wheels), wheels=list(wheels), kind=logs[0].meta.kind,
    )


def _log_arrays(log: Log) -> dict:
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
    out["roll"] = _interval_mean(_fill(log.signals["roll"], t)) if log.has("roll") else None
    out["gyro"] = _interval_mean(_fill(log.signals["gyro_z"], t)) if log.has("gyro_z") else None
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


def _side_param(p: dict, base: str, default: np.ndarray | float) -> np.ndarray:
    """Per-side parameter (left, right) as an array of shape (2,), or the default."""
    if f"{base}_L" in p:
        return np.array([p[f"{base}_L"], p[f"{base}_R"]])
    return np.broadcast_to(np.asarray(default, dtype=float), (2,))


def slips(seg: Segments, p: dict, pos: np.ndarray | None = None) -> np.ndarray:
    """Longitudinal slip s_i per interval and wheel, shape (S, L-1, n_wheels) [-]."""
    s = np.zeros(seg.dphi.shape)
    if seg.torque is not None:
        if "c_L" in p:
            s += seg.torque * _side_param(p, "c", 0.0)[seg.sides]
        if "pc_L" in p:
            where = seg.pos if pos is None else pos
            w = patch_weight(where, p["px"], p["py"], p["pr"])
            s += w[..., None] * seg.torque * _side_param(p, "pc", 0.0)[seg.sides]
    if "sx0" in p:
        z = (np.abs(seg.beta) - p["b0c"]) / _SOFTPLUS_RAD
        hinge = _SOFTPLUS_RAD * np.logaddexp(0.0, z)
        s += (p["sx0"] + p["kb"] * hinge)[..., None]
    return s


def patch_weight(pos: np.ndarray, cx: float, cy: float, radius: float) -> np.ndarray:
    """Weight of a soft disc at ``pos`` (…, 2): 1 inside, 0 outside, C1 smoothstep edge.

    The edge band is 0.2 radius wide, centred on the circle (the blend of
    ``slipenv.terramechanics.soil_map.PatchSoilMap`` with ``blend_width_m = 0.2 radius``).
    """
    radius = max(float(radius), 1e-6)
    d = np.hypot(pos[..., 0] - cx, pos[..., 1] - cy) - radius
    u = np.clip(0.5 - d / (0.2 * radius), 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def simulate(seg: Segments, p: dict) -> np.ndarray:
    """Replay every segment with parameters ``p``; predicted x, y, yaw of shape (S, L, 3)."""
    radius = (np.broadcast_to(_side_param(p, "r", 0.0)[seg.sides], seg.radius.shape)
              if "r_L" in p else seg.radius)
    d = radius[:, None, :] * seg.dphi
    g = d - slips(seg, p) * np.abs(d)
    left = g[..., seg.sides == 0].mean(axis=-1)
    right = g[..., seg.sides == 1].mean(axis=-1)
    if "turn_k" in p:
        dt = np.maximum(seg.dt, 1e-9)
        f = endo_left_share(left / dt, right / dt, max(p["endo_n"], 1e-3), _ENDO_EPS_MPS)
        c = -p["turn_k"] * (right - left)
        left, right = left - f * c, right + (1.0 - f) * c
    track = p.get("W", seg.track)
    track = track[:, None] if np.ndim(track) else track
    ds = 0.5 * (left + right)
    dtheta = (right - left) / track
    theta0 = _anchor_heading(seg)
    theta = theta0[:, None] + np.concatenate([np.zeros((len(seg), 1)),
                                              np.cumsum(dtheta, axis=1)], axis=1)
    mid = theta[:, :-1] + 0.5 * dtheta
    du, dv = ds * np.cos(mid), ds * np.sin(mid)
    if "bpr" in p:
        roll = seg.roll if seg.roll is not None else _geometric_roll(mid, seg.tilt)
        dl = np.abs(ds) * np.tan(p["bpr"] * roll + p["b0"])
        du, dv = du - dl * np.sin(mid), dv + dl * np.cos(mid)
    return _to_world(seg, du, dv, theta)


def _geometric_roll(theta: np.ndarray, tilt: np.ndarray) -> np.ndarray:
    """Roll implied by the declared slope at in-plane heading θ (S, L-1), per segment."""
    return geometry.roll_from_heading(theta, tilt[:, None])


def _anchor_heading(seg: Segments) -> np.ndarray:
    """In-plane heading at each segment start, from the logged yaw, shape (S,)."""
    return geometry.heading_from_yaw(seg.gt[:, 0, 2], seg.tilt)


def _to_world(seg: Segments, du: np.ndarray, dv: np.ndarray, theta: np.ndarray) -> np.ndarray:
    """In-plane increments and headings -> world x, y, yaw, anchored at each segment start."""
    zeros = np.zeros((len(seg), 1))
    u = np.concatenate([zeros, np.cumsum(du, axis=1)], axis=1)
    v = np.concatenate([zeros, np.cumsum(dv, axis=1)], axis=1)
    m = seg.tilt[:, :2, :2]
    out = np.empty(seg.gt.shape)
    out[..., 0] = seg.gt[:, :1, 0] + m[:, 0, 0, None] * u + m[:, 0, 1, None] * v
    out[..., 1] = seg.gt[:, :1, 1] + m[:, 1, 0, None] * u + m[:, 1, 1, None] * v
    out[..., 2] = geometry.yaw_from_heading(theta, seg.tilt[:, None])
    return out


def simulate_gyro_heading(seg: Segments, p: dict) -> np.ndarray:
    """Yaw [rad] from the gyro alone (minus bias ``gyro_b``), anchored at segment starts (S, L)."""
    if seg.gyro is None:
        raise ValueError("the log has no gyro_z column")
    rate = seg.gyro - p.get("gyro_b", 0.0)
    theta = _anchor_heading(seg)[:, None] + np.concatenate(
        [np.zeros((len(seg), 1)), np.cumsum(rate * seg.dt, axis=1)], axis=1)
    return geometry.yaw_from_heading(theta, seg.tilt[:, None])


def pose_residuals(seg: Segments, pred: np.ndarray) -> np.ndarray:
    """Predicted minus logged x, y [m] and yaw [rad] (wrapped), (S, L, 3); 0 where no truth."""
    res = pred - seg.gt
    res[..., 2] = geometry.wrap(res[..., 2])
    res[~seg.gt_ok] = 0.0
    return res


def heading_residuals(seg: Segments, yaw: np.ndarray) -> np.ndarray:
    """Predicted minus logged yaw (wrapped), (S, L); 0 where no truth."""
    res = geometry.wrap(yaw - seg.gt[..., 2])
    res[~seg.gt_ok] = 0.0
    return res
