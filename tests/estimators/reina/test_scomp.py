"""sComp odometry (Reina Eq. 15-17), compass-aided odometry and Eq. 18 on a crabbing rover."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.contracts import SensorFrame
from slipenv.estimators import DeadReckoning, OdometryGeometry
from slipenv.estimators.reina import (
    CompassOdometry,
    SCompOdometry,
    SlipRatioModel,
    final_position_error,
)

R, CPR = 0.09, 285.0
GEOM = OdometryGeometry(R, 0.5, CPR, left=(0, 2), right=(1, 3))


def crab_frames(slip: float, beta: float, psi: float, n: int = 200,
                counts_per_step: int = 57) -> tuple[list[SensorFrame], np.ndarray]:
    """A rover crabbing in a straight line: frames and the true path of its reference point.

    Every wheel turns ``counts_per_step`` counts per 0.1 s step; the body moves forward by
    r Δφ (1 - s) and sideways by that times tan β (Eq. 3-4), heading fixed at ``psi``.
    """
    frames, path = [], [np.zeros(2)]
    rot = np.array([[math.cos(psi), -math.sin(psi)], [math.sin(psi), math.cos(psi)]])
    for k in range(n + 1):
        counts = np.full(4, k * counts_per_step, dtype=np.int64)
        frames.append(SensorFrame(0.1 * k, counts, np.full(4, np.nan), heading_rad=psi,
                                  steer_rad=np.zeros(4)))
        if k:
            dx = R * counts_per_step / CPR * (1.0 - slip)
            path.append(path[-1] + rot @ [dx, dx * math.tan(beta)])
    return frames, np.array(path)


def run(est, frames: list[SensorFrame], psi: float) -> np.ndarray:
    est.reset(0.0, 0.0, psi, frames[0])
    return np.array([[0.0, 0.0]] + [[e.x_m, e.y_m] for e in map(est.update, frames[1:])])


@pytest.mark.parametrize(("slip", "beta_deg", "psi"), [(0.2, 15.0, 0.4), (0.05, -8.0, -2.0)])
def test_scomp_with_true_slips_reproduces_a_crabbing_line(slip: float, beta_deg: float,
                                                          psi: float) -> None:
    beta = math.radians(beta_deg)
    frames, truth = crab_frames(slip, beta, psi)
    model = SlipRatioModel(s_x0=slip, k_per_rad=0.0)
    est = SCompOdometry(GEOM, model, slip_angle_source=lambda frame: beta)
    np.testing.assert_allclose(run(est, frames, psi), truth, atol=1e-9)


def test_plain_and_compass_odometry_miss_by_the_closed_form_amount() -> None:
    slip, beta, psi = 0.2, math.radians(15.0), 0.4
    frames, truth = crab_frames(slip, beta, psi)
    travelled = R * 200 * 57 / CPR  # r ω T
    expected = travelled * math.hypot(slip, (1.0 - slip) * math.tan(beta))
    plain = run(DeadReckoning(GEOM), frames, psi)
    compass = run(CompassOdometry(GEOM), frames, psi)
    assert final_position_error(plain, truth) == pytest.approx(expected, rel=1e-9)
    assert final_position_error(compass, truth) == pytest.approx(expected, rel=1e-9)


def test_scomp_uses_eq12_slip_ratio_and_the_set_slip_angle() -> None:
    beta = math.radians(12.0)
    model = SlipRatioModel(s_x0=0.05, k_per_rad=1.0, beta0_rad=math.radians(4.0))
    slip = model(beta)  # the slip ratio the model gives at this slip angle
    frames, truth = crab_frames(slip, beta, 0.0)
    est = SCompOdometry(GEOM, model)
    est.reset(0.0, 0.0, 0.0, frames[0])
    est.set_slip_angle(beta)
    for frame in frames[1:]:
        est.set_slip_angle(math.nan)  # a missed FTrace frame keeps the last slip angle
        out = est.update(frame)
    assert out.slip_angle_rad == pytest.approx(beta)
    assert out.extras["slip_ratio"] == pytest.approx(slip)
    assert final_position_error([out.x_m, out.y_m], truth) < 1e-9
    # Eq. 15 as printed (+k) would overshoot: V_x = rω(1 - s_x0 + k(β - β0)).
    printed = R * 200 * 57 / CPR * (1.0 - 0.05 + 1.0 * (beta - math.radians(4.0)))
    assert abs(out.x_m - printed) > 0.1


def test_compass_heading_is_required_and_slip_angle_bounded() -> None:
    frames, _ = crab_frames(0.1, 0.1, 0.0, n=2)
    est = SCompOdometry(GEOM, SlipRatioModel(0.1, 0.0))
    est.reset(0.0, 0.0, 0.0, frames[0])
    bad = SensorFrame(0.1, frames[1].enc_counts, frames[1].wheel_torque_nm)
    with pytest.raises(ValueError, match="heading_rad"):
        est.update(bad)
    with pytest.raises(ValueError, match="slip angle"):
        est.set_slip_angle(2.0)


def test_final_position_error_is_eq18() -> None:
    assert final_position_error([[0, 0], [3.0, 4.0]], [[0, 0], [0.0, 0.0]]) == pytest.approx(5.0)
    with pytest.raises(ValueError, match="estimate_xy"):
        final_position_error([1.0, 2.0, 3.0], [0.0, 0.0])
