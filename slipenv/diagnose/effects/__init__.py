"""The effect vocabulary of ``log-format.md``: one module per effect, collected here.

Every module of this package that defines ``EFFECT`` (an :class:`~.base.Effect`) is an entry
of :data:`EFFECTS`, ordered by ``Effect.rank`` (the vocabulary's order). Adding an effect is
adding a module (``base.py`` says what it holds); :func:`register` adds one from elsewhere
(a test, a plug-in). The generic code — replay, fit, selection, extension, generator —
iterates over the registry and never names an effect.

========================= ============= =====================================================
module                    parameters    meaning
========================= ============= =====================================================
``rolling_radius``        per side      effective rolling radius differs from nominal
``track_width``           W             effective distance between the contact lines
``torque_slip``           per side      longitudinal slip grows with torque (Lindgren)
``turning_slip``          n, κ          skid-steer slip split by the speed ratio (Endo)
``slope_side_slip``       β per roll    slip angle driven by roll on a side slope (Yamauchi)
``combined_slip``         s_x0, k_β, β0 longitudinal slip grows with slip angle (Reina Eq. 12)
``soil_patch``            disc, per side a disc of softer soil
``soil_map``              shapes        regions of rectangles and discs, each its own torque slip
``gyro_bias``             b             constant offset in the yaw-rate sensor
========================= ============= =====================================================
"""

from __future__ import annotations

import importlib
import pkgutil

import numpy as np

from slipenv.diagnose.effects.base import Effect, Term
from slipenv.diagnose.segments import Segments

EFFECTS: dict[str, Effect] = {}
"""Effect id -> effect, in the vocabulary's order (``rank``); ``none`` is not an entry."""


def _order() -> None:
    ranked = sorted(EFFECTS.values(), key=lambda e: e.rank)
    EFFECTS.clear()
    EFFECTS.update((e.name, e) for e in ranked)


def _discover() -> None:
    for info in pkgutil.iter_modules(__path__):
        module = importlib.import_module(f"{__name__}.{info.name}")
        found = getattr(module, "EFFECT", None)
        if isinstance(found, Effect):
            EFFECTS[found.name] = found
    _order()


def register(new: Effect) -> Effect:
    """Add ``new`` to the vocabulary (ValueError if its name is taken); returns it."""
    if new.name in EFFECTS or new.name == "none":
        raise ValueError(f"effect {new.name!r} is already in the vocabulary")
    EFFECTS[new.name] = new
    _order()
    return new


def unregister(name: str) -> None:
    """Remove the effect ``name`` (added by :func:`register`)."""
    effect(name)
    del EFFECTS[name]


def effect_ids() -> tuple[str, ...]:
    """``none`` and every effect id, in the vocabulary's order."""
    return ("none", *EFFECTS)


def effect(name: str) -> Effect:
    """The effect called ``name``; ValueError listing the vocabulary otherwise."""
    try:
        return EFFECTS[name]
    except KeyError:
        raise ValueError(f"unknown effect {name!r}; the vocabulary is "
                         f"{', '.join(effect_ids())}") from None


def why_not(name: str, seg: Segments) -> str | None:
    """None if the data can test ``name``, else the reason."""
    return effect(name).applicable(seg)


def contract_report(model: dict[str, Term], se: dict[str, dict[str, float]],
                    wheels: list[str], sides: np.ndarray) -> dict[str, list[float]]:
    """``{contract name: [value, se]}`` over all effects of ``model``.

    A name that another effect of the model also reports takes the effect's
    ``clash_prefix`` (soil-patch stiffnesses ``patch_k_s_<wheel>_nm`` beside torque slip's).
    """
    out: dict[str, list[float]] = {}
    for name, params in model.items():
        eff = effect(name)
        part = eff.to_contract(params, se[name], wheels, sides)
        if eff.clash_prefix:
            others = {n for other in model if other != name
                      for n in effect(other).contract_names(wheels)}
            part = {(eff.clash_prefix + k if k in others else k): v for k, v in part.items()}
        out.update(part)
    return out


def shown_parameters(parameters: dict[str, list[float]], effects: list[str]
                     ) -> tuple[dict[str, list[float]], list[str]]:
    """What a report lists of a model's ``{contract name: [value, se]}``: the parameters to
    show one per line and the lines the ``effects``' ``condense`` hooks add after them."""
    kept, lines = dict(parameters), []
    for name in effects:
        hook = EFFECTS[name].condense if name in EFFECTS else None
        if hook is not None:
            kept, more = hook(kept)
            lines += more
    return kept, lines


_discover()

__all__ = ["EFFECTS", "Effect", "Term", "contract_report", "effect", "effect_ids", "register",
           "shown_parameters", "unregister", "why_not"]
