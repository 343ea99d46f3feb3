"""A sweep's grid file: env ids × env-kwarg variations (soils, slopes, ...) × policies × seeds.

Grid file (YAML)::

    env_ids: [slipenv/TrackedSlopeCircle-v0, slipenv/FarmField-v0]   # required
    policies: [baseline, feedback, runs/ppo/model.zip]                # required
    seeds: [0, 1, 2]              # required: a list, or {start: 0, count: 3}
    soils: [toyoura_sand, loose_sand]   # optional axis: env kwarg ``soil``
    slopes_deg: [5, 15]           # optional axis: the preset's ground tilted to this slope
    variations:                   # optional axis: named env-kwarg sets
      short: {max_episode_s: 20}
    env_kwargs: {}                # optional: applied to every cell (before the axes)
    max_steps: 400                # optional: step limit per episode

A *cell* is one (env id, variation, policy, seed) episode; the variations are the product of
the ``soils``, ``slopes_deg`` and ``variations`` axes. :func:`load_grid` validates everything
(keys, env ids, policies, soil names, every cell's env kwargs) before any episode runs.
"""

from __future__ import annotations

import dataclasses
import hashlib
import itertools
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from slipenv.contracts.names import did_you_mean

GRID_KEYS = ("env_ids", "policies", "seeds", "soils", "slopes_deg", "variations", "env_kwargs",
             "max_steps")
REQUIRED_KEYS = ("env_ids", "policies", "seeds")
CELL_VERSION = 1
"""Bumped when a cell's metrics change meaning, so old result files are not reused."""


@dataclass(frozen=True)
class Cell:
    """One episode of the grid.

    Attributes
    ----------
    env_id, variation, policy : str
        The env id, the variation's label (``default`` without axes) and the policy spec.
    seed : int
    env_kwargs : dict
        Everything passed to ``gymnasium.make`` (grid ``env_kwargs`` + the variation).
    max_steps : int or None
    policy_key : str
        The policy's identity in the hash (a model's content hash, so a retrained model at
        the same path is re-evaluated).
    """

    env_id: str
    variation: str
    policy: str
    seed: int
    env_kwargs: dict
    max_steps: int | None
    policy_key: str

    @property
    def key(self) -> str:
        """Hash of everything that decides the cell's result (16 hex digits)."""
        doc = {"v": CELL_VERSION, "env_id": self.env_id, "env_kwargs": self.env_kwargs,
               "policy": self.policy_key, "seed": self.seed, "max_steps": self.max_steps}
        text = json.dumps(doc, sort_keys=True, separators=(",", ":"))
        return hashlib.sha256(text.encode()).hexdigest()[:16]

    def to_dict(self) -> dict:
        return {**dataclasses.asdict(self), "key": self.key}


def _err(path: str | Path, message: str) -> ValueError:
    return ValueError(f"{path}: {message}")


def _seeds(path: str | Path, value: Any) -> list[int]:
    if isinstance(value, dict):
        unknown = set(value) - {"start", "count"}
        if unknown or "count" not in value:
            raise _err(path, f"seeds as a mapping needs keys start, count; got {sorted(value)}")
        value = list(range(int(value.get("start", 0)), int(value.get("start", 0))
                           + int(value["count"])))
    if (not isinstance(value, list) or not value
            or not all(isinstance(s, int) and not isinstance(s, bool) for s in value)):
        raise _err(path, f"seeds must be a non-empty list of integers, got {value!r}")
    if len(set(value)) != len(value):
        raise _err(path, f"seeds repeat: {value}")
    return value


def _str_list(path: str | Path, key: str, value: Any) -> list[str]:
    if not isinstance(value, list) or not value or not all(isinstance(v, str) for v in value):
        raise _err(path, f"{key} must be a non-empty list of strings, got {value!r}")
    return value


def _policy_key(path: str | Path, policy: str) -> str:
    from slipenv.evaluation.policies import resolve_policy

    try:
        source = resolve_policy(policy)
    except ValueError as exc:
        raise _err(path, f"policies: {exc}") from None
    if source.kind == "model" and source.model_path:
        digest = hashlib.sha256(Path(source.model_path).read_bytes()).hexdigest()[:16]
        return f"model:{source.algo}:{digest}:{json.dumps(source.residual, sort_keys=True)}"
    return source.key


def _variations(path: str | Path, grid: dict) -> list[tuple[str, dict, float | None]]:
    """(label, env kwargs, slope or None) for each point of the soils × slopes × variations
    product."""
    from slipenv.terramechanics.presets import SOILS

    soils = grid.get("soils") or [None]
    if soils != [None]:
        for soil in _str_list(path, "soils", soils):
            if soil not in SOILS:
                raise _err(path, f"soils: unknown soil {soil!r}{did_you_mean(soil, SOILS)}; "
                                 f"soils: {sorted(SOILS)}")
    slopes = grid.get("slopes_deg") or [None]
    if slopes != [None] and not all(isinstance(s, int | float) and not isinstance(s, bool)
                                    for s in slopes):
        raise _err(path, f"slopes_deg must be a list of numbers [deg], got {slopes!r}")
    named = grid.get("variations") or {None: {}}
    if not isinstance(named, dict) or not all(isinstance(v, dict) for v in named.values()):
        raise _err(path, "variations must map a name to a mapping of env kwargs")
    out = []
    for soil, slope, (name, kwargs) in itertools.product(soils, slopes, named.items()):
        parts = [p for p in (soil and f"soil={soil}",
                             slope is not None and f"slope={slope:g}deg", name) if p]
        env_kwargs = dict(kwargs)
        if soil is not None:
            env_kwargs["soil"] = soil
        out.append((",".join(parts) or "default", env_kwargs, slope))
    return out


def _cell_kwargs(path: str | Path, env_id: str, common: dict, variation: dict,
                 slope: float | None, label: str) -> dict:
    """The cell's env kwargs, validated against the id's preset (the slope tilts the preset's
    own terrain, keeping its downhill direction)."""
    from slipenv.envs.config import SlipEnvConfig
    from slipenv.envs.registration import preset_config
    from slipenv.terrain.terrain import TerrainSpec

    kwargs = {**common, **variation}
    try:
        cfg = SlipEnvConfig.from_kwargs(preset_config(env_id), **kwargs)
        if slope is not None:
            assert isinstance(cfg.terrain, TerrainSpec)  # SlipEnvConfig keeps a spec
            # Mounds stay mounds, on a tilted plane; flat ground becomes a slope. Empty
            # placed mounds are left out so that cells keep the keys they had before them.
            spec = {k: v for k, v in dataclasses.asdict(cfg.terrain).items()
                    if k != "placed_mounds" or v}
            kind = "mounds" if cfg.terrain.kind == "mounds" else "slope"
            terrain = {**spec, "kind": kind, "slope_deg": float(slope)}
            kwargs["terrain"] = terrain
            SlipEnvConfig.from_kwargs(cfg, terrain=terrain)
    except (ValueError, TypeError) as exc:
        raise _err(path, f"{env_id} variation {label!r}: {exc}") from None
    return kwargs


def load_grid(path: str | Path) -> list[Cell]:
    """Read and validate a grid file; returns its cells in grid order.

    Raises
    ------
    ValueError
        Naming the file and the key: an unknown key (with the closest known one), a missing
        required key, an unknown env id, policy or soil, bad seeds, or env kwargs the env
        would reject.
    """
    import yaml

    from slipenv.envs.registration import preset_config

    path = Path(path)
    if not path.is_file():
        raise ValueError(f"grid file {str(path)!r} does not exist")
    try:
        grid = yaml.safe_load(path.read_text())
    except yaml.YAMLError as exc:
        raise _err(path, f"not valid YAML: {str(exc).splitlines()[0]}") from None
    if not isinstance(grid, dict):
        raise _err(path, "a grid file is a mapping of keys " + ", ".join(GRID_KEYS))
    for key in grid:
        if key not in GRID_KEYS:
            raise _err(path, f"unknown key {key!r}{did_you_mean(key, GRID_KEYS)}. "
                             f"Keys: {', '.join(GRID_KEYS)}")
    missing = [k for k in REQUIRED_KEYS if k not in grid]
    if missing:
        raise _err(path, f"missing required key(s) {', '.join(missing)}")
    env_ids = _str_list(path, "env_ids", grid["env_ids"])
    for env_id in env_ids:
        try:
            preset_config(env_id)
        except ValueError as exc:
            raise _err(path, f"env_ids: {exc}") from None
    policies = _str_list(path, "policies", grid["policies"])
    policy_keys = {p: _policy_key(path, p) for p in policies}
    seeds = _seeds(path, grid["seeds"])
    common = grid.get("env_kwargs") or {}
    if not isinstance(common, dict):
        raise _err(path, f"env_kwargs must be a mapping, got {common!r}")
    max_steps = grid.get("max_steps")
    if max_steps is not None and (not isinstance(max_steps, int) or max_steps < 1):
        raise _err(path, f"max_steps must be an integer >= 1, got {max_steps!r}")
    cells = []
    for env_id in env_ids:
        for label, variation, slope in _variations(path, grid):
            kwargs = _cell_kwargs(path, env_id, common, variation, slope, label)
            for policy in policies:
                cells += [Cell(env_id, label, policy, seed, kwargs, max_steps,
                               policy_keys[policy]) for seed in seeds]
    return cells
