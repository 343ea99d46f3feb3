"""Configuration of a slipenv environment: one frozen dataclass, every field a make kwarg.

``gymnasium.make("slipenv/Configurable-v0", vehicle="rover_4ws", soil="lunar_simulant", ...)``
builds a :class:`SlipEnvConfig` from the kwargs; an unknown kwarg is a ``ValueError`` that names
it and suggests the closest field (no silent typos).
"""

from __future__ import annotations

import difflib
import inspect
import math
import numbers
from collections.abc import Sequence
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np

from slipenv.contracts.observation import (
    OBS_CURVATURE,
    OBS_HIGH,
    OBS_REF_SPEED,
    OBS_X,
    OBS_YAW_RATE,
)
from slipenv.envs.factory import ForceModelFactory, make_path
from slipenv.paths import PATHS, Path
from slipenv.sensors.beacons import BeaconScanner, as_beacons_xy
from slipenv.sensors.noise import SensorNoise
from slipenv.terrain.terrain import TerrainSpec
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import FORCE_MODELS, ForceModel
from slipenv.terramechanics.presets import SOILS
from slipenv.terramechanics.soil import Soil
from slipenv.terramechanics.soil_map import SoilMap
from slipenv.vehicles.presets import VEHICLES
from slipenv.vehicles.spec import VehicleSpec

REWARD_TERMS = ("cross_track", "heading", "progress", "effort")

Beacons = bool | str | BeaconScanner | Sequence[Sequence[float]] | np.ndarray | None
"""What ``beacons`` accepts; stored as ``None``, ``False``, ``True``, a scanner, or a tuple of
(x, y) pairs."""


@dataclass(frozen=True)
class SlipEnvConfig:
    """Everything that defines a slipenv task.

    Attributes
    ----------
    vehicle : str | VehicleSpec
        Vehicle preset name (``farm_2wd``, ``tracked_patako``, ``rover_4ws``, ``husky``) or spec.
    terrain : TerrainSpec | dict[str, Any] | str
        Ground geometry: a spec, its fields as a dict, or a kind name (``flat``/``slope``/
        ``mounds``).
    soil : str | Soil
        Soil preset name or a :class:`slipenv.terramechanics.soil.Soil`.
    soil_map : SoilMap | None
        A spatially varying soil (any object with ``params_at(x, y)``; overrides ``soil``).
    force_model : str | ForceModel | ForceModelFactory
        ``"reina"``, ``"janosi"``, ``"linear"``, a model instance, or a callable taking the
        wheel's ``ContactGeometry`` and returning a model.
    force_model_kwargs : dict[str, Any]
        Options of the force model named by ``force_model`` (its constructor's keyword
        arguments), e.g. ``{"lateral_stiffness_ratio": 3.6}`` for ``janosi`` or ``linear``:
        the soil's lateral small-slip stiffness over its longitudinal one (Reina measured
        C_y/C_x = 3.6 on loose soil, Reina Table 3; Reina's own law has its C_y and takes no
        ratio), or ``rolling_resistance_coeff``. Default ``{}``: the model's defaults
        (isotropic, kappa = 1). Only with a force model given by name.
    multi_pass : bool
        A wheel running in the rut of the wheel ahead of it meets only the compaction of the
        soil below that rut (Wong §2.4, repetitive loading; ``WheelSoilInjector``'s
        ``multi_pass``). Default ``False`` (every wheel cuts its own rut). Per-wheel soil law
        only: a Wong-Chiang track (``tracked_patako_wong_chiang``) has its own rut state.
    castor_own_geometry : bool
        Castors (non-driven wheels) meet the Bekker compaction of their own wheel (radius,
        width, contact length; ``WheelSoilInjector``'s ``castor_own_geometry``) instead of the
        driven wheels' the force model was built for. Default ``False``: the farm vehicle's
        castors are an assumption (Lindgren gives none), and at their assumed size (0.30 m x
        0.12 m, ~1200 N each) on field loam they would meet ~300 N each, twice the default.
    path : str | Path
        Path name (``slipenv.paths.path_by_name``) or a built ``Path``.
    path_kwargs : dict[str, Any]
        Arguments of the named path (radius, speed, ...).
    estimator : str
        Odometry estimator producing the observation (``slipenv.envs.estimation``).
    estimator_kwargs : dict[str, Any]
        Arguments of the estimator.
    sensor_noise : SensorNoise | dict[str, float]
        Sensor noise levels (DESIGN §4 defaults); stored as a ``SensorNoise``.
    beacons : Beacons
        Laser beacon scanner (Lindgren §2.2): ``True`` (or ``"default"``) for the default
        15-beacon field, an (n, 2) array of surveyed beacon positions [m], or a scanner;
        ``None`` or ``False`` for none.
    control_hz, physics_hz : float
        Env step and physics substep rates [Hz].
    max_episode_s : float
        Episode time limit [s] (truncation).
    max_cross_track_m : float | None
        Half-width of the corridor [m]: a true cross-track error beyond it ends the episode
        as failed, so success means reaching the path's end inside it. ``None`` (default):
        a corridor that fits the path, :func:`corridor_for` (0.4 of the path's smallest
        turning radius, at most 2 m).
    reward_weights : dict[str, float]
        Weights (finite, >= 0) of the named reward terms ``cross_track``, ``heading``,
        ``progress``, ``effort``; each term's value is reported in ``info["reward_terms"]``.
        The terms carry their own signs (the penalties are <= 0, progress >= 0), so a
        negative weight would reward what the term penalises.
    start_jitter : tuple[float, float]
        ``(position_m, yaw_deg)``: ``reset(seed)`` starts the vehicle at the path's start
        moved by a uniform offset within a disc of ``position_m`` [m] and turned by a uniform
        angle in ``±yaw_deg`` [deg] (default 2 cm, 1°; at most 1 m, 30°), so every seed is a
        different episode. The estimator is told the jittered start (a surveyed start pose).
    camera_in_info : bool
        With an estimator that uses the rear trace camera (``estimator="scomp"``), put each
        rendered :class:`~slipenv.sensors.trace_camera.TraceFrame` (image and true trace) in
        ``info["trace_frame"]`` (``None`` on steps without a frame). Default off: the frames
        are 240 × 320 bytes each at 5 Hz. ``render()`` shows the last frame either way.

    Notes
    -----
    Every field is checked on construction (``ValueError`` naming the option, with a "did you
    mean" for misspelt names): names must be known presets, nested dicts may hold only their
    type's fields, numbers must be finite. ``physics_hz`` is at most 2000 Hz (the stiffest
    wheel contact, 1 mm static sinkage, rings at about 16 Hz and is resolved 100 times over,
    while the cost grows with the rate: 0.09 s of wall time per simulated second at 2000 Hz,
    about 5 s at 1e5 Hz) and an integer multiple of ``control_hz``.
    ``path_kwargs`` must be parameters of the named path builder, and the path (named or
    built) must fit the observation's ranges (:func:`check_path_fits`). ``estimator_kwargs``
    are checked by building the estimator when the env is made. This is the one place the options
    are checked: the builders (:mod:`slipenv.envs.factory`) and the
    :class:`~slipenv.sim.simulator.Simulator` take the checked values as they are.
    """

    vehicle: str | VehicleSpec = "husky"
    terrain: TerrainSpec | dict[str, Any] | str = "flat"
    soil: str | Soil = "loose_sand"
    soil_map: SoilMap | None = None
    force_model: str | ForceModel | ForceModelFactory = "reina"
    force_model_kwargs: dict[str, Any] = field(default_factory=dict)
    multi_pass: bool = False
    castor_own_geometry: bool = False
    path: str | Path = "circle"
    path_kwargs: dict[str, Any] = field(default_factory=dict)
    estimator: str = "dead_reckoning"
    estimator_kwargs: dict[str, Any] = field(default_factory=dict)
    sensor_noise: SensorNoise | dict[str, float] = field(default_factory=SensorNoise)
    beacons: Beacons = None
    control_hz: float = 20.0
    physics_hz: float = 240.0
    max_episode_s: float = 120.0
    max_cross_track_m: float | None = None
    reward_weights: dict[str, float] = field(
        default_factory=lambda: {"cross_track": 1.0, "heading": 0.2, "progress": 1.0,
                                 "effort": 0.05}
    )
    start_jitter: tuple[float, float] = (0.02, 1.0)
    camera_in_info: bool = False

    def __post_init__(self) -> None:
        _check_choice("vehicle", self.vehicle, VEHICLES, VehicleSpec)
        object.__setattr__(self, "terrain", _terrain(self.terrain))
        _check_choice("soil", self.soil, SOILS, Soil)
        if self.soil_map is not None and not isinstance(self.soil_map, SoilMap):
            raise ValueError(f"soil_map must provide params_at(x, y), got {self.soil_map!r}")
        if isinstance(self.force_model, str):
            _check_choice("force_model", self.force_model, FORCE_MODELS, None)
        elif not (hasattr(self.force_model, "resistance_n") or callable(self.force_model)):
            raise ValueError("force_model must be a name, a ForceModel or a factory, got "
                             f"{self.force_model!r}")
        _check_force_model_kwargs(self.force_model, self.force_model_kwargs)
        if not isinstance(self.multi_pass, bool):
            raise ValueError(f"multi_pass must be True or False, got {self.multi_pass!r}")
        if self.multi_pass and _track_model(self.vehicle) is not None:
            raise ValueError(
                f"multi_pass applies to the per-wheel soil law; vehicle {_name(self.vehicle)!r} "
                f"uses the {_track_model(self.vehicle)!r} track model, whose rut state already "
                "lets the rear of the track run in the rut the front cut")
        if not isinstance(self.castor_own_geometry, bool):
            raise ValueError("castor_own_geometry must be True or False, got "
                             f"{self.castor_own_geometry!r}")
        _check_choice("path", self.path, PATHS, Path)
        _check_options("path_kwargs", self.path_kwargs)
        if isinstance(self.path, str):
            _check_names(f"path_kwargs of path {self.path!r}", self.path_kwargs,
                         _path_parameters(self.path))
        if not isinstance(self.estimator, str):
            raise ValueError(f"estimator must be an estimator name, got {self.estimator!r}")
        _check_options("estimator_kwargs", self.estimator_kwargs)
        object.__setattr__(self, "sensor_noise", _sensor_noise(self.sensor_noise))
        object.__setattr__(self, "beacons", _beacons(self.beacons))
        for name in ("control_hz", "physics_hz", "max_episode_s", "max_cross_track_m"):
            value = getattr(self, name)
            if name == "max_cross_track_m" and value is None:
                continue
            if not (_is_number(value) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}"
                                 + (" (or None: a corridor that fits the path)"
                                    if name == "max_cross_track_m" else ""))
        for name, high in LIMITS.items():
            if getattr(self, name) is not None and getattr(self, name) > high:
                raise ValueError(f"{name} must be <= {high:g}, got {getattr(self, name)!r}"
                                 + (f" ({LIMIT_REASONS[name]})" if name in LIMIT_REASONS else ""))
        ratio = self.physics_hz / self.control_hz
        if ratio < 1.0 - 1e-9 or abs(ratio - round(ratio)) > 1e-9:
            raise ValueError(f"physics_hz ({self.physics_hz:g}) must be an integer multiple of "
                             f"control_hz ({self.control_hz:g}), got a ratio of {ratio:g}")
        jitter = self.start_jitter
        if (not isinstance(jitter, tuple | list) or len(jitter) != 2
                or not all(_is_number(v) and math.isfinite(v) for v in jitter)
                or not (0.0 <= jitter[0] <= 1.0 and 0.0 <= jitter[1] <= 30.0)):
            raise ValueError("start_jitter must be (position_m, yaw_deg) with 0 <= position_m "
                             f"<= 1 and 0 <= yaw_deg <= 30, got {jitter!r}")
        object.__setattr__(self, "start_jitter", (float(jitter[0]), float(jitter[1])))
        check_path_fits(self.path if isinstance(self.path, Path)
                        else make_path(self.path, self.path_kwargs),
                        self.vehicle, self.max_cross_track_m, self.start_jitter[0],
                        "path_kwargs" if isinstance(self.path, str) else "path")
        if not isinstance(self.camera_in_info, bool):
            raise ValueError(f"camera_in_info must be True or False, got {self.camera_in_info!r}")
        _check_options("reward_weights", self.reward_weights)
        _check_names("reward_weights", self.reward_weights, REWARD_TERMS, what="reward term")
        for key, value in self.reward_weights.items():
            if not (_is_number(value) and math.isfinite(value) and value >= 0):
                raise ValueError(
                    f"reward_weights[{key!r}] must be a finite number >= 0, got {value!r} "
                    "(each term carries its own sign: cross_track, heading and effort are "
                    "penalties <= 0, progress is >= 0; a negative weight would reward what "
                    "the term penalises)")

    def corridor_m(self, path: Path) -> float:
        """The corridor half-width [m] the env judges ``path`` by: ``max_cross_track_m``, or
        when it is None the corridor that fits the path (:func:`corridor_for`)."""
        return corridor_for(path) if self.max_cross_track_m is None else self.max_cross_track_m

    @classmethod
    def from_kwargs(cls, base: SlipEnvConfig | None = None, **kwargs: Any) -> SlipEnvConfig:
        """Build a config from make kwargs on top of ``base``; unknown names are an error."""
        names = {f.name for f in fields(cls)}
        for key in kwargs:
            if key not in names:
                close = difflib.get_close_matches(key, sorted(names), n=1)
                hint = f"; did you mean {close[0]!r}?" if close else ""
                raise ValueError(f"unknown slipenv option {key!r}{hint} Options: {sorted(names)}")
        merged = dict(kwargs)
        if base is not None and not isinstance(base, SlipEnvConfig):
            raise ValueError(f"config must be a SlipEnvConfig (or omitted), got {base!r}; "
                             "pass options as keyword arguments instead")
        if base is not None:
            for key in ("reward_weights",):
                if isinstance(merged.get(key), dict) and isinstance(getattr(base, key), dict):
                    merged[key] = {**getattr(base, key), **merged[key]}
            # A preset's options belong to its path, estimator and force model: choosing
            # another one by name starts from that one's own defaults.
            for choice, options in (("path", "path_kwargs"), ("estimator", "estimator_kwargs"),
                                    ("force_model", "force_model_kwargs")):
                if (choice in merged and options not in merged
                        and merged[choice] != getattr(base, choice)):
                    merged[options] = {}
            return replace(base, **merged)
        return cls(**merged)


LIMITS = {"physics_hz": 2000.0, "control_hz": 1000.0, "max_episode_s": 86400.0,
          "max_cross_track_m": 1000.0}
LIMIT_REASONS = {
    "physics_hz": "the stiffest wheel contact (1 mm static sinkage) rings at about 16 Hz, "
                  "resolved 100 times over at 2000 Hz, while the cost grows with the rate: "
                  "0.09 s of wall time per simulated second at 2000 Hz, about 5 s at 1e5 Hz",
}


def _is_number(value: Any) -> bool:
    return isinstance(value, numbers.Real) and not isinstance(value, bool)


def _suggest(name: Any, choices) -> str:
    choices = sorted(map(str, choices))
    close = difflib.get_close_matches(str(name), choices, n=1)
    close = close or [c for c in choices if str(name) and str(name) in c][:1]
    return f"; did you mean {close[0]!r}?" if close else ""


def _check_choice(option: str, value: Any, names, instance_type) -> None:
    """``value`` must be a known name or (when ``instance_type`` is given) an instance."""
    if isinstance(value, str):
        if value not in names:
            raise ValueError(f"unknown {option.replace('_', ' ')} {value!r} (option "
                             f"{option!r}){_suggest(value, names)} Known: {sorted(names)}")
        return
    if instance_type is not None and isinstance(value, instance_type):
        return
    kinds = "a name" + (f" or a {instance_type.__name__}" if instance_type else "")
    raise ValueError(f"{option} must be {kinds} (known names: {sorted(names)}), got {value!r}")


def _check_options(option: str, value: Any) -> None:
    if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
        raise ValueError(f"{option} must be a dict with string keys, got {value!r}")


def _check_names(option: str, given, allowed, what: str = "option") -> None:
    """Every key of ``given`` must be in ``allowed`` (else a "did you mean" error)."""
    for key in given:
        if key not in allowed:
            raise ValueError(f"unknown {what} {key!r} in {option}{_suggest(key, allowed)} "
                             f"Allowed: {sorted(allowed)}")


def _build(cls, values: dict, owner: str):
    _check_options(owner, values)
    _check_names(owner, values, [f.name for f in fields(cls)])
    return _named(owner, cls, **values)


def _named(owner: str, cls, **values):
    """``cls(**values)``, with the option ``owner`` named in any error."""
    try:
        return cls(**values)
    except ValueError as exc:
        raise ValueError(f"{owner}: {exc}") from None


# A wheel's contact geometry for checking a force model's options (any valid one).
_NOMINAL_GEOMETRY = ContactGeometry(radius_m=0.1, width_m=0.1, contact_length_m=0.05)


def _check_force_model_kwargs(force_model: Any, kwargs: Any) -> None:
    """``kwargs`` must be options of the named force model's class, numbers where its default
    is a number, flags where it is a flag, and build the model (its range checks)."""
    _check_options("force_model_kwargs", kwargs)
    if not kwargs:
        return
    if not isinstance(force_model, str):
        raise ValueError("force_model_kwargs apply to a force model given by name; with a "
                         f"model instance or factory pass its options to it (got "
                         f"force_model={force_model!r}, force_model_kwargs={kwargs!r})")
    cls = FORCE_MODELS[force_model]
    params = {k: v for k, v in inspect.signature(cls).parameters.items() if k != "geometry"}
    try:
        _check_names(f"force_model_kwargs of force model {force_model!r}", kwargs, params)
    except ValueError as exc:
        extra = (" (Reina's law has its own lateral stiffness C_y; use force_model='janosi' "
                 "or 'linear' for a lateral_stiffness_ratio)"
                 if "lateral_stiffness_ratio" in kwargs and "lateral_stiffness_ratio" not in params
                 else "")
        raise ValueError(f"{exc}{extra}") from None
    for key, value in kwargs.items():
        default = params[key].default
        if isinstance(default, bool):
            if not isinstance(value, bool):
                raise ValueError(f"force_model_kwargs[{key!r}] must be True or False, "
                                 f"got {value!r}")
        elif _is_number(default) and not (_is_number(value) and math.isfinite(value)):
            raise ValueError(f"force_model_kwargs[{key!r}] must be a finite number, "
                             f"got {value!r}")
    try:
        cls(_NOMINAL_GEOMETRY, **kwargs)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"force_model_kwargs: {exc}") from None


def _name(vehicle: str | VehicleSpec) -> str:
    return vehicle if isinstance(vehicle, str) else vehicle.name


def _track_model(vehicle: str | VehicleSpec) -> str | None:
    """The vehicle's track model (``None``: the per-wheel law)."""
    spec = VEHICLES[vehicle]() if isinstance(vehicle, str) else vehicle
    return None if spec.track_model == "per_wheel" else spec.track_model


def _terrain(value: Any) -> TerrainSpec:
    if isinstance(value, TerrainSpec):
        return value
    if isinstance(value, str):
        return _named("terrain", TerrainSpec, kind=value)
    if isinstance(value, dict):
        return _build(TerrainSpec, value, "terrain")
    raise ValueError(f"terrain must be a TerrainSpec, dict or kind name, got {value!r}")


def _sensor_noise(value: Any) -> SensorNoise:
    if isinstance(value, SensorNoise):
        return value
    if isinstance(value, dict):
        return _build(SensorNoise, value, "sensor_noise")
    raise ValueError(
        f"sensor_noise must be a SensorNoise or a dict of its fields, got {value!r} (for "
        "noise-free sensors pass SensorNoise.perfect(); for the defaults omit it or pass {})"
    )


def _beacons(value: Beacons) -> Beacons:
    """``None``/``False`` (none), ``True``/``"default"``, a scanner, or (n, 2) positions,
    which are stored as a tuple of (x, y) pairs so configs stay comparable and hashable."""
    if value is None or value is False or value is True or isinstance(value, BeaconScanner):
        return value
    if isinstance(value, str):
        if value == "default":
            return True
        raise ValueError(f"beacons must be True, 'default', None, an (n, 2) array of "
                         f"positions [m] or a BeaconScanner, got {value!r}")
    xy = as_beacons_xy(value, "beacons")
    return tuple((float(x), float(y)) for x, y in xy)


CORRIDOR_RADIUS_FRACTION = 0.4
"""Default corridor half-width as a fraction of the path's smallest turning radius: below one
radius, so that a vehicle at the centre of a turn (spinning in place there, or spiralled in)
is outside the corridor, with a margin; and every point of the corridor then lies nearer to
one branch of the turn than to the opposite one."""
CORRIDOR_CAP_M = 2.0
"""Default corridor half-width [m] on paths whose turns are wide or absent (a straight)."""
# The observation's ranges (slipenv.contracts.observation) that a path's values reach: the
# position (indices 0, 1), the yaw rate (5), the path curvature (9) and reference speed (10).
OBS_POSITION_M = float(OBS_HIGH[OBS_X])
OBS_YAW_RATE_RPS = float(OBS_HIGH[OBS_YAW_RATE])
OBS_CURVATURE_1PM = float(OBS_HIGH[OBS_CURVATURE])
OBS_REF_SPEED_MPS = float(OBS_HIGH[OBS_REF_SPEED])


def corridor_for(path: Path) -> float:
    """Corridor half-width [m] that fits ``path``: ``CORRIDOR_RADIUS_FRACTION`` (0.4) of its
    smallest turning radius, at most ``CORRIDOR_CAP_M`` (2 m). Yamauchi's r = 0.25 m circle
    gets 0.1 m; a straight, 2 m."""
    return min(CORRIDOR_CAP_M, CORRIDOR_RADIUS_FRACTION * path.min_turning_radius_m)


def check_path_fits(path: Path, vehicle: str | VehicleSpec, max_cross_track_m: float | None,
                    jitter_m: float, option: str = "path_kwargs") -> None:
    """Refuse a path whose values the observation would clip.

    Bounds (each error names ``option`` and states the bound):

    * position: every point of the path, widened by the corridor and the start jitter (as
      far as the true vehicle can be before the episode ends), within the observation's
      ±1e4 m, so the policy never sees a clipped position;
    * reference speed at most 50 m/s and the yaw rate it demands (speed x curvature) at most
      20 rad/s, the observation's ranges (the presets' vehicles top out at 0.3-1.2 m/s and
      0.6-1.5 rad/s, so these bounds only refuse values no vehicle here could approach);
    * turning radius at least 1 mm (curvature within the observation's 1e3 1/m).
    """
    spec = VEHICLES[vehicle]() if isinstance(vehicle, str) else vehicle
    about = (f"vehicle {spec.name!r} tops out at {spec.max_speed_mps:g} m/s and "
             f"{spec.max_yaw_rate_rad_s:g} rad/s")
    x0, y0, x1, y1 = path.extent()
    corridor = corridor_for(path) if max_cross_track_m is None else max_cross_track_m
    reach = max(abs(x0), abs(y0), abs(x1), abs(y1)) + corridor + jitter_m
    if not reach <= OBS_POSITION_M:
        raise ValueError(
            f"{option}: path {path.name!r} reaches {reach:.3g} m from the origin (its extent "
            f"x in [{x0:.3g}, {x1:.3g}], y in [{y0:.3g}, {y1:.3g}] m, plus the {corridor:.3g} "
            f"m corridor and the start jitter), beyond the observation's position range of "
            f"±{OBS_POSITION_M:g} m; use a smaller path (radius_m, length_m, loops, ...)")
    if not path.max_speed_mps <= OBS_REF_SPEED_MPS:
        raise ValueError(
            f"{option}: speed_mps reaches {path.max_speed_mps:g} m/s, beyond the "
            f"observation's reference-speed range of {OBS_REF_SPEED_MPS:g} m/s ({about})")
    if not path.max_curvature_1pm <= OBS_CURVATURE_1PM:
        raise ValueError(
            f"{option}: path {path.name!r} turns on a radius of "
            f"{path.min_turning_radius_m:.3g} m, below 1 mm (curvature beyond the "
            f"observation's range of {OBS_CURVATURE_1PM:g} 1/m)")
    if not path.max_yaw_rate_rps <= OBS_YAW_RATE_RPS:
        raise ValueError(
            f"{option}: path {path.name!r} asks for a yaw rate of {path.max_yaw_rate_rps:.3g} "
            f"rad/s (speed_mps x curvature on a radius of {path.min_turning_radius_m:.3g} m), "
            f"beyond the observation's yaw-rate range of {OBS_YAW_RATE_RPS:g} rad/s ({about})")


def _path_parameters(name: str) -> list[str]:
    return list(inspect.signature(PATHS[name]).parameters)
