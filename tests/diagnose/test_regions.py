"""``slipenv.diagnose.regions``: the per-interval quadratic of a soil map and the search for
rectangles with continuous edges, checked on linear worlds whose exact answer is known."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.diagnose import regions

# region 0 a rectangle, region 1 an L of two rectangles
TRUE = regions.Layout(((-3.0, -3.0, -0.4, 0.2), (1.1, 0.7, 3.3, 3.6), (1.1, -2.5, 2.2, 0.7)),
                      (0, 1, 1))
TRUE_LEVELS = np.array([0.008, 0.005])


def _linear_world(seed: int = 0, segments: int = 30, intervals: int = 16, rows: int = 12,
                  noise: float = 0.0):
    """Segments of ``intervals`` points scattered over a 8 m square, residuals linear in the
    per-interval compliance (r = r0 + D C) with r0 = -D C_true (+ noise): the true map's
    cost is the noise alone."""
    rng = np.random.default_rng(seed)
    uv = rng.uniform(-4.0, 4.0, (segments, intervals, 2))
    d = rng.normal(0.0, 1.0, (segments, rows, intervals))
    truth = regions.compliance(uv, TRUE, TRUE_LEVELS)
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


def test_an_edge_scan_finds_the_best_cut_that_brute_force_finds():
    q, *_ = _linear_world(noise=0.05)
    limits = regions.limits_of(q.uv)
    # two regions, the second of two overlapping rectangles (a union: no double count)
    layout = regions.Layout(((-2.0, -2.5, 0.5, 1.0), (1.5, 1.0, 3.0, 3.0),
                             (1.0, -1.0, 2.5, 2.0)), (0, 1, 1))
    for k in range(3):
        for edge in range(4):
            found, levels, cost = regions.scan_edge(q, layout, k, edge, limits)
            # every cut between two data coordinates, scored by the plain solve
            coords = np.unique(q.uv[..., edge % 2])
            best = np.inf
            for cut in np.concatenate([0.5 * (coords[1:] + coords[:-1]), [limits[edge]]]):
                rect = list(layout.rects[k])
                rect[edge] = cut
                if rect[2] <= rect[0] or rect[3] <= rect[1]:
                    continue
                trial = layout.with_rect(k, tuple(rect))
                others = layout.masks(q.uv, skip=k)[layout.labels[k]]
                if not np.any((regions.inside(q.uv, trial.rects[k]) > 0) & (others == 0)):
                    continue  # the rectangle adds nothing to its region
                lv, c = regions.solve(q, trial)
                if np.all(lv > 0):
                    best = min(best, c)
            assert cost == pytest.approx(best, rel=1e-9), (k, edge)
            again, again_cost = regions.solve(q, found)
            np.testing.assert_allclose(again, levels, rtol=1e-9)
            assert again_cost == pytest.approx(cost, rel=1e-9)


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
