"""The effect vocabulary of ``log-format.md``: parameters, bounds, applicability, naming.

Each :class:`Effect` names the internal parameters the kinematic replay (``replay.py``) reads,
their starting values, bounds and scales, and converts between them and the contract's SI
names (``radius_<wheel>_m``, ``k_s_<wheel>_nm``, ...) with standard errors. How an effect is
carried into the PyBullet world is in ``extension.py``.

Per-wheel parameters are fitted per *side* (left, right): wheels of one side of a skid-steer
vehicle turn together, so their radii or stiffnesses cannot be told apart; each wheel reports
its side's value. Torque compliance c = 1/k_s is what is fitted (linear in the slip, 0 when
there is no torque slip); k_s and its standard error follow by the delta method.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from slipenv.diagnose.replay import Segments

EFFECT_IDS = ("none", "rolling_radius", "track_width", "torque_slip", "turning_slip",
              "slope_side_slip", "combined_slip", "soil_patch", "gyro_bias")
_MIN_ROLL_RANGE_RAD = np.radians(2.0)  # roll must vary this much for β_roll to be identifiable
_MIN_BETA_RAD = np.radians(1.0)  # measured slip angle needed before combined slip is testable
_HUGE = 1e12  # k_s reported for a zero compliance (JSON has no infinity)


@dataclass(frozen=True)
class Param:
    """One internal parameter: name, start, bounds and typical scale (for the optimiser)."""

    name: str
    start: float
    lower: float
    upper: float
    scale: float


@dataclass(frozen=True)
class Effect:
    """One entry of the vocabulary.

    Attributes
    ----------
    name : str
        Effect id (``log-format.md``).
    meaning : str
        One line for the human report.
    channel : str
        ``"pose"`` (the encoder replay against ground-truth pose) or ``"gyro"`` (the gyro's
        heading against ground-truth heading).
    params : callable
        ``params(seg) -> list[Param]`` for the data at hand.
    applicable : callable
        ``applicable(seg) -> None`` or the reason the data cannot test the effect.
    contract : dict
        Internal name -> contract name, for parameters that map one to one.
    per_side : dict
        Internal base name (``r``, ``c``, ``pc``) -> contract template (``radius_{w}_m``),
        for parameters fitted per side and reported per wheel.
    """

    name: str
    meaning: str
    channel: str
    params: Callable[[Segments], list[Param]]
    applicable: Callable[[Segments], str | None]
    contract: dict[str, str] = field(default_factory=dict)
    per_side: dict[str, str] = field(default_factory=dict)

    def contract_names(self, wheels: list[str]) -> list[str]:
        """The contract parameter names this effect reports for ``wheels``."""
        names = list(self.contract.values())
        for template in self.per_side.values():
            names += [template.format(w=w) for w in wheels]
        return names

    def to_contract(self, values: dict[str, float], se: dict[str, float],
                    wheels: list[str], sides: np.ndarray) -> dict[str, list[float]]:
        """Internal values and standard errors -> ``{contract name: [value, se]}``."""
        out: dict[str, list[float]] = {}
        for internal, name in self.contract.items():
            out[name] = [float(values[internal]), float(se[internal])]
        for base, template in self.per_side.items():
            for w, side in zip(wheels, sides, strict=True):
                key = f"{base}_{'LR'[side]}"
                v, e = float(values[key]), float(se[key])
                if base in ("c", "pc"):  # compliance -> stiffness k_s = 1/c
                    v, e = (1.0 / v, e / v**2) if abs(v) > 1.0 / _HUGE else (_HUGE, _HUGE)
                out[template.format(w=w)] = [v, e]
        return out

    def from_contract(self, values: dict[str, float], wheels: list[str],
                      sides: np.ndarray) -> dict[str, float]:
        """``{contract name: value}`` -> internal values (per-side means of per-wheel values)."""
        out = {internal: float(values[name]) for internal, name in self.contract.items()}
        for base, template in self.per_side.items():
            for side in (0, 1):
                vals = [float(values[template.format(w=w)])
                        for w, s in zip(wheels, sides, strict=True) if s == side]
                v = float(np.mean(vals))
                out[f"{base}_{'LR'[side]}"] = 1.0 / v if base in ("c", "pc") else v
        return out


def _torque_scale(seg: Segments) -> float:
    """Typical |torque| [N m] of the moving samples (sets the compliance scale)."""
    moving = np.abs(seg.dphi).sum(axis=-1) > 0
    tq = np.abs(seg.torque[moving]) if moving.any() else np.abs(seg.torque)
    return max(float(np.median(tq)), 1e-3)


def _compliance(prefix: str) -> Callable[[Segments], list[Param]]:
    def params(seg: Segments) -> list[Param]:
        scale = 0.05 / _torque_scale(seg)  # 5 % slip at the typical torque
        return [Param(f"{prefix}_{s}", 0.0, -10 * scale, 20 * scale, scale) for s in "LR"]
    return params


def _radius(seg: Segments) -> list[Param]:
    r = float(np.median(seg.radius))
    return [Param(f"r_{s}", r, 0.5 * r, 1.5 * r, 0.01 * r) for s in "LR"]


def _track(seg: Segments) -> list[Param]:
    w = float(np.median(seg.track))
    return [Param("W", w, 0.2 * w, 5.0 * w, 0.05 * w)]


def _turning(seg: Segments) -> list[Param]:
    return [Param("endo_n", 0.8, 0.05, 3.0, 0.2), Param("turn_k", 0.0, -0.9, 0.95, 0.1)]


def _side_slip(seg: Segments) -> list[Param]:
    return [Param("bpr", 0.0, -5.0, 5.0, 0.2), Param("b0", 0.0, -0.5, 0.5, 0.02),
            Param("bpt", 0.0, -20.0, 20.0, 0.5)]


def _combined(seg: Segments) -> list[Param]:
    return [Param("sx0", 0.0, -0.5, 0.5, 0.02), Param("kb", 0.0, -10.0, 10.0, 0.5),
            Param("b0c", 0.02, 0.0, 0.5, 0.02)]


def patch_extent(seg: Segments) -> tuple[float, float, float, float]:
    """Bounding box (x0, y0, x1, y1) of the ground-truth positions [m]."""
    pos = seg.pos.reshape(-1, 2)
    return (float(pos[:, 0].min()), float(pos[:, 1].min()),
            float(pos[:, 0].max()), float(pos[:, 1].max()))


def _patch(seg: Segments) -> list[Param]:
    x0, y0, x1, y1 = patch_extent(seg)
    size = max(x1 - x0, y1 - y0, 1e-3)
    out = [Param("px", 0.5 * (x0 + x1), x0 - 0.25 * size, x1 + 0.25 * size, 0.1 * size),
           Param("py", 0.5 * (y0 + y1), y0 - 0.25 * size, y1 + 0.25 * size, 0.1 * size),
           Param("pr", 0.2 * size, 0.03 * size, 0.6 * size, 0.05 * size)]
    return out + _compliance("pc")(seg)


def _gyro(seg: Segments) -> list[Param]:
    return [Param("gyro_b", 0.0, -1.0, 1.0, 0.01)]


def _always(seg: Segments) -> str | None:
    return None


def _needs_torque(seg: Segments) -> str | None:
    return None if seg.torque is not None else "no torque_<wheel> columns"


def _needs_skid(seg: Segments) -> str | None:
    return None if seg.kind == "skid_steer" else "only skid-steer vehicles"


def _needs_roll(seg: Segments) -> str | None:
    if seg.roll is not None:
        roll = seg.roll
    else:
        from slipenv.diagnose.replay import _anchor_heading, _geometric_roll
        roll = _geometric_roll(_anchor_heading(seg)[:, None], seg.tilt)
    spread = float(np.percentile(roll, 95) - np.percentile(roll, 5)) if roll.size else 0.0
    if spread < _MIN_ROLL_RANGE_RAD:
        return "roll varies by less than 2° (level ground, or no roll signal)"
    return None


def _needs_beta(seg: Segments) -> str | None:
    if float(np.percentile(np.abs(seg.beta), 90)) < _MIN_BETA_RAD:
        return "measured slip angle stays below 1°"
    return None


def _needs_gyro(seg: Segments) -> str | None:
    return None if seg.gyro is not None else "no gyro_z column"


EFFECTS: dict[str, Effect] = {e.name: e for e in (
    Effect("rolling_radius", "effective rolling radius differs from nominal (per wheel)",
           "pose", _radius, _always, per_side={"r": "radius_{w}_m"}),
    Effect("track_width", "effective distance between the contact lines differs from nominal",
           "pose", _track, _always, contract={"W": "track_width_m"}),
    Effect("torque_slip", "longitudinal slip grows with wheel torque, s = T/k_s (Lindgren)",
           "pose", _compliance("c"), _needs_torque, per_side={"c": "k_s_{w}_nm"}),
    Effect("turning_slip", "skid-steer slip split by the speed ratio (Endo exponent n)",
           "pose", _turning, _needs_skid,
           contract={"endo_n": "endo_n", "turn_k": "turn_slip_scale"}),
    Effect("slope_side_slip", "slip angle driven by roll on a side slope (Yamauchi)",
           "pose", _side_slip, _needs_roll,
           contract={"bpr": "beta_per_roll", "b0": "beta_offset_rad",
                     "bpt": "beta_per_roll_yaw_rate_s"}),
    Effect("combined_slip", "longitudinal slip grows with slip angle (Reina Eq. 12)",
           "pose", _combined, _needs_beta,
           contract={"sx0": "s_x0", "kb": "k_beta", "b0c": "beta0_rad"}),
    Effect("soil_patch", "a disc of softer soil: torque slip inside a region",
           "pose", _patch, _needs_torque,
           contract={"px": "patch_center_x_m", "py": "patch_center_y_m",
                     "pr": "patch_radius_m"}, per_side={"pc": "k_s_{w}_nm"}),
    Effect("gyro_bias", "constant offset in the yaw-rate sensor", "gyro", _gyro, _needs_gyro,
           contract={"gyro_b": "gyro_bias_rad_s"}),
)}


def effect(name: str) -> Effect:
    """The effect called ``name``; ValueError listing the vocabulary otherwise."""
    try:
        return EFFECTS[name]
    except KeyError:
        raise ValueError(f"unknown effect {name!r}; the vocabulary is "
                         f"{', '.join(EFFECT_IDS)}") from None


def why_not(name: str, seg: Segments) -> str | None:
    """None if the data can test ``name``, else the reason."""
    return effect(name).applicable(seg)
