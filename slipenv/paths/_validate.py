"""Argument checks shared by segments and builders: each error names the offending argument."""

from __future__ import annotations

import math
import numbers
from collections.abc import Sequence


def finite(name: str, value: float) -> float:
    """Return ``value`` as a float, or raise ``ValueError`` naming ``name`` if it is not finite."""
    try:
        out = float(value)
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be a finite number, got {value!r}") from None
    if not math.isfinite(out):
        raise ValueError(f"{name} must be a finite number, got {value!r}")
    return out


def positive(name: str, value: float) -> float:
    """Return ``value`` if finite and > 0, else raise ``ValueError`` naming ``name``."""
    out = finite(name, value)
    if out <= 0.0:
        raise ValueError(f"{name} must be > 0, got {value!r}")
    return out


def non_negative(name: str, value: float) -> float:
    """Return ``value`` if finite and >= 0, else raise ``ValueError`` naming ``name``."""
    out = finite(name, value)
    if out < 0.0:
        raise ValueError(f"{name} must be >= 0, got {value!r}")
    return out


def point(name: str, value: Sequence[float]) -> tuple[float, float]:
    """Return a finite ``(x, y)`` pair [m], or raise ``ValueError`` naming ``name``."""
    try:
        x, y = value
    except (TypeError, ValueError):
        raise ValueError(f"{name} must be an (x, y) pair, got {value!r}") from None
    return finite(f"{name}[0]", x), finite(f"{name}[1]", y)


MAX_COUNT = 1000  # gates, legs, rows: each adds segments that every projection may scan


def count(name: str, value: int, minimum: int = 1, maximum: int = MAX_COUNT) -> int:
    """Return ``value`` if it is an integer in [``minimum``, ``maximum``], else raise
    ``ValueError`` naming ``name``."""
    if (isinstance(value, bool) or not isinstance(value, numbers.Integral)
            or not minimum <= value <= maximum):
        raise ValueError(f"{name} must be an integer in [{minimum}, {maximum}], got {value!r}")
    return int(value)


def speeds(v0_mps: float, v1_mps: float) -> tuple[float, float]:
    """Check a segment's initial and final speeds [m/s]: both >= 0, not both zero."""
    v0 = non_negative("v0_mps", v0_mps)
    v1 = non_negative("v1_mps", v1_mps)
    if v0 == 0.0 and v1 == 0.0:
        raise ValueError("v0_mps and v1_mps are both 0: the segment would never be traversed")
    return v0, v1
