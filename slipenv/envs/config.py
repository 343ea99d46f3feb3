"""Configuration of a slipenv environment: one frozen dataclass, every field a make kwarg.

``gymnasium.make("slipenv/Configurable-v0", vehicle="rover_4ws", soil="lunar_simulant", ...)``
builds a :class:`SlipEnvConfig` from the kwargs; an unknown kwarg is a ``ValueError`` that names
it and suggests the closest field (no silent typos).
"""

from __future__ import annotations

import difflib
import math
from dataclasses import dataclass, field, fields, replace
from typing import Any

from slipenv.sensors.noise import SensorNoise
from slipenv.terrain.terrain import TerrainSpec

REWARD_TERMS = ("cross_track", "heading", "progress", "effort")


@dataclass(frozen=True)
class SlipEnvConfig:
    """Everything that defines a slipenv task.

    Attributes
    ----------
    vehicle : str | VehicleSpec
        Vehicle preset name (``farm_2wd``, ``tracked_patako``, ``rover_4ws``, ``husky``) or spec.
    terrain : TerrainSpec | dict | str
        Ground geometry: a spec, its fields as a dict, or a kind name (``flat``/``slope``/
        ``mounds``).
    soil : str | Soil
        Soil preset name or a :class:`slipenv.terramechanics.soil.Soil`.
    soil_map : SoilMap | None
        A spatially varying soil (overrides ``soil``).
    force_model : str | ForceModel | callable
        ``"reina"``, ``"janosi"``, ``"linear"``, a model instance, or a callable taking the
        wheel's ``ContactGeometry`` and returning a model.
    path : str | Path
        Path name (``slipenv.paths.path_by_name``) or a built ``Path``.
    path_kwargs : dict
        Arguments of the named path (radius, speed, ...).
    estimator : str
        Odometry estimator producing the observation (``slipenv.envs.estimation``).
    estimator_kwargs : dict
        Arguments of the estimator.
    sensor_noise : SensorNoise | dict
        Sensor noise levels (DESIGN §4 defaults).
    beacons : bool | array | BeaconScanner | None
        Laser beacon scanner (Lindgren §2.2): ``True`` for the default 15-beacon field, an
        (n, 2) array of surveyed beacon positions [m], or a scanner; ``None`` for none.
    control_hz, physics_hz : float
        Env step and physics substep rates [Hz].
    max_episode_s : float
        Episode time limit [s] (truncation).
    max_cross_track_m : float
        True cross-track error that ends the episode as failed [m].
    reward_weights : dict
        Weights of the named reward terms ``cross_track``, ``heading``, ``progress``,
        ``effort``; each term's value is reported in ``info["reward_terms"]``.
    model : dict | None
        A fitted model extension (``slipenv diagnose``) applied to the world.
    """

    vehicle: Any = "husky"
    terrain: Any = "flat"
    soil: Any = "loose_sand"
    soil_map: Any = None
    force_model: Any = "reina"
    path: Any = "circle"
    path_kwargs: dict = field(default_factory=dict)
    estimator: str = "dead_reckoning"
    estimator_kwargs: dict = field(default_factory=dict)
    sensor_noise: Any = field(default_factory=SensorNoise)
    beacons: Any = None
    control_hz: float = 20.0
    physics_hz: float = 240.0
    max_episode_s: float = 120.0
    max_cross_track_m: float = 2.0
    reward_weights: dict = field(
        default_factory=lambda: {"cross_track": 1.0, "heading": 0.2, "progress": 1.0,
                                 "effort": 0.05}
    )
    model: dict | None = None

    def __post_init__(self) -> None:
        if isinstance(self.terrain, str):
            object.__setattr__(self, "terrain", TerrainSpec(kind=self.terrain))
        elif isinstance(self.terrain, dict):
            object.__setattr__(self, "terrain", _build(TerrainSpec, self.terrain, "terrain"))
        elif not isinstance(self.terrain, TerrainSpec):
            raise ValueError(
                f"terrain must be a TerrainSpec, dict or kind name, got {self.terrain!r}"
            )
        if isinstance(self.sensor_noise, dict):
            object.__setattr__(
                self, "sensor_noise", _build(SensorNoise, self.sensor_noise, "sensor_noise")
            )
        for name in ("control_hz", "physics_hz", "max_episode_s", "max_cross_track_m"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ValueError(f"{name} must be a finite number > 0, got {value!r}")
        unknown = set(self.reward_weights) - set(REWARD_TERMS)
        if unknown:
            raise ValueError(
                f"unknown reward term(s) {sorted(unknown)}; reward terms are {REWARD_TERMS}"
            )
        if not isinstance(self.path_kwargs, dict) or not isinstance(self.estimator_kwargs, dict):
            raise ValueError("path_kwargs and estimator_kwargs must be dicts")

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
        if base is not None:
            for key in ("reward_weights",):
                if key in merged:
                    merged[key] = {**getattr(base, key), **merged[key]}
            # A preset's options belong to its path and estimator: choosing another one by
            # name starts from that one's own defaults.
            for choice, options in (("path", "path_kwargs"), ("estimator", "estimator_kwargs")):
                if (choice in merged and options not in merged
                        and merged[choice] != getattr(base, choice)):
                    merged[options] = {}
            return replace(base, **merged)
        return cls(**merged)


def _build(cls, values: dict, owner: str):
    try:
        return cls(**values)
    except TypeError as exc:
        raise ValueError(f"bad {owner} options {sorted(values)}: {exc}") from None
