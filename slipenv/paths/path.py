"""A path: a continuous chain of segments with a speed profile, and its projection.

``Path.project`` is what the environment calls every control step to turn an (estimated)
position into the path-relative quantities of the observation: arc length, signed cross-track
error, path heading, curvature and reference speed.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Sequence
from typing import NamedTuple

import numpy as np

from slipenv.contracts import wrap_angle
from slipenv.paths import _validate as check
from slipenv.paths.segments import Nearest, Segment

CONTINUITY_TOL_M = 1e-6  # [m] largest gap allowed between one segment's end and the next start
CONTINUITY_TOL_RAD = 1e-6  # [rad] largest heading jump allowed at a joint (no corners)
CONTINUITY_TOL_MPS = 1e-9  # [m/s] largest jump of the reference speed at a joint
MAX_SEARCH_WINDOW_M = 4.0  # [m] cap on the local search window of ``project``
BOUNDS_MARGIN_M = 1e-9  # [m] segment boxes are grown by this (>> rounding of the curve points)


class PathProjection(NamedTuple):
    """Where a point lies relative to a path.

    Attributes
    ----------
    s : float
        Arc length of the nearest path point from the path start [m].
    cross_track_m : float
        Signed lateral offset of the query point from the path [m]; > 0 when the point is LEFT
        of the path (looking along the direction of travel).
    heading_rad : float
        Path heading at ``s``, counter-clockwise from world x [rad], in [-pi, pi] (atan2).
    curvature_1pm : float
        Path curvature at ``s`` [1/m]; > 0 when the path turns left.
    speed_mps : float
        Reference speed at ``s`` [m/s].
    remaining_m : float
        Path length still ahead, ``length_m - s`` [m].
    """

    s: float
    cross_track_m: float
    heading_rad: float
    curvature_1pm: float
    speed_mps: float
    remaining_m: float


class PathSamples(NamedTuple):
    """A path sampled at arc lengths ``s_m``; every field an array of shape (n,)."""

    s_m: np.ndarray
    x_m: np.ndarray
    y_m: np.ndarray
    heading_rad: np.ndarray
    curvature_1pm: np.ndarray
    speed_mps: np.ndarray
    time_s: np.ndarray


class Path:
    """A sequence of segments traversed in order (Lindgren §2.3).

    Parameters
    ----------
    segments : sequence of Segment
        At least one. Consecutive segments must join within ``CONTINUITY_TOL_M`` (1 µm) in
        position, ``CONTINUITY_TOL_RAD`` (1 µrad) in heading and ``CONTINUITY_TOL_MPS`` in
        reference speed; otherwise ``ValueError`` names the joint.
    search_back_m, search_ahead_m : float, optional
        Local search window of :meth:`project` around the hint [m]. By default the window
        spans ``E = min(4 m, 0.9 pi r_min)`` (``r_min`` the smallest radius of curvature on the
        path), a quarter behind and three quarters ahead. A curve shorter than ``pi r_min``
        turns by less than pi and so cannot meet itself: the window never holds two branches
        of a self-crossing. The vehicle must move less than ``search_ahead_m`` between calls.
    name : str
        Label used in ``repr`` and plots.
    """

    def __init__(self, segments: Sequence[Segment], *, search_back_m: float | None = None,
                 search_ahead_m: float | None = None, name: str = "") -> None:
        segs = tuple(segments)
        if not segs:
            raise ValueError("segments must hold at least one segment")
        for i, (a, b) in enumerate(zip(segs[:-1], segs[1:], strict=True)):
            (xa, ya), (xb, yb) = a.point(a.length_m), b.point(0.0)
            gap = math.hypot(xb - xa, yb - ya)
            if gap > CONTINUITY_TOL_M:
                raise ValueError(f"segments {i} and {i + 1} do not join: gap {gap:.3g} m")
            turn = abs(wrap_angle(b.heading(0.0) - a.heading(a.length_m)))
            if turn > CONTINUITY_TOL_RAD:
                raise ValueError(f"segments {i} and {i + 1} meet at a corner of {turn:.3g} rad")
            if abs(a.v1_mps - b.v0_mps) > CONTINUITY_TOL_MPS:
                raise ValueError(f"segments {i} and {i + 1}: speed jumps from {a.v1_mps} to "
                                 f"{b.v0_mps} m/s")
        self.segments = segs
        self.name = name
        starts, t_starts = [0.0], [0.0]
        for seg in segs:
            starts.append(starts[-1] + seg.length_m)
            t_starts.append(t_starts[-1] + seg.duration_s)
        self._starts, self._t_starts = starts, t_starts
        # Per segment, its box grown by BOUNDS_MARGIN_M (None: no box): ``project`` skips a
        # segment that cannot hold a nearer point than the best one so far.
        self._boxes = [_grown(seg.bounds()) for seg in segs]
        self.length_m = starts[-1]
        self.duration_s = t_starts[-1]
        kappa_max = max(seg.max_abs_curvature_1pm for seg in segs)
        self.max_curvature_1pm = kappa_max
        extent = MAX_SEARCH_WINDOW_M if kappa_max == 0.0 else min(MAX_SEARCH_WINDOW_M,
                                                                  0.9 * math.pi / kappa_max)
        self.search_back_m = (0.25 * extent if search_back_m is None
                              else check.positive("search_back_m", search_back_m))
        self.search_ahead_m = (0.75 * extent if search_ahead_m is None
                               else check.positive("search_ahead_m", search_ahead_m))

    def __repr__(self) -> str:
        return (f"Path({self.name!r}, {len(self.segments)} segments, "
                f"{self.length_m:.3f} m, {self.duration_s:.1f} s)")

    @property
    def min_turning_radius_m(self) -> float:
        """Smallest radius of curvature along the path [m] (``inf`` for a straight path)."""
        return math.inf if self.max_curvature_1pm == 0.0 else 1.0 / self.max_curvature_1pm

    @property
    def max_speed_mps(self) -> float:
        """Highest reference speed along the path [m/s] (each segment's speed changes
        monotonically, so its largest value is at one of its ends)."""
        return max(max(seg.v0_mps, seg.v1_mps) for seg in self.segments)

    @property
    def max_yaw_rate_rps(self) -> float:
        """An upper bound on the yaw rate the reference demands, max |speed x curvature|
        [rad/s], taken segment by segment (exact on lines and arcs, which have one curvature).
        """
        return max(max(seg.v0_mps, seg.v1_mps) * seg.max_abs_curvature_1pm
                   for seg in self.segments)

    def extent(self) -> tuple[float, float, float, float]:
        """A box ``(x_min, y_min, x_max, y_max)`` [m] holding every point of the path (the
        union of the segments' boxes, so it may be loose; a segment without a box is
        sampled every centimetre or every thousandth of its length)."""
        boxes = []
        for seg in self.segments:
            box = seg.bounds()
            if box is None:
                ds = max(seg.length_m / 1000.0, 0.01)
                pts = np.array([seg.point(min(k * ds, seg.length_m))
                                for k in range(math.ceil(seg.length_m / ds) + 1)])
                box = (*pts.min(axis=0), *pts.max(axis=0))
            boxes.append(box)
        b = np.array(boxes, dtype=float)
        return (float(b[:, 0].min()), float(b[:, 1].min()), float(b[:, 2].max()),
                float(b[:, 3].max()))

    def locate(self, s: float) -> tuple[int, float]:
        """Segment index and segment-local arc length for path arc length ``s`` (clamped)."""
        s = min(max(s, 0.0), self.length_m)
        i = min(bisect_right(self._starts, s) - 1, len(self.segments) - 1)
        return i, s - self._starts[i]

    def pose_at(self, s: float) -> tuple[float, float, float]:
        """``(x [m], y [m], heading [rad])`` at arc length ``s`` [m] (clamped to the path)."""
        i, ds = self.locate(s)
        x, y = self.segments[i].point(ds)
        return x, y, self.segments[i].heading(ds)

    def curvature_at(self, s: float) -> float:
        """Curvature [1/m] at arc length ``s``; > 0 turning left."""
        i, ds = self.locate(s)
        return self.segments[i].curvature(ds)

    def speed_at(self, s: float) -> float:
        """Reference speed [m/s] at arc length ``s``."""
        i, ds = self.locate(s)
        return self.segments[i].speed(ds)

    def time_at(self, s: float) -> float:
        """Time [s] to reach arc length ``s`` following the reference speed profile."""
        i, ds = self.locate(s)
        return self._t_starts[i] + self.segments[i].time(ds)

    def start_pose(self) -> tuple[float, float, float]:
        """``(x, y, heading)`` at the path start [m, m, rad]."""
        return self.pose_at(0.0)

    def end_pose(self) -> tuple[float, float, float]:
        """``(x, y, heading)`` at the path end [m, m, rad]."""
        return self.pose_at(self.length_m)

    def project(self, x: float, y: float, s_hint: float | None = None) -> PathProjection:
        """Project the point ``(x, y)`` [m] onto the path.

        Parameters
        ----------
        x, y : float
            Query position [m], world frame.
        s_hint : float, optional
            Arc length of the previous projection [m]. When given, only
            ``[s_hint - search_back_m, s_hint + search_ahead_m]`` is searched, so a path that
            crosses itself is followed along its branches instead of jumping between them.
            Without it the whole path is searched and ties go to the smallest ``s``.

        Returns
        -------
        PathProjection
            ``cross_track_m`` is the offset along the path's left normal at the nearest point
            (beyond the path ends: the lateral part of the offset from the end point).
        """
        if s_hint is None:
            lo, hi = 0.0, self.length_m
        else:
            s_hint = min(max(float(s_hint), 0.0), self.length_m)
            lo = max(s_hint - self.search_back_m, 0.0)
            hi = min(s_hint + self.search_ahead_m, self.length_m)
        starts, segs, boxes = self._starts, self.segments, self._boxes
        i = min(bisect_right(starts, lo) - 1, len(segs) - 1)
        best: Nearest | None = None
        best_i = i
        while i < len(segs) and starts[i] <= hi:
            box = boxes[i]
            if best is not None and box is not None:
                # Squared distance to the segment's (grown) box: a lower bound on any d2 the
                # segment can return (exact arithmetic; the 1e-12 relative slack covers the
                # rounding of both). Above the best d2 the segment cannot replace the best (it
                # would need d2 < best.d2 - 1e-12), so skipping it leaves the result unchanged.
                dx = max(box[0] - x, 0.0, x - box[2])
                dy = max(box[1] - y, 0.0, y - box[3])
                if (dx * dx + dy * dy) * (1.0 - 1e-12) > best.d2:
                    i += 1
                    continue
            s0 = starts[i]
            seg = segs[i]
            near = seg.nearest(x, y, max(lo - s0, 0.0), min(hi - s0, seg.length_m))
            if best is None or near.d2 < best.d2 - 1e-12:
                best, best_i = near, i
            i += 1
        assert best is not None
        s = starts[best_i] + best.s
        cross = (y - best.y) * best.tx - (x - best.x) * best.ty  # offset . left normal
        return PathProjection(s, cross, math.atan2(best.ty, best.tx), best.kappa,
                              segs[best_i].speed(best.s), self.length_m - s)

    def sample(self, ds_m: float = 0.05) -> PathSamples:
        """Sample the path every ``ds_m`` [m] (both ends included); see :func:`sample_path`."""
        return sample_path(self, ds_m)


def _grown(box: tuple[float, float, float, float] | None
           ) -> tuple[float, float, float, float] | None:
    if box is None:
        return None
    m = BOUNDS_MARGIN_M
    return box[0] - m, box[1] - m, box[2] + m, box[3] + m


def sample_path(path: Path, ds_m: float = 0.05) -> PathSamples:
    """Sample a path as arrays for plotting or analysis.

    Parameters
    ----------
    path : Path
    ds_m : float
        Largest spacing between samples [m]; samples are evenly spaced and include both ends.

    Returns
    -------
    PathSamples
        Arrays of shape (n,) with n = ceil(length / ds_m) + 1.
    """
    ds_m = check.positive("ds_m", ds_m)
    n = math.ceil(path.length_m / ds_m) + 1
    s = np.linspace(0.0, path.length_m, n)
    out = np.empty((6, n))
    for k, sk in enumerate(s):
        i, ds = path.locate(float(sk))
        seg = path.segments[i]
        out[0, k], out[1, k] = seg.point(ds)
        out[2, k] = seg.heading(ds)
        out[3, k] = seg.curvature(ds)
        out[4, k] = seg.speed(ds)
        out[5, k] = path.time_at(float(sk))
    return PathSamples(s, *out)
