"""``torque_slip``: longitudinal slip grows with wheel torque, s = T/k_s (Lindgren Eq. 24).

The compliance c = 1/k_s is what is fitted (linear in the slip, 0 when there is no torque
slip); k_s and its standard error follow by the delta method. Replay: s_i = T_i c_side
(``replay.py`` step 2). Simulation: the force law's longitudinal slip stiffness scaled so that
a drive channel's Σ r dF_x/ds at rest is k_s. Hidden in the tests (differential drive):
k_s set for 2-6 % slip at the typical torque.
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
    Term,
    compliance_bound,
    finite,
    needs_torque,
    side_values,
    stiffness_nm,
)
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments


@dataclass(frozen=True)
class TorqueSlip(Term):
    """Torque compliances c = 1/k_s of the left and right drive [1/(N m)]."""

    compliance_left_per_nm: float
    compliance_right_per_nm: float

    def __post_init__(self) -> None:
        finite(self)

    def slip(self, seg: Segments, pos: np.ndarray) -> np.ndarray | None:
        if seg.torque is None:
            return None
        c = side_values([self.compliance_left_per_nm, self.compliance_right_per_nm], seg)
        return seg.torque * c

    def stiffness_nm(self) -> float:
        """Mean torque-slip stiffness k_s of the two sides [N m per unit slip]."""
        return float(np.mean([stiffness_nm(self.compliance_left_per_nm),
                              stiffness_nm(self.compliance_right_per_nm)]))


def bounds(seg: Segments) -> dict[str, Bound]:
    return dict.fromkeys(("compliance_left_per_nm", "compliance_right_per_nm"),
                         compliance_bound(seg))


def apply(edit: WorldEdit, p: TorqueSlip) -> None:
    edit.slip_options["long_scale"] = p.stiffness_nm() / edit.channel_stiffness()


def draw(rng: np.random.Generator, ctx: DrawContext) -> Hidden:
    c = float(rng.uniform(0.02, 0.06)) / ctx.typical_torque_nm()
    return Hidden(TorqueSlip(c, c))


EFFECT = Effect(
    name="torque_slip",
    meaning="longitudinal slip grows with wheel torque, s = T/k_s (Lindgren)",
    params=TorqueSlip, bounds=bounds, apply=apply, rank=3, applicable=needs_torque,
    contract=(PerSide("compliance_left_per_nm", "compliance_right_per_nm", "k_s_{w}_nm",
                      reciprocal=True),),
    mechanism="torque slip law",
    hiding=Hiding(("diff_drive",), draw, columns=frozenset({"torque"})),
)
