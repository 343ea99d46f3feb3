"""``meta.json`` of a slipenv-log/1 folder: a dict with typed accessors, and its validation.

The contract (``log-format.md``) lets a producer add keys of its own; ``LogMeta`` keeps the
whole dict, so reading and rewriting a log preserves them. Accessors return SI values.
"""

from __future__ import annotations

import copy
import math
import re
from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any, TypeGuard

from slipenv.logs.bounds import META_BOUNDS, meta_range_text, meta_value_ok
from slipenv.logs.errors import LogFormatError

FORMAT = "slipenv-log/1"
VEHICLE_KINDS = ("diff_drive", "skid_steer", "rover4ws")
_WHEEL_NAME = re.compile(r"^[A-Za-z0-9_]+$")


class LogMeta:
    """The contents of ``meta.json``, with typed accessors.

    Parameters
    ----------
    data : Mapping
        The parsed JSON object. It is deep-copied; unknown keys are kept.

    Notes
    -----
    Construction does not validate; ``validate_meta`` does (``read_log`` and
    ``Log.from_arrays`` call it).
    """

    def __init__(self, data: Mapping[str, Any]) -> None:
        self.data: dict[str, Any] = copy.deepcopy(dict(data))

    @classmethod
    def new(
        cls,
        kind: str,
        wheels: Sequence[str],
        wheel_radius_m: float,
        track_width_m: float,
        counts_per_rad: float,
        *,
        wheelbase_m: float | None = None,
        mass_kg: float | None = None,
        terrain_description: str = "",
        soil: str = "rigid",
        slope_deg: float = 0.0,
        slope_downhill_azimuth_deg: float | None = None,
        notes: str = "",
        **extra: Any,
    ) -> LogMeta:
        """Build a meta dict in the contract's layout; ``extra`` become top-level keys."""
        data: dict[str, Any] = {
            "format": FORMAT,
            "vehicle": {
                "kind": kind,
                "wheels": list(wheels),
                "wheel_radius_m": wheel_radius_m,
                "track_width_m": track_width_m,
                "counts_per_rad": counts_per_rad,
                "wheelbase_m": wheelbase_m,
                "mass_kg": mass_kg,
            },
            "terrain": {
                "description": terrain_description,
                "soil": soil,
                "slope_deg": slope_deg,
                "slope_downhill_azimuth_deg": slope_downhill_azimuth_deg,
            },
            "notes": notes,
        }
        data.update(extra)
        return cls(data)

    def to_dict(self) -> dict[str, Any]:
        """A deep copy of the underlying dict, as written to ``meta.json``."""
        return copy.deepcopy(self.data)

    def copy(self) -> LogMeta:
        return LogMeta(self.data)

    def __repr__(self) -> str:
        return f"LogMeta({self.data!r})"

    def __eq__(self, other: object) -> bool:
        return isinstance(other, LogMeta) and self.data == other.data

    __hash__ = None  # type: ignore[assignment]  # mutable, compared by content

    @property
    def _vehicle(self) -> dict[str, Any]:
        return self.data.get("vehicle") or {}

    @property
    def _terrain(self) -> dict[str, Any]:
        return self.data.get("terrain") or {}

    @property
    def format(self) -> str:
        return str(self.data.get("format", ""))

    @property
    def kind(self) -> str:
        """Vehicle kind: ``diff_drive``, ``skid_steer`` or ``rover4ws``."""
        return str(self._vehicle["kind"])

    @property
    def wheels(self) -> list[str]:
        """Wheel (or track) names, left side first; they suffix the signal columns."""
        return [str(w) for w in self._vehicle["wheels"]]

    @property
    def wheel_radius_m(self) -> float:
        """Nominal wheel radius the operator believes in [m]."""
        return float(self._vehicle["wheel_radius_m"])

    @property
    def track_width_m(self) -> float:
        """Nominal distance between the left and right contact lines [m]."""
        return float(self._vehicle["track_width_m"])

    @property
    def counts_per_rad(self) -> float:
        """Encoder resolution [counts/rad of wheel rotation]."""
        return float(self._vehicle["counts_per_rad"])

    @property
    def wheelbase_m(self) -> float | None:
        """Front-to-rear axle distance [m] (rover4ws), else None."""
        return _optional_float(self._vehicle.get("wheelbase_m"))

    @property
    def mass_kg(self) -> float | None:
        """Vehicle mass [kg], if known."""
        return _optional_float(self._vehicle.get("mass_kg"))

    @property
    def terrain_description(self) -> str:
        return str(self._terrain.get("description") or "")

    @property
    def soil(self) -> str:
        """Soil the operator assumes; ``rigid`` when nothing is known."""
        return str(self._terrain.get("soil") or "rigid")

    @property
    def slope_deg(self) -> float:
        """Planar slope angle [deg]; 0 when not declared."""
        return float(self._terrain.get("slope_deg") or 0.0)

    @property
    def slope_downhill_azimuth_deg(self) -> float | None:
        """Direction of steepest descent, counter-clockwise from world x [deg]."""
        return _optional_float(self._terrain.get("slope_downhill_azimuth_deg"))

    @property
    def notes(self) -> str:
        return str(self.data.get("notes") or "")


def _optional_float(value: Any) -> float | None:
    return None if value is None else float(value)


def key_line(text: str | None, keys: Sequence[str]) -> int | None:
    """Best-effort 1-based line of a nested key (``["vehicle", "kind"]``) in JSON text.

    A missing key gives the line of its deepest present parent (line 1 at top level).
    """
    if text is None:
        return None
    pos = 0
    for key in keys:
        match = re.compile(r'"' + re.escape(key) + r'"\s*:').search(text, pos)
        if match is None:
            break
        pos = match.start()
    return text.count("\n", 0, pos) + 1


def validate_meta(data: Any, path: str | Path, text: str | None = None) -> None:
    """Check a parsed ``meta.json`` against the contract.

    Parameters
    ----------
    data : Any
        The parsed JSON.
    path : str or Path
        File named in errors.
    text : str, optional
        The raw JSON text, used to find the line of an offending key.

    Raises
    ------
    LogFormatError
        Naming the file, the line (when ``text`` is given) and the key path.
    """

    def fail(keys: Sequence[str], reason: str) -> LogFormatError:
        return LogFormatError(path, reason, line=key_line(text, keys),
                              column=".".join(keys) if keys else None, column_label="key")

    if not isinstance(data, dict):
        raise fail([], "meta.json must hold a JSON object")
    if "format" not in data:
        raise fail(["format"], f"missing key 'format' (expected '{FORMAT}')")
    if data["format"] != FORMAT:
        raise fail(["format"], f"unsupported format {data['format']!r}, expected '{FORMAT}'")
    vehicle = data.get("vehicle")
    if not isinstance(vehicle, dict):
        raise fail(["vehicle"], "missing or non-object 'vehicle'")
    kind = vehicle.get("kind")
    if kind not in VEHICLE_KINDS:
        raise fail(["vehicle", "kind"],
                   f"unknown vehicle kind {kind!r}, expected one of {', '.join(VEHICLE_KINDS)}")
    wheels = vehicle.get("wheels")
    if not isinstance(wheels, list) or len(wheels) < 2:
        raise fail(["vehicle", "wheels"], "'wheels' must list at least two wheel names")
    for name in wheels:
        if not isinstance(name, str) or not _WHEEL_NAME.match(name):
            raise fail(["vehicle", "wheels"],
                       f"wheel name {name!r} is not a column suffix ([A-Za-z0-9_]+)")
    if len(set(wheels)) != len(wheels):
        raise fail(["vehicle", "wheels"], "wheel names must be unique")
    for key in ("wheel_radius_m", "track_width_m", "counts_per_rad"):
        if not _positive(vehicle.get(key)):
            raise fail(["vehicle", key], f"'{key}' must be a finite number > 0, "
                                         f"got {vehicle.get(key)!r}")
    if kind == "rover4ws" and not _positive(vehicle.get("wheelbase_m")):
        raise fail(["vehicle", "wheelbase_m"], "rover4ws needs 'wheelbase_m' > 0")
    for key in ("wheelbase_m", "mass_kg"):
        if vehicle.get(key) is not None and not _positive(vehicle[key]):
            raise fail(["vehicle", key], f"'{key}' must be null or a finite number > 0")
    terrain = data.get("terrain", {})
    if terrain is not None:
        _validate_terrain(terrain, fail)
    for (section, key) in META_BOUNDS:
        value = (data.get(section) or {}).get(key)
        if _finite(value) and not meta_value_ok((section, key), value):
            raise fail([section, key], f"'{key}' = {value!r} is physically implausible "
                                       f"(allowed {meta_range_text((section, key))}; see "
                                       "slipenv.logs.bounds)")
    if data.get("notes") is not None and not isinstance(data["notes"], str):
        raise fail(["notes"], "'notes' must be a string")


def _validate_terrain(terrain: Any,
                      fail: Callable[[Sequence[str], str], LogFormatError]) -> None:
    if not isinstance(terrain, dict):
        raise fail(["terrain"], "'terrain' must be an object")
    for key in ("description", "soil"):
        if terrain.get(key) is not None and not isinstance(terrain[key], str):
            raise fail(["terrain", key], f"'{key}' must be a string")
    if terrain.get("slope_deg") is not None and not _finite(terrain["slope_deg"]):
        raise fail(["terrain", "slope_deg"], "'slope_deg' must be a finite number")
    azimuth = terrain.get("slope_downhill_azimuth_deg")
    if azimuth is not None and not _finite(azimuth):
        raise fail(["terrain", "slope_downhill_azimuth_deg"],
                   "'slope_downhill_azimuth_deg' must be null or a finite number")


def _finite(value: Any) -> TypeGuard[int | float]:
    return (isinstance(value, int | float) and not isinstance(value, bool)
            and math.isfinite(value))


def _positive(value: Any) -> bool:
    return _finite(value) and value > 0
