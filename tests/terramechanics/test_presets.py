"""Soil presets: values from the papers, lookup by name."""

import dataclasses
import math

import pytest

from slipenv.terramechanics import (
    CONCRETE,
    FIELD_LOAM,
    LOOSE_SAND,
    LUNAR_SIMULANT,
    SOILS,
    TOYOURA_SAND,
    soil_by_name,
)
from slipenv.terramechanics.bekker import wheel_sinkage_m
from slipenv.terramechanics.janosi import max_thrust_n


def test_all_presets_are_registered_under_their_names_and_revalidate():
    assert set(SOILS) == {"lunar_simulant", "loose_sand", "field_loam", "toyoura_sand",
                          "dry_sand", "concrete"}
    for name, soil in SOILS.items():
        assert soil.name == name
        assert soil_by_name(name) is soil
        assert dataclasses.replace(soil) == soil  # __post_init__ validation passes


def test_soils_mapping_is_read_only():
    with pytest.raises(TypeError):
        SOILS["mud"] = LOOSE_SAND  # type: ignore[index]


def test_unknown_soil_name_raises_naming_it_and_listing_known_names():
    with pytest.raises(ValueError, match=r"unknown soil 'mud'.*concrete.*lunar_simulant"):
        soil_by_name("mud")


def test_lunar_simulant_has_reina_table_2_and_3_values():
    s = LUNAR_SIMULANT
    assert s.cohesion_pa == 800.0
    assert s.friction_angle_rad == pytest.approx(math.radians(30.0), rel=1e-15)
    assert (s.mu, s.c_x_n, s.c_y_n, s.a_x, s.a_y) == (0.6, 55.0, 200.0, 0.02, 0.04)
    assert s.reference_load_n == pytest.approx(64.724, abs=1e-3)


def test_loose_sand_lies_inside_reina_table_2_ranges():
    assert 200.0 <= LOOSE_SAND.cohesion_pa <= 1000.0
    assert math.radians(26.0) <= LOOSE_SAND.friction_angle_rad <= math.radians(32.0)


def test_field_loam_rolling_radius_scale_is_lindgren_soil_over_concrete():
    assert FIELD_LOAM.rolling_radius_scale == pytest.approx(0.285 / 0.275, rel=1e-15)
    assert FIELD_LOAM.rolling_radius_scale == pytest.approx(1.03636, abs=1e-5)


def test_concrete_is_rigid_stiff_and_the_reference_radius():
    assert not CONCRETE.deformable and CONCRETE.params().deformable == 0.0
    assert CONCRETE.rolling_radius_scale == 1.0
    assert CONCRETE.shear_modulus_m < min(s.shear_modulus_m for s in SOILS.values()
                                          if s is not CONCRETE)
    assert math.tan(CONCRETE.friction_angle_rad) == pytest.approx(0.8, rel=1e-12)
    assert all(s.deformable for s in SOILS.values() if s is not CONCRETE)


def _reina_wheel_quantities(soil):
    """(F_max/W, small-slip stiffness) on Reina's test wheel (r 92 mm, b 110 mm, 6.6 kg)."""
    r, b, w = 0.092, 0.11, soil.reference_load_n
    z = float(wheel_sinkage_m(w, b, 2 * r, soil.k_c, soil.k_phi, soil.n_exp))
    length = r * math.acos(1 - z / r)
    f_max = float(max_thrust_n(w, b * length, soil.cohesion_pa, soil.friction_angle_rad))
    return f_max / w, f_max * length / (2 * soil.shear_modulus_m)


@pytest.mark.parametrize("soil", [LOOSE_SAND, FIELD_LOAM, TOYOURA_SAND])
def test_assumed_reina_parameters_follow_the_documented_scaling_of_table_3(soil):
    mu_ratio, stiff_ratio = (a / b for a, b in zip(_reina_wheel_quantities(soil),
                                                   _reina_wheel_quantities(LUNAR_SIMULANT),
                                                   strict=True))
    assert soil.mu == pytest.approx(0.6 * mu_ratio, rel=0.01)
    assert soil.c_x_n == pytest.approx(55.0 * stiff_ratio, rel=0.01)
    assert soil.c_y_n == pytest.approx(200.0 * stiff_ratio, rel=0.01)
