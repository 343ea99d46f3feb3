"""What the simulator, the sensors and the env read from a soil force injector.

Two injectors apply the soil's forces to a vehicle once per physics substep: the per-wheel law
(:class:`~slipenv.sim.wheel_soil.WheelSoilInjector`) and the Wong-Chiang track model
(:class:`~slipenv.sim.track_soil.TrackSoilInjector`). :class:`Injector` is the surface both
offer and the layers above rely on; anything else an injector has (its slip states, the
compiled loop, the track's shear field) is its own business.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Protocol, runtime_checkable

from slipenv.sim.wheel_soil import WheelContactState
from slipenv.terramechanics.models import ForceModel
from slipenv.terramechanics.soil import SoilParams

__all__ = ["Injector"]


@runtime_checkable
class Injector(Protocol):
    """A soil force injector for one vehicle in one PyBullet client.

    Per wheel ``k`` (the order of ``VehicleSpec.wheels``; a track's road wheels for the track
    model).
    """

    chassis_contact: bool
    """Whether a body other than a wheel touched the ground since the simulator cleared it."""

    @property
    def links(self) -> Sequence[int]:
        """PyBullet link index of each wheel."""
        ...

    @property
    def load(self) -> Sequence[float]:
        """Normal load of each wheel in the last substep [N] (0 in the air)."""
        ...

    @property
    def force_model(self) -> ForceModel:
        """The force law injected (the track model keeps it for the readers)."""
        ...

    def sample_soil(self, force: bool = False) -> None:
        """Look up the soil under the wheels (once per control step; ``force``: even if the
        vehicle has not moved)."""
        ...

    def apply(self) -> None:
        """Read the contacts and apply the soil forces of one substep (before stepping)."""
        ...

    def soil_at_wheel(self, k: int) -> SoilParams:
        """The soil under wheel ``k`` as last sampled."""
        ...

    def rolling_radius_m(self, k: int) -> float:
        """Effective rolling radius of wheel ``k`` on its soil [m] (the slip's reference)."""
        ...

    def contact_state(self) -> WheelContactState:
        """Per-wheel slip, loads and forces of the last substep (ground truth for ``info``)."""
        ...
