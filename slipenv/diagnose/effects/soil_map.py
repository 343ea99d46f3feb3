"""``soil_map``: soil stiffness that varies in space — a few regions of a coarse grid.

The generalisation of ``soil_patch`` (one disc) to regions of any shape: the ground-truth
extent is cut into an n × n grid of cells; each cell belongs to one of at most
``MAX_REGIONS`` regions, and each region has its own torque compliance c = 1/k_s
[1/(N m)] (Lindgren Eq. 24: s = T c, every wheel on that ground). Replay: s_i = c(x, y) T_i
(``replay.py`` step 2), the region looked up at the interval's ground-truth midpoint.

Fitting (:func:`start`): the residuals are linear in the cells' compliances to first order, so
one finite difference per cell gives a Jacobian J; a ridge solve (penalty towards the
cells' mean, so that a cell the route barely crosses stays at the mean) gives per-cell
compliances; 1-D k-means groups them into k = 1 … ``MAX_REGIONS`` regions, refined by moving
single cells to the region that lowers the (linearised) cost. The grid (n = 3, 4, 6 or 8
cells per side over the ground-truth extent) and the number of regions k are chosen on
held-out data: layout and compliances found on the even segments are scored on the odd ones
and back; the simplest (fewest regions, then coarsest grid) within ``K_TOLERANCE`` of the
best held-out error wins. The full fit
then refines the region compliances; the grid and the cells' regions stay as chosen (their
residuals do not change under the optimiser's small steps: the map's layout is a model-order
choice, not a fitted number). Simulation: a ``PatchSoilMap`` of rectangles (one per cell of
a softer region) over the base soil, each that region's compliance softer.

Contract names: ``map_x0_m``, ``map_y0_m``, ``map_x1_m``, ``map_y1_m`` (corners),
``map_grid`` (n), ``map_regions`` (k), ``map_cell_<i>`` (region of cell i = row × n + column,
rows along y; cells beyond n² unused),
``c_region<k>_per_nm`` (compliance of region k; k_s = 1/c).
"""

from __future__ import annotations

import dataclasses

import numpy as np

from slipenv.diagnose.effects.base import (
    Bound,
    Effect,
    Scalar,
    StartContext,
    Term,
    compliance_bound,
    finite,
    needs_torque,
    require,
    stiffness_nm,
)
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments
from slipenv.terramechanics.soil_map import PatchSoilMap, Rectangle

GRIDS = (3, 4, 6, 8)  # cells per side the map may have (chosen on held-out data)
GRID = max(GRIDS)  # the most cells per side (the parameter vector's room)
MAX_REGIONS = 3  # regions (distinct stiffnesses) a map may hold
K_TOLERANCE = 0.02  # fewer regions win within this relative held-out error of the best
_RIDGE = 0.05  # ridge weight of the per-cell guess, relative to the mean diagonal of JᵀJ
_SWEEPS = 4  # passes of single-cell moves refining the layout
_POTTS = (0.0, 0.5, 2.0)  # neighbour-disagreement weights tried, in one segment's noise
_N_CELLS = GRID * GRID

_FIXED = ("x0_m", "y0_m", "x1_m", "y1_m", "grid", "regions",
          *(f"cell_{i}" for i in range(_N_CELLS)))
_LEVELS = tuple(f"compliance_{k}_per_nm" for k in range(MAX_REGIONS))


def _make_params() -> type:
    fields = [(name, float) for name in (*_FIXED, *_LEVELS)]
    cls = dataclasses.make_dataclass("SoilMapParams", fields, bases=(_SoilMapTerm,),
                                     frozen=True)
    cls.__module__ = __name__
    cls.__doc__ = ("Soil map parameters: grid origin and cell sizes [m], number of regions, "
                   "each cell's region, each region's torque compliance [1/(N m)].")
    return cls


class _SoilMapTerm(Term):
    """Replay term of a soil map (the generated dataclass holds the fields)."""

    def __post_init__(self) -> None:
        finite(self)
        require(self.x1_m > self.x0_m and self.y1_m > self.y0_m, self,  # type: ignore
                "the map needs x1_m > x0_m and y1_m > y0_m")
        require(1 <= round(self.grid) <= GRID, self,  # type: ignore[attr-defined]
                f"grid must be 1..{GRID}")
        require(1 <= round(self.regions) <= MAX_REGIONS, self,  # type: ignore[attr-defined]
                f"regions must be 1..{MAX_REGIONS}")

    def labels(self) -> np.ndarray:
        """Region of each cell, (GRID * GRID,) ints."""
        raw = np.array([getattr(self, f"cell_{i}") for i in range(_N_CELLS)])
        return np.clip(np.round(raw), 0, MAX_REGIONS - 1).astype(int)

    def levels(self) -> np.ndarray:
        """Compliance of each region [1/(N m)], (MAX_REGIONS,)."""
        return np.array([getattr(self, name) for name in _LEVELS])

    def cells(self) -> tuple[int, float, float]:
        """Cells per side n and cell sizes [m] (x, y)."""
        p = self  # the generated dataclass
        n = int(np.clip(round(p.grid), 1, GRID))  # type: ignore[attr-defined]
        return n, (p.x1_m - p.x0_m) / n, (p.y1_m - p.y0_m) / n  # type: ignore[attr-defined]

    def cell_of(self, pos: np.ndarray) -> np.ndarray:
        """Cell index (row × n + column) of positions ``pos`` (…, 2) [m]; outside the map:
        the nearest cell."""
        p = self
        n, cx, cy = self.cells()
        ix = np.clip(np.floor((pos[..., 0] - p.x0_m) / cx), 0, n - 1)  # type: ignore
        iy = np.clip(np.floor((pos[..., 1] - p.y0_m) / cy), 0, n - 1)  # type: ignore
        return (iy * n + ix).astype(int)

    def compliance_at(self, pos: np.ndarray) -> np.ndarray:
        """Compliance c(x, y) [1/(N m)] at ``pos`` (…, 2)."""
        return self.levels()[self.labels()[self.cell_of(pos)]]

    def slip(self, seg: Segments, pos: np.ndarray) -> np.ndarray | None:
        if seg.torque is None:
            return None
        return self.compliance_at(pos)[..., None] * seg.torque

    def rectangles(self) -> list[tuple[Rectangle, int]]:
        """Every cell as (Rectangle, region)."""
        p = self
        n, cx, cy = self.cells()
        out = []
        for i, label in enumerate(self.labels()[:n * n]):
            iy, ix = divmod(i, n)
            x0 = p.x0_m + ix * cx  # type: ignore[attr-defined]
            y0 = p.y0_m + iy * cy  # type: ignore[attr-defined]
            out.append((Rectangle(x0, y0, x0 + cx, y0 + cy), int(label)))
        return out


SoilMap = _make_params()


def extent_of(seg: Segments) -> tuple[float, float, float, float]:
    """The map's corners (x0, y0, x1, y1) [m]: the ground-truth extent padded by 1 %."""
    pos = seg.pos.reshape(-1, 2)
    lo, hi = pos.min(axis=0), pos.max(axis=0)
    size = np.maximum(hi - lo, 1e-3)
    lo, hi = lo - 0.01 * size, hi + 0.01 * size
    return float(lo[0]), float(lo[1]), float(hi[0]), float(hi[1])


def _fixed_bound(value: float) -> Bound:
    tiny = 1e-9 * max(1.0, abs(value))
    return Bound(value, value - tiny, value + tiny, tiny)


def bounds(seg: Segments) -> dict[str, Bound]:
    x0, y0, x1, y1 = extent_of(seg)
    out = {"x0_m": _fixed_bound(x0), "y0_m": _fixed_bound(y0), "x1_m": _fixed_bound(x1),
           "y1_m": _fixed_bound(y1), "grid": Bound(float(GRIDS[0]), 0.6, GRID + 0.4, 1.0),
           "regions": Bound(1.0, 0.6, MAX_REGIONS + 0.4, 1.0)}
    out.update({f"cell_{i}": Bound(0.0, -0.4, MAX_REGIONS - 0.6, 1.0) for i in range(_N_CELLS)})
    out.update(dict.fromkeys(_LEVELS, compliance_bound(seg)))
    return out


def kmeans_1d(values: np.ndarray, k: int, weights: np.ndarray | None = None,
              iterations: int = 50) -> np.ndarray:
    """Labels 0 … k-1 of ``values`` by weighted 1-D k-means (centres started at quantiles,
    labels ordered by centre)."""
    w = np.ones_like(values) if weights is None else np.maximum(weights, 1e-12)
    centres = np.quantile(values, (np.arange(k) + 0.5) / k)
    labels = np.zeros(len(values), dtype=int)
    for _ in range(iterations):
        labels = np.argmin(np.abs(values[:, None] - centres[None, :]), axis=1)
        new = np.array([np.average(values[labels == j], weights=w[labels == j])
                        if np.any(labels == j) else centres[j] for j in range(k)])
        if np.allclose(new, centres):
            break
        centres = new
    order = np.argsort(centres)
    return np.argsort(order)[labels]


def start(ctx: StartContext) -> list:
    """The map's grid, layout and region compliances from a linearised fit (module doc)."""
    seg = ctx.seg
    x0, y0, x1, y1 = extent_of(seg)
    scale = compliance_bound(seg).scale

    def params(n: int, labels: np.ndarray, levels: np.ndarray, k: int):
        lab, lv = np.zeros(_N_CELLS), np.zeros(MAX_REGIONS)
        lab[:len(labels)], lv[:len(levels)] = labels, levels
        return SoilMap(x0, y0, x1, y1, float(n), float(k), *map(float, lab), *map(float, lv))

    moving = np.abs(seg.dphi).sum(axis=-1) > 0
    r0 = ctx.residuals({**ctx.model, EFFECT.name: params(1, np.zeros(1), np.zeros(1), 1)})
    rows = np.repeat(np.nonzero(seg.gt_ok)[0], r0.size // max(int(seg.gt_ok.sum()), 1))
    if rows.size != r0.size:  # not the layout this start assumes: no data-driven guess
        return []
    parts = [rows % 2 == 0, rows % 2 == 1, np.ones(rows.size, dtype=bool)]
    # (held-out error, complexity, n, k, labels, levels)
    found: list[tuple[float, tuple[int, int, float], int, int, np.ndarray, np.ndarray]] = []
    for n in GRIDS:
        cells = params(n, np.zeros(1), np.zeros(1), 1).cell_of(seg.pos)
        visited = np.array([float(np.sum((cells == i) & moving)) for i in range(n * n)])
        jac = np.zeros((r0.size, n * n))
        for i in np.flatnonzero(visited):
            one = np.zeros(n * n)
            one[i] = 1
            jac[:, i] = (ctx.residuals({**ctx.model, EFFECT.name: params(
                n, one, np.array([0.0, scale]), 2)}) - r0) / scale
        on_route = visited > 0
        normal = [_Normal(jac[m], r0[m]) for m in parts]
        # Potts weight unit: the noise of one segment's residuals under one region
        one = normal[2].cost(np.zeros(n * n, dtype=int), normal[2].levels(
            np.zeros(n * n, dtype=int), 1))
        unit = one / max(r0.size, 1) * r0.size / max(len(seg), 1)
        for k in range(1, MAX_REGIONS + 1):
            if on_route.sum() < k or (k == 1 and n != GRIDS[0]):
                continue  # one region is the same model on every grid
            for smooth in (_POTTS if k > 1 else (0.0,)):
                held_out = 0.0
                for train, test in ((0, 1), (1, 0)):  # layout and levels on one half, scored
                    labels = normal[train].layout(k, on_route, visited, smooth * unit)
                    held_out += normal[test].cost(labels, normal[train].levels(labels, k))
                labels = normal[2].layout(k, on_route, visited, smooth * unit)
                found.append((held_out, (k, n, -smooth), n, k, labels,
                              normal[2].levels(labels, k)))
    if not found:
        return []
    floor = min(f[0] for f in found)
    simplest = sorted((f for f in found if f[0] <= (1 + K_TOLERANCE) * floor),
                      key=lambda f: f[1])[0]
    _, _, n, k, labels, levels = simplest
    return [params(n, labels, levels, k)]


def _neighbour_pairs(n: int) -> tuple[np.ndarray, np.ndarray]:
    """Index pairs (a, b) of the 4-neighbour cells of an n × n grid (row-major), each once."""
    idx = np.arange(n * n).reshape(n, n)
    a = np.concatenate([idx[:, :-1].ravel(), idx[:-1, :].ravel()])
    b = np.concatenate([idx[:, 1:].ravel(), idx[1:, :].ravel()])
    return a, b


class _Normal:
    """Normal equations of the linearised map fit, r ≈ r0 + J c (per-cell compliances c)."""

    def __init__(self, jac: np.ndarray, r0: np.ndarray) -> None:
        self.ata, self.atr, self.rr = jac.T @ jac, jac.T @ r0, float(r0 @ r0)

    def levels(self, labels: np.ndarray, k: int) -> np.ndarray:
        m = np.eye(k)[labels]  # (cells, k) indicator
        a = m.T @ self.ata @ m
        ridge = 1e-9 * max(float(np.trace(a)) / k, 1e-300)  # empty regions stay at 0
        return np.linalg.solve(a + ridge * np.eye(k), -(m.T @ self.atr))

    def cost(self, labels: np.ndarray, levels: np.ndarray) -> float:
        """|r0 + J M levels|² of a layout and its levels."""
        c = levels[labels]
        return float(self.rr + 2 * c @ self.atr + c @ self.ata @ c)

    def layout(self, k: int, on_route: np.ndarray, weight: np.ndarray,
               potts: float = 0.0) -> np.ndarray:
        """Cells' regions: k-means of ridge per-cell compliances, then sweeps moving one cell
        at a time to the region that lowers cost + ``potts`` × (neighbour pairs in different
        regions) most — the regularisation that makes regions contiguous and gives a cell the
        route hardly saw its neighbours' region."""
        cells = len(self.atr)
        n = int(round(np.sqrt(cells)))
        lam = _RIDGE * max(float(np.trace(self.ata)) / cells, 1e-30)
        centre = np.eye(cells) - 1.0 / cells
        per_cell = np.linalg.lstsq(self.ata + lam * centre.T @ centre, -self.atr,
                                   rcond=None)[0]
        labels = np.zeros(cells, dtype=int)
        if k == 1:
            return labels
        labels[on_route] = kmeans_1d(per_cell[on_route], k, weight[on_route])
        labels[~on_route] = int(np.median(labels[on_route]))
        pa, pb = _neighbour_pairs(n)

        def total(lab: np.ndarray) -> float:
            cut = int(np.count_nonzero(lab[pa] != lab[pb])) if potts else 0
            return self.cost(lab, self.levels(lab, k)) + potts * cut

        current = total(labels)
        for _ in range(_SWEEPS):
            moved = False
            for i in range(cells):
                keep = labels[i]
                for j in range(k):
                    if j == keep:
                        continue
                    labels[i] = j
                    trial = total(labels)
                    if trial < current - 1e-12 * abs(current):
                        current, keep, moved = trial, j, True
                labels[i] = keep
            if not moved:
                break
        return labels


def condense(parameters: dict) -> tuple[dict, list[str]]:
    """The cells' regions as a grid of region numbers (north, the largest y, on top; "."
    where the grid has no cell) instead of one ``map_cell_<i>`` line per cell."""
    cells = {k: v for k, v in parameters.items() if k.startswith("map_cell_")}
    if not cells or "map_grid" not in parameters:
        return parameters, []
    kept = {k: v for k, v in parameters.items() if k not in cells}
    n = int(round(parameters["map_grid"][0]))
    values = [float(cells.get(f"map_cell_{i}", [np.nan])[0]) for i in range(n * n)]
    label = [str(int(round(v))) if np.isfinite(v) else "." for v in values]
    rows = [" ".join(label[r * n:(r + 1) * n]) for r in reversed(range(n))]
    return kept, [f"map regions by cell ({n} x {n}, north up, west left):", *rows]


def apply(edit: WorldEdit, p) -> None:
    """Every cell of a region with torque slip (c > 0) becomes a rectangle of softer soil."""
    levels = p.levels()
    base = edit.channel_stiffness()
    patches = [(rect, edit.softer(stiffness_nm(float(levels[label])) / base))
               for rect, label in p.rectangles() if levels[label] > 0.0]
    if patches:
        edit.replace["soil_map"] = PatchSoilMap(edit.soil, patches, blend_width_m=0.0)


EFFECT = Effect(
    name="soil_map",
    meaning="soil stiffness varies in space: regions of a coarse grid with their own torque "
            "slip (Lindgren's s = T/k_s per region)",
    params=SoilMap, bounds=bounds, start=start, apply=apply, rank=7.5, applicable=needs_torque,
    contract=(Scalar("x0_m", "map_x0_m"), Scalar("y0_m", "map_y0_m"),
              Scalar("x1_m", "map_x1_m"), Scalar("y1_m", "map_y1_m"), Scalar("grid", "map_grid"),
              Scalar("regions", "map_regions"),
              *(Scalar(f"cell_{i}", f"map_cell_{i}") for i in range(_N_CELLS)),
              *(Scalar(name, f"c_region{k}_per_nm") for k, name in enumerate(_LEVELS))),
    mechanism="torque slip law", fixed=_FIXED,
    local=True, condense=condense,
)
