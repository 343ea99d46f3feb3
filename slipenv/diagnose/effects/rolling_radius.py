"""``rolling_radius``: the effective rolling radius differs from nominal (per side).

Replay: rim travel d_i = r_side(i) Δφ_i (``replay.py`` step 1). Simulation: every driven
wheel's ``WheelSpec.rolling_radius_m``, as the fitted radius's ratio to the log's nominal one.
Hidden in the tests: each wheel's rolling radius 1-4 % off, either way.
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
    PerSide,
    StartContext,
    Term,
    finite,
    require,
    side_values,
)
from slipenv.diagnose.effects.linear_start import linear_starts
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments


@dataclass(frozen=True)
class RollingRadius(Term):
    """Effective rolling radii of the left and right wheels [m]."""

    left_m: float
    right_m: float

    def __post_init__(self) -> None:
        finite(self)
        require(self.left_m > 0 and self.right_m > 0, self,
                f"radii must be > 0 m, got {self.left_m}, {self.right_m}")

    def wheel_radius(self, seg: Segments, radius: np.ndarray) -> np.ndarray:
        return np.broadcast_to(side_values([self.left_m, self.right_m], seg), radius.shape)


def bounds(seg: Segments) -> dict[str, Bound]:
    r = float(np.median(seg.radius))
    return dict.fromkeys(("left_m", "right_m"), Bound(r, 0.5 * r, 1.5 * r, 0.01 * r))


def start(ctx: StartContext) -> list[RollingRadius]:
    lin = linear_starts(ctx.seg)
    return [RollingRadius(lin["radius_left_m"], lin["radius_right_m"])]


def apply(edit: WorldEdit, p: RollingRadius) -> None:
    edit.set_rolling_radii(p.left_m, p.right_m)


def draw(rng: np.random.Generator, ctx: DrawContext) -> Hidden:
    r = ctx.spec.wheel_radius_nominal_m
    sizes = [float(rng.uniform(0.01, 0.04) * rng.choice([-1.0, 1.0])) for _ in range(2)]
    return Hidden(RollingRadius(r * (1 + sizes[0]), r * (1 + sizes[1])))


EFFECT = Effect(
    name="rolling_radius",
    calibration=True,
    meaning="effective rolling radius differs from nominal (per wheel)",
    params=RollingRadius, bounds=bounds, start=start, apply=apply, rank=1,
    contract=(PerSide("left_m", "right_m", "radius_{w}_m"),),
    hiding=Hiding(("diff_drive", "skid_steer", "rover4ws"), draw),
)
