"""Long-horizon held-out comparison: blocked cross-validation in time, horizons of many lengths.

The segment comparison of ``select.py`` re-anchors every few seconds on the ground truth, so a
slow drift (a 1 % track-width error turning a circle leaves 0.2° per 3 s segment) hides in the
noise of each segment, and its gain looks immaterial over a few seconds. Here:

- **Blocks.** A single log is cut into ``N_BLOCKS`` contiguous blocks in time (two logs:
  each into half as many; three or more: every log is a block, folds as in
  ``select.make_folds``). For every fold the effects are fitted on the other folds' blocks,
  each replayed whole (a slow drift is estimated from the horizon it shows on), and the
  held-out blocks are replayed at horizons of several lengths: the segment length, doubled
  until it reaches the block, and the whole block (from the logged pose at its start only).
- **Halves.** A single log is also cut in two (two logs: one per log): fit on one half
  replayed whole, replay the other half whole. The gain and the material drift are read
  there, on the longest horizon a single log offers: 1 - E/E⁰ of the held-out mean squared
  errors, RMS fall × √3 / distance covered as in ``select.py``, and for the heading also per
  angle turned (a 1 % track-width error is a 1 % error of every turn, whatever the distance
  between turns).
- **p.** Errors along one run are correlated (a replay's error integrates the noise), so
  samples of one replay are not independent evidence. Two held-out score tests, each
  asking whether the reference's residual r points along the correction c = r - r' the
  extension predicts (with no effect, c comes from a fit on other data and is independent of
  the noise in r): a sign-flip test over the blocks (:func:`judge`; exact, but a few turns
  give few informative blocks), and a test on the halves' residuals whitened along the run
  (:func:`whitened_score`: differenced, AR(1)-filtered, variance by batch means). The
  smaller p, doubled (Bonferroni), is the route's p.

``select.py`` applies its three tests (p < α, gain, material drift) to these numbers as a
second route: an effect counts when it passes on the short segments or here.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import stats

from slipenv.diagnose.fit import Problem
from slipenv.diagnose.segments import Segments, cut_spans
from slipenv.diagnose.workers import INLINE, Workers

N_BLOCKS = 10  # blocks in time of a single log (folds of the blocked cross-validation)
MIN_BLOCKS = 3  # folds needed for a t-test with at least two degrees of freedom
WHITEN_BATCH_S = 2.0  # [s] batches of the whitened score's variance


@dataclass
class Horizons:
    """Held-out blocks replayed at several horizons.

    Attributes
    ----------
    seg : list of Segments
        One per horizon, shortest first (the last is the whole blocks).
    fold : list of ndarray
        Fold of each segment of each horizon.
    block : list of ndarray
        Block of each segment of each horizon.
    lengths_s : list of float
        Horizon lengths [s].
    """

    seg: list[Segments]
    fold: list[np.ndarray]
    block: list[np.ndarray]
    lengths_s: list[float]

    @property
    def folds(self) -> np.ndarray:
        return np.unique(np.concatenate(self.fold))


@dataclass
class Replays:
    """Held-out replays of the blocks at every horizon by one model (fitted per fold)."""

    res: list[np.ndarray]  # per horizon: residuals (S_h, L_h, k), heading scaled by ℓ
    errors: np.ndarray  # (F, H) mean squared residual per fold and horizon
    models: list = field(default_factory=list)  # fitted model of each fold


@dataclass
class LongScore:
    """An effect (set) scored on the held-out blocks against a reference model."""

    replays: Replays
    gain_relative: float = 0.0
    p_value: float = 1.0  # sign-flip test of the block scores
    drift: float = 0.0
    turn_drift: float = 0.0  # heading RMS fall × √3 / angle turned [-] (pose channel)

    @property
    def errors(self) -> np.ndarray:
        return self.replays.errors


def _spans(t: np.ndarray, ok: np.ndarray, a: int, b: int, length_s: float | None) -> list:
    """Windows of ``length_s`` [s] tiling samples [a, b), each starting on ground truth; the
    whole range when ``length_s`` is None."""
    good = np.flatnonzero(ok[a:b]) + a
    if good.size < 2:
        return []
    if length_s is None:
        return [(int(good[0]), int(good[-1]) + 1)]
    out, i = [], int(good[0])
    while True:
        j = int(np.searchsorted(t, t[i] + length_s - 1e-9))
        if j >= b:
            break
        out.append((i, j + 1))
        nxt = good[good >= j]
        if nxt.size == 0:
            break
        i = int(nxt[0])
    return out


def blocks(arrays: list[dict], n_folds: int, n_blocks: int = N_BLOCKS
           ) -> list[tuple[int, int, int, int]]:
    """``(fold, log, start, stop)`` of the held-out blocks: one per log with fold = log index
    mod ``n_folds`` when there are at least ``MIN_BLOCKS`` logs; fewer logs (one run, or a
    clockwise and a counter-clockwise run) are each cut into ⌈``n_blocks`` / logs⌉ blocks in
    time, every block its own fold."""
    n_logs = len(arrays)
    if n_logs >= MIN_BLOCKS:
        k = min(n_folds, n_logs)
        return [(li % k, li, 0, len(arr["t"])) for li, arr in enumerate(arrays)]
    per = -(-n_blocks // n_logs)
    out = []
    for li, arr in enumerate(arrays):
        edges = np.linspace(0, len(arr["t"]), per + 1).round().astype(int)
        out += [(li * per + k, li, int(edges[k]), int(edges[k + 1])) for k in range(per)]
    return out


def build(problem: Problem, arrays: list[dict], logs: list, n_folds: int,
          n_blocks: int = N_BLOCKS, min_folds: int = MIN_BLOCKS) -> Horizons | None:
    """The horizons of ``problem``'s logs (their ``segments.log_arrays``); None when the logs
    allow no blocked test."""
    seg = problem.seg
    parts = blocks(arrays, n_folds, n_blocks)
    if len({f for f, *_ in parts}) < min_folds:
        return None
    base = float(np.median(seg.t[:, -1] - seg.t[:, 0]))
    block_s = min(float(arrays[li]["t"][b - 1] - arrays[li]["t"][a]) for _, li, a, b in parts)
    lengths: list[float | None] = []
    h = base
    while h < 0.75 * block_s:
        lengths.append(h)
        h *= 2.0
    lengths.append(None)
    out_seg, out_fold, out_block, out_len = [], [], [], []
    for length in lengths:
        spans, folds, ids = [], [], []
        for k, (f, li, a, b) in enumerate(parts):
            arr = arrays[li]
            for s, e in _spans(arr["t"], arr["gt_ok"], a, b, length):
                spans.append((li, s, e))
                folds.append(f)
                ids.append(k)
        cut = cut_spans(arrays, logs, spans)
        if cut is None or len(cut) != len(spans):
            return None
        out_seg.append(cut)
        out_fold.append(np.array(folds))
        out_block.append(np.array(ids))
        out_len.append(block_s if length is None else length)
    return Horizons(out_seg, out_fold, out_block, out_len)


def submit(workers: Workers, problem: Problem, hz: Horizons, effects: tuple[str, ...],
           starts: list[dict] | None = None) -> list:
    """The fold fits :func:`held_out` needs, submitted to ``workers`` (none for no effect)."""
    if not effects:
        return []
    # fitted on the other folds' blocks replayed whole: a slow drift is estimated from the
    # horizon it shows on, not from re-anchored pieces of it
    whole = hz.seg[-1]
    return [workers.fit(Problem(whole.take(np.flatnonzero(hz.fold[-1] != f)),
                                problem.heading_scale_m, problem.travel_m),
                        effects, None, starts[i] if starts else None)
            for i, f in enumerate(hz.folds)]


def held_out(problem: Problem, hz: Horizons, effects: tuple[str, ...],
             channel: str, starts: list[dict] | None = None, fits: list | None = None
             ) -> Replays:
    """Held-out replays of the blocks by ``effects``, fitted on each fold's training part
    (``starts``: per fold, fitted values to start from; ``fits``: those fits as
    :func:`submit` gave them, else run here)."""
    folds = hz.folds
    if fits is None:
        fits = submit(INLINE, problem, hz, effects, starts)
    res = [np.zeros(seg.gt.shape[:2] + ((1,) if channel == "gyro" else (3,)))
           for seg in hz.seg]
    errors = np.zeros((len(folds), len(hz.seg)))
    models = []
    for i, f in enumerate(folds):
        model = fits[i].result().params if effects else {}
        models.append(model)
        for h, (seg, fold) in enumerate(zip(hz.seg, hz.fold, strict=True)):
            idx = np.flatnonzero(fold == f)
            if idx.size:
                part = seg.take(idx)
                res[h][idx] = problem.residuals(effects, model, part, channel)
                count = np.maximum(part.gt_ok.sum(axis=1), 1)
                errors[i, h] = float(np.mean((res[h][idx] ** 2).sum(axis=(1, 2)) / count))
    return Replays(res, errors, models)


def judge(problem: Problem, hz: Horizons, cand: Replays, reference: Replays,
          channel: str, halves: tuple[Replays, Replays, Horizons] | None = None) -> LongScore:
    """Gain, p and material drift of ``cand`` against ``reference`` on the held-out blocks.

    Gain and drift are read on the whole-block horizon of ``halves`` (``cand`` and
    ``reference`` replayed on a log cut in two: fit on one half, replay the other whole),
    else of ``hz``: a slow drift is material over a long run, not over a tenth of it.

    p: per block b and horizon h the score a_bh = Σ over its spans of the mean r · c, with r
    the reference's residual and c = r - r' the correction the candidate predicts (a held-out
    score test: with no effect, c was fitted on other blocks and is independent of the noise
    in r, so a_bh is centred on 0; with it, r holds the drift c predicts). Each horizon is
    scaled by its root-mean-square score and summed, a_b = Σ_h a_bh / rms_b(a_bh), and the
    one-sided sign-flip test over the blocks (independent replays; exact for symmetric noise)
    gives p. Weighing by r · c instead of comparing squared errors keeps the power a weak
    drift would lose to the noise of two squared errors (2 r · c - |c|² is what they test).
    """
    score = LongScore(cand)
    n_blocks = int(max(b.max() for b in hz.block)) + 1
    total = np.zeros(n_blocks)
    for h, (seg, block) in enumerate(zip(hz.seg, hz.block, strict=True)):
        r, r1 = reference.res[h], cand.res[h]
        count = np.maximum(seg.gt_ok.sum(axis=1), 1)
        dot = np.sum(r * (r - r1), axis=(1, 2)) / count
        rr = np.sum(r * r, axis=(1, 2)) / count
        cc = np.sum((r - r1) ** 2, axis=(1, 2)) / count
        num = np.bincount(block, weights=dot, minlength=n_blocks)
        den = np.sqrt(np.bincount(block, weights=rr, minlength=n_blocks))
        a = np.divide(num, den, out=np.zeros(n_blocks), where=den > 0)
        size = float(np.sqrt(np.mean(np.bincount(block, weights=cc, minlength=n_blocks))))
        if size > 0:
            total += a / size
    score.p_value = sign_flip(total)
    if halves is not None:
        cand, reference, hz = halves
    # Bonferroni over the two tests of the same hypothesis
    score.p_value = min(1.0, 2.0 * min(score.p_value, whitened_score(hz, cand, reference)))
    e, e0 = cand.errors, reference.errors
    score.gain_relative = float(1.0 - e[:, -1].sum() / max(float(e0[:, -1].sum()), 1e-300))
    longest = hz.seg[-1]
    fall = np.sqrt(3.0) * (np.sqrt(e0[:, -1].mean()) - np.sqrt(e[:, -1].mean()))
    if channel == "gyro":  # heading drift rate [rad/s], as in select.py
        score.drift = float(fall / problem.heading_scale_m / max(hz.lengths_s[-1], 1e-9))
    else:
        travel = np.abs(longest.dphi * longest.radius[:, None, :]).mean(axis=-1).sum(axis=1)
        score.drift = float(fall / max(float(np.median(travel)), 1e-9))
        d = longest.radius[:, None, :] * longest.dphi
        left = d[..., longest.sides == 0].mean(axis=-1)
        right = d[..., longest.sides == 1].mean(axis=-1)
        turned = np.abs((right - left) / longest.track[:, None]).sum(axis=1)
        ok = longest.gt_ok
        yaw0 = reference.res[-1][..., 2][ok] / problem.heading_scale_m
        yaw1 = cand.res[-1][..., 2][ok] / problem.heading_scale_m
        turn_fall = np.sqrt(3.0) * (np.sqrt(np.mean(yaw0**2)) - np.sqrt(np.mean(yaw1**2)))
        score.turn_drift = float(turn_fall / max(float(np.median(turned)), 1e-9))
    return score


def sign_flip(values: np.ndarray) -> float:
    """One-sided p of a sign-flip test that ``values`` are centred above 0 (exact
    enumeration up to 16 values, else 20 000 fixed-seed draws)."""
    d = values[values != 0.0]
    if d.size == 0:
        return 1.0
    total = float(d.sum()) - 1e-12 * float(np.abs(d).sum())
    if d.size <= 16:
        signs = 1.0 - 2.0 * ((np.arange(2**d.size)[:, None] >> np.arange(d.size)) & 1)
        return float(np.mean(signs @ d >= total))
    rng = np.random.default_rng(0)
    signs = rng.choice((-1.0, 1.0), size=(20000, d.size))
    return float((1 + np.sum(signs @ d >= total)) / 20001)


def judge_pair(reference: np.ndarray, errors: np.ndarray) -> float:
    """One-sided p that ``errors`` (F, H) beat ``reference``: Student t on the per-fold mean
    log ratios D_f = (1/H) Σ_h ln(E⁰_fh / E_fh) (batch means, F - 1 degrees of freedom)."""
    d = np.log(np.maximum(reference, 1e-300) / np.maximum(errors, 1e-300)).mean(axis=1)
    if d.size < 2:
        return 1.0
    sd = float(np.std(d, ddof=1))
    if sd == 0:
        return 0.0 if d.mean() > 0 else 1.0
    return float(stats.t.sf(d.mean() / (sd / np.sqrt(d.size)), d.size - 1))



def whitened_score(hz: Horizons, cand: Replays, reference: Replays,
                   batch_s: float = WHITEN_BATCH_S) -> float:
    """One-sided p of the whitened held-out score test on the whole-block replays of ``hz``.

    A replay's error integrates the noise of every step, so along a run it is a random walk
    plus a few slow transients; differencing it sample to sample whitens the walk, and an
    AR(1) filter, ρ from the reference's differenced residual of each component, the rest.
    With u the whitened reference residual and v the whitened correction c = r - r' (the
    same filter), S = Σ u · v; with no effect u is noise independent of v (fitted on the other
    blocks) and S is centred on 0. Its variance is estimated by batch means over windows of
    ``batch_s`` [s] (robust to the noise being larger in turns than on straights, and to the
    short correlation the filter leaves); p = P(N(0, 1) > S / √V).
    """
    seg = hz.seg[-1]
    dt = float(np.median(seg.dt[seg.dt > 0]))
    width = max(2, int(round(batch_s / dt)))
    batches = []
    for j in range(len(seg)):
        ok = seg.gt_ok[j]
        r = reference.res[-1][j][ok]
        c = r - cand.res[-1][j][ok]
        if len(r) < 3:
            continue
        dr, dc = np.diff(r, axis=0), np.diff(c, axis=0)
        prev = np.sum(dr[1:] * dr[:-1], axis=0)
        rho = np.clip(prev / np.maximum(np.sum(dr * dr, axis=0), 1e-300), -0.95, 0.95)
        u = dr[1:] - rho * dr[:-1]
        v = dc[1:] - rho * dc[:-1]
        prod = np.sum(u * v, axis=1)
        n = prod.size // width
        if n:
            batches.extend(prod[:n * width].reshape(n, width).sum(axis=1).tolist())
        if prod.size % width:
            batches.append(float(prod[n * width:].sum()))
    b = np.array(batches)
    var = float(np.sum(b * b))
    if b.size < 2 or var <= 0:
        return 1.0
    return float(stats.norm.sf(b.sum() / np.sqrt(var)))


# --- Transfer: models fitted on whole paths, replayed whole over the held-out parts ----------

@dataclass
class Transfer:
    """A model fitted on the whole dead-reckoned paths of some parts of the logs and replayed
    whole over the held-out part, for every part in turn (leave-one-part-out).

    The parts are the runs of a folder, or the two halves of a single run: the same test for
    a session (what does the model of some runs do to the others?) and for one run (what
    does the model of one half do to the other?). Whole paths, not segments re-anchored every
    few seconds, because a slow turn-scale error shows only over the path, and a closed path
    (a square run ends where it began) determines the track width only through its shape.

    Attributes
    ----------
    effects : tuple of str
    by : str
        ``"run"`` or ``"half"``.
    before, after : ndarray
        (P,) mean squared pose residual (position and heading times ℓ) over each held-out
        part, nominal model and fitted model.
    pos_before, pos_after : ndarray
        (P,) position RMSE over each held-out part [m].
    yaw_before, yaw_after : ndarray
        (P,) heading RMSE over each held-out part [rad].
    end_before, end_after : ndarray
        (P,) position error at the end of each held-out part [m].
    models : list
        Model fitted with each part held out; ``xs`` their fitted vectors (P, n).
    travel_m, turned_rad : float
        Distance a part covers and angle it turns (medians) [m, rad].
    """

    effects: tuple[str, ...]
    by: str
    before: np.ndarray
    after: np.ndarray
    pos_before: np.ndarray
    pos_after: np.ndarray
    end_before: np.ndarray
    end_after: np.ndarray
    models: list
    xs: np.ndarray
    yaw_before: np.ndarray
    yaw_after: np.ndarray
    travel_m: float = 1.0
    turned_rad: float = 1.0
    scales: np.ndarray | None = None

    def _drifts(self, pos: np.ndarray, yaw: np.ndarray) -> tuple[float, float]:
        fall = np.sqrt(3.0) * (float(pos.mean()) - float(self.pos_after.mean()))
        turn_fall = np.sqrt(3.0) * (float(yaw.mean()) - float(self.yaw_after.mean()))
        return fall / max(self.travel_m, 1e-9), turn_fall / max(self.turned_rad, 1e-9)

    @property
    def drift(self) -> float:
        """Position RMS fall × √3 / distance a part covers (median) [-]."""
        return self._drifts(self.pos_before, self.yaw_before)[0]

    @property
    def turn_drift(self) -> float:
        """Heading RMS fall × √3 / angle a part turns (median) [-]."""
        return self._drifts(self.pos_before, self.yaw_before)[1]

    def scale_change(self, other: Transfer | None = None) -> float:
        """How much this model changes the turn or the distance of the held-out parts, over
        the nominal model's (or ``other``'s), the same way on the parts: the larger of
        |median(c_θ - c_θ')| and |median(c_d - c_d')|, the medians signed, over the parts
        [-]. Fits that lengthen one held-out part's distance and shorten another's change
        no scale the parts share: they cancel."""
        if self.scales is None:
            return 0.0
        ref = np.ones_like(self.scales) if other is None or other.scales is None \
            else other.scales
        return float(np.abs(np.median(self.scales - ref, axis=0)).max())

    def versus(self, simpler: Transfer, min_fall: float, times_left: float,
               min_drift: float) -> dict:
        """This model against a ``simpler`` one on the same held-out parts
        (:func:`paired_fall`, :func:`fall_floor`, :func:`richer_wins`), for the report.

        The floor on the scale of what this model leaves counts only when this model is
        material against the simpler one: it changes the turn or the distance of the
        held-out parts by ``min_drift`` (:meth:`scale_change`)."""
        mean, se, lower = paired_fall(self.before, simpler.after, self.after)
        material = self.scale_change(simpler) >= min_drift
        floor = fall_floor(self.before, self.after, min_fall,
                           times_left if material else float("inf"))
        return {"richer": list(self.effects), "simpler": list(simpler.effects),
                "mean_fall": mean, "standard_error": se, "lower_on_parts": lower,
                "parts": int(self.after.size),
                "lower_in_sum": bool(self.after.sum() < simpler.after.sum()),
                "material": material, "floor": floor,
                "richer_wins": richer_wins(self.before, simpler.after, self.after, floor)}

    def jackknife_cov(self) -> np.ndarray:
        """Covariance of the fitted vector from the spread of the leave-one-part-out fits
        (jackknife: (n - 1)/n Σ (x_k - x̄)(x_k - x̄)ᵀ)."""
        n = len(self.xs)
        d = self.xs - self.xs.mean(axis=0)
        return (n - 1) / n * d.T @ d

    @property
    def ratio(self) -> float:
        """Held-out error over the nominal model's, summed over the parts."""
        return float(self.after.sum() / max(float(self.before.sum()), 1e-300))

    @property
    def worse(self) -> bool:
        """True if the model predicts the held-out parts worse than the nominal model: in
        sum, or on half of them or more, by any amount (reported; the rules ask
        :meth:`materially_worse`)."""
        return bool(self.after.sum() > self.before.sum()
                    or 2 * int(np.sum(self.after > self.before)) >= self.after.size)

    def materially_worse(self, min_drift: float) -> bool:
        """True if the model predicts the held-out parts worse than the nominal model in
        sum, or on half of them or more by a material amount: the position or heading drift
        it adds there is ``min_drift`` of the distance or of the angle turned (a change the
        gain rule would not count as a fix does not count as harm either).

        This is what "a model that makes held-out data worse is never named" means: worse
        in sum by any amount, or worse on most parts by a drift the gain rule would count.
        A closed path's first half, say, predicted with a width fitted on its second half
        1.3 times worse in mean square but by 0.2 % of the distance, is not harm: the
        noise of a small error, not a model that misleads."""
        pos = np.sqrt(3.0) * (self.pos_after - self.pos_before) / max(self.travel_m, 1e-9)
        yaw = np.sqrt(3.0) * (self.yaw_after - self.yaw_before) / max(self.turned_rad, 1e-9)
        harmed = np.maximum(pos, yaw) >= min_drift
        return bool(self.after.sum() > self.before.sum()
                    or 2 * int(np.sum(harmed)) >= self.after.size)

    def passes(self, min_gain: float, min_drift: float) -> bool:
        """Material transfer: the held-out error falls by ``min_gain`` overall, the model
        makes no part worse as :meth:`materially_worse` reads harm (so one of two halves may
        be worse by less than ``min_drift``), and the model is material: the drift it
        removes, or the change it makes to the turn or the distance of the parts
        (:meth:`scale_change`), is ``min_drift`` of the distance or of the angle turned (on a
        closed path the error does not grow along the path, so the drift read from its RMS
        understates a turn-scale error: the scale says it directly)."""
        return (1.0 - self.ratio >= min_gain and not self.materially_worse(min_drift)
                and max(self.drift, self.turn_drift, self.scale_change()) >= min_drift)

    def as_dict(self, min_drift: float) -> dict:
        """For the report: the held-out errors, drifts and both harm tests (``min_drift``
        of :meth:`materially_worse`)."""
        return {"effects": list(self.effects), "held_out_by": self.by,
                "error_ratio": self.ratio, "per_part_error_ratio":
                (self.after / np.maximum(self.before, 1e-300)).tolist(),
                "position_rmse_m": {"before": self.pos_before.tolist(),
                                    "after": self.pos_after.tolist()},
                "final_position_error_m": {"before": self.end_before.tolist(),
                                           "after": self.end_after.tolist()},
                "drift": self.drift, "turn_drift": self.turn_drift,
                "scale_change": self.scale_change(),
                "makes_a_part_worse": self.worse,
                "makes_parts_materially_worse": self.materially_worse(min_drift)}


def paired_fall(before: np.ndarray, simpler: np.ndarray, richer: np.ndarray
                ) -> tuple[float, float, int]:
    """How much lower a richer model's held-out error is than a simpler one's, part by
    part: the mean over the parts of d_k = (e_simpler,k - e_richer,k) / ē_nominal, on the
    scale of the nominal model's mean held-out error (not each part's own: a part the
    nominal model already predicts well would turn noise into a large relative fall), the
    standard error of that mean (s_d / √P; for two parts it is half their gap) and on how
    many parts the richer model is lower [-, -, count]."""
    d = (simpler - richer) / max(float(before.mean()), 1e-300)
    se = float(d.std(ddof=1) / np.sqrt(d.size)) if d.size > 1 else float("inf")
    return float(d.mean()), se, int(np.sum(d > 0))


def fall_floor(before: np.ndarray, richer: np.ndarray, min_fall: float,
               times_left: float) -> float:
    """The paired fall (:func:`paired_fall`, on the nominal model's scale) a richer model
    must reach to beat a simpler one: the smaller of ``min_fall`` and ``times_left`` times
    the richer model's own mean held-out error [-].

    The floor keeps two fits that both leave only the noise tied. A share of the nominal
    error stands for the noise while the models leave a sizeable part of it; but where a
    large error (a turn-scale error over a long log) makes the nominal error hundreds of
    times what a fitting model leaves, a consistent fall far below ``min_fall`` of it can be
    a real component the simpler model misses (a distance scale beside the turn). Judged
    against what the richer model leaves, not against the turn error, it is many times
    that. ``Transfer.versus`` passes ``times_left`` only for a richer model that is material
    against the simpler one: re-splitting the same geometry lowers two halves' small
    residuals by up to 30 times what it leaves on kinematic logs with nothing to find, and
    only ``min_fall`` holds it."""
    nominal = max(float(before.mean()), 1e-300)
    return min(min_fall, times_left * float(richer.mean()) / nominal)


def richer_wins(before: np.ndarray, simpler: np.ndarray, richer: np.ndarray,
                floor: float) -> bool:
    """Whether a richer model's held-out error beats a simpler (nested) one's by more than
    its uncertainty: lower on most parts, and the mean paired fall (:func:`paired_fall`, on
    the nominal model's scale; positive means lower in sum) above one standard error of it
    and at least ``floor`` (:func:`fall_floor`). The parts are held out (other runs, or the
    other half of a run), so extra parameters that only fit the training parts' noise do
    not pass however many they are; the floor keeps two fits that both leave only the noise
    tied (with two parts the standard error is half their gap, itself noise).

    ``before``, ``simpler``, ``richer``: (P,) held-out mean squared errors of the nominal,
    simpler and richer models on the same parts."""
    mean, se, lower = paired_fall(before, simpler, richer)
    return bool(richer.sum() < simpler.sum() and 2 * lower > richer.size
                and mean > se and mean >= floor)


def whole_parts(logs: list) -> tuple[Segments, str] | None:
    """The parts of ``logs`` replayed whole (from the first to the last ground-truth sample):
    every run when there are ``MIN_BLOCKS`` or more, else the two halves of each run (a
    clockwise and a counter-clockwise run: a model fitted on one direction alone cannot
    separate the wheel-radius ratio from the track width, so each held-out half is predicted
    by a model that saw both directions); None when fewer than two parts hold ground truth."""
    from slipenv.diagnose.segments import log_arrays

    arrays = [log_arrays(log) for log in logs]
    spans = []
    for li, arr in enumerate(arrays):
        ok = np.flatnonzero(arr["gt_ok"])
        if ok.size < 2:
            continue
        if len(logs) >= MIN_BLOCKS:
            spans.append((li, int(ok[0]), int(ok[-1]) + 1))
        else:
            mid = int(ok[ok.size // 2])
            spans += [(li, int(ok[0]), mid + 1), (li, mid, int(ok[-1]) + 1)]
    seg = cut_spans(arrays, logs, spans) if len(spans) >= 2 else None
    if seg is None or len(seg) < 2:
        return None
    return seg, "run" if len(logs) >= MIN_BLOCKS else "half"


def whole_runs(logs: list) -> Segments | None:
    """Every run of ``logs`` replayed whole, from its first to its last ground-truth sample
    (the paths a folder's model must explain)."""
    from slipenv.diagnose.segments import log_arrays

    arrays = [log_arrays(log) for log in logs]
    spans = [(li, int(ok[0]), int(ok[-1]) + 1) for li, arr in enumerate(arrays)
             if (ok := np.flatnonzero(arr["gt_ok"])).size >= 2]
    return cut_spans(arrays, logs, spans) if spans else None


def fit_whole(problem: Problem, parts: Segments, effects: tuple[str, ...],
              index: np.ndarray | None = None, start: dict | None = None):
    """``effects`` fitted on the parts at ``index`` (all by default) replayed whole."""
    from slipenv.diagnose.fit import fit

    whole = Problem(parts, problem.heading_scale_m, problem.travel_m)
    return fit(whole, effects, index, start)


def transfer(problem: Problem, parts: Segments, by: str, effects: tuple[str, ...],
             start: dict | None = None, on_segments: bool = False) -> Transfer:
    """Leave-one-part-out replays of ``parts`` (:func:`whole_parts`) by ``effects``.

    ``on_segments``: each held-out part is replayed by ``effects`` fitted the way the
    short route names them, on ``problem``'s segments outside that part, instead of on the
    other parts' whole paths."""
    from slipenv.diagnose.fit import fit

    whole = Problem(parts, problem.heading_scale_m, problem.travel_m)
    n = len(parts)
    out = {k: np.zeros(n) for k in ("before", "after", "pos_before", "pos_after",
                                     "end_before", "end_after")}
    models, xs, scales = [], [], np.ones((n, 2))
    yaw = {"before": np.zeros(n), "after": np.zeros(n)}
    for k in range(n):
        f = (fit(problem, effects, outside(problem.seg, parts, k), start) if on_segments
             else fit_whole(problem, parts, effects, np.flatnonzero(np.arange(n) != k), start))
        model = f.params
        models.append(model)
        xs.append(f.x)
        part = parts.take(np.array([k]))
        ok = part.gt_ok[0]
        scales[k] = motion_scales(part, model)
        for tag, m in (("before", {}), ("after", model)):
            res = whole.residuals((), m, part, "pose")[0][ok]
            out[tag][k] = float(np.mean(np.sum(res**2, axis=-1)))
            out[f"pos_{tag}"][k] = float(np.sqrt(np.mean(np.sum(res[:, :2] ** 2, axis=-1))))
            out[f"end_{tag}"][k] = float(np.hypot(*res[-1, :2]))
            yaw[tag][k] = float(np.sqrt(np.mean(res[:, 2] ** 2))) / problem.heading_scale_m
    travel = np.abs(parts.dphi * parts.radius[:, None, :]).mean(axis=-1).sum(axis=1)
    d = parts.radius[:, None, :] * parts.dphi
    left = d[..., parts.sides == 0].mean(axis=-1)
    right = d[..., parts.sides == 1].mean(axis=-1)
    turned = np.abs((right - left) / parts.track[:, None]).sum(axis=1)
    return Transfer(effects, by, models=models, xs=np.array(xs), yaw_before=yaw["before"],
                    yaw_after=yaw["after"], travel_m=float(np.median(travel)),
                    turned_rad=float(np.median(turned)), scales=scales, **out)


def outside(seg: Segments, parts: Segments, k: int) -> np.ndarray:
    """Index of the segments of ``seg`` whose middle lies outside part ``k`` of ``parts``
    (another log, or another stretch of the same log)."""
    mid = seg.start + 0.5 * seg.gt_ok.sum(axis=1)
    lo = parts.start[k]
    hi = lo + int(parts.gt_ok[k].sum())
    inside = (seg.log_index == parts.log_index[k]) & (mid >= lo) & (mid < hi)
    return np.flatnonzero(~inside)


def motion_scales(part: Segments, model) -> np.ndarray:
    """(c_θ, c_d): the turn and the distance of ``part`` (one segment) replayed by ``model``
    over the nominal replay's (each interval's turn signed by the nominal one's)."""
    from slipenv.diagnose.replay import simulate

    nominal, pred = simulate(part, {})[0], simulate(part, model)[0]
    d0, d1 = (np.angle(np.exp(1j * np.diff(x[:, 2]))) for x in (nominal, pred))
    s0 = np.hypot(*np.diff(nominal[:, :2], axis=0).T)
    s1 = np.hypot(*np.diff(pred[:, :2], axis=0).T)
    turn = float(np.sum(np.sign(d0) * d1) / max(float(np.abs(d0).sum()), 1e-12))
    return np.array([turn, float(s1.sum() / max(float(s0.sum()), 1e-12))])
