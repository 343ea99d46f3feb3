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
    """

    seg: Segments
    heading_scale_m: float

    @classmethod
    def from_segments(cls, seg: Segments) -> Problem:
        travel = np.abs(seg.dphi * seg.radius[:, None, :]).mean(axis=-1).sum(axis=1)
        ell = 0.5 * float(np.median(travel))
        return cls(seg, max(ell, float(np.median(seg.track))))

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
        start: dict[str, float] | None = None) -> Fit:
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
    lo = np.array([s.lower for s in specs])
    hi = np.array([s.upper for s in specs])
    x0 = np.clip([init.get(s.name, s.start) for s in specs], lo + 1e-12 * np.abs(lo),
                 hi - 1e-12 * np.abs(hi))
    mask = seg.gt_ok

    def fun(x: np.ndarray) -> np.ndarray:
        return problem.residuals(effects, dict(zip(names, x, strict=True)), seg)[mask].ravel()

    sol = least_squares(fun, x0, bounds=(lo, hi), x_scale=np.array([s.scale for s in specs]),
                        method="trf", xtol=1e-10, ftol=1e-10, max_nfev=200 * len(specs))
    cov = _cluster_covariance(problem, effects, seg, names, sol.x, sol.jac)
    return Fit(effects, names, sol.x, cov, float(np.sqrt(np.mean(sol.fun**2))), len(seg))


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
