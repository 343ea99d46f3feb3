"""Endo's slip-ratio odometry for skid-steer tracked vehicles (Endo 2007; Yamauchi Eq. 7-8).

The gyro measures the true yaw rate ω, the encoders the input track speeds v_l, v_r. Two
equations fix the two slip ratios:

- Eq. 7: ``v_r(1 - α_r) - v_l(1 - α_l) = 2d ω``;
- Eq. 8: ``α_l / α_r = -sgn(v_r v_l) |v_r / v_l|^n``.

Closed form. Write the slip *velocities* ``s = α v`` (input speed minus ground speed). Eq. 8
multiplied by ``v_l / v_r`` becomes, for either sign of ``v_r v_l``,

    s_l / s_r = -|v_l / v_r|^(1-n),

so ``s_l = f c`` and ``s_r = -(1 - f) c`` with

    c = 2d ω - (v_r - v_l)          (yaw-rate discrepancy × tread, Eq. 7 rearranged)
    f = |v_l|^(1-n) / (|v_l|^(1-n) + |v_r|^(1-n)).

Eq. 7 then holds exactly (``s_l - s_r = c``) and, by Eq. 1, the ground speed of the reference point
is ``V_x = (v_l + v_r)/2 - (s_l + s_r)/2 = (v_l + v_r)/2 - (2f - 1) c / 2``. No root-finding is
needed: the problem is linear in the slips once their ratio is fixed.

Regimes and regularisation (``speed_eps_mps`` = ε):

- Straight driving, v_l ≈ v_r: Eq. 8 gives α_l/α_r = -1, f = 1/2, so V_x is the mean track speed
  and gyro noise or bias only shows up as equal and opposite slip ratios (the ratio α_l/α_r is
  0/0 in the data, which is why :func:`.identification.fit_endo_n` drops such samples).
  Nothing divides by v_l - v_r, so nothing blows up.
- Pivot turn, v_l = -v_r: f = 1/2, V_x = 0 and α_l = α_r (Eq. 8 with sgn = -1): both tracks
  lose the same fraction of their speed and the vehicle turns on the spot.
- One track stopped, or both: f has a |v|^(1-n) cusp at v = 0 (infinite slope for n < 1) and is
  0/0 when both tracks stop. The speeds in f are replaced by ``sqrt(v² + ε²)``: f → 1/2 when both
  stop (so gyro bias at standstill produces no creep) and the sensitivity to encoder quantisation
  near a stopped track is bounded. Choose ε near the encoder speed resolution
  ``R / (counts_per_rad · dt)``; the default 1 mm/s suits the Patako-like defaults.
- Slip ratios are reported as ``α = s v / (v² + ε²)``, which equals s / v for |v| ≫ ε and stays
  finite for a stopped track (whose slip ratio is undefined).

The functions take and return plain floats: :class:`EndoOdometry` calls them once per control
step, where numpy's per-call overhead on scalars would cost several times the arithmetic.
"""

from __future__ import annotations

import math
from typing import overload

import numpy as np

from slipenv.contracts import SensorFrame

from ..base import OdometryGeometry
from ..gyrodometry import Gyrodometry
from .kinematics import check_tread

Speed = float | np.ndarray
"""A track speed [m/s] (or a share derived from two): one float, or a numpy array of them."""

DEFAULT_SPEED_EPS_MPS = 1e-3  # [m/s] regularising track speed in the Endo weights


def check_endo_n(n: float) -> float:
    """Return Endo's exponent as float, raising ``ValueError`` unless finite and > 0 [-]."""
    try:
        value = float(n)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"n must be a finite number > 0, got {n!r}") from exc
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"n must be finite and > 0, got {n!r}")
    return value


def _check_eps(speed_eps_mps: float) -> float:
    eps = float(speed_eps_mps)
    if not (math.isfinite(eps) and eps >= 0.0):
        raise ValueError(f"speed_eps_mps must be finite and >= 0, got {speed_eps_mps!r}")
    return eps


def endo_ratio(v_l: float, v_r: float, n: float) -> float:
    """Right-hand side of Endo's relation, ``α_l/α_r = -sgn(v_r v_l)|v_r/v_l|^n`` (Eq. 8) [-];
    NaN for a stopped left track."""
    n = check_endo_n(n)
    if v_l == 0.0:
        return math.nan
    return -math.copysign(1.0, v_r * v_l) * abs(v_r / v_l) ** n if v_r != 0.0 else -0.0


@overload
def endo_left_share(v_l: float, v_r: float, n: float,
                    speed_eps_mps: float = ...) -> float: ...
@overload
def endo_left_share(v_l: np.ndarray, v_r: np.ndarray, n: float,
                    speed_eps_mps: float = ...) -> np.ndarray: ...
def endo_left_share(v_l: Speed, v_r: Speed, n: float,
                    speed_eps_mps: float = DEFAULT_SPEED_EPS_MPS) -> Speed:
    """Share f of the yaw-rate discrepancy taken by the left track's slip velocity [-].

    ``f = a_l / (a_l + a_r)`` with ``a = (v² + ε²)^((1-n)/2)``; written with the exponent's
    magnitude so that n > 1 gives no infinities. f = 1/2 when both regularised speeds are 0.
    Floats give a float (the odometry, once per control step); numpy arrays give an array of
    their broadcast shape (the diagnosis, over whole logs): the same arithmetic either way.
    """
    n, eps = check_endo_n(n), _check_eps(speed_eps_mps)
    half_power = 0.5 * abs(1.0 - n)
    a_l = (v_l * v_l + eps * eps) ** half_power
    a_r = (v_r * v_r + eps * eps) ** half_power
    total = a_l + a_r
    num = a_l if n <= 1.0 else a_r
    if isinstance(total, np.ndarray):
        return np.where(total > 0.0, num / np.where(total > 0.0, total, 1.0), 0.5)
    return num / total if total > 0.0 else 0.5


def endo_slip_velocities(
    v_l: float,
    v_r: float,
    yaw_rate: float,
    tread_m: float,
    n: float,
    speed_eps_mps: float = DEFAULT_SPEED_EPS_MPS,
) -> tuple[float, float]:
    """Slip velocities ``s = α v`` of the tracks from Eq. 7-8 in closed form [m/s].

    Parameters
    ----------
    v_l, v_r : float
        Input (encoder) track speeds [m/s].
    yaw_rate : float
        Measured yaw rate ω (gyro) [rad/s].
    tread_m : float
        Tread 2d [m].
    n : float
        Endo's exponent [-] (Yamauchi: 0.824 on a hard floor).
    speed_eps_mps : float
        Regularising speed ε [m/s] (module docstring); 0 gives the exact Eq. 8.

    Returns
    -------
    s_l, s_r : float
        ``s_l = f c``, ``s_r = -(1 - f) c`` with ``c = 2d ω - (v_r - v_l)``.
    """
    share = endo_left_share(v_l, v_r, n, speed_eps_mps)
    mismatch = check_tread(tread_m) * yaw_rate - (v_r - v_l)
    return share * mismatch, -(1.0 - share) * mismatch


def slip_ratio_from_slip_velocity(
    slip_velocity: float, v: float, speed_eps_mps: float = DEFAULT_SPEED_EPS_MPS
) -> float:
    """Regularised slip ratio ``α = s v / (v² + ε²)`` [-]; NaN only if ε = 0 and v = 0."""
    eps = _check_eps(speed_eps_mps)
    den = v * v + eps * eps
    return slip_velocity * v / den if den > 0.0 else math.nan


def endo_slip_ratios(
    v_l: float,
    v_r: float,
    yaw_rate: float,
    tread_m: float,
    n: float,
    speed_eps_mps: float = DEFAULT_SPEED_EPS_MPS,
) -> tuple[float, float]:
    """Slip ratios α_l, α_r solving Eq. 7-8 for a measured yaw rate [-].

    Same arguments as :func:`endo_slip_velocities`; the ratios are divided out with
    :func:`slip_ratio_from_slip_velocity`.
    """
    s_l, s_r = endo_slip_velocities(v_l, v_r, yaw_rate, tread_m, n, speed_eps_mps)
    return (
        slip_ratio_from_slip_velocity(s_l, v_l, speed_eps_mps),
        slip_ratio_from_slip_velocity(s_r, v_r, speed_eps_mps),
    )


def endo_n_for_direction(v_l: float, v_r: float, n: float,
                         n_clockwise: float | None) -> float:
    """Endo's exponent of a step turning the way the track speeds command [-]: ``n_clockwise``
    when the right track is slower (v_r < v_l, a clockwise turn forwards or backwards), else
    ``n``; ``n`` alone when ``n_clockwise`` is None.

    The switch is continuous in the odometry: at v_l = v_r the left share is 1/2 for any n
    (:func:`endo_left_share`), so the step's slips do not jump where the direction changes.
    """
    return n_clockwise if n_clockwise is not None and v_r < v_l else n


class EndoOdometry(Gyrodometry):
    """Gyrodometry with Endo's longitudinal slip compensation and β = 0 (Yamauchi Eq. 1-8).

    Each step takes the track speeds ``v = Δs / dt`` and gyro rate ``ω = Δθ / dt``, solves the
    slip velocities with :func:`endo_slip_velocities` and moves the body by
    ``Δx = (Δs_l + Δs_r)/2 - (s_l + s_r) dt / 2`` (Eq. 1) along the gyro heading. With no slip
    (gyro rate equal to the encoder rate) this is dead reckoning.

    Parameters
    ----------
    geometry : OdometryGeometry
        Sprocket radius, tread (``track_width_m`` = 2d) and encoder layout.
    n : float
        Endo's exponent [-], > 0 (:func:`.identification.fit_endo_n`); with ``n_clockwise``,
        the exponent of counter-clockwise steps only.
    speed_eps_mps : float
        Regularising track speed ε [m/s], >= 0 (module docstring).
    n_clockwise : float or None
        Endo's exponent of clockwise steps (right track slower than the left, v_r < v_l) [-],
        > 0; None (default): ``n`` for both, as Eq. 8. On a slope the tracks slip differently
        turning the nose uphill and downhill, which one n cannot express
        (:func:`endo_n_for_direction`).

    Notes
    -----
    ``PoseEstimate.extras`` holds ``alpha_l``, ``alpha_r`` [-] and ``slip_velocity_l_mps``,
    ``slip_velocity_r_mps`` [m/s] of the step.
    """

    def __init__(
        self,
        geometry: OdometryGeometry,
        n: float,
        *,
        speed_eps_mps: float = DEFAULT_SPEED_EPS_MPS,
        n_clockwise: float | None = None,
    ) -> None:
        super().__init__(geometry)
        self.n = check_endo_n(n)
        self.n_clockwise = None if n_clockwise is None else check_endo_n(n_clockwise)
        self.speed_eps_mps = _check_eps(speed_eps_mps)

    def slip_velocities(self, v_l: float, v_r: float, yaw_rate: float) -> tuple[float, float]:
        """The step's track slip velocities ``s_l, s_r`` [m/s] from the encoder speeds and the
        gyro rate: Eq. 7-8 in closed form (:func:`endo_slip_velocities`) with the exponent of
        the step's turning direction."""
        n = endo_n_for_direction(v_l, v_r, self.n, self.n_clockwise)
        return endo_slip_velocities(v_l, v_r, yaw_rate, self.geometry.track_width_m, n,
                                    self.speed_eps_mps)

    def _translation(
        self, d_left: float, d_right: float, dyaw: float, dt: float, frame: SensorFrame
    ) -> tuple[float, float, dict]:
        v_l, v_r = d_left / dt, d_right / dt
        eps = self.speed_eps_mps
        s_l, s_r = self.slip_velocities(v_l, v_r, dyaw / dt)
        forward_m = 0.5 * (d_left + d_right) - 0.5 * (s_l + s_r) * dt  # Eq. 1
        extras = {
            "alpha_l": slip_ratio_from_slip_velocity(s_l, v_l, eps),
            "alpha_r": slip_ratio_from_slip_velocity(s_r, v_r, eps),
            "slip_velocity_l_mps": s_l,
            "slip_velocity_r_mps": s_r,
        }
        return forward_m, 0.0, extras
