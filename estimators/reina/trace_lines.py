"""Geometry of FTrace's line candidates on the ground plane (Reina §2.2).

Hough segments are back-projected to the ground, merged into rut edges (segments of one edge
agree in angle and lie on one line), and turned into trace candidates: a pair of near-parallel
edges about one wheel width apart (the two rut walls), whose mid-line is the trace centre line,
or a lone edge, whose centre line is half a wheel width to the side nearer the wheel.
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


def refine_angle(edges: np.ndarray, camera: PinholeCamera, ground_z_m: float,
                 edge_lines: np.ndarray, angle_rad: float, band_m: float = 0.012,
                 iterations: int = 3) -> float:
    """Least-squares angle of the edge pixels lying on a candidate's edge lines [rad].

    Edge pixels within ``band_m`` of each line are back-projected; the groups are centred on
    their own means and fitted jointly (parallel lines, one direction: total least squares);
    the lines are then moved to the new direction through their groups' means and the
    selection repeated, so a slightly curved trace is fitted over its whole visible length
    rather than along the Hough segment only. Falls back to ``angle_rad`` when too few pixels
    support the fit.
    """
    # (column, row) of every edge pixel in row-major order, as np.nonzero gives them;
    # OpenCV's scan is about three times faster on a uint8 edge map
    if edges.dtype == np.uint8 and edges.ndim == 2:
        found = cv2.findNonZero(edges)
        uv = np.zeros((0, 2)) if found is None else found.reshape(-1, 2).astype(float)
    else:
        rows, cols = np.nonzero(edges)
        uv = np.column_stack([cols, rows]).astype(float)
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
