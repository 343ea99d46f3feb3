"""A diagnosed model extension carried into the simulated world: ``apply_model``.

``gymnasium.make(env_id, model=report)`` (``SlipEnvConfig.model``) makes ``SlipEnv`` call
:func:`apply_model`, which rewrites the world's vehicle, soil, force law and sensor noise so the
next training run drives in the corrected world. ``model`` is either the diagnosis report
(``{"cause", "also", "parameters": {name: [value, se]}, ...}``, ``log-format.md``) or a plain
``{effect: {parameter: value}}`` dict. An optional ``"nominal"`` entry (the report writes it)
holds the log's nominal ``wheel_radius_m`` and ``track_width_m``: fitted radii and track
widths are then applied as ratios to the simulated vehicle's own geometry.

How each effect enters the physics (the PyBullet world, not the kinematic replay):

============== =================================================================================
rolling_radius ``WheelSpec.rolling_radius_m`` of every driven wheel on that side
track_width    wheel positions scaled laterally (and ``track_width_m``)
torque_slip    longitudinal slip stiffness of the force law scaled to k_s per drive channel
soil_patch     a ``PatchSoilMap`` disc whose soil is that much softer (Reina's C_x, or the
               Janosi/linear shear modulus K)
slope_side_slip lateral slip stiffness scaled so that β = β_roll roll on a side slope (sum of
               the driven wheels' side forces balances m g sin roll), offset β_0 as a crab angle
combined_slip  the force law's zero-traction slip moved to s_x(β) (Reina Eq. 12; forward travel)
turning_slip   approximation: its yaw loss as a track-width change, 1/(1 - κ); the Endo split
               of forward speed has no counterpart in the force law and is not carried over
gyro_bias      ``SensorNoise.gyro_bias_rad_s``
============== =================================================================================
"""

from __future__ import annotations

import dataclasses
import math
import re
from typing import Any

import numpy as np

from slipenv.diagnose.effects import EFFECT_IDS, effect
from slipenv.diagnose.replay import wheel_sides
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.terramechanics.presets import soil_by_name
from slipenv.terramechanics.soil import Soil
from slipenv.terramechanics.soil_map import Circle, PatchSoilMap
from slipenv.vehicles.spec import VehicleSpec

_G = 9.81  # [m/s^2]
OPTIONAL = {"slope_side_slip": {"beta_per_roll_yaw_rate_s": 0.0}}
"""Parameters slipenv adds to the contract's list, with the value that switches them off."""
_PER_WHEEL = re.compile(r"^(radius|k_s|patch_k_s)_(?P<wheel>[A-Za-z0-9_]+?)_(m|nm)$")


class ScaledSlipForceModel:
    """A force law with scaled slip stiffnesses and shifted zero-force slips.

    At small slip the longitudinal and side stiffnesses are ``long_scale`` and ``lat_scale``
    times the base law's; the wheel rolls free at slip s_x(β) = s_x0 + k_β max(|β| - β0, 0)
    (Reina Eq. 12) and drifts free at slip angle β_0. For Reina's law the stiffnesses C_x,
    C_y of the soil are scaled (the friction limit and the combined-slip coupling stay those
    of the real slips); the isotropic Janosi and linear laws have one stiffness, K, so their
    slip inputs are scaled instead: ``base((s - s_x) a_long, (tan β - tan β_0) a_lat)``.
    """

    def __init__(self, base, long_scale=1.0, lat_scale=1.0, lat_offset_rad=0.0,
                 s_x0=0.0, k_beta=0.0, beta0_rad=0.0) -> None:
        from slipenv.terramechanics.models import ReinaForceModel

        self.base = base
        self.long_scale, self.lat_scale = float(long_scale), float(lat_scale)
        self.tan_offset = math.tan(lat_offset_rad)
        self.s_x0, self.k_beta, self.beta0 = float(s_x0), float(k_beta), float(beta0_rad)
        inner = base
        while isinstance(inner, ScaledSlipForceModel):
            inner = inner.base
        self._reina = isinstance(inner, ReinaForceModel)
        self._soils: dict[int, tuple] = {}

    def _soil(self, soil):
        if not self._reina:
            return soil
        hit = self._soils.get(id(soil))
        if hit is None or hit[0] is not soil:
            if len(self._soils) > 64:
                self._soils.clear()
            hit = (soil, soil._replace(c_x_n=soil.c_x_n * self.long_scale,
                                       c_y_n=soil.c_y_n * self.lat_scale))
            self._soils[id(soil)] = hit
        return hit[1]

    def _input_scales(self) -> tuple[float, float]:
        return (1.0, 1.0) if self._reina else (self.long_scale, self.lat_scale)

    def __call__(self, slip, tan_beta, load_n, soil):
        beta = np.abs(np.arctan(tan_beta))
        shift = self.s_x0 + self.k_beta * np.maximum(beta - self.beta0, 0.0)
        ls, la = self._input_scales()
        return self.base((np.asarray(slip) - shift) * ls,
                         (np.asarray(tan_beta) - self.tan_offset) * la, load_n, self._soil(soil))

    def resistance_n(self, load_n, soil):
        return self.base.resistance_n(load_n, soil)

    def scalar_kernel(self, soil):
        """Float kernel ``(slip, tan_beta, load) -> (fx, fy, resistance)`` (the hot path)."""
        from slipenv.sim.wheel_soil import _kernel

        inner = _kernel(self.base, self._soil(soil))
        (ls, la), off = self._input_scales(), self.tan_offset
        sx0, kb, b0 = self.s_x0, self.k_beta, self.beta0

        def kernel(slip: float, tan_beta: float, load_n: float):
            shift = sx0 + kb * max(abs(math.atan(tan_beta)) - b0, 0.0) if (sx0 or kb) else 0.0
            return inner((slip - shift) * ls, (tan_beta - off) * la, load_n)

        return kernel


@dataclasses.dataclass(frozen=True)
class ScaledSlip:
    """Force-model factory (``SlipEnvConfig.force_model``) wrapping ``base`` in the above."""

    base: Any
    options: tuple[tuple[str, float], ...]

    def __call__(self, geometry):
        from slipenv.terramechanics.models import force_model_by_name

        base = self.base
        if isinstance(base, str):
            base = force_model_by_name(base, geometry)
        elif not hasattr(base, "resistance_n"):
            base = base(geometry)
        return ScaledSlipForceModel(base, **dict(self.options))


def parse_model(model: Any) -> tuple[dict[str, dict[str, float]], dict[str, float]]:
    """``model`` (report or ``{effect: {param: value}}``) -> (effects, nominal geometry).

    Raises
    ------
    ValueError
        For an unknown effect, an unknown, missing or non-numeric parameter.
    """
    if not isinstance(model, dict):
        raise ValueError(f"model must be a dict (a diagnosis report or {{effect: {{param: "
                         f"value}}}}), got {type(model).__name__}")
    nominal = {k: float(v) for k, v in (model.get("nominal") or {}).items()}
    if "cause" in model or "parameters" in model:
        names = [model.get("cause", "none"), *model.get("also", [])]
        for name in names:
            effect(name) if name != "none" else None
        names = [n for n in names if n != "none"]
        if isinstance(model.get("effects"), dict):
            raw = {n: model["effects"].get(n, {}) for n in names}
        else:
            raw = _split_parameters(names, model.get("parameters") or {})
    else:
        raw = {k: v for k, v in model.items() if k != "nominal"}
    out: dict[str, dict[str, float]] = {}
    for name, params in raw.items():
        if name == "none":
            continue
        eff = effect(name)
        if not isinstance(params, dict):
            raise ValueError(f"parameters of effect {name!r} must be a dict, got {params!r}")
        values = {k: _number(name, k, v) for k, v in params.items()}
        wheels = sorted({m["wheel"] for k in values if (m := _PER_WHEEL.match(k))})
        expected = set(eff.contract_names(wheels))
        unknown = sorted(set(values) - expected)
        if unknown:
            raise ValueError(f"unknown parameter(s) {unknown} for effect {name!r}; expected "
                             f"{sorted(eff.contract_names(['<wheel>']))}")
        for key, default in OPTIONAL.get(name, {}).items():
            values.setdefault(key, default)
        missing = sorted(expected - set(values))
        if missing or (eff.per_side and not wheels):
            raise ValueError(f"effect {name!r} is missing parameter(s) "
                             f"{missing or sorted(eff.contract_names(['<wheel>']))}")
        out[name] = values
    return out, nominal


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
        owners = [n for n in names if _belongs(n, key, "torque_slip" in names)]
        if not owners:
            raise ValueError(f"parameter {key!r} belongs to none of the effects {names}")
        name = key[len("patch_"):] if key.startswith("patch_k_s_") else key
        out[owners[0]][name] = value
    return out


def _belongs(name: str, key: str, torque_too: bool) -> bool:
    eff = effect(name)
    if key in eff.contract.values():
        return True
    if name == "soil_patch" and torque_too:
        return key.startswith("patch_k_s_")
    return any(re.fullmatch(t.replace("{w}", "[A-Za-z0-9_]+?"), key) for t in eff.per_side.values())


def apply_model(config: SlipEnvConfig, model: Any) -> SlipEnvConfig:
    """The config of the world extended by ``model`` (see the module docstring).

    Returns a new config with the vehicle spec, soil map, force model and sensor noise
    rewritten and ``model`` cleared (so applying the result again changes nothing).
    """
    if model is None:
        return config
    effects, nominal = parse_model(model)
    spec = make_vehicle(config.vehicle)
    soil = config.soil if isinstance(config.soil, Soil) else soil_by_name(config.soil)
    changes: dict[str, Any] = {"model": None}
    wrap: dict[str, float] = {}
    for name, values in effects.items():
        if name == "rolling_radius":
            spec = _radii(spec, values, nominal)
        elif name in ("track_width", "turning_slip"):
            w = values["track_width_m"] if name == "track_width" else None
            ratio = (w / nominal.get("track_width_m", spec.track_width_m) if w is not None
                     else 1.0 / max(1.0 - values["turn_slip_scale"], 0.05))
            spec = _scale_track(spec, ratio)
        elif name == "torque_slip":
            k_s = np.mean([v for k, v in values.items() if k.startswith("k_s_")])
            wrap["long_scale"] = k_s / _channel_stiffness(config, spec, soil)
        elif name == "soil_patch":
            k_s = np.mean([v for k, v in values.items() if k.startswith("k_s_")])
            inner = _softer(soil, k_s / _channel_stiffness(config, spec, soil),
                            _base_law(config, spec))
            radius = values["patch_radius_m"]
            disc = Circle(values["patch_center_x_m"], values["patch_center_y_m"], radius)
            changes["soil_map"] = PatchSoilMap(soil, [(disc, inner)], blend_width_m=0.2 * radius)
        elif name == "slope_side_slip":
            c_y = _lateral_stiffness(config, spec, soil)
            bpr = abs(values["beta_per_roll"]) or 1e-6
            wrap["lat_scale"] = spec.mass_kg * _G / bpr / c_y
            wrap["lat_offset_rad"] = values["beta_offset_rad"]
        elif name == "combined_slip":
            wrap.update(s_x0=values["s_x0"], k_beta=values["k_beta"],
                        beta0_rad=values["beta0_rad"])
        elif name == "gyro_bias":
            changes["sensor_noise"] = dataclasses.replace(
                config.sensor_noise, gyro_bias_rad_s=values["gyro_bias_rad_s"])
    if wrap:
        changes["force_model"] = ScaledSlip(config.force_model, tuple(sorted(wrap.items())))
    if spec != make_vehicle(config.vehicle):
        changes["vehicle"] = spec
    return dataclasses.replace(config, **changes)


def _base_law(config: SlipEnvConfig, spec: VehicleSpec):
    """The force law under any ``ScaledSlip`` wrappers."""
    model = make_force_model(config.force_model, spec)
    while isinstance(model, ScaledSlipForceModel):
        model = model.base
    return model


def _softer(soil: Soil, f: float, law) -> Soil:
    """``soil`` with its longitudinal slip stiffness times ``f``.

    Reina's law has its own longitudinal stiffness C_x (the side stiffness C_y stays); the
    Janosi and linear laws take theirs from the shear modulus K, isotropically.
    """
    from slipenv.terramechanics.models import ReinaForceModel

    if isinstance(law, ReinaForceModel):
        return dataclasses.replace(soil, name=f"{soil.name}_patch", c_x_n=soil.c_x_n * f)
    return dataclasses.replace(soil, name=f"{soil.name}_patch",
                               shear_modulus_m=soil.shear_modulus_m / f)


def _side_of(spec: VehicleSpec, wheel) -> int:
    return 0 if wheel.position_m[1] > 0 else 1


def _radii(spec: VehicleSpec, values: dict[str, float], nominal: dict) -> VehicleSpec:
    names = [k[len("radius_"):-len("_m")] for k in values]
    sides = wheel_sides(names)
    by_name = dict(zip(names, values.values(), strict=True))
    r_nom = nominal.get("wheel_radius_m", spec.wheel_radius_nominal_m)
    wheels = []
    for w in spec.wheels:
        if w.role != "driven":
            wheels.append(w)
            continue
        value = by_name.get(w.channel)
        if value is None:
            value = float(np.mean([v for v, s in zip(by_name.values(), sides, strict=True)
                                   if s == _side_of(spec, w)]))
        wheels.append(dataclasses.replace(w, rolling_radius_m=w.radius_m * value / r_nom))
    return dataclasses.replace(spec, wheels=tuple(wheels))


def _scale_track(spec: VehicleSpec, ratio: float) -> VehicleSpec:
    wheels = tuple(dataclasses.replace(w, position_m=(w.position_m[0], w.position_m[1] * ratio,
                                                      w.position_m[2])) for w in spec.wheels)
    return dataclasses.replace(spec, wheels=wheels, track_width_m=spec.track_width_m * ratio)


def _kernel_at_rest(config: SlipEnvConfig, spec: VehicleSpec, soil: Soil):
    from slipenv.sim.wheel_soil import _kernel

    model = make_force_model(config.force_model, spec)
    params = make_soil_map(soil, config.soil_map).params_at(np.zeros(1), np.zeros(1))
    if isinstance(params.cohesion_pa, np.ndarray):
        params = type(params)(*(float(np.ravel(v)[0]) for v in params))
    return _kernel(model, params), spec.mass_kg * _G / len(spec.wheels)


def _channel_stiffness(config: SlipEnvConfig, spec: VehicleSpec, soil: Soil) -> float:
    """Mean over drive channels of Σ r dF_x/ds at s = 0 and static load [N m per unit slip]."""
    kernel, load = _kernel_at_rest(config, spec, soil)
    k = abs(kernel(1e-4, 0.0, load)[0]) / 1e-4
    per_channel = [sum(w.radius_m * k for w in spec.wheels if w.channel == c)
                   for c in spec.channels]
    return float(np.mean(per_channel))


def _lateral_stiffness(config: SlipEnvConfig, spec: VehicleSpec, soil: Soil) -> float:
    """Σ over driven wheels of dF_y/d tan β at β = 0 and static load [N per unit tan β]."""
    kernel, load = _kernel_at_rest(config, spec, soil)
    c = abs(kernel(0.0, 1e-4, load)[1]) / 1e-4
    return c * sum(1 for w in spec.wheels if w.role == "driven")


__all__ = ["EFFECT_IDS", "ScaledSlip", "ScaledSlipForceModel", "apply_model", "parse_model"]
