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
5. lateral travel dl = |ds| tan β with β = (β_roll + β_turn |dθ/dt|) roll + β_0
   (``slope_side_slip``; Yamauchi's regression on roll, with the turning term that makes a
   skid-steer vehicle slide downhill while it scrubs round a turn);
6. midpoint integration in the slope plane, mapped to the world by ``geometry.tilt_matrix``.

The gyro channel replays heading from the gyro alone (``gyro_bias`` b subtracted), for
comparison with the ground-truth heading.
"""

from __future__ import annotations

import numpy as np

from slipenv.diagnose import geometry
from slipenv.diagnose.segments import (  # noqa: F401  (re-exported)
    SUPPORTED_KINDS,
    Segments,
    build_segments,
    check_logs,
    wheel_sides,
)
from slipenv.estimators.endo import endo_left_share

_SOFTPLUS_RAD = 0.01  # [rad] corner width of the combined-slip hinge (Reina Eq. 12 smoothed)
_ENDO_EPS_MPS = 1e-3  # [m/s] regularising speed in Endo's split (slipenv.estimators.endo)


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
        turn = np.abs(dtheta) / np.maximum(seg.dt, 1e-9)
        dl = np.abs(ds) * np.tan(roll * (p["bpr"] + p.get("bpt", 0.0) * turn) + p["b0"])
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
