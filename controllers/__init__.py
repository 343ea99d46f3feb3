"""Control laws as policies: ``act(obs) -> action`` and stable-baselines3's ``predict``.

Controllers read the observation laid out in :mod:`slipenv.contracts.observation` and return
``[v / v_max, omega / omega_max]`` as float32 in [-1, 1]^2. :func:`baseline_controller` builds
an env's path-following baseline from the env's public surface (vehicle, path, control period).
"""

from __future__ import annotations

from slipenv.contracts.names import lookup
from slipenv.contracts.observation import OBS_DIM, OBS_NAMES, build_observation

from .base import Controller, Policy
from .baseline import BASELINE_NAMES, baseline_controller
from .pure_pursuit import PurePursuitController
from .stanley import StanleyController
from .yamauchi import YamauchiController, is_hurwitz

CONTROLLERS: dict[str, type[Controller]] = {
    "yamauchi": YamauchiController,
    "pure_pursuit": PurePursuitController,
    "stanley": StanleyController,
}


def controller_by_name(name: str, **kw: object) -> Controller:
    """Build the controller registered as ``name`` with keyword arguments ``kw``
    (``v_max_mps``, ``omega_max_rps``, ``dt_s`` and the law's gains).

    Raises
    ------
    ValueError
        If ``name`` is unknown (the message lists the known names).
    """
    return lookup(CONTROLLERS, name, "controller")(**kw)  # type: ignore[arg-type]


__all__ = [
    "BASELINE_NAMES",
    "CONTROLLERS",
    "OBS_DIM",
    "OBS_NAMES",
    "Controller",
    "Policy",
    "PurePursuitController",
    "StanleyController",
    "YamauchiController",
    "baseline_controller",
    "build_observation",
    "controller_by_name",
    "is_hurwitz",
]
