"""Mounds on an inclined plane: one surface, plane + mounds, whose PyBullet heightfield has the
heights and contact normals of the analytic ground up to the grid's resolution error."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pybullet as p
import pytest

from slipenv.terrain.terrain import (
    TerrainSpec,
    build_terrain,
    gaussian_mound,
    ground_heights,
    plane_heights,
)

SLOPE_DEG = 5.0
DOWNHILL_DEG = 180.0  # the ground rises along +x, as on Reina's climbs
# One broad mound (crest curvature H / r^2 = 0.156 /m) and one small one on a 5 deg plane.
BIG = (2.0, 1.5, 1.5, 0.35)
SMALL = (-2.5, -2.0, 0.6, 0.08)
RESOLUTION_M = 0.05
# Flat triangles between grid points tilt from the true surface by at most about
# h * curvature: 0.05 m * 0.156 /m = 0.45 deg on the broad mound's crest (0.27 deg measured).
# Dropping the plane term would tilt every normal by 5 deg.
NORMAL_TOL_DEG = 0.35


def composed(**overrides) -> TerrainSpec:
    values = dict(kind="mounds", slope_deg=SLOPE_DEG, downhill_azimuth_deg=DOWNHILL_DEG,
                  mound_count=0, placed_mounds=[BIG], size_m=12.0, resolution_m=RESOLUTION_M)
    return TerrainSpec(**{**values, **overrides})


def analytic_normal(slope_deg, downhill_deg, mounds, x, y) -> np.ndarray:
    """Upward unit normal of z = -tan(a) (d . (x, y)) + sum H exp(-|r - c|^2 / (2 R^2)),
    from its closed-form gradient."""
    g = math.tan(math.radians(slope_deg))
    az = math.radians(downhill_deg)
    gx, gy = -g * math.cos(az), -g * math.sin(az)
    for cx, cy, radius, height in mounds:
        e = height * math.exp(-((x - cx) ** 2 + (y - cy) ** 2) / (2 * radius**2))
        gx -= e * (x - cx) / radius**2
        gy -= e * (y - cy) / radius**2
    n = np.array([-gx, -gy, 1.0])
    return n / np.linalg.norm(n)


def angle_deg(a, b) -> float:
    return math.degrees(math.acos(min(1.0, float(np.dot(a, b)))))


@pytest.fixture
def client():
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


def ray_hits(client, xy):
    rays = p.rayTestBatch([[x, y, 10.0] for x, y in xy], [[x, y, -10.0] for x, y in xy],
                          physicsClientId=client)
    return np.array([r[3] for r in rays]), np.array([r[4] for r in rays])


# -- the surface as plain functions -------------------------------------------------------------

@pytest.mark.parametrize("azimuth", [0.0, 90.0, 180.0, -135.0])
def test_the_plane_falls_tan_slope_per_metre_along_its_downhill_azimuth(azimuth):
    az = math.radians(azimuth)
    z = plane_heights(10.0, azimuth, 3.0 * math.cos(az), 3.0 * math.sin(az))
    assert z == pytest.approx(-3.0 * math.tan(math.radians(10.0)), abs=1e-12)
    # Level across the fall line.
    assert plane_heights(10.0, azimuth, -math.sin(az), math.cos(az)) == pytest.approx(0.0,
                                                                                      abs=1e-12)


def test_a_mound_is_its_height_at_the_centre_and_e_to_minus_half_one_radius_out():
    assert gaussian_mound(1.0, 2.0, 1.0, 2.0, 0.5, 0.3) == pytest.approx(0.3)
    assert gaussian_mound(1.5, 2.0, 1.0, 2.0, 0.5, 0.3) == pytest.approx(0.3 * math.exp(-0.5))


def test_mounds_on_a_slope_are_the_level_mounds_plus_the_plane():
    level = TerrainSpec(kind="mounds", mound_count=20, mound_radius_m=0.4, size_m=14.0,
                        placed_mounds=[BIG, SMALL])
    sloped = dataclasses.replace(level, slope_deg=SLOPE_DEG, downhill_azimuth_deg=30.0)
    x, y = np.meshgrid(np.linspace(-7, 7, 57), np.linspace(-7, 7, 57))
    np.testing.assert_allclose(ground_heights(sloped, x, y) - ground_heights(level, x, y),
                               plane_heights(SLOPE_DEG, 30.0, x, y), atol=1e-12)


def test_level_random_mounds_keep_exactly_their_former_heights():
    from slipenv.terrain.terrain import _mound_centres

    spec = TerrainSpec(kind="mounds", mound_count=12, size_m=10.0)
    x, y = np.meshgrid(np.linspace(-5, 5, 41), np.linspace(-5, 5, 41))
    former = np.zeros(x.shape)
    for cx, cy in _mound_centres(spec):
        former += spec.mound_height_m * np.exp(
            -((x - cx) ** 2 + (y - cy) ** 2) / (2 * spec.mound_radius_m**2))
    np.testing.assert_array_equal(ground_heights(spec, x, y), former)


# -- the PyBullet body ----------------------------------------------------------------------------

def test_one_large_placed_mound_stands_where_asked_on_the_slope(client):
    spec = composed()
    terrain = build_terrain(spec, client)
    cx, cy, _, height = BIG
    rise = math.tan(math.radians(SLOPE_DEG)) * cx  # the plane rises along +x
    assert terrain.height(cx, cy) == pytest.approx(rise + height, abs=1e-12)
    hits, _ = ray_hits(client, [(cx, cy), (-4.0, -4.0)])
    assert hits[0, 2] == pytest.approx(rise + height, abs=2e-4)
    # Far from the mound the ground is the bare plane.
    assert hits[1, 2] == pytest.approx(-4.0 * math.tan(math.radians(SLOPE_DEG)), abs=2e-4)


def test_heightfield_heights_match_the_analytic_ground_across_the_field(client):
    spec = composed(placed_mounds=[BIG, SMALL], mound_count=8, mound_radius_m=0.5,
                    mound_height_m=0.1)
    terrain = build_terrain(spec, client)
    xy = np.random.default_rng(3).uniform(-5.5, 5.5, size=(800, 2))
    hits, _ = ray_hits(client, xy)
    expected = [terrain.height(x, y) for x, y in xy]
    # Flat triangles between grid points: error <= curvature x h^2 / 2 = 0.4 /m x (0.05 m)^2 / 2
    # = 0.5 mm (0.27 mm measured); a lost plane term or vertical offset is 0.1-0.5 m.
    curvature = 0.1 / 0.5**2
    np.testing.assert_allclose(hits[:, 2], expected, atol=curvature * RESOLUTION_M**2 / 2)


def test_terrain_normal_is_the_analytic_normal_of_plane_plus_mounds(client):
    terrain = build_terrain(composed(placed_mounds=[BIG, SMALL]), client)
    for x, y in [(0.0, 0.0), (2.0, 0.5), (3.1, 2.4), (-2.2, -2.3), (-4.0, 4.0)]:
        np.testing.assert_allclose(
            terrain.normal(x, y),
            analytic_normal(SLOPE_DEG, DOWNHILL_DEG, [BIG, SMALL], x, y), atol=1e-6)


def test_ray_normals_of_the_heightfield_are_the_analytic_normals(client):
    spec = composed()
    build_terrain(spec, client)
    xy = np.random.default_rng(7).uniform(-5.5, 5.5, size=(600, 2))
    _, normals = ray_hits(client, xy)
    errors = [angle_deg(n, analytic_normal(SLOPE_DEG, DOWNHILL_DEG, [BIG], x, y))
              for (x, y), n in zip(xy, normals, strict=True)]
    assert max(errors) < NORMAL_TOL_DEG
    # The tolerance sees the plane: the level mound's normals are 5 deg off.
    level = [angle_deg(n, analytic_normal(0.0, DOWNHILL_DEG, [BIG], x, y))
             for (x, y), n in zip(xy, normals, strict=True)]
    assert min(level) > 4.5


@pytest.mark.parametrize(("where", "x", "y"), [
    ("flank of the mound, across the slope", 2.0, 0.0),  # the ground falls to -y and -x
    ("flank of the mound, facing downhill", 0.5, 1.5),
    ("crest of the mound", 2.0, 1.5),
    ("bare plane between the mounds", 0.0, -3.5),
    ("foot of the small mound", -2.5, -1.4),
])
def test_a_sphere_on_the_ground_is_pushed_along_the_analytic_normal(client, where, x, y):
    mounds = [BIG, SMALL]
    spec = composed(placed_mounds=mounds)
    terrain = build_terrain(spec, client)
    radius = 0.1
    n = analytic_normal(SLOPE_DEG, DOWNHILL_DEG, mounds, x, y)
    centre = np.array([x, y, terrain.height(x, y)]) + n * (radius + 0.001)
    sphere = p.createMultiBody(
        1.0, p.createCollisionShape(p.GEOM_SPHERE, radius=radius, physicsClientId=client),
        basePosition=centre.tolist(), physicsClientId=client)
    contacts = p.getClosestPoints(sphere, terrain.body_id, 0.01, physicsClientId=client)
    assert contacts, where
    deepest = min(contacts, key=lambda c: c[8])
    normal_on_ground = np.array(deepest[7])  # contactNormalOnB: on the ground, towards A
    contact_xy = deepest[6][:2]
    expected = analytic_normal(SLOPE_DEG, DOWNHILL_DEG, mounds, *contact_xy)
    assert angle_deg(normal_on_ground, expected) < NORMAL_TOL_DEG, where
    assert deepest[8] == pytest.approx(0.001, abs=5e-4), where  # it touches where placed


# -- today's kinds unchanged ----------------------------------------------------------------------

@pytest.mark.parametrize("kind", ["flat", "slope"])
def test_flat_and_slope_are_still_infinite_planes(client, kind):
    terrain = build_terrain(TerrainSpec(kind=kind, slope_deg=SLOPE_DEG,
                                        downhill_azimuth_deg=DOWNHILL_DEG), client)
    shape = p.getCollisionShapeData(terrain.body_id, -1, physicsClientId=client)[0]
    assert shape[2] == p.GEOM_PLANE
    grade = math.tan(math.radians(SLOPE_DEG)) if kind == "slope" else 0.0
    far = 400.0  # well beyond any heightfield
    assert terrain.height(far, 0.0) == pytest.approx(grade * far)
    hit = p.rayTest([far, 0.0, grade * far + 1.0], [far, 0.0, grade * far - 1.0],
                    physicsClientId=client)[0]
    assert hit[0] == terrain.body_id and hit[3][2] == pytest.approx(grade * far, abs=1e-6)


# -- options ----------------------------------------------------------------------------------

def test_placed_mounds_from_json_give_the_same_spec():
    spec = composed(placed_mounds=[BIG, {"x_m": -2.5, "y_m": -2.0, "radius_m": 0.6,
                                         "height_m": 0.08}])
    assert spec.placed_mounds == (BIG, SMALL)
    again = TerrainSpec(**json.loads(json.dumps(dataclasses.asdict(spec))))
    assert again == spec and hash(again) == hash(spec)


def test_a_terrain_dict_from_the_env_config_reaches_the_spec():
    from slipenv.envs.config import SlipEnvConfig

    cfg = SlipEnvConfig.from_kwargs(terrain={"kind": "mounds", "slope_deg": 5,
                                             "mound_count": 0, "placed_mounds": [list(BIG)]})
    assert cfg.terrain.plane_slope_deg == 5.0 and cfg.terrain.placed_mounds == (BIG,)
    with pytest.raises(ValueError, match=r"terrain: TerrainSpec.placed_mounds\[0\]"):
        SlipEnvConfig.from_kwargs(terrain={"kind": "mounds", "placed_mounds": [[0, 0, 1]]})


def test_the_summary_names_the_plane_and_every_mound():
    summary = composed(placed_mounds=[BIG]).summary()
    assert summary["slope_deg"] == SLOPE_DEG and summary["downhill_azimuth_deg"] == 180.0
    assert summary["placed_mounds"] == [{"x_m": 2.0, "y_m": 1.5, "radius_m": 1.5,
                                         "height_m": 0.35}]
    assert summary["random_mounds"]["count"] == 0
    json.dumps(summary)
    assert TerrainSpec(kind="flat", slope_deg=5.0).summary()["slope_deg"] == 0.0


@pytest.mark.parametrize(("bad", "message"), [
    (dict(placed_mounds=[(7.0, 0.0, 1.0, 0.2)]), r"placed_mounds\[0\]: centre"),
    (dict(placed_mounds=[BIG, (0.0, 0.0, 0.0, 0.2)]), r"placed_mounds\[1\]: radius_m"),
    (dict(placed_mounds=[(0.0, 0.0, 3.5, 0.2)]), r"placed_mounds\[0\]: radius_m"),
    (dict(placed_mounds=[(0.0, 0.0, 1.0, 6.0)]), r"placed_mounds\[0\]: height_m"),
    (dict(placed_mounds=[(0.0, 0.0, 1.0, -0.1)]), r"placed_mounds\[0\]: height_m"),
    (dict(placed_mounds=[(0.0, 0.0, 1.0)]), r"placed_mounds\[0\] must be"),
    (dict(placed_mounds=[(0.0, float("nan"), 1.0, 0.1)]), r"placed_mounds\[0\]: y_m"),
    (dict(placed_mounds=[{"x_m": 0, "y_m": 0, "radius": 1, "height_m": 0.1}]),
     r"placed_mounds\[0\] must have the keys"),
    (dict(placed_mounds="big"), "placed_mounds must be a list"),
    (dict(kind="slope", placed_mounds=[BIG]), "placed_mounds applies to kind 'mounds'"),
    (dict(slope_deg=46.0), "slope_deg"),
    (dict(mound_count=1000), "mound_count"),
])
def test_a_bad_composed_terrain_is_a_value_error_naming_the_field(bad, message):
    with pytest.raises(ValueError, match=message):
        composed(**bad)
