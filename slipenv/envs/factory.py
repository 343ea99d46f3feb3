"""Build the physics pieces of an env from its :class:`SlipEnvConfig`."""

from __future__ import annotations

import difflib
import inspect
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from slipenv.paths import Path, path_by_name
from slipenv.terramechanics.models import ContactGeometry, ForceModel, force_model_by_name
from slipenv.terramechanics.presets import soil_by_name
from slipenv.terramechanics.soil import Soil
from slipenv.terramechanics.soil_map import SoilMap, UniformSoil
from slipenv.vehicles.presets import vehicle_by_name
from slipenv.vehicles.spec import VehicleSpec

if TYPE_CHECKING:  # the estimators package imports scipy.stats and numba: 1.5 s
    from slipenv.estimators.base import Estimator

ForceModelFactory = Callable[[ContactGeometry], ForceModel]
"""A force model built for a wheel's contact geometry (the ``force_model`` option's callable)."""


def make_vehicle(vehicle: str | VehicleSpec) -> VehicleSpec:
    """A vehicle spec from a preset name or a spec (checked by :class:`SlipEnvConfig`)."""
    return vehicle if isinstance(vehicle, VehicleSpec) else vehicle_by_name(vehicle)


def make_soil_map(soil: str | Soil, soil_map: SoilMap | None) -> SoilMap:
    """The soil map: the explicit map if given, else a uniform soil from a name or ``Soil``
    (both checked by :class:`SlipEnvConfig`)."""
    if soil_map is not None:
        return soil_map
    return UniformSoil(soil_by_name(soil) if isinstance(soil, str) else soil)


def contact_geometry(spec: VehicleSpec) -> ContactGeometry:
    """Contact patch of the driven wheels (all driven wheels of a preset are alike)."""
    wheel = next(w for w in spec.wheels if w.role == "driven")
    return ContactGeometry(
        radius_m=wheel.radius_m, width_m=wheel.width_m, contact_length_m=wheel.contact_length_m,
        track_length_m=spec.track_length_m,
    )


def make_force_model(force_model: str | ForceModel | ForceModelFactory, spec: VehicleSpec,
                     options: dict[str, Any] | None = None) -> ForceModel:
    """A force model from a name (built with ``options``, the config's
    ``force_model_kwargs``), an instance, or a factory taking a ContactGeometry.

    The name, the kind of value and the options are checked by :class:`SlipEnvConfig`; what
    only building can tell, a factory's return value, is checked here.
    """
    geometry = contact_geometry(spec)
    if isinstance(force_model, str):
        return force_model_by_name(force_model, geometry, **(options or {}))
    if hasattr(force_model, "resistance_n") and not isinstance(force_model, type):
        return cast(ForceModel, force_model)
    model = cast(ForceModelFactory, force_model)(geometry)
    if not hasattr(model, "resistance_n"):
        raise ValueError("force_model: a factory must return a ForceModel (with resistance_n), "
                         f"got {model!r}")
    return model


def make_path(name: str, kwargs: dict) -> Path:
    """The named path built with ``kwargs``; any failure is a ``ValueError`` naming
    ``path_kwargs`` (the builders name the bad argument)."""
    try:
        return path_by_name(name, **kwargs)
    except (TypeError, ValueError, OverflowError) as exc:
        raise ValueError(f"bad path_kwargs for path {name!r}: {exc}") from None


def check_estimator_name(name: str) -> None:
    """``name`` must be a registered estimator (else a "did you mean" ``ValueError``)."""
    from slipenv.envs.estimation import ESTIMATORS

    if name not in ESTIMATORS:
        close = difflib.get_close_matches(name, sorted(ESTIMATORS), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ValueError(f"unknown estimator {name!r}{hint} Known estimators: "
                         f"{sorted(ESTIMATORS)}")


def build_estimator(name: str, kwargs: dict, spec: VehicleSpec, context: dict) -> Estimator:
    """Build estimator ``name`` with ``kwargs``; any failure (unknown option, bad value) is a
    ``ValueError`` naming ``estimator_kwargs``, with a suggestion for a misspelt option."""
    from slipenv.envs.estimation import ESTIMATORS, make_estimator

    try:
        return make_estimator(name, spec, context, **kwargs)
    except (TypeError, ValueError, KeyError, OverflowError, AttributeError) as exc:
        # An AttributeError here is an option of the wrong type (e.g. ``params=1`` where the
        # EKF expects LindgrenNoise or a dict) reaching the estimator's constructor.
        known = [p for p in inspect.signature(ESTIMATORS[name]).parameters][2:]
        known = [k for k in known if k not in ("kw", "kwargs")]
        hints = []
        for key in kwargs:
            if key not in known and key in str(exc):
                close = difflib.get_close_matches(key, known, n=1)
                if close:
                    hints.append(f"did you mean {close[0]!r} for {key!r}?")
        hint = (" " + " ".join(hints)) if hints else ""
        raise ValueError(f"bad estimator_kwargs {kwargs!r} for estimator {name!r}: "
                         f"{exc}{hint}") from None


def check_action(action: Any) -> np.ndarray:
    """The action as a float64 array of shape (2,); anything else is a ``ValueError``.

    Accepted: real numbers (bool, integer or float dtypes), finite, two of them. Complex,
    string and object actions are refused rather than cast (a complex number would lose its
    imaginary part silently, a string would be parsed).
    """
    raw = np.asarray(action) if not isinstance(action, np.ndarray) else action
    if raw.dtype.kind not in "biuf":
        raise ValueError(f"action must hold real numbers, got dtype {raw.dtype} ({action!r})")
    out = raw.astype(np.float64).reshape(-1)
    if out.shape != (2,):
        raise ValueError(f"action must have shape (2,), got {np.shape(raw)}")
    if not np.all(np.isfinite(out)):
        raise ValueError(f"action contains NaN or inf: {out.tolist()}")
    return out
