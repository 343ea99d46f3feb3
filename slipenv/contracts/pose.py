"""The pose estimate: what every estimator returns and what the observation is built from."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass(frozen=True)
class PoseEstimate:
    """An estimator's output at one step.

    Attributes
    ----------
    x_m, y_m : float
        Estimated position of the reference point (midway between the contact lines) [m].
    yaw_rad : float
        Estimated heading, counter-clockwise from world x [rad].
    speed_mps : float
        Estimated forward speed [m/s].
    yaw_rate_rps : float
        Estimated yaw rate [rad/s].
    slip_angle_rad : float
        Estimated body slip angle β̂ [rad] (angle from body x to the velocity); 0 when the
        estimator does not model it.
    cov : np.ndarray, shape (3, 3) or None
        Covariance of (x, y, yaw) if the estimator tracks one.
    extras : dict
        Estimator-specific values (e.g. estimated k_s, R_w) for ``info``.
    """

    x_m: float
    y_m: float
    yaw_rad: float
    speed_mps: float = 0.0
    yaw_rate_rps: float = 0.0
    slip_angle_rad: float = 0.0
    cov: np.ndarray | None = None
    extras: dict = field(default_factory=dict)

    @classmethod
    def construct(cls, x_m: float, y_m: float, yaw_rad: float, speed_mps: float,
                  yaw_rate_rps: float, slip_angle_rad: float, cov: np.ndarray | None,
                  extras: dict) -> PoseEstimate:
        """The estimate of these field values, every one given, built without ``__init__``.

        Equal to ``PoseEstimate(x_m, ..., extras)`` in every way (fields, equality, ``repr``,
        pickling, :func:`dataclasses.replace`), at a third of the cost: a frozen dataclass's
        ``__init__`` sets each field through ``object.__setattr__`` (~2 µs for the eight),
        where this sets the instance's ``__dict__`` once. For an estimator that returns an
        estimate at every control step of an env; it checks nothing, as ``__init__`` does not.
        """
        est = _new(cls)
        _setattr(est, "__dict__", {
            "x_m": x_m, "y_m": y_m, "yaw_rad": yaw_rad, "speed_mps": speed_mps,
            "yaw_rate_rps": yaw_rate_rps, "slip_angle_rad": slip_angle_rad, "cov": cov,
            "extras": extras})
        return est


_new = object.__new__
_setattr = object.__setattr__  # the frozen dataclass's own __setattr__ refuses every field
