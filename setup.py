"""Compiled hot paths (issue 15), built by ``pip install`` with the machine's C compiler.

Everything else about the package is in pyproject.toml. Each extension is optional: if it does
not compile, installation goes on and slipenv runs the same physics in plain Python (the
reference the compiled kernels are tested against: `slipenv.sim.compiled`,
``SLIPENV_PURE_PYTHON``).
``-ffp-contract=off`` keeps the compiler from fusing a*b+c into one rounding, so the C
arithmetic rounds exactly as Python's does.
"""

import sys

from setuptools import Extension, setup

_FLAGS = ["-O2", "-ffp-contract=off", "-fno-fast-math", "-std=c99"]

setup(
    ext_modules=[
        Extension("slipenv.sim._wheel_loop", ["slipenv/sim/_wheel_loop.c"],
                  depends=["slipenv/sim/bullet_native.h"],
                  libraries=[] if sys.platform == "win32" else ["dl"],
                  extra_compile_args=_FLAGS, optional=True),
        Extension("slipenv.estimators.lindgren._ekf", ["estimators/lindgren/_ekf.c"],
                  extra_compile_args=_FLAGS, optional=True),
    ],
)
