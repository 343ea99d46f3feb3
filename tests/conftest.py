"""Session set-up shared by every test module."""

from __future__ import annotations

import multiprocessing
from concurrent.futures import ProcessPoolExecutor

import pytest


def pytest_configure(config: pytest.Config) -> None:
    """Compile (or load from numba's disk cache) the Lindgren EKF and the track model once,
    before pytest-xdist starts its workers: on a fresh clone the workers would otherwise all
    compile them at the same time and race to write the same cache files. Each kernel compiles
    in its own process (they share no compiled function), so on two cores a fresh clone waits
    for the slower one instead of both in turn (about 30 s instead of 55)."""
    if hasattr(config, "workerinput"):  # an xdist worker: the controller has done it
        return
    from slipenv.envs.compiled import KERNELS, warm_up

    spawn = multiprocessing.get_context("spawn")
    with ProcessPoolExecutor(len(KERNELS), mp_context=spawn) as pool:
        list(pool.map(warm_up, [[name] for name in KERNELS]))
