"""Fuzzy confidence that a line candidate is the wheel trace (Reina §2.2, FTrace).

The paper scores each Hough candidate against the trace model "in both the image plane of the
camera and the real world" with fuzzy reasoning, and defers the rule base to its Ref. [12]; this
paper gives only the inputs (trace pose d_t, θ_t; Fig. 3) and the output (a confidence in
[0, 1], Table 1). The memberships and the rules below are therefore our choice, built on the five
cues of the trace model (physics-notes §3):

========================  ===================================================================
input                     membership (trapezoid: full inside ``full``, zero beyond ``zero``)
========================  ===================================================================
contact offset |e|        NEAR: the line passes through the wheel's contact region at x_w
midpoint distance |d_t|   CLOSE: the trace stays near the wheel-centre line in the view
angle change |Δθ|         CONT: continuity with the last frame's trace (or, with no last
                          trace, a prior |θ| below the largest plausible slip angle)
pair mismatch |s/b - 1|   PAIRED: an opposite rut edge at about the wheel width b
length L                  LONG: a long straight edge in the view
========================  ===================================================================

Zero-order Sugeno inference, AND = min, NOT = 1 - μ, output = Σ wᵢ zᵢ / Σ wᵢ:

- R1 NEAR ∧ CLOSE ∧ CONT ∧ PAIRED ∧ LONG → 1.0
- R2 NEAR ∧ CLOSE ∧ CONT ∧ PAIRED ∧ ¬LONG → 0.7
- R3 NEAR ∧ CLOSE ∧ CONT ∧ ¬PAIRED ∧ LONG → 0.6
- R4 NEAR ∧ CLOSE ∧ CONT ∧ ¬PAIRED ∧ ¬LONG → 0.2
- R5 ¬NEAR ∨ ¬CLOSE → 0.0
- R6 ¬CONT → 0.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


def trapezoid_low(x: np.ndarray, full: float, zero: float) -> np.ndarray:
    """Membership 1 for ``x <= full``, falling linearly to 0 at ``x >= zero``."""
    return np.clip((zero - np.asarray(x, dtype=float)) / (zero - full), 0.0, 1.0)


@dataclass(frozen=True)
class FuzzyTraceRules:
    """Breakpoints of the memberships (full, zero) and the rule outputs.

    Attributes
    ----------
    contact_m : tuple of float
        |e|, lateral offset of the candidate at the contact point's x [m].
    midpoint_m : tuple of float
        |d_t| at the middle of the view [m] (0.34 m behind the wheel; 25° of slip gives 0.16 m).
    angle_change_rad : tuple of float
        |θ - θ_last| between frames 0.2 s apart [rad].
    prior_angle_rad : tuple of float
        |θ| when there is no last trace [rad].
    pair_mismatch : tuple of float
        |s/b - 1| for the separation s of the paired edge [-].
    length_m : tuple of float
        Edge length; LONG rises from the second value (0) to the first (1) [m].
    outputs : tuple of float
        z of R1..R4 (R5, R6 give 0).
    """

    contact_m: tuple[float, float] = (0.02, 0.06)
    midpoint_m: tuple[float, float] = (0.20, 0.35)
    angle_change_rad: tuple[float, float] = (math.radians(2.5), math.radians(8.0))
    prior_angle_rad: tuple[float, float] = (math.radians(30.0), math.radians(45.0))
    pair_mismatch: tuple[float, float] = (0.25, 0.5)
    length_m: tuple[float, float] = (0.30, 0.08)
    outputs: tuple[float, float, float, float] = (1.0, 0.7, 0.6, 0.2)

    def __post_init__(self) -> None:
        for name in ("contact_m", "midpoint_m", "angle_change_rad", "prior_angle_rad",
                     "pair_mismatch"):
            full, zero = getattr(self, name)
            if not 0.0 <= full < zero:
                raise ValueError(f"FuzzyTraceRules.{name} needs 0 <= full < zero, got "
                                 f"{getattr(self, name)!r}")
        if not 0.0 <= self.length_m[1] < self.length_m[0]:
            raise ValueError(f"FuzzyTraceRules.length_m needs (long, short) with long > short, "
                             f"got {self.length_m!r}")
        if not all(0.0 <= z <= 1.0 for z in self.outputs):
            raise ValueError(f"FuzzyTraceRules.outputs must lie in [0, 1], got {self.outputs!r}")

    def confidence(
        self,
        contact_offset_m: np.ndarray,
        midpoint_offset_m: np.ndarray,
        angle_rad: np.ndarray,
        last_angle_rad: float | None,
        pair_mismatch: np.ndarray,
        length_m: np.ndarray,
    ) -> np.ndarray:
        """Confidence in [0, 1] for each candidate (arrays of equal shape).

        ``pair_mismatch`` is ``inf`` for a candidate without an opposite edge.
        """
        near = trapezoid_low(np.abs(contact_offset_m), *self.contact_m)
        close = trapezoid_low(np.abs(midpoint_offset_m), *self.midpoint_m)
        if last_angle_rad is None:
            cont = trapezoid_low(np.abs(angle_rad), *self.prior_angle_rad)
        else:
            cont = trapezoid_low(np.abs(np.asarray(angle_rad) - last_angle_rad),
                                 *self.angle_change_rad)
        paired = trapezoid_low(pair_mismatch, *self.pair_mismatch)
        long_ = 1.0 - trapezoid_low(length_m, self.length_m[1], self.length_m[0])
        base = np.minimum(np.minimum(near, close), cont)
        z1, z2, z3, z4 = self.outputs
        w = [np.minimum(base, np.minimum(paired, long_)),
             np.minimum(base, np.minimum(paired, 1.0 - long_)),
             np.minimum(base, np.minimum(1.0 - paired, long_)),
             np.minimum(base, np.minimum(1.0 - paired, 1.0 - long_)),
             np.maximum(1.0 - near, 1.0 - close),
             1.0 - cont]
        num = z1 * w[0] + z2 * w[1] + z3 * w[2] + z4 * w[3]
        den = sum(w)
        return np.where(den > 0.0, num / np.where(den > 0.0, den, 1.0), 0.0)
