"""Slip-compensated odometry of a skid-steer tracked vehicle (Yamauchi §2.2, Eq. 1-10).

Endo's longitudinal slip compensation (:mod:`.endo`) plus the lateral slip: a slip angle β̂
predicted by the linear regression of Eq. 9,

    β = a1 + a2·roll + a3·(angular displacement) + a4·(rotation radius),

and the position integrated along the heading plus β̂ (Eq. 2, 5-6).

The regressors, as the paper defines them (§2.2) and as computed here online:

- roll [rad]: the inclinometer roll ``frame.roll_rad`` (> 0 lifts the left side); on a side slope
  it carries the weight component parallel to the slope.
- angular displacement [rad]: "Note that the angular displacement is the angle from the starting
  orientation of the rotation movement." Here: the gyro heading change accumulated since the
  current rotation movement started, signed (counter-clockwise > 0). A rotation movement starts at
  :meth:`~slipenv.estimators.gyrodometry.Gyrodometry.reset`, and again whenever the vehicle drives
  straight (|ω| < ``straight_yaw_rate_rps``, the displacement is then 0) or reverses its turning
  direction. In the paper's experiments every run is one rotation of about 90° from rest, which
  this reproduces; ``straight_yaw_rate_rps=None`` keeps the angle since reset.
- rotation radius [m]: the distance from the centre of rotation (Yamauchi Fig. 1) to the reference
  point, ``|V_x / ω|`` with V_x from Endo's Eq. 1 and ω from the gyro (the paper's runs at
  5 cm/s and 10/20/30 °/s have 0.29/0.14/0.10 m). The paper does not give the sign; the magnitude
  is used because the turning direction is already in the sign of the angular displacement and a
  signed radius would jump between ±∞ on straight driving. It is clipped to
  ``max_rotation_radius_m`` (straight driving gives the clip value, not ∞), and is 0 at rest.

Units matter because the coefficients are fitted in them: rad, rad, m; β in rad. Train the model
(:func:`.identification.fit_slip_angle_regression`) on features computed with
:func:`rotation_radius_m` and the same clip as the odometry uses.
"""

from __future__ import annotations

import math
from typing import Protocol

import numpy as np
from numpy.typing import ArrayLike

from slipenv.contracts import SensorFrame

from ..base import OdometryGeometry
from ..gyrodometry import finite_reading
from .endo import DEFAULT_SPEED_EPS_MPS, EndoOdometry


class SlipAnglePredictor(Protocol):
    """Anything with Eq. 9's ``predict``, e.g. :class:`.identification.SlipAngleModel`."""

    def predict(
        self, roll: ArrayLike, angular_displacement: ArrayLike, rotation_radius: ArrayLike
    ) -> np.ndarray:
        """Slip angle [rad] from roll [rad], angular displacement [rad], rotation radius [m]."""
        ...


def rotation_radius_m(v_x: ArrayLike, yaw_rate: ArrayLike, max_radius_m: float) -> np.ndarray:
    """Rotation radius ``min(|V_x / ω|, max_radius_m)`` [m]; 0 where V_x = 0.

    Parameters
    ----------
    v_x : array_like
        Longitudinal ground speed of the reference point [m/s].
    yaw_rate : array_like
        Yaw rate [rad/s].
    max_radius_m : float
        Clip value [m], > 0; also the radius of straight driving (ω = 0).
    """
    r_max = float(max_radius_m)
    if not (math.isfinite(r_max) and r_max > 0.0):
        raise ValueError(f"max_radius_m must be finite and > 0, got {max_radius_m!r}")
    if type(v_x) is float and type(yaw_rate) is float:
        # one step's values: the same IEEE operations on plain floats (numpy's
        # per-call cost on 0-d arrays dominated the estimator); bit-identical to the array path
        speed, rate = abs(v_x), abs(yaw_rate)
        radius_f = speed / rate if rate > 0.0 else r_max
        return np.asarray(min(radius_f, r_max) if speed > 0.0 else 0.0)
    speed, rate = np.abs(np.asarray(v_x, dtype=float)), np.abs(np.asarray(yaw_rate, dtype=float))
    speed, rate = np.broadcast_arrays(speed, rate)
    radius = np.divide(speed, rate, out=np.full(speed.shape, r_max), where=rate > 0.0)
    return np.where(speed > 0.0, np.minimum(radius, r_max), 0.0)


def next_angular_displacement(
    previous_rad: float, dyaw_rad: float, yaw_rate: float, straight_yaw_rate_rps: float | None
) -> float:
    """Angular displacement from the start of the current rotation movement after one step [rad].

    Restarts (from this step's heading change) when the turning direction reverses, and is 0
    while ``|yaw_rate| < straight_yaw_rate_rps`` (straight driving ends a rotation movement).
    """
    if straight_yaw_rate_rps is None:
        return previous_rad + dyaw_rad
    if abs(yaw_rate) < straight_yaw_rate_rps:
        return 0.0
    if previous_rad * dyaw_rad < 0.0:
        return dyaw_rad
    return previous_rad + dyaw_rad


class SlipCompensatedOdometry(EndoOdometry):
    """Yamauchi's slip-compensated odometry: Endo slip ratios plus regression slip angle.

    Per step: Endo's body-x displacement Δx and gyro heading change Δθ
    (:class:`~.endo.EndoOdometry`); the features (roll, angular displacement, rotation radius)
    at the new frame; ``β̂ = beta_model.predict(...)`` clipped to ±``max_slip_angle_rad``; the
    position moves ``Δx / cos β̄`` along ``θ + Δθ/2 + β̄`` (β̄ = mean β̂ of the step's ends),
    i.e. Eq. 5-6 with ``V_y = V_x tan β`` (Eq. 2).

    Parameters
    ----------
    geometry : OdometryGeometry
        Sprocket radius, tread and encoder layout.
    n : float
        Endo's exponent [-], > 0.
    beta_model : SlipAnglePredictor
        Fitted Eq. 9 regression, e.g. :class:`.identification.SlipAngleModel`.
    speed_eps_mps : float
        Regularising track speed of the Endo solve [m/s].
    max_rotation_radius_m : float
        Clip of the rotation-radius regressor [m] (default 1 m, about 3× the paper's largest
        training radius); use the value the model was trained with.
    straight_yaw_rate_rps : float or None
        Yaw rate below which the vehicle counts as driving straight and the angular displacement
        restarts [rad/s] (default 0.02 rad/s ≈ 1.1 °/s, well below the paper's 10 °/s); None: the
        angular displacement is measured from reset.
    max_slip_angle_rad : float
        Clip of β̂ [rad] (default 1 rad), so an extrapolating regression cannot reach π/2 where
        ``1 / cos β`` diverges.
    n_clockwise : float or None
        Endo's exponent of clockwise steps [-]; None: ``n`` for both turning directions
        (:class:`~.endo.EndoOdometry`).

    Notes
    -----
    ``PoseEstimate.slip_angle_rad`` is β̂, for the controller's feed-forward (Yamauchi §3 Eq. 10).
    ``extras`` adds ``roll_rad``, ``angular_displacement_rad`` and ``rotation_radius_m`` to
    Endo's.
    """

    def __init__(
        self,
        geometry: OdometryGeometry,
        n: float,
        beta_model: SlipAnglePredictor,
        *,
        speed_eps_mps: float = DEFAULT_SPEED_EPS_MPS,
        max_rotation_radius_m: float = 1.0,
        straight_yaw_rate_rps: float | None = 0.02,
        max_slip_angle_rad: float = 1.0,
        n_clockwise: float | None = None,
    ) -> None:
        super().__init__(geometry, n, speed_eps_mps=speed_eps_mps, n_clockwise=n_clockwise)
        if not callable(getattr(beta_model, "predict", None)):
            kind = type(beta_model).__name__
            raise ValueError(f"beta_model must have a predict method, got {kind}")
        rotation_radius_m(0.0, 0.0, max_rotation_radius_m)  # validates the clip
        if straight_yaw_rate_rps is not None and not (
            math.isfinite(straight_yaw_rate_rps) and straight_yaw_rate_rps >= 0.0
        ):
            raise ValueError(
                "straight_yaw_rate_rps must be finite and >= 0 or None, "
                f"got {straight_yaw_rate_rps!r}"
            )
        if not (math.isfinite(max_slip_angle_rad) and 0.0 < max_slip_angle_rad < 0.5 * math.pi):
            raise ValueError(f"max_slip_angle_rad must be in (0, π/2), got {max_slip_angle_rad!r}")
        self.beta_model = beta_model
        self.max_rotation_radius_m = float(max_rotation_radius_m)
        self.straight_yaw_rate_rps = straight_yaw_rate_rps
        self.max_slip_angle_rad = float(max_slip_angle_rad)
        self._angular_displacement = 0.0

    def _reset_hook(self, frame: SensorFrame) -> None:
        self._angular_displacement = 0.0

    def _translation(
        self, d_left: float, d_right: float, dyaw: float, dt: float, frame: SensorFrame
    ) -> tuple[float, float, dict]:
        forward_m, _, extras = super()._translation(d_left, d_right, dyaw, dt, frame)
        roll = finite_reading(frame.roll_rad, "frame.roll_rad")
        self._angular_displacement = next_angular_displacement(
            self._angular_displacement, dyaw, dyaw / dt, self.straight_yaw_rate_rps
        )
        radius = float(rotation_radius_m(forward_m / dt, dyaw / dt, self.max_rotation_radius_m))
        beta = float(np.asarray(self.beta_model.predict(roll, self._angular_displacement, radius)))
        if not math.isfinite(beta):
            raise ValueError(f"beta_model.predict returned a non-finite slip angle {beta!r}")
        beta = min(max(beta, -self.max_slip_angle_rad), self.max_slip_angle_rad)
        extras.update(
            roll_rad=roll,
            angular_displacement_rad=self._angular_displacement,
            rotation_radius_m=radius,
        )
        return forward_m, beta, extras
