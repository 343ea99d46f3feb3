"""A pinhole camera fixed to the vehicle body, and its mapping to and from a ground plane.

Shared by the rear trace camera (:mod:`slipenv.sensors.trace_camera`, which renders with the
*true* mount) and the FTrace detector (:mod:`slipenv.estimators.reina`, which back-projects with
the *nominal* one), so it lives with the contracts. Frames: body x forward, y left, z up (REP 103);
the camera optical frame has z along the viewing ray, x along image columns, y along image rows.
The ground is modelled as the body-frame plane ``z_b = ground_z_m`` (the chassis rests on the
terrain, so the local ground is parallel to the body x-y plane).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

# Nadir view with image "up" = body forward: columns point to body -y, rows to body -x.
NADIR_R_BODY_CAM = np.array([[0.0, -1.0, 0.0], [-1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def rotation_rpy(roll_rad: float, pitch_rad: float, yaw_rad: float) -> np.ndarray:
    """Rotation matrix R = Rz(yaw) Ry(pitch) Rx(roll) (REP 103 fixed-axis roll-pitch-yaw)."""
    cr, sr = math.cos(roll_rad), math.sin(roll_rad)
    cp, sp = math.cos(pitch_rad), math.sin(pitch_rad)
    cy, sy = math.cos(yaw_rad), math.sin(yaw_rad)
    return np.array([
        [cy * cp, cy * sp * sr - sy * cr, cy * sp * cr + sy * sr],
        [sy * cp, sy * sp * sr + cy * cr, sy * sp * cr - cy * sr],
        [-sp, cp * sr, cp * cr],
    ])


@dataclass(frozen=True)
class PinholeCamera:
    """Intrinsics and body-frame mount of a pinhole camera.

    Attributes
    ----------
    width_px, height_px : int
        Image size [px].
    fx_px, fy_px : float
        Focal lengths [px].
    cx_px, cy_px : float
        Principal point [px] (column, row).
    position_m : tuple[float, float, float]
        Optical centre in the body frame [m].
    tilt_rpy_rad : tuple[float, float, float]
        Body-frame roll, pitch, yaw applied on top of the nadir orientation [rad] (zero: looking
        straight down, image up = body forward).
    """

    width_px: int
    height_px: int
    fx_px: float
    fy_px: float
    cx_px: float
    cy_px: float
    position_m: tuple[float, float, float]
    tilt_rpy_rad: tuple[float, float, float] = (0.0, 0.0, 0.0)

    def __post_init__(self) -> None:
        for name in ("width_px", "height_px"):
            value = getattr(self, name)
            if int(value) != value or value < 8:
                raise ValueError(f"PinholeCamera.{name} must be an integer >= 8, got {value!r}")
        for name in ("fx_px", "fy_px"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"PinholeCamera.{name} must be finite and > 0, got {value!r}")
        for name in ("cx_px", "cy_px"):
            if not math.isfinite(getattr(self, name)):
                raise ValueError(f"PinholeCamera.{name} must be finite")
        for name in ("position_m", "tilt_rpy_rad"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.shape != (3,) or not np.all(np.isfinite(value)):
                raise ValueError(f"PinholeCamera.{name} must be 3 finite numbers, got {value!r}")

    @property
    def shape(self) -> tuple[int, int]:
        """Image shape (rows, columns)."""
        return int(self.height_px), int(self.width_px)

    @property
    def r_body_cam(self) -> np.ndarray:
        """Rotation from the optical frame to the body frame, shape (3, 3)."""
        return rotation_rpy(*self.tilt_rpy_rad) @ NADIR_R_BODY_CAM

    def with_tilt(self, tilt_rpy_rad: ArrayLike) -> PinholeCamera:
        """The same camera with another mount tilt (e.g. a calibration error)."""
        roll, pitch, yaw = (float(v) for v in np.asarray(tilt_rpy_rad, dtype=float))
        return PinholeCamera(self.width_px, self.height_px, self.fx_px, self.fy_px, self.cx_px,
                             self.cy_px, self.position_m, (roll, pitch, yaw))

    def project(self, points_body_m: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
        """Project body-frame points, shape (n, 3), to pixels.

        Returns
        -------
        uv_px : np.ndarray, shape (n, 2)
            (column, row) [px]; NaN for points behind the camera.
        depth_m : np.ndarray, shape (n,)
            Distance along the optical axis [m].
        """
        p = np.atleast_2d(np.asarray(points_body_m, dtype=float))
        pc = (p - np.asarray(self.position_m)) @ self.r_body_cam  # R^T (p - c), row-wise
        z = pc[:, 2]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.where(z > 1e-6, self.fx_px * pc[:, 0] / z + self.cx_px, np.nan)
            v = np.where(z > 1e-6, self.fy_px * pc[:, 1] / z + self.cy_px, np.nan)
        return np.column_stack([u, v]), z

    def ground_to_image(self, xy_body_m: ArrayLike, ground_z_m: float) -> np.ndarray:
        """Pixels (column, row) of ground points (x_b, y_b) on the plane z_b = ``ground_z_m``."""
        xy = np.atleast_2d(np.asarray(xy_body_m, dtype=float))
        pts = np.column_stack([xy, np.full(len(xy), float(ground_z_m))])
        return self.project(pts)[0]

    def image_to_ground(self, uv_px: ArrayLike, ground_z_m: float) -> np.ndarray:
        """Back-project pixels (column, row), shape (n, 2), to body ``(x_b, y_b)`` on the ground.

        Rays that do not hit the plane in front of the camera give NaN.
        """
        uv = np.atleast_2d(np.asarray(uv_px, dtype=float))
        rays = np.column_stack([(uv[:, 0] - self.cx_px) / self.fx_px,
                                (uv[:, 1] - self.cy_px) / self.fy_px, np.ones(len(uv))])
        d = rays @ self.r_body_cam.T
        c = np.asarray(self.position_m, dtype=float)
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (float(ground_z_m) - c[2]) / d[:, 2]
        t = np.where(t > 0.0, t, np.nan)
        return c[:2] + t[:, None] * d[:, :2]


def downward_camera(
    footprint_center_xy_m: tuple[float, float],
    height_m: float,
    ground_z_m: float,
    footprint_m: tuple[float, float] = (0.60, 0.80),
    shape_px: tuple[int, int] = (240, 320),
) -> PinholeCamera:
    """A nadir camera whose image covers ``footprint_m`` (length along x, width along y).

    Parameters
    ----------
    footprint_center_xy_m : tuple of float
        Body-frame centre of the ground footprint [m].
    height_m : float
        Height of the optical centre above the ground plane [m].
    ground_z_m : float
        Body-frame height of the ground plane [m].
    footprint_m : tuple of float
        Ground length (body x, image rows) and width (body y, image columns) covered [m].
    shape_px : tuple of int
        Image (rows, columns).
    """
    if not (math.isfinite(height_m) and height_m > 0.0):
        raise ValueError(f"height_m must be finite and > 0, got {height_m!r}")
    length, width = (float(v) for v in footprint_m)
    if not (length > 0.0 and width > 0.0):
        raise ValueError(f"footprint_m must be two positive lengths, got {footprint_m!r}")
    rows, cols = (int(v) for v in shape_px)
    return PinholeCamera(
        width_px=cols, height_px=rows,
        fx_px=cols * height_m / width, fy_px=rows * height_m / length,
        cx_px=(cols - 1) / 2.0, cy_px=(rows - 1) / 2.0,
        position_m=(float(footprint_center_xy_m[0]), float(footprint_center_xy_m[1]),
                    float(ground_z_m) + float(height_m)),
    )
