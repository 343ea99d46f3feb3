"""The windowed polyline distance equals the whole-image one bit for bit.

The distance transform runs on a crop around the window of at least
``EXACT_TRANSFORM_MIN_PIXELS``, where OpenCV's precise transform is the exact Euclidean one
(checked here against scipy's exact transform), so the crop's distances are the image's.

:func:`polyline_distance_window` lets the trace camera draw a rut on the part of the frame it
can reach; the frame must not change by one bit, so the window's distances and along-track
coordinates must be exactly the whole image's there, and every pixel left out must lie beyond
the reach.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest
from scipy import ndimage

from slipenv.sensors.trace_raster import (
    EXACT_TRANSFORM_MIN_PIXELS,
    _exact_transform_crop,
    polyline_distance_px,
    polyline_distance_window,
)

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


def _exact_edt(mask: np.ndarray) -> np.ndarray:
    """float32 sqrt of the exact integer squared distance to the nearest zero pixel."""
    _, (rows, cols) = ndimage.distance_transform_edt(mask != 0, return_indices=True)
    yy, xx = np.indices(mask.shape)
    return np.sqrt(((rows - yy) ** 2 + (cols - xx) ** 2).astype(np.float32))


def _mask(uv: np.ndarray, shape: tuple[int, int]) -> np.ndarray:
    mask = np.full(shape, 255, np.uint8)
    pts = np.round(uv * 16).astype(np.int32).reshape(-1, 1, 2)
    cv2.polylines(mask, [pts], False, 0, 1, cv2.LINE_8, 4)
    return mask


@pytest.mark.parametrize("shape", [SHAPE, (240, 69), (128, 128), (16, 1024)])
def test_opencv_precise_transform_is_exact_from_the_minimum_size(shape):
    # the crop of polyline_distance_window rests on this: from EXACT_TRANSFORM_MIN_PIXELS up,
    # OpenCV's DIST_MASK_PRECISE is the exact Euclidean transform, whatever the image's shape
    assert shape[0] * shape[1] >= EXACT_TRANSFORM_MIN_PIXELS
    rng = np.random.default_rng(5)
    for _ in range(6):
        uv = rng.uniform([0.0, 0.0], [shape[1], shape[0]], (5, 2))
        mask = _mask(uv, shape)
        dist = cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
        np.testing.assert_array_equal(dist, _exact_edt(mask))


def test_the_exact_transform_crop_holds_the_window_and_the_minimum_size():
    for window in [(slice(0, 240), slice(100, 140)), (slice(10, 30), slice(0, 5)),
                   (slice(200, 240), slice(300, 320)), (slice(0, 240), slice(0, 320))]:
        rows, cols = _exact_transform_crop(window, SHAPE)
        assert 0 <= rows.start <= window[0].start and window[0].stop <= rows.stop <= SHAPE[0]
        assert 0 <= cols.start <= window[1].start and window[1].stop <= cols.stop <= SHAPE[1]
        assert (rows.stop - rows.start) * (cols.stop - cols.start) >= EXACT_TRANSFORM_MIN_PIXELS
    small = (100, 100)  # below the minimum: the whole image
    assert _exact_transform_crop((slice(5, 9), slice(5, 9)), small) == (slice(0, 100),
                                                                       slice(0, 100))


def test_window_of_camera_like_traces_is_the_whole_image_cut():
    # near-vertical wheel traces with the camera's reach (rut and berm: 31 px)
    rng = np.random.default_rng(9)
    for _ in range(30):
        x0, slope = rng.uniform(0.0, 320.0), rng.normal(0.0, 0.3)
        v = np.sort(rng.uniform(-40.0, 280.0, 40))
        uv = np.column_stack([x0 + slope * v + rng.normal(0.0, 0.5, 40), v])
        near = polyline_distance_window(uv, SHAPE, 31.4)
        full_dist, full_along = polyline_distance_px(uv, SHAPE)
        if near is None:
            continue
        dist, along, window = near
        np.testing.assert_array_equal(dist, full_dist[window])
        np.testing.assert_array_equal(along, full_along[window])
