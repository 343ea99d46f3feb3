"""The windowed polyline distance equals the whole-image one bit for bit (issue 15).

:func:`polyline_distance_window` lets the trace camera draw a rut on the part of the frame it
can reach; the frame must not change by one bit, so the window's distances and along-track
coordinates must be exactly the whole image's there, and every pixel left out must lie beyond
the reach.
"""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.sensors.trace_raster import polyline_distance_px, polyline_distance_window

SHAPE = (240, 320)


def _polylines(n: int) -> list[np.ndarray]:
    rng = np.random.default_rng(7)
    out = []
    for _ in range(n):
        start = rng.uniform([-40.0, -40.0], [360.0, 280.0])
        steps = rng.normal(0.0, 6.0, (rng.integers(2, 60), 2)) + rng.uniform(-4.0, 4.0, 2)
        out.append(start + np.cumsum(steps, axis=0))
    return out


@pytest.mark.parametrize("reach_px", [3.0, 17.5])
def test_window_is_the_whole_image_cut_to_the_reach(reach_px):
    checked = 0
    for uv in _polylines(40):
        full_dist, full_along = polyline_distance_px(uv, SHAPE)
        near = polyline_distance_window(uv, SHAPE, reach_px)
        if near is None:
            assert full_dist.min() > 1e5  # missed the image: no pixel is near the line
            continue
        dist, along, window = near
        np.testing.assert_array_equal(dist, full_dist[window])
        np.testing.assert_array_equal(along, full_along[window])
        outside = np.ones(SHAPE, bool)
        outside[window] = False
        assert np.all(full_dist[outside] > reach_px)
        checked += 1
    assert checked > 20


def test_polyline_off_the_image_gives_no_window():
    uv = np.array([[-50.0, -50.0], [-10.0, -80.0]])
    assert polyline_distance_window(uv, SHAPE, 5.0) is None
    assert polyline_distance_window(np.array([[10.0, 10.0]]), SHAPE, 5.0) is None
