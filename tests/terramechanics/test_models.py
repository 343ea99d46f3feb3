"""Force models against the plain force laws, and the injection contract."""

import math

import numpy as np
import pytest

from slipenv.terramechanics import (
    CONCRETE,
    FIELD_LOAM,
    FORCE_MODELS,
    LOOSE_SAND,
    LUNAR_SIMULANT,
    TOYOURA_SAND,
    ContactGeometry,
    ForceModel,
    JanosiForceModel,
    LinearSlipForceModel,
    ReinaForceModel,
    SoilParams,
    force_model_by_name,
    wheel_kernel,
)
from slipenv.terramechanics.bekker import compaction_resistance_n, wheel_sinkage_m
from slipenv.terramechanics.janosi import (
    janosi_forces,
    max_thrust_n,
    patch_thrust_n,
    small_slip_stiffness,
)
from slipenv.terramechanics.lindgren import linear_slip_forces
from slipenv.terramechanics.reina import reina_forces, reina_forces_n

WHEEL = ContactGeometry(radius_m=0.092, width_m=0.11, contact_length_m=0.06)
SAND = LOOSE_SAND.params()
RNG = np.random.default_rng(7)
SLIP = np.concatenate(([0.0, 1e-9, -1e-9, 1.0, -1.0], RNG.uniform(-1, 1, 40)))
TAN_BETA = np.concatenate(([0.0, 0.0, 1e-9, 0.3, -2.0], np.tan(RNG.uniform(-0.6, 0.6, 40))))
LOAD = np.concatenate(([60.0, 60.0, 60.0, 120.0, 15.0], RNG.uniform(10.0, 200.0, 40)))


def _f_max(p: SoilParams, load=LOAD) -> np.ndarray:
    return max_thrust_n(load, WHEEL.area_m2, p.cohesion_pa, p.friction_angle_rad)


@pytest.fixture(params=sorted(FORCE_MODELS))
def model(request) -> ForceModel:
    return force_model_by_name(request.param, WHEEL)


def test_every_model_satisfies_the_force_model_protocol(model):
    assert isinstance(model, ForceModel)
    fx, fy = model(SLIP, TAN_BETA, LOAD, SAND)
    assert fx.shape == fy.shape == SLIP.shape
    assert np.all(np.isfinite(fx)) and np.all(np.isfinite(fy))


def test_force_model_by_name_builds_the_class_and_passes_options():
    m = force_model_by_name("reina", WHEEL, rolling_resistance_coeff=0.02,
                            scale_stiffness_with_load=False)
    assert type(m) is ReinaForceModel and m.rolling_resistance_coeff == 0.02
    assert not m.scale_stiffness_with_load
    assert type(force_model_by_name("linear", WHEEL)) is LinearSlipForceModel


def test_unknown_model_name_raises_naming_it_and_listing_known_names():
    with pytest.raises(ValueError, match=r"unknown force model 'pacejka'.*janosi, linear, reina"):
        force_model_by_name("pacejka", WHEEL)


def test_invalid_construction_arguments_raise():
    with pytest.raises(TypeError, match="ContactGeometry"):
        JanosiForceModel((0.1, 0.1, 0.05))  # type: ignore[arg-type]
    with pytest.raises(ValueError, match="rolling_resistance_coeff=-0.01"):
        JanosiForceModel(WHEEL, rolling_resistance_coeff=-0.01)


def test_fy_opposes_tan_beta_and_fx_has_the_sign_of_slip(model):
    fx, fy = model(SLIP, TAN_BETA, LOAD, SAND)
    assert np.all(np.sign(fy) == -np.sign(TAN_BETA))
    assert np.all(np.sign(fx) == np.sign(SLIP))


def test_forces_are_odd_in_slip_and_in_tan_beta(model):
    fx, fy = model(SLIP, TAN_BETA, LOAD, SAND)
    fx_m, fy_m = model(-SLIP, TAN_BETA, LOAD, SAND)
    np.testing.assert_allclose(fx_m, -fx, rtol=1e-15)
    np.testing.assert_allclose(fy_m, fy, rtol=1e-15)
    fx_m, fy_m = model(SLIP, -TAN_BETA, LOAD, SAND)
    np.testing.assert_allclose(fx_m, fx, rtol=1e-15)
    np.testing.assert_allclose(fy_m, -fy, rtol=1e-15)


def test_zero_slip_gives_zero_force_and_zero_load_gives_zero_force(model):
    zeros = np.zeros(4)
    assert not np.any(np.concatenate(model(zeros, zeros, np.full(4, 100.0), SAND)))
    fx, fy = model(np.full(4, 0.3), np.full(4, 0.1), np.array([0.0, -5.0, 0.0, 0.0]), SAND)
    assert np.all(np.abs(fx) <= 1e-12) and np.all(np.abs(fy) <= 1e-12)


@pytest.mark.parametrize("cls", [JanosiForceModel, LinearSlipForceModel])
def test_resultant_never_exceeds_mohr_coulomb_limit(cls):
    big_slip = np.array([0.0, 0.05, 1.0, 1.0, 50.0])
    big_tan = np.array([1.0, 0.0, 1.0, 50.0, 50.0])
    load = np.full(5, 80.0)
    for soil in (SAND, LUNAR_SIMULANT.params(), CONCRETE.params()):
        fx, fy = cls(WHEEL)(big_slip, big_tan, load, soil)
        f_max = _f_max(soil, load)
        assert np.all(np.hypot(fx, fy) <= f_max * (1 + 1e-15))


def test_janosi_pure_longitudinal_equals_okello_patch_thrust():
    fx, fy = JanosiForceModel(WHEEL)(SLIP, np.zeros_like(SLIP), LOAD, SAND)
    expected = patch_thrust_n(SLIP, LOAD, WHEEL.area_m2, WHEEL.contact_length_m,
                              SAND.cohesion_pa, SAND.friction_angle_rad, SAND.shear_modulus_m)
    np.testing.assert_allclose(fx, expected, rtol=1e-12, atol=1e-15)
    assert not np.any(fy)


def test_janosi_combined_slip_is_okello_thrust_at_total_slip_split_by_direction():
    fx, fy = JanosiForceModel(WHEEL)(SLIP, TAN_BETA, LOAD, SAND)
    sigma = np.hypot(SLIP, TAN_BETA)
    total = patch_thrust_n(sigma, LOAD, WHEEL.area_m2, WHEEL.contact_length_m,
                           SAND.cohesion_pa, SAND.friction_angle_rad, SAND.shear_modulus_m)
    np.testing.assert_allclose(np.hypot(fx, fy), total, rtol=1e-12, atol=1e-15)
    moving = sigma > 0
    np.testing.assert_allclose(fx[moving] * sigma[moving], total[moving] * SLIP[moving],
                               rtol=1e-12, atol=1e-15)


def test_linear_slope_is_lindgren_k_s_over_radius():
    k_b = WHEEL.contact_length_m / SAND.shear_modulus_m
    load = np.array([50.0, 100.0, 150.0])
    t_max = WHEEL.radius_m * _f_max(SAND, load)
    k_s = small_slip_stiffness(t_max, 1.0 / k_b)  # Lindgren Eq. 24, B = K/L
    s = np.full(3, 0.01)
    fx, _ = LinearSlipForceModel(WHEEL)(s, np.zeros(3), load, SAND)
    np.testing.assert_allclose(fx, k_s / WHEEL.radius_m * s, rtol=1e-14)
    _, fy = LinearSlipForceModel(WHEEL)(np.zeros(3), s, load, SAND)
    np.testing.assert_allclose(fy, -k_s / WHEEL.radius_m * s, rtol=1e-14)


def test_linear_saturates_exactly_at_mohr_coulomb_limit_beyond_two_b():
    two_b = 2 * SAND.shear_modulus_m / WHEEL.contact_length_m
    s = np.array([1.01, 2.0, 5.0]) * two_b
    fx, _ = LinearSlipForceModel(WHEEL)(s, np.zeros(3), np.full(3, 90.0), SAND)
    np.testing.assert_allclose(fx, _f_max(SAND, np.full(3, 90.0)), rtol=1e-14)


def test_linear_agrees_with_janosi_within_2_percent_at_small_slip():
    k_over_l = SAND.shear_modulus_m / WHEEL.contact_length_m
    angle = np.linspace(0.0, 2 * math.pi, 12)
    x = np.array([1e-6, 0.01, 0.03, 0.05, 0.059])  # x = sigma L / K
    sigma = np.repeat(x * k_over_l, 12)
    s, tb = sigma * np.tile(np.cos(angle), 5), sigma * np.tile(np.sin(angle), 5)
    load = np.full(60, 100.0)
    ratio = np.hypot(*LinearSlipForceModel(WHEEL)(s, tb, load, SAND)) / np.hypot(
        *JanosiForceModel(WHEEL)(s, tb, load, SAND))
    assert np.all(np.abs(ratio - 1.0) <= 0.02)
    # (x/2)/g(x) = 1/(2 h(x)), h = g/x = sum (-x)^k/(k+2)! (Eq. 22-23 without truncation)
    h = [math.fsum((-xi) ** k / math.factorial(k + 2) for k in range(30)) for xi in x]
    np.testing.assert_allclose(ratio, np.repeat(0.5 / np.array(h), 12), rtol=1e-10)


def test_reina_model_equals_reina_functions_with_load_scaled_stiffness():
    p = LUNAR_SIMULANT.params()
    fx, fy = ReinaForceModel(WHEEL)(SLIP, TAN_BETA, LOAD, p)
    scale = LOAD / p.reference_load_n
    ex, ey = reina_forces_n(SLIP, TAN_BETA, LOAD, p.mu, p.c_x_n * scale, p.c_y_n * scale,
                            p.a_x, p.a_y)
    np.testing.assert_allclose(fx, ex, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(fy, ey, rtol=1e-12, atol=1e-15)


def test_reina_model_without_scaling_is_reina_eq_5_to_9_verbatim():
    p = LUNAR_SIMULANT.params()
    fx, fy = ReinaForceModel(WHEEL, scale_stiffness_with_load=False)(SLIP, TAN_BETA, LOAD, p)
    ex, ey = reina_forces_n(SLIP, TAN_BETA, LOAD, p.mu, p.c_x_n, p.c_y_n, p.a_x, p.a_y)
    np.testing.assert_allclose(fx, ex, rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(fy, ey, rtol=1e-12, atol=1e-15)


def test_reina_scaled_and_verbatim_agree_at_the_reference_load():
    p = LUNAR_SIMULANT.params()
    load = np.full_like(SLIP, p.reference_load_n)
    a = ReinaForceModel(WHEEL)(SLIP, TAN_BETA, load, p)
    b = ReinaForceModel(WHEEL, scale_stiffness_with_load=False)(SLIP, TAN_BETA, load, p)
    np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)


def test_resistance_is_bekker_compaction_plus_rolling(model):
    if isinstance(model, ReinaForceModel):  # Reina's law is net: compaction only on request
        model = ReinaForceModel(WHEEL, compaction=True)
    load = np.array([0.0, 30.0, 120.0, -4.0])
    expected = compaction_resistance_n(
        wheel_sinkage_m(load, WHEEL.width_m, 2 * WHEEL.radius_m, SAND.k_c, SAND.k_phi,
                        SAND.n_exp), WHEEL.width_m, SAND.k_c, SAND.k_phi, SAND.n_exp)
    expected += 0.01 * np.maximum(load, 0.0)
    np.testing.assert_allclose(model.resistance_n(load, SAND), expected, rtol=1e-12)


def test_resistance_on_concrete_is_rolling_resistance_only(model):
    load = np.array([0.0, 30.0, 120.0])
    np.testing.assert_array_equal(model.resistance_n(load, CONCRETE.params()), 0.01 * load)


def test_track_segments_use_whole_track_shear_length_and_share_one_rut():
    whole = ContactGeometry(radius_m=0.05, width_m=0.11, contact_length_m=0.6,
                            track_length_m=0.6)
    half = ContactGeometry(radius_m=0.05, width_m=0.11, contact_length_m=0.3,
                           track_length_m=0.6)
    s, tb = np.array([0.05, 0.3]), np.array([0.02, -0.1])
    f_whole = JanosiForceModel(whole)(s, tb, np.full(2, 200.0), SAND)
    f_half = JanosiForceModel(half)(s, tb, np.full(2, 100.0), SAND)
    np.testing.assert_allclose(f_whole, 2 * np.asarray(f_half), rtol=1e-13)
    r_whole = JanosiForceModel(whole).resistance_n(np.array([200.0]), SAND)
    r_half = JanosiForceModel(half).resistance_n(np.array([100.0]), SAND)
    np.testing.assert_allclose(r_whole, 2 * r_half, rtol=1e-13)


def _stacked(*soils) -> SoilParams:
    return SoilParams(*np.array([s.params() for s in soils]).T)


def test_vectorised_soil_arrays_equal_per_wheel_scalar_calls(model):
    soils = (LUNAR_SIMULANT, LOOSE_SAND, FIELD_LOAM, TOYOURA_SAND, CONCRETE)
    s = np.array([0.2, -0.1, 0.05, 0.6, 0.3])
    tb = np.array([0.1, 0.0, -0.3, 0.05, 0.2])
    load = np.array([60.0, 120.0, 0.0, 800.0, 40.0])
    fx, fy = model(s, tb, load, _stacked(*soils))
    res = model.resistance_n(load, _stacked(*soils))
    for i, soil in enumerate(soils):
        one = type(model)(WHEEL)
        fxi, fyi = one(s[i:i + 1], tb[i:i + 1], load[i:i + 1], soil.params())
        assert fx[i] == pytest.approx(fxi[0], rel=1e-13, abs=1e-15)
        assert fy[i] == pytest.approx(fyi[0], rel=1e-13, abs=1e-15)
        assert res[i] == pytest.approx(one.resistance_n(load[i:i + 1], soil.params())[0],
                                       rel=1e-13, abs=1e-15)


def test_changing_soil_object_is_never_served_from_a_stale_cache(model):
    s, tb, load = np.array([0.2]), np.array([0.1]), np.array([100.0])
    first = model(s, tb, load, SAND)
    other = model(s, tb, load, CONCRETE.params())
    assert model(s, tb, load, SAND) == first
    assert other != first


def test_repr_names_the_class_and_its_settings():
    assert repr(ReinaForceModel(WHEEL)).startswith("ReinaForceModel(ContactGeometry(")
    assert "scale_stiffness_with_load=True" in repr(ReinaForceModel(WHEEL))


class _ArrayOnlyModel:
    """A user ForceModel without the ``scalar_kernel`` hook (plain arrays)."""

    def __call__(self, slip, tan_beta, load_n, soil):
        return 2.0 * np.asarray(slip) * load_n, -np.asarray(tan_beta) * load_n

    def resistance_n(self, load_n, soil):
        return 0.1 * np.asarray(load_n)


def test_wheel_kernel_uses_the_models_own_scalar_kernel(model):
    kernel = wheel_kernel(model, SAND)
    assert kernel(0.2, -0.1, 90.0) == model.scalar_kernel(SAND)(0.2, -0.1, 90.0)
    fx, fy = model(np.array([0.2]), np.array([-0.1]), np.array([90.0]), SAND)
    res = model.resistance_n(np.array([90.0]), SAND)
    assert kernel(0.2, -0.1, 90.0) == (fx[0], fy[0], res[0])


def test_wheel_kernel_wraps_a_model_without_the_hook():
    fx, fy, res = wheel_kernel(_ArrayOnlyModel(), SAND)(0.25, 0.5, 40.0)
    assert (fx, fy, res) == (20.0, -20.0, 4.0)
    assert all(type(v) is float for v in (fx, fy, res))


@pytest.mark.parametrize("law", [janosi_forces, linear_slip_forces])
def test_patch_laws_give_no_force_without_contact(law):
    assert law(0.3, 0.2, 0.0, 15.0, 0.6, 2.0) == (0.0, 0.0)
    assert law(0.3, 0.2, -4.0, 15.0, 0.6, 2.0) == (0.0, 0.0)


def test_reina_law_gives_no_force_without_contact_in_both_forms():
    assert reina_forces(0.3, 0.2, 0.0, 0.6, 55.0, 200.0, 0.02, 0.04) == (0.0, 0.0)
    for scaled in (True, False):
        m = ReinaForceModel(WHEEL, scale_stiffness_with_load=scaled)
        fx, fy = m(np.array([0.3]), np.array([0.2]), np.array([-1.0]), SAND)
        assert fx[0] == 0.0 and fy[0] == 0.0


def test_reina_load_scaling_is_load_times_the_law_at_unit_load_with_c_over_w_ref():
    p = LUNAR_SIMULANT.params()
    kernel = ReinaForceModel(WHEEL).scalar_kernel(p)
    for s, tb, w in [(0.2, 0.1, 40.0), (-0.5, 0.3, 700.0), (0.0, -0.2, 3.0)]:
        fx1, fy1 = reina_forces(s, tb, 1.0, p.mu, p.c_x_n / p.reference_load_n,
                                p.c_y_n / p.reference_load_n, p.a_x, p.a_y)
        fx, fy, _ = kernel(s, tb, w)
        # W times the law at unit load with C/W_ref is the law at W with C W/W_ref, to rounding
        assert (fx, fy) == pytest.approx((fx1 * w, fy1 * w), rel=1e-12)


@pytest.mark.parametrize("cls", [JanosiForceModel, LinearSlipForceModel])
def test_lateral_stiffness_ratio_scales_side_stiffness_only_and_defaults_to_isotropic(cls):
    soil = FIELD_LOAM.params()
    iso, aniso = cls(WHEEL), cls(WHEEL, lateral_stiffness_ratio=3.6)
    assert iso.lateral_stiffness_ratio == 1.0
    d, w = 1e-6, np.array([150.0])
    fx_i, _ = iso(np.array([d]), np.zeros(1), w, soil)
    fx_a, _ = aniso(np.array([d]), np.zeros(1), w, soil)
    _, fy_i = iso(np.zeros(1), np.array([d]), w, soil)
    _, fy_a = aniso(np.zeros(1), np.array([d]), w, soil)
    assert fx_a[0] == fx_i[0]
    assert fy_a[0] / fy_i[0] == pytest.approx(3.6, rel=1e-4)
    assert "lateral_stiffness_ratio=3.6" in repr(aniso)
    for bad in (0.0, -1.0, math.nan, math.inf):
        with pytest.raises(ValueError, match="lateral_stiffness_ratio"):
            cls(WHEEL, lateral_stiffness_ratio=bad)


@pytest.mark.parametrize("cls", [JanosiForceModel, LinearSlipForceModel, ReinaForceModel])
def test_a_subclass_keeping_the_law_gets_the_compiled_kernels_forces_from_its_python_kernel(cls):
    """A subclass runs `_forces` (the Python kernel the substep loop calls back); keeping the
    law it must give what the compiled kernel of its base class gives."""
    reina = cls is ReinaForceModel
    options = {} if reina else {"lateral_stiffness_ratio": 2.0}
    sub, base = type("Same", (cls,), {})(WHEEL, **options), cls(WHEEL, **options)
    soil = LUNAR_SIMULANT.params() if reina else SAND
    assert sub.kernel_constants(soil) is None and base.kernel_constants(soil) is not None
    python, compiled = sub.scalar_kernel(soil), base.scalar_kernel(soil)
    for s, tb, w in zip(SLIP[5:15], TAN_BETA[5:15], LOAD[5:15], strict=True):
        assert python(s, tb, w) == pytest.approx(compiled(s, tb, w), rel=1e-12, abs=1e-12)


def test_reinas_law_takes_reinas_slip_angle_and_the_shear_laws_the_sliding_velocitys():
    """Reina's law was fitted with tan(beta) = v_lat/v_x (Reina Eq. 4); the Janosi and linear
    laws split the shear displacement along the sliding velocity (Lindgren Eq. 2). A wrapper
    without its own declaration (a model with a ``base``) takes its base law's, a subclass
    its class's, anything else the sliding one; an unknown name is an error."""
    from slipenv.terramechanics.models import slip_angle_convention

    assert slip_angle_convention(ReinaForceModel(WHEEL)) == "reina"
    assert slip_angle_convention(JanosiForceModel(WHEEL)) == "sliding"
    assert slip_angle_convention(LinearSlipForceModel(WHEEL)) == "sliding"

    class Wrapper:
        def __init__(self, base):
            self.base = base

    class Reina2(ReinaForceModel):
        pass

    assert slip_angle_convention(Wrapper(Wrapper(ReinaForceModel(WHEEL)))) == "reina"
    assert slip_angle_convention(Reina2(WHEEL)) == "reina"
    assert slip_angle_convention(object()) == "sliding"
    wrong = Wrapper(None)
    wrong.slip_angle_convention = "pacejka"
    with pytest.raises(ValueError, match="pacejka"):
        slip_angle_convention(wrong)
