"""The estimator contract: what every pose estimator in ``estimators/`` takes and returns.

Estimators eat :class:`slipenv.contracts.SensorFrame` readings and never see PyBullet or
ground truth. The environment calls ``reset`` once per episode with the known start pose and
``update`` once per control step; the returned :class:`slipenv.contracts.PoseEstimate` becomes
the observation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

import numpy as np

from slipenv.contracts import PoseEstimate, SensorFrame


@dataclass(frozen=True)
class OdometryGeometry:
    """What an odometric model knows about the vehicle (the operator's nominal belief).

    Attributes
    ----------
    wheel_radius_m : float
        Nominal wheel (or sprocket) radius the operator believes in [m].
    track_width_m : float
        Lateral distance between the left and right contact lines [m].
    counts_per_rad : float
        Encoder resolution [counts/rad] (Lindgren: 285).
    left : tuple[int, ...]
        Indices into ``SensorFrame.enc_counts`` of the left-side wheels (or the left track).
    right : tuple[int, ...]
        Indices of the right-side wheels (or the right track).
    wheel_xy_m : np.ndarray, shape (n_wheels, 2) or None
        Wheel contact positions in the body frame [m]; needed only by steered vehicles.
    """

    wheel_radius_m: float
    track_width_m: float
    counts_per_rad: float
    left: tuple[int, ...] = (0,)
    right: tuple[int, ...] = (1,)
    wheel_xy_m: np.ndarray | None = None

    def __post_init__(self) -> None:
        for name in ("wheel_radius_m", "track_width_m", "counts_per_rad"):
            value = getattr(self, name)
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"OdometryGeometry.{name} must be finite and > 0, got {value!r}")
        if not self.left or not self.right:
            raise ValueError("OdometryGeometry needs at least one left and one right wheel index")


@runtime_checkable
class Estimator(Protocol):
    """A pose estimator fed one :class:`SensorFrame` per control step."""

    def reset(self, x_m: float, y_m: float, yaw_rad: float, frame: SensorFrame) -> PoseEstimate:
        """Start from a known pose; ``frame`` gives the initial encoder counts."""
        ...

    def update(self, frame: SensorFrame) -> PoseEstimate:
        """Take the next frame (time strictly increasing) and return the new estimate."""
        ...


def check_frame_time(previous_t_s: float | None, frame: SensorFrame) -> float:
    """Return the step ``dt`` to ``frame``, raising ``ValueError`` on NaN or out-of-order time."""
    t = float(frame.t_s)
    if not math.isfinite(t):
        raise ValueError(f"sensor frame time is not finite: {t!r}")
    if previous_t_s is not None and t <= previous_t_s:
        raise ValueError(
            f"sensor frame out of order: t = {t:.6f} s is not after the previous "
            f"{previous_t_s:.6f} s"
        )
    return 0.0 if previous_t_s is None else t - previous_t_s
