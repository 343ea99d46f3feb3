"""Slip sinkage (Lyasko 2010) and the wheel's frontal bulldozing (Bekker 1956): closed forms at
known inputs, zero at zero slip, monotone in |slip|, and a resistance the soil never turns into
positive work; the slip sinkage as a state (the depth dug grows with the distance slid and
relaxes over the distance rolled): its steady state, its relaxation length, its growth with
nothing rolled."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terramechanics import _laws, bekker, sidewall, slip_dynamics
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import (
    DEFAULT_EXCAVATION_DEPTH_M,
    WHEEL_SLIP_SINKAGE,
    JanosiForceModel,
    LinearSlipForceModel,
    ReinaForceModel,
    dug_depth_resistance,
    dug_depth_step,
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
def test_the_default_is_the_wheels_default_and_off_the_resistance_ignores_slip(cls):
    assert cls(ROVER_WHEEL).slip_sinkage == WHEEL_SLIP_SINKAGE
    model = cls(ROVER_WHEEL, slip_sinkage=None)
    k = model.kernel_constants(SAND)
    assert model.slip_sinkage is None and not k.slip_sinkage and not k.sinkage_state
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


# -- slip sinkage as a state: the depth dug grows with the distance slid, relaxes over the
# -- distance rolled (models.dug_depth_step, C laws_slip_sinkage_step)

DELTA, SIGMA, DT = 0.004, 0.06, 1e-4


def _run_state(dug, rim, v, seconds, cap=1.0):
    h = DT / SIGMA
    for _ in range(round(seconds / DT)):
        dug = dug_depth_step(dug, rim, v, h, DELTA, cap)
    return dug


@pytest.mark.parametrize(("rim", "v"), [(1.0, 0.7), (0.5, 0.1), (0.4, 0.5), (0.1, 0.6),
                                         (-1.0, -0.6), (-0.3, -0.9)])
def test_state_settles_at_delta_slide_over_roll(rim, v):
    """Steady state of sigma dd/dt = delta |r omega - v| - v_roll d: delta s/(1 - |s|), s the
    slip over the larger speed, driving or braking, forward or in reverse."""
    slip = (rim - v) / max(abs(rim), abs(v))
    want = DELTA * abs(slip) / (1.0 - abs(slip))
    assert want == pytest.approx(DELTA * abs(rim - v) / min(abs(rim), abs(v)), rel=1e-12)
    # from below and from above: the same fixed point of the backward-Euler map
    seconds = 40.0 * SIGMA / min(abs(rim), abs(v))
    for start in (0.0, 3.0 * want):
        assert _run_state(start, rim, v, seconds) == pytest.approx(want, rel=1e-9)
    h = DT / SIGMA
    assert dug_depth_step(want, rim, v, h, DELTA, 1.0) == pytest.approx(want, rel=1e-13)


@pytest.mark.parametrize("v", [0.05, 0.5, 2.0])
def test_rolling_without_slip_relaxes_over_one_patch_length(v):
    """Pure rolling (r omega = v): d(x) = d0 exp(-x/sigma) over the distance x rolled, at any
    speed: exactly d0 (1 + h v)^(-n) after n steps of backward Euler, which is exp(-x/sigma)
    to within (x/sigma) h v/2 (0.5 % at 3 sigma and h v = 3.3e-3)."""
    d0, h = 0.01, DT / SIGMA
    for x in (SIGMA, 3.0 * SIGMA):
        n = round(x / v / DT)
        got = _run_state(d0, v, v, x / v)
        assert got == pytest.approx(d0 * (1.0 + h * v) ** -n, rel=1e-10)
        bound = 0.6 * (x / SIGMA) * h * v
        assert got == pytest.approx(d0 * math.exp(-x / SIGMA), rel=bound)


@pytest.mark.parametrize(("rim", "v"), [(0.8, 0.0), (0.0, -0.8), (0.5, -0.3)])
def test_with_nothing_rolled_the_wheel_digs_delta_per_patch_length_slid_up_to_the_cap(rim, v):
    """Spinning in place, locked and skidding, or spinning against the travel: v_roll = 0, so
    d = delta x/sigma over the distance x slid, until the cap (buried to the axle)."""
    slid = abs(rim - v) * 0.05
    assert _run_state(0.0, rim, v, 0.05) == pytest.approx(DELTA * slid / SIGMA, rel=1e-9)
    assert _run_state(0.0, rim, v, 5.0, cap=0.03) == 0.03


def test_dug_resistance_at_lyaskos_depth_is_the_instantaneous_law():
    args = (12.0, 1.1, 0.02, 0.08, 600.0, math.radians(29.0), 1.5e4)
    for slip in (0.1, 0.5, 1.0, -0.7):
        dug = 0.02 * (bekker.slip_sinkage_factor(abs(slip)) - 1.0)
        assert _laws.dug_resistance_n(dug, *args) == pytest.approx(
            _laws.slip_sinkage_resistance_n(slip, *args), rel=1e-12)
    assert _laws.dug_resistance_n(0.0, *args) == 0.0
    assert _laws.dug_resistance_n(-0.01, *args) == 0.0


def test_accumulated_mode_binds_the_state_and_leaves_the_kernel_stateless():
    """The kernel has no memory: in the "accumulated" mode its resistance ignores the slip and
    the simulation's state adds the bulldozing of the depth dug (`dug_depth_resistance`)."""
    model = ReinaForceModel(ROVER_WHEEL, slip_sinkage="accumulated")
    k = model.kernel_constants(SAND)
    assert k.sinkage_state and not k.slip_sinkage and k.sinkage_gamma == 0.0
    assert k.excavation_depth_m == DEFAULT_EXCAVATION_DEPTH_M
    r = [_model_resistance(model, SAND, s, 60.0) for s in (-1.0, 0.0, 0.4, 1.0)]
    assert r == pytest.approx([r[1]] * 4, rel=1e-15)
    load, dug = 60.0, 0.015
    want = ROVER_WHEEL.width_m * float(sidewall.bulldozing_resistance_n_per_m(
        dug, SAND.cohesion_pa, SAND.friction_angle_rad, model.soil_unit_weight_n_m3))
    assert dug_depth_resistance(dug, load, k) == pytest.approx(want, rel=1e-12)
    # one substep of the loop's state: delta = the model's depth, then that resistance
    z0 = bekker.wheel_sinkage_float_m(load, ROVER_WHEEL.width_m, 0.18, SAND.k_c, SAND.k_phi,
                                      SAND.n_exp)
    h = 1e-3 / 0.05
    dug1, res1 = _laws.kernel_sinkage_state(tuple(k), dug, 0.3, 0.1, h, load)
    assert dug1 == pytest.approx(
        dug_depth_step(dug, 0.3, 0.1, h, DEFAULT_EXCAVATION_DEPTH_M, 0.09 - z0), rel=1e-14)
    assert res1 == pytest.approx(dug_depth_resistance(dug1, load, k), rel=1e-12)
    assert _laws.kernel_sinkage_state(tuple(k), dug, 0.3, 0.1, h, 0.0) == (0.0, 0.0)
    off = ReinaForceModel(ROVER_WHEEL, slip_sinkage=None).kernel_constants(SAND)
    assert _laws.kernel_sinkage_state(tuple(off), dug, 0.3, 0.1, h, load) == (0.0, 0.0)


def test_excavation_depth_m_is_validated():
    with pytest.raises(ValueError, match="excavation_depth_m"):
        ReinaForceModel(ROVER_WHEEL, slip_sinkage="accumulated", excavation_depth_m=-0.1)
    with pytest.raises(ValueError, match="excavation_depth_m"):
        JanosiForceModel(ROVER_WHEEL, slip_sinkage="accumulated", excavation_depth_m=math.nan)


def test_the_wheels_default_mode_never_reaches_a_track(monkeypatch):
    """Whatever the wheels' default (`models.WHEEL_SLIP_SINKAGE`), a track's contact, which has
    its own law, builds without slip sinkage; asked for another mode, it still refuses."""
    from slipenv.terramechanics import models
    monkeypatch.setattr(models, "WHEEL_SLIP_SINKAGE", "accumulated")
    track = ContactGeometry(radius_m=0.05, width_m=0.1, contact_length_m=0.4,
                            track_length_m=0.4)
    assert JanosiForceModel(track, slip_sinkage="accumulated").slip_sinkage is None
    assert ReinaForceModel(ROVER_WHEEL, slip_sinkage="accumulated").slip_sinkage == "accumulated"
    with pytest.raises(ValueError, match="track"):
        JanosiForceModel(track, slip_sinkage="bulldozing")
