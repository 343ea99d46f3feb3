"""Endo's slip ratios (Yamauchi Eq. 7-8) and the Endo odometry."""

import math
from dataclasses import replace

import numpy as np
import pytest

from slipenv.contracts import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.skid_steer.endo import (
    EndoOdometry,
    endo_left_share,
    endo_ratio,
    endo_slip_ratios,
    endo_slip_velocities,
)
from slipenv.estimators.skid_steer.kinematics import body_velocity
from tests.estimators import skid_steer_synth as synth

TREAD = synth.TREAD_M
GEOM = OdometryGeometry(0.06, TREAD, 1e9)  # fine encoders: quantisation below 1e-9 rad
run = synth.feed


def constant_run(v_l, v_r, gyro, n=100):
    return synth.constant_frames(v_l, v_r, gyro, n=n, geometry=GEOM)


def test_closed_form_solves_eq7_and_eq8():
    rng = np.random.default_rng(1)
    k = 500
    v_l = rng.choice([-1.0, 1.0], k) * rng.uniform(0.01, 0.3, k)
    v_r = rng.choice([-1.0, 1.0], k) * rng.uniform(0.01, 0.3, k)
    omega = rng.uniform(-1.0, 1.0, k)
    for n in (0.824, 1.3):
        for vl, vr, om in zip(v_l, v_r, omega, strict=True):
            alpha_l, alpha_r = endo_slip_ratios(vl, vr, om, TREAD, n, speed_eps_mps=0.0)
            _, _, omega_back = body_velocity(vl, vr, alpha_l, alpha_r, 0.0, TREAD)
            assert omega_back == pytest.approx(om, rel=0, abs=1e-12)  # Eq. 7
            assert alpha_l / alpha_r == pytest.approx(endo_ratio(vl, vr, n), rel=1e-10)  # Eq. 8


def test_pivot_turn_loses_equal_fractions():
    # Pivot: v_l = -v_r; gyro sees 70 % of the commanded rate -> both tracks slip 30 %.
    v = 0.1
    alpha_l, alpha_r = endo_slip_ratios(-v, v, 0.7 * 2 * v / TREAD, TREAD, 0.824, 0.0)
    assert alpha_l == pytest.approx(0.3) and alpha_r == pytest.approx(0.3)
    est = run(EndoOdometry(GEOM, 0.824), constant_run(-v, v, 0.7 * 2 * v / TREAD))[-1]
    assert math.hypot(est.x_m, est.y_m) < 1e-9 and est.speed_mps == pytest.approx(0.0, abs=1e-9)
    assert est.extras["alpha_l"] == pytest.approx(0.3, abs=1e-4)  # ε-regularised ratio


def test_straight_driving_is_well_conditioned():
    assert endo_left_share(0.1, 0.1, 0.824) == 0.5
    # Gyro noise while driving straight only makes equal and opposite slips, no extra distance.
    rng = np.random.default_rng(2)
    frames = constant_run(0.1, 0.1, 0.0, n=200)
    frames = [replace(f, gyro_z_rad_s=0.003 * rng.standard_normal()) for f in frames]
    endo = run(EndoOdometry(GEOM, 0.824), frames)
    gyro = run(Gyrodometry(GEOM), frames)
    for a, b in zip(endo, gyro, strict=True):
        assert (a.x_m, a.y_m) == (pytest.approx(b.x_m, abs=1e-12), pytest.approx(b.y_m, abs=1e-12))
        assert a.extras["alpha_l"] == pytest.approx(-a.extras["alpha_r"], abs=1e-12)
        assert abs(a.extras["alpha_l"]) < 0.1


def test_standstill_with_gyro_bias_does_not_creep():
    est = run(EndoOdometry(GEOM, 0.824), constant_run(0.0, 0.0, 0.01, n=100))
    assert all(math.isfinite(e.extras["alpha_l"]) for e in est)
    assert est[-1].x_m == 0.0 and est[-1].y_m == 0.0


def test_stopped_track_limit():
    # Exact Eq. 8 with v_l -> 0: all the discrepancy is the moving track's, s_l -> 0.
    s_l, s_r = endo_slip_velocities(0.0, 0.1, 0.1, TREAD, 0.824, speed_eps_mps=0.0)
    assert s_l == 0.0 and s_r == pytest.approx(-(TREAD * 0.1 - 0.1))
    # The regularised share is finite and tends to the exact one as eps -> 0.
    shares = [endo_left_share(0.0, 0.1, 0.824, eps) for eps in (1e-3, 1e-6, 1e-12)]
    assert shares == sorted(shares, reverse=True) and shares[-1] < 0.05
    assert np.isfinite(endo_slip_ratios(0.0, 0.1, 0.1, TREAD, 0.824)).all()
    assert np.isfinite(endo_slip_velocities(0.0, 0.0, 0.1, TREAD, 1.5)).all()  # n > 1


def test_endo_recovers_true_speed_on_turning_run():
    # Data generated with Endo's law: Endo's path length is right, gyrodometry's too long.
    run_ = synth.simulate_run(0.05, 0.35, 0.7, 0.0, 0.0, 8.0, np.random.default_rng(3))
    endo = synth.run_estimator(EndoOdometry(synth.GEOMETRY, synth.N_TRUE), run_)[1]
    gyro = synth.run_estimator(Gyrodometry(synth.GEOMETRY), run_)[1]
    assert np.mean([e.speed_mps for e in endo[1:]]) == pytest.approx(run_.v_x, rel=2e-3)
    assert np.mean([e.speed_mps for e in gyro[1:]]) > 1.02 * run_.v_x


@pytest.mark.parametrize("n", [0.0, -0.8, float("nan"), float("inf"), "abc", None])
def test_bad_n_is_rejected(n):
    with pytest.raises(ValueError, match="n must"):
        EndoOdometry(GEOM, n)
    with pytest.raises(ValueError, match="n must"):
        endo_slip_ratios(0.1, 0.2, 0.1, TREAD, n)


def test_endo_ratio_sign_follows_the_track_directions():
    """Eq. 8: opposite-sign slip ratios when both tracks drive forward, equal signs in a pivot
    (v_l = -v_r, where |v_r / v_l| = 1)."""
    assert endo_ratio(0.1, 0.2, 0.824) == pytest.approx(-(2.0**0.824))
    assert endo_ratio(-0.1, 0.1, 0.824) == pytest.approx(1.0)
    assert math.isnan(endo_ratio(0.0, 0.1, 0.824))


def test_odometry_step_is_eq1_with_the_closed_form_slips():
    """One step of EndoOdometry moves (Δs_l + Δs_r)/2 - (s_l + s_r) dt / 2 (Eq. 1) with the
    slips of :func:`endo_slip_velocities` and reports their ratios."""
    odo = EndoOdometry(GEOM, 0.824)
    dt, d_l, d_r, dyaw = 0.05, 0.004, 0.006, 0.0015
    forward, beta, extras = odo._translation(d_l, d_r, dyaw, dt, constant_run(0, 0, 0, 1)[0])
    s_l, s_r = endo_slip_velocities(d_l / dt, d_r / dt, dyaw / dt, TREAD, 0.824)
    assert beta == 0.0
    assert forward == pytest.approx(0.5 * (d_l + d_r) - 0.5 * (s_l + s_r) * dt, rel=1e-15)
    assert extras["alpha_l"] == pytest.approx(s_l / (d_l / dt), rel=1e-3)  # |v| >> ε


def test_bad_eps_and_tread_are_rejected():
    with pytest.raises(ValueError, match="speed_eps_mps"):
        EndoOdometry(GEOM, 0.824, speed_eps_mps=-1e-3)
    with pytest.raises(ValueError, match="tread_m"):
        endo_slip_velocities(0.1, 0.2, 0.1, -0.41, 0.824)


def test_the_left_share_of_arrays_is_the_left_share_of_each_element():
    """The diagnosis calls the odometry's own law on whole logs: element by element it is the
    float law, and a zero-speed pair with ε = 0 still splits the discrepancy in half."""
    rng = np.random.default_rng(7)
    v_l, v_r = rng.normal(0.0, 0.2, 50), rng.normal(0.0, 0.2, 50)
    v_l[0] = v_r[0] = 0.0
    for n in (0.5, 0.824, 1.3):
        shares = endo_left_share(v_l, v_r, n, 0.0)
        expected = [endo_left_share(float(a), float(b), n, 0.0)
                    for a, b in zip(v_l, v_r, strict=True)]
        np.testing.assert_allclose(shares, expected, rtol=1e-14)
        assert shares[0] == 0.5


def turn_frames(segments, dt=0.05):
    """Frames of consecutive constant segments (v_l, v_r, gyro, steps) on level ground, the
    encoders continuing from one segment to the next."""
    frames, t, angles = [], 0.0, np.zeros(2)
    for v_l, v_r, gyro, steps in segments:
        for _ in range(steps):
            counts = np.rint(angles * GEOM.counts_per_rad).astype(np.int64)
            frames.append(SensorFrame(t, counts, np.full(2, np.nan), gyro_z_rad_s=gyro,
                                            roll_rad=0.0))
            angles = angles + np.array([v_l, v_r]) / GEOM.wheel_radius_m * dt
            t += dt
    return frames


def test_an_n_per_turning_direction_recovers_direction_dependent_slips_exactly():
    """Tracks whose slips follow Eq. 8 with n = 0.4 turning left and n = 1.3 turning right (as
    on a slope, turning the nose uphill and downhill): the odometry with both exponents gets
    each step's slip ratios and forward speed (Eq. 1) exactly, one pooled n gets neither."""
    n_ccw, n_cw, efficiency = 0.4, 1.3, 0.7
    segments, truth = [], []
    for v_l, v_r, n in ((0.03, 0.07, n_ccw), (0.07, 0.03, n_cw)):
        gyro = efficiency * (v_r - v_l) / TREAD
        s_l, s_r = endo_slip_velocities(v_l, v_r, gyro, TREAD, n)
        segments.append((v_l, v_r, gyro, 40))
        truth.append((endo_slip_ratios(v_l, v_r, gyro, TREAD, n),
                      0.5 * (v_l + v_r) - 0.5 * (s_l + s_r)))
    frames = turn_frames(segments)
    split = run(EndoOdometry(GEOM, n_ccw, n_clockwise=n_cw), frames)
    pooled = run(EndoOdometry(GEOM, 0.5 * (n_ccw + n_cw)), frames)
    # steps 1-38 turn left, 41-78 right (the steps that straddle the change mix both)
    for steps, ((alpha_l, alpha_r), v_x) in zip((split[1:38], split[41:78]), truth, strict=True):
        for est in steps:
            assert est.extras["alpha_l"] == pytest.approx(alpha_l, rel=1e-6)
            assert est.extras["alpha_r"] == pytest.approx(alpha_r, rel=1e-6)
            assert est.speed_mps == pytest.approx(v_x, rel=1e-6)
    for steps, (_, v_x) in zip((pooled[1:38], pooled[41:78]), truth, strict=True):
        assert abs(steps[0].speed_mps / v_x - 1.0) > 0.01  # 2.3 % and 2.2 % off


def test_the_turning_direction_switch_does_not_move_straight_driving():
    """At v_l = v_r the left share is 1/2 for any n, so the exponent of either direction
    gives the same step: the switch between them is continuous."""
    frames = turn_frames([(0.05, 0.05, 0.01, 60)])
    split = run(EndoOdometry(GEOM, 0.3, n_clockwise=1.4), frames)
    pooled = run(EndoOdometry(GEOM, 0.824), frames)
    for a, b in zip(split, pooled, strict=True):
        assert (a.x_m, a.y_m) == (pytest.approx(b.x_m, abs=1e-12), pytest.approx(b.y_m, abs=1e-12))
    with pytest.raises(ValueError, match="n must"):
        EndoOdometry(GEOM, 0.824, n_clockwise=0.0)
