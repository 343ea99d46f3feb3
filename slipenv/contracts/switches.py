"""Environment switches every layer reads the same way (estimators too, which may import only
the contracts).

``SLIPENV_PURE_PYTHON=1`` runs the plain-Python (numpy) reference of every compiled kernel:
the wheel-soil loop (`slipenv.sim.compiled`) and the Lindgren EKF
(`slipenv.estimators.lindgren.ekf`), to compare them or to step through the physics.
"""

from __future__ import annotations

import os

__all__ = ["PURE_PYTHON_ENV", "env_flag", "pure_python"]

PURE_PYTHON_ENV = "SLIPENV_PURE_PYTHON"


def env_flag(name: str) -> bool:
    """True if the environment variable `name` is set to anything but '' or '0'."""
    return os.environ.get(name, "") not in ("", "0")


def pure_python() -> bool:
    """True if ``SLIPENV_PURE_PYTHON`` asks for the plain-Python references."""
    return env_flag(PURE_PYTHON_ENV)
