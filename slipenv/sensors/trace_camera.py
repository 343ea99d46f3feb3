"""Rear trace camera: a 5 Hz grey image of the ground behind the rear-left wheel (Reina §2, §4).

The image is rasterised from the wheels' true contact history (physics-notes §3, option A):
each trace becomes a rut in a height map (floor at the sinkage depth, walls at ± half the wheel
width, low berms outside, grouser grooves at the grouser pitch), the height map is shaded by a sun
at a fixed world azimuth (Lambert + ambient), multiplied by a sand albedo with fBm texture, then
the nuisances are added from the seeded generator: an old trace crossing the view, a cast shadow,
a soil-patch boundary, blur, sensor noise, and a fixed extrinsic calibration error of the mount
(drawn once per camera). Reina's camera sees 60 cm (along the rover) × 80 cm (across) at 5 Hz.

The truth returned with each frame (trace present, its angle and lateral offset in the body
frame) comes from the contact points, not from the image, so it scores the detector.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field

import cv2
import numpy as np
from numpy.typing import ArrayLike

from slipenv.contracts.camera import PinholeCamera, downward_camera, rotation_rpy
from slipenv.sensors.trace_history import ContactHistory, WheelTrack
from slipenv.sensors.trace_raster import (
    fbm_noise,
    polyline_distance_px,
    polyline_distance_window,
    rut_height,
    soft_halfplane,
)


@dataclass(frozen=True)
class TraceCameraConfig:
    """Mount, scene and nuisance parameters of the rear trace camera.

    Attributes
    ----------
    wheel_name : str
        The wheel whose trace is measured (Reina: rear left).
    wheel_xy_m : tuple of float
        That wheel's contact point in the body frame [m] (``rover_4ws``: (-0.30, 0.25)).
    wheel_radius_m, wheel_width_m : float
        Wheel radius (sets the body-frame ground height ``-r``) and width (rut width) [m].
    footprint_m : tuple of float
        Ground seen: length along body x, width along body y [m] (Reina: 0.60 × 0.80).
    gap_m : float
        Distance from the contact point back to the near edge of the footprint [m].
    camera_height_m : float
        Optical centre above the ground [m] (assumed; sets the focal length for the footprint).
    shape_px : tuple of int
        Image rows, columns.
    rate_hz : float
        Frame rate [Hz] (Reina: 5).
    grouser_pitch_m : float
        Spacing of the grouser marks [m] (assumed 12 grousers on a 9 cm wheel: 2πr/12).
    sun_azimuth_rad, sun_elevation_rad : float
        Sun direction in the world (azimuth counter-clockwise from world x) [rad].
    calibration_error_deg : float
        Bound of the uniform extrinsic error per axis (roll, pitch, yaw) [deg].
    p_old_trace, p_shadow, p_patch : float
        Per-frame probabilities of an old crossing trace, a cast shadow, a soil-patch boundary.
    blur_sigma_px : tuple of float
        Range of the Gaussian blur (defocus, motion) [px].
    noise_std : float
        Sensor noise [grey levels].
    min_visible_m : float
        Trace length inside the footprint for the truth to count as "trace present" [m].
    """

    wheel_name: str = "rear_left"
    wheel_xy_m: tuple[float, float] = (-0.30, 0.25)
    wheel_radius_m: float = 0.09
    wheel_width_m: float = 0.08
    footprint_m: tuple[float, float] = (0.60, 0.80)
    gap_m: float = 0.02
    camera_height_m: float = 0.50
    shape_px: tuple[int, int] = (240, 320)
    rate_hz: float = 5.0
    grouser_pitch_m: float = 2.0 * math.pi * 0.09 / 12.0
    sun_azimuth_rad: float = 2.3
    sun_elevation_rad: float = 0.6
    calibration_error_deg: float = 0.75
    p_old_trace: float = 0.3
    p_shadow: float = 0.3
    p_patch: float = 0.2
    blur_sigma_px: tuple[float, float] = (0.6, 1.6)
    noise_std: float = 3.0
    min_visible_m: float = 0.15

    def __post_init__(self) -> None:
        positive = ("wheel_radius_m", "wheel_width_m", "camera_height_m", "rate_hz",
                    "grouser_pitch_m", "sun_elevation_rad", "min_visible_m")
        for name in positive:
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"TraceCameraConfig.{name} must be finite and > 0, got {value!r}")
        for name in ("gap_m", "calibration_error_deg", "noise_std"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"TraceCameraConfig.{name} must be finite and >= 0, got {value!r}")
        for name in ("p_old_trace", "p_shadow", "p_patch"):
            value = getattr(self, name)
            if not 0.0 <= value <= 1.0:
                raise ValueError(f"TraceCameraConfig.{name} must be in [0, 1], got {value!r}")
        lo, hi = self.blur_sigma_px
        if not 0.0 <= lo <= hi:
            raise ValueError(f"TraceCameraConfig.blur_sigma_px must be 0 <= lo <= hi, got "
                             f"{self.blur_sigma_px!r}")
        if min(self.footprint_m) <= 0.0 or min(self.shape_px) < 16:
            raise ValueError("TraceCameraConfig.footprint_m must be > 0 and shape_px >= 16")

    @property
    def ground_z_m(self) -> float:
        """Body-frame height of the ground plane [m] (wheel centres at z = 0)."""
        return -self.wheel_radius_m

    def nominal_camera(self) -> PinholeCamera:
        """The camera model the detector believes in (no calibration error)."""
        cx = self.wheel_xy_m[0] - self.gap_m - 0.5 * self.footprint_m[0]
        return downward_camera((cx, self.wheel_xy_m[1]), self.camera_height_m, self.ground_z_m,
                               self.footprint_m, self.shape_px)


@dataclass(frozen=True, eq=False)
class TraceFrame:
    """One camera frame and the truth to score a detector against.

    Attributes
    ----------
    image : np.ndarray, shape (rows, cols), uint8
        Grey image.
    t_s : float
        Time stamp [s].
    trace_present : bool
        At least ``min_visible_m`` of the measured wheel's trace lies in the footprint.
    trace_angle_rad : float
        True trace angle in the body ground plane: direction of the trace towards the wheel,
        counter-clockwise from body x [rad]; equals the body slip angle of the wheel's velocity
        on a straight crab. NaN if no trace is present.
    trace_offset_m : float
        True lateral offset of the trace line at the contact point's x, relative to the
        wheel-centre line (body y) [m]. NaN if no trace is present.
    nuisances : dict
        What was drawn this frame (``old_trace``, ``shadow``, ``patch``, ``blur_sigma_px``,
        ``second_imprint``).
    """

    image: np.ndarray
    t_s: float
    trace_present: bool
    trace_angle_rad: float
    trace_offset_m: float
    nuisances: dict = field(default_factory=dict)


class TraceCamera:
    """The rear trace camera: ``measure(history, pose, rng) -> TraceFrame``.

    Parameters
    ----------
    config : TraceCameraConfig
        Mount, scene and nuisances.
    calibration_rng : np.random.Generator or None
        Draws the fixed extrinsic calibration error (uniform within ±``calibration_error_deg``
        per axis); ``None`` mounts the camera exactly as calibrated.
    """

    def __init__(self, config: TraceCameraConfig | None = None,
                 calibration_rng: np.random.Generator | None = None) -> None:
        self.config = config or TraceCameraConfig()
        self.camera = self.config.nominal_camera()
        error = np.zeros(3)
        if calibration_rng is not None:
            bound = math.radians(self.config.calibration_error_deg)
            error = calibration_rng.uniform(-bound, bound, 3)
        self.calibration_error_rad = error
        self.true_camera = self.camera.with_tilt(error)
        self._last_t: float | None = None
        rows, cols = self.camera.shape
        # The ground under the true camera, per pixel: sets the metric scale of the raster.
        centre = np.array([[cols / 2.0, rows / 2.0], [cols / 2.0 + 1, rows / 2.0],
                           [cols / 2.0, rows / 2.0 + 1]])
        g = self.true_camera.image_to_ground(centre, self.config.ground_z_m)
        self._e_u, self._e_v = g[1] - g[0], g[2] - g[0]
        area = self._e_u[0] * self._e_v[1] - self._e_u[1] * self._e_v[0]  # pixel on the ground
        self.m_per_px = float(np.sqrt(abs(area)))

    @property
    def period_s(self) -> float:
        """Time between frames [s]."""
        return 1.0 / self.config.rate_hz

    def due(self, t_s: float) -> bool:
        """Whether a frame is due at ``t_s`` (the first call is always due)."""
        return self._last_t is None or t_s >= self._last_t + self.period_s - 1e-9

    def reset(self) -> None:
        """Forget the last frame time (new episode)."""
        self._last_t = None

    def measure(self, history: ContactHistory | Sequence[WheelTrack], pose: ArrayLike,
                rng: np.random.Generator, t_s: float = 0.0) -> TraceFrame:
        """Render the frame seen from chassis ``pose`` and the truth to score it.

        Parameters
        ----------
        history : ContactHistory or sequence of WheelTrack
            The wheels' world-frame traces.
        pose : array_like, shape (6,)
            Chassis x, y, z [m] and roll, pitch, yaw [rad] in the world.
        rng : np.random.Generator
            Source of every nuisance draw.
        t_s : float
            Time stamp [s].
        """
        cfg = self.config
        tracks = history.tracks() if isinstance(history, ContactHistory) else tuple(history)
        if not all(isinstance(tr, WheelTrack) for tr in tracks):
            raise ValueError("history must be a ContactHistory or a sequence of WheelTrack")
        pose_arr = np.asarray(pose, dtype=float)
        if pose_arr.shape != (6,) or not np.all(np.isfinite(pose_arr)):
            raise ValueError(f"pose must be 6 finite numbers (x, y, z, roll, pitch, yaw), got "
                             f"{pose_arr!r}")
        if not isinstance(rng, np.random.Generator):
            raise ValueError(f"rng must be a numpy Generator, got {type(rng).__name__}")
        if not math.isfinite(t_s):
            raise ValueError(f"t_s must be finite, got {t_s!r}")
        r_wb = rotation_rpy(*pose_arr[3:])
        body = [(tr, (tr.points_m - pose_arr[:3]) @ r_wb) for tr in tracks]
        rows, cols = self.camera.shape
        ground_z = cfg.ground_z_m
        height = np.zeros((rows, cols), np.float32)
        floor = np.zeros((rows, cols), bool)
        nuisances: dict = {"old_trace": False, "shadow": False, "patch": False}
        if rng.random() < cfg.p_old_trace:
            nuisances["old_trace"] = True
            self._draw_old_trace(height, floor, rng)
        # The measured wheel rolls last: its rut overwrites older ones where they overlap.
        body.sort(key=lambda item: item[0].name == cfg.wheel_name)
        nuisances["second_imprint"] = False
        for tr, pts in body:
            uv = self.true_camera.ground_to_image(pts[:, :2], ground_z)
            inside = ((uv[:, 0] > -60) & (uv[:, 0] < cols + 60) & (uv[:, 1] > -60)
                      & (uv[:, 1] < rows + 60))
            if inside.sum() < 2:
                continue
            if tr.name != cfg.wheel_name:
                nuisances["second_imprint"] = True
            depth = float(np.mean(tr.depth_m[inside]))
            px_per_half_width = np.float32(self.m_per_px / (0.5 * tr.width_m))
            # Only the rut and its berms (q < 1.9) change the ground: draw on the window of
            # the image they can reach (1 px of margin against the float32 rounding of q).
            near = polyline_distance_window(uv, (rows, cols),
                                            1.9 / float(px_per_half_width) + 1.0)
            phase = rng.uniform(0, 2 * np.pi)
            if near is None:  # the trace misses the image
                continue
            dist_px, along_px, window = near
            q = dist_px * px_per_half_width
            band = q < 1.9
            q_b = q[band]
            grooves = (0.5 + 0.5 * np.cos(along_px[band] * np.float32(
                2.0 * np.pi * self.m_per_px / cfg.grouser_pitch_m) + np.float32(phase))) ** 8
            rut, in_rut = rut_height(q_b, depth, grooves)
            height_w, floor_w = height[window], floor[window]  # views: writes reach the image
            old = height_w[band]
            height_w[band] = np.where(in_rut, rut, old + rut)
            floor_w[band] |= q_b < 0.85
        image = self._shade(height, floor, pose_arr[5], rng, nuisances)
        self._last_t = float(t_s)
        present, angle, offset = self._truth(body)
        return TraceFrame(image, float(t_s), present, angle, offset, nuisances)

    # -- rendering -------------------------------------------------------------------------
    def _draw_old_trace(self, height: np.ndarray, floor: np.ndarray,
                        rng: np.random.Generator) -> None:
        """An eroded rut from an earlier pass, straight, at any angle through the view."""
        rows, cols = height.shape
        angle = rng.uniform(0.0, np.pi)
        centre = np.array([rng.uniform(0.2, 0.8) * cols, rng.uniform(0.2, 0.8) * rows])
        reach = 2.0 * (rows + cols)
        ends = centre + np.outer([-reach, reach], [np.cos(angle), np.sin(angle)])
        dist_px, _ = polyline_distance_px(ends, (rows, cols))
        q = dist_px * (self.m_per_px / (0.5 * self.config.wheel_width_m))
        depth = rng.uniform(0.3, 0.7) * 0.01
        rut, _ = rut_height(q, depth, np.zeros_like(q))
        height += cv2.GaussianBlur(rut, (0, 0), 2.0)  # eroded: soft walls
        floor |= q < 0.7

    def _shade(self, height: np.ndarray, floor: np.ndarray, yaw_rad: float,
               rng: np.random.Generator, nuisances: dict) -> np.ndarray:
        cfg = self.config
        rows, cols = height.shape
        az_b = cfg.sun_azimuth_rad - yaw_rad
        s_h = math.cos(cfg.sun_elevation_rad)
        sun_b = s_h * np.array([math.cos(az_b), math.sin(az_b)])
        e_u = self._e_u / np.linalg.norm(self._e_u)
        e_v = self._e_v / np.linalg.norm(self._e_v)
        s_u, s_v, s_z = float(sun_b @ e_u), float(sun_b @ e_v), math.sin(cfg.sun_elevation_rad)
        sun = (np.float32(s_u), np.float32(s_v), np.float32(s_z))
        light = self._sunlight(height, sun)
        # albedo = 0.55 + 0.10 fbm - 0.08 floor, in float32, on one array: 0.10 fbm + 0.55 is
        # the same sum, and off the rut floor 0.08 * False = 0 leaves the value as it is (a
        # full frame per operation saved: the camera's cost per frame)
        albedo = fbm_noise((rows, cols), rng)
        albedo *= np.float32(0.10)
        albedo += np.float32(0.55)
        np.subtract(albedo, np.float32(0.08), out=albedo, where=floor)
        if rng.random() < cfg.p_patch:
            nuisances["patch"] = True
            albedo = albedo + rng.choice([-1.0, 1.0]) * rng.uniform(0.05, 0.12) * soft_halfplane(
                (rows, cols), rng, softness_px=rng.uniform(4.0, 15.0))
        if rng.random() < cfg.p_shadow:
            nuisances["shadow"] = True
            shade = soft_halfplane((rows, cols), rng, softness_px=rng.uniform(1.5, 5.0))
            light = light * (1.0 - rng.uniform(0.3, 0.55) * shade)
        grey: np.ndarray = np.float32(255.0 * 0.85) * albedo
        grey *= light
        sigma = rng.uniform(*cfg.blur_sigma_px)
        nuisances["blur_sigma_px"] = float(sigma)
        if sigma > 0.0:
            grey = cv2.GaussianBlur(grey.astype(np.float32, copy=False), (0, 0), sigma)
        noise = rng.standard_normal((rows, cols), np.float32)
        noise *= np.float32(cfg.noise_std)
        if grey.dtype == np.float32:  # (a float64 grey, unblurred, must not round to float32)
            noise += grey  # grey + noise: the same float32 sums, written into the noise frame
            grey = noise
        else:
            grey = grey + noise
        return np.clip(grey, 0, 255, out=grey).astype(np.uint8)

    def _sunlight(self, height: np.ndarray, sun: tuple[np.float32, np.float32, np.float32]
                  ) -> np.ndarray:
        """Ambient + Lambert light of the height map under the sun (body-image axes u, v, z).

        Flat ground (zero height gradient) gets one value, so only the window around the ruts
        (the nonzero height, 2 px wider for the gradient's stencil) is computed per pixel; the
        rest is the same expression evaluated on flat ground, so the image is bit for bit the
        whole-image computation at a fraction of the camera's cost per frame.
        """
        rows, cols = height.shape
        light = np.full((rows, cols), _lambert_light(np.zeros((1, 1), np.float32),
                                                     np.zeros((1, 1), np.float32), sun)[0, 0])
        # the box of the nonzero height (OpenCV's bounding box of the nonzero mask: one pass
        # over the frame instead of two reductions)
        col0, row0, width, box_rows = cv2.boundingRect((height != 0).view(np.uint8))
        if width == 0:
            return light
        # Outside the nonzero height dilated by 1 px the gradient is exactly 0. np.gradient is
        # central inside the window and one-sided on its border, which is either the image's
        # own border (one-sided there too) or 2 px from any nonzero height (0 either way).
        window = (slice(max(row0 - 2, 0), min(row0 + box_rows + 2, rows)),
                  slice(max(col0 - 2, 0), min(col0 + width + 2, cols)))
        h_v, h_u = np.gradient(height[window], np.float32(self.m_per_px))
        light[window] = _lambert_light(h_u, h_v, sun)
        return light

    # -- truth ------------------------------------------------------------------------------
    def _truth(self, body: list[tuple[WheelTrack, np.ndarray]]) -> tuple[bool, float, float]:
        """Trace present, its angle and offset, from the contact points in the footprint."""
        cfg = self.config
        xw, yw = cfg.wheel_xy_m
        length, width = cfg.footprint_m
        for tr, pts in body:
            if tr.name != cfg.wheel_name:
                continue
            x, y = pts[:, 0], pts[:, 1]
            sel = (x <= xw - cfg.gap_m) & (x >= xw - cfg.gap_m - length) & \
                (np.abs(y - yw) <= 0.5 * width)
            if sel.sum() < 3:
                return False, math.nan, math.nan
            xy = pts[sel, :2]
            if np.sum(np.hypot(*np.diff(xy, axis=0).T)) < cfg.min_visible_m:
                return False, math.nan, math.nan
            mean = xy.mean(axis=0)
            _, _, vt = np.linalg.svd(xy - mean, full_matrices=False)
            direction = vt[0] if vt[0, 0] >= 0.0 else -vt[0]
            angle = math.atan2(direction[1], direction[0])
            offset = mean[1] + (xw - mean[0]) * math.tan(angle) - yw
            return True, angle, float(offset)
        return False, math.nan, math.nan


def _lambert_light(h_u: np.ndarray, h_v: np.ndarray,
                   sun: tuple[np.float32, np.float32, np.float32]) -> np.ndarray:
    """Light factor (0.35 ambient + 0.65 Lambert, 1 on flat ground in the sun) per pixel from
    the height gradient [m/m] along the image axes and the sun direction (u, v, z), float32."""
    s_u, s_v, s_z = sun
    lambert = (s_z - h_u * s_u - h_v * s_v) / np.sqrt(1.0 + h_u * h_u + h_v * h_v)
    return np.float32(0.35) + np.float32(0.65 / s_z) * np.maximum(lambert, np.float32(0.0))
