"""``slope_side_slip``: a slip angle driven by roll on a side slope (Yamauchi's regression).

Replay (``replay.py`` step 5): β = (β_roll + β_turn |dθ/dt|) roll + β_0, the logged roll or
the declared slope's; the turning term makes a skid-steer vehicle slide downhill while it
scrubs round a turn (slipenv's addition to the contract's list, 0 when absent). Simulation:
the lateral slip stiffness scaled so that β = β_roll roll on a side slope (the driven wheels'
side forces balance m g sin roll), the offset β_0 as a crab angle. Hidden in the tests
(skid-steer): an 8-15° side slope with a soft side stiffness (×0.15-0.4); the log's nominal
width is calibrated on level ground of the same soil.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipenv.contracts.constants import G_MPS2
from slipenv.diagnose.effects.base import (
    Bound,
    DrawContext,
    Effect,
    Hidden,
    Hiding,
    Scalar,
    Term,
    finite,
)
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments

_MIN_ROLL_RANGE_RAD = np.radians(2.0)  # roll must vary this much for β_roll to be identifiable


@dataclass(frozen=True)
class SlopeSideSlip(Term):
    """β per roll [rad/rad], offset β_0 [rad], β per roll and yaw rate [s]."""

    beta_per_roll: float
    beta_offset_rad: float
    beta_per_roll_yaw_rate_s: float = 0.0

    def __post_init__(self) -> None:
        finite(self)

    def slip_angle(self, seg: Segments, ds: np.ndarray, dtheta: np.ndarray,
                   mid: np.ndarray) -> np.ndarray:
        roll = seg.roll if seg.roll is not None else seg.geometric_roll(mid)
        turn = np.abs(dtheta) / np.maximum(seg.dt, 1e-9)
        return roll * (self.beta_per_roll + self.beta_per_roll_yaw_rate_s * turn) \
            + self.beta_offset_rad


def applicable(seg: Segments) -> str | None:
    roll = seg.roll if seg.roll is not None else seg.geometric_roll(seg.anchor_heading()[:, None])
    spread = float(np.percentile(roll, 95) - np.percentile(roll, 5)) if roll.size else 0.0
    if spread < _MIN_ROLL_RANGE_RAD:
        return "roll varies by less than 2° (level ground, or no roll signal)"
    return None


def bounds(seg: Segments) -> dict[str, Bound]:
    return {"beta_per_roll": Bound(0.0, -5.0, 5.0, 0.2),
            "beta_offset_rad": Bound(0.0, -0.5, 0.5, 0.02),
            "beta_per_roll_yaw_rate_s": Bound(0.0, -20.0, 20.0, 0.5)}


def apply(edit: WorldEdit, p: SlopeSideSlip) -> None:
    per_roll = max(abs(p.beta_per_roll), 1e-6)  # no side slip: very stiff sideways
    edit.slip_options["lat_scale"] = (edit.spec.mass_kg * G_MPS2 / per_roll
                                      / edit.lateral_stiffness())
    edit.slip_options["lat_offset_rad"] = p.beta_offset_rad


def draw(rng: np.random.Generator, ctx: DrawContext) -> Hidden:
    # soft ground that gives little side force: on the slope the vehicle slides downhill
    return Hidden(slip_options={"lat_scale": float(rng.uniform(0.15, 0.4))})


EFFECT = Effect(
    name="slope_side_slip",
    meaning="slip angle driven by roll on a side slope (Yamauchi)",
    params=SlopeSideSlip, bounds=bounds, apply=apply, rank=5, applicable=applicable,
    contract=(Scalar("beta_per_roll", "beta_per_roll"),
              Scalar("beta_offset_rad", "beta_offset_rad"),
              Scalar("beta_per_roll_yaw_rate_s", "beta_per_roll_yaw_rate_s")),
    optional={"beta_per_roll_yaw_rate_s": 0.0},
    hiding=Hiding(("skid_steer",), draw, slope_deg=(8.0, 15.0), level_width=True),
)
