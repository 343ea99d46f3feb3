"""The world of the experiment: the registered tracked env on a slope or on flat ground."""

from __future__ import annotations

import gymnasium as gym

from .settings import ENV_ID


def make_world(tilt_deg: float, soil: str = "toyoura_sand", **kwargs) -> gym.Env:
    """``slipenv/TrackedSlopeCircle-v0`` on a slope of ``tilt_deg`` [deg] (downhill -y), or on
    flat ground at 0°; ``kwargs`` override further preset fields."""
    terrain = ({"kind": "slope", "slope_deg": float(tilt_deg), "downhill_azimuth_deg": -90.0}
               if tilt_deg > 0.0 else "flat")
    return gym.make(ENV_ID, terrain=terrain, soil=soil, **kwargs)
