"""Fitting effect parameters to ground truth: nonlinear least squares on replay residuals.

The residuals of one segment are its replayed-minus-logged positions [m] and headings scaled
by a length ℓ (half the median distance a segment covers: a heading error δ displaces the
rest of the segment by about δ ℓ). They are strongly correlated within a segment (a wrong
radius shows as a growing drift), so the standard errors come from the cluster-robust
("sandwich") covariance with one cluster per segment (Liang and Zeger 1986), scaled by
G/(G - p) for G segments and p parameters; never smaller than the classical
σ² (JᵀJ)⁻¹, which holds when the residuals are independent.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from slipenv.diagnose import replay
from slipenv.diagnose.effects import Param, effect
from slipenv.diagnose.replay import Segments


@dataclass
class Problem:
    """The segments of the log(s) and the scales the residuals use.

    Attributes
    ----------
    seg : Segments
    heading_scale_m : float
        ℓ [m], the length a heading residual is multiplied by.
    travel_m : float
        Median distance the wheels cover in a segment [m].
    """

    seg: Segments
    heading_scale_m: float
    travel_m: float

    @classmethod
    def from_segments(cls, seg: Segments) -> Problem:
        travel = np.abs(seg.dphi * seg.radius[:, None, :]).mean(axis=-1).sum(axis=1)
        median = max(float(np.median(travel)), 1e-6)
        return cls(seg, max(0.5 * median, float(np.median(seg.track))), median)

    def channel(self, effects: tuple[str, ...]) -> str:
        chans = {effect(e).channel for e in effects} or {"pose"}
        if len(chans) > 1:
            raise ValueError(f"effects {effects} mix the pose and gyro channels")
        return chans.pop()

    def residuals(self, effects: tuple[str, ...], p: dict, seg: Segments | None = None
                  ) -> np.ndarray:
        """Residuals (S, L, k) of the channel of ``effects``: k = 3 (pose) or 1 (gyro)."""
        seg = self.seg if seg is None else seg
        if self.channel(effects) == "gyro":
            yaw = replay.simulate_gyro_heading(seg, p)
            return (self.heading_scale_m * replay.heading_residuals(seg, yaw))[..., None]
        res = replay.pose_residuals(seg, replay.simulate(seg, p))
        res[..., 2] *= self.heading_scale_m
        return res

    def segment_errors(self, effects: tuple[str, ...], p: dict,
                       seg: Segments | None = None) -> np.ndarray:
        """Mean squared residual of each segment (S,), over its ground-truth samples."""
        seg = self.seg if seg is None else seg
        res = self.residuals(effects, p, seg)
        count = np.maximum(seg.gt_ok.sum(axis=1), 1)
        return (res**2).sum(axis=(1, 2)) / count


@dataclass
class Fit:
    """A fitted set of effects.

    Attributes
    ----------
    effects : tuple[str, ...]
    names : list[str]
        Internal parameter names, in ``x`` order.
    x : ndarray
        Fitted internal values.
    cov : ndarray
        Cluster-robust covariance of ``x``.
    rmse : float
        Root mean square of the training residuals.
    n_segments : int
        Training segments.
    """

    effects: tuple[str, ...]
    names: list[str]
    x: np.ndarray
    cov: np.ndarray
    rmse: float
    n_segments: int

    @property
    def params(self) -> dict[str, float]:
        return dict(zip(self.names, self.x.tolist(), strict=True))

    @property
    def se(self) -> dict[str, float]:
        return dict(zip(self.names, np.sqrt(np.maximum(np.diag(self.cov), 0.0)).tolist(),
                        strict=True))

    def report(self, seg: Segments) -> dict[str, list[float]]:
        """``{contract name: [value, se]}`` over all effects (soil-patch stiffnesses prefixed
        ``patch_`` when torque slip is fitted too)."""
        out: dict[str, list[float]] = {}
        for name in self.effects:
            part = effect(name).to_contract(self.params, self.se, seg.wheels, seg.sides)
            if name == "soil_patch" and "torque_slip" in self.effects:
                part = {(f"patch_{k}" if k.startswith("k_s_") else k): v for k, v in part.items()}
            out.update(part)
        return out


def param_specs(effects: tuple[str, ...], seg: Segments) -> list[Param]:
    specs: list[Param] = []
    for name in effects:
        specs += effect(name).params(seg)
    return specs


def fit(problem: Problem, effects: tuple[str, ...], index: np.ndarray | None = None,
        start: dict[str, float] | None = None, budget: int = 60) -> Fit:
    """Fit ``effects`` on the segments at ``index`` (all by default).

    Parameters
    ----------
    problem : Problem
    effects : tuple of str
        Effect ids; an empty tuple gives the nominal model (nothing to fit).
    index : ndarray of int, optional
        Training segments.
    start : dict, optional
        Starting values overriding the effects' defaults (internal names).
    budget : int
        Function evaluations allowed per parameter.
    """
    seg = problem.seg if index is None else problem.seg.take(index)
    specs = param_specs(effects, seg)
    names = [s.name for s in specs]
    if not specs:
        res = problem.residuals(effects, {}, seg)[seg.gt_ok]
        return Fit(effects, [], np.zeros(0), np.zeros((0, 0)),
                   float(np.sqrt(np.mean(res**2))), len(seg))
    init = dict(start or {})
    if "soil_patch" in effects and not {"px", "py", "pr"} <= init.keys():
        init.update(patch_start(problem, seg, effects, init))
    names_set = {sp.name for sp in specs}
    if names_set & {"W", "r_L", "turn_k"}:
        for key, value in linear_starts(seg).items():
            if key in names_set and key not in init:
                init[key] = value
    if "turning_slip" in effects and "turn_k" not in init:
        # the yaw loss is a track-width change to first order: κ0 = 1 - W/W_fit; Endo's
        # exponent from a few starts (the split of the forward speed is not convex in n)
        w_fit = linear_starts(seg)["W"]
        init["turn_k"] = float(np.clip(1.0 - float(np.median(seg.track)) / w_fit, -0.8, 0.9))
        best = None
        for n0 in (0.3, 0.8, 1.5):  # short trial fits; the best one is refined
            trial = fit(problem, effects, index, {**init, "endo_n": n0}, budget=8)
            if best is None or trial.rmse < best.rmse:
                best = trial
        return fit(problem, effects, index, best.params, budget)
    lo = np.array([s.lower for s in specs])
    hi = np.array([s.upper for s in specs])
    x0 = np.clip([init.get(s.name, s.start) for s in specs], lo + 1e-12 * np.abs(lo),
                 hi - 1e-12 * np.abs(hi))
    mask = seg.gt_ok

    def fun(x: np.ndarray) -> np.ndarray:
        return problem.residuals(effects, dict(zip(names, x, strict=True)), seg)[mask].ravel()

    sol = least_squares(fun, x0, bounds=(lo, hi), x_scale=np.array([s.scale for s in specs]),
                        method="trf", xtol=1e-8, ftol=1e-8, max_nfev=budget * len(specs))
    cov = _cluster_covariance(problem, effects, seg, names, sol.x, sol.jac)
    return Fit(effects, names, sol.x, cov, float(np.sqrt(np.mean(sol.fun**2))), len(seg))


def linear_starts(seg: Segments, window: int = 10) -> dict[str, float]:
    """Closed-form starts for the track width and the side radii, from short windows.

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
        return {"W": w0, "r_L": r0, "r_R": r0}
    phl, phr, dyaw, ds = np.array(rows).T
    diff = r0 * (phr - phl)
    inv_w = float(dyaw @ diff / max(diff @ diff, 1e-300))
    w = float(np.clip(1.0 / inv_w, 0.25 * w0, 4.0 * w0)) if inv_w > 0 else w0
    a = np.vstack([np.column_stack([0.5 * phl, 0.5 * phr]), np.column_stack([-phl, phr])])
    r, *_ = np.linalg.lstsq(a, np.concatenate([ds, w * dyaw]), rcond=None)
    r = np.clip(r, 0.6 * r0, 1.4 * r0)
    return {"W": w, "r_L": float(r[0]), "r_R": float(r[1])}


def _cluster_covariance(problem: Problem, effects, seg: Segments, names, x, jac) -> np.ndarray:
    """Cluster-robust covariance (one cluster per segment), floored by the classical one."""
    res = problem.residuals(effects, dict(zip(names, x, strict=True)), seg)
    k = res.shape[-1]
    cluster = np.repeat(np.nonzero(seg.gt_ok)[0], k)
    r = res[seg.gt_ok].ravel()
    p = len(x)
    a = jac.T @ jac
    a_inv = np.linalg.pinv(a)
    g = len(seg)
    scores = np.zeros((g, p))
    np.add.at(scores, cluster, jac * r[:, None])
    meat = scores.T @ scores
    robust = a_inv @ meat @ a_inv * (g / max(g - p, 1))
    classical = a_inv * float(r @ r) / max(len(r) - p, 1)
    # keep the robust correlations, floor each standard error at the classical one
    ratio = np.diag(classical) / np.maximum(np.diag(robust), 1e-300)
    d = np.sqrt(np.maximum(ratio, 1.0))
    return robust * d[:, None] * d[None, :]


def patch_start(problem: Problem, seg: Segments, effects: tuple[str, ...],
                init: dict[str, float]) -> dict[str, float]:
    """Best disc on a grid for the soil patch, with its compliances (linearised fit).

    For each disc (8 × 8 centres over the ground-truth extent, 3 radii) the residuals are
    linear in the two inside compliances to first order: one finite difference each and a
    2 × 2 least squares give the disc's cost. The best disc starts the full fit.
    """
    from slipenv.diagnose.effects import patch_extent

    x0, y0, x1, y1 = patch_extent(seg)
    size = max(x1 - x0, y1 - y0, 1e-3)
    base = {s.name: init.get(s.name, s.start) for s in param_specs(effects, seg)}
    scale = effect("soil_patch").params(seg)[3].scale
    mask = seg.gt_ok
    best = (np.inf, {})
    for radius in (0.1 * size, 0.2 * size, 0.35 * size):
        for cx in np.linspace(x0, x1, 8):
            for cy in np.linspace(y0, y1, 8):
                p = {**base, "px": cx, "py": cy, "pr": radius, "pc_L": 0.0, "pc_R": 0.0}
                w = replay.patch_weight(seg.pos, cx, cy, radius)
                if w.max() < 0.5:
                    continue
                r0 = problem.residuals(effects, p, seg)[mask].ravel()
                cols = []
                for side in "LR":
                    q = {**p, f"pc_{side}": scale}
                    cols.append((problem.residuals(effects, q, seg)[mask].ravel() - r0) / scale)
                jac = np.column_stack(cols)
                step, *_ = np.linalg.lstsq(jac, -r0, rcond=None)
                cost = float(np.sum((r0 + jac @ step) ** 2))
                if cost < best[0]:
                    best = (cost, {"px": cx, "py": cy, "pr": radius,
                                   "pc_L": float(step[0]), "pc_R": float(step[1])})
    return best[1]
