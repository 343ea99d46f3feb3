"""Side-wall bulldozing force of a sunken wheel: Bekker's coefficients, Ishigami's integral."""

from __future__ import annotations

import math

import pytest

from slipenv.terramechanics.sidewall import (
    bulldozing_coefficients,
    bulldozing_resistance_n_per_m,
    sidewall_force_n,
)


def test_bulldozing_coefficients_at_30_degrees_match_their_closed_form():
    # X_c = 30 deg: cot X_c = sqrt(3), tan(X_c + phi) = tan 60 = sqrt(3), tan phi = 1/sqrt(3).
    d1, d2 = bulldozing_coefficients(math.radians(30.0))
    assert d1 == pytest.approx(2.0 * math.sqrt(3.0), rel=1e-12)
    assert d2 == pytest.approx(math.sqrt(3.0) + 3.0 / math.sqrt(3.0), rel=1e-12)
    # phi = 0: X_c = 45 deg, D_1 = 1 + 1, D_2 = 1.
    assert bulldozing_coefficients(0.0) == pytest.approx((2.0, 1.0), rel=1e-12)


def test_bulldozing_resistance_is_cohesive_linear_plus_frictional_quadratic_in_depth():
    phi, c, gamma, h = math.radians(30.0), 800.0, 1.5e4, 0.02
    d1, d2 = bulldozing_coefficients(phi)
    assert float(bulldozing_resistance_n_per_m(h, c, phi, gamma)) == pytest.approx(
        d1 * (c * h + 0.5 * d2 * gamma * h * h), rel=1e-12)
    assert float(bulldozing_resistance_n_per_m(-0.01, c, phi, gamma)) == 0.0


def _closed_form_force(z, r, c, phi, gamma):
    """F_s over [0, theta_f] integrated by hand: h = r (cos t - a), a = cos theta_f."""
    tf, a = math.acos(1.0 - z / r), 1.0 - z / r
    s, s2, s4 = math.sin(tf), math.sin(2 * tf), math.sin(4 * tf)
    i_cos = s                                               # int cos
    i_cos2 = tf / 2 + s2 / 4                                # int cos^2
    i_cos3 = s - s ** 3 / 3                                 # int cos^3
    i_cos4 = 3 * tf / 8 + s2 / 4 + s4 / 32                  # int cos^4
    int_h = r * (i_cos - a * tf)                            # int h
    int_h_cos = r * (i_cos2 - a * i_cos)                    # int h cos
    int_h2 = r * r * (i_cos2 - 2 * a * i_cos + a * a * tf)  # int h^2
    int_h2_cos = r * r * (i_cos3 - 2 * a * i_cos2 + a * a * i_cos)
    int_h3_cos = r ** 3 * (i_cos4 - 3 * a * i_cos3 + 3 * a * a * i_cos2 - a ** 3 * i_cos)
    d1, d2 = bulldozing_coefficients(phi)
    cohesive = c * (r * int_h - int_h2_cos)                 # int c h (r - h cos)
    frictional = 0.5 * d2 * gamma * (r * int_h2 - int_h3_cos)
    assert int_h_cos > 0.0
    return d1 * (cohesive + frictional)


@pytest.mark.parametrize("z", [0.002, 0.01, 0.03])
def test_sidewall_force_equals_the_closed_form_integral_at_a_known_sinkage(z):
    r, c, phi, gamma = 0.092, 800.0, math.radians(30.0), 1.5e4
    expected = _closed_form_force(z, r, c, phi, gamma)
    assert sidewall_force_n(z, r, c, phi, gamma) == pytest.approx(expected, rel=1e-9)
    # Each soil term alone as well (cohesion only; weight only).
    assert sidewall_force_n(z, r, c, phi, 0.0) == pytest.approx(
        _closed_form_force(z, r, c, phi, 0.0), rel=1e-9)
    assert sidewall_force_n(z, r, 0.0, phi, gamma) == pytest.approx(
        _closed_form_force(z, r, 0.0, phi, gamma), rel=1e-9)


def test_sidewall_force_grows_as_sinkage_to_the_3_2_for_a_cohesive_shallow_wheel():
    # Shallow: h ~ r (theta_f^2 - theta^2)/2, theta_f ~ sqrt(2 z/r), so F ~ c D_1 r^2 theta_f^3/3.
    r, c, phi = 0.092, 800.0, math.radians(30.0)
    f1, f2 = (sidewall_force_n(z, r, c, phi, 0.0) for z in (1e-5, 4e-5))
    assert f2 / f1 == pytest.approx(8.0, rel=1e-3)
    d1, _ = bulldozing_coefficients(phi)
    tf = math.sqrt(2e-5 / r)
    assert f1 == pytest.approx(c * d1 * r * r * tf ** 3 / 3.0, rel=1e-3)


def test_a_symmetric_rut_doubles_the_wall_of_a_no_rebound_rut_and_no_sinkage_gives_none():
    r, z, c, phi, gamma = 0.092, 0.015, 800.0, math.radians(30.0), 1.5e4
    one = sidewall_force_n(z, r, c, phi, gamma)
    both = sidewall_force_n(z, r, c, phi, gamma, exit_angle_rad=-math.acos(1 - z / r))
    assert both == pytest.approx(2.0 * one, rel=1e-9)
    assert sidewall_force_n(0.0, r, c, phi, gamma) == 0.0
    with pytest.raises(ValueError, match="exit_angle_rad"):
        sidewall_force_n(z, r, c, phi, gamma, exit_angle_rad=0.1)
