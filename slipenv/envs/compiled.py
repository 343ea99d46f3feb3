"""The numba-compiled kernels of the envs, compiled (or loaded from numba's disk cache) at once.

Two hot paths are compiled with numba from their one plain-Python text: the Lindgren EKF
(`slipenv.estimators.lindgren.kernel`) and the Wong–Chiang track model
(`slipenv.terramechanics.track`, driven by `slipenv.sim.track_soil`). The first use after an
install or an edit of their source compiles them (tens of seconds of CPU); later ones load them.
numba's cache is not safe against several processes writing it at the same time, so a parent
process calls :func:`warm_up` before it starts workers (pytest-xdist, a sweep's process pool,
SB3's `SubprocVecEnv`, the benchmark's fresh interpreters).
"""

from __future__ import annotations

from typing import Any

__all__ = ["KERNELS", "kernels_used", "warm_up"]

KERNELS = {"lindgren_ekf": "the Lindgren EKF", "track_model": "the track model"}
"""The compiled kernels, by name, with what a user is told while they compile."""


def kernels_used(env: Any) -> list[str]:
    """The compiled kernels (`KERNELS` names) a slipenv env steps with."""
    base = env.unwrapped
    used = []
    if "lindgren" in base.config.estimator:
        used.append("lindgren_ekf")
    if base.vehicle.track_model == "wong_chiang":
        used.append("track_model")
    return used


def warm_up(names: list[str] | None = None) -> None:
    """Compile or load the compiled kernels ``names`` (default: all of `KERNELS`), here."""
    # Imported here: ``import slipenv`` loads neither numba nor an estimator.
    names = list(KERNELS) if names is None else names
    if "lindgren_ekf" in names:
        from slipenv.estimators.lindgren.ekf import warm_up as warm_up_ekf

        warm_up_ekf()
    if "track_model" in names:
        from slipenv.sim.track_soil import warm_up as warm_up_track_model

        warm_up_track_model()
