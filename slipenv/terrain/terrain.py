"""Ground geometry: flat plane, tilted plane (any slope and direction), heightfield mounds.

A :class:`TerrainSpec` is pure configuration; :func:`build_terrain` creates the PyBullet body
and returns a :class:`Terrain` that also answers height and normal queries (used to spawn the
vehicle and to express ground truth). Soil is separate (``slipenv.terramechanics``): geometry
and soil vary independently.
"""

from __future__ import annotations

import functools
import math
import numbers
from dataclasses import dataclass

import numpy as np

from slipenv.contracts.names import did_you_mean

TERRAIN_KINDS = ("flat", "slope", "mounds")
MAX_SLOPE_DEG = 45.0  # [deg] steeper than any soil's angle of repose: nothing drives there
MAX_SIZE_M = 1000.0  # [m] side of the heightfield
MAX_MOUND_HEIGHT_M = 5.0  # [m] taller is a hill, not an obstacle for these vehicles
MAX_MOUNDS = 1000
# A side of at most 2049 points: 4.2 M heights, ~34 MB as PyBullet's float list (1e-4 m over
# 24 m would be 240 001 points a side, 429 GiB).
MAX_GRID_POINTS = 2049
MAX_DRAWS_PER_MOUND = 200  # rejection-sampling budget (acceptance < 0.5 % is an error)


@dataclass(frozen=True)
class TerrainSpec:
    """Ground geometry.

    Attributes
    ----------
    kind : str
        ``flat`` | ``slope`` | ``mounds``.
    slope_deg : float
        Inclination of the plane for ``slope`` [deg], 0 <= slope < 45.
    downhill_azimuth_deg : float
        Direction of steepest descent, counter-clockwise from world x [deg] (log-format
        ``slope_downhill_azimuth_deg``); the plane passes through the world origin.
    mound_count : int
        Number of Gaussian mounds for ``mounds``.
    mound_height_m : float
        Peak height of each mound [m].
    mound_radius_m : float
        Standard deviation of each mound's Gaussian profile [m].
    size_m : float
        Side of the square heightfield [m].
    resolution_m : float
        Heightfield grid spacing [m].
    layout_seed : int
        Seed of the mound layout (terrain is part of the task definition, not of the episode
        noise, so it does not change with ``reset(seed)``).
    clear_radius_m : float
        Radius around the origin kept free of mounds so the vehicle spawns on level ground [m].

    Notes
    -----
    Bounds (``ValueError`` naming the field otherwise): numbers finite, counts integers;
    0 <= slope < 45 deg, |azimuth| <= 360 deg, 0 < mound height <= 5 m, 0 < size <= 1000 m,
    mound_count <= 1000; for ``mounds`` the heightfield has at most 2049 points a side, mound
    centres (kept two radii inside the edge) must fit outside the clear disc, and their
    placement is a bounded draw, so an impossible layout fails instead of hanging.
    """

    kind: str = "flat"
    slope_deg: float = 0.0
    downhill_azimuth_deg: float = 0.0
    mound_count: int = 12
    mound_height_m: float = 0.12
    mound_radius_m: float = 0.6
    size_m: float = 24.0
    resolution_m: float = 0.1
    layout_seed: int = 0
    clear_radius_m: float = 1.0

    def __post_init__(self) -> None:
        if not isinstance(self.kind, str) or self.kind not in TERRAIN_KINDS:
            hint = did_you_mean(self.kind, TERRAIN_KINDS)
            raise ValueError(
                f"TerrainSpec.kind must be one of {TERRAIN_KINDS}, got {self.kind!r}{hint}"
            )
        for name in ("slope_deg", "downhill_azimuth_deg", "mound_height_m", "mound_radius_m",
                     "size_m", "resolution_m", "clear_radius_m"):
            value = getattr(self, name)
            if not _is_real(value) or not math.isfinite(value):
                raise ValueError(f"TerrainSpec.{name} must be a finite number, got {value!r}")
        for name in ("mound_count", "layout_seed"):
            value = getattr(self, name)
            if not _is_int(value) or value < 0:
                raise ValueError(f"TerrainSpec.{name} must be an integer >= 0, got {value!r}")
        if not (0.0 <= self.slope_deg < MAX_SLOPE_DEG):
            raise ValueError(
                f"TerrainSpec.slope_deg must be in [0, {MAX_SLOPE_DEG:g}), got {self.slope_deg!r}"
            )
        if abs(self.downhill_azimuth_deg) > 360.0:
            raise ValueError("TerrainSpec.downhill_azimuth_deg must be in [-360, 360] deg, got "
                             f"{self.downhill_azimuth_deg!r}")
        for name, high in (("mound_height_m", MAX_MOUND_HEIGHT_M), ("mound_radius_m", None),
                           ("size_m", MAX_SIZE_M), ("resolution_m", None)):
            value = getattr(self, name)
            if value <= 0.0 or (high is not None and value > high):
                bound = f" and <= {high:g}" if high is not None else ""
                raise ValueError(f"TerrainSpec.{name} must be > 0{bound}, got {value!r}")
        if self.clear_radius_m < 0.0:
            raise ValueError(
                f"TerrainSpec.clear_radius_m must be >= 0, got {self.clear_radius_m!r}"
            )
        if self.kind == "mounds":
            self._check_mounds()

    def _check_mounds(self) -> None:
        """Mound-field options that are fine one by one but not together."""
        if self.mound_count > MAX_MOUNDS:
            raise ValueError(
                f"TerrainSpec.mound_count must be <= {MAX_MOUNDS}, got {self.mound_count}"
            )
        n = grid_points(self)
        if n > MAX_GRID_POINTS:
            raise ValueError(
                f"TerrainSpec.resolution_m={self.resolution_m:g} m over size_m={self.size_m:g} m "
                f"makes a {n} x {n} heightfield; at most {MAX_GRID_POINTS} points a side "
                f"(resolution_m >= {self.size_m / (MAX_GRID_POINTS - 1):.3g} m)"
            )
        if n < 3:
            raise ValueError(f"TerrainSpec.resolution_m={self.resolution_m:g} m must be smaller "
                             f"than size_m/2 = {self.size_m / 2:g} m")
        if self.mound_count == 0:
            return
        half = _placement_half_side(self)
        if half <= 0.0:
            raise ValueError(
                f"TerrainSpec.mound_radius_m={self.mound_radius_m:g} m is too large for "
                f"size_m={self.size_m:g} m: mound centres stay 2 radii inside the edge, so "
                f"mound_radius_m must be < size_m / 4 = {self.size_m / 4:g} m"
            )
        if half * math.sqrt(2.0) <= self.clear_radius_m + 2.0 * self.mound_radius_m:
            raise ValueError(
                f"TerrainSpec.clear_radius_m={self.clear_radius_m:g} m leaves no room for "
                f"mounds in a {self.size_m:g} m field: mound centres must lie "
                f"{self.clear_radius_m + 2 * self.mound_radius_m:g} m from the origin but "
                f"within {half:g} m of it along each axis"
            )
        _mound_centres(self)  # bounded draw: raises if the free area is too small


def _is_real(value) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _is_int(value) -> bool:
    return isinstance(value, numbers.Integral) and not isinstance(value, bool)


class Terrain:
    """A built terrain: its PyBullet body id and height/normal queries."""

    def __init__(self, spec: TerrainSpec, body_id: int, heights: np.ndarray | None = None):
        self.spec = spec
        self.body_id = body_id
        self._heights = heights
        az = math.radians(spec.downhill_azimuth_deg)
        self._downhill = (math.cos(az), math.sin(az))
        self._grade = math.tan(math.radians(spec.slope_deg)) if spec.kind == "slope" else 0.0

    def height(self, x_m: float, y_m: float) -> float:
        """Ground height at (x, y) [m]."""
        if self.spec.kind == "mounds":
            return float(_mound_heights(self.spec, np.array([x_m]), np.array([y_m]))[0])
        return -self._grade * (self._downhill[0] * x_m + self._downhill[1] * y_m)

    def normal(self, x_m: float, y_m: float) -> tuple[float, float, float]:
        """Unit upward ground normal at (x, y)."""
        if self.spec.kind == "mounds":
            e = 1e-3
            dzdx = (self.height(x_m + e, y_m) - self.height(x_m - e, y_m)) / (2 * e)
            dzdy = (self.height(x_m, y_m + e) - self.height(x_m, y_m - e)) / (2 * e)
        else:
            dzdx, dzdy = -self._grade * self._downhill[0], -self._grade * self._downhill[1]
        norm = math.sqrt(dzdx * dzdx + dzdy * dzdy + 1.0)
        return (-dzdx / norm, -dzdy / norm, 1.0 / norm)


def grid_points(spec: TerrainSpec) -> int:
    """Heightfield points along each side for ``mounds``."""
    return int(round(spec.size_m / spec.resolution_m)) + 1


def _placement_half_side(spec: TerrainSpec) -> float:
    return spec.size_m / 2 - 2 * spec.mound_radius_m


@functools.lru_cache(maxsize=64)
def _mound_centres(spec: TerrainSpec) -> np.ndarray:
    """Mound centres by rejection sampling outside the clear disc (at most
    ``MAX_DRAWS_PER_MOUND`` draws per mound: a free area too small for that is an error)."""
    rng = np.random.default_rng(spec.layout_seed)
    half = _placement_half_side(spec)
    keep_out = spec.clear_radius_m + 2 * spec.mound_radius_m
    centres: list[np.ndarray] = []
    budget = MAX_DRAWS_PER_MOUND * spec.mound_count
    for _ in range(budget):
        if len(centres) == spec.mound_count:
            break
        c = rng.uniform(-half, half, size=2)
        if np.hypot(*c) > keep_out:
            centres.append(c)
    if len(centres) < spec.mound_count:
        raise ValueError(
            f"TerrainSpec.clear_radius_m={spec.clear_radius_m:g} m leaves too little of the "
            f"{spec.size_m:g} m field for {spec.mound_count} mounds ({len(centres)} placed in "
            f"{budget} draws); lower clear_radius_m or mound_radius_m, or raise size_m"
        )
    out = np.array(centres).reshape(-1, 2)
    out.flags.writeable = False  # cached: shared by every caller
    return out


def _mound_heights(spec: TerrainSpec, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    z = np.zeros(np.broadcast(x, y).shape)
    for cx, cy in _mound_centres(spec):
        z += spec.mound_height_m * np.exp(
            -((x - cx) ** 2 + (y - cy) ** 2) / (2 * spec.mound_radius_m**2)
        )
    return z


def build_terrain(spec: TerrainSpec, client: int) -> Terrain:
    """Create the ground body in ``client``; its friction is zero (the force law carries it)."""
    from slipenv.pybullet_quiet import import_pybullet

    p = import_pybullet()  # here, not at module level: a spec alone must not load the engine

    if spec.kind == "mounds":
        n = int(round(spec.size_m / spec.resolution_m)) + 1
        axis = np.linspace(-spec.size_m / 2, spec.size_m / 2, n)
        xx, yy = np.meshgrid(axis, axis, indexing="xy")
        heights = _mound_heights(spec, xx, yy)
        shape = p.createCollisionShape(
            p.GEOM_HEIGHTFIELD,
            meshScale=[spec.resolution_m, spec.resolution_m, 1.0],
            heightfieldData=heights.ravel().tolist(),
            numHeightfieldRows=n,
            numHeightfieldColumns=n,
            physicsClientId=client,
        )
        # PyBullet centres a heightfield vertically on the midpoint of its height range.
        offset = 0.5 * (float(heights.max()) + float(heights.min()))
        body = p.createMultiBody(0, shape, basePosition=[0, 0, offset], physicsClientId=client)
        p.changeVisualShape(body, -1, rgbaColor=[0.76, 0.66, 0.48, 1], physicsClientId=client)
    else:
        shape = p.createCollisionShape(p.GEOM_PLANE, physicsClientId=client)
        slope = math.radians(spec.slope_deg) if spec.kind == "slope" else 0.0
        az = math.radians(spec.downhill_azimuth_deg)
        # Tilt about the horizontal axis perpendicular to the downhill direction.
        tilt_axis = (-math.sin(az), math.cos(az), 0.0)
        quat = p.getQuaternionFromAxisAngle(tilt_axis, slope) if slope > 0 else (0, 0, 0, 1)
        body = p.createMultiBody(0, shape, baseOrientation=quat, physicsClientId=client)
        p.changeVisualShape(body, -1, rgbaColor=[0.6, 0.5, 0.35, 1], physicsClientId=client)
        heights = None
    p.changeDynamics(
        body, -1, lateralFriction=0.0, spinningFriction=0.0, rollingFriction=0.0,
        physicsClientId=client,
    )
    return Terrain(spec, body, heights)
