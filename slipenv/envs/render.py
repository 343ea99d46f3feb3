"""The ``rgb_array`` frame: a top-down map a person can read, drawn straight into an array.

PyBullet's TinyRenderer does not show debug lines, and a chase-camera image of a vehicle on
uniform soil says little about path following. The frame is a north-up map instead: soil
background with a 1 m grid, the reference path, the vehicle's true trace, the estimator's
trace, and the vehicle's chassis outline at its true pose. Pure numpy: no display and no
plotting library needed. Envs with the rear trace camera add :func:`render_camera_panel`
beside the map: the last camera frame with FTrace's detected trace.
"""

from __future__ import annotations

import math

import cv2
import numpy as np

from slipenv.contracts.camera import PinholeCamera

FRAME_HW = (480, 640)  # frame height, width [px]
BACKGROUND = (200, 182, 148)  # soil
GRID = (184, 166, 132)
PATH_RGB = (30, 80, 220)  # blue: the reference path
TRUE_RGB = (210, 30, 30)  # red: where the vehicle really went
ESTIMATE_RGB = (240, 150, 0)  # orange: where the estimator thinks it went
VEHICLE_RGB = (20, 20, 20)
MARGIN_M = 1.0  # [m] around the path in view
DETECTED_RGB = (40, 220, 40)  # green: the trace FTrace detected
HELD_RGB = (240, 200, 0)  # yellow: the trace FTrace holds from an earlier frame


class MapView:
    """World (x east, y north) [m] to pixel (row, column) for a fixed extent."""

    def __init__(self, xy_extent: np.ndarray, frame_hw: tuple[int, int] = FRAME_HW) -> None:
        h, w = frame_hw
        lo = xy_extent.min(axis=0) - MARGIN_M
        hi = xy_extent.max(axis=0) + MARGIN_M
        self.scale = min((w - 1) / (hi[0] - lo[0]), (h - 1) / (hi[1] - lo[1]))  # [px/m]
        centre = 0.5 * (lo + hi)
        self.origin = centre - 0.5 * np.array([w - 1, h - 1]) / self.scale
        self.hw = (h, w)

    def to_px(self, xy: np.ndarray) -> np.ndarray:
        """Pixel (column, row) of world points, shape (n, 2), as floats."""
        col = (xy[:, 0] - self.origin[0]) * self.scale
        row = (self.hw[0] - 1) - (xy[:, 1] - self.origin[1]) * self.scale
        return np.stack([col, row], axis=1)


def blank_frame(view: MapView) -> np.ndarray:
    """Soil background with grid lines every metre."""
    h, w = view.hw
    frame = np.empty((h, w, 3), dtype=np.uint8)
    frame[:] = BACKGROUND
    x0, y0 = view.origin
    x1, y1 = x0 + (w - 1) / view.scale, y0 + (h - 1) / view.scale
    if view.scale >= 4.0:  # grid lines closer than 4 px would only darken the frame
        for gx in np.arange(math.ceil(x0), math.floor(x1) + 1):
            col = int(round((gx - x0) * view.scale))
            frame[:, col] = GRID
        for gy in np.arange(math.ceil(y0), math.floor(y1) + 1):
            row = int(round((h - 1) - (gy - y0) * view.scale))
            frame[row, :] = GRID
    return frame


def draw_polyline(frame: np.ndarray, px: np.ndarray, rgb, width_px: int = 2) -> None:
    """Draw the polyline through pixel points ``px`` (n, 2) with square pens of ``width_px``."""
    if len(px) == 0:
        return
    if len(px) == 1:
        pts = px
    else:
        seg = np.diff(px, axis=0)
        steps = np.maximum(np.ceil(np.abs(seg).max(axis=1) * 2.0), 1).astype(int)
        steps = np.minimum(steps, 4000)  # a wild point off screen must not cost millions
        t = np.concatenate([np.arange(k) / k for k in steps])
        start = np.repeat(px[:-1], steps, axis=0)
        pts = np.concatenate([start + np.repeat(seg, steps, axis=0) * t[:, None], px[-1:]])
    h, w = frame.shape[:2]
    cols = np.round(pts[:, 0]).astype(int)
    rows = np.round(pts[:, 1]).astype(int)
    half = width_px // 2
    for dr in range(-half, width_px - half):
        for dc in range(-half, width_px - half):
            r, c = rows + dr, cols + dc
            ok = (r >= 0) & (r < h) & (c >= 0) & (c < w)
            frame[r[ok], c[ok]] = rgb


def chassis_outline(x: float, y: float, yaw: float, length_m: float,
                    width_m: float) -> np.ndarray:
    """Closed outline of the chassis footprint plus a nose tick, world points (6, 2) [m]."""
    c, s = math.cos(yaw), math.sin(yaw)
    local = np.array([[-0.5, -0.5], [0.5, -0.5], [0.75, 0.0], [0.5, 0.5], [-0.5, 0.5],
                      [-0.5, -0.5]]) * np.array([length_m, width_m])
    rot = np.array([[c, -s], [s, c]])
    return local @ rot.T + np.array([x, y])


def render_map(path_xy: np.ndarray, true_xy: np.ndarray, estimate_xy: np.ndarray,
               pose: tuple[float, float, float], chassis_lw_m: tuple[float, float],
               frame_hw: tuple[int, int] = FRAME_HW) -> np.ndarray:
    """The frame: (H, W, 3) uint8, north up, the whole path in view.

    Parameters
    ----------
    path_xy, true_xy, estimate_xy : np.ndarray, shape (n, 2)
        Reference path samples, true trace and estimated trace [m].
    pose : tuple
        True (x [m], y [m], yaw [rad]) of the vehicle now.
    chassis_lw_m : tuple
        Chassis length and width [m].
    """
    x, y, yaw = pose
    extent = np.concatenate([path_xy, np.array([[x, y]])])
    view = MapView(extent, frame_hw)
    frame = blank_frame(view)
    draw_polyline(frame, view.to_px(path_xy), PATH_RGB, 3)
    draw_polyline(frame, view.to_px(estimate_xy), ESTIMATE_RGB, 2)
    draw_polyline(frame, view.to_px(true_xy), TRUE_RGB, 2)
    outline = chassis_outline(x, y, yaw, *chassis_lw_m)
    draw_polyline(frame, view.to_px(outline), VEHICLE_RGB, 2)
    return frame


def trace_line_px(camera: PinholeCamera, angle_rad: float, offset_m: float,
                  wheel_xy_m: tuple[float, float], ground_z_m: float,
                  length_m: float = 1.5) -> np.ndarray:
    """Image points (column, row), shape (2, 2), of a trace line on the ground.

    The line passes the wheel's contact x at lateral ``offset_m`` from the wheel-centre line
    and runs backwards at ``angle_rad`` (body ground plane, counter-clockwise from body x).
    """
    xw, yw = wheel_xy_m
    x1 = xw - length_m
    ground = np.array([[xw, yw + offset_m],
                       [x1, yw + offset_m + (x1 - xw) * math.tan(angle_rad)]])
    return camera.ground_to_image(ground, ground_z_m)


def render_camera_panel(image: np.ndarray | None, camera: PinholeCamera, detection,
                        ground_z_m: float, panel_hw: tuple[int, int],
                        wheel_xy_m: tuple[float, float] | None = None) -> np.ndarray:
    """The rear camera frame as an RGB panel of ``panel_hw`` with FTrace's trace drawn on it.

    Parameters
    ----------
    image : np.ndarray (rows, cols) uint8 or None
        The grey camera frame; None (no frame yet) gives a grey panel.
    camera : PinholeCamera
        The nominal camera model (draws the detected line where FTrace believes it is).
    detection : TraceDetection or None
        FTrace's answer (green if detected this frame, yellow if held, nothing if none).
    ground_z_m : float
        Body-frame ground height [m].
    panel_hw : tuple of int
        Panel height and width [px].
    wheel_xy_m : tuple of float, optional
        Contact point of the watched wheel in the body frame [m] (default: the camera's
        ``wheel_xy_m`` if it has one, else FTrace's default).
    """
    h, w = panel_hw
    if image is None:
        return np.full((h, w, 3), 96, np.uint8)
    rgb = cv2.cvtColor(image, cv2.COLOR_GRAY2RGB)
    if detection is not None and getattr(detection, "found", False):
        xy = wheel_xy_m if wheel_xy_m is not None else (-0.30, 0.25)
        uv = trace_line_px(camera, detection.angle_rad, detection.offset_m, xy, ground_z_m)
        if np.all(np.isfinite(uv)):
            colour = DETECTED_RGB if detection.status == "detected" else HELD_RGB
            a, b = (tuple(int(round(v)) for v in pt) for pt in uv)
            cv2.line(rgb, a, b, colour, 2, cv2.LINE_AA)
    return cv2.resize(rgb, (w, h), interpolation=cv2.INTER_LINEAR)
