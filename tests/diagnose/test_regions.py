"""``slipenv.diagnose.regions``: the per-interval quadratic of a soil map and the search for
rectangles with continuous edges, checked on linear worlds whose exact answer is known."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from slipenv.diagnose import regions

# region 0 a rectangle, region 1 an L of two rectangles
TRUE = regions.Layout(((-3.0, -3.0, -0.4, 0.2), (1.1, 0.7, 3.3, 3.6), (1.1, -2.5, 2.2, 0.7)),
                      (0, 1, 1))
TRUE_LEVELS = np.array([0.008, 0.005])


# region 0 a disc, region 1 an L of two rectangles
DISC_AND_L = regions.Layout((regions.disc((-1.6, 1.4), 1.7), (0.5, -3.5, 3.5, -1.5),
                             (2.0, -1.5, 3.5, 1.0)), (0, 1, 1),
                            (regions.DISC, regions.RECT, regions.RECT))


def _linear_world(seed: int = 0, segments: int = 30, intervals: int = 16, rows: int = 12,
                  noise: float = 0.0, true: regions.Layout = TRUE,
                  levels: np.ndarray = TRUE_LEVELS):
    """Segments of ``intervals`` points scattered over a 8 m square, residuals linear in the
    per-interval compliance (r = r0 + D C) with r0 = -D C_true (+ noise): the true map's
    cost is the noise alone."""
    rng = np.random.default_rng(seed)
    uv = rng.uniform(-4.0, 4.0, (segments, intervals, 2))
    d = rng.normal(0.0, 1.0, (segments, rows, intervals))
    truth = regions.compliance(uv, true, levels)
    r0 = -np.einsum("srj,sj->sr", d, truth) + noise * rng.normal(size=(segments, rows))
    seg_of_row = np.repeat(np.arange(segments), rows)

    def residuals(j: int, c: float) -> np.ndarray:
        return (r0 + c * d[:, :, j]).ravel()

    q = regions.Quadratic.from_residuals(residuals, seg_of_row, intervals, 1e-3, uv)
    return q, d, r0, uv


def test_the_quadratic_scores_any_map_as_the_residuals_would():
    q, d, r0, uv = _linear_world()
    rng = np.random.default_rng(1)
    for _ in range(3):
        c = rng.normal(0.0, 0.01, uv.shape[:2])
        exact = np.sum((r0 + np.einsum("srj,sj->sr", d, c)) ** 2, axis=1)
        np.testing.assert_allclose(q.segment_costs(c), exact, rtol=1e-9)


def _best_by_solve(q, layout: regions.Layout, k: int, shapes) -> float:
    """The least cost the plain solve gives with shape ``k`` replaced by each of ``shapes``
    (those adding something to its region, with every level positive)."""
    others = layout.masks(q.uv, skip=k)[layout.labels[k]]
    best = np.inf
    for shape in shapes:
        if not np.any((regions.inside(q.uv, shape, layout.kinds[k]) > 0) & (others == 0)):
            continue  # the shape adds nothing to its region
        levels, cost = regions.solve(q, layout.with_rect(k, shape))
        if np.all(levels > 0):
            best = min(best, cost)
    return best


def _assert_scan_found(q, scanned, best: float) -> None:
    """A scan's (layout, levels, cost) is the brute-force best and its own solve."""
    found, levels, cost = scanned
    assert cost == pytest.approx(best, rel=1e-9)
    again, again_cost = regions.solve(q, found)
    np.testing.assert_allclose(again, levels, rtol=1e-9)
    assert again_cost == pytest.approx(cost, rel=1e-9)


def test_an_edge_scan_finds_the_best_cut_that_brute_force_finds():
    q, *_ = _linear_world(noise=0.05)
    limits = regions.limits_of(q.uv)
    # two regions, the second of two overlapping rectangles (a union: no double count)
    layout = regions.Layout(((-2.0, -2.5, 0.5, 1.0), (1.5, 1.0, 3.0, 3.0),
                             (1.0, -1.0, 2.5, 2.0)), (0, 1, 1))
    for k in range(3):
        for edge in range(4):
            # every cut between two data coordinates, scored by the plain solve
            coords = np.unique(q.uv[..., edge % 2])
            rects = []
            for cut in np.concatenate([0.5 * (coords[1:] + coords[:-1]), [limits[edge]]]):
                rect = list(layout.rects[k])
                rect[edge] = cut
                if rect[2] > rect[0] and rect[3] > rect[1]:
                    rects.append(tuple(rect))
            _assert_scan_found(q, regions.scan_edge(q, layout, k, edge, limits),
                               _best_by_solve(q, layout, k, rects))


def test_a_radius_scan_finds_the_best_radius_that_brute_force_finds():
    q, *_ = _linear_world(noise=0.05, true=DISC_AND_L)
    limits = regions.limits_of(q.uv)
    layout = regions.Layout((regions.disc((-1.0, 1.0), 1.0), (0.5, -3.0, 3.0, -1.0),
                             regions.disc((2.5, -2.0), 1.0)), (0, 1, 1),
                            (regions.DISC, regions.RECT, regions.DISC))
    for k, centre in ((0, (-1.5, 1.5)), (0, (0.3, -0.2)), (2, (2.0, 0.0))):
        scanned = regions.scan_radius(q, layout, k, centre, limits)
        assert scanned[0].kinds[k] == regions.DISC
        np.testing.assert_allclose(regions.disc_of(scanned[0].rects[k])[0], centre, atol=1e-12)
        # every radius between two data distances, scored by the plain solve
        dist = np.unique(np.hypot(q.uv[..., 0] - centre[0], q.uv[..., 1] - centre[1]))
        radii = np.concatenate([0.5 * (dist[1:] + dist[:-1]), [dist[-1] + 1.0]])
        _assert_scan_found(q, scanned, _best_by_solve(q, layout, k,
                                                      [regions.disc(centre, r) for r in radii]))


def test_scans_keep_every_shape_at_least_the_minimum_size_and_are_best_among_those():
    q, *_ = _linear_world(noise=0.05)
    q = dataclasses.replace(q, min_size_m=1.7)
    limits = regions.limits_of(q.uv)
    layout = regions.Layout(((-2.0, -2.5, 0.5, 1.0), regions.disc((2.0, 2.0), 1.0)), (0, 1),
                            (regions.RECT, regions.DISC))
    for edge in range(4):
        axis, lower = edge % 2, edge < 2
        opposite = layout.rects[0][edge + 2 if lower else edge - 2]
        coords = np.unique(q.uv[..., axis])
        mids = np.concatenate([0.5 * (coords[1:] + coords[:-1]), [limits[edge]]])
        # each cut moved to the minimum size where it would make the rectangle narrower
        cuts = np.minimum(mids, opposite - 1.7) if lower else np.maximum(mids, opposite + 1.7)
        rects = [tuple(cut if i == edge else e for i, e in enumerate(layout.rects[0]))
                 for cut in cuts]
        scanned = regions.scan_edge(q, layout, 0, edge, limits)
        u0, v0, u1, v1 = scanned[0].rects[0]
        assert min(u1 - u0, v1 - v0) >= 1.7 - 1e-12
        _assert_scan_found(q, scanned, _best_by_solve(q, layout, 0, rects))
    centre = (0.3, -0.2)
    dist = np.unique(np.hypot(q.uv[..., 0] - centre[0], q.uv[..., 1] - centre[1]))
    radii = np.maximum(np.concatenate([0.5 * (dist[1:] + dist[:-1]), [dist[-1] + 1.0]]), 0.85)
    scanned = regions.scan_radius(q, layout, 1, centre, limits)
    assert regions.disc_of(scanned[0].rects[1])[1] >= 0.85 - 1e-12
    _assert_scan_found(q, scanned, _best_by_solve(q, layout, 1,
                                                  [regions.disc(centre, r) for r in radii]))


def test_an_edge_moved_past_the_last_point_keeps_the_minimum_size_beyond_the_map():
    border = regions.Layout(((-4.5, -4.5, -3.4, 4.5),), (0,))  # soft ground along one border
    q, *_ = _linear_world(segments=60, true=border, levels=TRUE_LEVELS[:1])
    q = dataclasses.replace(q, min_size_m=1.7)
    limits = regions.limits_of(q.uv)
    start = regions.Layout(((-3.6, -4.5, -3.4, 4.5),), (0,))
    found, _, cost = regions.scan_edge(q, start, 0, 0, limits)
    u0, _, u1, _ = found.rects[0]
    assert cost < 1e-6 * q.rr.sum()  # every soft interval in: the edge went past the last
    assert u1 - limits[0] < 1.7  # the map's limit alone would leave it narrower
    assert u0 == pytest.approx(u1 - 1.7) and u0 < limits[0]


def test_a_strip_narrower_than_the_minimum_size_is_not_fitted_as_a_sliver():
    strip = regions.Layout(((-4.0, -0.2, 4.0, 0.2),), (0,))  # 0.4 m wide, across the map
    q, *_ = _linear_world(segments=60, true=strip, levels=TRUE_LEVELS[:1])
    limits = regions.limits_of(q.uv)
    sliver = regions.grow(q, limits, 1, 1)[0][0].rects[0]
    assert sliver[3] - sliver[1] < 0.6  # without a minimum, the strip itself
    for shapes, *_ in regions.grow(dataclasses.replace(q, min_size_m=1.5), limits, 3, 3):
        for rect in shapes.rects:
            assert min(rect[2] - rect[0], rect[3] - rect[1]) >= 1.5 - 1e-12


def test_a_disc_and_an_l_shaped_region_are_found_the_disc_as_one_disc():
    q, *_ = _linear_world(segments=80, true=DISC_AND_L)
    path = regions.grow(q, regions.limits_of(q.uv), 4, 3)
    layout, levels, cost = path[2]  # three shapes
    assert cost < 1e-6 * q.rr.sum()  # every interval on the right side of every edge
    assert sorted(layout.kinds) == [regions.RECT, regions.RECT, regions.DISC]
    (centre, radius), = [regions.disc_of(r) for r, kind in zip(layout.rects, layout.kinds,
                                                               strict=True)
                         if kind == regions.DISC]
    spacing = 8.0 / np.sqrt(q.uv[..., 0].size)  # the data's spacing
    assert np.hypot(centre[0] + 1.6, centre[1] - 1.4) < 0.5 * spacing
    assert abs(radius - 1.7) < 0.5 * spacing
    # the fitted map matches the truth everywhere but within the data spacing of an edge (the
    # L may come as two regions of one compliance: the same ground)
    grid = np.stack(np.meshgrid(np.linspace(-4, 4, 161), np.linspace(-4, 4, 161)), axis=-1)
    true = regions.compliance(grid, DISC_AND_L, TRUE_LEVELS)
    edges = np.abs(np.hypot(grid[..., 0] + 1.6, grid[..., 1] - 1.4) - 1.7) < 2 * spacing
    for u0, v0, u1, v1 in DISC_AND_L.rects[1:]:
        for a, axis in ((u0, 0), (u1, 0), (v0, 1), (v1, 1)):
            edges |= np.abs(grid[..., axis] - a) < 2 * spacing
    fitted = regions.compliance(grid, layout, levels)
    assert np.allclose(fitted[~edges], true[~edges], atol=0.02 * TRUE_LEVELS.max())
    # rectangles alone leave a staircase's error with as many shapes
    assert regions.grow(q, regions.limits_of(q.uv), 4, 3, discs=False)[2][2] > 0.03 * q.rr.sum()


def test_a_rectangle_and_an_l_shaped_region_are_found_with_their_compliances():
    q, *_ = _linear_world(segments=80)
    path = regions.grow(q, regions.limits_of(q.uv), 4, 3)
    layout, levels, cost = path[2]  # three rectangles
    assert cost < 0.01 * q.rr.sum()  # they explain nearly everything (a local optimum)
    assert layout.count == 2
    np.testing.assert_allclose(np.sort(levels), np.sort(TRUE_LEVELS), rtol=0.02)
    # the fitted map matches the truth everywhere but within the data spacing of an edge
    grid = np.stack(np.meshgrid(np.linspace(-4, 4, 161), np.linspace(-4, 4, 161)), axis=-1)
    fitted = regions.compliance(grid, layout, levels)
    true = regions.compliance(grid, TRUE, TRUE_LEVELS)
    spacing = 8.0 / np.sqrt(q.uv[..., 0].size)
    edges = np.zeros(grid.shape[:2], bool)
    for u0, v0, u1, v1 in TRUE.rects:
        for a, axis in ((u0, 0), (u1, 0), (v0, 1), (v1, 1)):
            edges |= np.abs(grid[..., axis] - a) < 2 * spacing
    assert np.allclose(fitted[~edges], true[~edges], atol=0.02 * TRUE_LEVELS.max())


def test_no_soft_region_is_found_where_the_ground_is_uniform():
    rng = np.random.default_rng(3)
    uv = rng.uniform(-4.0, 4.0, (20, 10, 2))
    d = rng.normal(size=(20, 8, 10))
    r0 = 0.01 * np.abs(rng.normal(size=(20, 8)))  # no compliance lowers this cost on its own
    d = np.abs(d)  # every positive compliance raises it
    q = regions.Quadratic.from_residuals(lambda j, c: (r0 + c * d[:, :, j]).ravel(),
                                         np.repeat(np.arange(20), 8), 10, 1e-3, uv)
    assert regions.grow(q, regions.limits_of(uv), 3, 3) == []


def test_the_main_direction_of_a_turned_sweep_is_its_lanes_direction():
    t = np.linspace(0.0, 8.0, 81)
    lanes = [np.column_stack([t if i % 2 == 0 else t[::-1], np.full_like(t, float(i))])
             for i in range(6)]
    pts = np.stack(lanes)  # (6 lanes, 81, 2)
    turn = np.radians(20.0)
    rotated = regions.to_map(pts, -turn)  # the map frame of -20 deg is the world turned +20
    assert regions.main_direction(rotated, np.ones(pts.shape[:2], bool)) == \
        pytest.approx(turn, abs=1e-9)
    np.testing.assert_allclose(regions.to_map(rotated, turn), pts, atol=1e-12)
