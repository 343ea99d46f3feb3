"""s_x(beta) on a slope from Reina's law (Fig. 12) and its Eq. 12 fit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terramechanics.presets import LUNAR_SIMULANT
from slipenv.terramechanics.reina import reina_reference_force_n
from slipenv.testbed.slip_curve import fit_slip_ratio_for_slope, slip_ratio_for_slope

SOIL = LUNAR_SIMULANT


def test_without_slip_angle_the_slip_solves_eq_5_for_the_tractive_effort():
    s0 = float(slip_ratio_for_slope(0.0, 12.0, SOIL))
    # Normal load cos(theta), effort sin(theta), per unit weight: F_x0(s0)/cos = tan(theta).
    f = reina_reference_force_n(s0, 1.0, SOIL.mu, SOIL.c_x_n / SOIL.reference_load_n, SOIL.a_x)
    assert float(f) == pytest.approx(math.tan(math.radians(12.0)), rel=1e-9)


def test_slip_ratio_grows_with_slip_angle_as_in_fig_12():
    beta = np.radians(np.linspace(0.0, 25.0, 11))
    s = slip_ratio_for_slope(beta, 12.0, SOIL)
    assert np.all(np.diff(s) > 0)
    assert s[-1] > 1.1 * s[0]  # lateral slip uses up adhesion (friction ellipse, Eq. 11)


def test_eq_12_fit_follows_the_numerical_curve_and_steepens_with_the_slope():
    fits = {}
    for slope in (8.0, 12.0, 16.0):
        fit, beta, s = fit_slip_ratio_for_slope(slope, SOIL)
        assert np.max(np.abs(fit.model(beta) - s)) < 0.01
        assert fit.model.s_x0 == pytest.approx(s[0], abs=0.005)
        fits[slope] = fit.model
    # Reina §3.3: for a given terrain both k and s_x0 increase with the inclination.
    assert fits[8.0].s_x0 < fits[12.0].s_x0 < fits[16.0].s_x0
    assert 0 < fits[8.0].k_per_rad < fits[12.0].k_per_rad < fits[16.0].k_per_rad


def test_a_slope_beyond_the_soils_adhesion_has_no_slip_that_climbs_it():
    assert np.all(np.isnan(slip_ratio_for_slope([0.0, 0.2], 35.0, SOIL)))  # tan 35 > mu
    with pytest.raises(ValueError, match="cannot deliver"):
        fit_slip_ratio_for_slope(35.0, SOIL)
    with pytest.raises(ValueError, match="slope_deg"):
        slip_ratio_for_slope(0.0, -5.0, SOIL)
