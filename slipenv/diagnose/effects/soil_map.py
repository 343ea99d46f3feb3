"""``soil_map``: soil stiffness that varies in space — a few regions with continuous edges.

The generalisation of ``soil_patch`` (one disc) to several regions of any shape: up to
``MAX_REGIONS`` regions, each a union of shapes — rectangles and discs, ``MAX_RECTS`` in
all — in a map frame turned by ``angle_rad``, each region with its own torque compliance
c = 1/k_s [1/(N m)] (Lindgren Eq. 24: s = T c, every wheel on that ground); where regions
overlap their compliances add. An L-shaped field is one region of two rectangles, a round
patch one disc.
Replay: s_i = c(x, y) T_i (``replay.py`` step 2), c looked up at the interval's ground-truth
midpoint.

Fitting (:func:`start`, ``slipenv.diagnose.regions``): the residuals' sensitivity to the
compliance of each run of a few intervals gives a quadratic in which any map is scored without
replaying; the rectangles' edges and the discs' centres and radii are placed anywhere (between
data points, not on a grid: a grid's cell at a field's edge mixes the soft lane ends with the
firm turns beyond them), greedily one shape at a time, none narrower than the vehicle's track
width (the replay looks the soil up at the body's centre, so ground finer than the vehicle is
not resolved: such a sliver fits the noise of the few intervals it holds). The frame's angle is
the one whose map (a quicker search: one seed cell per shape, no polish) fits the training data
best (every ``_ANGLE_STEP`` over a quarter turn and the route's main direction, then the step
halved twice around the best); the number of shapes is chosen on held-out data: maps found on
the other training segments are scored on each of ``_K_FOLDS`` interleaved folds, and the
fewest shapes within ``K_TOLERANCE`` of the best held-out error win. The full fit then refines
the compliances with the layout held (the layout is a model-order choice, not a fitted number).
Simulation: a ``PatchSoilMap`` over the base soil painting each region (the ``Union`` of its
turned rectangles and discs), then each overlap of regions (their ``Intersection``) with the
summed compliance. Hidden in the PyBullet tests on request (``Hiding.drawn`` False): a field
split in two halves of their own softness across the route's focus (:func:`draw`), on level
differential-drive ground and under the rover on a slope.

Contract names: ``map_angle_rad``, ``map_rects`` (n), ``map_rect<k>_u0_m`` … ``_v1_m``,
``map_rect<k>_region`` and ``map_rect<k>_shape`` (shape k's corners in the map frame, u
along the angle and v across it, its region, and 0 for the rectangle or 1 for the disc
inscribed in it, a square; 0 when left out; shapes beyond n unused),
``c_region<r>_per_nm`` (compliance of region r; k_s = 1/c).
"""

from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass

import numpy as np

from slipenv.diagnose import regions
from slipenv.diagnose.effects.base import (
    Bound,
    DrawContext,
    Effect,
    Hidden,
    Hiding,
    Scalar,
    StartContext,
    Term,
    applicable_to_world,
    compliance_bound,
    finite,
    needs_torque,
    require,
    stiffness_nm,
)
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments
from slipenv.terramechanics.soil_map import (
    Circle,
    Intersection,
    PatchSoilMap,
    Rectangle,
    Region,
    Union,
)

MAX_REGIONS = 3  # regions (each its own stiffness) a map may hold
MAX_RECTS = 5  # shapes (rectangles, discs) the regions are made of
K_TOLERANCE = 0.02  # fewer regions win within this relative held-out error of the best
_ANGLE_STEP = np.pi / 24  # [rad] first pass of the frame's angle over a quarter turn
_K_FOLDS = 4  # interleaved folds of the training segments the rectangle count is chosen on
_RUNS = 20  # most runs of intervals per segment in the search (module doc)
_EDGES = ("u0_m", "v0_m", "u1_m", "v1_m")
_RECTS = tuple(f"rect{k}_{e}" for k in range(MAX_RECTS)
               for e in (*_EDGES, "region", "shape"))
_FIXED = ("angle_rad", "rects", *_RECTS)
_LEVELS = tuple(f"compliance_{k}_per_nm" for k in range(MAX_REGIONS))


def _make_params() -> type:
    fields = [(name, float) for name in (*_FIXED, *_LEVELS)]
    cls = dataclasses.make_dataclass("SoilMapParams", fields, bases=(_SoilMapTerm,),
                                     frozen=True)
    cls.__module__ = __name__
    cls.__doc__ = ("Soil map parameters: the map frame's angle [rad], the number of "
                   "shapes, each one's corners in the map frame [m], region and kind "
                   "(0 rectangle, 1 the disc inscribed in it), each region's torque "
                   "compliance [1/(N m)].")
    return cls


class _SoilMapTerm(Term):
    """Replay term of a soil map (the generated dataclass holds the fields)."""

    def __post_init__(self) -> None:
        finite(self)
        require(1 <= round(self.rects) <= MAX_RECTS, self,  # type: ignore[attr-defined]
                f"rects must be 1..{MAX_RECTS}")
        for k in range(self._used()):
            kind = getattr(self, f"rect{k}_shape")
            require(kind in (regions.RECT, regions.DISC), self,
                    f"rect{k}_shape must be 0 (rectangle) or 1 (disc), got {kind}")
        layout = self.layout()
        for k, ((u0, v0, u1, v1), kind) in enumerate(zip(layout.rects, layout.kinds,
                                                         strict=True)):
            require(u1 > u0 and v1 > v0, self,
                    f"rectangle {k} needs u1_m > u0_m and v1_m > v0_m, got {(u0, v0, u1, v1)}")
            require(kind == regions.RECT or np.isclose(u1 - u0, v1 - v0, rtol=1e-9, atol=0.0),
                    self, f"disc {k} needs a square (u1_m - u0_m == v1_m - v0_m), got "
                          f"{(u0, v0, u1, v1)}")
        require(all(0 <= r < MAX_REGIONS for r in layout.labels)
                and sorted(set(layout.labels)) == list(range(layout.count)), self,
                f"the rectangles' regions must be 0..{MAX_REGIONS - 1}, each used")

    def _used(self) -> int:
        """Number of shapes used (``rects`` rounded into 1 … ``MAX_RECTS``)."""
        return int(np.clip(round(self.rects), 1, MAX_RECTS))  # type: ignore[attr-defined]

    def used_fields(self) -> int:
        """Fields the layout uses: the frame's angle and the shape count, each used shape's
        corners, region and kind, each region's compliance."""
        return 2 + (len(_EDGES) + 2) * self._used() + self.regions

    def layout(self) -> regions.Layout:
        """The used shapes (corners in the map frame [m]), their regions and kinds."""
        count = self._used()
        rects = tuple(tuple(float(getattr(self, f"rect{k}_{e}")) for e in _EDGES)
                      for k in range(count))
        labels = tuple(int(round(getattr(self, f"rect{k}_region"))) for k in range(count))
        kinds = tuple(int(getattr(self, f"rect{k}_shape")) for k in range(count))
        return regions.Layout(rects, labels, kinds)  # type: ignore[arg-type]

    @property
    def regions(self) -> int:
        """Number of regions (distinct stiffnesses)."""
        return self.layout().count

    def levels(self, count: int | None = None) -> np.ndarray:
        """Compliance of each region [1/(N m)] (of the first ``count``: all used)."""
        count = self.regions if count is None else count
        return np.array([getattr(self, name) for name in _LEVELS[:count]])

    def compliance_at(self, pos: np.ndarray) -> np.ndarray:
        """Compliance c(x, y) [1/(N m)] at world positions ``pos`` (…, 2) [m]."""
        uv = regions.to_map(pos, self.angle_rad)  # type: ignore[attr-defined]
        layout = self.layout()
        return regions.compliance(uv, layout, self.levels(layout.count))

    def slip(self, seg: Segments, pos: np.ndarray) -> np.ndarray | None:
        if seg.torque is None:
            return None
        return self.compliance_at(pos)[..., None] * seg.torque

    def shapes(self) -> list[tuple[Region, int]]:
        """Each used shape in the world frame (a turned ``Rectangle`` or a ``Circle``) and
        its region."""
        angle = float(self.angle_rad)  # type: ignore[attr-defined]
        layout = self.layout()
        out: list[tuple[Region, int]] = []
        for rect, label, kind in zip(layout.rects, layout.labels, layout.kinds, strict=True):
            (cu, cv), radius = regions.disc_of(rect)
            cx, cy = (float(x) for x in regions.to_map(np.array([cu, cv]), -angle))
            if kind == regions.DISC:
                out.append((Circle(cx, cy, radius), label))
            else:
                hu, hv = 0.5 * (rect[2] - rect[0]), 0.5 * (rect[3] - rect[1])
                out.append((Rectangle(cx - hu, cy - hv, cx + hu, cy + hv, angle), label))
        return out

    def patches(self) -> list[tuple[Region, float]]:
        """The map as patches to paint in order (``PatchSoilMap``: later on top), each with
        its compliance: every region (the union of its shapes), then every overlap of two
        regions, then of three (their intersection), each with the summed compliance of the
        regions holding it — a point in exactly the regions T is painted last by T itself.
        Patches of no compliance are left out."""
        layout = self.layout()
        levels = self.levels(layout.count)
        by_region: dict[int, list[Region]] = {}
        for shape, label in self.shapes():
            by_region.setdefault(label, []).append(shape)
        unions = {r: (s[0] if len(s) == 1 else Union(tuple(s))) for r, s in by_region.items()}
        out: list[tuple[Region, float]] = []
        for size in range(1, layout.count + 1):
            for group in itertools.combinations(sorted(unions), size):
                level = float(sum(levels[r] for r in group))
                if level != 0.0:
                    region = unions[group[0]] if size == 1 else \
                        Intersection(tuple(unions[r] for r in group))
                    out.append((region, level))
        return out


SoilMap = _make_params()
SoilMapParams = SoilMap  # its class's name: pickle (worker processes) looks it up by it


@dataclass(frozen=True)
class _Probe(Term):
    """Compliance ``c`` [1/(N m)] on intervals ``lo`` … ``hi - 1`` of every segment, nowhere
    else."""

    lo: int
    hi: int
    c: float

    def slip(self, seg: Segments, pos: np.ndarray) -> np.ndarray | None:
        if seg.torque is None:
            return None
        out = np.zeros(seg.torque.shape)
        out[:, self.lo:self.hi] = self.c * seg.torque[:, self.lo:self.hi]
        return out


def _fixed_bound(value: float) -> Bound:
    return Bound(value, -1e9, 1e9, 1.0)


def _params(angle: float, layout: regions.Layout, levels: np.ndarray) -> Term:
    rects = np.zeros((MAX_RECTS, 6))
    rects[:] = (0.0, 0.0, 1.0, 1.0, 0.0, 0.0)  # unused shapes: a unit square, region 0
    for k, (rect, label, kind) in enumerate(zip(layout.rects, layout.labels, layout.kinds,
                                                strict=True)):
        rects[k] = (*rect, label, kind)
    lv = np.zeros(MAX_REGIONS)
    lv[:len(levels)] = levels
    return SoilMap(float(angle), float(len(layout.rects)), *map(float, rects.ravel()),
                   *map(float, lv))


def bounds(seg: Segments) -> dict[str, Bound]:
    start = _params(0.0, regions.Layout((regions.limits_of(seg.pos),), (0,)), np.zeros(1))
    out = {name: _fixed_bound(float(getattr(start, name))) for name in _FIXED}
    out.update(dict.fromkeys(_LEVELS, compliance_bound(seg)))
    return out


def start(ctx: StartContext) -> list:
    """The map's frame, regions and compliances from the linearised fit (module doc)."""
    seg = ctx.seg
    scale = compliance_bound(seg).scale
    r0 = ctx.residuals({**ctx.model, EFFECT.name: _Probe(0, 0, 0.0)})
    count = max(int(seg.gt_ok.sum()), 1)
    rows = np.repeat(np.nonzero(seg.gt_ok)[0], r0.size // count)
    if rows.size != r0.size:  # not the layout this start assumes: no data-driven guess
        return []

    # runs of ``size`` intervals share a compliance in the search (a few cm of travel on the
    # short segments): the quadratic is over runs, ``_RUNS`` per segment at most
    n_int = seg.pos.shape[1]
    size = -(-n_int // _RUNS)
    cuts = list(range(0, n_int, size)) + [n_int]
    spans = list(itertools.pairwise(cuts))
    centres = np.stack([seg.pos[:, a:b].mean(axis=1) for a, b in spans], axis=1)

    def residuals(j: int, c: float) -> np.ndarray:
        return ctx.residuals({**ctx.model, EFFECT.name: _Probe(*spans[j], c)})

    # no shape narrower than the vehicle's track (regions.Quadratic.min_size_m)
    world = regions.Quadratic.from_residuals(residuals, rows, len(spans), scale, centres, r0,
                                             float(np.median(seg.track)))

    def frame(angle: float) -> tuple[regions.Quadratic, regions.Rect]:
        q = dataclasses.replace(world, uv=regions.to_map(centres, angle))
        return q, regions.limits_of(q.uv)

    moving = np.abs(seg.dphi).sum(axis=-1) > 0
    angle = _frame_angle(lambda a: regions.grow(*frame(a), MAX_RECTS, MAX_REGIONS, quick=True),
                         regions.main_direction(seg.pos, moving))
    q, limits = frame(angle)
    path = regions.grow(q, limits, MAX_RECTS, MAX_REGIONS)
    if not path:
        return []
    held = _held_out(q, limits, len(path))  # the fewest shapes within K_TOLERANCE of the best
    layout, levels, _ = path[int(np.flatnonzero(held <= (1 + K_TOLERANCE) * held.min())[0])]
    return [_params(angle, layout, levels)]


def _frame_angle(quick_path, main_direction: float) -> float:
    """The map frame's angle whose quick map (``quick_path(angle)``, a :func:`regions.grow`
    path) leaves the least training cost: every ``_ANGLE_STEP`` over a quarter turn and the
    route's main direction, then the step halved twice around the best."""
    def score(angle: float) -> float:
        path = quick_path(angle)
        return path[-1][2] if path else np.inf

    angles = [float(a) for a in np.arange(0.0, np.pi / 2, _ANGLE_STEP)]
    angles.append(main_direction % (np.pi / 2))
    scored = {a: score(a) for a in angles}
    step = _ANGLE_STEP
    for _ in range(2):
        step /= 2
        best = min(scored, key=scored.__getitem__)
        scored.update({a: score(a) for a in (best - step, best + step) if a not in scored})
    return min(scored, key=scored.__getitem__)


def _held_out(q: regions.Quadratic, limits: regions.Rect, count: int) -> np.ndarray:
    """Held-out cost of maps of 1 … ``count`` shapes: found on the other folds' segments,
    scored on each of ``_K_FOLDS`` interleaved folds'."""
    idx = np.arange(len(q.rr))
    held = np.zeros(count)
    for fold in range(_K_FOLDS):
        test = idx % _K_FOLDS == fold
        if test.all() or not test.any():
            continue
        part = regions.grow(q.take(~test), limits, count, MAX_REGIONS)
        rest = q.take(test)
        for k in range(count):
            layout, levels, _ = part[min(k, len(part) - 1)] if part else \
                (regions.Layout(), np.zeros(0), 0.0)
            held[k] += float(rest.segment_costs(
                regions.compliance(rest.uv, layout, levels)).sum())
    return held


def condense(parameters: dict) -> tuple[dict, list[str]]:
    """The regions one line each (their shapes' centres and sizes, or radii, in the world
    frame) instead of six numbers per shape, used or not."""
    if "map_rects" not in parameters or "map_angle_rad" not in parameters:
        return parameters, []
    kept = {k: v for k, v in parameters.items()
            if not k.startswith("map_rect") and k != "map_angle_rad"}
    count = int(round(parameters["map_rects"][0]))
    angle = float(parameters["map_angle_rad"][0])
    by_region: dict[int, list[str]] = {}
    for k in range(count):
        try:
            u0, v0, u1, v1, label = (float(parameters[f"map_rect{k}_{e}"][0])
                                     for e in (*_EDGES, "region"))
        except KeyError:
            continue
        cx, cy = regions.to_map(np.array([0.5 * (u0 + u1), 0.5 * (v0 + v1)]), -angle)
        disc = parameters.get(f"map_rect{k}_shape", [0.0])[0] == regions.DISC
        by_region.setdefault(int(round(label)), []).append(
            f"disc ({cx:.2f}, {cy:.2f}) m, radius {0.5 * (u1 - u0):.2f} m" if disc else
            f"({cx:.2f}, {cy:.2f}) m, {u1 - u0:.2f} x {v1 - v0:.2f} m")
    lines = [f"soil map: {len(by_region)} region(s) of {count} shape(s), rectangles turned "
             f"{np.degrees(angle):.1f} deg (centre in world x, y; size along, across):"]
    lines += [f"  region {r} (c_region{r}_per_nm): " + "; ".join(rects)
              for r, rects in sorted(by_region.items())]
    for r in range(len(by_region), MAX_REGIONS):  # unused regions' compliances say nothing
        kept.pop(f"c_region{r}_per_nm", None)
    return kept, lines


def apply(edit: WorldEdit, p) -> None:
    """Every region (and overlap) with torque slip (c > 0) becomes a patch of softer soil
    (:meth:`patches`); a region of negative compliance (the fit's bounds straddle 0) is
    refused, named."""
    levels = p.levels()
    applicable_to_world(bool(np.all(levels >= 0.0)), EFFECT.name,
                        ", ".join(f"c_region{r}_per_nm" for r in np.flatnonzero(levels < 0.0)),
                        f"a region's torque compliance must be >= 0 (a driven wheel cannot "
                        f"run ahead of its rim), got {levels.tolist()} 1/(N m)")
    base = edit.channel_stiffness()
    patches = [(region, edit.softer(stiffness_nm(level) / base))
               for region, level in p.patches() if level > 0.0]
    if patches:
        edit.replace["soil_map"] = PatchSoilMap(edit.soil, patches, blend_width_m=0.0)


def draw(rng: np.random.Generator, ctx: DrawContext) -> Hidden:
    """A field split in two of their own softness across the route's focus (a wetter half),
    turned at random: each half 0.4-0.7 of the arena's half-size long and 0.4-0.8 wide, so
    that the legs through the focus cross both and the edge between them; 2-5 % slip on the
    first at the drawn torque (``DrawContext.slip_torque_nm``), 1.6-2.4 times as much on the
    second."""
    angle = float(rng.uniform(0.0, np.pi / 2))
    arena = ctx.arena_m
    centre = regions.to_map(np.asarray(ctx.focus, dtype=float), angle)
    rects = []
    for side in (1.0, -1.0):
        length = float(rng.uniform(0.4, 0.7)) * arena
        half_width = 0.5 * float(rng.uniform(0.4, 0.8)) * arena
        shift = float(rng.uniform(-0.25, 0.25)) * half_width
        far = centre[0] + side * length
        rects.append((min(centre[0], far), centre[1] + shift - half_width,
                      max(centre[0], far), centre[1] + shift + half_width))
    c0 = float(rng.uniform(0.02, 0.05)) / ctx.slip_torque_nm()
    levels = np.array([c0, c0 * float(rng.uniform(1.6, 2.4))])
    return Hidden(_params(angle, regions.Layout(tuple(rects), (0, 1)), levels))


EFFECT = Effect(
    name="soil_map",
    meaning="soil stiffness varies in space: a few regions with continuous edges, each its "
            "own torque slip (Lindgren's s = T/k_s per region)",
    params=SoilMap, bounds=bounds, start=start, apply=apply, rank=7.5, applicable=needs_torque,
    contract=(Scalar("angle_rad", "map_angle_rad"), Scalar("rects", "map_rects"),
              *(Scalar(name, f"map_{name}") for name in _RECTS),
              *(Scalar(name, f"c_region{k}_per_nm") for k, name in enumerate(_LEVELS))),
    mechanism="torque slip law", fixed=_FIXED,
    local=True, condense=condense, used=_SoilMapTerm.used_fields,
    # level differential drive (as soil_patch), the rover on a slope (its drive torque, as
    # torque_slip); a skid-steer vehicle shows a softer longitudinal law as turning slip
    hiding=Hiding(("diff_drive", "rover4ws"), draw, slope_deg=(6.0, 12.0),
                  slope_kinds=("rover4ws",), random_slope=False,
                  columns=frozenset({"torque"}), compare=False, drawn=False),
    # a hand-written map may leave out the shapes and regions it does not use, and the
    # kind of a rectangle
    optional={**{f"map_rect{k}_{e}": 0.0 for k in range(1, MAX_RECTS)
                 for e in (*_EDGES, "region")},
              **{f"map_rect{k}_shape": 0.0 for k in range(MAX_RECTS)},
              **{f"c_region{r}_per_nm": 0.0 for r in range(1, MAX_REGIONS)}},
)
