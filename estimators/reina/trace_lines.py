"""Geometry of FTrace's line candidates on the ground plane (Reina §2.2).

Hough segments are back-projected to the ground, merged into rut edges (segments of one edge
agree in angle and lie on one line), and turned into trace candidates: a pair of near-parallel
edges about one wheel width apart (the two rut walls), whose mid-line is the trace centre line,
or a lone edge, whose centre line is half a wheel width to the side nearer the wheel.
:func:`refine_angle` fits the chosen candidate's straight line to the edge pixels (Reina's
straight-line trace model, §2.1); :func:`follow_trace` follows its edges along a bending trace
so that the near part of the trace can be fitted on its own.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import cv2
import numpy as np

from slipenv.contracts.camera import PinholeCamera

MAX_ABS_ANGLE_RAD = math.radians(75.0)  # steeper edges cannot be a trace (and break tan θ)
MERGE_ANGLE_RAD = math.radians(2.0)
MERGE_DISTANCE_M = 0.012
PAIR_ANGLE_RAD = math.radians(3.0)


def segments_to_ground(segments_px: np.ndarray, camera: PinholeCamera,
                       ground_z_m: float) -> np.ndarray:
    """Back-project segments (u1, v1, u2, v2) [px], shape (k, 4), to body (x1, y1, x2, y2) [m].

    Segments that do not hit the ground are dropped.
    """
    seg = np.asarray(segments_px, dtype=float).reshape(-1, 4)
    if not len(seg):
        return np.zeros((0, 4))
    ends = camera.image_to_ground(seg.reshape(-1, 2), ground_z_m).reshape(-1, 4)
    return ends[np.all(np.isfinite(ends), axis=1)]


@dataclass(frozen=True)
class Candidates:
    """Trace candidates (arrays of shape (n,)) and the edge lines each one rests on.

    ``edge_lines[i]`` has shape (m, 3): unit normal (n_x, n_y) and c with n·p = c on the edge.
    """

    angle: np.ndarray
    offset: np.ndarray
    pair_mismatch: np.ndarray
    length: np.ndarray
    edge_lines: list[np.ndarray]


def _merge_edges(ground: np.ndarray) -> list[dict]:
    d = ground[:, 2:] - ground[:, :2]
    d = np.where(d[:, :1] < 0.0, -d, d)  # direction with x >= 0: towards the wheel
    length = np.hypot(d[:, 0], d[:, 1])
    keep = length > 1e-6
    ground, d, length = ground[keep], d[keep], length[keep]
    theta = np.arctan2(d[:, 1], d[:, 0])
    ok = np.abs(theta) < MAX_ABS_ANGLE_RAD
    ground, d, length, theta = ground[ok], d[ok], length[ok], theta[ok]
    edges: list[dict] = []
    for k in np.argsort(-length):
        mid = 0.5 * (ground[k, :2] + ground[k, 2:])
        for edge in edges:
            if (abs(theta[k] - edge["theta"]) < MERGE_ANGLE_RAD
                    and abs(edge["normal"] @ mid - edge["c"]) < MERGE_DISTANCE_M):
                t = [edge["dir"] @ ground[k, :2], edge["dir"] @ ground[k, 2:]]
                edge["lo"], edge["hi"] = min(edge["lo"], *t), max(edge["hi"], *t)
                break
        else:
            direction = d[k] / length[k]
            normal = np.array([-direction[1], direction[0]])
            t = [direction @ ground[k, :2], direction @ ground[k, 2:]]
            edges.append({"theta": float(theta[k]), "dir": direction, "normal": normal,
                          "c": float(normal @ mid), "mid": mid, "lo": min(t), "hi": max(t)})
    return edges


def candidates_from_segments(ground: np.ndarray, wheel_xy_m: tuple[float, float],
                             wheel_width_m: float) -> Candidates:
    """Trace candidates from ground segments (x1, y1, x2, y2) [m].

    Offsets are the lateral position of the candidate centre line at the contact point's x,
    relative to the wheel-centre line [m].
    """
    xw, yw = wheel_xy_m
    edges = _merge_edges(np.asarray(ground, dtype=float).reshape(-1, 4))

    def offset_at_wheel(theta: float, point: np.ndarray) -> float:
        return float(point[1] + (xw - point[0]) * math.tan(theta) - yw)

    angle, offset, mismatch, length, lines = [], [], [], [], []
    for i, a in enumerate(edges):
        len_a = a["hi"] - a["lo"]
        line_a = np.array([[*a["normal"], a["c"]]])
        e_a = offset_at_wheel(a["theta"], a["mid"])
        # A lone edge: the rut centre is half a wheel width to the side nearer the wheel.
        shift = 0.5 * wheel_width_m / math.cos(a["theta"])
        angle.append(a["theta"])
        offset.append(min(e_a - shift, e_a + shift, key=abs))
        mismatch.append(math.inf)
        length.append(len_a)
        lines.append(line_a)
        for b in edges[i + 1:]:
            if abs(a["theta"] - b["theta"]) >= PAIR_ANGLE_RAD:
                continue
            separation = abs(a["normal"] @ b["mid"] - a["c"])
            len_b = b["hi"] - b["lo"]
            theta = (a["theta"] * len_a + b["theta"] * len_b) / (len_a + len_b)
            angle.append(theta)
            offset.append(0.5 * (e_a + offset_at_wheel(b["theta"], b["mid"])))
            mismatch.append(abs(separation / wheel_width_m - 1.0))
            length.append(0.5 * (len_a + len_b))
            lines.append(np.array([line_a[0], [*b["normal"], b["c"]]]))  # (np.vstack's)
    return Candidates(np.array(angle), np.array(offset), np.array(mismatch), np.array(length),
                      lines)


def edge_pixels(edges: np.ndarray) -> np.ndarray:
    """(column, row) of every edge pixel in row-major order, as np.nonzero gives them, shape
    (k, 2) float; OpenCV's scan is about three times faster on a uint8 edge map."""
    if edges.dtype == np.uint8 and edges.ndim == 2:
        found = cv2.findNonZero(edges)
        return np.zeros((0, 2)) if found is None else found.reshape(-1, 2).astype(float)
    rows, cols = np.nonzero(edges)
    return np.column_stack([cols, rows]).astype(float)


def edge_points_ground(edges: np.ndarray, camera: PinholeCamera, ground_z_m: float,
                       image: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Every edge pixel of an edge map back-projected to the ground, and its edge normal.

    Returns the points, shape (k, 2) [m], and the unit direction of the grey-level gradient
    on the ground at each, shape (k, 2) (the normal of the edge through the pixel; Sobel on
    ``image``, NaN without one). Pixels that do not hit the ground are dropped.
    """
    uv = edge_pixels(edges)
    if not len(uv):
        return np.zeros((0, 2)), np.zeros((0, 2))
    pts = camera.image_to_ground(uv, ground_z_m)
    normals = np.full_like(pts, np.nan)
    if image is not None:
        col, row = uv[:, 0].astype(int), uv[:, 1].astype(int)
        grad = np.column_stack([cv2.Sobel(image, cv2.CV_32F, 1, 0)[row, col],
                                cv2.Sobel(image, cv2.CV_32F, 0, 1)[row, col]]).astype(float)
        norm = np.hypot(grad[:, 0], grad[:, 1])
        ok = norm > 0.0
        step = np.zeros_like(grad)
        step[ok] = grad[ok] / norm[ok, None]
        ahead = camera.image_to_ground(uv + step, ground_z_m) - pts
        length = np.hypot(ahead[:, 0], ahead[:, 1])
        good = ok & (length > 0.0)
        normals[good] = ahead[good] / length[good, None]
    keep = np.all(np.isfinite(pts), axis=1)
    return pts[keep], normals[keep]


@dataclass(frozen=True, eq=False)
class TraceCurve:
    """A trace candidate's rut-edge pixels followed along the ground (Reina §2.1, generalised).

    ``u`` = x - x_w (x_w: the contact point's x) and ``y`` of the edge pixels the trace rests
    on, ``group`` the rut edge each belongs to. Angles are directions towards the wheel.
    """

    u: np.ndarray
    y: np.ndarray
    group: np.ndarray

    @property
    def u_range(self) -> tuple[float, float]:
        """(far end, near end) of the followed trace [m]."""
        return float(self.u.min()), float(self.u.max())

    def line_angle(self, near_m: float = math.inf, min_points: int = 10) -> float:
        """Total-least-squares angle of the edges over the last ``near_m`` of trace [rad].

        Each edge's pixels are centred on their own mean and fitted jointly (parallel edges,
        one direction). With ``near_m`` infinite this is the least-squares line of the whole
        visible trace, Reina's straight-line model (§2.1); with a finite ``near_m`` it is the
        near-field line, whose direction is that of the wheel's path ``near_m``/2 behind the
        contact point on a uniformly bending trace. NaN with fewer than ``min_points``.
        """
        keep = self.u >= self.u.max() - near_m
        centred = []
        for k in np.unique(self.group[keep]):
            sel = keep & (self.group == k)
            if np.count_nonzero(sel) >= 3:
                xy = np.column_stack([self.u[sel], self.y[sel]])
                centred.append(xy - xy.mean(axis=0))
        if not centred or sum(len(c) for c in centred) < min_points:
            return math.nan
        _, _, vt = np.linalg.svd(np.vstack(centred), full_matrices=False)
        direction = vt[0] if vt[0, 0] >= 0.0 else -vt[0]
        return math.atan2(direction[1], direction[0])


def _fit_parallel(u: np.ndarray, y: np.ndarray, group: np.ndarray, n_groups: int,
                  quadratic: bool) -> np.ndarray:
    """Least squares of y = c_group + a₁ u (+ a₂ u²): returns (c_0..c_{m-1}, a₁, a₂)."""
    cols = [(group == k).astype(float) for k in range(n_groups)] + [u]
    if quadratic:
        cols.append(u * u)
    sol, *_ = np.linalg.lstsq(np.column_stack(cols), y, rcond=None)
    return np.concatenate([sol, [0.0]]) if not quadratic else sol


STRIP_M = 0.08
"""Length along body x [m] of the strips :func:`follow_trace` grows a trace by."""


def follow_trace(points: np.ndarray, edge_lines: np.ndarray, angle_rad: float,
                 x_wheel_m: float, normals: np.ndarray | None = None,
                 max_normal_tilt_rad: float = math.radians(30.0),
                 band_m: float = 0.012, strip_m: float = STRIP_M,
                 min_points: int = 10, min_quadratic_span_m: float = 0.25) -> TraceCurve | None:
    """Follow a candidate's rut edges along the ground and fit them as a curve.

    Reina's trace model is a straight line (§2.1), valid while the visible trace and the
    sideslip between two images are small; on mounds the visible trace bends by several
    degrees. The Hough candidate is the straightest piece of the trace; from the strip (of
    ``strip_m`` along body x) where its edge lines collect the most edge pixels, the fit
    grows strip by strip towards both ends, each new strip's pixels selected within
    ``band_m`` of the curve fitted so far (a line until it spans ``min_quadratic_span_m``,
    then parallel quadratics y = c_k + a₁ u + a₂ u² with u = x - x_w), skipping at most one
    empty strip (a shadow edge, a grouser gap). A final pass selects every pixel within the
    band; the curve only selects pixels, and the angles are straight-line fits to them
    (:meth:`TraceCurve.line_angle`). With ``normals``, pixels whose edge normal is more than
    ``max_normal_tilt_rad`` from the trace's normal (the grouser marks across the rut) are
    left out.

    Parameters
    ----------
    points : np.ndarray, shape (k, 2)
        Edge pixels on the ground plane (body x, y) [m].
    edge_lines : np.ndarray, shape (m, 3)
        The candidate's edge lines (unit normal, c), as in :class:`Candidates`.
    angle_rad : float
        The candidate's angle (direction towards the wheel) [rad].
    x_wheel_m : float
        Body x of the contact point [m].
    normals : np.ndarray, shape (k, 2), optional
        Unit edge normal on the ground at each pixel (:func:`edge_points_ground`); NaN rows
        are kept.

    Returns
    -------
    TraceCurve or None
        None when fewer than ``min_points`` pixels support the candidate.
    """
    pts = np.asarray(points, dtype=float).reshape(-1, 2)
    lines = np.array(edge_lines, dtype=float).reshape(-1, 3)
    if normals is not None:
        # A rut wall's gradient is across the trace; a grouser mark's runs along it.
        across = np.abs(np.asarray(normals, dtype=float).reshape(-1, 2)
                        @ np.array([-math.sin(angle_rad), math.cos(angle_rad)]))
        pts = pts[~(across < math.cos(max_normal_tilt_rad))]  # NaN normals are kept
    if len(pts) < min_points or not len(lines):
        return None
    u, y = pts[:, 0] - x_wheel_m, pts[:, 1]
    # each edge line as y = c_k + tan(θ) u (|θ| < 75°, so n_y is not 0)
    slope = math.tan(angle_rad)
    coef = np.concatenate([(lines[:, 2] - lines[:, 0] * x_wheel_m) / lines[:, 1],
                           [slope, 0.0]])
    m = len(lines)

    def residuals(c: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        centre = c[m] * u + c[m + 1] * u * u
        d = np.abs(y[:, None] - centre[:, None] - c[None, :m])
        return d.min(axis=1), d.argmin(axis=1)

    dist, group = residuals(coef)
    strip = np.floor(u / strip_m).astype(int)
    inlier = dist < band_m
    if np.count_nonzero(inlier) < min_points:
        return None
    counts = np.bincount(strip[inlier] - strip.min())
    seed = int(np.argmax(counts)) + strip.min()
    if counts[seed - strip.min()] < min_points:
        return None
    accepted = inlier & (strip == seed)
    lo = hi = seed
    grow = {+1: True, -1: True}
    misses = {+1: 0, -1: 0}
    while any(grow.values()):
        for step in (+1, -1):
            if not grow[step]:
                continue
            k = (hi if step > 0 else lo) + step * (misses[step] + 1)
            if k < strip.min() or k > strip.max():
                grow[step] = False
                continue
            span = (hi - lo + 1) * strip_m
            coef = _fit_parallel(u[accepted], y[accepted], group[accepted], m,
                                 span >= min_quadratic_span_m)
            dist, group = residuals(coef)
            new = (strip == k) & (dist < band_m)
            if np.count_nonzero(new) >= min_points:
                accepted |= new
                lo, hi = min(lo, k), max(hi, k)
                misses[step] = 0
            elif misses[step] == 0:
                misses[step] = 1
            else:
                grow[step] = False
    quadratic = (hi - lo + 1) * strip_m >= min_quadratic_span_m
    coef = _fit_parallel(u[accepted], y[accepted], group[accepted], m, quadratic)
    dist, group = residuals(coef)
    final = (dist < band_m) & (strip >= lo) & (strip <= hi)
    if np.count_nonzero(final) < min_points:
        return None
    return TraceCurve(u[final], y[final], group[final])


def refine_angle(edges: np.ndarray, camera: PinholeCamera, ground_z_m: float,
                 edge_lines: np.ndarray, angle_rad: float, band_m: float = 0.004,
                 iterations: int = 3) -> float:
    """Least-squares angle of the edge pixels lying on a candidate's edge lines [rad].

    Edge pixels within ``band_m`` of each line are back-projected; the groups are centred on
    their own means and fitted jointly (parallel lines, one direction: total least squares);
    ``band_m`` is about the localisation of one Canny edge (±1.6 px at the rear camera's 2.5 mm
    per pixel): a rut wall comes with parallel edges a few millimetres away (the floor's edge
    at 0.85 of the half width, the berm, an overlapping older rut's wall) that diverge from it
    along the view, and a wider band pulls the fit towards them (set on Reina's test 1);
    the lines are then moved to the new direction through their groups' means and the
    selection repeated, so a slightly curved trace is fitted over its whole visible length
    rather than along the Hough segment only. Falls back to ``angle_rad`` when too few pixels
    support the fit.
    """
    uv = edge_pixels(edges)
    if len(uv) < 10:
        return angle_rad
    pts = camera.image_to_ground(uv, ground_z_m)
    # the x and y columns as contiguous arrays, read once per line per iteration below
    px, py = np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1])
    lines = np.array(edge_lines, dtype=float).reshape(-1, 3)
    angle = angle_rad
    for _ in range(iterations):
        centred, means = [], []
        for nx, ny, c in lines:
            near = np.abs(px * nx + py * ny - c) < band_m
            if np.count_nonzero(near) >= 10:
                group = pts[near]
                means.append(group.mean(axis=0))
                centred.append(group - means[-1])
        if not centred:
            return angle_rad
        _, _, vt = np.linalg.svd(np.vstack(centred), full_matrices=False)
        direction = vt[0] if vt[0, 0] >= 0.0 else -vt[0]
        angle = math.atan2(direction[1], direction[0])
        normal = np.array([-direction[1], direction[0]])
        lines = np.array([[*normal, float(normal @ m)] for m in means])
    # Guard: a fit pulled away by crossing edges is not trusted.
    return angle if abs(angle - angle_rad) < math.radians(4.0) else angle_rad
