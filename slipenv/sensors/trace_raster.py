"""Raster helpers of the rear trace camera: distance to a polyline, rut profile, fBm, shadows.

All work on whole images with OpenCV/numpy (a frame costs a few milliseconds).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

_SHIFT = 4  # fixed-point bits for sub-pixel polyline vertices (cv2 ``shift``)
EXACT_TRANSFORM_MIN_PIXELS = 1 << 14
"""Smallest image (rows x columns) whose ``cv2.distanceTransform(DIST_L2, DIST_MASK_PRECISE)``
is the exact Euclidean transform; below it OpenCV takes an approximate path (measured on
OpenCV 5.0; ``tests/sensors/test_trace_raster_window.py`` checks both facts)."""


def polyline_distance_px(uv_px: np.ndarray, shape: tuple[int, int]) -> tuple[np.ndarray,
                                                                              np.ndarray]:
    """Per-pixel distance to a polyline and an along-track coordinate [px].

    Parameters
    ----------
    uv_px : np.ndarray, shape (n, 2)
        Vertices (column, row) [px]; NaN rows are dropped.
    shape : tuple of int
        Image (rows, columns).

    Returns
    -------
    dist_px : np.ndarray, float32
        Euclidean distance to the rasterised centreline [px].
    along_px : np.ndarray, float32
        Coordinate along the polyline's principal direction [px] (the traces are nearly
        straight inside the view, so this places grouser marks across the rut).
    """
    rows, cols = shape
    uv = uv_px[np.all(np.isfinite(uv_px), axis=1)]
    mask = np.full((rows, cols), 255, np.uint8)
    if len(uv) >= 2:
        pts = np.round(uv * (1 << _SHIFT)).astype(np.int32).reshape(-1, 1, 2)
        cv2.polylines(mask, [pts], False, 0, 1, cv2.LINE_8, _SHIFT)
    if mask.min() > 0:  # polyline outside the image
        return np.full((rows, cols), 1e6, np.float32), np.zeros((rows, cols), np.float32)
    dist = cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    direction = uv[-1] - uv[0]
    norm = float(np.hypot(*direction))
    direction = direction / norm if norm > 0 else np.array([1.0, 0.0])
    u = np.arange(cols, dtype=np.float32) - np.float32(uv[0, 0])
    v = np.arange(rows, dtype=np.float32) - np.float32(uv[0, 1])
    along = v[:, None] * np.float32(direction[1]) + u[None, :] * np.float32(direction[0])
    return dist, along


def polyline_distance_window(uv_px: np.ndarray, shape: tuple[int, int], reach_px: float
                             ) -> tuple[np.ndarray, np.ndarray, tuple[slice, slice]] | None:
    """:func:`polyline_distance_px` cut to the part of the image within ``reach_px`` of the line.

    The same distances and along-track coordinates, bit for bit, on the window of the image
    around the rasterised centreline padded by ``reach_px``: every pixel outside it lies
    farther than ``reach_px`` from the line. A rut covers a few percent of the frame, so the
    caller's per-pixel work shrinks with the window. The distance transform runs on
    a crop holding the window (so every zero pixel of the mask) of at least
    ``EXACT_TRANSFORM_MIN_PIXELS``: OpenCV's precise L2 transform is then the exact Euclidean
    one (float32 ``sqrt`` of the integer squared distance, Felzenszwalb & Huttenlocher), which
    depends only on the zero pixels, so the crop's distances are the whole image's bit for bit.
    Smaller images go through an approximate (IPP) path whose last bit depends on the image
    size; there the whole image is transformed, as before.

    Returns
    -------
    (dist_px, along_px, window) or None
        Distance and along-track coordinate on ``window`` (they equal
        ``polyline_distance_px(uv_px, shape)[i][window]``); None if the polyline misses the
        image.
    """
    rows, cols = shape
    uv = uv_px[np.all(np.isfinite(uv_px), axis=1)]
    if len(uv) < 2:
        return None
    # The centreline drawn as 255 on 0 (the transform's mask is its negative): OpenCV's
    # bounding box of the nonzero pixels then replaces two whole-image scans.
    line = np.zeros((rows, cols), np.uint8)
    pts = np.round(uv * (1 << _SHIFT)).astype(np.int32).reshape(-1, 1, 2)
    cv2.polylines(line, [pts], False, 255, 1, cv2.LINE_8, _SHIFT)
    col0, row0, width, height = cv2.boundingRect(line)
    if width == 0:  # polyline outside the image
        return None
    pad = int(math.ceil(reach_px)) + 1
    window = (slice(max(row0 - pad, 0), min(row0 + height + pad, rows)),
              slice(max(col0 - pad, 0), min(col0 + width + pad, cols)))
    crop = _exact_transform_crop(window, shape)
    dist = cv2.distanceTransform(cv2.bitwise_not(line[crop]), cv2.DIST_L2,
                                 cv2.DIST_MASK_PRECISE)
    # the window's rows and columns inside the crop
    in_crop = (slice(window[0].start - crop[0].start, window[0].stop - crop[0].start),
               slice(window[1].start - crop[1].start, window[1].stop - crop[1].start))
    direction = uv[-1] - uv[0]
    norm = float(np.hypot(*direction))
    direction = direction / norm if norm > 0 else np.array([1.0, 0.0])
    u = (np.arange(cols, dtype=np.float32) - np.float32(uv[0, 0]))[window[1]]
    v = (np.arange(rows, dtype=np.float32) - np.float32(uv[0, 1]))[window[0]]
    along = v[:, None] * np.float32(direction[1]) + u[None, :] * np.float32(direction[0])
    return dist[in_crop], along, window


def _exact_transform_crop(window: tuple[slice, slice], shape: tuple[int, int]
                          ) -> tuple[slice, slice]:
    """The smallest crop around ``window`` (grown across, then along the rows, centred where the
    image allows) with at least ``EXACT_TRANSFORM_MIN_PIXELS``, or the whole image if it is
    smaller than that (see :func:`polyline_distance_window`)."""
    rows, cols = shape
    if rows * cols < EXACT_TRANSFORM_MIN_PIXELS:
        return slice(0, rows), slice(0, cols)

    def grow(part: slice, size: int, extent: int) -> slice:
        size = min(max(size, part.stop - part.start), extent)
        start = min(max(part.start - (size - (part.stop - part.start)) // 2, 0), extent - size)
        return slice(start, start + size)

    r, c = window
    height = r.stop - r.start
    c = grow(c, -(-EXACT_TRANSFORM_MIN_PIXELS // height), cols)
    width = c.stop - c.start
    r = grow(r, -(-EXACT_TRANSFORM_MIN_PIXELS // width), rows)
    return r, c


def rut_height(q: np.ndarray, depth_m: float, grooves: np.ndarray) -> tuple[np.ndarray,
                                                                            np.ndarray]:
    """Height of a rut cross-section [m] at normalised distance ``q = d / (b/2)``.

    Flat floor at ``-depth`` out to q = 0.85, walls to q = 1.15, a berm of 0.25 depth pushed
    out to q = 1.9; grouser grooves (``grooves`` in [0, 1]) cut 0.35 depth into the floor.
    Returns the height and the mask of the rut proper (q < 1.15) that overwrites older ground.
    """
    q = np.asarray(q, np.float32)
    d = np.float32(depth_m)
    t = np.clip((q - np.float32(0.85)) / np.float32(0.30), np.float32(0.0), np.float32(1.0))
    wall = 1.0 - t * t * (3.0 - 2.0 * t)  # smoothstep: 1 on the floor, 0 outside
    x = np.clip((q - np.float32(1.0)) / np.float32(0.9), np.float32(0.0), np.float32(1.0))
    berm = 4.0 * x * (1.0 - x)  # parabolic bump between q = 1 and 1.9
    h = -d * wall + np.float32(0.25) * d * berm - np.float32(0.35) * d * grooves * (q < 0.85)
    return h.astype(np.float32), q < 1.15


def fbm_noise(shape: tuple[int, int], rng: np.random.Generator, octaves: int = 5) -> np.ndarray:
    """Fractal (fBm) value noise of unit standard deviation: octaves of smooth random grids."""
    rows, cols = shape
    out = np.zeros(shape, np.float32)
    for k in range(octaves):
        n_r, n_c = 3 * 2 ** k, 4 * 2 ** k
        grid = rng.standard_normal((n_r, n_c)).astype(np.float32)
        octave = cv2.resize(grid, (cols, rows), interpolation=cv2.INTER_CUBIC)
        # in place: the float32 product 0.55^k * octave, without one more frame
        np.multiply(octave, 0.55 ** k, out=octave)
        out += octave
    out /= max(float(out.std()), 1e-6)
    return out


def soft_halfplane(shape: tuple[int, int], rng: np.random.Generator,
                   softness_px: float) -> np.ndarray:
    """A random half-plane (through the middle 60 % of the image) with a soft edge, in [0, 1]."""
    rows, cols = shape
    angle = rng.uniform(0.0, 2.0 * np.pi)
    cu, cv = rng.uniform(0.2, 0.8) * cols, rng.uniform(0.2, 0.8) * rows
    u = np.arange(cols, dtype=np.float32) - np.float32(cu)
    v = np.arange(rows, dtype=np.float32) - np.float32(cv)
    signed = u[None, :] * np.float32(np.cos(angle)) + v[:, None] * np.float32(np.sin(angle))
    return 1.0 / (1.0 + np.exp(np.clip(-signed / np.float32(softness_px), -30.0, 30.0)))
