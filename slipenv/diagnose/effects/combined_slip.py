"""``combined_slip``: longitudinal slip grows with the slip angle (Reina Eq. 12).

Replay (``replay.py`` step 2): s = s_x0 + k_β softplus(|β| - β0) with the slip angle β measured
from ground truth (the hinge of Reina Eq. 12, smoothed over ``_SOFTPLUS_RAD``). Simulation:
the force law's zero-traction slip moved to s_x(β) (``ScaledSlipForceModel``). Not hidden by
the test generator: on its vehicles a slip angle comes only with side slip, so it never appears
alone (``tests/diagnose/test_replay.py`` hides it kinematically).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipenv.diagnose.effects.base import Bound, Effect, Scalar, Term, applicable_to_world, finite
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments

_SOFTPLUS_RAD = 0.01  # [rad] corner width of the hinge
_MIN_BETA_RAD = np.radians(1.0)  # measured slip angle needed before the effect is testable


@dataclass(frozen=True)
class CombinedSlip(Term):
    """Slip at zero slip angle s_x0 [-], its growth k_β [1/rad], the hinge β0 [rad]."""

    s_x0: float
    k_beta: float
    beta0_rad: float

    def __post_init__(self) -> None:
        finite(self)

    def slip(self, seg: Segments, pos: np.ndarray) -> np.ndarray:
        z = (np.abs(seg.beta) - self.beta0_rad) / _SOFTPLUS_RAD
        hinge = _SOFTPLUS_RAD * np.logaddexp(0.0, z)
        return (self.s_x0 + self.k_beta * hinge)[..., None]


def applicable(seg: Segments) -> str | None:
    if float(np.percentile(np.abs(seg.beta), 90)) < _MIN_BETA_RAD:
        return "measured slip angle stays below 1°"
    return None


def bounds(seg: Segments) -> dict[str, Bound]:
    return {"s_x0": Bound(0.0, -0.5, 0.5, 0.02), "k_beta": Bound(0.0, -10.0, 10.0, 0.5),
            "beta0_rad": Bound(0.02, 0.0, 0.5, 0.02)}


def apply(edit: WorldEdit, p: CombinedSlip) -> None:
    applicable_to_world(abs(p.s_x0) < 1.0, EFFECT.name, "s_x0",
                        f"the slip the wheel rolls free at is a slip ratio, |s_x0| < 1, got "
                        f"{p.s_x0}")
    edit.slip_options.update(s_x0=p.s_x0, k_beta=p.k_beta, beta0_rad=p.beta0_rad)


EFFECT = Effect(
    name="combined_slip",
    meaning="longitudinal slip grows with slip angle (Reina Eq. 12)",
    params=CombinedSlip, bounds=bounds, apply=apply, rank=6, applicable=applicable,
    redundant={"s_x0": "rolling_radius"},
    contract=(Scalar("s_x0", "s_x0"), Scalar("k_beta", "k_beta"),
              Scalar("beta0_rad", "beta0_rad")),
)
