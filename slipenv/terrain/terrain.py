"""Ground geometry: flat plane, tilted plane (any slope and direction), heightfield mounds on a
level or tilted plane.

A :class:`TerrainSpec` is pure configuration; :func:`build_terrain` creates the PyBullet body
and returns a :class:`Terrain` that also answers height and normal queries (used to spawn the
vehicle and to express ground truth). Soil is separate (``slipenv.terramechanics``): geometry
and soil vary independently.

The ``mounds`` ground is one surface, z = plane(x, y) + sum of Gaussian mounds(x, y), sampled
on a square grid into a PyBullet heightfield. Between grid points the heightfield is flat
triangles, so a plane is represented exactly and a mound to second order: the face slope
differs from the true slope by about (grid spacing) x (largest curvature) at most, e.g.
0.05 m x 0.49 /m = 0.025 rad (1.4 deg) on the crest of a 0.10 m high, 0.45 m radius mound
(over 220 such mounds on a 5 deg plane, ray tests measure 1.5 deg at most, 0.26 deg RMS; the
heights are off by 0.5 mm at most; halving the spacing halves the slope error and quarters the
height error).
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
PLACED_MOUND_KEYS = ("x_m", "y_m", "radius_m", "height_m")


@dataclass(frozen=True)
class TerrainSpec:
    """Ground geometry.

    Attributes
    ----------
    kind : str
        ``flat`` | ``slope`` | ``mounds``.
    slope_deg : float
        Inclination of the plane [deg], 0 <= slope < 45: the ground of ``slope``, the ground
        the mounds stand on for ``mounds`` (0: level). ``flat`` ignores it.
    downhill_azimuth_deg : float
        Direction of steepest descent, counter-clockwise from world x [deg] (log-format
        ``slope_downhill_azimuth_deg``); the plane passes through the world origin.
    mound_count : int
        Number of Gaussian mounds for ``mounds`` placed at random (``layout_seed``).
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
        Radius around the origin kept free of the random mounds so the vehicle spawns on the
        bare plane [m].
    placed_mounds : tuple
        Mounds at given places for ``mounds``, added to the random ones: each a
        ``(x_m, y_m, radius_m, height_m)`` tuple or a dict with those keys (centre [m],
        standard deviation of the Gaussian profile [m], peak height above the plane [m]).
        One large mound alone is ``mound_count=0, placed_mounds=[(x, y, r, h)]``. Stored as a
        tuple of 4-tuples of floats. The clear disc does not apply: a placed mound is where
        it is asked to be.

    Notes
    -----
    Bounds (``ValueError`` naming the field otherwise): numbers finite, counts integers;
    0 <= slope < 45 deg, |azimuth| <= 360 deg, 0 < mound height <= 5 m, 0 < size <= 1000 m,
    mound_count <= 1000; for ``mounds`` the heightfield has at most 2049 points a side, mound
    centres (kept two radii inside the edge) must fit outside the clear disc, and their
    placement is a bounded draw, so an impossible layout fails instead of hanging. Placed
    mounds: centres inside the field, 0 < radius < size_m / 4, 0 < height <= 5 m, and only
    for ``mounds``.
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
    placed_mounds: tuple = ()

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
        object.__setattr__(self, "placed_mounds", _placed_mounds(self.placed_mounds))
        if self.placed_mounds and self.kind != "mounds":
            raise ValueError(f"TerrainSpec.placed_mounds applies to kind 'mounds', not "
                             f"{self.kind!r} (mounds on a slope: kind='mounds', slope_deg=...)")
        if self.kind == "mounds":
            self._check_mounds()

    @property
    def plane_slope_deg(self) -> float:
        """Inclination of the plane under everything [deg] (0 for ``flat``)."""
        return 0.0 if self.kind == "flat" else float(self.slope_deg)

    def summary(self) -> dict:
        """The ground in a few JSON-friendly numbers (for reports and run records)."""
        out: dict = {"kind": self.kind, "slope_deg": self.plane_slope_deg,
                     "downhill_azimuth_deg": float(self.downhill_azimuth_deg)}
        if self.kind == "mounds":
            out.update(size_m=float(self.size_m), resolution_m=float(self.resolution_m),
                       random_mounds={"count": int(self.mound_count),
                                      "height_m": float(self.mound_height_m),
                                      "radius_m": float(self.mound_radius_m),
                                      "layout_seed": int(self.layout_seed),
                                      "clear_radius_m": float(self.clear_radius_m)},
                       placed_mounds=[dict(zip(PLACED_MOUND_KEYS, m, strict=True)) for m in
                                      self.placed_mounds])
        return out

    def _check_mounds(self) -> None:
        """Mound-field options that are fine one by one but not together."""
        if self.mound_count + len(self.placed_mounds) > MAX_MOUNDS:
            raise ValueError(
                f"TerrainSpec.mound_count must be <= {MAX_MOUNDS} (with placed_mounds), got "
                f"{self.mound_count} + {len(self.placed_mounds)} placed"
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
        for i, (x, y, radius, height) in enumerate(self.placed_mounds):
            where = f"TerrainSpec.placed_mounds[{i}]"
            if max(abs(x), abs(y)) > self.size_m / 2:
                raise ValueError(f"{where}: centre ({x:g}, {y:g}) m lies outside the "
                                 f"{self.size_m:g} m field (|x|, |y| <= {self.size_m / 2:g} m)")
            if not 0.0 < radius < self.size_m / 4:
                raise ValueError(f"{where}: radius_m must be > 0 and < size_m / 4 = "
                                 f"{self.size_m / 4:g} m, got {radius!r}")
            if not 0.0 < height <= MAX_MOUND_HEIGHT_M:
                raise ValueError(f"{where}: height_m must be > 0 and <= "
                                 f"{MAX_MOUND_HEIGHT_M:g}, got {height!r}")
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


def _placed_mounds(value) -> tuple:
    """``placed_mounds`` as a tuple of ``(x, y, radius, height)`` float tuples: hashable, so a
    spec stays a cache key and comparable after a JSON round trip (lists, dicts)."""
    if value is None:
        return ()
    if isinstance(value, (str, bytes, dict)) or not hasattr(value, "__iter__"):
        raise ValueError("TerrainSpec.placed_mounds must be a list of (x_m, y_m, radius_m, "
                         f"height_m) or of dicts with those keys, got {value!r}")
    out = []
    for i, mound in enumerate(value):
        where = f"TerrainSpec.placed_mounds[{i}]"
        if isinstance(mound, dict):
            unknown = sorted(set(mound) - set(PLACED_MOUND_KEYS))
            missing = [k for k in PLACED_MOUND_KEYS if k not in mound]
            if unknown or missing:
                raise ValueError(f"{where} must have the keys {PLACED_MOUND_KEYS}; unknown "
                                 f"{unknown}, missing {missing}")
            mound = [mound[k] for k in PLACED_MOUND_KEYS]
        elif isinstance(mound, (str, bytes)) or not hasattr(mound, "__len__") \
                or len(mound) != 4:
            raise ValueError(f"{where} must be (x_m, y_m, radius_m, height_m), got {mound!r}")
        for key, v in zip(PLACED_MOUND_KEYS, mound, strict=True):
            if not _is_real(v) or not math.isfinite(v):
                raise ValueError(f"{where}: {key} must be a finite number, got {v!r}")
        out.append(tuple(float(v) for v in mound))
    return tuple(out)


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
        self._grade = math.tan(math.radians(spec.plane_slope_deg))

    def height(self, x_m: float, y_m: float) -> float:
        """Ground height at (x, y) [m]: the analytic surface the heightfield samples."""
        if self.spec.kind == "mounds":
            return float(ground_heights(self.spec, np.array([x_m]), np.array([y_m]))[0])
        return -self._grade * (self._downhill[0] * x_m + self._downhill[1] * y_m)

    def normal(self, x_m: float, y_m: float) -> tuple[float, float, float]:
        """Unit upward normal of the analytic surface at (x, y)."""
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


def plane_heights(slope_deg: float, downhill_azimuth_deg: float, x, y) -> np.ndarray:
    """Height of the plane through the origin falling at ``slope_deg`` towards
    ``downhill_azimuth_deg`` (counter-clockwise from world x): z = -tan(slope) (d . (x, y))."""
    az = math.radians(downhill_azimuth_deg)
    return -math.tan(math.radians(slope_deg)) * (math.cos(az) * np.asarray(x)
                                                 + math.sin(az) * np.asarray(y))


def gaussian_mound(x, y, cx: float, cy: float, radius_m: float, height_m: float) -> np.ndarray:
    """One mound: height_m exp(-((x - cx)^2 + (y - cy)^2) / (2 radius_m^2))."""
    return height_m * np.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * radius_m**2))


def ground_heights(spec: TerrainSpec, x, y) -> np.ndarray:
    """Height of the ``mounds`` ground: the plane plus every random and placed mound."""
    z = np.zeros(np.broadcast(x, y).shape)
    for cx, cy in _mound_centres(spec):
        z += gaussian_mound(x, y, cx, cy, spec.mound_radius_m, spec.mound_height_m)
    for cx, cy, radius, height in spec.placed_mounds:
        z += gaussian_mound(x, y, cx, cy, radius, height)
    if spec.slope_deg > 0.0:  # a level field keeps exactly its former heights
        z += plane_heights(spec.slope_deg, spec.downhill_azimuth_deg, x, y)
    return z


def build_terrain(spec: TerrainSpec, client: int) -> Terrain:
    """Create the ground body in ``client``; its friction is zero (the force law carries it)."""
    from slipenv.pybullet_quiet import import_pybullet

    p = import_pybullet()  # here, not at module level: a spec alone must not load the engine

    if spec.kind == "mounds":
        n = grid_points(spec)
        axis = np.linspace(-spec.size_m / 2, spec.size_m / 2, n)
        xx, yy = np.meshgrid(axis, axis, indexing="xy")
        heights = ground_heights(spec, xx, yy)
        shape = p.createCollisionShape(
            p.GEOM_HEIGHTFIELD,
            meshScale=[spec.resolution_m, spec.resolution_m, 1.0],
            heightfieldData=heights.ravel().tolist(),
            numHeightfieldRows=n,
            numHeightfieldColumns=n,
            physicsClientId=client,
        )
        # PyBullet centres the grid on the body origin in x and y (the linspace above does too)
        # and vertically on the midpoint of its height range.
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
