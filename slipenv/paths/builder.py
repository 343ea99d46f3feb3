"""Chain segments tangentially from a start pose ("turtle" style).

Each call appends segments that start where, and heading the way, the previous one ended, so
the resulting :class:`~slipenv.paths.path.Path` is continuous by construction. Speeds follow
Lindgren §2.3: each call may give a final speed, reached with constant acceleration from the
current one.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from slipenv.paths import _validate as check
from slipenv.paths.path import Path
from slipenv.paths.segments import Arc, Line, Segment
from slipenv.paths.spline import QuadraticSpline

Point = tuple[float, float]


class PathBuilder:
    """Build a path piece by piece.

    Parameters
    ----------
    x_m, y_m : float
        Start position [m].
    heading_rad : float
        Start heading, counter-clockwise from world x [rad].
    speed_mps : float
        Reference speed at the start [m/s] (>= 0; 0 starts from rest).

    Examples
    --------
    >>> path = PathBuilder(speed_mps=1.0).line(5.0).arc(2.0, math.pi).line(5.0).build()
    """

    def __init__(self, x_m: float = 0.0, y_m: float = 0.0, heading_rad: float = 0.0,
                 speed_mps: float = 1.0) -> None:
        self.x_m = check.finite("x_m", x_m)
        self.y_m = check.finite("y_m", y_m)
        self.heading_rad = check.finite("heading_rad", heading_rad)
        self.speed_mps = check.non_negative("speed_mps", speed_mps)
        self.segments: list[Segment] = []

    def _final_speed(self, speed_mps: float | None) -> float:
        return self.speed_mps if speed_mps is None else check.non_negative("speed_mps", speed_mps)

    def _append(self, seg: Segment) -> PathBuilder:
        self.segments.append(seg)
        self.x_m, self.y_m = seg.point(seg.length_m)
        self.heading_rad = seg.heading(seg.length_m)
        self.speed_mps = seg.v1_mps
        return self

    def _local(self, forward_m: float, left_m: float) -> Point:
        """World point at ``forward_m`` ahead and ``left_m`` left of the current pose."""
        c, s = math.cos(self.heading_rad), math.sin(self.heading_rad)
        return self.x_m + c * forward_m - s * left_m, self.y_m + s * forward_m + c * left_m

    def line(self, length_m: float, speed_mps: float | None = None) -> PathBuilder:
        """Straight line of ``length_m`` [m] along the current heading."""
        length_m = check.positive("length_m", length_m)
        end = self._local(length_m, 0.0)
        return self._append(Line((self.x_m, self.y_m), end, self.speed_mps,
                                 self._final_speed(speed_mps)))

    def arc(self, radius_m: float, angle_rad: float, clockwise: bool = False,
            speed_mps: float | None = None) -> PathBuilder:
        """Circular arc of ``radius_m`` [m] turning by ``angle_rad`` > 0 [rad] (may exceed 2 pi).

        ``clockwise=False`` turns left (centre on the left of the current heading).
        """
        radius_m = check.positive("radius_m", radius_m)
        angle_rad = check.positive("angle_rad", angle_rad)
        sigma = -1.0 if clockwise else 1.0
        center = self._local(0.0, sigma * radius_m)
        start_angle = self.heading_rad - sigma * 0.5 * math.pi
        return self._append(Arc(center, radius_m, start_angle, angle_rad, clockwise,
                                self.speed_mps, self._final_speed(speed_mps)))

    def splines(self, control_points: Sequence[tuple[Point, Point]],
                speed_mps: float | None = None) -> PathBuilder:
        """Quadratic splines through ``[(control, end), ...]`` in world coordinates [m].

        The first control point must lie ahead along the current heading, and each joint must
        be collinear with its neighbouring control points, or ``Path`` reports a corner. The
        speed changes with one constant acceleration over the whole chain.
        """
        if not control_points:
            raise ValueError("control_points must hold at least one (control, end) pair")
        v0, v1 = self.speed_mps, self._final_speed(speed_mps)
        probe_speed = max(v0, v1)
        geometry: list[tuple[Point, Point, Point]] = []
        start: Point = (self.x_m, self.y_m)
        for k, (control, end) in enumerate(control_points):
            control = check.point(f"control_points[{k}][0]", control)
            end = check.point(f"control_points[{k}][1]", end)
            geometry.append((start, control, end))
            start = end
        lengths = [QuadraticSpline(*g, probe_speed, probe_speed).length_m for g in geometry]
        total, done = sum(lengths), 0.0
        for g, length in zip(geometry, lengths, strict=True):
            done += length
            v_end = math.sqrt(v0**2 + (v1**2 - v0**2) * min(done / total, 1.0))
            self._append(QuadraticSpline(*g, self.speed_mps, v_end))
        return self

    def s_bend(self, forward_m: float, left_m: float,
               speed_mps: float | None = None) -> PathBuilder:
        """Lateral shift by ``left_m`` [m] (< 0: right) over ``forward_m`` [m] with two
        quadratic splines; the heading at the end equals the heading at the start.

        Control points at a quarter and three quarters of the way make the joint (the midpoint)
        collinear with them, so the tangent is continuous.
        """
        forward_m = check.positive("forward_m", forward_m)
        left_m = check.finite("left_m", left_m)
        pts = [self._local(f * forward_m, w * left_m)
               for f, w in ((0.25, 0.0), (0.5, 0.5), (0.75, 1.0), (1.0, 1.0))]
        return self.splines([(pts[0], pts[1]), (pts[2], pts[3])], speed_mps)

    def u_turn(self, width_m: float, depth_m: float, left: bool = True,
               speed_mps: float | None = None) -> PathBuilder:
        """180° headland turn with two quadratic splines.

        Ends ``width_m`` [m] to the side (left if ``left``) heading the opposite way, reaching
        ``depth_m`` [m] beyond the start. The apex is the midpoint between the two control
        points, so the tangent is continuous there.
        """
        width_m = check.positive("width_m", width_m)
        depth_m = check.positive("depth_m", depth_m)
        side = 1.0 if left else -1.0
        pts = [self._local(f, side * w) for f, w in ((depth_m, 0.0), (depth_m, 0.5 * width_m),
                                                   (depth_m, width_m), (0.0, width_m))]
        return self.splines([(pts[0], pts[1]), (pts[2], pts[3])], speed_mps)

    def build(self, name: str = "", **path_kw: float) -> Path:
        """The finished :class:`Path` (``path_kw`` go to its constructor)."""
        return Path(self.segments, name=name, **path_kw)
