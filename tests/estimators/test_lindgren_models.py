"""Lindgren EKF models: Jacobians against central finite differences, closed forms, the paper's
equations. The functions tested are the compiled ones the filter runs."""

from __future__ import annotations

import math

import numpy as np
import pytest
from filterpy.common import Q_continuous_white_noise

from slipenv.estimators.lindgren import models as lm
from slipenv.estimators.lindgren import observations as lo
from slipenv.estimators.lindgren.models import OracleSoil

W = 1.5  # track width [m] (assumed vehicle)
CPR = 285.0  # counts/rad (Lindgren)
TAU = 0.05  # [s]


def state(seed: int = 0, n: int = lm.N_SLIP, v: float = 1.2) -> np.ndarray:
    """A generic state with every entry non-zero."""
    rng = np.random.default_rng(seed)
    x = np.array([3.0, -2.0, 0.7, v, 0.3, 0.4, -0.2, 0.05, -0.03,
                  0.283, 0.287, 2500.0, 2200.0])[:n]
    x[:9] += rng.normal(0.0, 0.05, 9)
    return x


def fd_jacobian(fun, x: np.ndarray) -> np.ndarray:
    """Central finite differences, step scaled to each entry."""
    cols = []
    for i in range(len(x)):
        h = 1e-6 * max(1.0, abs(x[i]))
        xp, xm = x.copy(), x.copy()
        xp[i] += h
        xm[i] -= h
        cols.append((np.atleast_1d(fun(xp)) - np.atleast_1d(fun(xm))) / (2.0 * h))
    return np.array(cols).T


def assert_jacobian(H: np.ndarray, fun, x: np.ndarray) -> None:
    H_fd = fd_jacobian(fun, x)
    assert H.shape == H_fd.shape
    np.testing.assert_allclose(H, H_fd, rtol=1e-6, atol=1e-7 * max(1.0, np.abs(H).max()))


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("n", [lm.N_BASE, lm.N_SLIP])
def test_process_jacobian(seed: int, n: int) -> None:
    x = state(seed, n)
    for tau in (TAU, 0.013, 0.4):
        assert_jacobian(lm.process_F(x, tau), lambda s, t=tau: lm.process_fx(s, t), x)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_observation_jacobians(seed: int) -> None:
    x = state(seed)
    assert_jacobian(lo.ins_H(x), lo.ins_hx, x)
    assert_jacobian(lo.tilt_H(x), lo.tilt_hx, x)
    args = (TAU, 0.275, W, CPR)
    assert_jacobian(lo.odo_H(x, *args), lambda s: lo.odo_hx(s, *args), x)
    beacon = np.array([14.0, 9.0])
    assert_jacobian(lo.bearing_H(x, beacon), lambda s: lo.bearing_hx(s, beacon[None]), x)


@pytest.mark.parametrize("torque", [(120.0, 300.0), (-80.0, 40.0)])
@pytest.mark.parametrize("v", [1.2, -0.8])
def test_slip_odometry_jacobian_eq38_41(torque: tuple[float, float], v: float) -> None:
    """Eq. 37's Jacobian (Eq. 38-41 plus the mean-speed columns) for drive, brake, reverse."""
    x = state(0, v=v)
    T = np.array(torque)
    assert_jacobian(lo.odo_slip_H(x, TAU, T, W, CPR, lo.NO_SOIL),
                    lambda s: lo.odo_slip_hx(s, TAU, T, W, CPR, lo.NO_SOIL), x)
    soil = OracleSoil((0.283, 0.287), (2500.0, 2200.0)).as_array()
    x9 = x[:lm.N_BASE].copy()
    assert_jacobian(lo.odo_slip_H(x9, TAU, T, W, CPR, soil),
                    lambda s: lo.odo_slip_hx(s, TAU, T, W, CPR, soil), x9)
    np.testing.assert_allclose(lo.odo_slip_hx(x9, TAU, T, W, CPR, soil),
                               lo.odo_slip_hx(x, TAU, T, W, CPR, lo.NO_SOIL), rtol=1e-14)


def test_slip_jacobian_matches_paper_formulas() -> None:
    """At v̇ = Ω̇ = 0 the columns are Lindgren Eq. 38-41 written out literally (Γ = 1/CPR)."""
    x = state(1)
    x[lm.IVD] = x[lm.IOMD] = 0.0
    T = np.array([150.0, 260.0])
    H = lo.odo_slip_H(x, TAU, T, W, CPR, lo.NO_SOIL)
    gamma = 1.0 / CPR
    v, om = x[lm.IV], x[lm.IOM]
    for i, (sign, ir, ik) in enumerate([(-1.0, lm.IRL, lm.IKL), (1.0, lm.IRR, lm.IKR)]):
        r_w, k_s, t = x[ir], x[ik], T[i]
        va = v + sign * W / 2.0 * om  # Eq. 33
        assert H[i, lm.IV] == pytest.approx(TAU * k_s / gamma / (r_w * (k_s - t)), rel=1e-12)
        assert H[i, lm.IOM] == pytest.approx(
            sign * TAU * k_s * W / (2.0 * gamma) / (r_w * (k_s - t)), rel=1e-12)
        assert H[i, ir] == pytest.approx(
            -1.0 / r_w**2 * TAU / gamma * va * k_s / (k_s - t), rel=1e-12)
        assert H[i, ik] == pytest.approx(-TAU * t / (r_w * gamma) * va / (k_s - t) ** 2,
                                         rel=1e-12)
        # Eq. 37 itself
        z = lo.odo_slip_hx(x, TAU, T, W, CPR, lo.NO_SOIL)[i]
        assert z == pytest.approx(TAU / gamma * va * k_s / (r_w * (k_s - t)), rel=1e-12)


def test_slip_model_reduces_to_eq15_without_torque() -> None:
    x = state(2)
    x[lm.IRL:lm.IRR + 1] = 0.275
    np.testing.assert_allclose(lo.odo_slip_hx(x, TAU, np.zeros(2), W, CPR, lo.NO_SOIL),
                               lo.odo_hx(x, TAU, 0.275, W, CPR), rtol=1e-14)


def test_odometry_closed_form() -> None:
    """1 m/s straight for 0.05 s on a 0.275 m wheel at 285 counts/rad: 51.818 counts each;
    a 20 % slip (T = k_s / 5) makes the wheel turn 1/(1 - 0.2) times as far."""
    x = np.zeros(lm.N_SLIP)
    x[lm.IV] = 1.0
    x[lm.IRL:lm.IRR + 1] = 0.275
    x[lm.IKL:] = 1000.0
    np.testing.assert_allclose(lo.odo_hx(x, TAU, 0.275, W, CPR), 0.05 * 285 / 0.275)
    T = np.array([200.0, 200.0])
    np.testing.assert_allclose(lo.odo_slip_hx(x, TAU, T, W, CPR, lo.NO_SOIL),
                               0.05 * 285 / 0.275 / 0.8)
    np.testing.assert_allclose(lo.wheel_slip(x, TAU, np.array([200.0, -100.0]), W, lo.NO_SOIL),
                               [0.2, -0.1])
    x[lm.IV] = -1.0  # reverse driving with driving torque: the wheel still overspins
    np.testing.assert_allclose(lo.odo_slip_hx(x, TAU, -T, W, CPR, lo.NO_SOIL),
                               -0.05 * 285 / 0.275 / 0.8)


def test_odometry_counts_mean_speed_of_interval() -> None:
    """With v̇ the counts follow the interval's mean speed: speeding from 0 to 1 m/s in 1 s."""
    x = np.zeros(lm.N_BASE)
    x[lm.IV], x[lm.IVD] = 1.0, 1.0
    np.testing.assert_allclose(lo.odo_hx(x, 1.0, 0.25, W, CPR), 0.5 / 0.25 * CPR)


def test_jerk_block_is_filterpys_continuous_white_noise() -> None:
    for tau, q in [(0.05, 0.5), (0.013, 2.0), (1.0, 0.1)]:
        np.testing.assert_allclose(lm.jerk_block(tau, q), Q_continuous_white_noise(3, tau, q),
                                   rtol=1e-12, atol=0.0)


def test_process_noise_grows_with_distance_for_soil_states() -> None:
    x = state(0)
    x[lm.IVD] = 0.0
    q1 = lm.process_Q(x, 0.1, 0.5, 0.5, 1e-4, 1e-6, 1e-4)
    x2 = x.copy()
    x2[lm.IV] *= 2.0
    q2 = lm.process_Q(x2, 0.1, 0.5, 0.5, 1e-4, 1e-6, 1e-4)
    soil = [lm.IRL, lm.IRR, lm.IKL, lm.IKR]
    np.testing.assert_allclose(np.diag(q2)[soil], 2.0 * np.diag(q1)[soil], rtol=1e-12)
    assert q1[lm.IRL, lm.IRL] == pytest.approx(1e-6 * abs(x[lm.IV]) * 0.1, rel=1e-12)
    assert q1[lm.IKL, lm.IKL] == pytest.approx(1e-4 * abs(x[lm.IV]) * 0.1 * 2500.0**2,
                                               rel=1e-12)
    x0 = x.copy()
    x0[lm.IV] = 0.0
    assert np.all(np.diag(lm.process_Q(x0, 0.1, 0.5, 0.5, 1e-4, 1e-6, 1e-4))[soil] == 0.0)
    np.testing.assert_array_equal(q1, q1.T)
    eig = np.linalg.eigvalsh(q1)
    assert eig.min() > -1e-14 * eig.max()  # positive semi-definite up to round-off


def test_process_integrates_a_circle() -> None:
    """A 4 m circle at 1 m/s (Lindgren §5) at 20 Hz closes to within 1 mm after one loop."""
    x = np.zeros(lm.N_BASE)
    x[lm.IV], x[lm.IOM] = 1.0, 0.25
    n = int(round(2.0 * math.pi / 0.25 / TAU))
    tau = 2.0 * math.pi / 0.25 / n
    for _ in range(n):
        x = lm.process_fx(x, tau)
    assert math.hypot(x[lm.IX], x[lm.IY]) < 1e-3
    assert x[lm.ITH] == pytest.approx(2.0 * math.pi, abs=1e-12)


def test_tilt_follows_a_fixed_plane_while_yawing() -> None:
    """On a plane rising along world x with gradient 0.1, nose-up pitch is 0.1 cos θ and
    right-side-up roll 0.1 sin θ at any heading θ."""
    x = np.zeros(lm.N_BASE)
    x[lm.IOM] = 0.5
    x[lm.IA1] = 0.1
    for _ in range(70):
        x = lm.process_fx(x, 0.1)
    th = x[lm.ITH]
    np.testing.assert_allclose(x[[lm.IA1, lm.IA2]], [0.1 * math.cos(th), 0.1 * math.sin(th)],
                               atol=1e-12)


def test_inertial_model_eq14() -> None:
    """At rest nose-up on a 0.1 rad slope the forward accelerometer reads 0.1 g; turning at
    1 m/s and 0.5 rad/s the lateral one reads 0.5/g (Eq. 14)."""
    x = np.zeros(lm.N_BASE)
    x[lm.IA1] = 0.1
    np.testing.assert_allclose(lo.ins_hx(x), [0.1, 0.0, 0.0])
    x = np.zeros(lm.N_BASE)
    x[lm.IV], x[lm.IOM], x[lm.IA2] = 1.0, 0.5, 0.02
    np.testing.assert_allclose(lo.ins_hx(x), [0.0, 0.5 / lm.G_MPS2 - 0.02, 0.5])


def test_bearing_model_and_residual() -> None:
    x = np.zeros(lm.N_BASE)
    beacons = np.array([[10.0, 10.0], [-10.0, 0.0]])
    # one angle convention across slipenv: (-π, π], so straight behind is +π
    np.testing.assert_allclose(lo.bearing_hx(x, beacons), [math.pi / 4, math.pi])
    x[lm.ITH] = math.pi / 2
    np.testing.assert_allclose(lo.bearing_hx(x, beacons), [-math.pi / 4, math.pi / 2])
    assert float(lo.bearing_residual(3.1, -3.1)) == pytest.approx(6.2 - 2.0 * math.pi)
    assert float(lo.bearing_residual(-3.1, 3.1)) == pytest.approx(2.0 * math.pi - 6.2)


def test_nearest_beacon_picks_smallest_innovation() -> None:
    x = np.zeros(lm.N_BASE)
    x[lm.ITH] = 0.3
    beacons = np.array([[10.0, 0.0], [10.0, 3.0], [0.0, 10.0], [-8.0, -8.0]])
    for j in range(len(beacons)):
        z = float(lo.bearing_hx(x, beacons[j:j + 1])[0]) + 0.01
        k, y = lo.nearest_beacon(x, z, beacons)
        assert k == j
        assert y == pytest.approx(0.01)


def test_oracle_soil_validation() -> None:
    soil = OracleSoil([0.283, 0.287], [2500, 2200])
    assert soil.wheel_radius_m == (0.283, 0.287)
    np.testing.assert_array_equal(soil.as_array(), [0.283, 0.287, 2500.0, 2200.0])
    with pytest.raises(ValueError, match="k_s"):
        OracleSoil((0.283, 0.287), (2500.0, -1.0))
    with pytest.raises(ValueError, match="wheel_radius_m"):
        OracleSoil((0.283,), (2500.0, 2200.0))
