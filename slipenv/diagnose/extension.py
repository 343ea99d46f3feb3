"""A diagnosed model extension carried into the simulated world: ``apply_model``, ``make_env``.

::

    from slipenv.diagnose import apply_model, make_env
    from slipenv.envs.registration import preset_config

    config = apply_model(preset_config("slipenv/Husky-v0"), report)   # a new SlipEnvConfig
    env = gymnasium.make("slipenv/Husky-v0", config=config)
    env = make_env("slipenv/Husky-v0", report)                        # the same, in one call

``report`` is either the diagnosis report (``{"cause", "also", "parameters": {name: [value,
se]}, ...}``, ``log-format.md``) or a plain ``{effect: {parameter: value}}`` dict. An
optional ``"nominal"`` entry (the report writes it) holds the log's nominal
``wheel_radius_m`` and ``track_width_m``: fitted radii and track widths are then applied as
ratios to the simulated vehicle's own geometry. The report's ``vehicle_kind`` and wheel names
(``wheels``, and those in per-wheel parameter names) must be the env vehicle's kind and drive
channels: a model fitted on one vehicle says nothing about another.

How each effect enters the physics is in its module (``effects/<effect>.py``, ``apply``): the
vehicle spec, the soil map, a ``ScaledSlip`` wrapper of the force law, or the sensor noise.
The env itself knows nothing of the diagnosis.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from slipenv.diagnose.effects import Term, effect
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import wheel_sides
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.factory import make_vehicle
from slipenv.envs.registration import preset_config
from slipenv.vehicles.spec import VehicleSpec

_REPORT_KEYS = ("nominal", "vehicle_kind", "wheels")  # not effects in a plain model dict


@dataclass(frozen=True)
class Extension:
    """A parsed model: effects with their parameters, and what it was fitted on.

    Attributes
    ----------
    effects : dict
        ``{effect id: parameters}``, in the report's order (cause first).
    nominal : dict
        The log's nominal ``wheel_radius_m`` / ``track_width_m`` (may be empty).
    vehicle_kind : str or None
        Kind of the vehicle the model was fitted on, if the report says.
    wheels : tuple of str
        Wheel (drive channel) names the report names, sorted; empty if none.
    """

    effects: dict[str, Term]
    nominal: dict[str, float] = field(default_factory=dict)
    vehicle_kind: str | None = None
    wheels: tuple[str, ...] = ()


def parse_model(model: Any) -> Extension:
    """``model`` (a report or ``{effect: {param: value}}``) -> :class:`Extension`.

    Raises
    ------
    ValueError
        For an unknown effect, an unknown, missing or non-numeric parameter, a parameter that
        belongs to none of the report's effects, or parameters out of their range.
    """
    if not isinstance(model, dict):
        raise ValueError(f"model must be a dict (a diagnosis report or {{effect: {{param: "
                         f"value}}}}), got {type(model).__name__}")
    nominal = {k: _number("nominal", k, v) for k, v in (model.get("nominal") or {}).items()}
    kind = model.get("vehicle_kind")
    if kind is not None and not isinstance(kind, str):
        raise ValueError(f"vehicle_kind must be a string, got {kind!r}")
    wheels = set(model.get("wheels") or ())
    if "cause" in model or "parameters" in model:
        names = [model.get("cause", "none"), *model.get("also", [])]
        names = [effect(n).name for n in names if n != "none"]
        if isinstance(model.get("effects"), dict):
            raw = {n: model["effects"].get(n, {}) for n in names}
        else:
            raw = _split_parameters(names, model.get("parameters") or {})
    else:
        raw = {k: v for k, v in model.items() if k not in _REPORT_KEYS}
    out: dict[str, Term] = {}
    for name, params in raw.items():
        if name == "none":
            continue
        eff = effect(name)
        if not isinstance(params, dict):
            raise ValueError(f"parameters of effect {name!r} must be a dict, got {params!r}")
        values = {k: _number(name, k, v) for k, v in params.items()}
        named = eff.wheels_named(values)
        expected = set(eff.contract_names(named))
        unknown = sorted(set(values) - expected)
        if unknown:
            raise ValueError(f"unknown parameter(s) {unknown} for effect {name!r}; expected "
                             f"{sorted(eff.contract_names(['<wheel>']))}")
        for key, default in eff.optional.items():
            values.setdefault(key, default)
        missing = sorted(expected - set(values))
        per_wheel = len(eff.contract_names(["<wheel>"])) > len(eff.contract_names([]))
        if missing or (per_wheel and not named):
            raise ValueError(f"effect {name!r} is missing parameter(s) "
                             f"{missing or sorted(eff.contract_names(['<wheel>']))}")
        try:
            out[name] = eff.from_contract(values, named, wheel_sides(named))
        except ValueError as exc:  # the parameters' own checks name their fields
            raise _named(name, exc, f" (parameters {sorted(values)})") from exc
        wheels |= set(named)
    return Extension(out, nominal, kind, tuple(sorted(wheels)))


def _number(name: str, key: str, value: Any) -> float:
    if isinstance(value, list | tuple) and value:
        value = value[0]  # [value, standard error]
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ValueError(f"parameter {key!r} of effect {name!r} must be a finite number, "
                         f"got {value!r}")
    return float(value)


def _split_parameters(names: list[str], params: dict) -> dict[str, dict]:
    """Attribute a report's flat ``parameters`` to its effects by name."""
    out: dict[str, dict] = {n: {} for n in names}
    for key, value in params.items():
        for name in names:
            claimed = _claim(name, key, names)
            if claimed is not None:
                out[name][claimed] = value
                break
        else:
            raise ValueError(f"parameter {key!r} belongs to none of the effects {names}")
    return out


def _claim(name: str, key: str, names: list[str]) -> str | None:
    """The parameter name ``key`` stands for if effect ``name`` owns it, else None.

    A name two effects of the report share belongs to the one without a clash prefix; the
    other reports it with its prefix (``patch_k_s_<wheel>_nm``: ``effects.contract_report``).
    """
    eff = effect(name)
    others = [effect(n) for n in names if n != name]
    prefix = eff.clash_prefix
    if eff.matches(key):
        return None if prefix and any(o.matches(key) for o in others) else key
    if prefix and key.startswith(prefix):
        bare = key[len(prefix):]
        if eff.matches(bare) and any(o.matches(bare) for o in others):
            return bare
    return None


def check_vehicle(ext: Extension, spec: VehicleSpec) -> None:
    """ValueError unless the model was fitted on a vehicle of ``spec``'s kind and wheels."""
    kind_ok = ext.vehicle_kind is None or ext.vehicle_kind == spec.kind
    wheels_ok = not ext.wheels or set(ext.wheels) == set(spec.channels)
    if not (kind_ok and wheels_ok):
        raise ValueError(
            f"the model was fitted on a {ext.vehicle_kind or 'vehicle'} with wheels "
            f"{list(ext.wheels) or '(unnamed)'}, but the env's vehicle {spec.name!r} is a "
            f"{spec.kind} with wheels {list(spec.channels)}: a model applies only to the kind "
            "of vehicle it was fitted on, with the same wheel names")


def extend(config: SlipEnvConfig, effects: Mapping[str, Term],
           nominal: dict[str, float] | None = None) -> SlipEnvConfig:
    """``config`` with every effect applied, in order (no vehicle check: see
    :func:`apply_model`)."""
    edit = WorldEdit.of(config, nominal)
    for name, params in effects.items():
        try:
            effect(name).apply(edit, params)
        except ValueError as exc:  # e.g. the world's own checks (a vehicle 30 m wide)
            raise _named(name, exc, "", "cannot be applied to the simulation: ") from exc
    try:
        return edit.build()
    except ValueError as exc:
        raise _named("+".join(effects), exc, "", "cannot be applied to the simulation: ") \
            from exc


def _named(name: str, exc: ValueError, suffix: str, what: str = "") -> ValueError:
    """``exc`` with the effect's name in front (unless it already starts with it)."""
    text = str(exc)
    if text.startswith(f"effect {name!r}"):
        return ValueError(text + suffix)
    return ValueError(f"effect {name!r} {what}{text}{suffix}" if what
                      else f"effect {name!r}: {text}{suffix}")


def apply_model(config: SlipEnvConfig, report: Any) -> SlipEnvConfig:
    """A new env config: ``config``'s world extended by the diagnosed model ``report``.

    Parameters
    ----------
    config : SlipEnvConfig
        The world to extend (e.g. ``slipenv.envs.registration.preset_config(env_id)``).
    report : dict or None
        A diagnosis report (``slipenv diagnose --json``) or ``{effect: {param: value}}``;
        None returns ``config`` unchanged.

    Raises
    ------
    ValueError
        If the report is malformed (:func:`parse_model`) or was fitted on another kind of
        vehicle or other wheels than ``config``'s vehicle.
    """
    if report is None:
        return config
    ext = parse_model(report)
    check_vehicle(ext, make_vehicle(config.vehicle))
    return extend(config, ext.effects, ext.nominal)


def make_env(env_id: str, report: Any, render_mode: str | None = None, **overrides: Any):
    """``gymnasium.make(env_id, config=apply_model(preset, report))``.

    ``overrides`` replace fields of the id's preset config (as ``gymnasium.make(env_id,
    **overrides)`` would) before the model is applied.
    """
    import gymnasium as gym

    config = SlipEnvConfig.from_kwargs(preset_config(env_id), **overrides)
    extra: dict[str, Any] = {"render_mode": render_mode} if render_mode is not None else {}
    return gym.make(env_id, config=apply_model(config, report), **extra)


__all__ = ["Extension", "apply_model", "check_vehicle", "extend", "make_env", "parse_model"]
