"""The in-memory measured log (slipenv-log/1), its validation and the helpers a diagnosis needs.

Units follow ``log-format.md``: time [s], encoder counts [counts] (cumulative integers stored as
float64), angles [rad], positions [m]. NaN means "not measured at this sample".
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from slipenv.logs.bounds import (
    first_out_of_bounds,
    first_rate_out_of_bounds,
    rate_bound,
    signal_bound,
)
from slipenv.logs.errors import LogFormatError
from slipenv.logs.meta import LogMeta, validate_meta

GT_COLUMNS = ("gt_x", "gt_y", "gt_yaw")
ARRAYS_PATH = "<arrays>"  # what errors name when a log is built from arrays, not read
_SLACK_S = 1e-9  # [s] tolerance on time bounds, far below any sample period


def required_columns(meta: LogMeta, require_ground_truth: bool = True) -> list[str]:
    """Columns the contract requires for this vehicle (``t``, ``enc_*``, ``steer_*``, ``gt_*``)."""
    cols = ["t"] + [f"enc_{w}" for w in meta.wheels]
    if meta.kind == "rover4ws":
        cols += [f"steer_{w}" for w in meta.wheels]
    if require_ground_truth:
        cols += list(GT_COLUMNS)
    return cols


def validate_signals(
    meta: LogMeta,
    signals: Mapping[str, np.ndarray],
    path: str | Path,
    *,
    require_ground_truth: bool = True,
    lines: np.ndarray | None = None,
    header_line: int | None = None,
) -> None:
    """Check the signal columns against the contract.

    Parameters
    ----------
    meta : LogMeta
        Validated meta (gives the wheel names and vehicle kind).
    signals : Mapping[str, ndarray]
        Column name -> 1-D float64 array, all of one length.
    path : str or Path
        File named in errors (``signals.csv``, or ``<arrays>``).
    require_ground_truth : bool
        The contract requires ``gt_x, gt_y, gt_yaw`` with at least some values. Logs of
        vehicles without any ground truth (e.g. BorealTC) pass only with ``False``.
    lines : ndarray of int, optional
        1-based file line of each data row, so errors can name it.
    header_line : int, optional
        Line of the header, named for a missing column.

    Raises
    ------
    LogFormatError
        Naming the file, the 1-based data row (and line) and the column.
    """

    def fail(reason: str, column: str, index: int | None = None) -> LogFormatError:
        if index is None:
            return LogFormatError(path, reason, line=header_line, column=column)
        line = None if lines is None else int(lines[index])
        return LogFormatError(path, reason, row=index + 1, line=line, column=column)

    for name in required_columns(meta, require_ground_truth):
        if name not in signals:
            raise fail("required column missing", name)
    for name, values in signals.items():
        if values.ndim != 1:
            raise fail(f"column has shape {values.shape}, expected one dimension", name)
    n = len(signals["t"])
    if n == 0:
        raise fail("the log holds no samples", "t")
    for name, values in signals.items():
        if len(values) != n:
            raise fail(f"column has {len(values)} samples, 't' has {n}", name)
        bad = np.flatnonzero(np.isinf(values))
        if bad.size:
            raise fail("infinite value", name, int(bad[0]))
        bound = signal_bound(name, meta.wheels)
        if bound is not None:
            k = first_out_of_bounds(values, bound[0])
            if k is not None:
                raise fail(f"value {float(values[k])!r} is physically implausible (|{name}| "
                           f"<= {bound[0]:g} {bound[1]}; see slipenv.logs.bounds)", name, k)
    t = signals["t"]
    enc = [f"enc_{w}" for w in meta.wheels]
    for name in ["t", *enc]:
        missing = np.flatnonzero(np.isnan(signals[name]))
        if missing.size:
            raise fail("value required but empty or NaN", name, int(missing[0]))
    for name in enc:
        frac = np.flatnonzero(signals[name] != np.round(signals[name]))
        if frac.size:
            value = float(signals[name][frac[0]])
            raise fail(f"encoder count {value!r} is not an integer", name, int(frac[0]))
    back = np.flatnonzero(np.diff(t) <= 0.0)
    if back.size:
        i = int(back[0]) + 1
        raise fail(f"time not strictly increasing ({float(t[i])!r} s after "
                   f"{float(t[i - 1])!r} s)", "t", i)
    for name, values in signals.items():
        limit = rate_bound(name, meta.wheels)
        if limit is None:
            continue
        scale = meta.counts_per_rad if name.startswith("enc_") else 1.0
        k = first_rate_out_of_bounds(t, values, limit[0], scale)
        if k is not None:
            prev = int(np.flatnonzero(np.isfinite(values[:k]))[-1])
            rate = abs(float(values[k]) - float(values[prev])) / scale / float(t[k] - t[prev])
            raise fail(f"jump from {float(values[prev])!r} to {float(values[k])!r} is "
                       f"physically implausible ({rate:.3g} {limit[1]} > {limit[0]:g} "
                       f"{limit[1]}; see slipenv.logs.bounds)", name, k)
    if require_ground_truth:
        for name in GT_COLUMNS:
            if not np.isfinite(signals[name]).any():
                raise fail("ground-truth column holds no values", name)
        if not ground_truth_mask(signals).any():
            raise fail("no sample has all of gt_x, gt_y, gt_yaw", "gt_x")


def ground_truth_mask(signals: Mapping[str, np.ndarray]) -> np.ndarray:
    """Boolean mask of samples where ``gt_x``, ``gt_y`` and ``gt_yaw`` are all measured."""
    n = len(signals["t"])
    if not all(c in signals for c in GT_COLUMNS):
        return np.zeros(n, dtype=bool)
    return np.logical_and.reduce([np.isfinite(signals[c]) for c in GT_COLUMNS])


@dataclass(eq=False)
class Log:
    """A measured (or simulated) run in the slipenv-log/1 layout.

    Attributes
    ----------
    meta : LogMeta
        ``meta.json`` contents; unknown keys are kept.
    signals : dict[str, ndarray]
        Column name -> float64 array of shape (n,), including ``t`` [s]; insertion order is
        the column order written to ``signals.csv``. NaN = not measured.
    path : Path or None
        Folder the log was read from, if any.
    """

    meta: LogMeta
    signals: dict[str, np.ndarray]
    path: Path | None = field(default=None, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.meta, LogMeta):
            self.meta = LogMeta(self.meta)

    @classmethod
    def from_arrays(
        cls, meta: Mapping[str, Any] | LogMeta, *, require_ground_truth: bool = True,
        **columns: Any,
    ) -> Log:
        """Build a validated log from arrays (e.g. a simulated episode), ``t`` first.

        Parameters
        ----------
        meta : Mapping or LogMeta
            ``meta.json`` contents (see ``LogMeta.new``).
        require_ground_truth : bool
            See ``validate_signals``.
        **columns : array_like
            Column name -> values of shape (n,), e.g. ``t=..., enc_left=..., gt_x=...``.

        Raises
        ------
        LogFormatError
            As ``read_log`` does, naming ``<arrays>``, the 1-based row and the column.
        """
        meta = meta.copy() if isinstance(meta, LogMeta) else LogMeta(meta)
        validate_meta(meta.data, ARRAYS_PATH)
        signals: dict[str, np.ndarray] = {}
        for name, values in columns.items():
            try:
                signals[name] = np.array(values, dtype=np.float64)
            except (TypeError, ValueError):
                raise LogFormatError(ARRAYS_PATH, "values are not numeric",
                                     column=name) from None
        if "t" in signals:
            signals = {"t": signals.pop("t"), **signals}
        validate_signals(meta, signals, ARRAYS_PATH, require_ground_truth=require_ground_truth)
        return cls(meta, signals)

    def __len__(self) -> int:
        return len(self.signals["t"])

    @property
    def t(self) -> np.ndarray:
        """Sample times [s], shape (n,)."""
        return self.signals["t"]

    @property
    def wheels(self) -> list[str]:
        return self.meta.wheels

    @property
    def columns(self) -> list[str]:
        return list(self.signals)

    def has(self, column: str) -> bool:
        """True if the column exists and holds at least one measured value."""
        return column in self.signals and bool(np.isfinite(self.signals[column]).any())

    @property
    def gt_mask(self) -> np.ndarray:
        """Boolean mask (n,) of samples with a full ground-truth pose."""
        return ground_truth_mask(self.signals)

    def ground_truth(self) -> np.ndarray:
        """Ground-truth pose ``[gt_x, gt_y, gt_yaw]`` [m, m, rad], shape (n, 3), NaN if absent."""
        return np.column_stack([self.signals.get(c, np.full(len(self), np.nan))
                                for c in GT_COLUMNS])

    def wheel_angle(self, wheel: str) -> np.ndarray:
        """Cumulative wheel rotation ``counts / counts_per_rad`` [rad], shape (n,)."""
        return self.signals[f"enc_{wheel}"] / self.meta.counts_per_rad

    def wheel_angles(self) -> np.ndarray:
        """Cumulative rotation of every wheel [rad], shape (n, n_wheels), in ``wheels`` order."""
        return np.column_stack([self.wheel_angle(w) for w in self.wheels])

    def wheel_speeds(self) -> np.ndarray:
        """Wheel angular speeds by backward differences [rad/s], shape (n, n_wheels).

        Row i is the mean speed over ``[t[i-1], t[i]]``; row 0 is NaN (no interval).
        """
        angles = self.wheel_angles()
        speeds = np.full_like(angles, np.nan)
        speeds[1:] = np.diff(angles, axis=0) / np.diff(self.t)[:, None]
        return speeds

    def slice(self, t0: float, t1: float) -> Log:
        """Samples with ``t0 <= t <= t1`` [s] (closed: consecutive slices share a boundary).

        The bounds have 1 ns of slack, so ``slice(0.2, 0.6)`` keeps a sample stored as
        0.6000000000000001. Encoder counts stay cumulative (not re-zeroed). The slice is not
        re-validated: it may hold no ground truth.
        """
        keep = (self.t >= t0 - _SLACK_S) & (self.t <= t1 + _SLACK_S)
        return Log(self.meta.copy(), {k: v[keep].copy() for k, v in self.signals.items()})

    def segment_bounds(self, duration_s: float) -> list[tuple[int, int]]:
        """Index ranges of consecutive segments of ``duration_s`` that start on ground truth.

        A segment starts at a sample with a full ground-truth pose and ends at the first sample
        at or after ``start time + duration_s``; the next segment starts at that end sample if
        it has ground truth, else at the next sample that has. Stretches without ground truth
        are skipped; a last segment shorter than ``duration_s`` is dropped.

        Parameters
        ----------
        duration_s : float
            Segment length [s], > 0.

        Returns
        -------
        list of (start, stop)
            Half-open index ranges ``t[start:stop]``; ``stop - 1`` is the end sample.
        """
        if not duration_s > 0:
            raise ValueError(f"duration_s must be > 0, got {duration_s}")
        t, gt = self.t, self.gt_mask
        gt_idx = np.flatnonzero(gt)
        bounds: list[tuple[int, int]] = []
        k = 0
        while k < gt_idx.size:
            i = int(gt_idx[k])
            # first sample at or after the end time (1 ns slack for float round-off)
            j = max(i + 1, int(np.searchsorted(t, t[i] + duration_s - _SLACK_S)))
            if j >= len(t):
                break
            bounds.append((i, j + 1))
            k = int(np.searchsorted(gt_idx, j))
        return bounds

    def segments(self, duration_s: float) -> list[Log]:
        """The segments of ``segment_bounds`` as logs (see there)."""
        return [Log(self.meta.copy(), {k: v[a:b].copy() for k, v in self.signals.items()})
                for a, b in self.segment_bounds(duration_s)]
