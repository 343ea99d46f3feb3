"""The track model's plain functions against the closed forms (Wong & Chiang 2001; Okello;
Bekker; Rankine)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terramechanics.janosi import patch_thrust_n
from slipenv.terramechanics.track import (
    advance_shear,
    advance_wall,
    bekker_sinkage_m,
    berm_height_m,
    cell_forces,
    compaction_resistance_n,
    load_spread_matrix,
    passive_pressure_n_per_m,
    rut_resistance_n,
    shear_direction,
    slip_sinkage_factor,
    steady_track_forces,
    wall_force_n_per_m,
)

L, B_W, N = 0.48, 0.11, 16  # Patako's track: contact length, width [m]; cells
C, PHI, K = 1.04e3, math.radians(28.0), 0.025  # Wong's dry sand (LLL), K of loose sand
TAN_PHI = math.tan(PHI)
P = 2800.0  # [Pa] about 30 kg on two 0.48 x 0.11 m tracks
DX = L / N
E_MAX = 1e-3  # [m] the direction state's length (slipenv.sim.track_soil default)
X_CELL = L / 2 - DX * (np.arange(N) + 0.5)


def _steady(vx, vy, omega, ys, us, t_end=8.0, dt=1 / 240):
    """Run the transient scheme at fixed kinematics to steady state; forces per track."""
    n_t = len(ys)
    j, e = np.zeros((2, n_t, N + 1)), np.zeros((2, n_t, N))
    ys_a, us_a = np.asarray(ys, float)[:, None], np.asarray(us, float)
    vc = np.stack((np.broadcast_to(vx - omega * ys_a - us_a[:, None], (n_t, N)),
                   np.broadcast_to(vy + omega * X_CELL, (n_t, N))))
    for _ in range(int(t_end / dt)):
        advance_shear(j, vc, us_a, omega, DX, dt, e, E_MAX)
    fx, fy = cell_forces(j, e, np.full((n_t, N), P), B_W, DX, C, TAN_PHI, K)
    mz = (X_CELL * fy).sum(axis=1) - ys_a[:, 0] * fx.sum(axis=1)
    return fx.sum(axis=1), fy.sum(axis=1), mz, (X_CELL * fy).sum(axis=1)


@pytest.mark.parametrize("slip", [0.02, 0.1, 0.3, 0.7])
def test_straight_driving_follows_the_okello_janosi_curve(slip):
    u = 0.2
    fx, fy, _, _ = _steady(u * (1 - slip), 0.0, 0.0, [0.0], [u])
    w = P * B_W * L
    expected = patch_thrust_n(slip, w, B_W * L, L, C, PHI, K)
    assert fx[0] == pytest.approx(float(expected), rel=0.02)
    assert abs(fy[0]) < 1e-9


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
    assert fx[0] > fx[1] > -1e9


def test_the_stress_opposes_the_sliding_velocity_and_at_rest_the_displacement():
    dx, dy = shear_direction(np.array([0.1, 0.0]), np.array([0.0, 0.0]),
                             np.array([-1.0, 0.002]), np.array([0.0, 0.0]))
    assert dx[0] == pytest.approx(1.0) and dx[1] == pytest.approx(1.0)
    assert dy[0] == dy[1] == 0.0


def test_lateral_force_saturates_at_mohr_coulomb_plus_bulldozing():
    gamma, z = 14.0e3, 0.004
    j, e = np.zeros((2, 1, N + 1)), np.zeros((2, 1, N))
    d, berm = np.zeros((2, 1, N)), np.zeros((2, 1, N))
    vc = np.stack((np.zeros((1, N)), np.full((1, N), -0.02)))
    dt = 1 / 240
    for _ in range(int(10.0 / dt)):
        advance_shear(j, vc, np.zeros(1), 0.0, DX, dt, e, E_MAX)
        advance_wall(d, berm, vc[1], np.zeros(1), np.full((1, N), z), DX, dt)
    _, fy = cell_forces(j, e, np.full((1, N), P), B_W, DX, C, TAN_PHI, K)
    wall = wall_force_n_per_m(d, berm, np.full((1, N), z), gamma, C, PHI, 0.1) * DX
    mohr_coulomb = B_W * L * (C + P * TAN_PHI)
    assert fy.sum() == pytest.approx(mohr_coulomb, rel=1e-3)
    # The berm is the swept volume z |d| as a ridge at the angle of repose.
    assert berm[1, 0, 0] == pytest.approx(z * 0.2, rel=1e-6)  # right side, pushed into
    assert berm[0].max() == 0.0 and d[0].max() == 0.0  # the left wall moved away
    h = z + float(berm_height_m(z * 0.2, PHI))
    assert wall.sum() == pytest.approx(L * passive_pressure_n_per_m(h, gamma, C, PHI), rel=1e-3)
    assert wall.sum() > 0.0  # pushing -y, the soil pushes back +y


def test_the_berm_makes_the_side_force_grow_with_lateral_displacement():
    z, gamma = 0.004, 14.0e3
    forces = []
    for t_end in (0.25, 1.0, 3.0):
        d, berm = np.zeros((2, 1, N)), np.zeros((2, 1, N))
        for _ in range(int(t_end * 240)):
            advance_wall(d, berm, np.full((1, N), 0.02), np.zeros(1), np.full((1, N), z), DX,
                         1 / 240)
        forces.append(-wall_force_n_per_m(d, berm, np.full((1, N), z), gamma, 0.0, PHI,
                                          0.1).sum())
    assert forces[0] < forces[1] < forces[2]


def test_in_a_pivot_turn_the_walls_resist_the_turn_and_add_no_net_side_force():
    """Front half sliding left, rear half right (a counter-clockwise pivot): the
    front pushes the left soil, the rear the right soil: equal and opposite forces, a moment
    against the turn."""
    z, omega = 0.004, 0.2
    d, berm = np.zeros((2, 1, N)), np.zeros((2, 1, N))
    vy = (omega * X_CELL)[None, :]
    for _ in range(240):
        advance_wall(d, berm, vy, np.zeros(1), np.full((1, N), z), DX, 1 / 240)
    f = wall_force_n_per_m(d, berm, np.full((1, N), z), 14e3, 0.0, PHI, 0.1)[0] * DX
    assert abs(f.sum()) < 1e-9 * np.abs(f).sum()
    assert (X_CELL * f).sum() < 0.0  # resists the counter-clockwise turn
    assert (f[X_CELL > 0] < 0).all() and (f[X_CELL < 0] > 0).all()


def test_passive_pressure_is_rankine():
    n_phi = math.tan(math.radians(45 + 15)) ** 2
    assert passive_pressure_n_per_m(0.1, 15e3, 500.0, math.radians(30)) == pytest.approx(
        0.5 * 15e3 * 0.01 * n_phi + 2 * 500 * 0.1 * math.sqrt(n_phi))


def test_sinkage_compaction_and_slip_sinkage_are_bekker_and_lyasko():
    k_c, k_phi, n = 0.99e3, 1528.43e3, 1.1
    z = float(bekker_sinkage_m(P, B_W, k_c, k_phi, n))
    assert (k_c / B_W + k_phi) * z ** n == pytest.approx(P)
    r = float(compaction_resistance_n(z, B_W, k_c, k_phi, n))
    # R_c is the work of pressing the rut, b int_0^z p dz.
    zs = np.linspace(0, z, 20001)
    assert r == pytest.approx(B_W * np.trapezoid((k_c / B_W + k_phi) * zs ** n, zs), rel=1e-6)
    assert slip_sinkage_factor(0.0) == 1.0 and slip_sinkage_factor(1.0) == pytest.approx(4.0)


def test_compaction_resistance_is_a_rut_state_not_a_speed_ramp():
    # Advancing into new soil at 1 cm/s or 1 m/s: the same resistance.
    assert rut_resistance_n(10.0, 0.5, 0.4, 0.0, 0.01, 1e-3)[0] == -10.0
    assert rut_resistance_n(10.0, 0.5, 0.4, 0.0, 1.0, 1e-3)[0] == -10.0
    # Inside its own rut (backed up then forward again): none.
    assert rut_resistance_n(10.0, 0.3, 0.4, 0.0, 0.01, 1e-3)[0] == 0.0
    # Reversing out of the rear of the rut cuts new soil.
    f, front, rear = rut_resistance_n(10.0, -0.01, 0.4, 0.0, -0.05, 1e-3)
    assert f == 10.0 and rear == -0.01 and front == 0.4


def test_road_wheel_loads_spread_over_the_cells_conserve_the_load():
    xw = np.array([-0.192, -0.096, 0.0, 0.096, 0.192])
    m = load_spread_matrix(xw, X_CELL)
    w = np.array([10.0, 20.0, 30.0, 40.0, 50.0])
    q = m @ w
    assert q.sum() == pytest.approx(w.sum())
    assert q[0] > q[-1]  # the front (x > 0) carries the heavier load
