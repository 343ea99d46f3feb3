"""Linear torque-slip law and the rolling-radius error line (Lindgren Eq. 24-31)."""

import numpy as np
import pytest

from slipenv.terramechanics.lindgren import (
    actual_slip,
    linear_torque_nm,
    measured_slip,
    slip_from_speeds,
    stiffness_and_radius_ratio,
    torque_slip_line,
)


def test_linear_torque_is_k_s_times_slip_below_saturation():
    s = np.array([-0.02, 0.0, 0.01, 0.05])
    assert linear_torque_nm(s, 400.0, 100.0) == pytest.approx(400.0 * s, rel=1e-15)


def test_linear_torque_saturates_at_plus_minus_t_max():
    t = linear_torque_nm(np.array([-1.0, 0.5, 0.25]), 400.0, 100.0)
    assert t.tolist() == [-100.0, 100.0, 100.0]


def test_slip_from_speeds_is_one_minus_v_over_omega_r():
    assert slip_from_speeds(0.9, 4.0, 0.25) == pytest.approx(0.1, rel=1e-14)
    assert slip_from_speeds(1.0, 4.0, 0.25) == 0.0


def test_actual_slip_eq_30_agrees_with_eq_25_26_from_speeds():
    omega, v = np.array([3.0, 3.5, 4.0]), np.array([0.80, 0.95, 1.05])
    r_m, r_a = 0.275, 0.283  # Lindgren: concrete-calibrated radius, actual radius on soil
    s_m = slip_from_speeds(v, omega, r_m)
    s_a = slip_from_speeds(v, omega, r_a)
    assert actual_slip(s_m, r_m, r_a) == pytest.approx(s_a, rel=1e-13)
    assert measured_slip(s_a, r_m, r_a) == pytest.approx(s_m, rel=1e-13)


def test_radius_error_line_eq_31_has_lindgren_slope_and_offset():
    k_s, r_m, r_a = 7.7449, 0.275, 0.283
    slope, intercept = torque_slip_line(k_s, r_m, r_a)
    assert slope == pytest.approx(k_s * 0.275 / 0.283, rel=1e-15)
    assert intercept == pytest.approx(k_s * (1 - 0.275 / 0.283), rel=1e-13)
    assert intercept == pytest.approx(0.21894, abs=1e-5)
    # the law T = k_s s_a, plotted against measured slip, is exactly that line
    s_a = np.linspace(0.0, 0.2, 11)
    fit_slope, fit_intercept = np.polyfit(measured_slip(s_a, r_m, r_a), k_s * s_a, 1)
    assert fit_slope == pytest.approx(slope, rel=1e-12)
    assert fit_intercept == pytest.approx(intercept, rel=1e-10)


def test_line_is_through_origin_when_radius_is_right():
    slope, intercept = torque_slip_line(5.0, 0.28, 0.28)
    assert (slope, intercept) == (5.0, 0.0)


def test_inverting_lindgren_fig_2_fit_gives_stiffness_and_radius_ratio():
    k_s, ratio = stiffness_and_radius_ratio(7.2874, 0.4575)  # T = 0.4575 + 7.2874 s
    assert k_s == pytest.approx(7.7449, rel=1e-15)
    assert ratio == pytest.approx(7.2874 / 7.7449, rel=1e-15)
    assert ratio == pytest.approx(0.94093, abs=1e-5)
    assert torque_slip_line(k_s, ratio, 1.0) == pytest.approx((7.2874, 0.4575), rel=1e-12)
