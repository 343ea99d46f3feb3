"""The path-following baseline of every env: a controller with gains scaled to its vehicle.

:func:`baseline_controller` builds it from an env's public read-only surface alone (duck-typed:
``vehicle.max_speed_mps``, ``vehicle.max_yaw_rate_rad_s``, ``control_dt_s`` and
``path.speed_at(s)``), so this module needs nothing of the simulator. The names it accepts,
:data:`BASELINE_NAMES`, are exactly what ``slipenv run --controller`` offers.
"""

from __future__ import annotations

from typing import Any

from .base import Controller
from .pure_pursuit import PurePursuitController
from .stanley import StanleyController
from .yamauchi import YamauchiController

POLE_LENGTH_M = 0.6
"""[m] The baseline's closed-loop pole is v_ref / POLE_LENGTH_M: about one vehicle length."""
POLE_RANGE_RPS = (0.15, 1.0)
"""[rad/s] Clip range of that pole (slow vehicles stay responsive, fast ones stay discrete-safe)."""

BASELINE_NAMES: tuple[str, ...] = ("yamauchi", "yamauchi_feedback", "pure_pursuit", "stanley")
"""Accepted ``name`` values: Yamauchi Eq. 10 (slip feed-forward), Yamauchi Eq. 9 (feedback
only), pure pursuit, Stanley."""


def _surface(env_or_surface: Any) -> Any:
    """The object carrying ``vehicle``, ``path`` and ``control_dt_s`` (unwrapping gym wrappers)."""
    surface = getattr(env_or_surface, "unwrapped", env_or_surface)
    missing = [a for a in ("vehicle", "path", "control_dt_s") if not hasattr(surface, a)]
    if missing:
        raise TypeError(f"baseline_controller needs an env (or object) with .vehicle, .path and "
                        f".control_dt_s; {type(surface).__name__} lacks {', '.join(missing)}")
    return surface


def baseline_pole_rps(v_ref_mps: float) -> float:
    """Triple closed-loop pole p = clip(v_ref / 0.6 m, 0.15, 1.0) [rad/s] of the baseline.

    A pole tied to the time it takes to cover about one vehicle length, so a 5 cm/s tracked
    vehicle and a 1 m/s Husky get the same behaviour per metre travelled.
    """
    lo, hi = POLE_RANGE_RPS
    return min(max(v_ref_mps / POLE_LENGTH_M, lo), hi)


def baseline_controller(env_or_surface: Any, name: str = "yamauchi", **kwargs: Any) -> Controller:
    """The path-following baseline for an env, with gains scaled to its reference speed.

    Parameters
    ----------
    env_or_surface : gymnasium.Env or object
        A slipenv env (wrappers allowed) or anything with ``vehicle`` (``max_speed_mps`` [m/s],
        ``max_yaw_rate_rad_s`` [rad/s]), ``path`` (``speed_at(s) -> m/s``) and
        ``control_dt_s`` [s].
    name : str
        One of :data:`BASELINE_NAMES`. ``"yamauchi"`` places a triple pole at
        :func:`baseline_pole_rps` (Yamauchi §3 law, Eq. 10, via
        :meth:`YamauchiController.from_poles`); ``"yamauchi_feedback"`` is the same law without
        the slip-angle feed-forward (Eq. 9).
    **kwargs
        Extra controller arguments (gains, ``use_feedforward`` ...).

    Returns
    -------
    Controller
        Answers SB3's ``predict`` and ``act``.

    Raises
    ------
    ValueError
        If ``name`` is not one of :data:`BASELINE_NAMES`.
    """
    if name not in BASELINE_NAMES:
        raise ValueError(f"unknown controller {name!r}; known controllers: "
                         f"{', '.join(BASELINE_NAMES)}")
    base = _surface(env_or_surface)
    spec = base.vehicle
    common: dict[str, Any] = dict(v_max_mps=spec.max_speed_mps,
                                  omega_max_rps=spec.max_yaw_rate_rad_s,
                                  dt_s=base.control_dt_s)
    if name in ("yamauchi", "yamauchi_feedback"):
        if name == "yamauchi_feedback":
            kwargs = {**kwargs, "use_feedforward": False}
        v_ref = max(float(base.path.speed_at(0.0)), 1e-3)
        return YamauchiController.from_poles(baseline_pole_rps(v_ref), v_ref, **common, **kwargs)
    cls = PurePursuitController if name == "pure_pursuit" else StanleyController
    return cls(**common, **kwargs)
