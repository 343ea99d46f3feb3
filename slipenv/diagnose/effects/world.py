"""The simulated world being extended: what an effect's ``apply`` may change, and the
stiffnesses it converts its fitted parameters with.

``extension.extend`` makes one :class:`WorldEdit` from an env config, lets every effect of the
model apply itself in the model's order (each sees the vehicle as the earlier ones left it),
and builds the new config.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.diagnose.slip_law import innermost, scaled
from slipenv.envs.config import SlipEnvConfig
from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.terramechanics import wheel_kernel
from slipenv.terramechanics.models import ReinaForceModel
from slipenv.terramechanics.presets import soil_by_name
from slipenv.terramechanics.soil import Soil
from slipenv.vehicles.spec import VehicleSpec

_PROBE = 1e-4  # slip (or tan β) of the finite difference giving a stiffness at rest


@dataclass
class WorldEdit:
    """A working copy of the config's parts the effects change.

    Attributes
    ----------
    config : SlipEnvConfig
        The world before the extension.
    spec : VehicleSpec
        The vehicle, as the effects applied so far left it.
    soil : Soil
        The config's soil.
    nominal_radius_m, nominal_track_m : float or None
        The diagnosed log's nominal wheel radius and track width: fitted radii and widths are
        applied as ratios to them (None: the vehicle's own nominal values).
    slip_options : dict
        Options of the ``ScaledSlip`` wrapper of the force law (none: no wrapper).
    replace : dict
        Other config fields replaced (``soil_map``, ``sensor_noise``).
    """

    config: SlipEnvConfig
    spec: VehicleSpec
    soil: Soil
    nominal_radius_m: float | None = None
    nominal_track_m: float | None = None
    slip_options: dict[str, float] = field(default_factory=dict)
    replace: dict[str, Any] = field(default_factory=dict)

    @classmethod
    def of(cls, config: SlipEnvConfig, nominal: dict[str, float] | None = None) -> WorldEdit:
        nominal = nominal or {}
        soil = config.soil if isinstance(config.soil, Soil) else soil_by_name(config.soil)
        return cls(config, make_vehicle(config.vehicle), soil,
                   nominal.get("wheel_radius_m"), nominal.get("track_width_m"))

    def build(self) -> SlipEnvConfig:
        """The extended config (the original object when nothing changed)."""
        changes = dict(self.replace)
        if self.slip_options:
            changes["force_model"] = scaled(self.config.force_model, **self.slip_options)
        if self.spec != make_vehicle(self.config.vehicle):
            changes["vehicle"] = self.spec
        return dataclasses.replace(self.config, **changes) if changes else self.config

    # -- the vehicle ---------------------------------------------------------------------------

    def side_of(self, wheel) -> int:
        """0 for a wheel on the left (y > 0 in the body frame), 1 on the right."""
        return 0 if wheel.position_m[1] > 0 else 1

    def set_rolling_radii(self, left_m: float, right_m: float) -> None:
        """Driven wheels roll as if their radius were the fitted one, scaled from the log's
        nominal radius to this vehicle's wheel radius."""
        r_nom = self.nominal_radius_m or self.spec.wheel_radius_nominal_m
        wheels = tuple(
            dataclasses.replace(w, rolling_radius_m=w.radius_m * (left_m, right_m)[
                self.side_of(w)] / r_nom) if w.role == "driven" else w
            for w in self.spec.wheels)
        self.spec = dataclasses.replace(self.spec, wheels=wheels)

    def scale_track(self, ratio: float) -> None:
        """Wheels moved apart laterally by ``ratio`` (and ``track_width_m``)."""
        wheels = tuple(dataclasses.replace(w, position_m=(w.position_m[0],
                                                          w.position_m[1] * ratio,
                                                          w.position_m[2]))
                       for w in self.spec.wheels)
        self.spec = dataclasses.replace(self.spec, wheels=wheels,
                                        track_width_m=self.spec.track_width_m * ratio)

    # -- the soil and the force law ------------------------------------------------------------

    def base_law(self):
        """The force law under any ``ScaledSlip`` wrappers."""
        return innermost(make_force_model(self.config.force_model, self.spec))

    def softer(self, factor: float) -> Soil:
        """The soil with its longitudinal slip stiffness times ``factor``.

        Reina's law has its own longitudinal stiffness C_x (the side stiffness C_y stays); the
        Janosi and linear laws take theirs from the shear modulus K, isotropically.
        """
        if isinstance(self.base_law(), ReinaForceModel):
            return dataclasses.replace(self.soil, name=f"{self.soil.name}_patch",
                                       c_x_n=self.soil.c_x_n * factor)
        return dataclasses.replace(self.soil, name=f"{self.soil.name}_patch",
                                   shear_modulus_m=self.soil.shear_modulus_m / factor)

    def _kernel_at_rest(self):
        model = make_force_model(self.config.force_model, self.spec)
        soil_map = make_soil_map(self.soil, self.config.soil_map)
        params = soil_map.params_at(np.zeros(1), np.zeros(1))
        if isinstance(params.cohesion_pa, np.ndarray):
            params = type(params)(*(float(np.ravel(v)[0]) for v in params))
        return wheel_kernel(model, params), self.spec.mass_kg * G_MPS2 / len(self.spec.wheels)

    def channel_stiffness(self) -> float:
        """Mean over drive channels of Σ r dF_x/ds at s = 0 and static load [N m per unit
        slip]: the torque-slip stiffness k_s of the world as it is."""
        kernel, load = self._kernel_at_rest()
        k = abs(kernel(_PROBE, 0.0, load)[0]) / _PROBE
        per_channel = [sum(w.radius_m * k for w in self.spec.wheels if w.channel == c)
                       for c in self.spec.channels]
        return float(np.mean(per_channel))

    def lateral_stiffness(self) -> float:
        """Σ over driven wheels of dF_y/d tan β at β = 0 and static load [N per unit tan β]."""
        kernel, load = self._kernel_at_rest()
        c = abs(kernel(0.0, _PROBE, load)[1]) / _PROBE
        return c * sum(1 for w in self.spec.wheels if w.role == "driven")
