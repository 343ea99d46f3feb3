"""Raster helpers of the rear trace camera: distance to a polyline, rut profile, fBm, shadows.

All work on whole images with OpenCV/numpy (a frame costs a few milliseconds).
"""

from __future__ import annotations

import math

import cv2
import numpy as np

_SHIFT = 4  # fixed-point bits for sub-pixel polyline vertices (cv2 ``shift``)


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
    caller's per-pixel work shrinks with the window (issue 15). The distance transform itself
    still runs on the whole image: OpenCV's exact transform of a crop differs from the
    whole image's in the last bit.

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
    mask = np.full((rows, cols), 255, np.uint8)
    pts = np.round(uv * (1 << _SHIFT)).astype(np.int32).reshape(-1, 1, 2)
    cv2.polylines(mask, [pts], False, 0, 1, cv2.LINE_8, _SHIFT)
    on_row, on_col = np.flatnonzero(mask.min(axis=1) == 0), np.flatnonzero(mask.min(axis=0) == 0)
    if len(on_row) == 0:  # polyline outside the image
        return None
    dist = cv2.distanceTransform(mask, cv2.DIST_L2, cv2.DIST_MASK_PRECISE)
    pad = int(math.ceil(reach_px)) + 1
    window = (slice(max(int(on_row[0]) - pad, 0), min(int(on_row[-1]) + pad + 1, rows)),
              slice(max(int(on_col[0]) - pad, 0), min(int(on_col[-1]) + pad + 1, cols)))
    direction = uv[-1] - uv[0]
    norm = float(np.hypot(*direction))
    direction = direction / norm if norm > 0 else np.array([1.0, 0.0])
    u = (np.arange(cols, dtype=np.float32) - np.float32(uv[0, 0]))[window[1]]
    v = (np.arange(rows, dtype=np.float32) - np.float32(uv[0, 1]))[window[0]]
    along = v[:, None] * np.float32(direction[1]) + u[None, :] * np.float32(direction[0])
    return dist[window], along, window


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
        out += 0.55 ** k * cv2.resize(grid, (cols, rows), interpolation=cv2.INTER_CUBIC)
    return out / max(float(out.std()), 1e-6)


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
