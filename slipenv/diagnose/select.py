"""Naming the cause: held-out comparison of the fitted effects, and a significance test.

Every applicable effect is fitted by K-fold cross-validation over the segments (fold = segment
index mod K, so every fold spans the whole log; with several logs, fold = log index mod K, so
a run is predicted only by models fitted on other runs). Each segment thus gets a held-out
error from a model that never saw it, next to the nominal model's error on the same segment.

An effect is *significant* when both

- the paired one-sided Wilcoxon signed-rank test of (nominal - extended) held-out segment
  errors gives p < ``ALPHA`` (the extension wins on most segments, not on one), and
- the held-out mean squared error falls by at least ``MIN_GAIN`` (a material gain: a clean log
  still holds small unmodelled physics and noise, and a flexible extension fitted to them
  must not pass for a cause).

On a log the nominal model explains, an extension fitted on other segments predicts held-out
segments slightly *worse* (it fitted noise), so neither test passes and the answer is
``none``. Among significant effects the cause is the one with the lowest held-out error,
except that a candidate with fewer parameters that is not significantly worse (and within
``TIE_RATIO`` of the best) is preferred: parsimony, so that a track-width change is not
called turning slip. Further effects are added one at a time ("also") while the joint model
passes the same two tests against the current one.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats
from tqdm import tqdm

from slipenv.diagnose import replay
from slipenv.diagnose.effects import EFFECTS, effect
from slipenv.diagnose.fit import Fit, Problem, fit, param_specs

ALPHA = 1e-3  # one-sided Wilcoxon p-value an effect must beat
MIN_GAIN = 0.25  # relative fall of the held-out mean squared error an effect must reach
TIE_RATIO = 1.25  # a simpler effect within this error ratio of the best and not worse wins
N_FOLDS = 4
MIN_SEGMENTS = 4


@dataclass
class Candidate:
    """One effect (or set of effects) compared on held-out segments.

    ``errors`` are held-out mean squared residuals per segment; ``pred`` the held-out
    predictions (pose: x, y, yaw of shape (S, L, 3); gyro: yaw of shape (S, L)).
    """

    effects: tuple[str, ...]
    channel: str
    n_params: int = 0
    errors: np.ndarray | None = None
    pred: np.ndarray | None = None
    gain_relative: float = 0.0
    error_ratio: float = 1.0
    p_value: float = 1.0
    significant: bool = False
    untestable: str | None = None
    fold_fits: list[Fit] = field(default_factory=list)

    @property
    def name(self) -> str:
        return "+".join(self.effects) or "none"


@dataclass
class Selection:
    """The outcome of the comparison."""

    cause: str
    also: list[str]
    candidates: list[Candidate]
    baseline: dict[str, Candidate]
    final: dict[str, Candidate]
    fits: dict[str, Fit]
    folds: np.ndarray


def make_folds(seg: replay.Segments) -> np.ndarray:
    """Fold of each segment: by log when there are several logs, else interleaved."""
    n = len(seg)
    if n < MIN_SEGMENTS:
        raise ValueError(f"only {n} segment(s) with ground truth: the held-out comparison "
                         f"needs at least {MIN_SEGMENTS} (a longer log, or denser ground truth)")
    n_logs = int(seg.log_index.max()) + 1
    if n_logs >= 2:
        return seg.log_index % min(N_FOLDS, n_logs)
    return np.arange(n) % min(N_FOLDS, n)


def cross_validate(problem: Problem, effects: tuple[str, ...], folds: np.ndarray,
                   channel: str | None = None) -> Candidate:
    """Held-out errors and predictions of ``effects`` (refitted with each fold left out)."""
    seg = problem.seg
    chan = channel or problem.channel(effects)
    cand = Candidate(effects, chan, len(param_specs(effects, seg)))
    errors = np.zeros(len(seg))
    pred = np.zeros(seg.gt.shape if chan == "pose" else seg.gt.shape[:2])
    probe = effects or (("gyro_bias",) if chan == "gyro" else ())
    for k in np.unique(folds):
        test = np.flatnonzero(folds == k)
        p: dict[str, float] = {}
        if effects:
            f = fit(problem, effects, np.flatnonzero(folds != k))
            cand.fold_fits.append(f)
            p = f.params
        part = seg.take(test)
        errors[test] = problem.segment_errors(probe, p, part)
        pred[test] = (replay.simulate(part, p) if chan == "pose"
                      else replay.simulate_gyro_heading(part, p))
    cand.errors, cand.pred = errors, pred
    return cand


def compare(reference: np.ndarray, errors: np.ndarray) -> tuple[float, float]:
    """(relative fall of the summed error, one-sided Wilcoxon p) of ``errors`` vs reference."""
    gain = 1.0 - float(errors.sum()) / max(float(reference.sum()), 1e-300)
    diff = reference - errors
    if np.all(diff == 0):
        return gain, 1.0
    try:
        p = float(stats.wilcoxon(diff, alternative="greater").pvalue)
    except ValueError:
        p = 1.0
    return gain, p


def _judge(cand: Candidate, reference: np.ndarray) -> None:
    cand.gain_relative, cand.p_value = compare(reference, cand.errors)
    cand.error_ratio = float(cand.errors.sum()) / max(float(reference.sum()), 1e-300)
    cand.significant = cand.p_value < ALPHA and cand.gain_relative >= MIN_GAIN


def _pick(significant: list[Candidate]) -> Candidate:
    """Lowest held-out error, unless a simpler candidate is not significantly worse."""
    best = min(significant, key=lambda c: c.errors.sum())
    for cand in sorted(significant, key=lambda c: (c.n_params, c.errors.sum())):
        if cand is best:
            return best
        _, p_worse = compare(cand.errors, best.errors)
        if p_worse >= ALPHA and cand.errors.sum() <= TIE_RATIO * best.errors.sum():
            return cand
    return best


def select(problem: Problem, progress: bool = False) -> Selection:
    """Compare every applicable effect on held-out segments and name the cause."""
    seg = problem.seg
    folds = make_folds(seg)
    channels = ["pose"] + (["gyro"] if seg.gyro is not None else [])
    baseline = {ch: cross_validate(problem, (), folds, ch) for ch in channels}
    names = list(EFFECTS)
    candidates: list[Candidate] = []
    for name in tqdm(names, desc="fitting effects", unit="effect", disable=not progress):
        why = effect(name).applicable(seg)
        if why is not None:
            candidates.append(Candidate((name,), effect(name).channel, untestable=why))
            continue
        cand = cross_validate(problem, (name,), folds)
        _judge(cand, baseline[cand.channel].errors)
        candidates.append(cand)
    final: dict[str, Candidate] = {}
    for ch in channels:
        sig = [c for c in candidates if c.channel == ch and c.significant]
        if not sig:
            continue
        current = _pick(sig)
        rest = [c.effects[0] for c in sig if c.effects[0] not in current.effects]
        while rest:
            trials = []
            for name in rest:
                joint = cross_validate(problem, (*current.effects, name), folds)
                _judge(joint, current.errors)
                if joint.significant:
                    trials.append(joint)
            if not trials:
                break
            current = min(trials, key=lambda c: c.errors.sum())
            _judge(current, baseline[ch].errors)
            rest = [r for r in rest if r not in current.effects]
        final[ch] = current
    order = sorted(final.values(), key=lambda c: -c.gain_relative)
    chosen = [e for c in order for e in c.effects]
    fits = {ch: fit(problem, c.effects) for ch, c in final.items()}
    ranked = sorted(candidates, key=lambda c: (c.untestable is not None,
                                               c.effects[0] not in chosen[:1],
                                               not c.significant, c.error_ratio))
    return Selection(cause=chosen[0] if chosen else "none", also=chosen[1:],
                     candidates=ranked, baseline=baseline, final=final, fits=fits, folds=folds)
