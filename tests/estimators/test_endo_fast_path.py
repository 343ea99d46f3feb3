"""Endo odometry's per-step plain-float path equals the plain functions bit for bit (issue 15)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.contracts import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.skid_steer.endo import (
    EndoOdometry,
    endo_slip_velocities,
    slip_ratio_from_slip_velocity,
)

GEOM = OdometryGeometry(0.1, 0.4, 1000.0)


@pytest.mark.parametrize("n", [0.5, 0.824, 1.0, 1.7])
@pytest.mark.parametrize("eps", [0.0, 0.01])
def test_translation_equals_the_plain_functions_bit_for_bit(n, eps):
    odo = EndoOdometry(GEOM, n, speed_eps_mps=eps)
    rng = np.random.default_rng(int(100 * n) + int(1000 * eps))
    frame = SensorFrame(t_s=0.0, enc_counts=np.zeros(2), wheel_torque_nm=np.zeros(2))
    samples = [tuple(rng.normal(0.0, 0.05, 3)) for _ in range(200)]
    samples += [(0.0, 0.0, 0.01), (0.01, 0.0, 0.0), (0.0, 0.02, -0.01), (0.03, -0.03, 0.1)]
    for d_l, d_r, dyaw in samples:
        dt = 0.05
        forward, beta, extras = odo._translation(d_l, d_r, dyaw, dt, frame)
        v_l, v_r = d_l / dt, d_r / dt
        s_l, s_r = (float(s) for s in endo_slip_velocities(v_l, v_r, dyaw / dt, 0.4, n, eps))
        assert forward == 0.5 * (d_l + d_r) - 0.5 * (s_l + s_r) * dt and beta == 0.0
        assert (extras["slip_velocity_l_mps"], extras["slip_velocity_r_mps"]) == (s_l, s_r)
        for side, s, v in (("l", s_l, v_l), ("r", s_r, v_r)):
            expected = float(slip_ratio_from_slip_velocity(s, v, eps))
            got = extras[f"alpha_{side}"]
            assert got == expected or (math.isnan(got) and math.isnan(expected))


def test_side_angles_equal_numpy_means_bit_for_bit():
    """The group means in plain floats are np.mean's, for groups of one to six wheels."""
    from slipenv.estimators.dead_reckoning import side_angles_rad

    rng = np.random.default_rng(3)
    for k in range(1, 7):
        counts = rng.integers(-10**9, 10**9, 2 * k)
        geom = OdometryGeometry(0.1, 0.4, 285.0, tuple(range(k)), tuple(range(k, 2 * k)))
        frame = SensorFrame(t_s=0.0, enc_counts=counts, wheel_torque_nm=np.zeros(2 * k))
        c = counts.astype(float)
        expected = (float(np.mean(c[:k])) / 285.0, float(np.mean(c[k:])) / 285.0)
        assert side_angles_rad(frame, geom) == expected
