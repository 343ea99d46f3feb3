"""Fitting effect parameters to ground truth: nonlinear least squares on replay residuals.

The residuals of one segment are its replayed-minus-logged positions [m] and headings scaled
by a length ℓ (half the median distance a segment covers: a heading error δ displaces the
rest of the segment by about δ ℓ). They are strongly correlated within a segment (a wrong
radius shows as a growing drift), so the standard errors come from the cluster-robust
("sandwich") covariance with one cluster per segment (Liang and Zeger 1986), scaled by
G/(G - p) for G segments and p parameters; never smaller than the classical
σ² (JᵀJ)⁻¹, which holds when the residuals are independent (the classical one alone when
there are no more segments than parameters: the sandwich is then singular).

What is fitted comes from each effect's module (``effects/``): its fields, their bounds and
scales, and its data-driven starting guesses; this module never names an effect.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from slipenv.diagnose import replay
from slipenv.diagnose.effects import Term, contract_report, effect
from slipenv.diagnose.effects.base import Bound, StartContext
from slipenv.diagnose.segments import Segments

TRIAL_BUDGET = 8  # function evaluations per parameter of each short trial fit (several starts)


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

    def residuals(self, effects: tuple[str, ...], model: replay.Model,
                  seg: Segments | None = None, channel: str | None = None) -> np.ndarray:
        """Residuals (S, L, k) of the channel of ``effects`` (or ``channel``, for the nominal
        model): k = 3 (pose) or 1 (gyro)."""
        seg = self.seg if seg is None else seg
        if (channel or self.channel(effects)) == "gyro":
            yaw = replay.simulate_gyro_heading(seg, model)
            return (self.heading_scale_m * replay.heading_residuals(seg, yaw))[..., None]
        res = replay.pose_residuals(seg, replay.simulate(seg, model))
        res[..., 2] *= self.heading_scale_m
        return res

    def segment_errors(self, effects: tuple[str, ...], model: replay.Model,
                       seg: Segments | None = None, channel: str | None = None) -> np.ndarray:
        """Mean squared residual of each segment (S,), over its ground-truth samples."""
        seg = self.seg if seg is None else seg
        res = self.residuals(effects, model, seg, channel)
        count = np.maximum(seg.gt_ok.sum(axis=1), 1)
        return (res**2).sum(axis=(1, 2)) / count


@dataclass
class Fit:
    """A fitted set of effects.

    Attributes
    ----------
    effects : tuple[str, ...]
    names : list[str]
        ``<effect>.<field>`` of each entry of ``x``.
    x : ndarray
        Fitted values (the effects' fields, in order).
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
    def params(self) -> dict[str, Term]:
        """The fitted model: ``{effect id: parameters}`` (what ``replay.simulate`` takes)."""
        return unpack(self.effects, self.x)

    @property
    def se(self) -> dict[str, dict[str, float]]:
        """Standard errors, ``{effect id: {field: se}}``, in the fields' units."""
        errors = np.sqrt(np.maximum(np.diag(self.cov), 0.0)).tolist()
        out: dict[str, dict[str, float]] = {name: {} for name in self.effects}
        for key, e in zip(self.names, errors, strict=True):
            name, _, field_name = key.partition(".")
            out[name][field_name] = e
        return out

    def report(self, seg: Segments) -> dict[str, list[float]]:
        """``{contract name: [value, se]}`` over all effects (``effects.contract_report``)."""
        return contract_report(self.params, self.se, seg.wheels, seg.sides)


def unpack(effects: tuple[str, ...], x) -> dict[str, Term]:
    """The fitted vector ``x`` as ``{effect id: parameters}``."""
    out, k = {}, 0
    for name in effects:
        eff = effect(name)
        n = len(eff.fields())
        out[name] = eff.from_vector(x[k:k + n])
        k += n
    return out


def param_count(effects: tuple[str, ...], params: dict[str, Term] | None = None) -> int:
    """Number of fitted parameters of ``effects`` (a layout field counts: chosen from the
    data, it is a degree of freedom of the model; a redundant one held is not; with the
    fitted ``params``, only the fields their layout uses: ``Effect.used``)."""
    total = 0
    for name in effects:
        eff = effect(name)
        fields = len(eff.fields()) if params is None or eff.used is None else \
            eff.used(params[name])
        total += fields - len(eff.held(effects))
    return total


def layout(effects: tuple[str, ...], seg: Segments) -> list[tuple[str, Bound]]:
    """``(<effect>.<field>, Bound)`` of every fitted parameter, in the vector's order."""
    out = []
    for name in effects:
        eff = effect(name)
        bounds = eff.bounds(seg)
        if set(bounds) != set(eff.fields()):
            raise ValueError(f"effect {name!r}: bounds for {sorted(bounds)}, parameters "
                             f"{list(eff.fields())}")
        out += [(f"{name}.{f}", bounds[f]) for f in eff.fields()]
    return out


def _flat(name: str, params: Term) -> dict[str, float]:
    eff = effect(name)
    return dict(zip((f"{name}.{f}" for f in eff.fields()), eff.to_vector(params), strict=True))


class FitError(ValueError):
    """A least-squares fit that failed (non-finite residuals, a singular problem); the caller
    adds the log's name (``cli.diagnose``)."""


def fit(problem: Problem, effects: tuple[str, ...], index: np.ndarray | None = None,
        start: Mapping[str, Term] | None = None, budget: int = 60) -> Fit:
    """Fit ``effects`` on the segments at ``index`` (all by default).

    Starting values: ``start``'s, else each effect's data-driven guesses (``Effect.start``),
    else its bounds' starts. When the guesses give several starting points, short trial fits
    (``TRIAL_BUDGET``) pick the one the full fit is refined from.

    Parameters
    ----------
    problem : Problem
    effects : tuple of str
        Effect ids; an empty tuple gives the nominal model (nothing to fit).
    index : ndarray of int, optional
        Training segments.
    start : dict, optional
        ``{effect id: parameters}`` to start from (overrides the guesses of those effects).
    budget : int
        Function evaluations allowed per parameter.
    """
    seg = problem.seg if index is None else problem.seg.take(index)
    specs = layout(effects, seg)
    names = [n for n, _ in specs]
    mask = seg.gt_ok
    if not specs:
        res = problem.residuals(effects, {}, seg)[mask]
        return Fit(effects, [], np.zeros(0), np.zeros((0, 0)),
                   float(np.sqrt(np.mean(res**2))), len(seg))
    init: dict[str, float] = {}
    for name, params in (start or {}).items():
        init.update(_flat(name, params))
    bound = dict(specs)
    defaults = unpack(effects, [init.get(n, bound[n].start) for n in names])
    ctx = StartContext(seg, defaults,
                       lambda model: problem.residuals(effects, model, seg)[mask].ravel())
    starts = [init]
    for name in effects:
        eff = effect(name)
        if eff.start is None or all(f"{name}.{f}" in init for f in eff.fields()):
            continue
        guesses = [_flat(name, g) for g in eff.start(ctx)]
        if guesses:
            starts = [{**g, **s} for s in starts for g in guesses]
    lo = np.array([b.lower for _, b in specs])
    hi = np.array([b.upper for _, b in specs])
    scale = np.array([b.scale for _, b in specs])
    # layout fields (``Effect.fixed``): set by the start, never moved by the optimiser
    fixed = {f"{name}.{f}" for name in effects for f in effect(name).fixed}
    # a degree of freedom another fitted effect already carries: held at its start
    held = {f"{name}.{f}" for name in effects for f in effect(name).held(effects)}
    free = np.array([n not in fixed and n not in held for n in names])

    def solve(values: dict[str, float], evals: int):
        full = np.clip([bound[n].start if n in held else values.get(n, bound[n].start)
                        for n in names], lo + 1e-12 * np.abs(lo), hi - 1e-12 * np.abs(hi))

        def fun(xf: np.ndarray) -> np.ndarray:
            x = full.copy()
            x[free] = xf
            return problem.residuals(effects, unpack(effects, x), seg)[mask].ravel()

        try:
            sol = least_squares(fun, full[free], bounds=(lo[free], hi[free]),
                                x_scale=scale[free], method="trf", xtol=1e-8, ftol=1e-8,
                                max_nfev=evals * int(free.sum()))
        except (ValueError, np.linalg.LinAlgError, FloatingPointError) as exc:
            raise FitError(f"the least-squares fit of {'+'.join(effects)} failed: "
                           f"{type(exc).__name__}: {exc}") from exc
        x = full.copy()
        x[free] = sol.x
        jac = np.zeros((sol.jac.shape[0], len(names)))
        jac[:, free] = sol.jac
        return x, jac, sol.fun

    if len(starts) > 1:
        trials = [solve(s, TRIAL_BUDGET) for s in starts]
        best = min(trials, key=lambda sol: float(np.mean(sol[2]**2)))
        starts = [dict(zip(names, best[0].tolist(), strict=True))]
    x, jac, res = solve(starts[0], budget)
    cov = _cluster_covariance(problem, effects, seg, x, jac)
    return Fit(effects, names, x, cov, float(np.sqrt(np.mean(res**2))), len(seg))


def _cluster_covariance(problem: Problem, effects, seg: Segments, x, jac) -> np.ndarray:
    """Cluster-robust covariance (one cluster per segment), floored by the classical one."""
    res = problem.residuals(effects, unpack(effects, x), seg)
    k = res.shape[-1]
    cluster = np.repeat(np.nonzero(seg.gt_ok)[0], k)
    r = res[seg.gt_ok].ravel()
    p = max(int(np.sum(np.any(jac != 0, axis=0))), 1)  # parameters the data move
    a = jac.T @ jac
    a_inv = np.linalg.pinv(a)
    g = len(seg)
    scores = np.zeros((g, jac.shape[1]))
    np.add.at(scores, cluster, jac * r[:, None])
    meat = scores.T @ scores
    robust = a_inv @ meat @ a_inv * (g / max(g - p, 1))
    classical = a_inv * float(r @ r) / max(len(r) - p, 1)
    if g <= p:  # fewer clusters than parameters (a few whole paths): the robust estimate is
        return classical  # singular; the caller floors it by what the paths' spread shows
    # keep the robust correlations, floor each standard error at the classical one
    ratio = np.diag(classical) / np.maximum(np.diag(robust), 1e-300)
    d = np.sqrt(np.maximum(ratio, 1.0))
    return robust * d[:, None] * d[None, :]
