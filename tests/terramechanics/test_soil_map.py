"""Soil maps: uniform, blended patches, bilinear grids."""

import math

import numpy as np
import pytest

from slipenv.terramechanics import (
    CONCRETE,
    FIELD_LOAM,
    LOOSE_SAND,
    LUNAR_SIMULANT,
    PARAM_FIELDS,
    Circle,
    ContactGeometry,
    GridSoilMap,
    Intersection,
    JanosiForceModel,
    PatchSoilMap,
    Rectangle,
    SoilMap,
    UniformSoil,
    Union,
)

BASE, PATCH = LOOSE_SAND.params(), CONCRETE.params()


def _field(params, key):
    return np.asarray(getattr(params, key), dtype=float)


def test_uniform_soil_returns_the_cached_scalar_params_everywhere():
    m = UniformSoil(LOOSE_SAND)
    assert isinstance(m, SoilMap)
    assert m.params_at(np.array([0.0, 100.0]), np.array([-5.0, 3.0])) is LOOSE_SAND.params()


def test_circle_and_rectangle_signed_distances():
    c = Circle(1.0, 2.0, 0.5)
    np.testing.assert_allclose(c.signed_distance_m(np.array([1.0, 1.5, 4.0]), np.full(3, 2.0)),
                               [-0.5, 0.0, 2.5], rtol=1e-15)
    r = Rectangle(0.0, 0.0, 4.0, 2.0)
    d = r.signed_distance_m(np.array([2.0, 0.5, 4.0, 7.0, 2.0]), np.array([1.0, 1.0, 1.0, 6.0,
                                                                              -0.5]))
    np.testing.assert_allclose(d, [-1.0, -0.5, 0.0, 5.0, 0.5], rtol=1e-15)


def test_a_turned_rectangle_measures_distance_in_its_own_axes():
    # 4 m x 2 m centred at (2, 1), turned a quarter turn: 2 m along x, 4 m along y
    r = Rectangle(0.0, 0.0, 4.0, 2.0, angle_rad=np.pi / 2)
    d = r.signed_distance_m(np.array([2.0, 2.0, 3.0, 3.5, 2.0]),
                            np.array([1.0, 2.9, 1.0, 1.0, 3.5]))
    np.testing.assert_allclose(d, [-1.0, -0.1, 0.0, 0.5, 0.5], atol=1e-12)
    turned = Rectangle(0.0, 0.0, 4.0, 2.0, angle_rad=np.pi / 6)
    x, y = np.random.default_rng(0).uniform(-3.0, 7.0, (2, 200))
    c, s = np.cos(np.pi / 6), np.sin(np.pi / 6)  # the same points in the rectangle's axes
    u, v = 2.0 + c * (x - 2.0) + s * (y - 1.0), 1.0 - s * (x - 2.0) + c * (y - 1.0)
    np.testing.assert_allclose(turned.signed_distance_m(x, y),
                               Rectangle(0.0, 0.0, 4.0, 2.0).signed_distance_m(u, v), atol=1e-12)


def test_a_union_and_an_intersection_hold_the_points_of_any_and_of_all():
    disc, box = Circle(0.0, 0.0, 1.0), Rectangle(0.5, -0.5, 2.5, 0.5)
    x, y = np.random.default_rng(1).uniform(-2.0, 3.0, (2, 2000))
    in_disc = disc.signed_distance_m(x, y) < 0
    in_box = box.signed_distance_m(x, y) < 0
    assert np.array_equal(Union((disc, box)).signed_distance_m(x, y) < 0, in_disc | in_box)
    assert np.array_equal(Intersection((disc, box)).signed_distance_m(x, y) < 0,
                          in_disc & in_box)
    assert 0 < np.sum(in_disc & in_box) < np.sum(in_disc | in_box)  # the two overlap
    # outside the union its distance is the exact distance to the nearer shape
    np.testing.assert_allclose(Union((disc, box)).signed_distance_m(np.array([4.0]),
                                                                    np.array([0.0])), [1.5])
    with pytest.raises(ValueError, match="one or more regions"):
        Union(())
    with pytest.raises(ValueError, match="one or more regions"):
        Intersection((disc, "box"))


def test_degenerate_rectangle_and_circle_raise():
    with pytest.raises(ValueError, match="x_min_m < x_max_m"):
        Rectangle(1.0, 0.0, 1.0, 2.0)
    with pytest.raises(ValueError, match="angle_rad=nan"):
        Rectangle(0.0, 0.0, 1.0, 2.0, angle_rad=float("nan"))
    with pytest.raises(ValueError, match="radius_m=0.0"):
        Circle(0.0, 0.0, 0.0)


def test_patch_map_gives_patch_soil_inside_and_base_outside_as_cached_objects():
    m = PatchSoilMap(LOOSE_SAND, [(Circle(0.0, 0.0, 2.0), CONCRETE)], blend_width_m=0.4)
    assert m.params_at(np.array([0.0, 1.7]), np.array([0.0, 0.0])) is PATCH
    assert m.params_at(np.array([2.3, -5.0]), np.array([0.0, 0.0])) is BASE


def test_patch_map_mixed_points_get_their_own_soils_and_the_midpoint_on_the_boundary():
    m = PatchSoilMap(LOOSE_SAND, [(Circle(0.0, 0.0, 2.0), CONCRETE)], blend_width_m=0.4)
    p = m.params_at(np.array([0.0, 2.0, 5.0]), np.zeros(3))
    for key in PARAM_FIELDS:
        lo, hi = getattr(PATCH, key), getattr(BASE, key)
        np.testing.assert_allclose(_field(p, key), [lo, 0.5 * (lo + hi), hi], rtol=1e-14,
                                   atol=1e-300)


def test_patch_blend_is_continuous_and_monotone_across_the_boundary():
    width = 0.5
    m = PatchSoilMap(LOOSE_SAND, [(Rectangle(0.0, -1.0, 3.0, 1.0), FIELD_LOAM)], width)
    x = np.linspace(2.0, 4.0, 2001)  # crosses the edge x = 3
    p = m.params_at(x, np.zeros_like(x))
    step = x[1] - x[0]
    for key in ("cohesion_pa", "friction_angle_rad", "k_phi", "mu"):
        v = _field(p, key)
        jump = abs(getattr(FIELD_LOAM, key) - getattr(LOOSE_SAND, key))
        dv = np.diff(v)
        assert np.all(np.abs(dv) <= 1.5 * jump * step / width * (1 + 1e-9))  # smoothstep slope
        assert np.all(dv * np.sign(getattr(LOOSE_SAND, key) - getattr(FIELD_LOAM, key)) >= 0)


def test_forces_change_continuously_across_a_patch_edge_but_jump_at_a_hard_edge():
    model = JanosiForceModel(ContactGeometry(0.165, 0.1, 0.05))

    def largest_step(blend_width_m, n):
        m = PatchSoilMap(LOOSE_SAND, [(Circle(0.0, 0.0, 1.0), CONCRETE)], blend_width_m)
        x = np.linspace(0.5, 1.5, n)
        fx, _ = model(np.full(n, 0.1), np.zeros(n), np.full(n, 120.0),
                      m.params_at(x, np.zeros(n)))
        assert fx[0] - fx[-1] > 60.0  # [N] concrete grips, sand slips
        return np.abs(np.diff(fx)).max()

    coarse, fine = largest_step(0.3, 1001), largest_step(0.3, 10001)
    assert coarse < 1.0 and 9.0 < coarse / fine < 11.0  # Lipschitz: steps shrink with spacing
    assert largest_step(0.0, 10001) > 60.0


def test_later_patches_are_painted_over_earlier_ones():
    m = PatchSoilMap(LOOSE_SAND, [(Circle(0.0, 0.0, 3.0), FIELD_LOAM),
                                  (Circle(0.0, 0.0, 1.0), CONCRETE)], blend_width_m=0.2)
    assert m.params_at(np.array([0.0]), np.array([0.0])) is PATCH
    assert m.params_at(np.array([2.0]), np.array([0.0])) is FIELD_LOAM.params()
    p = m.params_at(np.array([0.0, 2.0, 9.0]), np.zeros(3))
    np.testing.assert_allclose(p.cohesion_pa, [PATCH.cohesion_pa, FIELD_LOAM.cohesion_pa,
                                               BASE.cohesion_pa], rtol=1e-15)


def test_zero_blend_width_gives_hard_edges_with_the_boundary_outside():
    m = PatchSoilMap(LOOSE_SAND, [(Circle(0.0, 0.0, 1.0), CONCRETE)], blend_width_m=0.0)
    p = m.params_at(np.array([0.999, 1.0, 1.001]), np.zeros(3))
    np.testing.assert_array_equal(p.deformable, [0.0, 1.0, 1.0])
    assert m.params_at(np.array([1.0]), np.array([0.0])) is BASE
    assert m.params_at(np.array([0.999]), np.array([0.0])) is PATCH


def test_invalid_patch_arguments_raise():
    with pytest.raises(ValueError, match="blend_width_m=-1"):
        PatchSoilMap(LOOSE_SAND, [], blend_width_m=-1.0)
    with pytest.raises(TypeError, match="each patch must be"):
        PatchSoilMap(LOOSE_SAND, [(Circle(0.0, 0.0, 1.0), "concrete")])


GRID = np.array([[0, 0, 1],
                 [0, 2, 1]])  # rows are y = 0, 2; columns x = 10, 12, 14
SOILS3 = (LOOSE_SAND, CONCRETE, LUNAR_SIMULANT)


def test_grid_nodes_carry_their_soil_and_cells_interpolate_bilinearly():
    m = GridSoilMap(SOILS3, GRID, origin_m=(10.0, 0.0), cell_size_m=2.0)
    p = m.params_at(np.array([12.0, 14.0, 11.0, 13.0, 11.5]), np.array([2.0, 0.0, 1.0, 1.0, 0.5]))
    c = [s.cohesion_pa for s in SOILS3]
    # (11.5, 0.5): tx = 0.75, ty = 0.25 in the cell with nodes 0, 0 (bottom) and 0, 2 (top)
    expected = [c[2], c[1], 0.75 * c[0] + 0.25 * c[2],
                0.25 * (c[0] + c[1] + c[2] + c[1]), 0.8125 * c[0] + 0.1875 * c[2]]
    np.testing.assert_allclose(p.cohesion_pa, expected, rtol=1e-14)


def test_grid_returns_cached_params_where_all_points_are_on_one_soil():
    grid = [[0, 0, 1], [0, 0, 1], [2, 2, 1]]
    m = GridSoilMap(SOILS3, grid, origin_m=(10.0, 0.0), cell_size_m=2.0)
    assert m.params_at(np.array([10.0, 11.0, 9.0]), np.array([0.0, 0.5, -3.0])) \
        is LOOSE_SAND.params()


def test_grid_clamps_points_outside_to_the_edge():
    m = GridSoilMap(SOILS3, GRID, origin_m=(10.0, 0.0), cell_size_m=(2.0, 2.0))
    inside = m.params_at(np.array([14.0, 13.0]), np.array([1.0, 2.0]))
    outside = m.params_at(np.array([99.0, 13.0]), np.array([1.0, 50.0]))
    for key in PARAM_FIELDS:
        np.testing.assert_allclose(_field(outside, key), _field(inside, key), rtol=1e-15)


def test_single_row_grid_interpolates_along_x_only_and_single_node_is_uniform():
    m = GridSoilMap(SOILS3, [[0, 1]], origin_m=(0.0, 0.0), cell_size_m=2.0)
    p = m.params_at(np.array([0.5, 1.0]), np.array([-3.0, 7.0]))
    c0, c1 = LOOSE_SAND.cohesion_pa, CONCRETE.cohesion_pa
    np.testing.assert_allclose(p.cohesion_pa, [0.75 * c0 + 0.25 * c1, 0.5 * (c0 + c1)],
                               rtol=1e-15)
    single = GridSoilMap(SOILS3, [[2]])
    assert single.params_at(np.array([-9.0, 9.0]), np.array([3.0, 0.0])) \
        is LUNAR_SIMULANT.params()


def test_invalid_index_grid_raises():
    with pytest.raises(ValueError, match=r"\[0, 3\)"):
        GridSoilMap(SOILS3, [[0, 3]])
    with pytest.raises(ValueError, match="2-D integer"):
        GridSoilMap(SOILS3, [[0.5, 1.0]])
    with pytest.raises(ValueError, match="cell_size_m"):
        GridSoilMap(SOILS3, GRID, cell_size_m=0.0)


def test_scaled_grid_scales_only_the_chosen_fields_bilinearly():
    scale = np.array([[1.0, 2.0], [0.5, 1.0]])
    m = GridSoilMap.scaled(LOOSE_SAND, scale, ["cohesion_pa", "k_phi"], cell_size_m=1.0)
    p = m.params_at(np.array([0.0, 1.0, 0.5]), np.array([0.0, 0.0, 0.5]))
    s = np.array([1.0, 2.0, 1.125])
    np.testing.assert_allclose(p.cohesion_pa, LOOSE_SAND.cohesion_pa * s, rtol=1e-14)
    np.testing.assert_allclose(p.k_phi, LOOSE_SAND.k_phi * s, rtol=1e-14)
    np.testing.assert_allclose(p.friction_angle_rad, LOOSE_SAND.friction_angle_rad, rtol=1e-15)


def test_scaled_grid_rejects_bad_fields_and_scales_that_make_the_soil_invalid():
    with pytest.raises(ValueError, match="not scalable"):
        GridSoilMap.scaled(LOOSE_SAND, [[1.0]], ["deformable"])
    with pytest.raises(ValueError, match="finite values > 0"):
        GridSoilMap.scaled(LOOSE_SAND, [[1.0, -1.0]], ["k_phi"])
    with pytest.raises(ValueError, match="friction_angle_rad"):
        GridSoilMap.scaled(LOOSE_SAND, [[1.0, 4.0]], ["friction_angle_rad"])


def test_soil_maps_are_deterministic():
    m = PatchSoilMap(LOOSE_SAND, [(Circle(0.0, 0.0, 1.0), CONCRETE)])
    x = np.linspace(-2.0, 2.0, 9)
    a, b = m.params_at(x, x), m.params_at(x, x)
    for key in PARAM_FIELDS:
        np.testing.assert_array_equal(_field(a, key), _field(b, key))
    assert math.isclose(float(np.max(_field(a, "deformable"))), 1.0)
