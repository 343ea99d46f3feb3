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
TILT_PSD = 1e-4  # [rad²/s] the filter's default pitch and roll spectral density


def state(seed: int = 0, n: int = lm.N_SLIP, v: float = 1.2) -> np.ndarray:
    """A generic state of any layout (9, 13 or 15 entries, plus k_β) with every entry
    non-zero."""
    rng = np.random.default_rng(seed)
    x = np.array([3.0, -2.0, 0.7, v, 0.3, 0.4, -0.2, 0.05, -0.03,
                  0.283, 0.287, 2500.0, 2200.0, 7.0, 9.0])[:lm.soil_size(n)]
    x[:9] += rng.normal(0.0, 0.05, 9)
    if lm.lateral_index(n) >= 0:
        x = np.append(x, 2.5)  # k_β [rad/g]
    return x


LAYOUTS = [lm.N_BASE, lm.N_BASE + 1, lm.N_SLIP, lm.N_SLIP + 1, lm.N_OKELLO, lm.N_OKELLO + 1]


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
@pytest.mark.parametrize("n", LAYOUTS)
def test_process_jacobian(seed: int, n: int) -> None:
    x = state(seed, n)
    for tau in (TAU, 0.013, 0.4):
        assert_jacobian(lm.process_F(x, tau, TILT_PSD),
                        lambda s, t=tau: lm.process_fx(s, t, TILT_PSD), x)


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


def test_process_noise_chains_are_the_jerk_blocks() -> None:
    """Q's (θ, Ω, Ω̇) chain is the white-jerk block of the yaw density; its (s, v, v̇) chain is
    that of the forward density, with the distance s laid along the mean heading u in (x, y)
    (Lindgren Eq. 7)."""
    x = state(2, lm.N_OKELLO + 1)
    tau, q_v, q_w = 0.07, 0.5, 0.2
    Q = lm.process_Q(x, tau, q_v, q_w, 1e-4, 1e-6, 1e-4, 0.3, 0.02)
    yaw = [lm.ITH, lm.IOM, lm.IOMD]
    np.testing.assert_allclose(Q[np.ix_(yaw, yaw)], Q_continuous_white_noise(3, tau, q_w),
                               rtol=1e-12, atol=0.0)
    qv = Q_continuous_white_noise(3, tau, q_v)
    th_mid = x[lm.ITH] + 0.5 * tau * (x[lm.IOM] + 0.5 * tau * x[lm.IOMD])
    u = np.array([math.cos(th_mid), math.sin(th_mid)])
    speed = [lm.IV, lm.IVD]
    np.testing.assert_allclose(Q[np.ix_(speed, speed)], qv[1:, 1:], rtol=1e-12, atol=0.0)
    np.testing.assert_allclose(Q[:2, :2], qv[0, 0] * np.outer(u, u), rtol=1e-12, atol=1e-30)
    np.testing.assert_allclose(Q[:2, speed], np.outer(u, qv[0, 1:]), rtol=1e-12, atol=1e-30)
    np.testing.assert_array_equal(Q, Q.T)
    chains = [0, 1, *yaw, *speed]
    rest = np.ones_like(Q, dtype=bool)
    rest[np.ix_(chains, chains)] = False
    np.testing.assert_array_equal(Q[rest & ~np.eye(len(x), dtype=bool)], 0.0)


@pytest.mark.parametrize("n", LAYOUTS)
def test_models_written_into_a_used_array_equal_the_allocating_ones(n: int) -> None:
    """The filter's ``_into`` models write into a workspace that still holds the last frame's
    numbers: each must set every entry of its output, the Jacobians' zeros included, to what
    the allocating function returns."""
    x = state(3, n)
    T = np.array([150.0, -60.0])
    soil = (OracleSoil((0.283, 0.287), (2500.0, 2200.0)).as_array()
            if lm.soil_size(n) == lm.N_BASE else lo.NO_SOIL)
    beacon = np.array([14.0, 9.0])
    odo, slip = (TAU, 0.275, W, CPR), (TAU, T, W, CPR, soil)
    cases = [
        (lm.process_fx(x, TAU, TILT_PSD), lambda o: lm.process_fx_into(x, TAU, TILT_PSD, o)),
        (lo.ins_hx(x), lambda o: lo.ins_hx_into(x, o)),
        (lo.ins_H(x), lambda o: lo.ins_H_into(x, o)),
        (lo.tilt_hx(x), lambda o: lo.tilt_hx_into(x, o)),
        (lo.tilt_H(x), lambda o: lo.tilt_H_into(x, o)),
        (lo.odo_hx(x, *odo), lambda o: lo.odo_hx_into(x, *odo, o)),
        (lo.odo_H(x, *odo), lambda o: lo.odo_H_into(x, *odo, o)),
        (lo.odo_slip_hx(x, *slip), lambda o: lo.odo_slip_hx_into(x, *slip, o)),
        (lo.odo_slip_H(x, *slip), lambda o: lo.odo_slip_H_into(x, *slip, o)),
        (lo.bearing_H(x, beacon), lambda o: lo.bearing_H_into(x, beacon, o)),
    ]
    for expected, write_into in cases:
        out = np.full(expected.shape, np.nan)
        write_into(out)
        assert np.all(np.isfinite(out))
        np.testing.assert_array_equal(out, expected)
    s = lo.slip_model(x, TAU, T, W, soil)
    for i in range(2):
        assert lo.wheel_slip_model(x, TAU, T, W, soil, i) == (s[0][i], s[1][i], s[2][i])
    beacons = np.array([[14.0, 9.0], [-3.0, 5.0]])
    assert [lo.bearing_to(x, *b) for b in beacons] == list(lo.bearing_hx(x, beacons))


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
        x = lm.process_fx(x, tau, TILT_PSD)
    assert math.hypot(x[lm.IX], x[lm.IY]) < 1e-3
    assert x[lm.ITH] == pytest.approx(2.0 * math.pi, abs=1e-12)


def test_tilt_follows_a_fixed_plane_while_yawing() -> None:
    """On a plane rising along world x with gradient 0.1, nose-up pitch is 0.1 cos θ and
    right-side-up roll 0.1 sin θ at any heading θ (without reversion to level: q = 0)."""
    x = np.zeros(lm.N_BASE)
    x[lm.IOM] = 0.5
    x[lm.IA1] = 0.1
    for _ in range(70):
        x = lm.process_fx(x, 0.1, 0.0)
    th = x[lm.ITH]
    np.testing.assert_allclose(x[[lm.IA1, lm.IA2]], [0.1 * math.cos(th), 0.1 * math.sin(th)],
                               atol=1e-12)


def test_tilt_reverts_to_level_within_the_field_slope_prior() -> None:
    """Pitch and roll are a Gauss-Markov process: a tilt decays as exp(-t q / 2σ²) (σ the
    field's slope prior), over a short interval the noise is the random walk's q τ, and the
    covariance propagated without measurements settles at σ² on each axis, while yawing too,
    instead of growing without bound."""
    sigma, q = lm.TILT_SIGMA_RAD, TILT_PSD
    x = np.zeros(lm.N_BASE)
    x[lm.IA1] = 0.1
    for _ in range(1000):  # 50 s straight
        x = lm.process_fx(x, TAU, q)
    assert x[lm.IA1] == pytest.approx(0.1 * math.exp(-50.0 * q / (2.0 * sigma**2)), rel=1e-9)
    assert lm.process_Q(x, TAU, 0.5, 0.5, q)[lm.IA1, lm.IA1] == pytest.approx(q * TAU, rel=2e-3)
    x = np.zeros(lm.N_BASE)
    x[lm.IV], x[lm.IOM] = 0.5, 0.3
    tilt = [lm.IA1, lm.IA2]
    P = np.zeros((2, 2))
    for _ in range(40_000):  # 2000 s, 40 correlation times
        F = lm.process_F(x, TAU, q)[np.ix_(tilt, tilt)]
        P = F @ P @ F.T + lm.process_Q(x, TAU, 0.5, 0.5, q)[np.ix_(tilt, tilt)]
    np.testing.assert_allclose(P, sigma**2 * np.eye(2), rtol=1e-6, atol=1e-12)


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


def test_nearest_beacon_equals_comparing_every_innovation_bit_for_bit() -> None:
    """The association screens beacons by direction cosine before computing innovations: it
    must pick the beacon (lowest index among ties) and return the innovation that comparing
    the exact innovation of every beacon gives, also for beacons in one direction, a
    duplicated beacon, a bearing exactly on a beacon, the vehicle on a beacon and a NaN
    heading."""
    rng = np.random.default_rng(7)
    for trial in range(3000):
        m = int(rng.integers(0, 7))
        beacons = rng.uniform(-20.0, 20.0, (m, 2))
        if m >= 2 and trial % 4 == 0:  # a beacon behind another, or a duplicate
            beacons[1] = beacons[0] * rng.choice([0.5, 1.0, 2.0])
        x = np.zeros(lm.N_BASE)
        x[[lm.IX, lm.IY]] = rng.uniform(-20.0, 20.0, 2)
        x[lm.ITH] = rng.uniform(-math.pi, math.pi)
        if m and trial % 9 == 0:
            x[[lm.IX, lm.IY]] = beacons[-1]
        z = rng.uniform(-math.pi, math.pi)
        if m and trial % 5 == 0:
            z = float(lo.bearing_hx(x, beacons[:1])[0])
        if trial % 31 == 0:
            x[lm.ITH] = math.nan
        best, y_best = 0, math.inf  # the exact innovation of every beacon, in order
        for j in range(m):
            y = lo.bearing_residual(z, lo.bearing_to(x, beacons[j, 0], beacons[j, 1]))
            if abs(y) < abs(y_best):
                best, y_best = j, y
        k, y = lo.nearest_beacon(x, z, beacons)
        assert k == best
        assert np.float64(y).tobytes() == np.float64(y_best).tobytes()


def test_oracle_soil_validation() -> None:
    soil = OracleSoil([0.283, 0.287], [2500, 2200])
    assert soil.wheel_radius_m == (0.283, 0.287)
    np.testing.assert_array_equal(soil.as_array(), [0.283, 0.287, 2500.0, 2200.0])
    with pytest.raises(ValueError, match="k_s"):
        OracleSoil((0.283, 0.287), (2500.0, -1.0))
    with pytest.raises(ValueError, match="wheel_radius_m"):
        OracleSoil((0.283,), (2500.0, 2200.0))


# ---------------------------------------------------------------------------------------------
# Lateral slip gain (any layout) and Okello's curve (scheme 5)
# ---------------------------------------------------------------------------------------------
def test_state_layouts_are_named_and_decoded() -> None:
    assert [len(lm.state_names(n)) for n in LAYOUTS] == LAYOUTS
    assert lm.state_names(lm.N_SLIP + 1)[-1] == "k_beta"
    assert lm.state_names(lm.N_OKELLO)[lm.IBL:] == ("b_l", "b_r")
    assert [lm.lateral_index(n) for n in LAYOUTS] == [-1, 9, -1, 13, -1, 15]
    with pytest.raises(ValueError, match="11 entries"):
        lm.state_names(11)


@pytest.mark.parametrize("n", [lm.N_BASE + 1, lm.N_SLIP + 1, lm.N_OKELLO + 1])
def test_lateral_slip_leans_the_velocity_by_the_slip_angle(n: int) -> None:
    """On a steady turn the position moves at β = atan(k_β a_y) off the heading, with
    a_y = v Ω / g - α2 the lateral specific force (Eq. 14), and at the forward speed v / cos β
    (v is the body-x speed the odometers see); k_β = 0 is the paper's model exactly."""
    x = state(0, n)
    x[[lm.IVD, lm.IOMD]] = 0.0
    tau = 1e-4  # short enough that the heading does not turn
    step = lm.process_fx(x, tau, TILT_PSD)[:2] - x[:2]
    a_y = x[lm.IV] * x[lm.IOM] / lm.G_MPS2 - x[lm.IA2]
    beta = math.atan(x[-1] * a_y)
    direction = math.atan2(step[1], step[0]) - (x[lm.ITH] + 0.5 * tau * x[lm.IOM])
    assert direction == pytest.approx(beta, rel=1e-9)
    assert math.hypot(*step) == pytest.approx(tau * x[lm.IV] / math.cos(beta), rel=1e-9)
    x[-1] = 0.0
    np.testing.assert_array_equal(lm.process_fx(x, 0.3, TILT_PSD)[:-1],
                                  lm.process_fx(x[:-1], 0.3, TILT_PSD))


def test_lateral_slip_gain_grows_with_distance_only() -> None:
    x = state(0, lm.N_SLIP + 1)
    Q = lm.process_Q(x, TAU, 0.5, 0.5, 1e-4, 1e-6, 1e-4, 1e-2, 1e-3)
    d = abs(x[lm.IV] + 0.5 * TAU * x[lm.IVD]) * TAU
    assert Q[-1, -1] == pytest.approx(1e-3 * d, rel=1e-12)
    assert not Q[-1, :-1].any()
    x[[lm.IV, lm.IVD]] = 0.0
    assert lm.process_Q(x, TAU, 0.5, 0.5, 1e-4, 1e-6, 1e-4, 1e-2, 1e-3)[-1, -1] == 0.0


def test_okello_curve_is_the_papers_and_terramechanics_one() -> None:
    """g(x) = 1 - (1 - e^{-x}) / x (Lindgren Eq. 18), the simulation's Okello curve with
    A = B = 1, through its series below 0.1 and its closed form above; g' against finite
    differences on both sides of the switch."""
    from slipenv.terramechanics.janosi import okello_traction

    xs = np.concatenate([np.linspace(1e-6, 0.2, 41), np.linspace(0.2, 40.0, 60)])
    g = np.array([lo.okello_g(v) for v in xs])
    np.testing.assert_allclose(g, okello_traction(xs, 1.0, 1.0), rtol=1e-9)
    for v in (-3.0, -0.1 - 1e-9, -0.05, 1e-4, 0.0999999, 0.1000001, 2.0, 15.0):
        h = 1e-6
        fd = (lo.okello_g(v + h) - lo.okello_g(v - h)) / (2 * h)
        assert lo.okello_dg(v) == pytest.approx(fd, rel=1e-7)
    assert lo.okello_g(0.0) == 0.0 and lo.okello_dg(0.0) == 0.5  # Lindgren Eq. 23


@pytest.mark.parametrize("u", [-4.0, -0.3, -1e-3 - 1e-12, -2e-4, 0.0, 3e-4, 1e-3 + 1e-12, 0.2,
                               0.5, 0.8, 0.99])
def test_okello_inverse_and_slip_factor(u: float) -> None:
    """g(g⁻¹(u)) = u to rounding; φ = g⁻¹(u) / (2u) with φ(0) = 1 (the linear law) and φ'
    against finite differences, across the series/Newton switch at |u| = 1e-3."""
    x = lo.okello_inverse(u)
    assert lo.okello_g(x) == pytest.approx(u, abs=1e-14)
    phi, dphi = lo.okello_slip_factor(u)
    assert phi == pytest.approx(x / (2 * u) if u else 1.0, rel=1e-10)
    h = 1e-7
    fd = (lo.okello_slip_factor(u + h)[0] - lo.okello_slip_factor(u - h)[0]) / (2 * h)
    assert dphi == pytest.approx(fd, rel=1e-5)


def okello_state(b: float, n: int = lm.N_OKELLO) -> np.ndarray:
    x = state(0, n)
    x[lm.IBL:lm.IBR + 1] = b
    return x


@pytest.mark.parametrize("torque", [(420.0, 150.0), (-300.0, 60.0)])
@pytest.mark.parametrize("v", [1.2, -0.8])
def test_okello_slip_is_the_inverse_of_the_curve(torque: tuple[float, float], v: float) -> None:
    """The slip the 15-state model assigns to a torque puts that torque on Okello's curve,
    T = T_max g(s / B) with B = 1/b and T_max = 2 B k_s (Lindgren Eq. 20, 24), odd in s."""
    from slipenv.terramechanics.janosi import okello_traction

    x = okello_state(b=7.0)
    T = np.array(torque)
    s = lo.wheel_slip(x, TAU, T, W, lo.NO_SOIL)
    sigma = np.sign(lo.wheel_speeds(x, TAU, W))
    B = 1.0 / x[lm.IBL:lm.IBR + 1]
    t_max = 2.0 * B * x[lm.IKL:lm.IKR + 1]
    np.testing.assert_allclose(okello_traction(s, t_max, B), sigma * T, rtol=1e-10)
    linear = sigma * T / x[lm.IKL:lm.IKR + 1]
    assert np.all(np.abs(s) > np.abs(linear))  # the curve bends: more slip than the line


@pytest.mark.parametrize("b", [0.0, 1e-9])
def test_okello_model_limit_is_the_linear_law(b: float) -> None:
    """b = 1/B → 0 (T_max → ∞ at fixed k_s): counts and Jacobian are Eq. 37 and Eq. 38-41 of
    the linear law, the closed form z = (τ / Γ) v_w k_s / (R_w (k_s - σ T))."""
    x15 = okello_state(b)
    x13 = x15[:lm.N_SLIP].copy()
    T = np.array([300.0, -120.0])
    z = lo.odo_slip_hx(x15, TAU, T, W, CPR, lo.NO_SOIL)
    v_w = lo.wheel_speeds(x13, TAU, W)
    sigma = np.sign(v_w)
    k_s, r_w = x13[lm.IKL:lm.IKR + 1], x13[lm.IRL:lm.IRR + 1]
    closed = TAU * CPR * v_w * k_s / (r_w * (k_s - sigma * T))
    np.testing.assert_allclose(z, closed, rtol=1e-7)
    H15 = lo.odo_slip_H(x15, TAU, T, W, CPR, lo.NO_SOIL)
    H13 = lo.odo_slip_H(x13, TAU, T, W, CPR, lo.NO_SOIL)
    np.testing.assert_allclose(H15[:, :lm.N_SLIP], H13, rtol=1e-7, atol=1e-12)


@pytest.mark.parametrize("n", [lm.N_OKELLO, lm.N_OKELLO + 1, lm.N_SLIP + 1])
@pytest.mark.parametrize("torque", [(420.0, 150.0), (-80.0, 40.0)])
@pytest.mark.parametrize("v", [1.2, -0.8])
def test_curved_and_lateral_odometry_jacobians(n: int, torque: tuple[float, float],
                                               v: float) -> None:
    x = state(0, n, v=v)
    T = np.array(torque)
    assert_jacobian(lo.odo_slip_H(x, TAU, T, W, CPR, lo.NO_SOIL),
                    lambda s: lo.odo_slip_hx(s, TAU, T, W, CPR, lo.NO_SOIL), x)
    assert_jacobian(lo.ins_H(x), lo.ins_hx, x)
    beacon = np.array([14.0, 9.0])
    assert_jacobian(lo.bearing_H(x, beacon), lambda s: lo.bearing_hx(s, beacon[None]), x)


def test_okello_slip_past_the_curves_limit_is_infinite() -> None:
    """A torque at or above T_max = 2 k_s / b has no slip on the curve: inf, which the filter
    skips as out of range."""
    x = okello_state(b=7.0)
    t_max = 2.0 * x[lm.IKL] / 7.0
    s = lo.wheel_slip(x, TAU, np.array([1.01 * t_max, 10.0]), W, lo.NO_SOIL)
    assert s[0] == math.inf and 0.0 < s[1] < 0.01
