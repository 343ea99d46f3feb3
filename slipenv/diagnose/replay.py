"""Kinematic replay: the logged wheel motion integrated into pose, segment by segment.

The workhorse of the diagnosis. Each segment starts on a ground-truth sample (re-anchored: the
replay starts from the logged pose there) and integrates the encoder increments with the
nominal kinematics of the log's ``meta.json`` — wheel radii, track width, counts per radian,
slope geometry — extended by the *terms* of a model: ``{effect id: parameters}``, where each
parameter object (``slipenv.diagnose.effects.<effect>``) carries its own replay term as the
hooks of :class:`slipenv.diagnose.effects.base.Term`. All segments are integrated at once on
padded arrays (segments × samples), so one replay of a 5-minute, 20 Hz log costs well under a
millisecond.

Per sample interval k (from sample k to k+1), with the terms' hooks in brackets:

1. rim travel of each wheel, d_i = r_i Δφ_i  (``wheel_radius``: ``rolling_radius``);
2. longitudinal slip s_i = Σ of the terms' slips (``slip``: ``torque_slip`` T_i c_side with
   c = 1/k_s; ``soil_patch`` the same inside a disc; ``combined_slip``
   s_x0 + k_β softplus(|β| - β0)), ground travel g_i = d_i - s_i |d_i| (slip in the sense of
   travel, contact-law convention of ``slipenv.terramechanics.contact``);
3. left/right means g_L, g_R, moved by the terms' splits (``split``: ``turning_slip``, Endo's
   split of a yaw discrepancy c = -κ (g_R - g_L): g_L -= f c, g_R += (1 - f) c, Yamauchi
   Eq. 7-8);
4. forward travel ds = (g_L + g_R)/2, in-plane turn dθ = (g_R - g_L)/W (``track_width``: W);
5. lateral travel dl = |ds| tan β with β the sum of the terms' slip angles (``slip_angle``:
   ``slope_side_slip``, β = (β_roll + β_turn |dθ/dt|) roll + β_0, Yamauchi's regression on
   roll with the turning term that makes a skid-steer vehicle slide downhill while it scrubs
   round a turn); none when no term gives one;
6. midpoint integration in the slope plane, mapped to the world by ``geometry.tilt_matrix``.

A 4WS rover (``rover4ws``, steering angles logged) replaces steps 3-4 by
:func:`rover_body_motion`: the body's forward and lateral travel and turn that best explain
every wheel's ground travel along its steered heading with no sideways sliding; the track
width W (``track_width``) sets the wheels' lateral offsets ±W/2.

The gyro channel replays heading from the gyro alone, through the terms' ``gyro_rate``
(``gyro_bias``: b subtracted), for comparison with the ground-truth heading.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from slipenv.diagnose import geometry
from slipenv.diagnose.segments import (
    DURATIONS_S,
    MAX_END_HEADING_RAD,
    MIN_SEGMENTS,
    SUPPORTED_KINDS,
    Segments,
    check_logs,
    cut,
    log_arrays,
    wheel_sides,
)
from slipenv.logs.log import Log

if TYPE_CHECKING:  # for the type only: the effects package loads the envs
    from slipenv.diagnose.effects.base import Term

Model = Mapping[str, "Term"]
"""Effect id -> its parameter object (a ``Term``); ``{}`` is the nominal model."""

__all__ = ["SUPPORTED_KINDS", "Model", "Segments", "build_segments", "check_logs",
           "choose_duration", "heading_residuals", "pose_residuals", "simulate",
           "simulate_gyro_heading", "rover_body_motion", "rover_twist", "slips",
           "wheel_sides"]


def slips(seg: Segments, model: Model, pos: np.ndarray | None = None) -> np.ndarray:
    """Longitudinal slip s_i per interval and wheel, shape (S, L-1, n_wheels) [-].

    ``pos`` (S, L-1, 2) replaces the ground-truth positions for position-dependent terms.
    """
    s = np.zeros(seg.dphi.shape)
    for term in model.values():
        extra = term.slip(seg, seg.pos if pos is None else pos)
        if extra is not None:
            s += extra
    return s


def simulate(seg: Segments, model: Model) -> np.ndarray:
    """Replay every segment with ``model``; predicted x, y, yaw of shape (S, L, 3)."""
    terms = list(model.values())
    radius = seg.radius
    for term in terms:
        radius = term.wheel_radius(seg, radius)
    d = radius[:, None, :] * seg.dphi
    g = d - slips(seg, model) * np.abs(d) if terms else d
    track: np.ndarray | float
    if seg.steer is not None and seg.wheel_x is not None:
        track = seg.track
        for term in terms:
            track = term.track_width(seg, track)
        ds, dlat, dtheta = rover_body_motion(seg, g, track)
        theta = seg.anchor_heading()[:, None] + np.concatenate(
            [np.zeros((len(seg), 1)), np.cumsum(dtheta, axis=1)], axis=1)
        mid = theta[:, :-1] + 0.5 * dtheta
        angles = [b for term in terms if (b := term.slip_angle(seg, ds, dtheta, mid))
                  is not None]
        if angles:
            dlat = dlat + np.abs(ds) * np.tan(sum(angles))
        du = ds * np.cos(mid) - dlat * np.sin(mid)
        dv = ds * np.sin(mid) + dlat * np.cos(mid)
        return _to_world(seg, du, dv, theta)
    left = g[..., seg.sides == 0].mean(axis=-1)
    right = g[..., seg.sides == 1].mean(axis=-1)
    for term in terms:
        left, right = term.split(seg, left, right)
    track = seg.track
    for term in terms:
        track = term.track_width(seg, track)
    track = track[:, None] if isinstance(track, np.ndarray) and track.ndim else track
    ds = 0.5 * (left + right)
    dtheta = (right - left) / track
    theta = seg.anchor_heading()[:, None] + np.concatenate(
        [np.zeros((len(seg), 1)), np.cumsum(dtheta, axis=1)], axis=1)
    mid = theta[:, :-1] + 0.5 * dtheta
    du, dv = ds * np.cos(mid), ds * np.sin(mid)
    angles = [b for term in terms if (b := term.slip_angle(seg, ds, dtheta, mid)) is not None]
    if angles:
        dl = np.abs(ds) * np.tan(sum(angles))
        du, dv = du - dl * np.sin(mid), dv + dl * np.cos(mid)
    return _to_world(seg, du, dv, theta)


def rover_body_motion(seg: Segments, g: np.ndarray, track: np.ndarray | float
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Body forward, lateral travel [m] and turn [rad] per interval of a 4WS rover, (S, L-1).

    Each wheel i at (x_i, ±W/2), steered by δ_i, rolls g_i along its heading and does not
    slide sideways (Reina §2, the kinematic double-Ackermann model the commands come from):
    the contact point's travel (du - y_i dθ, dv + x_i dθ) has component g_i along
    (cos δ_i, sin δ_i) and 0 across. The 2 n equations in (du, dv, dθ) are solved by least
    squares per interval (exact when the wheels agree with one body motion).
    """
    if seg.steer is None or seg.wheel_x is None:
        raise ValueError("a 4WS replay needs the logged steering angles and wheel positions")
    w = np.asarray(track, dtype=float)
    w = w[:, None, None] if w.ndim else w
    y = (0.5 - seg.sides)[None, None, :] * w  # left (side 0) at +W/2
    return rover_twist(g, seg.steer, np.broadcast_to(seg.wheel_x, seg.steer.shape), y)


def rover_twist(g: np.ndarray, steer: np.ndarray, x: np.ndarray, y: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Least-squares body travel (du, dv, dθ) of wheels at body positions (x, y) [m], steered
    by ``steer`` [rad], rolling ``g`` [m] without sideways sliding (arrays (..., n_wheels))."""
    c, s = np.cos(steer), np.sin(steer)
    x, y = np.broadcast_to(x, g.shape), np.broadcast_to(y, g.shape)
    # Rows (c, s, x s - y c) = g_i and (-s, c, x c + y s) = 0: the normal matrix AᵀA does not
    # depend on the steering, [[n, 0, -Σy], [0, n, Σx], [-Σy, Σx, Σ(x² + y²)]]; Aᵀb =
    # (Σ c g, Σ s g, Σ (x s - y c) g).
    n = g.shape[-1]
    sx, sy, sr = x.sum(-1), y.sum(-1), (x * x + y * y).sum(-1)
    t0, t1, t2 = (c * g).sum(-1), (s * g).sum(-1), ((x * s - y * c) * g).sum(-1)
    # eliminate du, dv (rows 1-2), then dθ from row 3
    turn = (t2 + (sy * t0 - sx * t1) / n) / (sr - (sx * sx + sy * sy) / n)
    q = np.stack([(t0 + sy * turn) / n, (t1 - sx * turn) / n, turn], axis=-1)
    return q[..., 0], q[..., 1], q[..., 2]


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


def simulate_gyro_heading(seg: Segments, model: Model) -> np.ndarray:
    """Yaw [rad] from the gyro alone (through the terms' ``gyro_rate``), anchored at segment
    starts, (S, L)."""
    if seg.gyro is None:
        raise ValueError("the log has no gyro_z column")
    rate = seg.gyro
    for term in model.values():
        rate = term.gyro_rate(seg, rate)
    theta = seg.anchor_heading()[:, None] + np.concatenate(
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


def choose_duration(arrays: list[dict], logs: list[Log]) -> float:
    """Segment length [s]: the longest of ``DURATIONS_S`` that still gives ``MIN_SEGMENTS``
    segments and keeps the nominal replay within ``MAX_END_HEADING_RAD`` of the logged heading
    at a segment's end (median).

    A weak effect shows as a drift that grows with the segment (a heading error makes the
    position error grow quadratically) while the noise does not, so longer is better; but a
    strong effect must not turn the nominal replay so far that the wrapped heading residual
    gives the fit local minima, and the held-out comparison needs segments to compare.
    """
    best = DURATIONS_S[0]
    for duration in DURATIONS_S:
        seg = cut(arrays, logs, duration)
        if seg is None or len(seg) < MIN_SEGMENTS:
            break
        last = np.array([np.flatnonzero(row)[-1] for row in seg.gt_ok])
        pred = simulate(seg, {})[np.arange(len(seg)), last, 2]
        err = np.abs(geometry.wrap(pred - seg.gt[np.arange(len(seg)), last, 2]))
        if float(np.median(err)) > MAX_END_HEADING_RAD:
            break
        best = duration
    return best


def build_segments(logs: list[Log], segment_s: float | None = None) -> Segments:
    """Cut the logs into ground-truth-anchored segments and pad them into arrays.

    Parameters
    ----------
    logs : list of Log
    segment_s : float, optional
        Segment length [s]; chosen from the data (:func:`choose_duration`) when None.

    Raises
    ------
    ValueError
        If a log cannot be replayed (``segments.check_logs``) or no segment fits.
    """
    check_logs(logs)
    arrays = [log_arrays(log) for log in logs]
    seg_s = segment_s or choose_duration(arrays, logs)
    seg = cut(arrays, logs, seg_s)
    if seg is None:
        raise ValueError(f"no segment of {seg_s:.1f} s with ground truth at both ends fits in "
                         "the log(s); the log is too short or its ground truth too sparse")
    return seg
