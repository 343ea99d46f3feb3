"""What ``slipenv reproduce reina`` runs (Reina §4.2-4.3) and its targets."""

from __future__ import annotations

import math
from dataclasses import dataclass

TESTS = ("sideways", "mounds")
TARGETS = {"scomp_ratio_max": 0.3, "slip_angle_rms_deg_max": 2.0,
           "false_negative_max": 0.03, "misidentification_max": 0.01, "frames_min": 1000}


@dataclass(frozen=True)
class Settings:
    """The run plan. Angles in degrees, lengths in metres, speeds in m/s, as named.

    Test 1 (``sideways``): a plane rising ``climb_deg`` along the drive and falling
    ``bank_deg`` to its right (transverse inclination), driven straight for
    ``sideways_length_m``. Test 2 (``mounds``): Gaussian sand mounds, driven straight for
    ``mounds_length_m``. The rover holds its compass heading at ``speed_mps`` (Reina: remote
    control along a straight line). Each test is driven once per seed.
    """

    seeds: int = 3
    speed_mps: float = 0.08  # Reina §4: about 8 cm/s
    sideways_length_m: float = 7.0
    climb_deg: float = 5.0
    bank_deg: float = 8.0
    mounds_length_m: float = 13.0
    mound_count: int = 220
    mound_height_m: float = 0.10
    mound_radius_m: float = 0.45
    mound_field_m: float = 30.0
    # [1/s] compass heading hold, Ω = -k (ψ - ψ_ref): the driver of the joypad. 2° of compass
    # noise at 20 Hz becomes 0.6°/s of commanded yaw-rate noise at 0.3/s (10x that at 3/s).
    heading_gain: float = 0.3
    truth_window_s: float = 1.0  # ground-truth slip angle and slip ratio averaged over this
    misid_threshold_deg: float = 2.0
    frames_saved: int = 4

    def __post_init__(self) -> None:
        if self.seeds < 1:
            raise ValueError(f"seeds must be >= 1, got {self.seeds}")
        for name in ("speed_mps", "sideways_length_m", "mounds_length_m", "heading_gain",
                     "truth_window_s", "misid_threshold_deg"):
            if not (math.isfinite(getattr(self, name)) and getattr(self, name) > 0.0):
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if not (0.0 <= self.climb_deg < 30.0 and 0.0 <= self.bank_deg < 30.0):
            raise ValueError("climb_deg and bank_deg must be in [0, 30)")

    def slope(self) -> tuple[float, float]:
        """(slope_deg, downhill_azimuth_deg) of the plane of test 1 (travel along +x)."""
        gx, gy = math.tan(math.radians(self.climb_deg)), math.tan(math.radians(self.bank_deg))
        slope = math.degrees(math.atan(math.hypot(gx, gy)))
        return slope, math.degrees(math.atan2(-gy, -gx))


QUICK = Settings(seeds=1)
