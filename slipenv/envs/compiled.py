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

__all__ = ["warm_up"]


def warm_up() -> None:
    """Compile or load every compiled kernel an env may use, in this process."""
    # Imported here: ``import slipenv`` loads neither numba nor an estimator.
    from slipenv.estimators.lindgren.ekf import warm_up as warm_up_ekf
    from slipenv.sim.track_soil import warm_up as warm_up_track_model

    warm_up_ekf()
    warm_up_track_model()
