"""The odometry limits of the reproduction: the true slip angle and the true track slips in
place of what the slip-compensated odometry infers (Yamauchi Eq. 1, 7-9), on a synthetic
turn on a slope whose truth is known in closed form."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.experiments.yamauchi.odometry import (
    TrueSlipAngle,
    TrueSlipOdometry,
    replay,
    true_beta_odometry,
)
from slipenv.experiments.yamauchi.rotation import RotationRun
from slipenv.experiments.yamauchi.settings import ORACLE_MAX_SLIP_ANGLE_RAD
from tests.estimators import skid_steer_synth as synth


@pytest.fixture(scope="module")
def turn():
    """A 90° turn at 5 cm/s and 20 °/s on a 15° slope, the gyro seeing 70 % of the commanded
    rate, the slips following Eq. 8 with the synthetic n and β Eq. 9; a noiseless gyro."""
    rate = math.radians(20.0)
    s = synth.simulate_run(0.05, rate, 0.7, math.radians(15.0), 0.0, 0.5 * math.pi / (0.7 * rate),
                           np.random.default_rng(4), gyro_std=0.0)
    v_body = np.column_stack([np.full(s.t.size, s.v_x), s.v_x * np.tan(s.beta)])
    pose = np.column_stack([s.x, s.y, s.yaw])
    return RotationRun("synthetic", 15.0, 20.0, 1, s.frames, s.t, pose, v_body,
                       np.full(s.t.size, s.omega), s.beta)


def final_error_m(estimator, run, oracle=None) -> float:
    xy, _ = replay(estimator, run, oracle)
    return float(np.hypot(*(xy[-1] - run.pose[-1, :2])))


def test_the_true_slips_and_slip_angle_recover_the_path(turn):
    """Eq. 1 with the true forward speed and Eq. 5-6 with the true β: only the midpoint rule's
    error is left, 4 µm on a 30 cm turn, where gyrodometry (the slips ignored) is 3 cm off."""
    oracle = TrueSlipAngle()
    odometry = TrueSlipOdometry(synth.GEOMETRY, 0.824, oracle, oracle,
                                max_slip_angle_rad=ORACLE_MAX_SLIP_ANGLE_RAD)
    assert final_error_m(odometry, turn, oracle) < 2e-5
    assert final_error_m(Gyrodometry(synth.GEOMETRY), turn) > 0.01


def test_the_true_forward_speed_is_the_step_displacement_along_the_heading(turn):
    oracle = TrueSlipAngle()
    for k in (1, len(turn.t_s) // 2, len(turn.t_s) - 1):
        oracle.observe(turn, k)
        assert oracle.forward_mps == pytest.approx(turn.v_body[k, 0], rel=1e-4)
        assert oracle.beta_rad == turn.slip_angle[k]


def test_tracks_that_follow_eq8_leave_endo_nothing_to_add(turn):
    """The synthetic slips follow Eq. 8 with the n the odometry uses: Endo's slips are the true
    ones, and with the true β the odometry is as good as with the true slips (the encoder
    quantisation apart: 0.02 mm); a wrong n (0.3) leaves 5 cm."""
    oracle = TrueSlipAngle()
    endo = true_beta_odometry(synth.GEOMETRY, synth.N_TRUE, oracle)
    assert final_error_m(endo, turn, oracle) < 1e-4
    wrong = true_beta_odometry(synth.GEOMETRY, 0.3, oracle)
    assert final_error_m(wrong, turn, oracle) > 0.01
