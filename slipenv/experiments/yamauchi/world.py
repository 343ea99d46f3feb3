"""The world of the experiment: the registered tracked env on a slope or on flat ground."""

from __future__ import annotations

import gymnasium as gym

from .settings import ENV_ID


def make_world(tilt_deg: float, soil: str | None = None, vehicle: str | None = None,
               **kwargs) -> gym.Env:
    """``slipenv/TrackedSlopeCircle-v0`` on a slope of ``tilt_deg`` [deg] (downhill -y), or on
    flat ground at 0°; ``soil`` and ``vehicle`` (names) replace the preset's when given (e.g.
    ``dry_sand`` or ``tracked_patako``, the per-wheel track law);
    ``kwargs`` override further preset fields."""
    terrain = ({"kind": "slope", "slope_deg": float(tilt_deg), "downhill_azimuth_deg": -90.0}
               if tilt_deg > 0.0 else "flat")
    if soil is not None:
        kwargs["soil"] = soil
    if vehicle is not None:
        kwargs["vehicle"] = vehicle
    # Laps are judged in the env's own corridor (0.4 r = 0.1 m on Yamauchi's circle): a lap
    # counts as completed only if the vehicle stays within 0.1 m of it all the way round.
    return gym.make(ENV_ID, terrain=terrain, **kwargs)
