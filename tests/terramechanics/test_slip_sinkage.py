"""Slip sinkage (Lyasko 2010) and the wheel's frontal bulldozing (Bekker 1956): closed forms at
known inputs, zero at zero slip, monotone in |slip|, and a resistance the soil never turns into
positive work."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terramechanics import _laws, bekker, sidewall, slip_dynamics
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import (
    JanosiForceModel,
    LinearSlipForceModel,
    ReinaForceModel,
    slip_sinkage_resistance,
    wheel_kernel,
)
from slipenv.terramechanics.presets import CONCRETE, LOOSE_SAND, LUNAR_SIMULANT

ROVER_WHEEL = ContactGeometry(radius_m=0.09, width_m=0.08, contact_length_m=0.05)
SAND = LOOSE_SAND.params()
SLIPS = np.linspace(-1.0, 1.0, 201)


@pytest.mark.parametrize(("slip", "factor"), [(0.0, 1.0), (0.2, 1.2 / 0.9), (0.5, 2.0),
                                               (1.0, 4.0), (-0.4, 1.0), (1.7, 4.0)])
def test_lyasko_factor_is_one_plus_i_over_one_minus_half_i_on_the_clipped_slip(slip, factor):
    assert bekker.slip_sinkage_factor(slip) == pytest.approx(factor, rel=1e-15)


def test_lyasko_factor_grows_with_slip():
    f = [bekker.slip_sinkage_factor(s) for s in np.linspace(0.0, 1.0, 101)]
    assert np.all(np.diff(f) > 0.0)


@pytest.mark.parametrize(("phi_deg", "d1", "d2"), [(0.0, 2.0, 1.0),
                                                   (30.0, 2.0 * math.sqrt(3.0),
                                                    2.0 * math.sqrt(3.0))])
def test_bulldozing_coefficients_at_known_friction_angles(phi_deg, d1, d2):
    # phi = 0: X_c = 45 deg, cot = 1; phi = 30 deg: X_c = 30 deg, cot = tan 60 = sqrt 3
    got = sidewall.bulldozing_coefficients(math.radians(phi_deg))
    assert got == pytest.approx((d1, d2), rel=1e-14)


def test_bulldozing_per_width_is_bekkers_quadratic_in_depth():
    d1 = d2 = 2.0 * math.sqrt(3.0)
    c, gamma, h = 800.0, 1.5e4, 0.03
    want = d1 * (c * h + d2 * gamma * h * h / 2.0)
    assert _laws.bulldozing_resistance_n_per_m(h, c, math.radians(30.0), gamma) == \
        pytest.approx(want, rel=1e-14)
    assert _laws.bulldozing_resistance_n_per_m(-0.01, c, math.radians(30.0), gamma) == 0.0


def test_slip_sinkage_resistance_closed_form_at_full_slip():
    rc0, n, z0, b, c, phi, gamma = 10.0, 1.1, 0.02, 0.08, 600.0, math.radians(29.0), 1.5e4
    d1, d2 = sidewall.bulldozing_coefficients(phi)
    dug = 3.0 * z0  # f(1) = 4: three static sinkages dug out
    want = rc0 * (4.0 ** (n + 1.0) - 1.0) + b * d1 * (c * dug + d2 * gamma * dug * dug / 2.0)
    for slip in (1.0, -1.0):  # spinning, or locked and skidding
        got = _laws.slip_sinkage_resistance_n(slip, rc0, n, z0, b, c, phi, gamma)
        assert got == pytest.approx(want, rel=1e-13)


def test_slip_sinkage_resistance_is_zero_at_zero_slip_and_grows_with_abs_slip():
    args = (12.0, 1.1, 0.02, 0.08, 600.0, math.radians(29.0), 1.5e4)
    assert _laws.slip_sinkage_resistance_n(0.0, *args) == 0.0
    mags = np.linspace(0.0, 1.0, 101)
    for sign in (1.0, -1.0):
        r = [_laws.slip_sinkage_resistance_n(sign * m, *args) for m in mags]
        assert np.all(np.diff(r) > 0.0)


def _model_resistance(model, soil, slip, load):
    return wheel_kernel(model, soil)(slip, 0.0, load)[2]


@pytest.mark.parametrize("cls", [JanosiForceModel, LinearSlipForceModel, ReinaForceModel])
def test_the_option_is_off_by_default_and_the_resistance_then_ignores_slip(cls):
    model = cls(ROVER_WHEEL)
    assert model.slip_sinkage is None and not model.kernel_constants(SAND).slip_sinkage
    r = [_model_resistance(model, SAND, s, 60.0) for s in (-1.0, -0.3, 0.0, 0.3, 1.0)]
    assert r == pytest.approx([r[2]] * 5, rel=1e-15)


def test_full_mode_is_bekker_compaction_at_the_lyasko_sinkage_plus_bulldozing():
    load, slip = 60.0, 0.5  # f = 2: the sinkage doubles
    model = JanosiForceModel(ROVER_WHEEL, slip_sinkage="full")
    s, b, d = SAND, ROVER_WHEEL.width_m, 2.0 * ROVER_WHEEL.radius_m
    z0 = bekker.wheel_sinkage_float_m(load, b, d, s.k_c, s.k_phi, s.n_exp)
    rc = [float(bekker.compaction_resistance_n(z, b, s.k_c, s.k_phi, s.n_exp))
          for z in (z0, 2.0 * z0)]
    bulldozing = b * sidewall.bulldozing_resistance_n_per_m(z0, s.cohesion_pa,
                                                            s.friction_angle_rad,
                                                            model.soil_unit_weight_n_m3)
    want = rc[1] - rc[0] + float(bulldozing)
    static = _model_resistance(model, SAND, 0.0, load)
    assert static == pytest.approx(0.01 * load + rc[0], rel=1e-12)
    assert _model_resistance(model, SAND, slip, load) - static == pytest.approx(want, rel=1e-10)


def test_bulldozing_mode_adds_only_the_fronts_bulldozing():
    load, slip = 60.0, -1.0  # locked: f = 4, three static sinkages dug out
    model = ReinaForceModel(ROVER_WHEEL, slip_sinkage="bulldozing")
    s, b = SAND, ROVER_WHEEL.width_m
    z0 = bekker.wheel_sinkage_float_m(load, b, 0.18, s.k_c, s.k_phi, s.n_exp)
    want = b * float(sidewall.bulldozing_resistance_n_per_m(3.0 * z0, s.cohesion_pa,
                                                             s.friction_angle_rad,
                                                             model.soil_unit_weight_n_m3))
    extra = slip_sinkage_resistance(slip, load, model.kernel_constants(SAND))
    assert extra == pytest.approx(want, rel=1e-12)
    # a light rover wheel locked on loose sand meets about half its load ahead of it
    assert 0.3 * load < extra < 0.8 * load


@pytest.mark.parametrize("mode", ["bulldozing", "full"])
@pytest.mark.parametrize("soil", [SAND, LUNAR_SIMULANT.params()])
def test_resistance_grows_with_abs_slip_in_drive_and_braking(mode, soil):
    model = JanosiForceModel(ROVER_WHEEL, slip_sinkage=mode)
    r = np.array([_model_resistance(model, soil, s, 60.0) for s in SLIPS])
    mid = len(SLIPS) // 2
    assert np.all(np.diff(r[mid:]) > 0.0) and np.all(np.diff(r[:mid + 1]) < 0.0)
    assert r[-1] > 2.0 * r[mid] and r[0] == pytest.approx(r[-1], rel=1e-15)


def test_no_slip_sinkage_on_rigid_ground():
    model = JanosiForceModel(ROVER_WHEEL, slip_sinkage="full")
    concrete = CONCRETE.params()
    assert _model_resistance(model, concrete, 1.0, 60.0) == \
        pytest.approx(_model_resistance(model, concrete, 0.0, 60.0), rel=1e-15)


def test_the_option_is_validated():
    with pytest.raises(ValueError, match="slip_sinkage"):
        JanosiForceModel(ROVER_WHEEL, slip_sinkage="lyasko")
    with pytest.raises(ValueError, match="soil_unit_weight_n_m3"):
        ReinaForceModel(ROVER_WHEEL, slip_sinkage="full", soil_unit_weight_n_m3=-1.0)
    track = ContactGeometry(radius_m=0.05, width_m=0.1, contact_length_m=0.4,
                            track_length_m=0.4)
    with pytest.raises(ValueError, match="track"):
        JanosiForceModel(track, slip_sinkage="bulldozing")


def test_the_soil_never_does_positive_work_on_a_sliding_wheel():
    """The slip-dependent resistance through the rate-independent element: whatever the slip
    and load, once the wheel slides (|v| dt beyond the stick length) the force opposes v."""
    rng = np.random.default_rng(7)
    kernel = wheel_kernel(ReinaForceModel(ROVER_WHEEL, slip_sinkage="full"), SAND)
    dt, stick, state = 1e-3, 1e-3, 0.0
    for _ in range(2000):
        slip, load = rng.uniform(-1.0, 1.0), rng.uniform(0.0, 120.0)
        v = rng.choice([-1.0, 1.0]) * rng.uniform(2.0 * stick / dt, 3.0)
        res = kernel(slip, 0.0, load)[2]
        assert res >= 0.0
        r, state = slip_dynamics.rut_resistance_n(res, state, v * dt, v, stick, 0.0)
        assert -r * v <= 0.0 and abs(r) <= res * (1.0 + 1e-15)


def test_the_tracks_array_factor_is_the_wheels_c_law():
    from slipenv.terramechanics import track
    slips = np.linspace(-0.5, 1.5, 401)
    want = [bekker.slip_sinkage_factor(s) for s in slips.tolist()]
    assert track.slip_sinkage_factor(slips) == pytest.approx(want, rel=1e-15)
