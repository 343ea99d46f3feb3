"""Path segments of Lindgren §2.3: the segment contract, straight lines and circular arcs.

"Commanded paths for the vehicle may be composed of multiple segments, which may each take the
form of a straight line, circular arc or quadratic spline. The segments are specified by the
cartesian coordinates of their end points plus an additional control point where necessary,
and the initial and final speeds. Where the speeds differ, a constant acceleration is used."
(Lindgren §2.3)

The quadratic spline lives in :mod:`slipenv.paths.spline`.

Every segment is parametrised by arc length ``s`` in [0, length_m] and evaluated with scalar
``math`` (the projection runs every control step; small numpy arrays would cost more than the
arithmetic). Headings are counter-clockwise from world x [rad]; curvature is > 0 for a left
(counter-clockwise) turn [1/m].
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from dataclasses import dataclass, field
from typing import NamedTuple

from slipenv.paths import _validate as check

TWO_PI = 2.0 * math.pi


class Nearest(NamedTuple):
    """Nearest point of a segment to a query point (segment-local arc length)."""

    d2: float  # squared distance [m^2]
    s: float  # arc length from the segment start [m]
    x: float  # nearest point [m]
    y: float
    tx: float  # unit tangent there
    ty: float
    kappa: float  # curvature there [1/m]


class Segment(ABC):
    """One piece of a path, traversed with constant acceleration from ``v0_mps`` to ``v1_mps``.

    Subclasses provide ``length_m``, ``v0_mps``, ``v1_mps`` and the geometry methods.
    """

    length_m: float
    v0_mps: float
    v1_mps: float

    @abstractmethod
    def point(self, s: float) -> tuple[float, float]:
        """Position ``(x, y)`` [m] at arc length ``s`` [m] from the segment start."""

    @abstractmethod
    def tangent(self, s: float) -> tuple[float, float]:
        """Unit tangent ``(cos, sin)`` of the heading at arc length ``s`` [m]."""

    @abstractmethod
    def curvature(self, s: float) -> float:
        """Signed curvature [1/m] at ``s``; > 0 turning left (counter-clockwise)."""

    @abstractmethod
    def nearest(self, x: float, y: float, s_lo: float, s_hi: float) -> Nearest:
        """Nearest point to ``(x, y)`` among arc lengths in ``[s_lo, s_hi]`` (within the segment).

        Ties between equally near points (a full circle seen from its centre) go to the
        smallest ``s``.
        """

    @property
    @abstractmethod
    def max_abs_curvature_1pm(self) -> float:
        """Largest |curvature| along the segment [1/m]."""

    def bounds(self) -> tuple[float, float, float, float] | None:
        """An axis-aligned box ``(x_min, y_min, x_max, y_max)`` [m] holding every point of the
        segment, or None if the segment gives none (:meth:`Path.project` then always searches
        it). The box may be loose; it must never cut the segment."""
        return None

    def heading(self, s: float) -> float:
        """Heading of the tangent at ``s`` [rad], in [-pi, pi] (atan2)."""
        tx, ty = self.tangent(s)
        return math.atan2(ty, tx)

    # Speed profile: constant acceleration a = (v1^2 - v0^2) / (2 L), so v(s)^2 = v0^2 + 2 a s.
    @property
    def accel_mps2(self) -> float:
        """Constant acceleration along the segment [m/s^2]."""
        return (self.v1_mps**2 - self.v0_mps**2) / (2.0 * self.length_m)

    @property
    def duration_s(self) -> float:
        """Time to traverse the segment [s]: 2 L / (v0 + v1) under constant acceleration."""
        return 2.0 * self.length_m / (self.v0_mps + self.v1_mps)

    def speed(self, s: float) -> float:
        """Reference speed [m/s] at arc length ``s``: sqrt(v0^2 + 2 a s)."""
        return math.sqrt(max(self.v0_mps**2 + 2.0 * self.accel_mps2 * s, 0.0))

    def time(self, s: float) -> float:
        """Time [s] to reach arc length ``s`` from the segment start: (v(s) - v0) / a."""
        a = self.accel_mps2
        if abs(a) * self.length_m < 1e-12 * self.v0_mps**2:
            return s / self.v0_mps
        return (self.speed(s) - self.v0_mps) / a


@dataclass(frozen=True)
class Line(Segment):
    """Straight line from ``start`` to ``end`` [m]."""

    start: tuple[float, float]
    end: tuple[float, float]
    v0_mps: float
    v1_mps: float
    length_m: float = field(init=False)
    _u: tuple[float, float] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        start, end = check.point("start", self.start), check.point("end", self.end)
        length = math.hypot(end[0] - start[0], end[1] - start[1])
        if length <= 0.0:
            raise ValueError(f"end must differ from start (zero-length segment at {start})")
        v0, v1 = check.speeds(self.v0_mps, self.v1_mps)
        u = ((end[0] - start[0]) / length, (end[1] - start[1]) / length)
        for name, value in (("start", start), ("end", end), ("v0_mps", v0), ("v1_mps", v1),
                            ("length_m", length), ("_u", u)):
            object.__setattr__(self, name, value)

    def point(self, s: float) -> tuple[float, float]:
        return self.start[0] + self._u[0] * s, self.start[1] + self._u[1] * s

    def tangent(self, s: float) -> tuple[float, float]:
        return self._u

    def curvature(self, s: float) -> float:
        return 0.0

    @property
    def max_abs_curvature_1pm(self) -> float:
        return 0.0

    def bounds(self) -> tuple[float, float, float, float]:
        (x0, y0), (x1, y1) = self.start, self.end
        return min(x0, x1), min(y0, y1), max(x0, x1), max(y0, y1)

    def nearest(self, x: float, y: float, s_lo: float, s_hi: float) -> Nearest:
        ux, uy = self._u
        s = (x - self.start[0]) * ux + (y - self.start[1]) * uy
        s = min(max(s, s_lo), s_hi)
        px, py = self.start[0] + ux * s, self.start[1] + uy * s
        return Nearest((x - px) ** 2 + (y - py) ** 2, s, px, py, ux, uy, 0.0)


@dataclass(frozen=True)
class Arc(Segment):
    """Circular arc about ``center`` [m] of ``radius_m``, starting at polar angle
    ``start_angle_rad`` about the centre and sweeping ``sweep_rad`` > 0 (may exceed 2 pi for
    repeated loops), clockwise or counter-clockwise.
    """

    center: tuple[float, float]
    radius_m: float
    start_angle_rad: float
    sweep_rad: float
    clockwise: bool
    v0_mps: float
    v1_mps: float
    length_m: float = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "center", check.point("center", self.center))
        object.__setattr__(self, "radius_m", check.positive("radius_m", self.radius_m))
        object.__setattr__(self, "start_angle_rad",
                           check.finite("start_angle_rad", self.start_angle_rad))
        object.__setattr__(self, "sweep_rad", check.positive("sweep_rad", self.sweep_rad))
        v0, v1 = check.speeds(self.v0_mps, self.v1_mps)
        object.__setattr__(self, "v0_mps", v0)
        object.__setattr__(self, "v1_mps", v1)
        object.__setattr__(self, "length_m", self.radius_m * self.sweep_rad)

    @property
    def _sigma(self) -> float:
        return -1.0 if self.clockwise else 1.0

    def point(self, s: float) -> tuple[float, float]:
        th = self.start_angle_rad + self._sigma * s / self.radius_m
        return (self.center[0] + self.radius_m * math.cos(th),
                self.center[1] + self.radius_m * math.sin(th))

    def tangent(self, s: float) -> tuple[float, float]:
        sig = self._sigma
        th = self.start_angle_rad + sig * s / self.radius_m
        return -sig * math.sin(th), sig * math.cos(th)

    def curvature(self, s: float) -> float:
        return self._sigma / self.radius_m

    @property
    def max_abs_curvature_1pm(self) -> float:
        return 1.0 / self.radius_m

    def bounds(self) -> tuple[float, float, float, float]:
        (cx, cy), r = self.center, self.radius_m  # the whole circle's box
        return cx - r, cy - r, cx + r, cy + r

    def nearest(self, x: float, y: float, s_lo: float, s_hi: float) -> Nearest:
        r, sig = self.radius_m, self._sigma
        # The nearest point of the full circle lies at the query's polar angle; unroll it to
        # the first loop at or after s_lo. Window ends are the other candidates.
        u = (sig * (math.atan2(y - self.center[1], x - self.center[0]) - self.start_angle_rad))
        s_c = r * (u % TWO_PI)
        if s_c < s_lo:
            s_c += r * TWO_PI * math.ceil((s_lo - s_c) / (r * TWO_PI))
        candidates = (s_c, s_lo, s_hi) if s_c <= s_hi else (s_lo, s_hi)
        best: tuple[float, float, float, float] | None = None  # (d2, s, px, py)
        for s in candidates:
            px, py = self.point(s)
            d2 = (x - px) ** 2 + (y - py) ** 2
            if best is None or d2 < best[0]:
                best = (d2, s, px, py)
        assert best is not None
        return Nearest(*best, *self.tangent(best[1]), sig / r)  # tangent of the winner only
