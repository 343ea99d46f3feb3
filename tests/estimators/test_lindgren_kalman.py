"""The Kalman mathematics of the Lindgren EKF (Lindgren Eq. 6-11): the compiled update against
filterpy's textbook Kalman filter, the whole filter against it on a linear-Gaussian special
case, and what a bearing update must do to P."""

from __future__ import annotations

import math

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter
from scipy import stats

from slipenv.contracts.frame import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren import kernel
from slipenv.estimators.lindgren import models as lm
from slipenv.estimators.lindgren import observations as lo
from slipenv.estimators.lindgren.ekf import LindgrenEKF, LindgrenNoise

GEOM = OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=285.0)
BEACONS = np.array([[10.0, 0.0], [0.0, 10.0], [-10.0, 0.0], [0.0, -10.0]])


def random_spd(rng: np.random.Generator, n: int) -> np.ndarray:
    A = rng.normal(size=(n, n))
    return A @ A.T / n + np.diag(rng.uniform(0.01, 0.1, n))


@pytest.mark.parametrize("nz", [1, 2])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_update_is_the_textbook_kalman_update(nz: int, seed: int) -> None:
    """x + K y and the Joseph form of P (Lindgren Eq. 8-11), as filterpy computes them."""
    rng = np.random.default_rng(seed)
    n = lm.N_SLIP
    x, P = rng.normal(size=n), random_spd(rng, n)
    x[lm.ITH] = 0.1  # inside (-π, π]: the update's wrap leaves it alone
    H = rng.normal(size=(nz, n))
    R = random_spd(rng, nz)
    z = H @ x + rng.normal(size=nz)
    kf = KalmanFilter(dim_x=n, dim_z=nz)
    kf.x, kf.P = x.copy(), P.copy()
    kf.update(z, R=R, H=H)
    S_out = np.empty(nz * nz)
    status = kernel.update(x, P, z - H @ x, H, R, math.inf, -1, S_out)
    assert status == kernel.ACCEPTED
    np.testing.assert_allclose(x, kf.x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(P, kf.P, rtol=1e-10, atol=1e-12)
    np.testing.assert_allclose(S_out.reshape(nz, nz), kf.S, rtol=1e-12)
    np.testing.assert_array_equal(P, P.T)


def test_gated_update_changes_nothing() -> None:
    rng = np.random.default_rng(5)
    n = lm.N_BASE
    x, P = rng.normal(size=n), random_spd(rng, n)
    x0, P0 = x.copy(), P.copy()
    h = np.zeros((1, n))
    h[0, lm.IX] = 1.0
    y = np.array([4.0 * math.sqrt(P[lm.IX, lm.IX] + 0.01)])  # NIS about 16 > 10.8
    status = kernel.update(x, P, y, h, np.array([[0.01]]), 10.8, -1, np.empty(1))
    assert status == kernel.GATED
    np.testing.assert_array_equal(x, x0)
    np.testing.assert_array_equal(P, P0)


def test_filter_equals_a_linear_kalman_filter_on_a_linear_gaussian_case() -> None:
    """Heading, yaw rate and yaw acceleration held at zero with (practically) zero variance make
    the Lindgren process model (Eq. 13) linear in the other states, and the gyro,
    accelerometers (Eq. 14), inclinometer and odometers (Eq. 15-16) linear too: the EKF must
    then be the textbook Kalman filter with F, Q and H of the plain functions, to 1e-10."""
    tiny = 1e-200  # variance of θ, Ω, Ω̇: their Jacobian columns act on nothing
    p = LindgrenNoise(jerk_psd_omega=tiny)
    ekf = LindgrenEKF(GEOM, 3, p)  # no beacon map: bearings never occur
    x0 = np.array([1.0, -2.0, 0.0, 0.8, 0.0, 0.1, 0.0, 0.02, -0.01])
    P0 = np.diag([0.05**2, 0.04**2, tiny, 0.1**2, tiny, 0.2**2, tiny, 0.03**2, 0.02**2])
    counts = np.array([1000.0, 2000.0])
    ekf.reset_state(x0, P0, SensorFrame(0.0, counts.copy(), np.zeros(2)))

    tau, g, cpr = 0.05, lm.G_MPS2, GEOM.counts_per_rad
    kf = KalmanFilter(dim_x=9, dim_z=2)
    kf.x, kf.P = x0.copy(), P0.copy()
    kf.F = lm.process_F(x0, tau, p.tilt_psd)
    kf.Q = lm.process_Q(x0, tau, p.jerk_psd_v, p.jerk_psd_omega, p.tilt_psd)
    H_acc = lo.ins_H(x0)[0:2]
    H_acc[1, lm.IOM] = 0.0  # v Ω / g with Ω ≡ 0
    R_acc = np.diag([p.acc_x_var_g2, p.acc_y_var_g2])
    R_tilt = np.eye(2) * p.tilt_var_rad2
    H_odo = lo.odo_H(x0, tau, GEOM.wheel_radius_m, GEOM.track_width_m, cpr)
    R_odo = np.eye(2) * p.odometer_var_rad2 * cpr**2

    rng = np.random.default_rng(7)
    for k in range(1, 41):
        gz, ax, ay, pitch, roll = rng.normal(0.0, [0.01, 0.3, 0.1, 0.03, 0.03])
        dc = 0.8 * tau * cpr / GEOM.wheel_radius_m + rng.normal(0.0, 2.0, 2)
        counts = counts + dc
        ekf.update(SensorFrame(k * tau, counts.copy(), np.zeros(2), gyro_z_rad_s=gz,
                               acc_x_mps2=ax, acc_y_mps2=ay, pitch_rad=pitch, roll_rad=roll))
        kf.predict()
        kf.update(np.array([gz]), R=np.array([[p.gyro_var_rad2ps2]]),
                  H=lo.ins_H(x0)[2:3])
        kf.update(np.array([ax / g, ay / g]), R=R_acc, H=H_acc)
        kf.update(np.array([-pitch, -roll]), R=R_tilt, H=lo.tilt_H(x0))
        kf.update(dc, R=R_odo, H=H_odo)
    assert ekf.skipped == {}
    np.testing.assert_allclose(ekf.x, kf.x, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(ekf.P, kf.P, rtol=1e-10, atol=1e-10 * np.abs(kf.P).max())


def test_bearing_update_reduces_the_trace_of_P_by_the_kalman_amount() -> None:
    """One bearing (Lindgren Eq. 17) removes ``|P h|² / (h' P h + r)`` from trace P, and no
    variance grows: P_pred - P_post is positive semi-definite (rank one)."""
    frame0 = SensorFrame(0.0, np.zeros(2), np.zeros(2))
    pred, upd = (LindgrenEKF(GEOM, 1, beacons_xy=BEACONS) for _ in range(2))
    for f in (pred, upd):
        f.reset(1.0, 2.0, 0.3, frame0)
    t = 0.05
    pred.predict_to(t)
    h = lo.bearing_H(pred.x, BEACONS[1])[0]  # beacon (0, 10): bearing about π/2 - 0.3 - 0.1
    z = float(lo.bearing_hx(pred.x, BEACONS[1:2])[0]) + 0.004
    upd.update(SensorFrame(t, np.zeros(2), np.zeros(2), beacon_bearings_rad=np.array([z]),
                           beacon_times_s=np.array([t])))
    assert len(upd.history["bearing"]) == 1
    r = upd.params.bearing_var_rad2
    Ph = pred.P @ h
    expected = Ph @ Ph / (h @ Ph + r)
    drop = np.trace(pred.P) - np.trace(upd.P)
    assert drop > 0.0
    assert drop == pytest.approx(expected, rel=1e-9)
    eig = np.linalg.eigvalsh(pred.P - upd.P)
    assert eig.min() > -1e-12 * eig.max()
    assert np.sum(eig > 1e-9 * eig.max()) == 1


def test_mills_ratio_is_the_normal_pdf_over_its_tail() -> None:
    for alpha in (0.0, 1.0, 4.9, 5.1, 12.0, 35.0):
        expected = stats.norm.pdf(alpha) / stats.norm.sf(alpha)
        assert kernel.mills_lambda(alpha) == pytest.approx(expected, rel=1e-10)


@pytest.mark.parametrize("b", [-0.5, -20.0])
def test_clamp_moves_b_to_zero_and_keeps_its_mean_square_error(b: float) -> None:
    """Imposing b >= 0 on N(x, P) with b < 0: b goes to 0, every other state to its
    conditional mean given b = 0 (filterpy's update with a noise-free measurement of b), and
    P_bb to the mean square of the truncated density about 0 (scipy's truncnorm); the rest
    of P shrinks along the regression on b; b >= 0 leaves everything as it is."""
    rng = np.random.default_rng(3)
    n = lm.N_OKELLO
    x, P = rng.normal(size=n), random_spd(rng, n)
    x[lm.ITH] = 0.1
    x[lm.IRL:lm.IKR + 1] = (0.28, 0.29, 2000.0, 2100.0)
    x[lm.IBL], x[lm.IBR] = b, 2.0  # left violates b >= 0, right does not
    P0 = P.copy()
    kf = KalmanFilter(dim_x=n, dim_z=1)
    kf.x, kf.P = x.copy(), P.copy()
    H = np.zeros((1, n))
    H[0, lm.IBL] = 1.0
    kf.update(np.zeros(1), R=np.array([[1e-14]]), H=H)
    kernel.clamp_nonnegative(x, P, lm.IBL)
    assert x[lm.IBL] == 0.0
    expected_x = kf.x.copy()
    expected_x[lm.ITH] = lm.wrap(expected_x[lm.ITH])  # the clamp wraps θ as the updates do
    np.testing.assert_allclose(x, expected_x, rtol=1e-9, atol=1e-9)
    sd = math.sqrt(P0[lm.IBL, lm.IBL])
    m2 = stats.truncnorm(-b / sd, math.inf, loc=b, scale=sd).moment(2)
    assert P[lm.IBL, lm.IBL] == pytest.approx(m2, rel=1e-8)
    col = P0[:, lm.IBL]
    expected = P0 - np.outer(col, col) * (1.0 - m2 / sd**2) / sd**2
    np.testing.assert_allclose(P, expected, rtol=1e-9, atol=1e-12)
    np.testing.assert_array_equal(P, P.T)
    assert np.all(np.linalg.eigvalsh(P) > 0.0)
    x2, P2 = x.copy(), P.copy()
    x2[lm.IBL] = 0.0
    kernel.constrain_shape(x2, P2)  # b >= 0 everywhere: nothing changes
    np.testing.assert_array_equal(x2, x)
    np.testing.assert_array_equal(P2, P)


def test_prediction_in_a_used_workspace_is_F_P_Ft_plus_Q() -> None:
    """The filter's prediction reuses one workspace frame after frame: whatever an earlier call
    left in it, x becomes f(x) and P becomes F P F' + Q (Lindgren Eq. 6-7)."""
    rng = np.random.default_rng(5)
    n = lm.N_OKELLO + 1
    x = rng.normal(size=n)
    x[lm.IRL:lm.IRR + 1], x[lm.IKL:lm.IKR + 1] = 0.28, 900.0
    P = random_spd(rng, n)
    cfg = rng.uniform(1e-4, 1e-2, kernel.N_CFG)
    work = np.full(kernel.work_size(n), 1e300)
    iwork = rng.integers(-5, 5, kernel.iwork_size(n))
    tau = 0.05
    F = lm.process_F(x, tau, cfg[kernel.C_TILT_PSD])
    Q = lm.process_Q(x, tau, *cfg[[kernel.C_JERK_V, kernel.C_JERK_W, kernel.C_TILT_PSD,
                                  kernel.C_RADIUS_VAR, kernel.C_KS_VAR, kernel.C_B_VAR,
                                  kernel.C_KBETA_VAR]])
    x_expected, P_expected = lm.process_fx(x, tau, cfg[kernel.C_TILT_PSD]), F @ P @ F.T + Q
    x_expected[lm.ITH] = lm.wrap(x_expected[lm.ITH])
    for _ in range(2):  # the second call finds the first one's temporaries
        xk, Pk = x.copy(), P.copy()
        kernel.predict_into(xk, Pk, tau, cfg, work, iwork)
        np.testing.assert_allclose(xk, x_expected, rtol=1e-13, atol=1e-13)
        np.testing.assert_allclose(Pk, P_expected, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("nz", [1, 2])
def test_update_in_a_used_workspace_is_the_textbook_update(nz: int) -> None:
    rng = np.random.default_rng(nz)
    n = 14
    x, P = rng.normal(size=n), random_spd(rng, n)
    H, R = rng.normal(size=(nz, n)), random_spd(rng, nz)
    y = rng.normal(size=nz)
    S = H @ P @ H.T + R
    K = P @ H.T @ np.linalg.inv(S)
    x_expected, P_expected = x + K @ y, P - K @ S @ K.T
    x_expected[lm.ITH] = lm.wrap(x_expected[lm.ITH])
    work = np.full(kernel.work_size(n), -1e300)
    for _ in range(2):
        xk, Pk = x.copy(), P.copy()
        assert kernel.update_into(xk, Pk, y, H, R, math.inf, -1, np.empty(nz * nz), work,
                                  np.full(2, math.nan), np.zeros(0), 0.5) == kernel.ACCEPTED
        np.testing.assert_allclose(xk, x_expected, rtol=1e-12, atol=1e-12)
        np.testing.assert_allclose(Pk, P_expected, rtol=1e-10, atol=1e-12)
