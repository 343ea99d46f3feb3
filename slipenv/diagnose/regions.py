"""Regions of softer soil with continuous edges, fitted on a per-interval quadratic.

A soil map's regions are unions of shapes — rectangles and discs — in a map frame (turned to
fit the ground; the caller chooses the angle): each edge, centre and radius may sit anywhere,
not on a grid, so a region follows a field's edge instead of mixing the soft end of a lane
with the firm turn beyond it in one cell, and a round patch (a puddle, a wet hollow) is one
disc instead of a staircase of rectangles.

**The quadratic.** Torque slip s = c(x, y) T (Lindgren Eq. 24) enters the replay per interval
and the segments are replayed apart, so to first order the training cost of any per-interval
compliance C (S segments, L-1 intervals) is

    Σ_s |r0_s + D_s C_s|² = rr_s + 2 b_s·C_s + C_sᵀ G_s C_s,   G_s = D_sᵀ D_s, b_s = D_sᵀ r0_s,

with D_s the residuals' sensitivity to interval j of segment s: one finite difference per
interval index j, all segments at once (:meth:`Quadratic.from_residuals`, L - 1 replays; the
caller may let runs of intervals share a compliance, and pass the runs as "intervals"). Any
map is then scored without replaying: its compliance at the intervals' midpoints goes into
the quadratic.

**The search.** A region is a union of shapes (an L-shaped field is two rectangles; a round
patch one disc); regions add where they overlap. For regions U_r (indicators over the
intervals) and their compliances c, the cost is rr + 2 hᵀc + cᵀ A c with A_rl = Σ U_rᵀ G U_l
and h_r = Σ bᵀ U_r, minimised by c = -A⁻¹h. Moving one edge of one rectangle adds or removes
intervals in the order of their coordinate, so A and h for *every* position of that edge come
from cumulative sums over that order (:func:`scan_edge`, exact, one pass); the edge goes to
the best, halfway between the data points on either side (the cut with the widest margin). A
disc's radius adds intervals in the order of their distance from its centre, so it is scanned
the same way (:func:`scan_radius`); its centre moves by steps halved down to the map's
resolution, the radius rescanned at each. No shape is narrower than the quadratic's
``min_size_m`` (a scanned edge stays that far from the opposite one, a radius at least half
of it, seed cells are widened to it): the data cannot resolve ground finer than the vehicle
that drove over it. An edge moved past the last data point goes to the map's limit, or past
it when the shape would otherwise end narrower (a disc past the farthest point likewise): no
data tell the places beyond the last point apart, so the cost is the same, and the shape
keeps its size where the replay may drive beyond the log. Coordinate descent over the edges
and discs, each
new shape (a new region or part of one; the better of a rectangle and a disc) seeded at the
best cells of a coarse grid, gives layouts of 1, 2, … shapes; how many is chosen on held-out
data by the caller.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass, field

import numpy as np
from numba import njit

_SEED_CELLS = 8  # cells per side of the coarse grid a new region is seeded from
_SEEDS = 3  # best seed cells each descended from
_DISC_SEEDS = 1  # of them, the cells a disc is descended from
_SWEEPS = 8  # most passes of coordinate descent over the edges
_TOL = 1e-9  # relative cost fall that counts as progress
_DISC_MOVES = 24  # most centre moves of a disc per descent
_RESOLUTION = 0.002  # smallest centre step of a disc, as a fraction of the map's size
_QUICK_RESOLUTION: float | None = 0.02  # the same in a quick search (None: not moved)
_POLISH_STEPS = 8  # a disc already placed moves from this many smallest steps

Rect = tuple[float, float, float, float]  # (u0, v0, u1, v1) in the map frame [m]
RECT, DISC = 0, 1  # shape kinds: the rectangle (u0, v0, u1, v1); the disc inscribed in it


@dataclass(frozen=True)
class Quadratic:
    """First-order training cost of a per-interval torque compliance (module doc).

    Attributes
    ----------
    G : ndarray (S, L-1, L-1)
    b : ndarray (S, L-1)
    rr : ndarray (S,)
        Each segment's cost at C = 0.
    uv : ndarray (S, L-1, 2)
        Interval midpoints in the map frame [m].
    min_size_m : float
        The narrowest a shape may be (a rectangle's sides, a disc's diameter) [m]: the
        caller's resolution of the ground, e.g. the vehicle's track width (the replay looks
        the soil up at the body's centre, between wheels that far apart, so a strip narrower
        than that is not resolved by the data: it would fit the noise of the few intervals
        it holds).
    """

    G: np.ndarray
    b: np.ndarray
    rr: np.ndarray
    uv: np.ndarray
    min_size_m: float = 0.0
    _masks: dict = field(default_factory=dict, init=False, repr=False, compare=False)

    @classmethod
    def from_residuals(cls, residuals, rows: np.ndarray, n_intervals: int, scale: float,
                       uv: np.ndarray, r0: np.ndarray | None = None, min_size_m: float = 0.0
                       ) -> Quadratic:
        """``residuals(j, c)``: the flat training residuals with compliance ``c`` on interval
        ``j`` of every segment (``c = 0``: none); ``rows``: the segment of each residual;
        ``r0``: the residuals without compliance, when the caller has them."""
        r0 = residuals(0, 0.0) if r0 is None else r0
        d = np.column_stack([(residuals(j, scale) - r0) / scale for j in range(n_intervals)])
        s_count = uv.shape[0]
        g = np.zeros((s_count, n_intervals, n_intervals))
        b = np.zeros((s_count, n_intervals))
        rr = np.zeros(s_count)
        order = np.argsort(rows, kind="stable")
        starts = np.searchsorted(rows[order], np.arange(s_count + 1))
        for s in range(s_count):
            m = order[starts[s]:starts[s + 1]]
            g[s], b[s], rr[s] = d[m].T @ d[m], d[m].T @ r0[m], r0[m] @ r0[m]
        return cls(g, b, rr, uv, min_size_m)

    def inside(self, rect: Rect, kind: int = RECT) -> np.ndarray:
        """:func:`inside` of the midpoints, remembered (a search asks for the same shapes
        again and again)."""
        key = (rect, kind)
        found = self._masks.get(key)
        if found is None:
            if len(self._masks) > 4096:
                self._masks.clear()
            found = self._masks[key] = inside(self.uv, rect, kind)
        return found

    def take(self, index: np.ndarray) -> Quadratic:
        return Quadratic(self.G[index], self.b[index], self.rr[index], self.uv[index],
                         self.min_size_m)

    def segment_costs(self, compliance: np.ndarray) -> np.ndarray:
        """Each segment's cost (S,) for a per-interval compliance (S, L-1)."""
        c = compliance
        return self.rr + 2 * np.einsum("sj,sj->s", self.b, c) + \
            np.einsum("sj,sjk,sk->s", c, self.G, c)


def inside(uv: np.ndarray, rect: Rect, kind: int = RECT) -> np.ndarray:
    """Indicator (float) of the points ``uv`` (…, 2) in a shape: for a rectangle u0 <= u < u1,
    v0 <= v < v1; for a disc (the one inscribed in the square ``rect``) closer to the centre
    than the radius."""
    u, v = uv[..., 0], uv[..., 1]
    if kind == DISC:
        (cu, cv), radius = disc_of(rect)
        return ((u - cu) ** 2 + (v - cv) ** 2 < radius * radius).astype(float)
    return ((u >= rect[0]) & (u < rect[2]) & (v >= rect[1]) & (v < rect[3])).astype(float)


def disc_of(rect: Rect) -> tuple[tuple[float, float], float]:
    """Centre (u, v) and radius [m] of the disc inscribed in the square ``rect``."""
    return (0.5 * (rect[0] + rect[2]), 0.5 * (rect[1] + rect[3])), 0.5 * (rect[2] - rect[0])


def disc(centre: tuple[float, float], radius: float) -> Rect:
    """The square a disc is inscribed in (the disc's shape in a :class:`Layout`)."""
    return (centre[0] - radius, centre[1] - radius, centre[0] + radius, centre[1] + radius)


@dataclass(frozen=True)
class Layout:
    """Shapes (u0, v0, u1, v1) in the map frame [m], the region each belongs to and its kind
    (``RECT``, or ``DISC``: the disc inscribed in the square; all rectangles when ``kinds``
    is empty); a region is the union of its shapes, regions add where they overlap."""

    rects: tuple[Rect, ...] = ()
    labels: tuple[int, ...] = ()
    kinds: tuple[int, ...] = ()

    def __post_init__(self) -> None:
        if not self.kinds:
            object.__setattr__(self, "kinds", (RECT,) * len(self.rects))
        if not len(self.rects) == len(self.labels) == len(self.kinds):
            raise ValueError(f"Layout: {len(self.rects)} shapes, {len(self.labels)} labels and "
                             f"{len(self.kinds)} kinds")

    @property
    def count(self) -> int:
        """Number of regions."""
        return max(self.labels) + 1 if self.labels else 0

    def masks(self, where: np.ndarray | Quadratic, skip: int | None = None) -> np.ndarray:
        """Indicator (regions, …) of each region at points ``uv`` (…, 2), or at a quadratic's
        midpoints (rectangle ``skip`` left out)."""
        if isinstance(where, Quadratic):
            shape, mask = where.uv.shape[:-1], where.inside
        else:
            shape, mask = where.shape[:-1], functools.partial(inside, where)
        out = np.zeros((self.count, *shape))
        for k, (rect, label, kind) in enumerate(zip(self.rects, self.labels, self.kinds,
                                                    strict=True)):
            if k != skip:
                out[label] = np.maximum(out[label], mask(rect, kind))
        return out

    def with_rect(self, k: int, rect: Rect) -> Layout:
        rects = list(self.rects)
        rects[k] = rect
        return Layout(tuple(rects), self.labels, self.kinds)

    def added(self, rect: Rect, label: int, kind: int = RECT) -> Layout:
        return Layout((*self.rects, rect), (*self.labels, label), (*self.kinds, kind))


def compliance(uv: np.ndarray, layout: Layout, levels: np.ndarray) -> np.ndarray:
    """Compliance at ``uv``: the sum of the levels of the regions holding each point."""
    return np.tensordot(np.asarray(levels, dtype=float), layout.masks(uv), axes=1) \
        if layout.rects else np.zeros(uv.shape[:-1])


@dataclass(frozen=True)
class _Normal:
    """The regions' indicators U (regions, S, L-1), G U, A = Uᵀ G U and h = bᵀ U."""

    masks: np.ndarray
    gm: np.ndarray
    a: np.ndarray
    h: np.ndarray

    @classmethod
    def of(cls, q: Quadratic, layout: Layout, skip: int | None = None) -> _Normal:
        """Of ``layout``'s regions (rectangle ``skip`` left out)."""
        masks = layout.masks(q, skip=skip)
        gm = np.einsum("sjk,rsk->rsj", q.G, masks)
        return cls(masks, gm, np.einsum("rsj,lsj->rl", masks, gm),
                   np.einsum("sj,rsj->r", q.b, masks))


def solve(q: Quadratic, layout: Layout) -> tuple[np.ndarray, float]:
    """Best levels of the regions of ``layout`` and the total cost they leave."""
    if not layout.rects:
        return np.zeros(0), float(q.rr.sum())
    normal = _Normal.of(q, layout)
    a, h = normal.a, normal.h
    c = -np.linalg.solve(a + _ridge(a) * np.eye(len(a)), h)
    return c, float(q.rr.sum() + h @ c)


def _ridge(a: np.ndarray) -> float:
    return 1e-12 * max(float(np.trace(a)) / max(len(a), 1), 1e-300)


def scan_edge(q: Quadratic, layout: Layout, k: int, edge: int, limits: Rect,
              others: _Normal | None = None) -> tuple[Layout, np.ndarray, float] | None:
    """The best position of ``edge`` (0: u0, 1: v0, 2: u1, 3: v1) of rectangle ``k``, the
    others held, over every cut between data points (module doc): (layout, levels, cost),
    or None when no cut leaves every level positive (softer ground only). ``others``: the
    regions without rectangle k (the same for its four edges), computed when not given."""
    axis, lower = edge % 2, edge < 2
    rect = layout.rects[k]
    others = _Normal.of(q, layout, skip=k) if others is None else others
    held = list(rect)
    held[edge] = limits[edge]  # the scanned edge open to the map's limit
    eligible = (inside(q.uv, tuple(held)) > 0) & (others.masks[layout.labels[k]] == 0)  # type: ignore[arg-type]
    key = -q.uv[..., axis] if lower else q.uv[..., axis]
    # at least min_size_m from the opposite edge (in the key's sense: -u for a lower edge)
    opposite = rect[edge + 2] if lower else rect[edge - 2]
    min_cut = q.min_size_m - opposite if lower else opposite + q.min_size_m
    found = _scan(q, layout.labels[k], eligible, key, others, min_cut)
    if found is None:
        return None
    cut, levels, cost = found
    out = list(rect)
    if cut is None:  # past the last point: to the map's limit, or past it to the minimum size
        cut = -min_cut if lower else min_cut
        out[edge] = min(limits[edge], cut) if lower else max(limits[edge], cut)
    else:
        out[edge] = -cut if lower else cut
    return layout.with_rect(k, tuple(out)), levels, cost  # type: ignore[arg-type]


def scan_radius(q: Quadratic, layout: Layout, k: int, centre: tuple[float, float],
                limits: Rect, others: _Normal | None = None
                ) -> tuple[Layout, np.ndarray, float] | None:
    """The best radius of disc ``k`` moved to ``centre``, the others held, over every radius
    between the distances of data points from the centre (as :func:`scan_edge`)."""
    others = _Normal.of(q, layout, skip=k) if others is None else others
    eligible = others.masks[layout.labels[k]] == 0
    key = np.hypot(q.uv[..., 0] - centre[0], q.uv[..., 1] - centre[1])
    found = _scan(q, layout.labels[k], eligible, key, others, 0.5 * q.min_size_m)
    if found is None:
        return None
    cut, levels, cost = found
    if cut is None:  # every point: a disc reaching past the farthest, and of the minimum size
        cut = max(float(key[eligible].max()) + _RESOLUTION * _size(limits),
                  0.5 * q.min_size_m)
    return layout.with_rect(k, disc(centre, cut)), levels, cost


def _size(limits: Rect) -> float:
    return max(limits[2] - limits[0], limits[3] - limits[1])


def _scan(q: Quadratic, region: int, eligible: np.ndarray, key: np.ndarray, others: _Normal,
          min_cut: float = -np.inf) -> tuple[float | None, np.ndarray, float] | None:
    """The best set of the ``eligible`` intervals with ``key`` below a cut added to
    ``region`` (the others held as in ``others``): (cut, levels, cost), the cut halfway
    between two distinct keys and at least ``min_cut`` (None: past the last), or None when no
    cut leaves every level positive."""
    if not eligible.any():
        return None
    found, cut, levels, cost = _scan_kernel(
        q.G, q.b, float(q.rr.sum()), others.gm, others.a, others.h, region,
        np.ascontiguousarray(eligible), np.ascontiguousarray(key, dtype=float), float(min_cut))
    if found < 0:
        return None
    return (None if found == 0 else cut), levels, cost


@njit(cache=True, error_model="numpy")
def _scan_kernel(G, b, rr_sum, gm, a0, h0, region, eligible, key, min_cut):
    """:func:`_scan`'s arithmetic, compiled (a search calls it ~10⁵ times). Returns (found,
    cut, levels, cost): found -1 when no cut is valid, 0 for a cut past the last key, 1
    otherwise.

    The intervals join ``region`` in the order of their key; every pair (i, j) of a segment
    counts in Uᵀ G U from the later of the two on, so A and h for every cut are cumulative
    sums over that order, and each cut's levels solve a regions × regions system (module
    doc)."""
    n_seg, n_int = eligible.shape
    n_reg = h0.size
    seg_of = np.empty(n_seg * n_int, np.int64)
    int_of = np.empty(n_seg * n_int, np.int64)
    coord = np.empty(n_seg * n_int)
    n = 0
    for s in range(n_seg):
        for j in range(n_int):
            if eligible[s, j]:
                seg_of[n], int_of[n], coord[n] = s, j, key[s, j]
                n += 1
    coord = coord[:n]
    order = np.argsort(coord, kind="mergesort")  # stable: ties keep the data's order
    rank = np.full((n_seg, n_int), -1, np.int64)
    for m in range(n):
        rank[seg_of[order[m]], int_of[order[m]]] = m
    added = np.zeros(n)
    for s in range(n_seg):
        for i in range(n_int):
            ri = rank[s, i]
            if ri < 0:
                continue
            for j in range(n_int):
                rj = rank[s, j]
                if rj >= 0:
                    added[max(ri, rj)] += G[s, i, j]
    a = np.empty((n, n_reg, n_reg))
    h = np.empty((n, n_reg))
    grow_a = np.zeros(n_reg)
    grow_h = 0.0
    grow_g = 0.0
    trace = 0.0
    for m in range(n):
        s, j = seg_of[order[m]], int_of[order[m]]
        grow_h += b[s, j]
        grow_g += added[m]
        for r in range(n_reg):
            grow_a[r] += gm[r, s, j]
        for r in range(n_reg):
            h[m, r] = h0[r]
            for col in range(n_reg):
                a[m, r, col] = a0[r, col]
        h[m, region] += grow_h
        for r in range(n_reg):
            a[m, region, r] += grow_a[r]
            a[m, r, region] += grow_a[r]
        a[m, region, region] += grow_g  # grow_a counted the region's own row twice
        for r in range(n_reg):
            trace += a[m, r, r]
    ridge = 1e-12 * max(trace / n / max(n_reg, 1), 1e-300)
    best, best_cost = -1, np.inf
    levels = np.empty((n, n_reg))
    for m in range(n):
        for r in range(n_reg):
            a[m, r, r] += ridge
        ok = _solve_small(a[m], h[m], levels[m])
        cost = rr_sum
        for r in range(n_reg):
            levels[m, r] = -levels[m, r]
            cost += h[m, r] * levels[m, r]
            ok = ok and levels[m, r] > 0
        last = m + 1 == n
        # a cut falls between two distinct coordinates (or beyond the last) and not below
        # min_cut: halfway (the widest margin), or min_cut when that falls within the gap
        ok = ok and np.isfinite(cost) and (last or coord[order[m]] != coord[order[m + 1]]) \
            and (last or coord[order[m + 1]] > min_cut)
        if ok and cost < best_cost:
            best, best_cost = m, cost
    if best < 0:
        return -1, 0.0, np.zeros(n_reg), 0.0
    if best + 1 == n:
        return 0, np.inf, levels[best].copy(), best_cost
    cut = max(0.5 * (coord[order[best]] + coord[order[best + 1]]), min_cut)
    return 1, cut, levels[best].copy(), best_cost


@njit(cache=True, error_model="numpy")
def _solve_small(a, h, out):
    """x with a x = h into ``out`` by Gaussian elimination with partial pivoting (a regions ×
    regions system, one per cut); False when ``a`` is singular."""
    k = h.size
    if k == 1:
        out[0] = h[0] / a[0, 0]
        return a[0, 0] != 0.0
    m = a.copy()
    x = h.copy()
    for col in range(k):
        piv = col
        for r in range(col + 1, k):
            if abs(m[r, col]) > abs(m[piv, col]):
                piv = r
        if m[piv, col] == 0.0:
            return False
        if piv != col:
            for c in range(k):
                m[col, c], m[piv, c] = m[piv, c], m[col, c]
            x[col], x[piv] = x[piv], x[col]
        for r in range(col + 1, k):
            f = m[r, col] / m[col, col]
            for c in range(col, k):
                m[r, c] -= f * m[col, c]
            x[r] -= f * x[col]
    for r in range(k - 1, -1, -1):
        acc = x[r]
        for c in range(r + 1, k):
            acc -= m[r, c] * out[c]
        out[r] = acc / m[r, r]
    return True


def _move_disc(q: Quadratic, layout: Layout, k: int, limits: Rect, others: _Normal,
               best: tuple[Layout, np.ndarray, float], resolution: float | None = _RESOLUTION,
               placed: bool = False) -> tuple[Layout, np.ndarray, float]:
    """Disc ``k``'s radius rescanned and its centre moved by steps of half its radius
    (``placed``: at most ``_POLISH_STEPS`` smallest steps), halved down to ``resolution`` of
    the map's size (None: not moved), the radius rescanned at each (``best``: the layout as
    it is, and its levels and cost)."""
    centre, radius = disc_of(layout.rects[k])
    found = scan_radius(q, layout, k, centre, limits, others)
    if found is not None and found[2] <= best[2]:
        best = found
    if resolution is None:
        return best
    floor = resolution * _size(limits)
    step = 0.5 * max(radius, floor)
    step = min(step, _POLISH_STEPS * floor) if placed else step
    came = None  # the move just made: its way back leads where the cost was higher
    for _ in range(_DISC_MOVES):
        if step < floor:
            break
        (cu, cv), _r = disc_of(best[0].rects[k])
        moves = [m for m in ((step, 0.0), (-step, 0.0), (0.0, step), (0.0, -step))
                 if came is None or m != (-came[0], -came[1])]
        tries = [(scan_radius(q, best[0], k, (cu + du, cv + dv), limits, others), (du, dv))
                 for du, dv in moves]
        better = [(t, m) for t, m in tries if t is not None and t[2] < best[2]]
        if better:
            best, came = min(better, key=lambda tm: tm[0][2])
        else:
            step /= 2
            came = None
    return best


def descend(q: Quadratic, layout: Layout, limits: Rect, moving: list[int] | None = None,
            resolution: float | None = _RESOLUTION, placed: bool = False
            ) -> tuple[Layout, np.ndarray, float]:
    """Coordinate descent over the edges of rectangles and the centres and radii of discs
    ``moving`` (all by default; ``resolution`` and ``placed`` as :func:`_move_disc`, every
    disc placed after the first sweep)."""
    levels, cost = solve(q, layout)
    for sweep in range(_SWEEPS):
        before = cost
        for k in (range(len(layout.rects)) if moving is None else moving):
            others = _Normal.of(q, layout, skip=k)  # moving k leaves the others as they are
            if layout.kinds[k] == DISC:
                layout, levels, cost = _move_disc(q, layout, k, limits, others,
                                                  (layout, levels, cost), resolution,
                                                  placed or sweep > 0)
                continue
            for edge in range(4):
                found = scan_edge(q, layout, k, edge, limits, others)
                if found is not None and found[2] <= cost:
                    layout, levels, cost = found
        if cost >= before - _TOL * abs(before):
            break
    return layout, levels, cost


def limits_of(uv: np.ndarray) -> Rect:
    """The map frame's limits: the midpoints' extent, padded by 1 %."""
    pts = uv.reshape(-1, 2)
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    pad = 0.01 * np.maximum(hi - lo, 1e-3)
    return float(lo[0] - pad[0]), float(lo[1] - pad[1]), float(hi[0] + pad[0]), \
        float(hi[1] + pad[1])


def grow(q: Quadratic, limits: Rect, max_rects: int, max_regions: int, quick: bool = False,
         discs: bool = True) -> list[tuple[Layout, np.ndarray, float]]:
    """Greedy layouts: for 1 … ``max_rects`` shapes, a new shape — a new region (up to
    ``max_regions``) or part of one already there — seeded at the coarse-grid cells that
    lower the cost most (levels all positive): from each of the best ``_SEEDS`` cells a
    rectangle (its edges descended) and, with ``discs``, from the best ``_DISC_SEEDS`` a disc
    (its centre and radius), the best of them kept, then every shape polished (``quick``: the
    best cell only, a disc's centre moved in coarser steps, no polish — a cheaper score of a
    map frame). Returns (layout, levels, cost) per shape count reached (fewer when no shape
    lowers the cost)."""
    u = np.linspace(limits[0], limits[2], _SEED_CELLS + 1)
    v = np.linspace(limits[1], limits[3], _SEED_CELLS + 1)
    cells = [_at_least(q.min_size_m, (float(u[i]), float(v[j]), float(u[i + 1]),
                                      float(v[j + 1])))
             for i in range(_SEED_CELLS) for j in range(_SEED_CELLS)]
    path: list[tuple[Layout, np.ndarray, float]] = []
    layout = Layout()
    cost = float(q.rr.sum())
    for _ in range(max_rects):
        seeds = _seeds(q, layout, cells, max_regions, cost)[:1 if quick else _SEEDS]
        if not seeds:
            break
        new = len(layout.rects)
        if discs:  # the disc inscribed in the best seed cell, as the same region (a disc
            # moves its centre, so it needs fewer seeds than a rectangle)
            seeds += [Layout(trial.rects[:-1] + (_inscribed(trial.rects[-1]),), trial.labels,
                             trial.kinds[:-1] + (DISC,)) for trial in seeds[:_DISC_SEEDS]]
        tries = [descend(q, trial, limits, moving=[new],
                         resolution=_QUICK_RESOLUTION if quick else _RESOLUTION)
                 for trial in seeds]
        layout, levels, cost = min(tries, key=lambda t: t[2])
        if not quick:  # the new shape placed, the others polished around it
            layout, levels, cost = descend(q, layout, limits, placed=True)
        path.append((layout, levels, cost))
    return path


def _at_least(size: float, cell: Rect) -> Rect:
    """``cell`` widened about its centre to ``size`` [m] where it is narrower."""
    du = 0.5 * max(size - (cell[2] - cell[0]), 0.0)
    dv = 0.5 * max(size - (cell[3] - cell[1]), 0.0)
    return cell[0] - du, cell[1] - dv, cell[2] + du, cell[3] + dv


def _inscribed(cell: Rect) -> Rect:
    (cu, cv), _r = disc_of(cell)
    return disc((cu, cv), 0.5 * min(cell[2] - cell[0], cell[3] - cell[1]))


def _seeds(q: Quadratic, layout: Layout, cells: list[Rect], max_regions: int,
           cost: float) -> list[Layout]:
    """The ``_SEEDS`` best layouts of one more rectangle, a cell of ``cells`` (a grid over
    the map, each cell widened to the minimum size, so they may overlap) as a new region or
    added to one, that lower ``cost`` with every level > 0.
    All cells of a label are scored at once: the cell indicators are the columns of O."""
    onehot = np.stack([q.inside(cell) for cell in cells], axis=-1)  # (S, L-1, cells)
    normal = _Normal.of(q, layout)
    masks, a0, h0 = normal.masks, normal.a, normal.h
    count = layout.count
    found = []
    for label in range(min(count + 1, max_regions)):
        size = max(count, label + 1)
        o = onehot if label == count else onehot * (1.0 - masks[label])[..., None]
        go = np.einsum("sjk,skc->sjc", q.G, o)
        cross = np.einsum("rsj,sjc->cr", masks, go)  # (cells, regions)
        a = np.zeros((len(cells), size, size))
        a[:, :count, :count] = a0
        a[:, label, :count] += cross
        a[:, :count, label] += cross
        a[:, label, label] += np.einsum("sjc,sjc->c", o, go)
        h = np.zeros((len(cells), size))
        h[:, :count] = h0
        h[:, label] += np.einsum("sj,sjc->c", q.b, o)
        useful = np.einsum("sjc->c", o) > 0
        ridge = _ridge(np.mean(a, axis=0)) * np.eye(size)
        c = -np.linalg.solve(a + ridge, h[..., None])[..., 0]
        total = q.rr.sum() + np.einsum("nk,nk->n", h, c)
        ok = useful & np.all(c > 0, axis=1) & (total < cost)
        found += [(float(total[i]), layout.added(cells[i], label)) for i in np.flatnonzero(ok)]
    found.sort(key=lambda f: f[0])
    return [trial for _, trial in found[:_SEEDS]]


def main_direction(uv: np.ndarray, moving: np.ndarray) -> float:
    """The route's main direction modulo 90° [rad]: the travel-weighted four-fold circular
    mean of the headings between consecutive midpoints (lanes of a field sweep, or the sides of
    a square), so that rectangles follow the way the ground was worked."""
    step = np.diff(uv, axis=1)
    ok = moving[:, 1:] & moving[:, :-1]
    length = np.hypot(step[..., 0], step[..., 1])[ok]
    heading = np.arctan2(step[..., 1], step[..., 0])[ok]
    if length.sum() <= 0:
        return 0.0
    z = np.sum(length * np.exp(4j * heading))
    return float(np.angle(z) / 4.0) if abs(z) > 1e-9 * length.sum() else 0.0


def to_map(pos: np.ndarray, angle_rad: float) -> np.ndarray:
    """World positions (…, 2) [m] in the map frame turned by ``angle_rad``."""
    c, s = np.cos(angle_rad), np.sin(angle_rad)
    return np.stack([c * pos[..., 0] + s * pos[..., 1], -s * pos[..., 0] + c * pos[..., 1]],
                    axis=-1)
