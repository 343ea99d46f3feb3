"""The path near the vehicle, rebuilt from the observation alone.

Geometric controllers need points ahead on the path, but the observation carries only the
path-relative errors at the projection. Around the projection the path is approximated by its
osculating arc: a circle of the observed curvature κ, tangent to the path there. In the path
frame (origin at the projection, x along the path tangent, y to its left) the vehicle sits at
``(0, cross_track)`` with heading ``heading_error``. The approximation is exact on straights
and arcs and misses only curvature changes ahead (segment joints, splines).

All functions are vectorised over numpy arrays and regular at κ = 0.
"""

from __future__ import annotations

import numpy as np


def arc_point(kappa: np.ndarray, s: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Point at arc length ``s`` [m] along the osculating arc of curvature ``kappa`` [1/m].

    ``(sin(κs)/κ, (1 - cos(κs))/κ)``, written with ``np.sinc`` so κ = 0 gives ``(s, 0)``.
    """
    x = s * np.sinc(kappa * s / np.pi)
    y = 0.5 * kappa * s**2 * np.sinc(kappa * s / (2.0 * np.pi)) ** 2
    return x, y


def arc_offset(kappa: np.ndarray, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """Signed offset [m] of the path-frame point ``(px, py)`` from the arc, > 0 to its left.

    For a circle of radius R = 1/κ about (0, R) the offset is R - |p - c| (sign-aware); written
    as (2 py - κ r²) / (1 + sqrt(1 - 2 κ py + κ² r²)) with r² = px² + py², which stays exact
    as κ -> 0 (the offset becomes py).
    """
    r2 = px**2 + py**2
    return (2.0 * py - kappa * r2) / (1.0 + np.sqrt(np.maximum(1.0 - 2.0 * kappa * py
                                                               + kappa**2 * r2, 0.0)))


def arc_heading(kappa: np.ndarray, px: np.ndarray, py: np.ndarray) -> np.ndarray:
    """Heading [rad] of the arc's tangent at the foot of ``(px, py)``, path frame.

    The foot lies on the ray from the centre (0, 1/κ) through the point, so the tangent is
    that ray turned by 90° in the direction of travel: ``atan2(κ px, 1 - κ py)``.
    """
    return np.arctan2(kappa * px, 1.0 - kappa * py)
