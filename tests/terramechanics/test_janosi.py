"""Janosi-Hanamoto shear, Mohr-Coulomb limit and Okello's curve (Lindgren Eq. 2-3, 18-24)."""

import math

import numpy as np
import pytest
from scipy.integrate import quad

from slipenv.terramechanics.janosi import (
    janosi_forces,
    janosi_shear_stress_pa,
    janosi_stress_pa,
    max_thrust_n,
    mohr_coulomb_strength_pa,
    okello_secant,
    okello_traction,
    patch_thrust_n,
    shear_strength_pa,
    small_slip_stiffness,
)


def _secant_series(x: float) -> float:
    """sum_k (-x)^k/(k+2)!, the Taylor series of (x - 1 + e^-x)/x^2 (exact enough for x < 6)."""
    return math.fsum((-x) ** k / math.factorial(k + 2) for k in range(60))


def test_mohr_coulomb_strength_is_cohesion_plus_normal_stress_tan_phi():
    q = mohr_coulomb_strength_pa(10e3, 800.0, math.radians(30.0))
    assert q == pytest.approx(800.0 + 10e3 / math.sqrt(3.0), rel=1e-14)


def test_janosi_shear_at_j_equal_k_is_63_2_percent_of_q_max():
    q = janosi_shear_stress_pa(0.025, 1000.0, 0.025)
    assert q == pytest.approx(1000.0 * (1.0 - math.exp(-1.0)), rel=1e-14)
    assert q == pytest.approx(632.1, abs=0.1)


def test_janosi_shear_is_zero_at_zero_odd_in_j_and_tends_to_q_max():
    j = np.array([0.0, 0.01, -0.01, 10.0])
    q = janosi_shear_stress_pa(j, 500.0, 0.02)
    assert q[0] == 0.0
    assert q[2] == -q[1]
    assert q[3] == pytest.approx(500.0, rel=1e-12)


def test_stress_of_floats_at_four_moduli_is_98_percent_of_the_mohr_coulomb_strength():
    """Wong Eq. 2.54 and 2.56 on plain floats, as the track model passes its soil."""
    strength = shear_strength_pa(2800.0, 1.04e3, math.tan(math.radians(28.0)))
    assert strength == pytest.approx(1.04e3 + 2800.0 * 0.531709, rel=1e-6)
    assert janosi_stress_pa(0.1, strength, 0.025) == pytest.approx(
        strength * (1.0 - math.exp(-4.0)), rel=1e-14)


def test_stress_broadcasts_a_strength_per_track_over_its_cells():
    j = np.array([0.0, 0.025, 1.0])
    strength = shear_strength_pa(np.array([[1e3], [2e3]]), 0.0, 1.0)
    tau = janosi_stress_pa(j, strength, 0.025)
    assert tau.shape == (2, 3)
    np.testing.assert_allclose(tau[:, 1], strength[:, 0] * (1.0 - math.exp(-1.0)), rtol=1e-14)
    assert not tau[:, 0].any()


@pytest.mark.parametrize("x", [0.0, 1e-12, 1e-9, 3e-6, 1e-5, 2e-5, 1e-3, 0.1, 1.0, 5.0])
def test_okello_secant_matches_its_taylor_series_to_1e_10(x):
    assert okello_secant(x) == pytest.approx(_secant_series(x), rel=1e-10, abs=0.0)


def test_okello_secant_is_one_half_at_zero_and_matches_closed_form_at_large_x():
    assert okello_secant(0.0) == pytest.approx(0.5, rel=1e-10)
    x = np.array([10.0, 100.0, 1e6])
    assert okello_secant(x) == pytest.approx((x - 1.0 + np.exp(-x)) / x**2, rel=1e-14)


def test_okello_curve_tends_to_amplitude_as_slip_grows():
    b = 0.1
    s = np.array([10.0, 100.0, 1e4])
    c_t = okello_traction(s, 2.0, b)
    assert c_t == pytest.approx(2.0 * (1.0 - b / s), rel=1e-14)  # e^{-s/B} below 1e-43
    assert okello_traction(1e9, 2.0, b) == pytest.approx(2.0, rel=1e-9)


def test_okello_curve_matches_lindgren_eq_23_series_at_small_slip():
    a, b = 3.0, 0.2
    s = np.array([1e-6, 1e-4, 1e-3])
    x = s / b
    series = a / (2 * b) * s * (1 - x / 3 + x**2 / 12 - x**3 / 60)  # Eq. 23, two terms more
    assert okello_traction(s, a, b) == pytest.approx(series, rel=1e-10)


def test_okello_curve_slope_at_zero_is_lindgren_eq_24_stiffness():
    a, b, ds = 3.0, 0.2, 1e-8
    slope = okello_traction(ds, a, b) / ds
    assert slope == pytest.approx(small_slip_stiffness(a, b), rel=1e-7)
    assert small_slip_stiffness(a, b) == pytest.approx(7.5, rel=1e-15)


def test_okello_curve_is_odd_and_zero_without_nan_at_zero_slip():
    s = np.array([-0.7, -0.01, 0.0, 0.01, 0.7])
    c_t = okello_traction(s, 1.0, 0.05)
    assert c_t[2] == 0.0
    assert c_t[::-1] == pytest.approx(-c_t, rel=1e-15)


def test_patch_thrust_equals_janosi_shear_integrated_over_the_patch():
    # uniform pressure p = W/A, shear displacement j = s x at x behind the front edge
    s, w, b, length, c, phi, k = 0.15, 650.0, 0.11, 0.06, 800.0, math.radians(30.0), 0.018
    q_max = float(mohr_coulomb_strength_pa(w / (b * length), c, phi))
    integral, _ = quad(lambda x: b * float(janosi_shear_stress_pa(s * x, q_max, k)), 0.0, length,
                       epsabs=0.0, epsrel=1e-13)
    assert patch_thrust_n(s, w, b * length, length, c, phi, k) == pytest.approx(integral,
                                                                                rel=1e-11)


def test_patch_thrust_never_exceeds_mohr_coulomb_limit():
    s = np.linspace(-1.0, 1.0, 401)
    f = patch_thrust_n(s, 400.0, 0.02, 0.1, 1500.0, 0.5, 0.005)
    f_max = max_thrust_n(400.0, 0.02, 1500.0, 0.5)
    assert f_max == pytest.approx(0.02 * 1500.0 + 400.0 * math.tan(0.5), rel=1e-15)
    assert np.all(np.abs(f) < f_max)
    assert np.abs(f).max() == pytest.approx(f_max * (1 - 0.05 * (1 - math.exp(-20.0))),
                                            rel=1e-13)


def test_lateral_anisotropy_multiplies_the_small_slip_side_stiffness_and_keeps_the_limit():
    """kappa = 3.6 (Reina's C_y/C_x on loose soil): the small-slip lateral stiffness is kappa
    times the longitudinal one, the resultant still saturates at A c + W tan phi, and
    kappa = 1 is the isotropic law exactly."""
    load, ac, tan_phi, ratio = 100.0, 20.0, 0.6, 6.0
    f_max = ac + load * tan_phi
    d = 1e-6
    c_x = janosi_forces(d, 0.0, load, ac, tan_phi, ratio, 3.6)[0] / d
    c_y = -janosi_forces(0.0, d, load, ac, tan_phi, ratio, 3.6)[1] / d
    assert c_x == pytest.approx(f_max * ratio / 2, rel=1e-5)  # Lindgren Eq. 24
    assert c_y / c_x == pytest.approx(3.6, rel=1e-5)
    fx, fy = janosi_forces(0.3, -20.0, load, ac, tan_phi, ratio, 3.6)
    assert math.hypot(fx, fy) < f_max
    assert fy == pytest.approx(f_max, rel=0.01)  # sliding sideways: the Mohr-Coulomb limit
    for s, t in ((0.1, 0.2), (-0.4, 0.05), (0.0, -0.3)):
        assert janosi_forces(s, t, load, ac, tan_phi, ratio, 1.0) == janosi_forces(
            s, t, load, ac, tan_phi, ratio)
