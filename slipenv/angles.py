"""Angle wrapping to [-π, π), for scalars (hot paths) and arrays.

(Path headings and the controllers' errors use (-π, π], the convention of ``atan2`` and of
``slipenv.paths``; the two differ only at exactly ±π.)
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_angle(angle_rad: float) -> float:
    """Wrap one angle to [-π, π) [rad] (plain float: cheap in per-step code)."""
    return (angle_rad + math.pi) % TWO_PI - math.pi


def wrap_angles(angle_rad: np.ndarray | float) -> np.ndarray:
    """Wrap angles element-wise to [-π, π) [rad]."""
    return np.mod(np.asarray(angle_rad, dtype=float) + np.pi, TWO_PI) - np.pi
