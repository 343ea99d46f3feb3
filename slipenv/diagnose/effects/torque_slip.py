"""``torque_slip``: longitudinal slip grows with wheel torque, s = T/k_s (Lindgren Eq. 24).

The compliance c = 1/k_s is what is fitted (linear in the slip, 0 when there is no torque
slip); k_s and its standard error follow by the delta method. Replay: s_i = T_i c_side
(``replay.py`` step 2). Simulation: the force law's longitudinal slip stiffness scaled so that
a drive channel's Σ r dF_x/ds at rest is k_s. Hidden in the tests: k_s set for 2-6 % slip at
the typical drive torque, on every vehicle kind:

- differential drive: the clean world's median channel torque;
- rover (4WD/4WS): on level rigid ground its torque is the wheels fighting one another over
  the steering geometry (median 2.7 N m), which a softer law takes away (0.1-0.2 N m left in
  the softened world: s = T/k_s of 0.2-0.4 %, below what a log resolves). The rover therefore
  stands on a 6-12° slope and k_s is set for the torque that holds it there,
  m g sin α r / n_channels (Lindgren's runs are on slopes for the same reason);
- skid-steer (and the tracked vehicle): on level ground a softer longitudinal law is exactly
  what ``turning_slip`` hides (the same stiffness scale, 0.04-0.12 of the rigid ground's),
  and it shows as slip in turns split between the sides (Endo). There the drive torque *is*
  the turning resistance: measured on level logs (seed 99), the side torques hardly vary
  (15-25 N m in every 0.5 s window, both sides alike) while the turn falls to 0.3 of the
  wheels' nominal turn, so T and the turn are one regressor and s = T/k_s can only fit each
  side's slip as a constant set by the log's mix of left and right turns; fitted on one half
  of the log it does not carry to the other (gain 1-5 %, turning slip's 100 %). Such a log
  names ``turning_slip`` and the report gives ``torque_slip`` as the confounded alternative
  (``Confound``). Torque slip is identifiable only where a torque that the turn does not set
  acts, so the skid-steer vehicles stand on a 6-12° slope, as the rover does: the grade
  torque changes sign between uphill and downhill legs whatever the turn (measured, skid-steer
  on 9.3°, 120 s: held-out error 0.010 of the nominal model's for torque slip against 0.029
  for turning slip, named ``torque_slip``). k_s is still sized for 2-6 % slip at the level
  world's typical torque, so the law is as soft as on level ground.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from slipenv.diagnose.effects.base import (
    Bound,
    Confound,
    DrawContext,
    Effect,
    Hidden,
    Hiding,
    PerSide,
    Term,
    applicable_to_world,
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
    sides = (p.compliance_left_per_nm, p.compliance_right_per_nm)
    applicable_to_world(min(sides) >= 0.0, EFFECT.name, "k_s_<wheel>_nm",
                        f"a torque stiffness must be > 0 (a driven wheel cannot run ahead "
                        f"of its rim), got compliances {sides} 1/(N m)")
    edit.slip_options["long_scale"] = p.stiffness_nm() / edit.channel_stiffness()


def draw(rng: np.random.Generator, ctx: DrawContext) -> Hidden:
    slip = float(rng.uniform(0.02, 0.06))
    c = slip / ctx.slip_torque_nm()
    return Hidden(TorqueSlip(c, c))


EFFECT = Effect(
    name="torque_slip",
    meaning="longitudinal slip grows with wheel torque, s = T/k_s (Lindgren)",
    params=TorqueSlip, bounds=bounds, apply=apply, rank=3, applicable=needs_torque,
    contract=(PerSide("compliance_left_per_nm", "compliance_right_per_nm", "k_s_{w}_nm",
                      reciprocal=True),),
    mechanism="torque slip law",
    hiding=Hiding(("diff_drive", "skid_steer", "rover4ws"), draw, slope_deg=(6.0, 12.0),
                  slope_kinds=("rover4ws", "skid_steer"), columns=frozenset({"torque"})),
    confounds=(Confound(
        "skid_steer", "turning_slip",
        "on a skid-steer vehicle on level ground a softer longitudinal law (torque slip's "
        "physics) shows as slip in turns split between the sides (Endo's turning slip); the "
        "drive torque is then the turning resistance and hardly varies, so s = T/k_s fits "
        "each side's slip only as a constant set by the log's mix of left and right turns, "
        "which does not carry over to the rest of the log; a grade (a torque the turn does "
        "not set) separates them"),),
)
