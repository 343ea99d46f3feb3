"""Build the physics pieces of an env from its :class:`SlipEnvConfig`."""

from __future__ import annotations

from typing import Any

from slipenv.terramechanics.models import ContactGeometry, force_model_by_name
from slipenv.terramechanics.presets import soil_by_name
from slipenv.terramechanics.soil import Soil
from slipenv.terramechanics.soil_map import UniformSoil
from slipenv.vehicles.presets import vehicle_by_name
from slipenv.vehicles.spec import VehicleSpec


def make_vehicle(vehicle: Any) -> VehicleSpec:
    """A vehicle spec from a preset name or a spec."""
    if isinstance(vehicle, VehicleSpec):
        return vehicle
    if isinstance(vehicle, str):
        return vehicle_by_name(vehicle)
    raise ValueError(f"vehicle must be a preset name or VehicleSpec, got {vehicle!r}")


def make_soil_map(soil: Any, soil_map: Any):
    """The soil map: the explicit map if given, else a uniform soil from a name or ``Soil``."""
    if soil_map is not None:
        if not hasattr(soil_map, "params_at"):
            raise ValueError(f"soil_map must provide params_at(x, y), got {soil_map!r}")
        return soil_map
    if isinstance(soil, str):
        soil = soil_by_name(soil)
    if not isinstance(soil, Soil):
        raise ValueError(f"soil must be a soil name or Soil, got {soil!r}")
    return UniformSoil(soil)


def contact_geometry(spec: VehicleSpec) -> ContactGeometry:
    """Contact patch of the driven wheels (all driven wheels of a preset are alike)."""
    wheel = next(w for w in spec.wheels if w.role == "driven")
    return ContactGeometry(
        radius_m=wheel.radius_m, width_m=wheel.width_m, contact_length_m=wheel.contact_length_m,
        track_length_m=spec.track_length_m,
    )


def make_force_model(force_model: Any, spec: VehicleSpec):
    """A force model from a name, an instance, or a factory taking a ContactGeometry."""
    geometry = contact_geometry(spec)
    if isinstance(force_model, str):
        return force_model_by_name(force_model, geometry)
    if hasattr(force_model, "resistance_n") and not isinstance(force_model, type):
        return force_model
    if callable(force_model):
        model = force_model(geometry)
        if not hasattr(model, "resistance_n"):
            raise ValueError("a force_model factory must return a ForceModel (with resistance_n)")
        return model
    raise ValueError(f"force_model must be a name, a ForceModel or a factory, got {force_model!r}")
