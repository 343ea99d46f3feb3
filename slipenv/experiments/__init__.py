"""The source papers' experiments re-run in simulation (``slipenv reproduce NAME``).

Each experiment is a sub-package (:mod:`.lindgren`, :mod:`.yamauchi`) whose ``run`` function,
``run(quick: bool, out_dir: str, json_path: str | None, seed: int, progress: bool,
docs_dir: str | None) -> dict``, returns ``{"metrics": {...}, "paper": {...}, ...}``, prints a
paper-vs-simulation table and, with ``docs_dir``, writes the results page
``docs_dir/NAME.md`` (:mod:`.docs_page`; the committed pages are in ``docs/reproductions/``).
Every episode runs through :func:`slipenv.rollout.rollout`.
"""

from __future__ import annotations

import importlib
from collections.abc import Callable

# name -> module path; modules are imported on demand (they pull in plotting, PyBullet).
EXPERIMENT_MODULES: dict[str, str] = {
    "lindgren": "slipenv.experiments.lindgren",
    "yamauchi": "slipenv.experiments.yamauchi",
    "reina": "slipenv.experiments.reina",
}


def experiment(name: str) -> Callable[..., dict]:
    """The ``run`` function of experiment ``name`` (``ValueError`` listing names if unknown)."""
    if name not in EXPERIMENT_MODULES:
        raise ValueError(f"unknown experiment {name!r}; known: {sorted(EXPERIMENT_MODULES)}")
    return importlib.import_module(EXPERIMENT_MODULES[name]).run
