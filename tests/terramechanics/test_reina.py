"""Reina's combined-slip model with Table 3 parameters (Reina Eq. 5-12)."""

import math

import numpy as np
import pytest

from slipenv.terramechanics.reina import (
    exp_secant,
    reina_forces_n,
    reina_max_longitudinal_force_n,
    reina_reference_force_n,
)

W = 6.6 * 9.80665  # [N] Reina Sec. 3.2 test-bed load
TABLE_3 = {"mu": 0.6, "c_x_n": 55.0, "c_y_n": 200.0, "a_x": 0.02, "a_y": 0.04}


def test_exp_secant_is_one_at_zero_and_exact_elsewhere():
    assert exp_secant(0.0) == 1.0
    y = np.array([1e-20, 1e-8, 0.3, 40.0])
    assert exp_secant(y) == pytest.approx(-np.expm1(-y) / y, rel=1e-15)


@pytest.mark.parametrize(("s", "expected"), [(0.2, 9.320445771278266),
                                             (0.5, 19.058803145625145),
                                             (0.8, 25.291773643987742)])
def test_table_3_longitudinal_reference_curve_eq_5_by_hand(s, expected):
    by_hand = W * (0.6 * (1.0 - math.exp(-55.0 * s / (0.6 * W))) - 0.02 * s)
    assert by_hand == pytest.approx(expected, rel=1e-14)
    assert reina_reference_force_n(s, W, 0.6, 55.0, 0.02) == pytest.approx(expected, rel=1e-14)


def test_table_3_lateral_reference_curve_eq_6_at_10_degrees():
    tb = math.tan(math.radians(10.0))
    f = reina_reference_force_n(tb, W, 0.6, 200.0, 0.04)
    assert f == pytest.approx(22.71631730782099, rel=1e-14)


def test_reference_curve_slope_at_zero_is_the_stiffness_c():
    ds = 1e-9
    assert reina_reference_force_n(ds, W, 0.6, 55.0, 0.02) / ds == pytest.approx(
        55.0 - 0.02 * W, rel=1e-7)


def test_reference_curve_is_odd_in_slip():
    s = np.array([-0.6, -0.1, 0.0, 0.1, 0.6])
    f = reina_reference_force_n(s, W, 0.6, 55.0, 0.02)
    assert f[::-1] == pytest.approx(-f, rel=1e-15)
    assert f[2] == 0.0


def test_combined_slip_reduces_to_pure_longitudinal_at_zero_slip_angle():
    s = np.linspace(-0.8, 0.8, 17)
    fx, fy = reina_forces_n(s, 0.0, W, **TABLE_3)
    assert fx == pytest.approx(reina_reference_force_n(s, W, 0.6, 55.0, 0.02), rel=1e-13,
                               abs=1e-13)
    assert np.all(fy == 0.0)


def test_combined_slip_reduces_to_pure_lateral_at_zero_slip_ratio():
    tb = np.tan(np.radians([-25.0, -5.0, 5.0, 25.0]))
    fx, fy = reina_forces_n(0.0, tb, W, **TABLE_3)
    assert np.all(fx == 0.0)
    assert -fy == pytest.approx(reina_reference_force_n(tb, W, 0.6, 200.0, 0.04), rel=1e-13)


def test_combined_forces_follow_eq_7_to_9_by_hand():
    s, tb = 0.3, math.tan(math.radians(15.0))
    sigma = math.hypot(s, tb)
    fx0 = W * (0.6 * (1 - math.exp(-55.0 * sigma / (0.6 * W))) - 0.02 * sigma)
    fy0 = W * (0.6 * (1 - math.exp(-200.0 * sigma / (0.6 * W))) - 0.04 * sigma)
    fx, fy = reina_forces_n(s, tb, W, **TABLE_3)
    assert fx == pytest.approx(s / sigma * fx0, rel=1e-13)
    assert fy == pytest.approx(-tb / sigma * fy0, rel=1e-13)


def test_combined_forces_are_odd_in_slip_and_in_slip_angle_and_fy_opposes_tan_beta():
    s, tb = np.meshgrid(np.linspace(-0.8, 0.8, 9), np.tan(np.radians(np.linspace(-25, 25, 11))))
    fx, fy = reina_forces_n(s, tb, W, **TABLE_3)
    fx_m, fy_m = reina_forces_n(-s, tb, W, **TABLE_3)
    assert fx_m == pytest.approx(-fx, rel=1e-15) and fy_m == pytest.approx(fy, rel=1e-15)
    fx_m, fy_m = reina_forces_n(s, -tb, W, **TABLE_3)
    assert fx_m == pytest.approx(fx, rel=1e-15) and fy_m == pytest.approx(-fy, rel=1e-15)
    assert np.all(np.sign(fy) == -np.sign(tb)) and np.all(np.sign(fx) == np.sign(s))


def test_slip_angle_reduces_longitudinal_force_at_the_same_slip_ratio():
    tb = np.tan(np.radians([0.0, 5.0, 10.0, 25.0]))
    fx, _ = reina_forces_n(0.3, tb, W, **TABLE_3)
    assert np.all(np.diff(fx) < 0.0)


def test_zero_total_slip_and_zero_load_give_zero_force_without_nan():
    fx, fy = reina_forces_n(np.zeros(3), np.zeros(3), np.array([0.0, W, 100.0]), **TABLE_3)
    assert np.all(fx == 0.0) and np.all(fy == 0.0)
    fx, fy = reina_forces_n(0.5, 0.2, 0.0, **TABLE_3)
    assert abs(fx) < 1e-11 and abs(fy) < 1e-11


def test_force_is_floored_at_zero_beyond_sigma_mu_over_a():
    fx, fy = reina_forces_n(0.0, 100.0, W, **TABLE_3)  # sigma = 100 > mu/A_y = 15
    assert fy == 0.0
    assert reina_reference_force_n(100.0, W, 0.6, 200.0, 0.04) < 0.0  # Eq. 6 itself turns


def test_saturation_matches_eq_10_when_a_x_is_negligible():
    tb = np.tan(np.radians([0.0, 10.0, 25.0]))
    fx, _ = reina_forces_n(1.0, tb, W, mu=0.6, c_x_n=5000.0, c_y_n=200.0, a_x=0.0, a_y=0.04)
    assert fx == pytest.approx(reina_max_longitudinal_force_n(tb, W, 0.6), rel=1e-12)
    assert reina_max_longitudinal_force_n(0.0, W, 0.6) == pytest.approx(0.6 * W, rel=1e-15)
