"""Which hot paths run compiled (issue 15).

``pip install`` builds C transcriptions of the per-substep loops (setup.py; each extension is
optional, so a machine without a compiler still installs and runs the plain Python). The plain
functions stay the physics' one source: each compiled kernel is tested bit for bit against them
(tests/sim/test_wheel_loop_compiled.py). Set ``SLIPENV_PURE_PYTHON=1`` to run the Python loops
(to compare, or to step through the physics in a debugger).
"""

from __future__ import annotations

import importlib
from types import ModuleType

from slipenv.contracts.switches import PURE_PYTHON_ENV, pure_python

__all__ = ["PURE_PYTHON_ENV", "pure_python", "wheel_loop_module"]


def wheel_loop_module() -> ModuleType | None:
    """The compiled wheel-soil loop (``slipenv.sim._wheel_loop``), or None if it was not built
    or ``SLIPENV_PURE_PYTHON`` is set."""
    if pure_python():
        return None
    try:
        return importlib.import_module("slipenv.sim._wheel_loop")
    except ImportError:
        return None
