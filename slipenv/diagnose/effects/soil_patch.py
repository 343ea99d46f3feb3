"""``soil_patch``: a disc of softer soil, torque slip inside a region.

Replay: s_i = w(x, y) T_i c_side with w a soft disc (``replay.py`` step 2; :func:`patch_weight`).
Fitted from the best disc of a grid search (:func:`start`). Simulation: a ``PatchSoilMap``
disc whose soil is that much softer (Reina's C_x, or the Janosi/linear shear modulus K).
Hidden in the tests (differential drive, level ground): a disc of 35-50 % of the arena's
half-size on the route's focus, 2-5 % slip inside at the typical torque.
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
    Scalar,
    StartContext,
    Term,
    applicable_to_world,
    compliance_bound,
    finite,
    needs_torque,
    require,
    side_values,
    stiffness_nm,
)
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments
from slipenv.terramechanics.soil_map import Circle, PatchSoilMap

_EDGE = 0.2  # width of the disc's blend band, as a fraction of its radius


@dataclass(frozen=True)
class SoilPatch(Term):
    """A disc (centre [m], radius [m]) with torque compliances c = 1/k_s inside [1/(N m)]."""

    center_x_m: float
    center_y_m: float
    radius_m: float
    compliance_left_per_nm: float
    compliance_right_per_nm: float

    def __post_init__(self) -> None:
        finite(self)
        require(self.radius_m > 0, self, f"radius_m must be > 0, got {self.radius_m}")

    def slip(self, seg: Segments, pos: np.ndarray) -> np.ndarray | None:
        if seg.torque is None:
            return None
        w = patch_weight(pos, self.center_x_m, self.center_y_m, self.radius_m)
        c = side_values([self.compliance_left_per_nm, self.compliance_right_per_nm], seg)
        return w[..., None] * seg.torque * c


def patch_weight(pos: np.ndarray, cx: float, cy: float, radius: float) -> np.ndarray:
    """Weight of a soft disc at ``pos`` (…, 2) [m]: 1 inside, 0 outside, C1 smoothstep edge.

    The edge band is 0.2 radius wide, centred on the circle (the blend of
    ``slipenv.terramechanics.soil_map.PatchSoilMap`` with ``blend_width_m = 0.2 radius``).
    """
    radius = max(float(radius), 1e-6)
    d = np.hypot(pos[..., 0] - cx, pos[..., 1] - cy) - radius
    u = np.clip(0.5 - d / (_EDGE * radius), 0.0, 1.0)
    return u * u * (3.0 - 2.0 * u)


def patch_extent(seg: Segments) -> tuple[float, float, float, float]:
    """Bounding box (x0, y0, x1, y1) of the ground-truth positions [m]."""
    pos = seg.pos.reshape(-1, 2)
    return (float(pos[:, 0].min()), float(pos[:, 1].min()),
            float(pos[:, 0].max()), float(pos[:, 1].max()))


def bounds(seg: Segments) -> dict[str, Bound]:
    x0, y0, x1, y1 = patch_extent(seg)
    size = max(x1 - x0, y1 - y0, 1e-3)
    c = compliance_bound(seg)
    return {"center_x_m": Bound(0.5 * (x0 + x1), x0 - 0.25 * size, x1 + 0.25 * size,
                                0.1 * size),
            "center_y_m": Bound(0.5 * (y0 + y1), y0 - 0.25 * size, y1 + 0.25 * size,
                                0.1 * size),
            "radius_m": Bound(0.2 * size, 0.03 * size, 0.6 * size, 0.05 * size),
            "compliance_left_per_nm": c, "compliance_right_per_nm": c}


def start(ctx: StartContext) -> list[SoilPatch]:
    """Best disc on a grid, with its compliances (linearised fit).

    For each disc (8 × 8 centres over the ground-truth extent, 3 radii) the residuals are
    linear in the two inside compliances to first order: one finite difference each and a
    2 × 2 least squares give the disc's cost. The best disc starts the full fit.
    """
    seg = ctx.seg
    x0, y0, x1, y1 = patch_extent(seg)
    size = max(x1 - x0, y1 - y0, 1e-3)
    scale = compliance_bound(seg).scale
    best: tuple[float, list[SoilPatch]] = (np.inf, [])
    for radius in (0.1 * size, 0.2 * size, 0.35 * size):
        for cx in np.linspace(x0, x1, 8):
            for cy in np.linspace(y0, y1, 8):
                if patch_weight(seg.pos, cx, cy, radius).max() < 0.5:
                    continue
                r0 = ctx.residuals({**ctx.model, EFFECT.name: SoilPatch(cx, cy, radius, 0, 0)})
                cols = [(ctx.residuals({**ctx.model, EFFECT.name: SoilPatch(
                    cx, cy, radius, *(scale * np.eye(2)[side]))}) - r0) / scale
                    for side in (0, 1)]
                jac = np.column_stack(cols)
                step, *_ = np.linalg.lstsq(jac, -r0, rcond=None)
                cost = float(np.sum((r0 + jac @ step) ** 2))
                if cost < best[0]:
                    best = (cost, [SoilPatch(float(cx), float(cy), radius, float(step[0]),
                                             float(step[1]))])
    return best[1]


def apply(edit: WorldEdit, p: SoilPatch) -> None:
    sides = (p.compliance_left_per_nm, p.compliance_right_per_nm)
    applicable_to_world(min(sides) >= 0.0, EFFECT.name, "k_s_<wheel>_nm",
                        f"the patch's torque stiffness must be > 0 (a driven wheel cannot "
                        f"run ahead of its rim), got compliances {sides} 1/(N m)")
    k_s = float(np.mean([stiffness_nm(p.compliance_left_per_nm),
                         stiffness_nm(p.compliance_right_per_nm)]))
    inner = edit.softer(k_s / edit.channel_stiffness())
    disc = Circle(p.center_x_m, p.center_y_m, p.radius_m)
    edit.replace["soil_map"] = PatchSoilMap(edit.soil, [(disc, inner)],
                                            blend_width_m=_EDGE * p.radius_m)


def draw(rng: np.random.Generator, ctx: DrawContext) -> Hidden:
    c = float(rng.uniform(0.02, 0.05)) / ctx.typical_torque_nm()
    radius = float(rng.uniform(0.35, 0.5)) * ctx.arena_m
    return Hidden(SoilPatch(ctx.focus[0], ctx.focus[1], radius, c, c))


EFFECT = Effect(
    name="soil_patch",
    meaning="a disc of softer soil: torque slip inside a region",
    params=SoilPatch, bounds=bounds, start=start, apply=apply, rank=7, applicable=needs_torque,
    contract=(Scalar("center_x_m", "patch_center_x_m"), Scalar("center_y_m", "patch_center_y_m"),
              Scalar("radius_m", "patch_radius_m"),
              PerSide("compliance_left_per_nm", "compliance_right_per_nm", "k_s_{w}_nm",
                      reciprocal=True)),
    mechanism="torque slip law", clash_prefix="patch_",
    hiding=Hiding(("diff_drive",), draw, random_slope=False, columns=frozenset({"torque"})),
    local=True,
)
