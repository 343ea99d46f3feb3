"""Terrain geometry: heights and normals agree with what PyBullet built."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from slipenv.terrain.terrain import TerrainSpec, build_terrain


@pytest.fixture
def client():
    cid = p.connect(p.DIRECT)
    yield cid
    p.disconnect(cid)


def ray_height(client, x, y):
    return p.rayTest([x, y, 10], [x, y, -10], physicsClientId=client)[0][3][2]


@pytest.mark.parametrize("azimuth", [0.0, 90.0, -135.0])
def test_a_slope_descends_along_its_downhill_azimuth(client, azimuth):
    terrain = build_terrain(TerrainSpec(kind="slope", slope_deg=15.0,
                                        downhill_azimuth_deg=azimuth), client)
    az = math.radians(azimuth)
    x, y = 2.0 * math.cos(az), 2.0 * math.sin(az)
    assert terrain.height(x, y) == pytest.approx(-2.0 * math.tan(math.radians(15)))
    assert ray_height(client, x, y) == pytest.approx(terrain.height(x, y), abs=1e-6)
    nx, ny, nz = terrain.normal(x, y)
    assert nz == pytest.approx(math.cos(math.radians(15)))
    # The normal leans downhill.
    assert nx * math.cos(az) + ny * math.sin(az) == pytest.approx(math.sin(math.radians(15)))


def test_mounds_match_the_pybullet_heightfield(client):
    spec = TerrainSpec(kind="mounds", mound_count=6, mound_height_m=0.2, size_m=10.0,
                       resolution_m=0.05)
    terrain = build_terrain(spec, client)
    for x, y in [(0.0, 0.0), (1.3, -2.1), (-3.0, 2.5), (3.7, 3.1)]:
        assert ray_height(client, x, y) == pytest.approx(terrain.height(x, y), abs=5e-3)
    assert terrain.height(0.0, 0.0) < 0.01  # the spawn area is kept clear


@pytest.mark.parametrize("bad", [dict(kind="cliff"), dict(slope_deg=50.0),
                                 dict(mound_height_m=-1.0), dict(mound_count=-2)])
def test_bad_terrain_is_a_value_error(bad):
    with pytest.raises(ValueError):
        TerrainSpec(**bad)


@pytest.mark.parametrize(("bad", "name"), [
    (dict(kind="mounds", clear_radius_m=100.0), "clear_radius_m"),
    (dict(kind="mounds", clear_radius_m=14.0), "clear_radius_m"),  # feasible corner, no room
    (dict(kind="mounds", mound_radius_m=10.0), "mound_radius_m"),
    (dict(kind="mounds", size_m=0.5), "size_m"),
    (dict(kind="mounds", resolution_m=1e-4), "resolution_m"),
    (dict(kind="mounds", mound_count=2.5), "mound_count"),
    (dict(kind="mounds", mound_count=10**6), "mound_count"),
    (dict(kind="slope", downhill_azimuth_deg=float("nan")), "downhill_azimuth_deg"),
    (dict(kind="slope", slope_deg="5"), "slope_deg"),
    (dict(kind="mound"), "did you mean 'mounds'"),
])
def test_an_impossible_terrain_fails_promptly_naming_the_option(bad, name):
    import time

    start = time.monotonic()
    with pytest.raises(ValueError, match=name):
        TerrainSpec(**bad)
    assert time.monotonic() - start < 1.0  # the mound draw is bounded: no hang


def test_the_mound_layout_is_cached_and_unchanged_by_the_bounded_draw():
    from slipenv.terrain.terrain import _mound_centres

    spec = TerrainSpec(kind="mounds", mound_count=30, mound_radius_m=0.4, size_m=14.0,
                       clear_radius_m=0.6)
    centres = _mound_centres(spec)
    assert centres.shape == (30, 2) and _mound_centres(spec) is centres
    assert np.all(np.hypot(*centres.T) > 0.6 + 0.8)
