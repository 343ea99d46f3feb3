"""``BeaconScanner.scan`` gives bit for bit what its plain numpy form gives.

The scan runs at every control step; it now updates its arrays in place and interpolates the
pose at the hits in one broadcast. The reference below is the scan as it was written before
(every expression on fresh arrays); both must return the same bearings and times, and draw the
same random numbers, for slow and fast heads (several sweeps past a beacon between two calls),
with and without clutter, on a wandering vehicle.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.contracts.angles import wrap_angle, wrap_angles
from slipenv.sensors.beacons import BeaconScanner


def _reference_scan(sc: BeaconScanner, last: tuple[float, float, float, float], t_s: float,
                    x_m: float, y_m: float, yaw_rad: float, rng: np.random.Generator):
    t0, x0, y0, yaw0 = last
    t1 = float(t_s)
    dyaw = wrap_angle(yaw_rad - yaw0)
    dt = t1 - t0

    def body(x: float, y: float, yaw: float) -> np.ndarray:
        return np.arctan2(sc.beacons_xy[:, 1] - y, sc.beacons_xy[:, 0] - x) - yaw

    phi0 = body(x0, y0, yaw0)
    phi1 = body(float(x_m), float(y_m), yaw0 + dyaw)
    dphi = wrap_angles(phi1 - phi0)
    g0 = sc.head_phase_rad + 2.0 * math.pi * sc.scan_rate_hz * t0 - phi0
    dg = 2.0 * math.pi * sc.scan_rate_hz * dt - dphi
    m_lo = np.floor(g0 / (2.0 * np.pi)) + 1.0
    m_hi = np.floor((g0 + dg) / (2.0 * np.pi))
    n_hits = np.maximum(m_hi - m_lo + 1.0, 0.0).astype(int) * (dg > 0.0)
    if sc.clutter_rate_hz == 0.0 and not n_hits.any():
        return np.zeros(0), np.zeros(0)
    if n_hits.max() == 1:
        idx = np.flatnonzero(n_hits)
        m = m_lo[idx]
    else:
        idx = np.repeat(np.arange(len(sc.beacons_xy)), n_hits)
        m = m_lo[idx] + (np.arange(len(idx)) - np.repeat(np.cumsum(n_hits) - n_hits, n_hits))
    frac = np.minimum(np.maximum((2.0 * np.pi * m - g0[idx]) / dg[idx], 0.0), 1.0)
    times = np.maximum(t0 + frac * dt, math.nextafter(t0, math.inf))
    xs, ys = x0 + frac * (x_m - x0), y0 + frac * (y_m - y0)
    yaws = yaw0 + frac * dyaw
    dx, dy = sc.beacons_xy[idx, 0] - xs, sc.beacons_xy[idx, 1] - ys
    bearing = wrap_angles(np.arctan2(dy, dx) - yaws)
    seen = (np.hypot(dx, dy) <= sc.max_range_m) & (np.abs(bearing) <= 0.5 * sc.fov_rad)
    bearing, times = bearing[seen], times[seen]
    bearing = bearing + rng.normal(0.0, math.sqrt(sc.bearing_var_rad2), bearing.shape)
    if sc.clutter_rate_hz > 0.0:
        k = rng.poisson(sc.clutter_rate_hz * dt)
        bearing = np.concatenate([bearing, rng.uniform(-0.5, 0.5, k) * sc.fov_rad])
        times = np.concatenate([times, t0 + dt * (1.0 - rng.uniform(0.0, 1.0, k))])
    if len(times) > 1:
        order = np.argsort(times, kind="stable")
        bearing, times = bearing[order], times[order]
    return wrap_angles(bearing), times


@pytest.mark.parametrize(("scan_rate_hz", "clutter_rate_hz", "dt_s"),
                         [(3.6, 0.0, 0.05), (3.6, 5.0, 0.05), (40.0, 0.0, 0.1), (90.0, 20.0, 0.2)])
def test_scan_is_the_plain_numpy_scan_bit_for_bit(scan_rate_hz, clutter_rate_hz, dt_s):
    scanner = BeaconScanner(scan_rate_hz=scan_rate_hz, clutter_rate_hz=clutter_rate_hz,
                            head_phase_rad=0.4)
    walk = np.random.default_rng(3)
    rng, rng_ref = np.random.default_rng(11), np.random.default_rng(11)
    t, x, y, yaw = 0.0, 1.0, -2.0, 0.5
    scanner.scan(t, x, y, yaw, rng)
    hits = multi = 0
    for _ in range(400):
        last = (t, x, y, yaw)
        t += dt_s
        x, y = x + walk.normal(0.0, 0.3), y + walk.normal(0.0, 0.3)
        yaw = wrap_angle(yaw + walk.normal(0.0, 0.4))
        got = scanner.scan(t, x, y, yaw, rng)
        want = _reference_scan(scanner, last, t, x, y, yaw, rng_ref)
        np.testing.assert_array_equal(got[0], want[0])
        np.testing.assert_array_equal(got[1], want[1])
        hits += len(got[0])
        multi += len(got[0]) > len(scanner.beacons_xy)
    assert rng.random() == rng_ref.random()  # the same draws, in the same order
    assert hits > 100
    if scan_rate_hz * dt_s > 2.0:
        assert multi > 0  # several sweeps past a beacon between two calls were exercised
