"""Compass-aided and slip-compensated (sComp) odometry (Reina §4.3, Eq. 15-18).

Both take the wheel angular speed ω as the mean over all driven wheels (Reina: the 1500:1 gear
ratio keeps the wheels' speeds equal even in heavy combined slip) and the heading ψ from the
compass (``SensorFrame.heading_rad``). Compass-aided odometry moves r ω̄ dt along ψ; sComp moves
V_x dt = r ω̄ dt (1 - s_x(β)) along the body x axis and V_y dt = V_x dt tan β along body y
(Eq. 15-16, with the sign of Eq. 12 and Eq. 3, see :mod:`.slip_model`), rotated into the world by
ψ (Eq. 17) at the mid-step heading. Plain odometry (encoder heading) is
:class:`slipenv.estimators.DeadReckoning`.

The slip angle reaches sComp in one of two ways (our design): a callable
``slip_angle_source(frame) -> β`` given to the constructor, called every update (e.g. a
geometric baseline or a log column), or, without one, the last value given to
:meth:`SCompOdometry.set_slip_angle` (FTrace runs at 5 Hz, the odometry at the control rate:
the latest measurement is held). NaN measurements are ignored (the previous β is held).

When the slip model has a pitch term (:mod:`.slip_model`), sComp reads the climb angle from the
inclinometer at every update (``SensorFrame.pitch_rad``, whose positive sense lowers the nose, so
θ = -pitch); a NaN reading stands for the model's reference climb.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

from slipenv.contracts import PoseEstimate, SensorFrame, wrap_angle

from ..base import OdometryGeometry, check_frame_time
from .slip_model import SlipRatioModel


def final_position_error(estimate_xy: np.ndarray, truth_xy: np.ndarray) -> float:
    """Eq. 18: E = sqrt((P_x - P_x^gt)² + (P_y - P_y^gt)²) of the final positions [m]."""
    e, t = np.asarray(estimate_xy, dtype=float), np.asarray(truth_xy, dtype=float)
    if e.shape[-1:] != (2,) or t.shape[-1:] != (2,):
        raise ValueError("estimate_xy and truth_xy must end in (x, y)")
    e, t = e.reshape(-1, 2)[-1], t.reshape(-1, 2)[-1]
    return float(math.hypot(*(e - t)))


def _heading(frame: SensorFrame) -> float:
    psi = float(frame.heading_rad)
    if not math.isfinite(psi):
        raise ValueError(f"SensorFrame.heading_rad (compass) is not finite at t = {frame.t_s}")
    return psi


class CompassOdometry:
    """Encoder distance along the compass heading ("enhanced odometry", Reina §4.3.1).

    Parameters
    ----------
    geometry : OdometryGeometry
        Nominal wheel radius and encoder resolution; ``left + right`` are the wheels averaged.
    """

    def __init__(self, geometry: OdometryGeometry) -> None:
        self.geometry = geometry
        self._wheels = list(geometry.left) + list(geometry.right)
        self._t: float | None = None
        self._angle = 0.0
        self._psi = 0.0
        self._xy = (0.0, 0.0)

    def _mean_angle(self, frame: SensorFrame) -> float:
        counts = np.asarray(frame.enc_counts, dtype=float)
        return float(np.mean(counts[self._wheels])) / self.geometry.counts_per_rad

    def reset(self, x_m: float, y_m: float, yaw_rad: float, frame: SensorFrame) -> PoseEstimate:
        self._t = float(frame.t_s)
        self._angle = self._mean_angle(frame)
        self._xy = (float(x_m), float(y_m))
        psi = float(frame.heading_rad)
        self._psi = psi if math.isfinite(psi) else wrap_angle(float(yaw_rad))
        return PoseEstimate(*self._xy, wrap_angle(float(yaw_rad)))

    def _body_step(self, frame: SensorFrame, wheel_distance_m: float) -> tuple[float, float]:
        """Body-frame displacement (along x, along y) for this step [m]."""
        return wheel_distance_m, 0.0

    def update(self, frame: SensorFrame) -> PoseEstimate:
        dt = check_frame_time(self._t, frame)
        psi = _heading(frame)
        angle = self._mean_angle(frame)
        dx_b, dy_b = self._body_step(frame, self.geometry.wheel_radius_m * (angle - self._angle))
        dpsi = wrap_angle(psi - self._psi)
        mid = self._psi + 0.5 * dpsi
        c, s = math.cos(mid), math.sin(mid)
        x, y = self._xy
        self._xy = (x + c * dx_b - s * dy_b, y + s * dx_b + c * dy_b)  # Eq. 17, integrated
        self._angle, self._psi, self._t = angle, psi, float(frame.t_s)
        return self._estimate(dx_b, dy_b, dpsi, dt)

    def _estimate(self, dx_b: float, dy_b: float, dpsi: float, dt: float) -> PoseEstimate:
        return PoseEstimate(*self._xy, wrap_angle(self._psi), speed_mps=dx_b / dt,
                            yaw_rate_rps=dpsi / dt)


class SCompOdometry(CompassOdometry):
    """Slip-compensated odometry, sComp (Reina Eq. 15-17).

    Parameters
    ----------
    geometry : OdometryGeometry
        Nominal wheel radius and encoder resolution; ``left + right`` are the wheels averaged.
    slip_model : SlipRatioModel
        s_x(β) of Eq. 12, optionally with the pitch term (fitted on a run with ground truth,
        Reina §4.3.1).
    slip_angle_source : callable, optional
        ``f(frame) -> β`` [rad] called at every update; without it the value of
        :meth:`set_slip_angle` is used.
    """

    def __init__(self, geometry: OdometryGeometry, slip_model: SlipRatioModel,
                 slip_angle_source: Callable[[SensorFrame], float] | None = None) -> None:
        super().__init__(geometry)
        self.slip_model = slip_model
        self.slip_angle_source = slip_angle_source
        self.beta_rad = 0.0
        self.slip_ratio = slip_model.s_x0

    def set_slip_angle(self, beta_rad: float) -> None:
        """Latest measured body slip angle β [rad] (e.g. FTrace); NaN keeps the previous one."""
        if math.isfinite(beta_rad):
            if abs(beta_rad) >= 0.5 * math.pi:
                raise ValueError(f"slip angle must be within ±90°, got {beta_rad!r} rad")
            self.beta_rad = float(beta_rad)

    def reset(self, x_m: float, y_m: float, yaw_rad: float, frame: SensorFrame) -> PoseEstimate:
        self.beta_rad, self.slip_ratio = 0.0, self.slip_model.s_x0
        return super().reset(x_m, y_m, yaw_rad, frame)

    def _body_step(self, frame: SensorFrame, wheel_distance_m: float) -> tuple[float, float]:
        if self.slip_angle_source is not None:
            self.set_slip_angle(float(self.slip_angle_source(frame)))
        climb = -float(frame.pitch_rad) if self.slip_model.k_pitch != 0.0 else None
        self.slip_ratio = float(self.slip_model(self.beta_rad, climb))
        dx = wheel_distance_m * (1.0 - self.slip_ratio)  # Eq. 15 with Eq. 12's sign
        return dx, dx * math.tan(self.beta_rad)  # Eq. 16

    def _estimate(self, dx_b: float, dy_b: float, dpsi: float, dt: float) -> PoseEstimate:
        return PoseEstimate(*self._xy, wrap_angle(self._psi), speed_mps=dx_b / dt,
                            yaw_rate_rps=dpsi / dt, slip_angle_rad=self.beta_rad,
                            extras={"slip_ratio": self.slip_ratio})
