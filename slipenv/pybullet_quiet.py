"""Import PyBullet without its ``pybullet build time: ...`` banner.

PyBullet's C module prints that line from its init function, straight to a file descriptor
(fd 2 with the PyPI wheels, fd 1 with some builds), so neither ``contextlib.redirect_stdout``
nor Python's ``sys.stderr`` can catch it. :func:`import_pybullet` imports the module once with
fds 1 and 2 pointed at ``/dev/null``; every later ``import pybullet`` anywhere in the process
gets the already-initialised module and prints nothing. Route the *first* import through it:

    from slipenv.pybullet_quiet import import_pybullet

    p = import_pybullet()

This module imports nothing of slipenv, so any layer may use it.
"""

from __future__ import annotations

import ctypes
import os
import sys
from types import ModuleType

_SILENCED_FDS = (1, 2)


def _flush_c_stdio() -> None:
    """Flush C's stdio buffers, so banner text buffered by libc goes to /dev/null too."""
    try:
        ctypes.CDLL(None).fflush(None)
    except (OSError, AttributeError):  # no libc symbol table (unusual platforms): nothing to do
        pass


def import_pybullet() -> ModuleType:
    """Return the ``pybullet`` module, importing it with its start-up banner suppressed.

    Returns
    -------
    module
        ``pybullet`` (the same object ``import pybullet`` gives).

    Notes
    -----
    Anything the C extension writes to fds 1 and 2 *while it initialises* is discarded;
    Python-level errors (``ImportError``) still propagate as exceptions.
    """
    if "pybullet" in sys.modules:
        return sys.modules["pybullet"]
    for stream in (sys.stdout, sys.stderr):
        if stream is not None:
            stream.flush()
    saved: list[tuple[int, int]] = []
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in _SILENCED_FDS:
            try:
                saved.append((fd, os.dup(fd)))
            except OSError:  # fd not open (a daemon without stdio): nothing to silence
                continue
            os.dup2(devnull, fd)
        import pybullet

        _flush_c_stdio()
    finally:
        for fd, copy in saved:
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)
    return pybullet
