"""The wheels' contact-point history that the rear trace camera renders (Reina §2, Fig. 1b).

A :class:`ContactHistory` records each wheel's true contact point (world frame) and sinkage as
the vehicle drives, thinned to a minimum spacing so a long run stays small; its
:meth:`ContactHistory.tracks` are the :class:`WheelTrack` polylines the camera draws.
:func:`history_from_poses` builds the same tracks from a sequence of chassis poses on flat ground
(rigid-body kinematics, no simulator): for tests and for the geometric baseline.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike


@dataclass(frozen=True, eq=False)
class WheelTrack:
    """One wheel's trace on the ground.

    Attributes
    ----------
    name : str
        Wheel name (e.g. ``"rear_left"``).
    points_m : np.ndarray, shape (n, 3)
        World-frame contact points, oldest first [m].
    width_m : float
        Rut width = wheel width [m].
    depth_m : np.ndarray, shape (n,)
        Sinkage (rut depth) at each point [m], >= 0.
    """

    name: str
    points_m: np.ndarray
    width_m: float
    depth_m: np.ndarray

    def __post_init__(self) -> None:
        pts = np.asarray(self.points_m, dtype=float)
        if pts.ndim != 2 or pts.shape[1] != 3 or not np.all(np.isfinite(pts)):
            raise ValueError(f"WheelTrack {self.name!r}: points_m must be finite, shape (n, 3), "
                             f"got shape {pts.shape}")
        depth = np.broadcast_to(np.asarray(self.depth_m, dtype=float), (len(pts),))
        if not np.all(np.isfinite(depth)) or np.any(depth < 0.0):
            raise ValueError(f"WheelTrack {self.name!r}: depth_m must be finite and >= 0")
        if not (math.isfinite(self.width_m) and self.width_m > 0.0):
            raise ValueError(f"WheelTrack {self.name!r}: width_m must be > 0, got {self.width_m!r}")
        object.__setattr__(self, "points_m", pts)
        object.__setattr__(self, "depth_m", np.array(depth))


class ContactHistory:
    """Per-wheel contact-point recorder, thinned to ``min_spacing_m`` and capped in length.

    Parameters
    ----------
    wheel_names : sequence of str
        Names in the order of the rows passed to :meth:`append`.
    wheel_widths_m : sequence of float
        Rut width per wheel [m].
    min_spacing_m : float
        A point is stored only when it is this far from the wheel's last stored one [m].
    max_points : int
        Points kept per wheel (oldest dropped); 400 × 1 cm covers 4 m of trace.
    """

    def __init__(self, wheel_names: Sequence[str], wheel_widths_m: Sequence[float],
                 min_spacing_m: float = 0.01, max_points: int = 400) -> None:
        if len(wheel_names) != len(wheel_widths_m) or not wheel_names:
            raise ValueError("wheel_names and wheel_widths_m must be non-empty and of equal length")
        if not (math.isfinite(min_spacing_m) and min_spacing_m > 0.0):
            raise ValueError(f"min_spacing_m must be > 0, got {min_spacing_m!r}")
        if int(max_points) < 2:
            raise ValueError(f"max_points must be >= 2, got {max_points!r}")
        self.names = tuple(wheel_names)
        self.widths = tuple(float(w) for w in wheel_widths_m)
        self.min_spacing_m, self.max_points = float(min_spacing_m), int(max_points)
        # Per wheel, the stored points and depths are rows lo..hi-1 of a buffer twice
        # ``max_points`` long, compacted to the front when it fills: ``tracks`` (every camera
        # frame) slices instead of stacking hundreds of small arrays.
        n, capacity = len(self.names), 2 * self.max_points
        self._points = np.empty((n, capacity, 3))
        self._depth = np.empty((n, capacity))
        self._lo, self._hi = [0] * n, [0] * n
        # each wheel's last stored (x, y), NaN before the first: the spacing test of every
        # wheel in one vectorised step (append runs at every control step)
        self._last_xy = np.full((n, 2), np.nan)

    def clear(self) -> None:
        """Forget every stored point (new episode)."""
        self._lo, self._hi = [0] * len(self.names), [0] * len(self.names)
        self._last_xy[:] = np.nan

    def append(self, contact_points_m: ArrayLike, sinkage_m: ArrayLike) -> None:
        """Record one sample: world contact points, shape (n_wheels, 3), and sinkage, (n_wheels,).

        Rows with a NaN (wheel in the air) are skipped.
        """
        pts = np.asarray(contact_points_m, dtype=float)
        sink = np.asarray(sinkage_m, dtype=float)
        if sink.shape != (len(self.names),):
            sink = np.broadcast_to(sink, (len(self.names),))
        if pts.shape != (len(self.names), 3):
            raise ValueError(f"contact_points_m must have shape ({len(self.names)}, 3), "
                             f"got {pts.shape}")
        finite = np.isfinite(pts).all(axis=1) & np.isfinite(sink)
        step = pts[:, :2] - self._last_xy
        # NaN distance (no point stored yet) is not "too close": the first point is stored
        too_close = np.hypot(step[:, 0], step[:, 1]) < self.min_spacing_m
        for i in np.flatnonzero(finite & ~too_close):
            lo, hi = self._lo[i], self._hi[i]
            if hi == self._points.shape[1]:  # buffer full: move the kept points to the front
                self._points[i, :hi - lo] = self._points[i, lo:hi]
                self._depth[i, :hi - lo] = self._depth[i, lo:hi]
                lo, hi = 0, hi - lo
            self._points[i, hi] = pts[i]
            self._depth[i, hi] = max(float(sink[i]), 0.0)
            hi += 1
            self._lo[i], self._hi[i] = max(lo, hi - self.max_points), hi
            self._last_xy[i] = pts[i, :2]

    def tracks(self) -> tuple[WheelTrack, ...]:
        """The wheels' traces with at least two points."""
        return tuple(
            WheelTrack(name, self._points[i, lo:hi].copy(), width, self._depth[i, lo:hi])
            for i, (name, width, lo, hi) in enumerate(zip(self.names, self.widths, self._lo,
                                                          self._hi, strict=True))
            if hi - lo >= 2
        )


def history_from_poses(
    poses: ArrayLike,
    wheel_xy_body_m: dict[str, tuple[float, float]],
    wheel_width_m: float,
    sinkage_m: float,
    ground_z_m: float = 0.0,
) -> tuple[WheelTrack, ...]:
    """Wheel traces of a rigid chassis driven through ``poses`` on flat ground.

    Parameters
    ----------
    poses : array_like, shape (n, 3)
        Chassis (x, y, yaw) in the world, oldest first [m, m, rad].
    wheel_xy_body_m : dict
        Wheel name -> contact point (x, y) in the body frame [m].
    wheel_width_m, sinkage_m : float
        Rut width and depth [m].
    ground_z_m : float
        World height of the ground [m].
    """
    p = np.asarray(poses, dtype=float)
    if p.ndim != 2 or p.shape[1] != 3 or len(p) < 2 or not np.all(np.isfinite(p)):
        raise ValueError(f"poses must be finite with shape (n >= 2, 3), got {p.shape}")
    c, s = np.cos(p[:, 2]), np.sin(p[:, 2])
    out = []
    for name, (bx, by) in wheel_xy_body_m.items():
        pts = np.column_stack([p[:, 0] + c * bx - s * by, p[:, 1] + s * bx + c * by,
                               np.full(len(p), float(ground_z_m))])
        out.append(WheelTrack(name, pts, float(wheel_width_m), np.full(len(p), float(sinkage_m))))
    return tuple(out)
