"""sComp with the pitch term: the slip ratio follows the inclinometer's climb angle."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.contracts import SensorFrame
from slipenv.estimators import OdometryGeometry
from slipenv.estimators.reina import SCompOdometry, SlipRatioModel

R, CPR = 0.09, 285.0
GEOM = OdometryGeometry(R, 0.5, CPR, left=(0, 2), right=(1, 3))
MODEL = SlipRatioModel(0.2, 0.8, 0.0, k_pitch=2.3, pitch_ref_rad=math.radians(5.0))


def climbing_frames(climb_rad: np.ndarray, pitch_seen_rad: np.ndarray, beta: float,
                    counts_per_step: int = 57) -> tuple[list[SensorFrame], np.ndarray]:
    """A rover heading +x over a climb that changes step by step; its slip ratio is the model's.

    ``pitch_seen_rad`` is what the inclinometer reports (SensorFrame convention: > 0 lowers the
    nose); ``climb_rad`` is the climb the slip follows.
    """
    frames, path = [], [np.zeros(2)]
    for k, (c, p) in enumerate(zip(climb_rad, pitch_seen_rad, strict=True)):
        counts = np.full(4, k * counts_per_step, dtype=np.int64)
        frames.append(SensorFrame(0.1 * k, counts, np.full(4, np.nan), heading_rad=0.0,
                                  steer_rad=np.zeros(4), pitch_rad=float(p)))
        if k:
            dx = R * counts_per_step / CPR * (1.0 - float(MODEL(beta, c)))
            path.append(path[-1] + [dx, dx * math.tan(beta)])
    return frames, np.array(path)


def run(est: SCompOdometry, frames: list[SensorFrame], beta: float) -> np.ndarray:
    est.reset(0.0, 0.0, 0.0, frames[0])
    est.set_slip_angle(beta)
    return np.array([[0.0, 0.0]] + [[e.x_m, e.y_m] for e in map(est.update, frames[1:])])


def test_scomp_follows_the_inclinometer_climb_over_mounds() -> None:
    n, beta = 300, math.radians(6.0)
    climb = math.radians(5.0) + math.radians(7.0) * np.sin(np.arange(n) * 0.05)
    frames, path = climbing_frames(climb, -climb, beta)
    got = run(SCompOdometry(GEOM, MODEL), frames, beta)
    np.testing.assert_allclose(got, path, atol=1e-9)
    # Without the pitch term sComp uses the reference slope's slip throughout and misses.
    flat = SlipRatioModel(MODEL.s_x0, MODEL.k_per_rad, MODEL.beta0_rad)
    miss = run(SCompOdometry(GEOM, flat), frames, beta)
    rolled = R * 57 / CPR * (n - 1)
    mean_extra = float(np.mean([MODEL(beta, c) - flat(beta) for c in climb[1:]]))
    assert miss[-1, 0] - path[-1, 0] == pytest.approx(rolled * mean_extra, rel=1e-6)


def test_a_missing_inclinometer_reading_stands_for_the_reference_climb() -> None:
    n, beta = 50, 0.0
    climb = np.full(n, math.radians(9.0))
    frames, _ = climbing_frames(climb, np.full(n, np.nan), beta)
    est = SCompOdometry(GEOM, MODEL)
    run(est, frames, beta)
    assert est.slip_ratio == pytest.approx(MODEL.s_x0)
    frames, _ = climbing_frames(climb, -climb, beta)
    run(est, frames, beta)
    assert est.slip_ratio == pytest.approx(
        0.2 + 2.3 * (math.tan(math.radians(9.0)) - math.tan(math.radians(5.0))))
