"""``track_width``: the effective distance between the contact lines differs from nominal.

Replay: in-plane turn dθ = (g_R - g_L)/W (``replay.py`` step 4). Simulation: the wheels moved
apart laterally by the fitted width's ratio to the log's nominal one. Hidden in the tests: on
the differential-drive vehicle, wheels moved 5-15 % apart or together; on a skid-steer, whose
effective width is its turning resistance rather than its wheel spacing, the side stiffness of
the force law ×1.5-3 or ÷1.5-3.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipenv.diagnose.effects.base import (
    Bound,
    DrawContext,
    Effect,
    Hidden,
    Hiding,
    Scalar,
    StartContext,
    Term,
    finite,
    require,
)
from slipenv.diagnose.effects.linear_start import linear_starts
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments


@dataclass(frozen=True)
class TrackWidth(Term):
    """Effective track width W [m]."""

    width_m: float

    def __post_init__(self) -> None:
        finite(self)
        require(self.width_m > 0, self, f"width_m must be > 0, got {self.width_m}")

    def track_width(self, seg: Segments, track: np.ndarray | float) -> float:
        return self.width_m


def bounds(seg: Segments) -> dict[str, Bound]:
    w = float(np.median(seg.track))
    return {"width_m": Bound(w, 0.2 * w, 5.0 * w, 0.05 * w)}


def start(ctx: StartContext) -> list[TrackWidth]:
    return [TrackWidth(linear_starts(ctx.seg)["track_width_m"])]


def apply(edit: WorldEdit, p: TrackWidth) -> None:
    edit.scale_track(p.width_m / (edit.nominal_track_m or edit.spec.track_width_m))


def draw(rng: np.random.Generator, ctx: DrawContext) -> Hidden:
    if ctx.kind == "skid_steer":
        # a skid-steer's effective width is its turning resistance, not its wheel spacing
        size = float(rng.uniform(np.log(1.5), np.log(3.0)) * rng.choice([-1.0, 1.0]))
        return Hidden(slip_options={"lat_scale": float(np.exp(size))})
    size = float(rng.uniform(0.05, 0.15) * rng.choice([-1.0, 1.0]))
    return Hidden(TrackWidth(ctx.spec.track_width_m * (1 + size)))


EFFECT = Effect(
    name="track_width",
    calibration=True,
    meaning="effective distance between the contact lines differs from nominal",
    params=TrackWidth, bounds=bounds, start=start, apply=apply, rank=2,
    contract=(Scalar("width_m", "track_width_m"),),
    hiding=Hiding(("diff_drive", "skid_steer", "rover4ws"), draw),
)
