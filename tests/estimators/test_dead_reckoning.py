"""Dead reckoning's side angles."""

from __future__ import annotations

import numpy as np

from slipenv.contracts import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.dead_reckoning import side_angles_rad


def test_side_angles_are_the_mean_wheel_angle_of_each_group():
    """Each side's angle is its wheels' mean count over counts_per_rad, for groups of one to
    six wheels and counts up to 1e9 (no precision lost to the summation)."""
    rng = np.random.default_rng(3)
    for k in range(1, 7):
        counts = rng.integers(-10**9, 10**9, 2 * k)
        geom = OdometryGeometry(0.1, 0.4, 285.0, tuple(range(k)), tuple(range(k, 2 * k)))
        frame = SensorFrame(t_s=0.0, enc_counts=counts, wheel_torque_nm=np.zeros(2 * k))
        c = counts.astype(float)
        expected = (float(np.mean(c[:k])) / 285.0, float(np.mean(c[k:])) / 285.0)
        np.testing.assert_allclose(side_angles_rad(frame, geom), expected, rtol=1e-15)
