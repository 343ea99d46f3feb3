"""Session set-up shared by every test module."""

from __future__ import annotations

import pytest


def pytest_configure(config: pytest.Config) -> None:
    """Compile (or load from numba's disk cache) the Lindgren EKF and the track model once, in
    the controlling process, before pytest-xdist starts its workers: on a fresh clone the workers
    would otherwise all compile them at the same time and race to write the same cache files."""
    if hasattr(config, "workerinput"):  # an xdist worker: the controller has done it
        return
    from slipenv.envs.compiled import warm_up

    warm_up()
