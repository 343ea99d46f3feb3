"""Angle wrapping to (-π, π], for scalars (hot paths) and arrays.

One convention for the whole package: that of ``atan2``, the paths' headings and the
controllers' errors.
"""

from __future__ import annotations

import math

import numpy as np

TWO_PI = 2.0 * math.pi


def wrap_angle(angle_rad: float) -> float:
    """Wrap one angle to (-π, π] [rad] (plain float: cheap in per-step code)."""
    return math.pi - (math.pi - angle_rad) % TWO_PI


def wrap_angles(angle_rad: np.ndarray | float) -> np.ndarray:
    """Wrap angles element-wise to (-π, π] [rad]."""
    return np.pi - np.mod(np.pi - np.asarray(angle_rad, dtype=float), TWO_PI)
