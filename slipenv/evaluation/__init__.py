"""Evaluate controllers and agents the way RL and robotics users do.

- :func:`evaluate` — a policy over seeds on an env id: true-pose metrics (cross-track RMSE,
  success rate, energy, odometry error, evo-style APE/RPE), a table, JSON, a plot
  (:func:`plot_evaluation`) and TUM trajectories;
- the pytest plugin (:mod:`slipenv.evaluation.pytest_plugin`, fixture ``slipenv_eval``);
- :func:`run_sweep` — a grid of evaluations on local processes or Ray, resumable;
- the ``evaluate`` and ``sweep`` subcommands (:mod:`.evaluate_cli`, :mod:`.sweep_cli`).

Names are imported lazily: the pytest plugin imports this package in every pytest run.
"""

from __future__ import annotations

import importlib
from typing import Any

_EXPORTS = {
    "Evaluation": "slipenv.evaluation.evaluator",
    "evaluate": "slipenv.evaluation.evaluator",
    "METRICS": "slipenv.evaluation.metrics",
    "resolve_policy": "slipenv.evaluation.policies",
    "BUILTIN_POLICIES": "slipenv.evaluation.policies",
    "plot_evaluation": "slipenv.evaluation.plots",
    "load_grid": "slipenv.evaluation.grid",
    "run_sweep": "slipenv.evaluation.sweep",
    "write_tum": "slipenv.evaluation.trajectory",
    "read_tum": "slipenv.evaluation.trajectory",
}


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        return getattr(importlib.import_module(_EXPORTS[name]), name)
    raise AttributeError(f"module 'slipenv.evaluation' has no attribute {name!r}")


__all__ = sorted(_EXPORTS)
