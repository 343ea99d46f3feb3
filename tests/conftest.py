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


# Modules whose module-scoped fixture runs a whole quick reproduction (15-100 s each). Run
# first: pytest-xdist hands each worker its first tests as one block of consecutive items, so
# these fixtures start at once, on one worker each time, instead of one of them starting near
# the end and leaving the other worker idle while it runs.
REPRODUCTION_MODULES = ("tests/experiments/test_lindgren.py",
                        "tests/experiments/test_yamauchi.py",
                        "tests/experiments/test_reina.py")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Move the reproduction modules' tests to the front, keeping every other order."""
    def first(item: pytest.Item) -> bool:
        return item.nodeid.split("::")[0] in REPRODUCTION_MODULES

    items[:] = [i for i in items if first(i)] + [i for i in items if not first(i)]
