"""Ground geometry: flat plane, tilted plane (any slope and direction), heightfield mounds.

A :class:`TerrainSpec` is pure configuration; :func:`build_terrain` creates the PyBullet body
and returns a :class:`Terrain` that also answers height and normal queries (used to spawn the
vehicle and to express ground truth). Soil is separate (``slipenv.terramechanics``): geometry
and soil vary independently.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

TERRAIN_KINDS = ("flat", "slope", "mounds")


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
        if self.kind not in TERRAIN_KINDS:
            raise ValueError(f"TerrainSpec.kind must be one of {TERRAIN_KINDS}, got {self.kind!r}")
        if not (0.0 <= self.slope_deg < 45.0):
            raise ValueError(f"TerrainSpec.slope_deg must be in [0, 45), got {self.slope_deg!r}")
        for name in ("mound_height_m", "mound_radius_m", "size_m", "resolution_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"TerrainSpec.{name} must be finite and > 0, got {value!r}")
        if self.mound_count < 0:
            raise ValueError(f"TerrainSpec.mound_count must be >= 0, got {self.mound_count}")


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


def _mound_centres(spec: TerrainSpec) -> np.ndarray:
    rng = np.random.default_rng(spec.layout_seed)
    half = spec.size_m / 2 - 2 * spec.mound_radius_m
    centres = []
    while len(centres) < spec.mound_count:
        c = rng.uniform(-half, half, size=2)
        if np.hypot(*c) > spec.clear_radius_m + 2 * spec.mound_radius_m:
            centres.append(c)
    return np.array(centres).reshape(-1, 2)


def _mound_heights(spec: TerrainSpec, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    z = np.zeros(np.broadcast(x, y).shape)
    for cx, cy in _mound_centres(spec):
        z += spec.mound_height_m * np.exp(
            -((x - cx) ** 2 + (y - cy) ** 2) / (2 * spec.mound_radius_m**2)
        )
    return z


def build_terrain(spec: TerrainSpec, client: int) -> Terrain:
    """Create the ground body in ``client``; its friction is zero (the force law carries it)."""
    import pybullet as p  # imported here: a spec alone must not load the physics engine

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
        axis = (-math.sin(az), math.cos(az), 0.0)
        quat = p.getQuaternionFromAxisAngle(axis, slope) if slope > 0 else (0, 0, 0, 1)
        body = p.createMultiBody(0, shape, baseOrientation=quat, physicsClientId=client)
        p.changeVisualShape(body, -1, rgbaColor=[0.6, 0.5, 0.35, 1], physicsClientId=client)
        heights = None
    p.changeDynamics(
        body, -1, lateralFriction=0.0, spinningFriction=0.0, rollingFriction=0.0,
        physicsClientId=client,
    )
    return Terrain(spec, body, heights)
