"""Compiled hot paths, built by ``pip install`` with the machine's C compiler.

Everything else about the package is in pyproject.toml. The wheel-soil laws exist once, in C
(``slipenv/terramechanics/_laws.h``): the per-substep wheel loop (``slipenv.sim._wheel_loop``)
includes them and ``slipenv.terramechanics._laws`` binds them for the Python API, so both
extensions are required. The track injector's native PyBullet reads and force commands
(``slipenv.sim._track_io``) share the wheel loop's ``bullet_native.h`` and give the compiled
track model the address of the slip-sinkage law of ``_laws.h``. ``-ffp-contract=off``
keeps the compiler from fusing a*b+c into one rounding, so results do not depend on the
target's FMA support.
"""

import sys

from setuptools import Extension, setup

_FLAGS = ["-O2", "-ffp-contract=off", "-fno-fast-math", "-std=c99"]
_LAWS = "slipenv/terramechanics/_laws.h"
_LIBM = [] if sys.platform == "win32" else ["m"]

setup(
    ext_modules=[
        Extension("slipenv.terramechanics._laws", ["slipenv/terramechanics/_laws.c"],
                  depends=[_LAWS], include_dirs=["slipenv/terramechanics"],
                  libraries=_LIBM, extra_compile_args=_FLAGS, optional=False),
        Extension("slipenv.sim._wheel_loop", ["slipenv/sim/_wheel_loop.c"],
                  depends=["slipenv/sim/bullet_native.h", _LAWS],
                  include_dirs=["slipenv/terramechanics"],
                  libraries=_LIBM + ([] if sys.platform == "win32" else ["dl"]),
                  extra_compile_args=_FLAGS, optional=False),
        Extension("slipenv.sim._track_io", ["slipenv/sim/_track_io.c"],
                  depends=["slipenv/sim/bullet_native.h", _LAWS],
                  include_dirs=["slipenv/terramechanics"],
                  libraries=_LIBM + ([] if sys.platform == "win32" else ["dl"]),
                  extra_compile_args=_FLAGS, optional=False),
    ],
)
