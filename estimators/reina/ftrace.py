"""FTrace: the wheel trace and the slip angle from a rear camera image (Reina §2, Eq. 1-2).

Pipeline per frame: region of interest from the last trace → Gaussian blur → Canny →
probabilistic Hough (OpenCV) → segments back-projected to the ground plane with the nominal
camera model → merged into rut edges → candidates (an edge with its opposite edge at about the
wheel width, or a lone edge) → fuzzy confidence (:mod:`.fuzzy`) → best candidate above the
threshold → its straight line refined on the edge pixels within a narrow band of its walls
(:func:`~.trace_lines.refine_angle`) and its rut edges followed along the
ground (:func:`~.trace_lines.follow_trace`), once in that narrow band for the line of the
whole visible trace and once in a wider one for the near field; a trace followed over less
than ``min_trace_m`` is not reported; otherwise the last trace is kept for at most
``max_hold_frames`` frames (Reina §4.1: never more than 3 in a row) → slip angle (Eq. 1-2)
from the trace near the wheel.

Reina's trace model is a straight line, "under the assumption that the portion of the trace in
the camera image, and the amount of sideslip between two consecutive images, is relatively
small" (§2.1), and θ_t of Eq. 1-2 is the angle of the rear wheel's velocity V_r (Fig. 3). The
camera sees the last 0.6 m of trace, about 7 s of travel at 8 cm/s; on mounds the slip angle
swings within that time and the visible trace bends. Two angles are therefore reported: the
trace line (``angle_rad``: the least-squares line of the visible trace, Reina's straight-line
model, which the continuity rule and the region of interest track; fitted to the walls
followed along the bend, since a straight band keeps only the straightest piece of a bending
rut and, where the rover crabs, the front wheel's older rut beside it) and the near-field angle
(``near_angle_rad``: the straight-band line plus the bend, the near-field line over the last
``near_field_m`` of trace minus the straight-band line, averaged over a few frames), the
direction V_r had about 1.5 s ago, which gives the slip angle. On a straight trace the two
agree.

Angles are in the body ground plane, counter-clockwise from body x; the trace angle is the
direction of the trace towards the wheel, so on a straight crab it equals the slip angle.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import cv2
import numpy as np

from slipenv.contracts.camera import PinholeCamera

from .fuzzy import FuzzyTraceRules
from .trace_lines import (
    STRIP_M,
    TraceCurve,
    candidates_from_segments,
    edge_points_ground,
    follow_trace,
    refine_angle,
    segments_to_ground,
)


def slip_angle_from_trace(trace_angle_rad: float, yaw_rate_rps: float = 0.0,
                          speed_x_mps: float = math.nan, rear_to_cg_m: float = 0.0,
                          min_speed_mps: float = 0.01) -> float:
    """Body slip angle β from the rear trace angle (Reina Eq. 1-2, without linearising).

    The rear wheel moves at V_y - r b sideways (b: rear axle to centre of mass), so the
    body-frame trace angle θ satisfies tan θ = (V_y - r b)/V_x and β = atan(V_y/V_x) =
    atan(tan θ + r b / V_x); for small angles this is Eq. 2, β = α_r - δ_r + b/R_t with
    R_t = V_x/r, where the body-frame trace angle θ is Eq. 2's α_r - δ_r (a camera on the
    body, not on the steered wheel). Below ``min_speed_mps`` (or with NaN speed) the turn term
    is dropped and β = θ (the paper: before the rover moves, the trace alone).

    Parameters
    ----------
    trace_angle_rad : float
        Body-frame trace angle θ [rad].
    yaw_rate_rps : float
        Rate of turn r [rad/s] (Reina: differentiated compass).
    speed_x_mps : float
        Longitudinal speed V_x [m/s].
    rear_to_cg_m : float
        b, distance from the rear axle forward to the centre of mass [m].
    """
    if not math.isfinite(trace_angle_rad):
        return math.nan
    if not (math.isfinite(speed_x_mps) and abs(speed_x_mps) >= min_speed_mps
            and math.isfinite(yaw_rate_rps)):
        return float(trace_angle_rad)
    return math.atan(math.tan(trace_angle_rad) + yaw_rate_rps * rear_to_cg_m / speed_x_mps)


@dataclass(frozen=True)
class FTraceConfig:
    """Trace model and detector settings.

    Attributes
    ----------
    wheel_xy_m : tuple of float
        Contact point of the tracked wheel in the body frame [m].
    wheel_width_m : float
        Wheel (rut) width b [m].
    ground_z_m : float
        Body-frame height of the ground plane used for back-projection [m].
    blur_sigma_px, canny_low, canny_high : float
        Pre-blur [px] and Canny hysteresis thresholds (L2 gradient) [grey levels/px].
    hough_threshold, min_line_px, max_gap_px : int
        ``cv2.HoughLinesP`` votes, minimum segment length and gap [px] (ρ 1 px, θ 0.5°).
    roi_half_width_m : float
        Half width of the ground band around the last trace searched in the next frame [m].
    initial_roi_angle_rad : float
        Half opening of the wedge from the contact point searched when no trace is held [rad].
    confidence_threshold : float
        Lowest fuzzy confidence accepted as a detection.
    max_hold_frames : int
        Frames the last trace is kept when nothing is detected (Reina: 3).
    near_field_m : float
        Length of the near-field line: the last ``near_field_m`` of the trace seen [m].
        0.2 m is 2.5 s of travel at 8 cm/s: on the mounds of Reina's test 2 the ideal
        near-field line of the true trace (with the 4 s yaw rate of Eq. 2) is off the
        1 s ground-truth slip angle by 1.88° / 1.82° / 1.89° / 2.06° / 2.25° r.m.s. for
        0.1 / 0.2 / 0.3 / 0.45 / 0.6 m.
    bend_smoothing_frames : float
        The bend (near-field angle minus line angle) is averaged over about this many frames
        (exponential filter of gain 1/(1 + n)): a short line is several times noisier than
        the whole trace's, and the bend changes over seconds.
    max_bend_rad : float
        Largest bend believed; beyond it the near-field line is taken to be pulled onto
        other edges and the line angle is used [rad].
    refine_band_m : float
        Half width of the band around a candidate's edge lines whose edge pixels fit its line
        [m] (see :func:`.trace_lines.refine_angle`).
    min_trace_m : float
        Shortest stretch of trace, followed along the ground, reported as a detection [m]:
        in the first seconds of a run the rut behind the wheel is shorter and gives no
        direction (a Hough line of 40 px is 0.1 m). 0.15 m is the rear camera's own length for
        a trace to be present (``TraceCameraConfig.min_visible_m``), set on Reina's test 1.
    rules : FuzzyTraceRules
        Memberships and rule outputs.
    """

    wheel_xy_m: tuple[float, float] = (-0.30, 0.25)
    wheel_width_m: float = 0.08
    ground_z_m: float = -0.09
    blur_sigma_px: float = 1.5
    canny_low: float = 25.0
    canny_high: float = 60.0
    hough_threshold: int = 30
    min_line_px: int = 40
    max_gap_px: int = 8
    roi_half_width_m: float = 0.10
    initial_roi_angle_rad: float = math.radians(40.0)
    confidence_threshold: float = 0.5
    max_hold_frames: int = 3
    near_field_m: float = 0.2
    bend_smoothing_frames: float = 3.0
    max_bend_rad: float = math.radians(6.0)
    refine_band_m: float = 0.004
    min_trace_m: float = 0.15
    rules: FuzzyTraceRules = field(default_factory=FuzzyTraceRules)

    def __post_init__(self) -> None:
        for name in ("wheel_width_m", "blur_sigma_px", "canny_low", "canny_high",
                     "roi_half_width_m", "initial_roi_angle_rad", "max_bend_rad",
                     "refine_band_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"FTraceConfig.{name} must be finite and > 0, got {value!r}")
        for name in ("near_field_m", "bend_smoothing_frames", "min_trace_m"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"FTraceConfig.{name} must be finite and >= 0, got {value!r}")
        if self.canny_low > self.canny_high:
            raise ValueError("FTraceConfig.canny_low must not exceed canny_high")
        for name in ("hough_threshold", "min_line_px", "max_gap_px", "max_hold_frames"):
            value = getattr(self, name)
            if int(value) != value or value < 0:
                raise ValueError(f"FTraceConfig.{name} must be an integer >= 0, got {value!r}")
        if not 0.0 < self.confidence_threshold <= 1.0:
            raise ValueError(f"FTraceConfig.confidence_threshold must be in (0, 1], got "
                             f"{self.confidence_threshold!r}")


@dataclass(frozen=True)
class TraceDetection:
    """FTrace's answer for one frame.

    Attributes
    ----------
    status : str
        ``"detected"`` (a candidate passed the threshold), ``"held"`` (nothing passed; the last
        trace is repeated) or ``"none"``.
    angle_rad : float
        Angle of the least-squares line of the visible trace in the body ground plane [rad]
        (NaN for ``"none"``).
    offset_m : float
        Lateral offset of the trace at the contact point's x from the wheel-centre line [m].
    confidence : float
        Fuzzy confidence of the chosen candidate (0 when none).
    slip_angle_rad : float
        Body slip angle from Eq. 1-2 with θ_t = ``near_angle_rad`` [rad] (NaN for ``"none"``).
    n_candidates : int
        Candidates scored this frame.
    near_angle_rad : float
        Near-field trace angle, θ_t of Eq. 1-2 [rad] (see the module notes); NaN when not
        given.
    """

    status: str
    angle_rad: float
    offset_m: float
    confidence: float
    slip_angle_rad: float
    n_candidates: int
    near_angle_rad: float = math.nan

    @property
    def found(self) -> bool:
        """Whether a trace is reported (detected or held)."""
        return self.status != "none"


class FTrace:
    """The FTrace detector with its state (last trace, hold count, region of interest).

    Parameters
    ----------
    camera : PinholeCamera
        The nominal camera model (intrinsics and body mount).
    config : FTraceConfig
        Trace model and detector settings.
    """

    def __init__(self, camera: PinholeCamera, config: FTraceConfig | None = None) -> None:
        self.camera, self.config = camera, config or FTraceConfig()
        # where the view lies on the ground, fixed by the camera model and the ground plane
        rows, cols = camera.shape
        z = self.config.ground_z_m
        corners = np.array([[0.0, 0.0], [cols, 0.0], [0.0, rows], [cols, rows]])
        # body x of the view's edge nearest the wheel, relative to the contact point [m]
        self._view_near_u = float(np.nanmax(camera.image_to_ground(corners, z)[:, 0])) \
            - self.config.wheel_xy_m[0]
        self._view_mid_x = float(camera.image_to_ground([[cols / 2.0, rows / 2.0]], z)[0, 0])
        self.reset()

    def reset(self) -> None:
        """Forget the last trace (new run)."""
        # (line angle, offset, near-field angle) of the last trace
        self.last: tuple[float, float, float] | None = None
        self.held_frames = 0
        self.bend_rad = 0.0  # smoothed near-field angle minus line angle
        self.last_edges: np.ndarray | None = None

    def update(self, image: np.ndarray, yaw_rate_rps: float = 0.0,
               speed_x_mps: float = math.nan, rear_to_cg_m: float = 0.0) -> TraceDetection:
        """Process one frame; see :func:`slip_angle_from_trace` for the optional inputs."""
        if not isinstance(image, np.ndarray) or image.dtype != np.uint8:
            raise ValueError(f"image must be a uint8 numpy array, got "
                             f"{getattr(image, 'dtype', type(image).__name__)}")
        if image.shape != self.camera.shape:
            raise ValueError(f"image must have shape {self.camera.shape} (rows, cols) of the "
                             f"camera model, got {image.shape}")
        cfg = self.config
        blurred = cv2.GaussianBlur(image, (0, 0), cfg.blur_sigma_px)
        edges = cv2.Canny(blurred, cfg.canny_low, cfg.canny_high, L2gradient=True)
        edges = cv2.bitwise_and(edges, self.roi_mask())
        self.last_edges = edges
        lines = cv2.HoughLinesP(edges, 1.0, math.pi / 360.0, cfg.hough_threshold,
                                minLineLength=cfg.min_line_px, maxLineGap=cfg.max_gap_px)
        segments = np.zeros((0, 4)) if lines is None else lines.reshape(-1, 4).astype(float)
        ground = segments_to_ground(segments, self.camera, cfg.ground_z_m)
        cands = candidates_from_segments(ground, cfg.wheel_xy_m, cfg.wheel_width_m)
        best, conf = -1, 0.0
        if len(cands.angle):
            x_mid = self._view_mid_x
            mid = cands.offset + (x_mid - cfg.wheel_xy_m[0]) * np.tan(cands.angle)
            scores = cfg.rules.confidence(
                cands.offset, mid, cands.angle,
                self.last[0] if self.last else None, cands.pair_mismatch, cands.length)
            best = int(np.argmax(scores))
            conf = float(scores[best])
        fit = None
        if best >= 0 and conf >= cfg.confidence_threshold:
            fit = self._fit_curve(blurred, edges, cands.edge_lines[best],
                                  float(cands.angle[best]))
            if fit[3] < cfg.min_trace_m:
                fit = None
        if fit is not None:
            angle, straight, near, _ = fit
            self.bend_rad += (near - straight - self.bend_rad) / (1.0 + cfg.bend_smoothing_frames)
            offset = float(cands.offset[best])
            self.last = (angle, offset, straight + self.bend_rad)
            self.held_frames, status = 0, "detected"
        elif self.last is not None and self.held_frames < cfg.max_hold_frames:
            self.held_frames += 1
            status = "held"
        else:
            self.last, self.held_frames, status = None, 0, "none"
            self.bend_rad = 0.0
        if self.last is None:
            return TraceDetection("none", math.nan, math.nan, conf, math.nan, len(cands.angle))
        angle, offset, near = self.last
        beta = slip_angle_from_trace(near, yaw_rate_rps, speed_x_mps, rear_to_cg_m)
        return TraceDetection(status, angle, offset, conf, beta, len(cands.angle), near)

    def _fit_curve(self, image: np.ndarray, edges: np.ndarray, edge_lines: np.ndarray,
                   angle_rad: float) -> tuple[float, float, float, float]:
        """(line angle, straight-band line angle, near-field angle, length followed [m]) of
        the candidate's trace; the length is infinite when the walls cannot be followed (the
        straight-band line stands). The bend is measured from the straight-band line, whose
        frame-to-frame noise the bend's filter was set against."""
        cfg = self.config
        straight = refine_angle(edges, self.camera, cfg.ground_z_m, edge_lines, angle_rad,
                                cfg.refine_band_m)
        points, normals = edge_points_ground(edges, self.camera, cfg.ground_z_m, image)
        walls = follow_trace(points, edge_lines, angle_rad, cfg.wheel_xy_m[0], normals,
                             band_m=cfg.refine_band_m)
        whole = self._whole_line(walls, len(np.reshape(edge_lines, (-1, 3))))
        line = whole if math.isfinite(whole) and abs(whole - straight) < math.radians(4.0) \
            else straight
        length = math.inf if walls is None else walls.u_range[1] - walls.u_range[0]
        curve = follow_trace(points, edge_lines, angle_rad, cfg.wheel_xy_m[0], normals)
        if curve is None:
            return line, straight, straight, length
        near = curve.line_angle(cfg.near_field_m)
        if not math.isfinite(near) or abs(near - straight) > cfg.max_bend_rad:
            return line, straight, straight, length
        return line, straight, near, length

    def _whole_line(self, walls: TraceCurve | None, n_walls: int) -> float:
        """Least-squares line of the candidate's walls followed over the whole view [rad].

        A bending trace leaves the straight band of :func:`.trace_lines.refine_angle` part of
        the way along, and where the front wheel's rut runs beside the rear one the straight
        band takes the older, straighter rut's wall instead. The walls followed as parallel
        curves in the same narrow band keep to the rear rut along the bend; the line is
        believed only when every wall is followed (the weakest with at least a third of the
        pixels of the strongest: the rut's two walls are cut together, and a wall that fades
        out part of the way has been left for another edge; set on Reina's test 1 and on
        synthetic traces) from the wheel's end of the view (within one strip of it), else NaN.
        """
        if walls is None:
            return math.nan
        counts = np.bincount(walls.group, minlength=n_walls)
        if 3 * counts.min() < counts.max():
            return math.nan
        if walls.u_range[1] < self._view_near_u - STRIP_M:
            return math.nan
        return walls.line_angle()

    def roi_mask(self) -> np.ndarray:
        """uint8 mask (255 inside) of the region searched in the next frame.

        A band of ``roi_half_width_m`` around the last trace; with none, a wedge from the
        contact point opening by ±``initial_roi_angle_rad``.
        """
        cfg = self.config
        rows, cols = self.camera.shape
        xw, yw = cfg.wheel_xy_m
        far = xw - 1.5  # beyond the far edge of any footprint of interest
        if self.last is not None:
            angle, offset, _ = self.last
            y0, y1 = yw + offset, yw + offset + (far - xw) * math.tan(angle)
            w = cfg.roi_half_width_m / max(math.cos(angle), 0.2)
            poly = [(xw + 0.05, y0 - w), (xw + 0.05, y0 + w), (far, y1 + w), (far, y1 - w)]
        else:
            spread = (xw - far) * math.tan(cfg.initial_roi_angle_rad)
            tol = cfg.rules.contact_m[1] + 0.5 * cfg.wheel_width_m
            poly = [(xw + 0.05, yw - tol), (xw + 0.05, yw + tol), (far, yw + tol + spread),
                    (far, yw - tol - spread)]
        uv = self.camera.ground_to_image(np.array(poly), cfg.ground_z_m)
        mask = np.zeros((rows, cols), np.uint8)
        if np.all(np.isfinite(uv)):
            cv2.fillConvexPoly(mask, np.round(uv).astype(np.int32), 255)
        return mask
