"""Soils that vary over the ground plane: uniform, patches with blended edges, and grids.

A soil map answers ``params_at(x_m, y_m) -> SoilParams`` for the n contact points of a vehicle.
When every point stands on one soil it returns that soil's cached `SoilParams` of floats, the
same object each time, so the force models keep their derived constants (fast path). Otherwise
the fields are arrays of shape (n,), blended linearly and continuously so that forces do not
jump at soil boundaries. Pure numpy and deterministic.

Cost: the one-soil answer takes a few microseconds; a blended answer costs more and makes each
force model re-derive its soil constants (together some tens of microseconds). A simulation on a
tight per-substep budget can query once per control step: a wheel moves millimetres per
physics substep.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np
from numpy.typing import ArrayLike

from slipenv.terramechanics.soil import PARAM_FIELDS, Soil, SoilParams

__all__ = ["SoilMap", "Region", "UniformSoil", "Circle", "Rectangle", "PatchSoilMap",
           "GridSoilMap"]


@runtime_checkable
class SoilMap(Protocol):
    """Soil parameters at ground-plane points (world frame, metres)."""

    def params_at(self, x_m: np.ndarray, y_m: np.ndarray) -> SoilParams:
        """Soil under points (x_m[i], y_m[i]): floats (one soil) or arrays of shape (n,)."""
        ...


@runtime_checkable
class Region(Protocol):
    """A region of the ground plane, described by its signed distance."""

    def signed_distance_m(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Distance to the boundary [m], negative inside."""
        ...


class UniformSoil:
    """The same soil everywhere; `params_at` returns its cached scalar `SoilParams`."""

    def __init__(self, soil: Soil) -> None:
        self.soil = soil
        self._params = soil.params()

    def params_at(self, x_m: np.ndarray, y_m: np.ndarray) -> SoilParams:
        """The soil's `SoilParams` of floats (broadcast over all points)."""
        return self._params


@dataclass(frozen=True)
class Circle:
    """Disc of radius `radius_m` [m] centred on (`center_x_m`, `center_y_m`) [m]."""

    center_x_m: float
    center_y_m: float
    radius_m: float

    def __post_init__(self) -> None:
        if not (math.isfinite(self.radius_m) and self.radius_m > 0.0):
            raise ValueError(f"Circle radius_m={self.radius_m!r} must be finite and > 0")

    def signed_distance_m(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Distance to the circle [m], negative inside."""
        return np.hypot(np.subtract(x_m, self.center_x_m), np.subtract(y_m, self.center_y_m)) \
            - self.radius_m


@dataclass(frozen=True)
class Rectangle:
    """Rectangle [x_min_m, x_max_m] x [y_min_m, y_max_m] [m], turned by `angle_rad` [rad]
    (counter-clockwise) about its centre; axis-aligned at the default 0."""

    x_min_m: float
    y_min_m: float
    x_max_m: float
    y_max_m: float
    angle_rad: float = 0.0

    def __post_init__(self) -> None:
        if not (self.x_min_m < self.x_max_m and self.y_min_m < self.y_max_m):
            raise ValueError(f"Rectangle needs x_min_m < x_max_m and y_min_m < y_max_m, got {self}")
        if not math.isfinite(self.angle_rad):
            raise ValueError(f"Rectangle angle_rad={self.angle_rad!r} must be finite")

    def signed_distance_m(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """Euclidean distance to the rectangle's boundary [m], negative inside."""
        dx = np.subtract(x_m, 0.5 * (self.x_min_m + self.x_max_m))
        dy = np.subtract(y_m, 0.5 * (self.y_min_m + self.y_max_m))
        if self.angle_rad != 0.0:  # into the rectangle's own axes
            c, s = math.cos(self.angle_rad), math.sin(self.angle_rad)
            dx, dy = c * dx + s * dy, -s * dx + c * dy
        qx = np.abs(dx) - 0.5 * (self.x_max_m - self.x_min_m)
        qy = np.abs(dy) - 0.5 * (self.y_max_m - self.y_min_m)
        outside = np.hypot(np.maximum(qx, 0.0), np.maximum(qy, 0.0))
        return outside + np.minimum(np.maximum(qx, qy), 0.0)


def _check_regions(combined) -> None:
    if not combined.regions or not all(isinstance(r, Region) for r in combined.regions):
        raise ValueError(f"{type(combined).__name__} needs one or more regions, "
                         f"got {combined.regions!r}")


@dataclass(frozen=True)
class Union:
    """Points in any of `regions`. Its signed distance is the least of theirs: exact outside
    and on the boundary's sign everywhere, a bound inside where the regions overlap (so a
    blend band is exact outside the union; with hard edges only the sign counts)."""

    regions: tuple

    def __post_init__(self) -> None:
        _check_regions(self)

    def signed_distance_m(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """The least signed distance of the regions [m], negative inside any."""
        return np.minimum.reduce([r.signed_distance_m(x_m, y_m) for r in self.regions])


@dataclass(frozen=True)
class Intersection:
    """Points in all of `regions`. Its signed distance is the greatest of theirs: exact on
    the boundary's sign, a bound elsewhere (with hard edges only the sign counts)."""

    regions: tuple

    def __post_init__(self) -> None:
        _check_regions(self)

    def signed_distance_m(self, x_m: np.ndarray, y_m: np.ndarray) -> np.ndarray:
        """The greatest signed distance of the regions [m], negative inside all."""
        return np.maximum.reduce([r.signed_distance_m(x_m, y_m) for r in self.regions])


_ZERO, _HALF, _ONE, _THREE = (np.asarray(v) for v in (0.0, 0.5, 1.0, 3.0))


def _column(params: SoilParams) -> np.ndarray:
    """A soil's fields as a column of shape (n_fields, 1), in `SoilParams` order."""
    return np.array(params, dtype=float).reshape(-1, 1)


class PatchSoilMap:
    """A base soil with patches of other soils painted over it, later patches on top.

    Parameters
    ----------
    base : Soil
        Soil outside every patch.
    patches : sequence of (Region, Soil)
        Regions (`Circle`, `Rectangle` or anything with ``signed_distance_m``) and their soils.
    blend_width_m : float
        Width [m] of the transition band centred on each boundary, >= 0. Inside it the patch
        weight goes smoothly (C1 smoothstep of the signed distance) from 1 to 0; it is 1/2 on
        the boundary. 0 gives hard edges, the boundary itself belonging to the outside (forces
        then jump at the boundary).
    """

    def __init__(self, base: Soil, patches: Sequence[tuple[Region, Soil]],
                 blend_width_m: float = 0.5) -> None:
        width = float(blend_width_m)
        if not (math.isfinite(width) and width >= 0.0):
            raise ValueError(f"blend_width_m={blend_width_m!r} must be finite and >= 0")
        for region, soil in patches:
            if not isinstance(region, Region) or not isinstance(soil, Soil):
                raise TypeError(f"each patch must be (Region, Soil), got ({region!r}, {soil!r})")
        self.base = base
        self.patches = tuple((region, soil) for region, soil in patches)
        self.blend_width_m = width
        self._half_width = 0.5 * width
        self._neg_inv_width = np.asarray(-1.0 / width if width > 0.0 else -math.inf)
        self._base = (base.params(), _column(base.params()))
        self._layers = tuple((region, soil.params(), _column(soil.params()))
                             for region, soil in self.patches)

    def weight(self, signed_distance_m: ArrayLike) -> np.ndarray:
        """Patch weight in [0, 1] at a signed distance [m] from its boundary (1 deep inside)."""
        d = np.asarray(signed_distance_m, dtype=float)
        if self.blend_width_m == 0.0:
            return (d < 0.0).astype(float)
        t = np.minimum(np.maximum(d * self._neg_inv_width + _HALF, _ZERO), _ONE)
        return t * t * (_THREE - (t + t))

    def params_at(self, x_m: np.ndarray, y_m: np.ndarray) -> SoilParams:
        """Soil under each point: one soil's cached params, or blended arrays of shape (n,)."""
        x = np.asarray(x_m, dtype=float).reshape(-1)
        y = np.asarray(y_m, dtype=float).reshape(-1)
        current, current_column = self._base
        values: np.ndarray | None = None  # (n_fields, n) once points disagree
        for region, params, column in self._layers:
            d = region.signed_distance_m(x, y)
            listed = d.tolist()  # min/max of a few floats: cheaper in Python than in numpy
            if min(listed) >= self._half_width:  # every point outside the band
                continue
            if max(listed) <= -self._half_width:  # every point fully inside
                current, current_column, values = params, column, None
                continue
            if values is None:
                values = np.repeat(current_column, x.size, axis=1)
            values += (column - values) * self.weight(d)
        return current if values is None else SoilParams(*values)


class GridSoilMap:
    """Soil on a regular grid of nodes, interpolated bilinearly between nodes.

    Node (row j, column i) sits at (x0 + i dx, y0 + j dy); points beyond the grid take the
    nearest edge value. Built from soil indices (this constructor) or from a scale on selected
    fields of one soil (`GridSoilMap.scaled`).

    Parameters
    ----------
    soils : sequence of Soil
        The soils the grid refers to.
    index_grid : array_like of int, shape (ny, nx)
        Index into `soils` at each node.
    origin_m : (float, float)
        (x0, y0) [m], position of node (0, 0).
    cell_size_m : float or (float, float)
        Node spacing dx (and dy) [m], > 0.
    """

    _scale: np.ndarray | None  # node scales (scaled grids) or None (index grids)
    _base_column: np.ndarray  # scaled grids: the base soil's fields, (n_fields, 1)
    _scaled_column: np.ndarray  # scaled grids: those fields that scale, others 0

    def __init__(self, soils: Sequence[Soil], index_grid: ArrayLike,
                 origin_m: tuple[float, float] = (0.0, 0.0),
                 cell_size_m: float | tuple[float, float] = 1.0) -> None:
        grid = np.asarray(index_grid)
        if grid.ndim != 2 or grid.size == 0 or not np.issubdtype(grid.dtype, np.integer):
            raise ValueError(f"index_grid must be a non-empty 2-D integer array, got "
                             f"shape {grid.shape} dtype {grid.dtype}")
        if len(soils) == 0 or grid.min() < 0 or grid.max() >= len(soils):
            raise ValueError(f"index_grid values must lie in [0, {len(soils)}), got "
                             f"[{grid.min()}, {grid.max()}]")
        self.soils = tuple(soils)
        self._params = tuple(s.params() for s in self.soils)
        self._matrix = np.array(self._params, dtype=float)  # (n_soils, n_fields)
        nodes = self._setup(grid.astype(np.intp), origin_m, cell_size_m)
        corners = np.stack([nodes[:-1, :-1], nodes[:-1, 1:], nodes[1:, :-1], nodes[1:, 1:]])
        cell = np.full(nodes.shape, -1, dtype=np.intp)  # soil of cells whose corners agree
        cell[:-1, :-1] = np.where((corners == corners[0]).all(axis=0), corners[0], -1)
        self._node_soil, self._cell_soil = nodes.ravel(), cell.ravel()
        self._scale = None

    @classmethod
    def scaled(cls, base: Soil, scale_grid: ArrayLike, fields: Sequence[str],
               origin_m: tuple[float, float] = (0.0, 0.0),
               cell_size_m: float | tuple[float, float] = 1.0) -> GridSoilMap:
        """Grid of one soil whose `fields` are multiplied by a per-node scale (> 0).

        Raises
        ------
        ValueError
            If a field is not a numeric soil field, a scale is not finite and > 0, or the
            scaled soil would be invalid (checked at the smallest and largest scale).
        """
        scale = np.asarray(scale_grid, dtype=float)
        if scale.ndim != 2 or scale.size == 0 or not np.all(np.isfinite(scale) & (scale > 0)):
            raise ValueError("scale_grid must be a non-empty 2-D array of finite values > 0")
        bad = [f for f in fields if f not in PARAM_FIELDS or f == "deformable"]
        if bad or not fields:
            raise ValueError(f"fields {bad or list(fields)} are not scalable; choose from "
                             f"{[f for f in PARAM_FIELDS if f != 'deformable']}")
        for extreme in (scale.min(), scale.max()):
            dataclasses.replace(base, **{f: getattr(base, f) * float(extreme) for f in fields})
        grid_map = cls.__new__(cls)
        cls._init_scaled(grid_map, base, scale, fields, origin_m, cell_size_m)
        return grid_map

    def _init_scaled(self, base: Soil, scale: np.ndarray, fields: Sequence[str],
                     origin_m: tuple[float, float],
                     cell_size_m: float | tuple[float, float]) -> None:
        """The state of a scaled grid (see `scaled`, which has checked the arguments)."""
        self.soils = (base,)
        self._params = (base.params(),)
        self._matrix = np.array(self._params, dtype=float)
        self._scale = self._setup(scale, origin_m, cell_size_m).ravel()
        mask = np.array([f in fields for f in PARAM_FIELDS], dtype=float).reshape(-1, 1)
        self._base_column = _column(base.params())
        self._scaled_column = self._base_column * mask

    def _setup(self, nodes: np.ndarray, origin_m: tuple[float, float],
               cell_size_m: float | tuple[float, float]) -> np.ndarray:
        """Store the grid frame; return the node array padded to at least 2 x 2."""
        dx, dy = np.broadcast_to(np.asarray(cell_size_m, dtype=float), (2,))
        x0, y0 = (float(v) for v in origin_m)
        if not (dx > 0 and dy > 0 and math.isfinite(dx * dy) and math.isfinite(x0 + y0)):
            raise ValueError(f"cell_size_m={cell_size_m!r} must be > 0 and origin_m={origin_m!r} "
                             "finite")
        self.shape = (int(nodes.shape[0]), int(nodes.shape[1]))
        self.origin_m = (x0, y0)
        self.cell_size_m = (float(dx), float(dy))
        # a single row or column is repeated, so every point has four corner nodes
        nodes = np.pad(nodes, ((0, int(nodes.shape[0] < 2)), (0, int(nodes.shape[1] < 2))),
                       mode="edge")
        ny, nx = nodes.shape
        self._origin = (np.asarray(x0), np.asarray(y0))
        self._inv_cell = (np.asarray(1.0 / dx), np.asarray(1.0 / dy))
        self._f_max = (np.asarray(float(nx - 1)), np.asarray(float(ny - 1)))
        self._i_max = (np.asarray(nx - 2, dtype=np.intp), np.asarray(ny - 2, dtype=np.intp))
        self._nx = np.asarray(nx, dtype=np.intp)
        self._offsets = np.array([0, 1, nx, nx + 1], dtype=np.intp).reshape(4, 1)
        return nodes

    def _cell(self, x_m: np.ndarray, y_m: np.ndarray) -> tuple[np.ndarray, ...]:
        """Flat index of each point's lower-left node and its fractional offsets (tx, ty)."""
        fx = np.minimum(np.maximum((np.asarray(x_m, dtype=float).reshape(-1) - self._origin[0])
                                   * self._inv_cell[0], _ZERO), self._f_max[0])
        fy = np.minimum(np.maximum((np.asarray(y_m, dtype=float).reshape(-1) - self._origin[1])
                                   * self._inv_cell[1], _ZERO), self._f_max[1])
        i0 = np.minimum(fx.astype(np.intp), self._i_max[0])
        j0 = np.minimum(fy.astype(np.intp), self._i_max[1])
        return j0 * self._nx + i0, fx - i0, fy - j0

    def params_at(self, x_m: np.ndarray, y_m: np.ndarray) -> SoilParams:
        """Soil under each point: one soil's cached params, or bilinear arrays of shape (n,)."""
        k, tx, ty = self._cell(x_m, y_m)
        if self._scale is not None:
            s = self._scale[k + self._offsets]  # (4, n): corners 00, 01, 10, 11
            bottom = s[0] + (s[1] - s[0]) * tx
            scale = bottom + (s[2] + (s[3] - s[2]) * tx - bottom) * ty
            return SoilParams(*(self._base_column + self._scaled_column * (scale - 1.0)))
        cells = self._cell_soil[k].tolist()
        if cells[0] >= 0 and min(cells) == max(cells):  # every point inside one soil's cells
            return self._params[cells[0]]
        ux, uy = 1.0 - tx, 1.0 - ty
        weight = np.array([ux * uy, tx * uy, ux * ty, tx * ty])
        values = np.einsum("kn,knf->fn", weight, self._matrix[self._node_soil[k + self._offsets]])
        return SoilParams(*values)


def soil_rows(soil_map: SoilMap, x_m: Sequence[float], y_m: Sequence[float]) -> list[SoilParams]:
    """The soil (floats) at each point: one `SoilParams` per point, for per-contact kernels.

    A `UniformSoil` gives the same object for every point (and is not queried per point), so a
    caller may cache what it derives from a row by the row's identity.
    """
    if isinstance(soil_map, UniformSoil):
        return [soil_map.params_at(np.zeros(1), np.zeros(1))] * len(x_m)
    params = soil_map.params_at(np.asarray(x_m, float), np.asarray(y_m, float))
    return [type(params)(*((v[k] if isinstance(v, np.ndarray) and v.ndim else v)
                           for v in params)) for k in range(len(x_m))]
