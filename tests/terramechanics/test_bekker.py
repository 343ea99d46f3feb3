"""Bekker sinkage and compaction resistance of wheels and tracks."""

import math

import numpy as np
import pytest

from slipenv.terramechanics import CONCRETE, FIELD_LOAM, LOOSE_SAND
from slipenv.terramechanics.bekker import (
    compaction_resistance_n,
    pressure_sinkage_m,
    rut_following_compaction_n,
    rut_load_ratio,
    track_compaction_law,
    track_sinkage_m,
    wheel_compaction_law,
    wheel_sinkage_m,
)

SAND = (LOOSE_SAND.k_c, LOOSE_SAND.k_phi, LOOSE_SAND.n_exp)


def test_wheel_sinkage_matches_closed_form_for_n_equal_one():
    # n = 1: z = (3 W / (2 (k_c + b k_phi) sqrt(D)))^(2/3)
    w, b, d, k_c, k_phi = 120.0, 0.1, 0.33, 1.4e3, 820e3
    expected = (3 * w / (2 * (k_c + b * k_phi) * math.sqrt(d))) ** (2 / 3)
    assert wheel_sinkage_m(w, b, d, k_c, k_phi, 1.0) == pytest.approx(expected, rel=1e-14)
    assert expected == pytest.approx(0.024168, abs=1e-6)


def test_wheel_sinkage_increases_with_load():
    z = wheel_sinkage_m(np.array([0.0, 50.0, 100.0, 400.0]), 0.1, 0.33, *SAND)
    assert z[0] == 0.0 and np.all(np.diff(z) > 0.0)


def test_wheel_sinkage_decreases_with_stiffer_soil():
    k_c, k_phi, n = SAND
    z = wheel_sinkage_m(120.0, 0.1, 0.33, k_c, np.array([1.0, 2.0, 4.0]) * k_phi, n)
    assert np.all(np.diff(z) < 0.0)
    z = wheel_sinkage_m(120.0, 0.1, 0.33, np.array([1.0, 100.0]) * k_c, k_phi, n)
    assert z[1] < z[0]


def test_wheel_sinkage_decreases_with_larger_wheel():
    z = wheel_sinkage_m(120.0, np.array([0.1, 0.2]), np.array([0.33, 0.66]), *SAND)
    assert z[1] < z[0]


def test_compaction_resistance_matches_closed_form_and_grows_with_load():
    z, b, k_c, k_phi = 0.02, 0.1, 1.4e3, 820e3
    assert compaction_resistance_n(z, b, k_c, k_phi, 1.0) == pytest.approx(
        b * (k_c / b + k_phi) * z**2 / 2, rel=1e-14)
    r = compaction_resistance_n(wheel_sinkage_m(np.array([50.0, 100.0]), b, 0.33, *SAND), b,
                                *SAND)
    assert r[1] > r[0] > 0.0


def test_wheel_compaction_power_law_equals_sinkage_then_resistance():
    w = np.array([0.0, 10.0, 120.0, 3000.0])
    gamma, e = wheel_compaction_law(0.1, 0.33, *SAND)
    direct = compaction_resistance_n(wheel_sinkage_m(w, 0.1, 0.33, *SAND), 0.1, *SAND)
    assert gamma * w**e == pytest.approx(direct, rel=1e-12)
    assert e == pytest.approx((2 * 1.1 + 2) / (2 * 1.1 + 1), rel=1e-15)


def test_track_sinkage_is_pressure_over_modulus_to_one_over_n():
    w, b, length, k_c, k_phi = 100.0, 0.11, 0.6, 990.0, 1.52843e6
    p = w / (b * length)
    z = track_sinkage_m(w, b, length, k_c, k_phi, 1.1)
    assert z == pytest.approx((p / (k_c / b + k_phi)) ** (1 / 1.1), rel=1e-14)
    assert z < wheel_sinkage_m(w, b, 0.1, k_c, k_phi, 1.1)  # a track spreads the load


def test_pressure_sinkage_solves_bekkers_law_and_compaction_is_the_work_of_the_rut():
    """A track cell under 2800 Pa (about 30 kg on two 0.48 x 0.11 m tracks) on dry sand."""
    p, b, k_c, k_phi, n = 2800.0, 0.11, 0.99e3, 1528.43e3, 1.1
    z = float(pressure_sinkage_m(p, b, k_c, k_phi, n))
    assert (k_c / b + k_phi) * z**n == pytest.approx(p, rel=1e-12)
    r = float(compaction_resistance_n(z, b, k_c, k_phi, n))
    zs = np.linspace(0.0, z, 20001)  # R_c = b int_0^z p dz
    assert r == pytest.approx(b * np.trapezoid((k_c / b + k_phi) * zs**n, zs), rel=1e-6)


def test_pressure_sinkage_and_compaction_broadcast_a_soil_per_track_over_its_cells():
    """The track model's shapes: pressures (n_tracks, n_cells), one soil per track (column)."""
    p = np.array([[0.0, 1e3, 4e3], [-50.0, 1e3, 4e3]])
    k_phi = np.array([[820e3], [1640e3]])
    z = pressure_sinkage_m(p, 0.11, 990.0, k_phi, 1.0)
    assert z.shape == (2, 3)
    np.testing.assert_allclose(z, p.clip(0.0) / (990.0 / 0.11 + k_phi), rtol=1e-14)
    r = compaction_resistance_n(z.max(axis=1, keepdims=True), 0.11, 990.0, k_phi, 1.0)
    assert r.shape == (2, 1) and r[1, 0] < r[0, 0]  # the stiffer soil sinks and resists less


def test_negative_sinkage_compacts_nothing():
    assert compaction_resistance_n(-0.01, 0.1, *SAND) == 0.0


def test_track_compaction_power_law_equals_sinkage_then_resistance():
    w = np.array([10.0, 100.0, 1000.0])
    gamma, e = track_compaction_law(0.11, 0.6, *SAND)
    direct = compaction_resistance_n(track_sinkage_m(w, 0.11, 0.6, *SAND), 0.11, *SAND)
    assert gamma * w**e == pytest.approx(direct, rel=1e-12)


def test_compaction_resistance_is_zero_on_concrete():
    p = CONCRETE.params()
    for law in (wheel_compaction_law(0.1, 0.33, p.k_c, p.k_phi, p.n_exp, p.deformable),
                track_compaction_law(0.1, 0.6, p.k_c, p.k_phi, p.n_exp, p.deformable)):
        gamma, e = law
        assert gamma == 0.0
        assert np.all(gamma * np.array([0.0, 100.0, 1e4]) ** e == 0.0)


def test_negative_load_counts_as_no_load():
    assert wheel_sinkage_m(-5.0, 0.1, 0.33, *SAND) == 0.0
    assert track_sinkage_m(-5.0, 0.1, 0.6, *SAND) == 0.0


def test_a_wheel_in_the_rut_of_an_equal_wheel_compacts_nothing_and_a_heavier_one_the_rest():
    """Multi-pass (Wong §2.4 repetitive loading): the follower's work is R_c(z_f) - R_c(z_rut),
    i.e. the compaction of the soil between the rut's depth and its own sinkage."""
    k_c, k_phi, n = SAND
    b, d = 0.25, 0.55
    z_lead = float(wheel_sinkage_m(1000.0, b, d, k_c, k_phi, n))
    z_follow = float(wheel_sinkage_m(1400.0, b, d, k_c, k_phi, n))
    r_lead = float(compaction_resistance_n(z_lead, b, k_c, k_phi, n))
    r_follow = float(compaction_resistance_n(z_follow, b, k_c, k_phi, n))
    k_eq = k_c + b * k_phi
    expected = k_eq * (z_follow ** (n + 1) - z_lead ** (n + 1)) / (n + 1)
    assert rut_following_compaction_n(r_follow, r_lead) == pytest.approx(expected, rel=1e-12)
    assert rut_following_compaction_n(r_lead, r_lead) == 0.0
    assert rut_following_compaction_n(r_lead, r_follow) == 0.0  # lighter: no deeper


def test_rut_load_ratio_gives_the_followers_compaction_at_the_leaders_rut_depth():
    """A narrow castor (0.12 m x 0.30 m) behind a wide wheel (0.25 m x 0.55 m): its own law at
    q W_leader equals Bekker's R_c for its width at the leader's sinkage, for any n."""
    soil = FIELD_LOAM
    for n in (0.5, soil.n_exp, 1.3):
        gamma, e = wheel_compaction_law(0.12, 0.30, soil.k_c, soil.k_phi, n)
        for w_lead in (200.0, 1500.0):
            z = float(wheel_sinkage_m(w_lead, 0.25, 0.55, soil.k_c, soil.k_phi, n))
            at_rut = float(compaction_resistance_n(z, 0.12, soil.k_c, soil.k_phi, n))
            q = rut_load_ratio(0.12, 0.30, 0.25, 0.55, soil.k_c, soil.k_phi)
            assert float(gamma) * (q * w_lead) ** float(e) == pytest.approx(at_rut, rel=1e-12)
    assert rut_load_ratio(0.25, 0.55, 0.25, 0.55, soil.k_c, soil.k_phi) == 1.0
    assert rut_load_ratio(0.12, 0.30, 0.25, 0.55, soil.k_c, soil.k_phi) < 1.0  # deeper per N
