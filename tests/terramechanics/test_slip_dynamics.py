"""Slip relaxation, soil dampers and resistance ramp: closed forms, without PyBullet."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

from slipenv.terramechanics.contact import slip_ratio
from slipenv.terramechanics.reina import reina_forces
from slipenv.terramechanics.slip_dynamics import (
    contact_relaxation_length_m,
    critical_damping_ns_per_m,
    lateral_soil_damping_n,
    longitudinal_soil_damping_n,
    relax_slip,
    resistance_along_travel_n,
    rut_resistance_n,
    rut_resistance_vector_n,
)

SIGMA_M = 0.02  # [m] relaxation length (a soil's Janosi K)
DT_S = 1.0 / 240.0  # [s] physics substep


def _run(s0: float, t0: float, rim: float, v: float, v_lat: float, steps: int,
         dt_s: float = DT_S, forward: bool = False) -> tuple[float, float]:
    s, t = s0, t0
    for _ in range(steps):
        s, t, _, _ = relax_slip(s, t, rim, v, v_lat, dt_s / SIGMA_M, forward)
    return s, t


@pytest.mark.parametrize(("rim", "v"), [(1.0, 0.9), (0.5, 0.6), (-1.0, -0.9), (0.2, 0.0),
                                        (0.0, 0.3), (0.05, 0.049)])
def test_steady_state_is_the_kinematic_slip_ratio(rim, v):
    s_ss = float(slip_ratio(rim, v))
    s, t, v_ref, v_lat_ref = relax_slip(s_ss, 0.0, rim, v, 0.0, DT_S / SIGMA_M)
    assert s == pytest.approx(s_ss, rel=1e-14, abs=1e-15)
    assert t == 0.0 and v_ref == v_lat_ref == max(abs(rim), abs(v))
    assert _run(0.0, 0.0, rim, v, 0.0, 5000)[0] == pytest.approx(s_ss, rel=1e-12, abs=1e-14)


def test_steady_side_slip_is_v_lat_over_v_and_points_along_the_sliding_velocity():
    rim, v, v_lat = 1.0, 0.8, 0.3  # |r omega| is the reference speed
    s, t = _run(0.0, 0.0, rim, v, v_lat, 5000)
    assert s == pytest.approx((rim - v) / rim, rel=1e-12)
    assert t == pytest.approx(v_lat / rim, rel=1e-12)
    assert math.atan2(t, s) == pytest.approx(math.atan2(v_lat, rim - v), rel=1e-12)
    _, t = _run(0.0, 0.0, 0.8, 0.8, 0.1, 5000)  # no longitudinal slip: tan beta = v_lat/|v|
    assert t == pytest.approx(0.1 / 0.8, rel=1e-12)


def test_in_reinas_convention_side_slip_relaxes_to_v_lat_over_v_x():
    """Reina Eq. 4: tan(beta) = v_lat/v_x, whatever the slip; the sliding-velocity state is
    (1 - s) times it in drive (Reina Eq. 3, s = 1 - v_x/(r omega))."""
    rim, v, v_lat = 1.0, 0.6, 0.2
    s, t = _run(0.0, 0.0, rim, v, v_lat, 5000, forward=True)
    assert s == pytest.approx(1.0 - v / rim, rel=1e-12)
    assert t == pytest.approx(v_lat / v, rel=1e-12)
    _, t_sliding = _run(0.0, 0.0, rim, v, v_lat, 5000)
    assert t_sliding == pytest.approx((1.0 - s) * t, rel=1e-12)
    # braking (|v| > |r omega|): the two conventions agree, tan(beta) = v_lat/|v|
    assert _run(0.0, 0.0, 0.5, 0.8, 0.1, 5000, forward=True)[1] == pytest.approx(0.125, rel=1e-12)
    assert _run(0.0, 0.0, 0.5, 0.8, 0.1, 5000)[1] == pytest.approx(0.125, rel=1e-12)
    # reversing: v_x < 0, tan(beta) = v_lat/|v_x|
    assert _run(0.0, 0.0, -1.0, -0.5, 0.1, 5000, forward=True)[1] == pytest.approx(0.2, rel=1e-12)


def test_in_reinas_convention_beyond_45_degrees_tan_beta_settles_at_one_from_below():
    """The leak max(|v_x|, |v_lat|) takes the state smoothly to +-1 (the clip never acts:
    |b + h v_lat| <= 1 + h |v_lat| when |b| <= 1)."""
    t, states = 0.0, []
    for _ in range(2000):
        _, t, _, v_b = relax_slip(0.0, t, 1.0, 0.2, -0.5, DT_S / SIGMA_M, True)
        states.append(t)
    assert v_b == 0.5
    assert np.all(np.diff(states) <= 0.0) and states[-1] == pytest.approx(-1.0, abs=1e-12)
    # one backward-Euler step per relaxation length of sideways travel takes it 1/2 of the way
    h = SIGMA_M / 0.5
    assert relax_slip(0.0, 0.0, 1.0, 0.2, -0.5, h / SIGMA_M, True)[1] == pytest.approx(-0.5)


def test_in_reinas_convention_a_wheel_spinning_in_place_holds_its_lateral_state():
    """v = v_lat = 0, r omega = 1: s -> 1, tan(beta) keeps the lateral deformation it had (no
    division by v_x = 0), and the side damper, which fades with the state's own leak V_b = 0,
    is at full strength."""
    s, t, v_ref, v_b = relax_slip(0.0, 0.3, 1.0, 0.0, 0.0, DT_S / SIGMA_M, True)
    assert t == 0.3 and v_ref == 1.0 and v_b == 0.0
    assert _run(0.0, 0.3, 1.0, 0.0, 0.0, 2000, forward=True) == pytest.approx((1.0, 0.3),
                                                                            rel=1e-12)
    assert lateral_soil_damping_n(0.01, v_b, 300.0, 0.2) == -3.0


def test_in_reinas_convention_starting_from_rest_the_state_is_finite_and_reaches_the_law():
    """Spin-up from standstill: r omega = a t, v_x = 0.5 a t, v_lat = 0.1 a t from exactly 0.
    The state is finite at every step (it never divides by v_x) and ends at Reina's
    s = 0.5, tan(beta) = v_lat/v_x = 0.2."""
    s, t = 0.0, 0.0
    for k in range(2400):
        speed = 0.1 * k * DT_S  # a = 0.1 m/s^2, 10 s
        s, t, _, _ = relax_slip(s, t, speed, 0.5 * speed, 0.1 * speed, DT_S / SIGMA_M, True)
        assert math.isfinite(s) and math.isfinite(t) and abs(s) <= 1.0 and abs(t) <= 1.0
    assert (s, t) == pytest.approx((0.5, 0.2), rel=0.01)


M_KG, LOAD_N = 6.6, 6.6 * 9.81  # Reina's wheel (Table 3 was fitted at W = 6.6 kg)
REINA_TABLE_3 = (0.6, 55.0, 200.0, 0.02, 0.04)  # mu, C_x [N], C_y [N], A_x, A_y


def _slide_sideways(rim: float, v_x: float, v_lat0: float, forward: bool,
                    steps: int = 2400) -> tuple[float, float, float, float]:
    """A wheel of mass m sliding sideways at v_lat0, held at (r omega, v_x), stopped only by
    Reina's side force on the relaxed state plus the side damper (as the substep loop applies
    them). Returns (largest cumulative work of the soil on the wheel [J], final v_lat, largest
    |tan beta|, largest |F_y|)."""
    c = critical_damping_ns_per_m(REINA_TABLE_3[2], SIGMA_M, M_KG, 0.5, 0.5 * M_KG / DT_S)
    d = c * SIGMA_M / DT_S
    s, t, v = 0.0, 0.0, v_lat0
    work = work_max = t_max = f_max = 0.0
    for _ in range(steps):
        s, t_new, _, v_b = relax_slip(s, t, rim, v_x, v, DT_S / SIGMA_M, forward)
        _, f_y = reina_forces(s, t_new, LOAD_N, *REINA_TABLE_3)
        f_y += lateral_soil_damping_n(t_new - t, v_b, d, 0.2)
        assert math.isfinite(f_y) and math.isfinite(t_new)
        t = t_new
        work += f_y * v * DT_S
        work_max, t_max, f_max = max(work_max, work), max(t_max, abs(t)), max(f_max, abs(f_y))
        v += f_y / M_KG * DT_S
    return work_max, v, t_max, f_max


@pytest.mark.parametrize("forward", [True, False])
@pytest.mark.parametrize(("rim", "v_x", "v_lat0"), [
    (0.0, 0.0, 0.05),    # pure sideways motion, wheel still
    (0.0, 0.0, 1.0),     # ... fast: far beyond 45 deg
    (0.1, 0.0, 0.05),    # spinning at v = 0 while sliding sideways
    (0.5, 0.0, 0.3),     # spinning fast at v = 0
    (1e-4, 1e-5, 0.05),  # creeping, v_x -> 0
])
def test_at_low_speed_the_side_force_stays_finite_and_dissipative(rim, v_x, v_lat0, forward):
    """Passivity: from an undeformed soil the side force never does net positive work on the
    wheel (it can only return what it stored), and it stops the sideways slide within 10 s.
    Bounded by Reina's mu W (plus the damper), whatever v_x."""
    work_max, v_end, t_max, f_max = _slide_sideways(rim, v_x, v_lat0, forward)
    assert work_max == 0.0
    assert abs(v_end) < 1e-6 * v_lat0
    assert t_max <= 1.0
    assert f_max < 2.0 * REINA_TABLE_3[0] * LOAD_N


@pytest.mark.parametrize("steps", [1, 3, 10, 40])
def test_step_response_is_the_backward_euler_geometric_decay(steps):
    rim, v = 0.5, 0.4
    h_v = DT_S / SIGMA_M * rim  # h V
    s_ss = (rim - v) / rim
    s, _ = _run(0.3, 0.0, rim, v, 0.0, steps)
    assert s == pytest.approx(s_ss + (0.3 - s_ss) * (1.0 + h_v) ** -steps, rel=1e-13)


def test_step_response_converges_to_the_exponential_of_the_ode_at_first_order_in_dt():
    """sigma ds/dt + V s = r omega - v from s = 0: s(t) = s_ss (1 - e^{-V t/sigma})."""
    rim, v, t_end = 0.5, 0.45, 0.04  # V t/sigma = 1
    s_ss = (rim - v) / rim
    exact = s_ss * (1.0 - math.exp(-rim * t_end / SIGMA_M))
    errors = []
    for n in (40, 80, 160, 320):
        s, _ = _run(0.0, 0.0, rim, v, 0.0, n, dt_s=t_end / n)
        errors.append(abs(s - exact))
    assert errors[-1] < 2e-3 * s_ss
    ratios = np.array(errors[:-1]) / np.array(errors[1:])
    np.testing.assert_allclose(ratios, 2.0, rtol=0.05)  # first order: halving dt halves it


def test_at_standstill_the_state_integrates_the_slip_displacement():
    """V -> 0: s = -(displacement)/sigma, the Janosi soil spring that holds a parked wheel."""
    creep = 1e-6  # [m/s] the wheel centre creeps forward with the wheel locked
    s, _ = _run(0.0, 0.0, 0.0, creep, 0.0, 240)  # 1 s
    assert s == pytest.approx(-creep * 1.0 / SIGMA_M, rel=1e-4)
    for forward in (False, True):
        assert relax_slip(0.01, -0.02, 0.0, 0.0, 0.0, DT_S / SIGMA_M, forward) == (
            0.01, -0.02, 0.0, 0.0)


def test_a_wheel_spinning_in_place_reaches_full_slip_monotonically_without_division_by_zero():
    s, slips = 0.0, []
    for _ in range(200):
        s, _, _, _ = relax_slip(s, 0.0, 1.0, 0.0, 0.0, DT_S / SIGMA_M)
        slips.append(s)
    assert np.all(np.diff(slips) >= 0.0) and slips[-1] == pytest.approx(1.0, abs=1e-12)
    assert slips[0] == pytest.approx(DT_S / SIGMA_M / (1.0 + DT_S / SIGMA_M), rel=1e-15)


def test_states_are_clipped_to_full_slip_when_the_wheel_turns_against_the_motion():
    assert _run(0.0, 0.0, 1.0, -1.0, 0.0, 200) == (1.0, 0.0)  # kinematic s = (1 + 1)/1 = 2
    assert _run(0.0, 0.0, -1.0, 1.0, 0.0, 200) == (-1.0, 0.0)
    assert _run(0.0, 0.0, 0.0, 0.0, -3.0, 200) == (0.0, -1.0)  # pure sideways sliding


def test_lateral_damper_vanishes_in_steady_side_slip_and_opposes_the_change():
    assert lateral_soil_damping_n(0.0, 0.05, 300.0, 0.2) == 0.0
    assert lateral_soil_damping_n(0.01, 0.0, 300.0, 0.2) == pytest.approx(-3.0, rel=1e-15)
    assert lateral_soil_damping_n(-0.01, 0.0, 300.0, 0.2) == pytest.approx(3.0, rel=1e-15)


def test_lateral_damper_fades_as_one_over_one_plus_speed_ratio_to_the_fourth():
    full = lateral_soil_damping_n(0.01, 0.0, 300.0, 0.2)
    assert lateral_soil_damping_n(0.01, 0.2, 300.0, 0.2) == pytest.approx(full / 2, rel=1e-15)
    assert lateral_soil_damping_n(0.01, 0.6, 300.0, 0.2) == pytest.approx(full / 82, rel=1e-14)


def test_longitudinal_damper_acts_only_below_the_low_speed_and_only_when_sliding():
    c, v_low = 40.0, 0.02
    assert longitudinal_soil_damping_n(0.001, 0.001, 0.001, c, v_low) == 0.0  # no sliding
    assert longitudinal_soil_damping_n(0.03, 0.0, 0.03, c, v_low) == 0.0  # driving
    assert longitudinal_soil_damping_n(0.02, 0.0, 0.02, c, v_low) == 0.0  # continuous at v_low
    # Linear fade: at V = v_low/2 half of c (r omega - v); full at standstill.
    assert longitudinal_soil_damping_n(0.0, -0.01, 0.01, c, v_low) == pytest.approx(0.2, rel=1e-14)
    assert longitudinal_soil_damping_n(1e-9, 0.0, 1e-9, c, v_low) == pytest.approx(4e-8, rel=1e-6)


def test_critical_damping_makes_the_soil_spring_critically_damped_at_ratio_one():
    stiffness_n, mass_kg = 3000.0, 12.0  # C = dF/ds [N], wheel's mass share
    c = critical_damping_ns_per_m(stiffness_n, SIGMA_M, mass_kg, 1.0, 1e9)
    k = stiffness_n / SIGMA_M  # [N/m]
    assert c * c == pytest.approx(4.0 * k * mass_kg, rel=1e-14)  # m x'' + c x' + k x: double root
    assert critical_damping_ns_per_m(stiffness_n, SIGMA_M, mass_kg, 0.5, 1e9) == pytest.approx(
        c / 2, rel=1e-15)
    assert critical_damping_ns_per_m(stiffness_n, SIGMA_M, mass_kg, 1.0, 100.0) == 100.0


def test_resistance_ramps_linearly_through_zero_and_opposes_travel_beyond():
    r, v_r = 5.0, 0.02
    assert resistance_along_travel_n(r, 0.0, v_r) == 0.0
    assert resistance_along_travel_n(r, 0.01, v_r) == pytest.approx(2.5, rel=1e-15)
    assert resistance_along_travel_n(r, -0.01, v_r) == pytest.approx(-2.5, rel=1e-15)
    assert resistance_along_travel_n(r, 3.0, v_r) == r
    assert resistance_along_travel_n(r, -3.0, v_r) == -r


def test_relaxation_length_is_the_front_arc_r_acos_1_minus_z_over_r_with_its_floor():
    r = 0.3
    assert contact_relaxation_length_m(r, 0.0, 0.01) == 0.01  # rigid ground: the floor
    assert contact_relaxation_length_m(r, r, 0.01) == pytest.approx(r * math.pi / 2, rel=1e-15)
    assert contact_relaxation_length_m(r, 2 * r, 0.01) == pytest.approx(r * math.pi / 2)  # clip
    z = 0.01  # shallow: the arc tends to the chord sqrt(2 r z)
    assert contact_relaxation_length_m(r, z, 0.0) == pytest.approx(math.sqrt(2 * r * z), rel=0.01)
    # Brush-model consistency (slip_dynamics docstring): the standstill stiffness C/sigma of a
    # patch of shear length L equals F_max/K when sigma = L/2 (C = F_max L/(2K), Lindgren Eq. 23).
    f_max, k_soil, length = 500.0, 0.025, 0.18
    assert (f_max * length / (2 * k_soil)) / (length / 2) == pytest.approx(f_max / k_soil)


def _push(force_n: float, resistance_n: float, mass_kg: float, steps: int,
          v0: float = 0.0) -> tuple[float, float]:
    """A mass pushed by a constant force against the resistance element; (x, v) at the end."""
    x, v, u = 0.0, v0, 0.0
    stick = 1e-3
    c = critical_damping_ns_per_m(resistance_n, stick, mass_kg, 0.5, 0.5 * mass_kg / DT_S)
    for _ in range(steps):
        r, u = rut_resistance_n(resistance_n, u, v * DT_S, v, stick, c)
        v += (force_n - r) / mass_kg * DT_S
        x += v * DT_S
    return x, v


def test_resistance_element_holds_a_push_below_r_without_creeping():
    """Coulomb at rest: 0.9 R applied from rest moves the mass by about the stick length (the
    damped spring overshoots a little), then it stays put: no creep between 5 s and 10 s (the
    old speed ramp crept at v_r F/R = 1.8 cm/s here)."""
    x5, v5 = _push(0.9 * 300.0, 300.0, 120.0, 1200)
    x10, v10 = _push(0.9 * 300.0, 300.0, 120.0, 2400)
    assert 0.0 < x5 < 2e-3
    assert abs(x10 - x5) < 1e-9 and abs(v10) < 1e-9


def test_resistance_element_is_rate_independent_in_sliding():
    """Pushed by 1.5 R, the mass accelerates at exactly (1.5 R - R)/m at any speed: the
    resistance is R whether it moves at 1 mm/s or 1 m/s (compaction is rate-independent)."""
    for v0 in (0.001, 0.01, 1.0):
        x, v = _push(450.0, 300.0, 120.0, 240, v0=v0)
        assert v - v0 == pytest.approx(150.0 / 120.0, rel=0.02)
    r, u = rut_resistance_n(300.0, 1.0, 1e-6, 1e-3, 1e-3, 1e4)
    assert (r, u) == (300.0, 1.0)
    r, u = rut_resistance_n(300.0, -1.0, -1e-6, -1e-3, 1e-3, 1e4)
    assert (r, u) == (-300.0, -1.0)


def test_resistance_element_never_exceeds_r_and_never_pushes_along_the_motion_when_sliding():
    rng = np.random.default_rng(3)
    for _ in range(200):
        res, u0 = rng.uniform(0, 500), rng.uniform(-1, 1)
        v = rng.normal(0, 0.5)
        r, u = rut_resistance_n(res, u0, v * DT_S, v, 1e-3, rng.uniform(0, 1e4))
        assert abs(r) <= res + 1e-12 and abs(u) <= 1.0
        if abs(u) == 1.0 and u * v > 0:
            assert r == pytest.approx(res * u)


def test_castor_resistance_points_along_its_velocity_with_magnitude_r():
    v = (0.3, 0.1, 0.0)
    u = (0.0, 0.0, 0.0)
    for _ in range(50):  # 0.2 s: far beyond the 1 mm stick length
        r, u = rut_resistance_vector_n(300.0, u, v, DT_S, 1e-3, 5e3)
    assert math.hypot(*r) == pytest.approx(300.0, rel=1e-12)
    assert math.atan2(r[1], r[0]) == pytest.approx(math.atan2(v[1], v[0]), abs=1e-9)
    # turning: the drag follows the new direction after a few stick lengths of travel
    v = (0.0, 0.3, 0.0)
    for _ in range(10):  # 12.5 mm
        r, u = rut_resistance_vector_n(300.0, u, v, DT_S, 1e-3, 5e3)
    assert math.atan2(r[1], r[0]) == pytest.approx(math.pi / 2, abs=1e-3)
    r, _ = rut_resistance_vector_n(300.0, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0), DT_S, 1e-3, 5e3)
    assert r == (0.0, 0.0, 0.0)  # at rest, unloaded: no force


def test_slip_dynamics_import_no_physics_engine():
    code = ("import sys, slipenv.terramechanics.slip_dynamics, slipenv.terramechanics; "
            "sys.exit('pybullet' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], check=False).returncode == 0
