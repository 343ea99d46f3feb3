"""Naming the cause: held-out comparison of the fitted effects, and a significance test.

Every applicable effect is fitted by K-fold cross-validation over the segments (fold = segment
index mod K, so every fold spans the whole log; with several logs, fold = log index mod K, so
a run is predicted only by models fitted on other runs). Each segment thus gets a held-out
error from a model that never saw it, next to the nominal model's error on the same segment.

An effect is *significant* when all three hold:

- a paired one-sided sign-flip test of the per-segment falls of the held-out RMS error
  gives p < ``ALPHA`` (the extension wins consistently, not on one segment; ``compare``);
- the held-out mean squared error falls by at least ``MIN_GAIN`` (relative to the noise);
- the fall is *material*: the held-out RMS error shrinks by at least ``MIN_DRIFT`` of the
  distance a segment covers (pose channel; an RMS error e over a segment of length L is a drift
  of about √3 e / L at its end), or the gyro heading drift by ``MIN_GYRO_DRIFT_RAD_S``. Real
  vehicles, and a physics engine, always hold some unmodelled slip: tread compliance uphill,
  tyre scrub in turns. Drifts below half a percent of the distance are below what odometry
  calibration resolves and do not count as a cause.

**Long-horizon route** (``horizon.py``, when ``select`` is given the logs): a slow drift
(a 1 % track-width error on one log of a few minutes) is invisible over a few seconds, so the
same three tests are also made on held-out blocks in time replayed whole (p: held-out score
tests over blocks and along the whitened run; gain and drift: one half of the log replayed
whole by a model fitted on the other half). An effect is significant when it passes on
either route; which route is reported per candidate (``long_horizon`` in the JSON).

On a log the nominal model explains, an extension fitted on other segments predicts held-out
segments slightly *worse* (it fitted noise), so the tests fail and the answer is ``none``.
Among significant effects the cause is the one with the lowest held-out error, except that a
candidate with fewer parameters that ties with the best (not significantly worse and its
error within ``TIE_RATIO`` of the best's; or, when the best refines its mechanism, within
``TIE_GAIN`` of the nominal model's error: two fits of one mechanism that both remove nearly
all of it tie) is preferred: parsimony, so that a track-width change is not called turning
slip, nor one torque-slip law a soil map. Further
effects are added one at a time ("also", forward selection over every testable effect that
helps alone on either route) while the joint model passes the same three tests against the
current one, except that a calibration effect (wheel radii, track
width: ``Effect.calibration``) need not be material on its own once a cause is named, and a
local effect (``Effect.local``: soil under part of the route) is added on the short route
only; the joint model is then fitted on all segments, its parameters reported with their
joint covariance.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats
from tqdm import tqdm

from slipenv.diagnose import horizon, replay
from slipenv.diagnose.effects import EFFECTS, effect
from slipenv.diagnose.fit import Fit, Problem, param_count
from slipenv.diagnose.numbers import implausible_geometry
from slipenv.diagnose.segments import Segments, log_arrays
from slipenv.diagnose.workers import INLINE, Workers

ALPHA = 0.01  # one-sided p-value an effect must beat
MIN_GAIN = 0.2  # relative fall of the held-out mean squared error an effect must reach
MIN_DRIFT = 0.005  # [-] material drift: RMS fall × √3 / segment travel
MIN_GYRO_DRIFT_RAD_S = 1e-3  # [rad/s] material gyro heading drift: RMS fall × √3 / duration
TIE_RATIO = 1.25  # a simpler effect within this error ratio of the best and not worse wins
TIE_GAIN = 0.01  # ... or, the best refining its mechanism, within this of the nominal error
# ... or a richer geometric model material against the simpler one, by this many times what
# it leaves (radii the width missed: 23 times; width and radii imitating turning slip: 3.4)
TIMES_LEFT = 4.0
N_FOLDS = 6
MIN_SEGMENTS = 4
GEOMETRIC_SETS = (("track_width",), ("track_width", "rolling_radius"))
"""The geometric models the transfer route compares: the width alone, the width and radii."""

Routes = tuple[horizon.Horizons, horizon.Horizons | None]
"""The long route's held-out blocks, and the two halves of a single log (or None)."""
LongReference = tuple[horizon.Replays, horizon.Replays | None]
"""A reference model's replays of the blocks and of the halves (None without halves)."""
LongFits = tuple[list, list | None]
"""Submitted fold fits of the blocks and of the halves."""


def _no_segments() -> np.ndarray:
    return np.zeros(0)


@dataclass
class Candidate:
    """One effect (or set of effects) compared on held-out segments.

    ``errors`` are held-out mean squared residuals per segment; ``pred`` the held-out
    predictions (pose: x, y, yaw of shape (S, L, 3); gyro: yaw of shape (S, L)); both empty
    for an untestable candidate.
    """

    effects: tuple[str, ...]
    channel: str
    n_params: int = 0
    errors: np.ndarray = field(default_factory=_no_segments)
    pred: np.ndarray = field(default_factory=_no_segments)
    gain_relative: float = 0.0
    error_ratio: float = 1.0
    p_value: float = 1.0
    drift: float = 0.0
    material: bool = False
    significant: bool = False
    untestable: str | None = None
    fold_fits: list[Fit] = field(default_factory=list)
    short_significant: bool = False
    long: horizon.LongScore | None = None
    long_significant: bool = False
    long_half: horizon.Replays | None = None

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
    horizons: horizon.Horizons | None = None
    halves: horizon.Horizons | None = None
    long_baseline: dict[str, LongReference] = field(default_factory=dict)
    transfer: dict = field(default_factory=dict)


def make_folds(seg: Segments) -> np.ndarray:
    """Fold of each segment: by log when there are several logs, else interleaved."""
    n = len(seg)
    if n < MIN_SEGMENTS:
        raise ValueError(f"only {n} segment(s) with ground truth: the held-out comparison "
                         f"needs at least {MIN_SEGMENTS} (a longer log, or denser ground truth)")
    n_logs = int(seg.log_index.max()) + 1
    if n_logs >= 2:
        return seg.log_index % min(N_FOLDS, n_logs)
    return np.arange(n) % min(N_FOLDS, n)


def submit_folds(workers: Workers, problem: Problem, effects: tuple[str, ...],
                 folds: np.ndarray, starts: list[dict] | None = None) -> list:
    """The fold fits :func:`cross_validate` needs, submitted to ``workers`` (none for no
    effect)."""
    if not effects:
        return []
    return [workers.fit(problem, effects, np.flatnonzero(folds != k),
                        starts[i] if starts else None)
            for i, k in enumerate(np.unique(folds))]


def cross_validate(problem: Problem, effects: tuple[str, ...], folds: np.ndarray,
                   channel: str | None = None, starts: list[dict] | None = None,
                   fits: list | None = None) -> Candidate:
    """Held-out errors and predictions of ``effects`` (refitted with each fold left out;
    ``starts``: per fold, fitted values to start from, e.g. the named cause's when an effect
    is added to it; ``fits``: those fits as :func:`submit_folds` gave them, else run here)."""
    seg = problem.seg
    chan = channel or problem.channel(effects)
    cand = Candidate(effects, chan, param_count(effects))
    if fits is None:
        fits = submit_folds(INLINE, problem, effects, folds, starts)
    errors = np.zeros(len(seg))
    pred = np.zeros(seg.gt.shape if chan == "pose" else seg.gt.shape[:2])
    for i, k in enumerate(np.unique(folds)):
        test = np.flatnonzero(folds == k)
        p: replay.Model = {}
        if effects:
            f = fits[i].result()
            cand.fold_fits.append(f)
            p = f.params
        part = seg.take(test)
        errors[test] = problem.segment_errors(effects, p, part, chan)
        pred[test] = (replay.simulate(part, p) if chan == "pose"
                      else replay.simulate_gyro_heading(part, p))
    cand.errors, cand.pred = errors, pred
    if cand.fold_fits:  # the most any fold's fit uses (a map's shapes vary by fold)
        cand.n_params = max(param_count(effects, f.params) for f in cand.fold_fits)
    return cand


def compare(reference: np.ndarray, errors: np.ndarray) -> tuple[float, float]:
    """(relative fall of the summed error, one-sided p) of ``errors`` against ``reference``.

    The p-value is that of a paired sign-flip (randomisation) test of the per-segment falls
    of the RMS error, d_j = √ref_j - √err_j: under "no gain" each d_j is as likely negative
    as positive, so p = P(Σ ±d_j >= Σ d_j) over random signs (20 000 fixed-seed draws; the
    normal approximation Σd/√Σd² beyond 64 segments). Segments the extension leaves exactly
    unchanged (outside a soil patch) carry no information and are left out. Unlike a rank
    test it weighs the few segments where a local effect shows by how much they gain.
    """
    gain = 1.0 - float(errors.sum()) / max(float(reference.sum()), 1e-300)
    d = np.sqrt(np.maximum(reference, 0.0)) - np.sqrt(np.maximum(errors, 0.0))
    d = d[d != 0.0]
    if d.size == 0:
        return gain, 1.0
    total = float(d.sum())
    if d.size > 64:
        return gain, float(stats.norm.sf(total / np.sqrt(float(np.sum(d * d)))))
    rng = np.random.default_rng(0)
    hits = 0
    for _ in range(10):
        signs = rng.choice((-1.0, 1.0), size=(2000, d.size))
        hits += int(np.sum(signs @ d >= total - 1e-15 * abs(total)))
    return gain, (1 + hits) / 20001


def _judge(problem: Problem, cand: Candidate, reference: np.ndarray,
           increment: bool = False) -> None:
    cand.gain_relative, cand.p_value = compare(reference, cand.errors)
    cand.error_ratio = float(cand.errors.sum()) / max(float(reference.sum()), 1e-300)
    fall = np.sqrt(3.0) * (np.sqrt(reference.mean()) - np.sqrt(cand.errors.mean()))
    if cand.channel == "gyro":
        seg = problem.seg
        duration = float(np.median(seg.t[:, -1] - seg.t[:, 0]))
        cand.drift = fall / problem.heading_scale_m / max(duration, 1e-9)
        cand.material = cand.drift >= MIN_GYRO_DRIFT_RAD_S
    else:
        cand.drift = fall / problem.travel_m
        cand.material = cand.drift >= MIN_DRIFT
    cand.short_significant = (cand.p_value < ALPHA and cand.gain_relative >= MIN_GAIN
                              and (cand.material or increment))
    cand.significant = cand.short_significant or _long_counts(cand)


def _submit_long(workers: Workers, problem: Problem, hz: Routes, effects: tuple[str, ...],
                 warm: tuple[Candidate, ...] = ()) -> LongFits:
    """The fold fits :func:`_judge_long` needs for ``effects`` (blocks, halves), submitted."""
    blocks, halves = hz
    return (horizon.submit(workers, problem, blocks, effects,
                           _merged([_long(c).replays.models for c in warm])),
            None if halves is None else
            horizon.submit(workers, problem, halves, effects,
                           _merged([_long_half(c).models for c in warm])))


def _long(cand: Candidate) -> horizon.LongScore:
    """The long-route score of a candidate judged there."""
    if cand.long is None:
        raise ValueError(f"{cand.name} was not judged on the long route")
    return cand.long


def _long_half(cand: Candidate) -> horizon.Replays:
    """The replays of the halves of a candidate judged on them."""
    if cand.long_half is None:
        raise ValueError(f"{cand.name} was not replayed on the halves of the log")
    return cand.long_half


def _judge_long(problem: Problem, hz: Routes | None, cand: Candidate,
                reference: LongReference | None,
                increment: bool = False, warm: tuple[Candidate, ...] = (),
                pending: LongFits | None = None, workers: Workers = INLINE) -> None:
    """The long-horizon route (``horizon.py``): the same three tests on the held-out blocks
    replayed at horizons up to the whole block (``hz``: the blocks, and the two halves of a
    single log for the gain and drift; ``reference``: their replays by the reference).
    ``increment``: materiality not required (``cand`` adds a calibration effect to a named
    cause); ``warm``: the candidates ``cand`` joins (its fits start from theirs, fold by
    fold: the named cause's and the added effect's fitted alone); ``pending``: its fits as
    :func:`_submit_long` gave them, else submitted to ``workers`` here.
    The candidate's held-out replays do not depend on the reference: judged again (an added
    cause, then against the nominal model), it reuses them."""
    if hz is None or reference is None:
        return
    blocks, halves = hz
    if cand.long is None:
        fits, half_fits = pending or _submit_long(workers, problem, hz, cand.effects, warm)
        replays = horizon.held_out(problem, blocks, cand.effects, cand.channel, fits=fits)
        cand.long_half = (None if halves is None else
                          horizon.held_out(problem, halves, cand.effects, cand.channel,
                                           fits=half_fits))
    else:
        replays = cand.long.replays
    half = None
    if halves is not None:
        if reference[1] is None:
            raise ValueError("the reference was not replayed on the halves of the log")
        half = (_long_half(cand), reference[1], halves)
    cand.long = horizon.judge(problem, blocks, replays, reference[0], cand.channel, half)
    material = MIN_GYRO_DRIFT_RAD_S if cand.channel == "gyro" else MIN_DRIFT
    drift = max(cand.long.drift, cand.long.turn_drift)
    cand.long_significant = (cand.long.p_value < ALPHA and cand.long.gain_relative >= MIN_GAIN
                             and (drift >= material or increment))
    cand.significant = cand.short_significant or _long_counts(cand)


def _long_counts(cand: Candidate) -> bool:
    """Whether a pass on the long route names ``cand``: not when its held-out short segments
    are materially worse than the reference's (a drift of ``MIN_DRIFT`` added, or
    ``MIN_GYRO_DRIFT_RAD_S``). A model that makes held-out data worse is never named; a slow
    drift the segments cannot see leaves them about as they were, while a soil map fitted on
    other blocks of a sweep, each its own ground, is a guess on the segments it never saw."""
    material = MIN_GYRO_DRIFT_RAD_S if cand.channel == "gyro" else MIN_DRIFT
    return cand.long_significant and cand.drift > -material


def _merged(per_source: list[list[dict]]) -> list[dict] | None:
    """Per fold, the union of the sources' fitted models (starting values of a joint fit)."""
    if not per_source:
        return None
    return [{k: v for models in fold for k, v in models.items()}
            for fold in zip(*per_source, strict=True)]


def _long_ratio(cand: Candidate, base: LongReference) -> float:
    """Horizon-averaged held-out error over the nominal model's (long route, blocks)."""
    return float(np.mean(_long(cand).errors.sum(axis=0)
                         / np.maximum(base[0].errors.sum(axis=0), 1e-300)))


def _same_mechanism(name: str, chosen: tuple[str, ...]) -> bool:
    """True if ``name`` shares its mechanism with a chosen effect (never fitted together)."""
    mechanism = effect(name).mechanism
    return mechanism is not None and any(effect(c).mechanism == mechanism for c in chosen)


def _nests(best: tuple[str, ...], simpler: tuple[str, ...]) -> bool:
    """Whether the best candidate refines the simpler one's mechanism (``Effect.mechanism``:
    a soil map's regions each hold a torque-slip law, so one law is a map of one region)."""
    return any(_same_mechanism(e, best) for e in simpler)


def _ties(effects: tuple[str, ...], best_effects: tuple[str, ...], cand_error: float,
          best_error: float, nominal_error: float, p_worse: float) -> bool:
    """Whether a simpler candidate (``effects``) ties with the best: not significantly worse
    (``p_worse``) and its error within ``TIE_RATIO`` of the best's; or, when the best refines
    the same mechanism (:func:`_nests`), within ``TIE_GAIN`` of the nominal model's error of
    it. A map of more regions fits a little better everywhere, so its consistent edge is
    significant however small: judged on the nominal scale, two fits of one mechanism that
    both remove nearly all of the nominal error tie, whatever the ratio of their residuals.
    Between mechanisms the ratio and the test decide (a turning slip is not a wheel radius
    because both leave little)."""
    return ((p_worse >= ALPHA and cand_error <= TIE_RATIO * best_error)
            or (_nests(best_effects, effects)
                and cand_error - best_error <= TIE_GAIN * nominal_error))


def _pick(significant: list[Candidate], reference: np.ndarray) -> Candidate:
    """Lowest held-out error, unless a simpler candidate ties with it (:func:`_ties`;
    ``reference``: the nominal model's held-out errors).

    "Simpler": fewer parameters, then earlier in the vocabulary's order (``Effect.rank``:
    geometry before slip laws, the order of ``log-format.md``).
    """
    best = min(significant, key=lambda c: c.errors.sum())
    order = list(EFFECTS)
    nominal = float(reference.sum())
    for cand in sorted(significant, key=lambda c: (c.n_params, order.index(c.effects[0]))):
        if cand is best:
            return best
        _, p_worse = compare(cand.errors, best.errors)
        if _ties(cand.effects, best.effects, float(cand.errors.sum()),
                 float(best.errors.sum()), nominal, p_worse):
            return cand
    return best


def _pick_long(significant: list[Candidate], base: LongReference) -> Candidate:
    """As :func:`_pick`, on the long-horizon scores (fold-level t-test for "not worse"; the
    scores are already ratios to the nominal model's)."""
    best = min(significant, key=lambda c: _long_ratio(c, base))
    order = list(EFFECTS)
    for cand in sorted(significant, key=lambda c: (c.n_params, order.index(c.effects[0]))):
        if cand is best:
            return best
        worse = horizon.judge_pair(_long(cand).errors, _long(best).errors)
        if _ties(cand.effects, best.effects, _long_ratio(cand, base), _long_ratio(best, base),
                 1.0, worse):
            return cand
    return best


def _choose(sig: list[Candidate], reference: np.ndarray,
            long_base: LongReference | None) -> Candidate:
    """The short-segment pick when some effect passes there, else the long-horizon pick
    (``reference``: the nominal model's held-out errors on the short segments)."""
    short = [c for c in sig if c.short_significant]
    return (_pick(short, reference) if short or long_base is None
            else _pick_long(sig, long_base))


def _step(problem: Problem, hz: Routes | None, folds: np.ndarray,
          candidates: list[Candidate], current: Candidate, rest: list[str],
          reference: np.ndarray, long_base: LongReference | None, workers: Workers
          ) -> Candidate | None:
    """One forward-selection step: ``current`` joined by each of ``rest`` in turn; the pick
    among the joints that pass against ``current`` (None if none does; ``reference``: the
    nominal model's held-out errors, the scale of the pick's ties)."""
    alone = {name: next(c for c in candidates if c.effects == (name,)) for name in rest}
    # each part starts from its own fit, fold by fold: the named cause's, and the added
    # effect's fitted alone (no second search for its start, e.g. a patch)
    submitted = {name: submit_folds(workers, problem, (*current.effects, name), folds,
                                    _merged([[f.params for f in current.fold_fits],
                                             [f.params for f in alone[name].fold_fits]]))
                 for name in rest}
    joints = {}
    for name in rest:
        joints[name] = cross_validate(problem, (*current.effects, name), folds,
                                      fits=submitted[name])
        _judge(problem, joints[name], current.errors, increment=effect(name).calibration)
    # the long route only where needed (cost), and not for a local effect (``Effect.local``:
    # it shows on the short segments that cross it)
    warm = {name: (current, alone[name]) if alone[name].long is not None else ()
            for name in rest}
    longs = {name: _submit_long(workers, problem, hz, joints[name].effects, warm[name])
             for name in rest if hz is not None and current.long is not None
             and not joints[name].short_significant and not effect(name).local}
    trials = []
    for name in rest:
        if name in longs:
            _judge_long(problem, hz, joints[name], (_long(current).replays, current.long_half),
                        increment=effect(name).calibration, warm=warm[name],
                        pending=longs[name])
        if joints[name].significant:
            trials.append(joints[name])
    return _choose(trials, reference, long_base) if trials else None


def select(problem: Problem, progress: bool = False, logs: list | None = None,
           jobs: int = 1) -> Selection:
    """Compare every applicable effect on held-out segments and name the cause.

    With ``logs`` (those ``problem`` was cut from), every effect is also compared on
    held-out blocks replayed at long horizons (``horizon.py``); an effect counts when it
    passes the tests on either route. ``jobs``: processes the fits run on (``workers.py``;
    the outcome does not depend on it).
    """
    with Workers(jobs) as workers:
        return _select(problem, progress, logs, workers)


def _select(problem: Problem, progress: bool, logs: list | None, workers: Workers
            ) -> Selection:
    seg = problem.seg
    folds = make_folds(seg)
    channels = ["pose"] + (["gyro"] if seg.gyro is not None else [])
    baseline = {ch: cross_validate(problem, (), folds, ch) for ch in channels}
    hz: Routes | None = None
    if logs:
        arrays = [log_arrays(log) for log in logs]
        blocks = horizon.build(problem, arrays, logs, N_FOLDS)
        halves = (horizon.build(problem, arrays, logs, N_FOLDS, 2, 2)
                  if len(logs) < horizon.MIN_BLOCKS else None)
        hz = None if blocks is None else (blocks, halves)
    long_base = ({ch: (horizon.held_out(problem, hz[0], (), ch),
                       None if hz[1] is None else horizon.held_out(problem, hz[1], (), ch))
                  for ch in channels} if hz is not None else {})
    names = list(EFFECTS)
    why = {name: effect(name).applicable(seg) for name in names}
    # every fit of every testable effect submitted at once, collected in order below
    pending = {name: (submit_folds(workers, problem, (name,), folds),
                      _submit_long(workers, problem, hz, (name,))
                      if hz is not None and effect(name).channel in long_base else None)
               for name in names if why[name] is None}
    candidates: list[Candidate] = []
    for name in tqdm(names, desc="fitting effects", unit="effect", disable=not progress):
        if why[name] is not None:
            candidates.append(Candidate((name,), effect(name).channel, untestable=why[name]))
            continue
        fold_fits, long_fits = pending.pop(name)
        cand = cross_validate(problem, (name,), folds, fits=fold_fits)
        _judge_long(problem, hz, cand, long_base.get(cand.channel), pending=long_fits)
        _judge(problem, cand, baseline[cand.channel].errors)
        candidates.append(cand)
    final: dict[str, Candidate] = {}
    for ch in channels:
        sig = [c for c in candidates if c.channel == ch and c.significant]
        if not sig:
            continue
        current = _choose(sig, baseline[ch].errors, long_base.get(ch))
        # forward selection over every testable effect that helps alone on either route (an
        # effect masked by the cause, not significant alone, may pass once the cause is in)
        rest = [c.effects[0] for c in candidates if c.channel == ch and not c.untestable
                and (c.gain_relative > 0 or (c.long is not None and c.long.gain_relative > 0))]
        rest = [r for r in rest if r not in current.effects
                and not _same_mechanism(r, current.effects)]
        while rest:
            best = _step(problem, hz, folds, candidates, current, rest,
                         baseline[ch].errors, long_base.get(ch), workers)
            if best is None:
                break
            current = best
            _judge_long(problem, hz, current, long_base.get(ch), workers=workers)
            _judge(problem, current, baseline[ch].errors)
            rest = [r for r in rest if r not in current.effects
                    and not _same_mechanism(r, current.effects)]
        final[ch] = current
    transfer_info: dict = {}
    whole_fit = None
    if logs and "pose" in channels:
        whole_fit, transfer_info = _transfer_route(problem, logs, final, folds,
                                                   baseline["pose"], why)
    order = sorted(final.values(), key=lambda c: -c.gain_relative)
    chosen = [e for c in order for e in c.effects]
    submitted = {ch: workers.fit(problem, c.effects) for ch, c in final.items()
                 if not (ch == "pose" and whole_fit is not None)}
    fits = {ch: f.result() for ch, f in submitted.items()}
    if whole_fit is not None:
        fits["pose"] = whole_fit
    ranked = sorted(candidates, key=lambda c: (c.untestable is not None,
                                               c.effects[0] not in chosen[:1],
                                               not c.significant, c.error_ratio))
    return Selection(cause=chosen[0] if chosen else "none", also=chosen[1:],
                     candidates=ranked, baseline=baseline, final=final, fits=fits, folds=folds,
                     horizons=None if hz is None else hz[0],
                     halves=None if hz is None else hz[1], long_baseline=long_base,
                     transfer=transfer_info)


def _geometric_order(effects: tuple[str, ...], first: tuple[str, ...]) -> tuple[str, ...]:
    """``effects`` with those of ``first`` (the cause already named) leading."""
    return tuple(sorted(effects, key=lambda e: (e not in first, e != "track_width")))


def _transfer_route(problem: Problem, logs: list, final: dict[str, Candidate],
                    folds: np.ndarray, baseline: Candidate, why: dict
                    ) -> tuple[Fit | None, dict]:
    """Transfer as the test of the pose channel's model (``horizon.transfer``).

    The geometric models (``GEOMETRIC_SETS``, and the named cause's when it is geometric)
    are fitted on the whole dead-reckoned paths of some parts of the logs (runs, or halves)
    and replayed whole over the held-out part. Among those whose transfer is material
    (``Transfer.passes``) the simplest is kept, and a larger set only when its held-out
    path error is lower by more than the held-out uncertainty (:func:`_richest_that_wins`;
    on parts the fits did not see, so two runs cannot be overfitted, and without asking
    the extra parameters to be material on their own). Then:

    - nothing named on the pose channel: the geometric model is named;
    - a geometric cause named: replaced by the geometric model (fitted on the whole paths:
      a closed path determines the width only through its shape); dropped if it predicts the
      held-out parts worse (``Transfer.materially_worse``: in sum, or on half of them or more
      by a drift the gain rule would count as a fix) and no geometric model transfers;
    - another cause named (not a local one, which the short segments judge): tested the same
      way, and replaced by the geometric model when that transfers at least as well, or
      dropped when it predicts the held-out parts worse. A slip law that passed on the
      held-out segments, though, is judged as it is named, fitted on segments: it stays
      unless the geometric model also explains those segments (:func:`_explains`: not
      significantly worse there, and tied), and when its whole-path fits predict the
      held-out parts worse it is fitted on the segments outside each part and replayed
      whole over it, and dropped (for the geometric model, if one transfers) only if it
      makes them materially worse (:func:`_worse_transfer_decision`). So a model that makes
      held-out data worse is still never named: the test is made on the model that is.

    ``final`` is updated in place. Returns the pose model fitted on every run's whole path
    (None when the pose channel's model is left as it was) and what the route found, for the
    report.
    """
    current = final.get("pose")
    if current is not None and any(effect(e).local for e in current.effects):
        return None, {}
    made = horizon.whole_parts(logs)
    if made is None:
        return None, {}
    parts, by = made
    sets: list[tuple[str, ...]] = [s for s in GEOMETRIC_SETS if all(why.get(e) is None for e in s)]
    geometric_current = current is not None and all(effect(e).calibration
                                                    for e in current.effects)
    if (current is not None and geometric_current
            and tuple(sorted(current.effects)) not in {tuple(sorted(s)) for s in sets}):
        sets.append(current.effects)
    sets.sort(key=param_count)
    tested = [horizon.transfer(problem, parts, by, s) for s in sets]
    shown: set[str] = (set(current.effects) if geometric_current and current is not None
                       else set())
    if any(not set(t.effects) <= shown and not shown <= set(t.effects) for t in tested) \
            and not _separates(problem):
        shown = set()  # the segments could not tell the named geometry from the other either
    best, versus = _richest_that_wins(tested, shown)
    mine = None
    if current is not None:
        mine = next((t for t in tested if set(t.effects) == set(current.effects)), None)
        if mine is None:
            mine = horizon.transfer(problem, parts, by, current.effects)
    info = {"held_out_by": by, "parts": len(parts),
            "tested": [{**t.as_dict(MIN_DRIFT), "transfers": t.passes(MIN_GAIN, MIN_DRIFT)}
                       for t in tested],
            **({"versus": versus} if versus else {}),
            **({"named_cause": {**mine.as_dict(MIN_DRIFT),
                                "transfers": mine.passes(MIN_GAIN, MIN_DRIFT)}}
               if mine is not None else {})}
    # (mine is None only when nothing was named)
    replace = best is not None and (current is None or geometric_current or mine is None
                                    or not mine.passes(MIN_GAIN, MIN_DRIFT)
                                    or best.after.sum() <= mine.after.sum())
    slip_law = (current is not None and mine is not None and not geometric_current
                and current.short_significant)
    geometric = named = None
    if slip_law and replace and best is not None and current is not None:
        # a slip law the held-out segments found stays unless the geometric model explains
        # those segments too
        geometric = cross_validate(problem, _geometric_order(best.effects, ()), folds)
        _judge(problem, geometric, baseline.errors)
        replace = _explains(geometric, current, baseline.errors)
        info["geometric_on_segments"] = {"effects": list(geometric.effects),
                                         "error_ratio": geometric.error_ratio,
                                         "explains_the_cause": replace}
    if (slip_law and not replace and mine is not None and mine.materially_worse(MIN_DRIFT)
            and current is not None):
        # the named model is fitted on segments: held out the same way, it is the model that
        # must not make a held-out part worse (three slip parameters fitted on one half's
        # whole path alone are ill-determined)
        named = horizon.transfer(problem, parts, by, current.effects, on_segments=True)
        info["named_cause_on_segments"] = {
            **named.as_dict(MIN_DRIFT), "transfers": named.passes(MIN_GAIN, MIN_DRIFT)}
        # failing its own test, it gives way to a geometric model that transfers
        replace = (best is not None and geometric is not None
                   and _worse_transfer_decision(False, True, named) == "dropped")
    if replace and best is not None:
        effects = _geometric_order(best.effects, current.effects if current else ())
        cand = geometric if geometric is not None else cross_validate(problem, effects, folds)
        _judge(problem, cand, baseline.errors)
        cand.gain_relative = 1.0 - best.ratio
        final["pose"] = cand
        # the model of the folder: the one that best explains every run's whole path
        runs = horizon.whole_runs(logs)
        whole = horizon.fit_whole(problem, parts if runs is None else runs, best.effects)
        jack = best.jackknife_cov()
        # the whole-path fit's own covariance, its standard errors floored by the spread of
        # the leave-one-part-out fits (the uncertainty the transfer shows)
        d = np.sqrt(np.maximum(np.diag(jack) / np.maximum(np.diag(whole.cov), 1e-300), 1.0))
        whole.cov = whole.cov * d[:, None] * d[None, :]
        info.update(chosen=best.as_dict(MIN_DRIFT), decision=(
            "named by transfer" if current is None else
            "the named geometric model refitted on the whole paths"
            if geometric_current and set(best.effects) == set(current.effects) else
            f"{current.name} replaced by {'+'.join(best.effects)} fitted on the whole paths"
            if geometric_current else
            f"replaces {current.name}: the geometric model transfers "
            + ("as well or better" if mine is not None and mine.passes(MIN_GAIN, MIN_DRIFT) else
               f"and {current.name} does not")
            + (", and explains the held-out segments as well" if geometric is not None
               and named is None else "")
            + (f"; {current.name}, fitted on the segments outside each held-out part, makes "
               "them materially worse" if named is not None else "")))
        return whole, info
    if current is None:
        info["decision"] = "none transfers"
        return None, info
    if mine is None or not mine.materially_worse(MIN_DRIFT):
        info["decision"] = (f"{current.name} kept: the geometric model transfers but does not "
                            "explain the held-out segments as well" if geometric is not None
                            else "kept")
        return None, info
    if _worse_transfer_decision(geometric_current, current.short_significant,
                                named) == "kept":
        info["decision"] = (f"{current.name} kept: significant on held-out segments, and "
                            "fitted on the segments outside each held-out part it makes no "
                            "part materially worse (its whole-path fits do)")
        return None, info
    if _far_from_nominal(problem, current):
        # the log's meta.json, not the vehicle, is the likelier culprit: keep the cause so
        # the report warns, rather than answer none
        info["decision"] = (f"{current.name} kept though it predicts the held-out parts "
                            "worse: its fit is far from the nominal geometry (warned)")
        return None, info
    del final["pose"]
    info["decision"] = f"{'+'.join(mine.effects)} dropped: it predicts the held-out " \
        "parts worse"
    return None, info


def _separates(problem: Problem) -> bool:
    """Whether the held-out segments can tell the wheel-radius ratio from the track width:
    the calibration's variance inflation below ``calibration.MAX_VIF`` (not so on a circle
    driven one way, where both scale the turn alike)."""
    from slipenv.diagnose.calibration import MAX_VIF, variance_inflation

    return variance_inflation(problem) < MAX_VIF


def _richest_that_wins(tested: list[horizon.Transfer], named: set[str] | None = None
                       ) -> tuple[horizon.Transfer | None, list[dict]]:
    """The geometric model the transfer route keeps, and the comparisons that chose it.

    Only a model that transfers (``Transfer.passes``: material against the nominal model)
    can be kept. Among those, in order of parameter count, a richer one replaces the one
    kept so far when its held-out path error is lower by more than the held-out
    uncertainty (``horizon.richer_wins``): by ``TIE_GAIN`` of the nominal error, under which
    the short route ties two fits of one mechanism (how much the extra parameters change
    the distance or the turn is not asked: a 0.3 % radius that every held-out run confirms
    is kept), or, when the richer model is material against the simpler one (it changes
    the turn or the distance of the held-out parts by ``MIN_DRIFT``), by ``TIMES_LEFT``
    times what it leaves itself (``horizon.fall_floor``: a large turn error must not hide a
    distance scale the held-out halves both confirm); else the simpler stays.

    ``named``: the geometric cause the held-out segments named, on a log that separates
    the radius ratio from the width (:func:`_separates`). The sets nested in it come first,
    then the others: a set that is not nested in it (the width against the radii) is no
    simpler in the sense that matters, so it replaces the named cause only by beating it on
    the held-out paths; where the paths tie, the segments, which told them apart, decide."""
    tested = sorted(tested, key=lambda t: not set(t.effects) <= (named or set()))
    best, versus = None, []
    for t in tested:
        if not t.passes(MIN_GAIN, MIN_DRIFT):
            continue
        if best is None:
            best = t
            continue
        v = t.versus(best, TIE_GAIN, TIMES_LEFT, MIN_DRIFT)
        versus.append(v)
        if v["richer_wins"]:
            best = t
    return best, versus


def _explains(geometric: Candidate, cause: Candidate, reference: np.ndarray) -> bool:
    """Whether a geometric model explains the held-out segments a named slip law was found
    on: not significantly worse there, and tied with it as :func:`_pick` ties a simpler
    candidate with the best (``reference``: the nominal model's held-out errors)."""
    _, p_worse = compare(geometric.errors, cause.errors)
    return _ties(geometric.effects, cause.effects, float(geometric.errors.sum()),
                 float(cause.errors.sum()), float(reference.sum()), p_worse)


def _worse_transfer_decision(geometric: bool, short_significant: bool,
                             on_segments: horizon.Transfer | None) -> str:
    """What becomes of a named cause whose whole-path fits predict the held-out parts worse
    and that no geometric model replaces: ``"kept"`` or ``"dropped"``.

    A geometric cause is judged by its whole paths alone: they are what determine it. A slip
    law that passed on the held-out segments is kept when it also passes the rule that no
    model making held-out data worse is named, tested on the model as it is named: fitted on
    the segments outside each held-out part (``on_segments``), replayed whole over that part,
    no worse than the nominal model in sum, nor materially worse (``MIN_DRIFT``: what would
    not count as a fix does not count as harm) on half of the parts or more. A cause found
    on the long route alone has no such evidence and is dropped.
    """
    if geometric or not short_significant or on_segments is None:
        return "dropped"
    return "dropped" if on_segments.materially_worse(MIN_DRIFT) else "kept"


def _far_from_nominal(problem: Problem, cand: Candidate) -> bool:
    """Whether a candidate's fitted track width or radii are implausibly far from the log's
    nominal geometry (`numbers.implausible_geometry`, the report's warning)."""
    if not cand.fold_fits:
        return False
    nominal = {"wheel_radius_m": float(np.median(problem.seg.radius)),
               "track_width_m": float(np.median(problem.seg.track))}
    return bool(implausible_geometry(cand.fold_fits[0].report(problem.seg), nominal))
