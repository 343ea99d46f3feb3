"""Quadratic (Bézier) spline segment of Lindgren §2.3: two end points plus one control point.

Arc length has no convenient closed form here, so it is tabulated by Gauss-Legendre
quadrature and inverted by Newton's method; the nearest point to a query solves a cubic.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from dataclasses import dataclass, field

from slipenv.paths import _validate as check
from slipenv.paths.segments import TWO_PI, Nearest, Segment

# Gauss-Legendre 5-point rule on [-1, 1]: exact for polynomials up to degree 9.
_GL_X = (-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640)
_GL_W = (0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
         0.2369268850561891)
_GL_XW = tuple(zip(_GL_X, _GL_W, strict=True))
_N_TABLE = 32  # arc-length table intervals in t


@dataclass(frozen=True)
class QuadraticSpline(Segment):
    """Quadratic Bézier spline B(t) = (1-t)^2 P0 + 2 t (1-t) P1 + t^2 P2, t in [0, 1].

    ``start`` (P0) and ``end`` (P2) are the end points and ``control`` (P1) the control point
    (Lindgren §2.3); the tangent at each end points along the control polygon. The arc length
    s(t) = ∫ |B'(t)| dt is tabulated with Gauss-Legendre quadrature (32 intervals, 5 points:
    error far below 1e-9 m for any spline without a near-cusp) and inverted by Newton's method.
    """

    start: tuple[float, float]
    control: tuple[float, float]
    end: tuple[float, float]
    v0_mps: float
    v1_mps: float
    length_m: float = field(init=False)
    _ab: tuple[float, float, float, float] = field(init=False, repr=False)
    _s_table: tuple[float, ...] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        p0, p1 = check.point("start", self.start), check.point("control", self.control)
        p2 = check.point("end", self.end)
        if p0 == p2:
            raise ValueError(f"end must differ from start (zero-length spline at {p0})")
        v0, v1 = check.speeds(self.v0_mps, self.v1_mps)
        for name, value in (("start", p0), ("control", p1), ("end", p2),
                            ("v0_mps", v0), ("v1_mps", v1)):
            object.__setattr__(self, name, value)
        # A = P1 - P0 and B = P0 - 2 P1 + P2, so B'(t) = 2 (A + t B) and B'' = 2 B.
        ax, ay = p1[0] - p0[0], p1[1] - p0[1]
        bx, by = p0[0] - 2.0 * p1[0] + p2[0], p0[1] - 2.0 * p1[1] + p2[1]
        object.__setattr__(self, "_ab", (ax, ay, bx, by))
        bb = bx * bx + by * by
        t_min = min(max(-(ax * bx + ay * by) / bb, 0.0), 1.0) if bb > 0.0 else 0.0
        if math.hypot(ax + t_min * bx, ay + t_min * by) <= 1e-9 * math.hypot(p2[0] - p0[0],
                                                                             p2[1] - p0[1]):
            raise ValueError(f"control {p1} makes the spline stop and reverse (a cusp, or the "
                             "control point on an end point): its tangent is undefined there")
        table = [0.0]
        for i in range(_N_TABLE):
            table.append(table[-1] + self._integral(i / _N_TABLE, (i + 1) / _N_TABLE))
        object.__setattr__(self, "_s_table", tuple(table))
        object.__setattr__(self, "length_m", table[-1])

    def _speed_t(self, t: float) -> float:
        """|dB/dt| [m per unit t]."""
        ax, ay, bx, by = self._ab
        return 2.0 * math.hypot(ax + t * bx, ay + t * by)

    def _integral(self, t0: float, t1: float) -> float:
        """∫ |B'(t)| dt from ``t0`` to ``t1`` by five-point Gauss-Legendre quadrature."""
        half, mid = 0.5 * (t1 - t0), 0.5 * (t1 + t0)
        return half * sum(w * self._speed_t(mid + half * x) for x, w in _GL_XW)

    def s_of_t(self, t: float) -> float:
        """Arc length [m] from the start to parameter ``t``."""
        i = min(int(t * _N_TABLE), _N_TABLE - 1)
        return self._s_table[i] + self._integral(i / _N_TABLE, t)

    def t_of_s(self, s: float, newton: bool = True) -> float:
        """Bézier parameter at arc length ``s`` [m] (table interpolation, then Newton)."""
        table = self._s_table
        s = min(max(s, 0.0), self.length_m)
        i = min(bisect_right(table, s) - 1, _N_TABLE - 1)
        t = (i + (s - table[i]) / (table[i + 1] - table[i])) / _N_TABLE
        for _ in range(8 if newton else 0):
            dt = (self.s_of_t(t) - s) / self._speed_t(t)
            t = min(max(t - dt, 0.0), 1.0)
            if abs(dt) < 1e-14:
                break
        return t

    def _eval(self, t: float) -> tuple[float, float, float, float, float]:
        """Point, unit tangent and curvature at parameter ``t``."""
        ax, ay, bx, by = self._ab
        x0, y0 = self.start
        dx, dy = ax + t * bx, ay + t * by
        norm = math.hypot(dx, dy)
        kappa = (ax * by - ay * bx) / (2.0 * norm**3)  # (B' x B'') / |B'|^3
        return (x0 + t * (2.0 * ax + t * bx), y0 + t * (2.0 * ay + t * by),
                dx / norm, dy / norm, kappa)

    def point(self, s: float) -> tuple[float, float]:
        x, y, *_ = self._eval(self.t_of_s(s))
        return x, y

    def tangent(self, s: float) -> tuple[float, float]:
        _, _, tx, ty, _ = self._eval(self.t_of_s(s))
        return tx, ty

    def curvature(self, s: float) -> float:
        return self._eval(self.t_of_s(s))[4]

    @property
    def max_abs_curvature_1pm(self) -> float:
        ax, ay, bx, by = self._ab
        bb = bx * bx + by * by
        t_min = min(max(-(ax * bx + ay * by) / bb, 0.0), 1.0) if bb > 0.0 else 0.0
        return abs(self._eval(t_min)[4])

    def bounds(self) -> tuple[float, float, float, float]:
        # A Bézier curve lies in the convex hull of its control points, so in their box.
        xs, ys = (self.start[0], self.control[0], self.end[0]), (self.start[1], self.control[1],
                                                                 self.end[1])
        return min(xs), min(ys), max(xs), max(ys)

    def nearest(self, x: float, y: float, s_lo: float, s_hi: float) -> Nearest:
        # Window ends mapped to t by table interpolation (exact at 0 and L; a soft bound
        # elsewhere). Interior minima solve (B(t) - p) . B'(t) = 0, a cubic in t.
        t_lo = self.t_of_s(s_lo, newton=False)
        t_hi = self.t_of_s(s_hi, newton=False)
        ax, ay, bx, by = self._ab
        dx, dy = self.start[0] - x, self.start[1] - y
        roots = _real_cubic_roots(bx * bx + by * by, 3.0 * (ax * bx + ay * by),
                                  2.0 * (ax * ax + ay * ay) + dx * bx + dy * by,
                                  dx * ax + dy * ay)
        best: tuple[float, float] | None = None
        for t in (t_lo, t_hi, *(r for r in roots if t_lo < r < t_hi)):
            px = self.start[0] + t * (2.0 * ax + t * bx)
            py = self.start[1] + t * (2.0 * ay + t * by)
            d2 = (x - px) ** 2 + (y - py) ** 2
            if best is None or d2 < best[0]:
                best = (d2, t)
        assert best is not None
        px, py, tx, ty, kappa = self._eval(best[1])
        return Nearest(best[0], self.s_of_t(best[1]), px, py, tx, ty, kappa)


def _real_cubic_roots(a: float, b: float, c: float, d: float) -> tuple[float, ...]:
    """Real roots of a t^3 + b t^2 + c t + d (Numerical Recipes §5.6), one Newton polish each.

    Falls back to the quadratic or linear case when the leading coefficients vanish
    (a straight spline with its control point at the chord midpoint).
    """
    scale = max(abs(a), abs(b), abs(c), abs(d), 1e-300)
    if abs(a) <= 1e-12 * scale:
        if abs(b) <= 1e-12 * scale:
            return (-d / c,) if abs(c) > 1e-12 * scale else ()
        disc = c * c - 4.0 * b * d
        if disc < 0.0:
            return ()
        q = -0.5 * (c + math.copysign(math.sqrt(disc), c))
        return (q / b, d / q) if q != 0.0 else (q / b,)
    p2, p1, p0 = b / a, c / a, d / a
    q = (p2 * p2 - 3.0 * p1) / 9.0
    r = (2.0 * p2**3 - 9.0 * p2 * p1 + 27.0 * p0) / 54.0
    if r * r < q**3:
        theta = math.acos(r / math.sqrt(q**3))
        sq = -2.0 * math.sqrt(q)
        roots: tuple[float, ...] = tuple(sq * math.cos((theta + k * TWO_PI) / 3.0) - p2 / 3.0
                                         for k in (0, 1, -1))
    else:
        big = -math.copysign((abs(r) + math.sqrt(r * r - q**3)) ** (1.0 / 3.0), r)
        roots = (big + (q / big if big != 0.0 else 0.0) - p2 / 3.0,)
    out = []
    for t in roots:
        deriv = 3.0 * t * t + 2.0 * p2 * t + p1
        if deriv != 0.0:
            t -= (((t + p2) * t + p1) * t + p0) / deriv
        out.append(t)
    return tuple(out)
