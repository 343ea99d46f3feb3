"""Soil: validation on construction, the cached SoilParams image."""

import dataclasses
import math

import pytest

from slipenv.terramechanics import LUNAR_SIMULANT, PARAM_FIELDS, Soil, SoilParams


def test_params_holds_every_numeric_field_as_float_in_order():
    p = LUNAR_SIMULANT.params()
    assert isinstance(p, SoilParams)
    assert p._fields == PARAM_FIELDS
    for key in PARAM_FIELDS[:-1]:
        assert p._asdict()[key] == getattr(LUNAR_SIMULANT, key)
        assert type(p._asdict()[key]) is float
    assert p.deformable == 1.0


def test_params_is_cached_same_object_each_call():
    assert LUNAR_SIMULANT.params() is LUNAR_SIMULANT.params()


def test_rebuilt_soil_equals_original_and_has_its_own_params():
    copy = dataclasses.replace(LUNAR_SIMULANT)
    assert copy == LUNAR_SIMULANT
    assert hash(copy) == hash(LUNAR_SIMULANT)
    assert copy.params() == LUNAR_SIMULANT.params()


def test_soil_is_frozen():
    with pytest.raises(dataclasses.FrozenInstanceError):
        LUNAR_SIMULANT.cohesion_pa = 1.0  # type: ignore[misc]


@pytest.mark.parametrize("key", PARAM_FIELDS[:-1])
@pytest.mark.parametrize("bad", [-1.0, math.nan, math.inf])
def test_negative_nan_or_infinite_field_raises_naming_field_and_value(key, bad):
    with pytest.raises(ValueError, match=rf"{key}={bad!r}"):
        dataclasses.replace(LUNAR_SIMULANT, **{key: bad})


@pytest.mark.parametrize("key", ["shear_modulus_m", "n_exp", "mu", "reference_load_n",
                                 "rolling_radius_scale"])
def test_zero_where_a_field_divides_raises(key):
    with pytest.raises(ValueError, match=rf"{key}=0.0 must be > 0"):
        dataclasses.replace(LUNAR_SIMULANT, **{key: 0.0})


@pytest.mark.parametrize(("key", "value"), [("friction_angle_rad", math.pi / 2),
                                            ("n_exp", 3.0)])
def test_field_at_its_upper_bound_raises(key, value):
    with pytest.raises(ValueError, match=key):
        dataclasses.replace(LUNAR_SIMULANT, **{key: value})


def test_zero_cohesion_and_zero_friction_terms_are_allowed():
    soil = dataclasses.replace(LUNAR_SIMULANT, cohesion_pa=0.0, friction_angle_rad=0.0,
                               a_x=0.0, a_y=0.0)
    assert soil.params().cohesion_pa == 0.0


def test_both_bekker_moduli_zero_raises():
    with pytest.raises(ValueError, match="k_c=0.0 and k_phi=0.0"):
        dataclasses.replace(LUNAR_SIMULANT, k_c=0.0, k_phi=0.0)


@pytest.mark.parametrize("bad", ["1.0", None, True])
def test_non_number_field_raises(bad):
    with pytest.raises(ValueError, match=r"cohesion_pa=.* must be a real number"):
        dataclasses.replace(LUNAR_SIMULANT, cohesion_pa=bad)


def test_empty_name_and_non_bool_deformable_raise():
    with pytest.raises(ValueError, match="name=''"):
        dataclasses.replace(LUNAR_SIMULANT, name="")
    with pytest.raises(ValueError, match="deformable=1"):
        dataclasses.replace(LUNAR_SIMULANT, deformable=1)


def test_integer_values_are_accepted_and_stored_as_float_params():
    soil = Soil(name="x", cohesion_pa=1000, friction_angle_rad=0.5, shear_modulus_m=0.02,
                k_c=0, k_phi=800_000, n_exp=1, mu=0.6, c_x_n=55, c_y_n=200, a_x=0, a_y=0,
                reference_load_n=65, rolling_radius_scale=1, deformable=True)
    assert soil.params().cohesion_pa == 1000.0
    assert type(soil.params().n_exp) is float
