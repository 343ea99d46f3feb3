"""The beacon scanner reuses the last pose's beacon bearings only for that very pose.

``BeaconScanner.scan`` starts each sweep from the previous call's pose, whose
bearings it keeps instead of computing them twice. A scanner moved by ``reset`` to another
pose must then give exactly what a new scanner placed there gives.
"""

from __future__ import annotations

import math

import numpy as np

from slipenv.sensors.beacons import BeaconScanner


def _sweep(scanner: BeaconScanner, t0: float, x0: float, y0: float, seed: int):
    rng = np.random.default_rng(seed)
    out = []
    for k in range(1, 80):
        t = t0 + 0.05 * k
        out.append(scanner.scan(t, x0 + 0.02 * k, y0 - 0.01 * k, 0.3 + 0.01 * k, rng))
    return out


def _assert_same(a, b):
    assert len(a) == len(b)
    for (bear_a, t_a), (bear_b, t_b) in zip(a, b, strict=True):
        np.testing.assert_array_equal(bear_a, bear_b)
        np.testing.assert_array_equal(t_a, t_b)


def test_a_scanner_reset_elsewhere_scans_like_a_new_one():
    used = BeaconScanner(clutter_rate_hz=2.0)
    _sweep(used, 0.0, 1.0, 2.0, seed=1)
    used.reset(10.0, -3.0, 4.0, 0.3)
    fresh = BeaconScanner(clutter_rate_hz=2.0)
    fresh.reset(10.0, -3.0, 4.0, 0.3)
    _assert_same(_sweep(used, 10.0, -3.0, 4.0, seed=2), _sweep(fresh, 10.0, -3.0, 4.0, seed=2))


def test_sweeps_find_bearings_and_sort_them_in_time():
    scans = _sweep(BeaconScanner(), 0.0, 0.0, 0.0, seed=3)
    counts = [len(b) for b, _ in scans]
    assert sum(counts) > 50 and 0 in counts and max(counts) >= 2
    for bearings, times in scans:
        assert np.all(np.diff(times) >= 0.0)
        assert np.all(np.abs(bearings) <= math.pi)
