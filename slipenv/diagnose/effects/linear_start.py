"""Closed-form starting values for the geometric effects (track width, side radii)."""

from __future__ import annotations

import numpy as np

from slipenv.diagnose.segments import Segments


def linear_starts(seg: Segments, window: int = 10) -> dict[str, float]:
    """Starts ``{"track_width_m", "radius_left_m", "radius_right_m"}`` from short windows.

    Over windows of ``window`` samples with ground truth at both ends, the logged heading
    change Δψ and along-track travel Δs are linear in 1/W and in (r_L, r_R):
    Δψ W = r_R Δφ_R - r_L Δφ_L and Δs = (r_L Δφ_L + r_R Δφ_R)/2 (level-ground kinematics;
    good enough to start from, and free of the local minima that wrapped headings give a
    long segment whose nominal replay is far off).
    """
    rows = []
    for j in range(len(seg)):
        ok = np.flatnonzero(seg.gt_ok[j])
        for a in ok[::window]:
            b = a + window
            if b >= seg.gt.shape[1] or not seg.gt_ok[j, b]:
                continue
            phi = seg.dphi[j, a:b].sum(axis=0)
            dyaw = float(np.angle(np.exp(1j * (seg.gt[j, b, 2] - seg.gt[j, a, 2]))))
            mid = seg.gt[j, a, 2] + 0.5 * dyaw
            dx, dy = seg.gt[j, b, :2] - seg.gt[j, a, :2]
            rows.append([phi[seg.sides == 0].mean(), phi[seg.sides == 1].mean(), dyaw,
                         np.cos(mid) * dx + np.sin(mid) * dy])
    r0, w0 = float(np.median(seg.radius)), float(np.median(seg.track))
    if len(rows) < 5:
        return {"track_width_m": w0, "radius_left_m": r0, "radius_right_m": r0}
    phl, phr, dyaw, ds = np.array(rows).T
    diff = r0 * (phr - phl)
    inv_w = float(dyaw @ diff / max(diff @ diff, 1e-300))
    w = float(np.clip(1.0 / inv_w, 0.25 * w0, 4.0 * w0)) if inv_w > 0 else w0
    a = np.vstack([np.column_stack([0.5 * phl, 0.5 * phr]), np.column_stack([-phl, phr])])
    r, *_ = np.linalg.lstsq(a, np.concatenate([ds, w * dyaw]), rcond=None)
    r = np.clip(r, 0.6 * r0, 1.4 * r0)
    return {"track_width_m": w, "radius_left_m": float(r[0]), "radius_right_m": float(r[1])}
