"""The compiled wheel-soil substep loop, ``slipenv.sim._wheel_loop``.

``pip install`` builds it (setup.py; it is required): the per-substep loop of every
`WheelSoilInjector`, running the laws of ``slipenv/terramechanics/_laws.h``. The one switch is
``SLIPENV_PYBULLET_API`` (`slipenv.sim.bullet_native`): set, the loop reads PyBullet through
pybullet's public Python API instead of Bullet's C API.
"""

from __future__ import annotations

import importlib
from types import ModuleType

__all__ = ["wheel_loop_module"]


def wheel_loop_module() -> ModuleType:
    """The compiled wheel-soil loop (``slipenv.sim._wheel_loop``)."""
    return importlib.import_module("slipenv.sim._wheel_loop")
