"""FTrace's robustness counters (Reina §4.1, Table 4).

Definitions (the paper's, with our threshold made explicit):

- **false positive**: a trace is *detected* in a frame where no trace is present;
- **false negative**: a trace is present but nothing is detected (a frame where the last trace
  is only *held* counts as a false negative: the paper's detector "does not return any
  information" and retains the last trace);
- **misidentification**: a trace is present and detected, but the detected angle is wrong:
  |θ_est - θ_true| > ``misid_threshold_rad`` (default 2°).

Rates are fractions of all scored frames, as in Table 4.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from slipenv.contracts import wrap_angle

from .ftrace import TraceDetection


@dataclass
class FTraceScore:
    """Running counts of FTrace's outcomes against the truth.

    Attributes
    ----------
    misid_threshold_rad : float
        Angle error above which a detection is a misidentification [rad].
    """

    misid_threshold_rad: float = math.radians(2.0)
    frames: int = 0
    with_trace: int = 0
    false_positive: int = 0
    false_negative: int = 0
    misidentification: int = 0
    held: int = 0
    max_consecutive_misses: int = 0
    _run: int = 0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.misid_threshold_rad) and self.misid_threshold_rad > 0.0):
            raise ValueError(f"misid_threshold_rad must be > 0, got {self.misid_threshold_rad!r}")

    def add(self, detection: TraceDetection, trace_present: bool,
            true_angle_rad: float) -> None:
        """Score one frame."""
        self.frames += 1
        detected = detection.status == "detected"
        self.held += detection.status == "held"
        if not trace_present:
            self.false_positive += detected
            self._run = 0
            return
        self.with_trace += 1
        if not detected:
            self.false_negative += 1
            self._run += 1
            self.max_consecutive_misses = max(self.max_consecutive_misses, self._run)
            return
        self._run = 0
        if not math.isfinite(true_angle_rad):
            raise ValueError("true_angle_rad must be finite when trace_present is True")
        if abs(wrap_angle(detection.angle_rad - true_angle_rad)) > self.misid_threshold_rad:
            self.misidentification += 1

    def rate(self, name: str) -> float:
        """``false_positive``, ``false_negative`` or ``misidentification`` per frame."""
        if name not in ("false_positive", "false_negative", "misidentification"):
            raise ValueError(f"unknown counter {name!r}")
        return getattr(self, name) / self.frames if self.frames else math.nan

    def confusion(self) -> dict:
        """Frames by truth (trace present or not) and outcome: the confusion table."""
        correct = self.with_trace - self.false_negative - self.misidentification
        without = self.frames - self.with_trace
        return {"trace_present": {"correct": correct, "misidentified": self.misidentification,
                                  "not_detected": self.false_negative},
                "no_trace": {"detected": self.false_positive,
                             "not_detected": without - self.false_positive}}

    def as_dict(self) -> dict:
        """Counts and rates, for a JSON report."""
        return {"frames": self.frames, "with_trace": self.with_trace,
                "false_positive": self.rate("false_positive"),
                "false_negative": self.rate("false_negative"),
                "misidentification": self.rate("misidentification"),
                "held": self.held, "max_consecutive_misses": self.max_consecutive_misses,
                "confusion": self.confusion()}
