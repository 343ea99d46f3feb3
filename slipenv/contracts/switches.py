"""Environment switches every layer reads the same way (estimators too, which may import only
the contracts).

The documented switch of the simulation is ``SLIPENV_PYBULLET_API=1``
(`slipenv.sim.bullet_native`): the compiled wheel loop reads PyBullet through pybullet's public
Python API instead of Bullet's C API.
"""

from __future__ import annotations

import os

__all__ = ["env_flag"]


def env_flag(name: str) -> bool:
    """True if the environment variable `name` is set to anything but '' or '0'."""
    return os.environ.get(name, "") not in ("", "0")
