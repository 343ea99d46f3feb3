"""The track model's plain functions against the closed forms (Wong & Chiang 2001; Wong,
Theory of Ground Vehicles, Ch. 2, 4 and 7; Bekker; Rankine; Lyasko)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terramechanics.track import (
    advance_shear,
    advance_wall,
    berm_height_m,
    cell_forces,
    load_spread_matrix,
    passive_coefficient,
    passive_pressure_n_per_m,
    rut_resistance_n,
    shear_direction,
    sliding_velocity,
    slip_sinkage_factor,
    soil_damper_forces,
    steady_shear_displacement,
    steady_track_forces,
    wall_force_n_per_m,
)

L, B_W, N = 0.48, 0.11, 16  # Patako's track: contact length, width [m]; cells
C, PHI, K = 1.04e3, math.radians(28.0), 0.025  # Wong's dry sand (LLL), K of loose sand
TAN_PHI = math.tan(PHI)
P = 2800.0  # [Pa] about 30 kg on two 0.48 x 0.11 m tracks
DX = L / N
DT = 1 / 240
E_MAX = 1e-3  # [m] the direction state's length (slipenv.sim.track_soil default)
X_CELL = L / 2 - DX * (np.arange(N) + 0.5)


def per_track(n_t, *values):
    """Each value as an array of one entry per track (the functions take the soil per track)."""
    out = tuple(np.full(n_t, float(v)) for v in values)
    return out if len(out) > 1 else out[0]


def soil(n_t, cohesion=C):
    """(b, c, tan phi, K) per track."""
    return per_track(n_t, B_W, cohesion, TAN_PHI, K)


def _steady(vx, vy, omega, ys, us, t_end=8.0, pressure=P):
    """Run the transient scheme at fixed kinematics to steady state; per track F_x, F_y, the
    yaw moment about the hull centre and the moment of the lateral forces b int x tau_y."""
    n_t = len(ys)
    j, e = np.zeros((2, n_t, N + 1)), np.zeros((2, n_t, N))
    ys_a = np.asarray(ys, float)
    us = np.asarray(us, float)
    x_cells = np.ascontiguousarray(np.broadcast_to(X_CELL, (n_t, N)))
    vc = sliding_velocity(vx - omega * ys_a, us, np.full(n_t, vy), omega, x_cells)
    for _ in range(int(t_end / DT)):
        advance_shear(j, e, vc, us, omega, DX, DT, E_MAX)
    b, c, tan_phi, k = soil(n_t)
    (fx, fy), _ = cell_forces(j, e, np.full((n_t, N), pressure), b, DX, c, tan_phi, k)
    mz = (X_CELL * fy).sum(axis=1) - ys_a * fx.sum(axis=1)
    return fx.sum(axis=1), fy.sum(axis=1), mz, (X_CELL * fy).sum(axis=1)


def _wong_track_thrust_n(slip, load_n):
    """Wong's track thrust with Janosi shear under uniform pressure (Wong Ch. 4):
    F = (A c + W tan phi)[1 - K/(i L)(1 - e^{-i L/K})]."""
    x = slip * L / K
    return (B_W * L * C + load_n * TAN_PHI) * (1.0 - (1.0 - math.exp(-x)) / x)


@pytest.mark.parametrize("slip", [0.02, 0.1, 0.3, 0.7])
def test_straight_driving_gives_wongs_track_thrust_equation(slip):
    u = 0.2
    fx, fy, _, _ = _steady(u * (1 - slip), 0.0, 0.0, [0.0], [u])
    assert fx[0] == pytest.approx(_wong_track_thrust_n(slip, P * B_W * L), rel=0.01)
    assert abs(fy[0]) < 1e-9


def test_driving_backwards_the_thrust_reverses():
    u = -0.2
    fx, _, _, _ = _steady(u * 0.9, 0.0, 0.0, [0.0], [u])
    assert fx[0] == pytest.approx(-_wong_track_thrust_n(0.1, P * B_W * L), rel=0.01)


@pytest.mark.parametrize("v,radius,vy,ratio_outer,ratio_inner", [
    (0.1, 0.5, 0.01, 0.8, 0.85),  # a 0.5 m turn with a lateral drift (shifted turning centre)
    (0.05, 0.25, 0.0, 0.7, 0.7),  # Yamauchi's r = 0.25 m circle at 5 cm/s
])
def test_steady_turn_thrusts_and_turning_moment_match_the_wong_chiang_integrals(
        v, radius, vy, ratio_outer, ratio_inner):
    """Outer and inner thrusts and the moment of turning resistance b int x tau_y dx of the
    transient scheme at steady state within 5 % of the exact Wong-Chiang integrals."""
    half = 0.205
    omega = v / radius
    ys = [-half, half]  # outer (right, for a left turn), inner
    us = [(radius + half) * omega / ratio_outer, (radius - half) * omega / ratio_inner]
    # Steady once the slowest belt has passed its contact length three times.
    fx, fy, mz, mr = _steady(v, vy, omega, ys, us, t_end=3 * L / min(us) + 2.0)
    exact = [steady_track_forces(v, vy, omega, y, u, L, B_W, P, C, TAN_PHI, K)
             for y, u in zip(ys, us, strict=True)]
    for i in range(2):
        assert fx[i] == pytest.approx(exact[i][0], rel=0.05)
    m_exact = sum(e[2] + y * e[0] for e, y in zip(exact, ys, strict=True))
    assert mr.sum() == pytest.approx(m_exact, rel=0.05)
    assert mr.sum() < 0.0  # the ground resists the left turn
    assert fx[0] > fx[1]


def steady_turn(v, radius, vy, ratio_outer, ratio_inner):
    """The shear field (j, e) of a left turn of ``radius`` [m] at ``v`` [m/s] with lateral
    drift ``vy``, the tracks at slip ratios ``ratio_*`` (ground over belt speed), run until the
    slowest belt has passed its contact length three times: (omega, ys, us, j, e), outer
    (right) track first."""
    half = 0.205
    omega = v / radius
    ys = np.array([-half, half])
    us = np.array([(radius + half) * omega / ratio_outer, (radius - half) * omega / ratio_inner])
    j, e = np.zeros((2, 2, N + 1)), np.zeros((2, 2, N))
    vc = sliding_velocity(v - omega * ys, us, np.full(2, vy), omega, np.array([X_CELL, X_CELL]))
    for _ in range(int((3 * L / min(us) + 2.0) / DT)):
        advance_shear(j, e, vc, us, omega, DX, DT, E_MAX)
    return omega, ys, us, j, e


@pytest.mark.parametrize("v,radius,vy,ratio_outer,ratio_inner", [
    (0.1, 0.5, 0.01, 0.8, 0.85), (0.05, 0.25, 0.0, 0.7, 0.7)])
def test_in_a_steady_turn_the_shear_field_is_wong_chiangs_path_integral(
        v, radius, vy, ratio_outer, ratio_inner):
    """The advected field j(x) at the faces against the exact path integral, the hull's
    rotation during contact included: within 1 % where the hull turns by less than 2 rad
    while the soil passes under the track (the 0.25 m circle's inner track turns by 7.5 rad;
    first-order upwinding smears it by a few per cent)."""
    omega, ys, us, j, _ = steady_turn(v, radius, vy, ratio_outer, ratio_inner)
    faces = L / 2 - DX * np.arange(N + 1)
    checked = 0
    for i in range(2):
        if omega * L / us[i] > 2.0:
            continue
        jx, jy = steady_shear_displacement(faces, v, vy, omega, ys[i], us[i], L)
        error = np.hypot(j[0, i] - jx, j[1, i] - jy).max() / np.hypot(jx, jy).max()
        assert error < 0.01
        checked += 1
    assert checked >= 1


def test_mirrored_turns_give_mirrored_forces():
    """A right turn is a left turn seen in a mirror (y -> -y): equal thrusts and opposite
    lateral forces and turning moments, track for track."""
    v, omega, half = 0.1, 0.4, 0.205
    us = [0.16, 0.07]
    left = _steady(v, 0.0, omega, [-half, half], us, t_end=4.0)
    right = _steady(v, 0.0, -omega, [half, -half], us, t_end=4.0)
    np.testing.assert_allclose(right[0], left[0], rtol=1e-9)
    np.testing.assert_allclose(right[1], -left[1], rtol=1e-9)
    np.testing.assert_allclose(right[2], -left[2], rtol=1e-9)
    assert np.abs(left[1]).min() > 1.0


def test_sliding_steadily_the_direction_state_settles_at_e_max_along_the_sliding():
    """The brush state's fixed point of de/dt = v_j - |v_j| e/e_max is e = e_max v_j/|v_j|:
    the stress points against the sliding, and a new sliding direction takes over within a
    few e_max of sliding."""
    j, e = np.zeros((2, 1, N + 1)), np.zeros((2, 1, N))
    v = np.stack((np.full((1, N), 0.03), np.full((1, N), -0.04)))  # 5 cm/s, belt at rest
    for _ in range(240):  # 5 cm of sliding: 50 e_max
        advance_shear(j, e, v, np.zeros(1), 0.0, DX, DT, E_MAX)
    np.testing.assert_allclose(e[:, 0], E_MAX * v[:, 0] / 0.05, rtol=1e-9)
    v[0] *= -1.0  # the sliding turns by 106 degrees
    for _ in range(12):  # 2.5 mm of sliding
        advance_shear(j, e, v, np.zeros(1), 0.0, DX, DT, E_MAX)
    assert (e[0] < 0.0).all()


def test_the_stress_opposes_the_sliding_velocity_and_at_rest_the_displacement():
    dx, dy = shear_direction(np.array([0.1, 0.0]), np.array([0.0, 0.0]),
                             np.array([-1.0, 0.002]), np.array([0.0, 0.0]))
    assert dx[0] == pytest.approx(1.0) and dx[1] == pytest.approx(1.0)
    assert dy[0] == dy[1] == 0.0


def test_the_cell_stiffness_is_the_derivative_of_the_janosi_stress():
    """k = b dx d tau/d|j| against a central difference of the cell force along the stress."""
    j_abs = np.array([[1e-4], [5e-3], [0.02], [0.1]])  # four one-cell tracks
    pressure = np.array([[500.0], [2000.0], [2800.0], [6000.0]])

    def force(jx):
        j = np.zeros((2, 4, 2))
        j[0] = jx  # both faces: the cell's j is jx
        e = np.zeros((2, 4, 1))
        e[0] = -1.0  # the stress pushes +x
        b, c, tan_phi, k = soil(4)
        return cell_forces(j, e, pressure, b, DX, c, tan_phi, k)

    (fx, fy), k = force(j_abs)
    h = 1e-7
    (fx_hi, _), _ = force(j_abs + h)
    (fx_lo, _), _ = force(j_abs - h)
    np.testing.assert_allclose(k, (fx_hi - fx_lo) / (2 * h), rtol=1e-5)
    np.testing.assert_allclose(fx, B_W * DX * (C + pressure * TAN_PHI) * (1 - np.exp(-j_abs / K)),
                               rtol=1e-12)
    assert not fy.any()


def test_the_soil_dampers_vanish_in_steady_motion_and_only_dissipate():
    rng = np.random.default_rng(3)
    f_shear = rng.normal(size=(2, 2, N)) * 5.0
    k = rng.uniform(0.0, 2e4, size=(2, N))
    dj = rng.normal(size=(2, 2, N)) * 1e-5
    m = 0.8
    args = (E_MAX, 1.0, m, DT)
    assert not soil_damper_forces(np.zeros_like(dj), f_shear, k, *args).any()
    f = soil_damper_forces(dj, f_shear, k, *args)
    assert ((f * dj).sum(axis=0) < 0.0).all()  # every cell's damper takes energy out
    # Along the stress: critical damping 2 sqrt(k m) of the Janosi spring, per unit time.
    n_hat = -f_shear / np.hypot(f_shear[0], f_shear[1])
    along = soil_damper_forces(n_hat * 1e-6, f_shear, k, *args)
    c = np.minimum(2.0 * np.sqrt(k * m), 0.5 * m / DT)
    np.testing.assert_allclose(along, -c / DT * n_hat * 1e-6, rtol=1e-9)
    assert (c == 0.5 * m / DT).any() and (c < 0.5 * m / DT).any()  # both sides of the cap


def test_lateral_force_saturates_at_mohr_coulomb_plus_bulldozing():
    gamma, z = 14.0e3, 0.004
    j, e = np.zeros((2, 1, N + 1)), np.zeros((2, 1, N))
    walls = np.zeros((2, 2, 1, N))
    vc = np.stack((np.zeros((1, N)), np.full((1, N), -0.02)))
    for _ in range(int(10.0 / DT)):
        advance_shear(j, e, vc, np.zeros(1), 0.0, DX, DT, E_MAX)
        advance_wall(walls, vc[1], np.zeros(1), np.full((1, N), z), DX, DT)
    b, c, tan_phi, k = soil(1)
    (_, fy), _ = cell_forces(j, e, np.full((1, N), P), b, DX, c, tan_phi, k)
    wall = wall_force_n_per_m(walls, np.full((1, N), z), gamma, *per_track(1, C, PHI), 0.1) * DX
    mohr_coulomb = B_W * L * (C + P * TAN_PHI)
    assert fy.sum() == pytest.approx(mohr_coulomb, rel=1e-3)
    # The berm is the swept volume z |d| as a ridge at the angle of repose.
    d, berm = walls
    assert berm[1, 0, 0] == pytest.approx(z * 0.2, rel=1e-6)  # right side, pushed into
    assert berm[0].max() == 0.0 and d[0].max() == 0.0  # the left wall moved away
    h = z + float(berm_height_m(z * 0.2, PHI))
    thrust = passive_pressure_n_per_m(h, gamma, C, passive_coefficient(PHI))
    assert wall.sum() == pytest.approx(L * thrust, rel=1e-3)
    assert wall.sum() > 0.0  # pushing -y, the soil pushes back +y


def test_the_berm_makes_the_side_force_grow_with_lateral_displacement():
    z, gamma = 0.004, 14.0e3
    forces = []
    for t_end in (0.25, 1.0, 3.0):
        walls = np.zeros((2, 2, 1, N))
        for _ in range(int(t_end * 240)):
            advance_wall(walls, np.full((1, N), 0.02), np.zeros(1), np.full((1, N), z), DX, DT)
        forces.append(-wall_force_n_per_m(walls, np.full((1, N), z), gamma,
                                          *per_track(1, 0.0, PHI), 0.1).sum())
    assert forces[0] < forces[1] < forces[2]


def test_in_a_pivot_turn_the_walls_resist_the_turn_and_add_no_net_side_force():
    """Front half sliding left, rear half right (a counter-clockwise pivot): the
    front pushes the left soil, the rear the right soil: equal and opposite forces, a moment
    against the turn."""
    z, omega = 0.004, 0.2
    walls = np.zeros((2, 2, 1, N))
    vy = (omega * X_CELL)[None, :]
    for _ in range(240):
        advance_wall(walls, vy, np.zeros(1), np.full((1, N), z), DX, DT)
    f = wall_force_n_per_m(walls, np.full((1, N), z), 14e3, *per_track(1, 0.0, PHI), 0.1)[0] * DX
    assert abs(f.sum()) < 1e-9 * np.abs(f).sum()
    assert (X_CELL * f).sum() < 0.0  # resists the counter-clockwise turn
    assert (f[X_CELL > 0] < 0).all() and (f[X_CELL < 0] > 0).all()


@pytest.mark.parametrize("speed", [0.2, -0.2], ids=["ahead", "reversing"])
def test_driving_on_the_walls_and_berms_leave_with_the_ground(speed):
    """Pushed sideways at rest (uniformly along the track), then driven straight: the loaded
    soil leaves past the rear end (the front end reversing) at the ground speed, so after a
    travel s the walls keep the share 1 - s/L of it, and nothing after two contact lengths
    (first-order upwinding smears the front of the fresh soil over about one)."""
    z = 0.004
    start = np.zeros((2, 2, 1, N))
    advance_wall(start, np.full((1, N), -0.02), np.zeros(1), np.full((1, N), z), DX, 0.5)
    assert start[:, 1].min() > 0.0 and not start[:, 0].any()  # the right side, pushed into
    for travel, kept in ((0.25 * L, 0.75), (0.5 * L, 0.5), (2.0 * L, 0.0)):
        walls = start.copy()
        for _ in range(round(travel / abs(speed) / DT)):
            advance_wall(walls, np.zeros((1, N)), np.array([speed]), np.full((1, N), z), DX, DT)
        share = walls[:, 1].sum(axis=-1) / start[:, 1].sum(axis=-1)
        np.testing.assert_allclose(share, kept, atol=1e-3)
        if kept == 0.5:  # fresh soil has come in at the entry end
            entry = walls[:, 1, :, : N // 4] if speed > 0 else walls[:, 1, :, -(N // 4):]
            assert entry.sum() < 0.02 * walls[:, 1].sum()


def test_passive_pressure_is_rankine():
    n_phi = math.tan(math.radians(45 + 15)) ** 2
    assert passive_coefficient(math.radians(30)) == pytest.approx(n_phi, rel=1e-12)
    assert passive_pressure_n_per_m(0.1, 15e3, 500.0, n_phi) == pytest.approx(
        0.5 * 15e3 * 0.01 * n_phi + 2 * 500 * 0.1 * math.sqrt(n_phi))


def test_slip_sinkage_is_lyaskos():
    assert slip_sinkage_factor(0.0) == 1.0
    assert slip_sinkage_factor(-0.5) == 1.0  # skidding does not dig in
    assert slip_sinkage_factor(0.5) == pytest.approx(1.5 / 0.75)
    assert slip_sinkage_factor(1.0) == pytest.approx(4.0)


def test_compaction_resistance_is_a_rut_state_not_a_speed_ramp():
    # Advancing into new soil at 1 cm/s or 1 m/s: the same resistance.
    assert rut_resistance_n(10.0, 0.5, 0.4, 0.0, 0.01, 1e-3)[0] == -10.0
    assert rut_resistance_n(10.0, 0.5, 0.4, 0.0, 1.0, 1e-3)[0] == -10.0
    # Inside its own rut (backed up then forward again): none.
    assert rut_resistance_n(10.0, 0.3, 0.4, 0.0, 0.01, 1e-3)[0] == 0.0
    # Reversing out of the rear of the rut cuts new soil.
    f, front, rear = rut_resistance_n(10.0, -0.01, 0.4, 0.0, -0.05, 1e-3)
    assert f == 10.0 and rear == -0.01 and front == 0.4


def test_the_rut_resistance_never_does_positive_work():
    """Random back-and-forth travel: the force never points along the motion, and over the
    whole walk the resistance took R_c per metre of new soil cut."""
    rng = np.random.default_rng(7)
    r_c, dt, v_reg = 10.0, DT, 1e-3
    travel, front, rear, work, speeds = 0.0, 0.0, 0.0, 0.0, []
    speed = 0.0
    for _ in range(20000):
        speed = 0.98 * speed + rng.normal(0.0, 0.01)
        speeds.append(speed)
        travel += speed * dt
        f, front, rear = rut_resistance_n(r_c, travel, front, rear, speed, v_reg)
        assert f * speed <= 0.0
        work += f * speed * dt
    assert max(speeds) > 0.05 and min(speeds) < -0.05  # it went both ways
    assert work < 0.0
    # what it took is R_c per metre of new soil cut (to the step's overshoot into new soil)
    assert -work == pytest.approx(r_c * (front - rear), rel=0.02)


def test_road_wheel_loads_spread_over_the_cells_conserve_the_load():
    xw = np.array([-0.192, -0.096, 0.0, 0.096, 0.192])
    m = load_spread_matrix(xw, X_CELL)
    w = np.array([10.0, 20.0, 30.0, 40.0, 50.0])
    q = m @ w
    assert q.sum() == pytest.approx(w.sum())
    assert q[0] > q[-1]  # the front (x > 0) carries the heavier load
