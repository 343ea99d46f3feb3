"""How the diagnosis prints numbers: never ``inf`` or ``nan``, and an estimate whose standard
error exceeds its magnitude as "not determined".

An estimate ``v ± se`` with ``se > |v|`` does not tell the sign, let alone the value, at one
standard error: printing ``74.552 ± 161.127 m`` invites a reader to use 74.552. The text
reports say "not determined"; the JSON keeps the number (the contract's ``[value, se]``) and
flags it in ``determined``.
"""

from __future__ import annotations

import math
from typing import Any

NOT_AVAILABLE = "n/a"


def is_number(value: Any) -> bool:
    """True for a finite real number (numpy scalars included)."""
    try:
        return not isinstance(value, bool) and math.isfinite(float(value))
    except (TypeError, ValueError):
        return False


def determined(value: Any, se: Any) -> bool:
    """Whether ``value ± se`` determines the value: both finite, ``se <= |value|``."""
    return is_number(value) and is_number(se) and float(se) <= abs(float(value))


def num(value: Any, spec: str = ".4g") -> str:
    """``value`` formatted with ``spec``, or ``n/a`` when it is missing or not finite."""
    return format(float(value), spec) if is_number(value) else NOT_AVAILABLE


def percent(fraction: Any, spec: str = ".1f") -> str:
    """``100 fraction`` with a ``%`` sign, or ``n/a``."""
    return f"{format(100.0 * float(fraction), spec)} %" if is_number(fraction) else NOT_AVAILABLE


def better(fraction: Any, spec: str = ".1f") -> str:
    """``"12.0 % better"``, ``"5.0 % worse"`` for a negative gain, or ``"n/a"``."""
    if not is_number(fraction):
        return NOT_AVAILABLE
    word = "better" if float(fraction) >= 0 else "worse"
    return f"{percent(abs(float(fraction)), spec)} {word}"


def estimate(value: Any, se: Any, spec: str = ".6g", se_spec: str = ".2g") -> str:
    """``v ± se``; "not determined (± se)" when the error exceeds the value; ``n/a``."""
    if not is_number(value):
        return NOT_AVAILABLE
    if not is_number(se):
        return f"{format(float(value), spec)} (standard error {NOT_AVAILABLE})"
    if not determined(value, se):
        return f"not determined (standard error {format(float(se), se_spec)} exceeds the estimate)"
    return f"{format(float(value), spec)} ± {format(float(se), se_spec)}"


def determined_map(parameters: dict[str, Any]) -> dict[str, bool]:
    """``{name: determined}`` of a ``{name: [value, se]}`` map."""
    out = {}
    for name, pair in parameters.items():
        value, se = (pair[0], pair[1]) if isinstance(pair, list | tuple) and len(pair) >= 2 \
            else (pair, None)
        out[name] = determined(value, se)
    return out


# Fitted geometry over the nominal one beyond which the log's meta.json, not the vehicle, is
# the likelier culprit (see ``proprio.PLAUSIBLE_WIDTH_RATIO`` for the track width's range).
PLAUSIBLE_RATIO = {"track_width_m": (0.67, 10.0), "radius_": (0.5, 2.0)}


def implausible_geometry(parameters: dict[str, Any], nominal: dict[str, float]) -> list[str]:
    """Warnings for fitted track width / radii far from the nominal geometry of ``meta.json``."""
    out = []
    for name, pair in parameters.items():
        if name == "track_width_m":
            ref, (low, high) = nominal.get("track_width_m"), PLAUSIBLE_RATIO["track_width_m"]
        elif name.startswith("radius_") and name.endswith("_m"):
            ref, (low, high) = nominal.get("wheel_radius_m"), PLAUSIBLE_RATIO["radius_"]
        else:
            continue
        value = pair[0] if isinstance(pair, list | tuple) else pair
        if ref is None or not (is_number(value) and is_number(ref) and float(ref) > 0):
            continue
        ratio = float(value) / float(ref)
        if not low <= ratio <= high:
            out.append(f"{name} {float(value):.4g} m is {ratio:.3g} times the nominal "
                       f"{float(ref):.4g} m (outside {low:g}-{high:g}): check the log's "
                       "meta.json geometry; the fit is not a calibration")
    return out
