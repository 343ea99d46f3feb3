"""Path following with slip-angle feed-forward (Yamauchi §3, Eq. 9-10).

Yamauchi's law (after Iida & Yuta 1991) commands the *rate of change* of the angular velocity:

    conventional (Eq. 9):    dω/dt = -(k_η η + k_φ φ + k_ω ω)
    feed-forward (Eq. 10):   dω/dt = -(k_η η + k_φ (φ - β) + k_ω ω)

with η the distance from the target path, φ the heading error, ω the angular velocity relative
to the path's reference and β the slip angle; "the robot moves to maintain an orientation error
equal to the slip angle on the target path".

Generalisation and conventions used here (departures from the paper, and why):

* Any path, not only circles: ω is the yaw rate relative to the path's reference v·κ
  (κ the projection's curvature), and the law is integrated at ``dt_s`` to a relative yaw-rate
  command u; the command is ω_cmd = v_ref·κ + u. On a circle this is the paper's law; on a path
  whose curvature changes, the v_ref·κ term stops every curvature step from becoming an error.
* Sign of β: the observation's β̂ is the angle from body x to the velocity (the paper's Eq. 2,
  V_y = V_x tan β), and φ = yaw - path heading. Staying on the path then needs the course
  yaw + β along the path, i.e. φ = -β, so the feed-forward term that achieves the paper's
  stated aim is k_φ (φ + β) in these conventions. (Eq. 10's "φ - β" holds if φ or β is
  measured the other way round; the paper does not define their signs.)
* η is the signed cross-track error, > 0 left of the path, so η' ≈ v sin(φ + β).

Linearised about the path (small φ, u = ω - vκ) the error dynamics are
η' = v (φ + β), φ' = u, u' = -(k_η η + k_φ (φ + β_ff) + k_ω u), so the characteristic
polynomial is s³ + k_ω s² + k_φ s + k_η v: stable iff all gains > 0 and k_ω k_φ > k_η v
(Routh-Hurwitz). With a constant slip β and no feed-forward the steady state is
η = k_φ β / k_η (on a straight); with β̂ = β it is η = 0.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from slipenv.contracts.observation import (
    OBS_CROSS_TRACK,
    OBS_CURVATURE,
    OBS_HEADING_ERROR,
    OBS_REF_SPEED,
    OBS_SLIP_ANGLE,
    OBS_SPEED,
    OBS_YAW_RATE,
)

from .base import Controller

POLE_DT_LIMIT = 0.5  # warn when the fastest continuous pole |λ| exceeds this / dt_s


def is_hurwitz(coefficients: np.ndarray) -> bool:
    """True if every root of the polynomial (highest power first) has a negative real part."""
    coefficients = np.asarray(coefficients, dtype=float)
    return bool(np.all(np.real(np.roots(coefficients)) < 0.0))


class YamauchiController(Controller):
    """Yamauchi §3 path-following law with optional slip-angle feed-forward.

    Parameters
    ----------
    v_max_mps, omega_max_rps, dt_s : float
        Action scaling [m/s], [rad/s] and control period [s] (see :class:`Controller`).
    k_eta : float
        Cross-track gain k_η [1/(m s²)].
    k_phi : float
        Heading gain k_φ [1/s²].
    k_omega : float
        Relative yaw-rate gain k_ω [1/s].
    use_feedforward : bool
        True: Eq. 10 with β = ``obs[6]``; False: the conventional Eq. 9 (β = 0).

    Notes
    -----
    Default gains place a triple pole at -1 rad/s for v = 1 m/s (``from_poles(1.0, 1.0)``):
    k_ω = 3, k_φ = 3, k_η = 1. They stay stable up to v = k_ω k_φ / k_η = 9 m/s, and give a
    feedback-only steady offset of k_φ/k_η = 3 m per rad of slip. For slow vehicles (Yamauchi's
    5 cm/s) use :meth:`from_poles`, since the η loop's bandwidth scales with k_η v.

    The forward speed command is the path's reference speed ``obs[10]``. The integrated
    command u is clipped so that |ω_cmd| <= omega_max_rps (anti-windup).
    """

    state_dim = 1

    def __init__(self, v_max_mps: float, omega_max_rps: float, dt_s: float, k_eta: float = 1.0,
                 k_phi: float = 3.0, k_omega: float = 3.0, use_feedforward: bool = True) -> None:
        super().__init__(v_max_mps, omega_max_rps, dt_s)
        for name, value in (("k_eta", k_eta), ("k_phi", k_phi), ("k_omega", k_omega)):
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {value!r}")
        self.k_eta, self.k_phi, self.k_omega = float(k_eta), float(k_phi), float(k_omega)
        self.use_feedforward = bool(use_feedforward)
        poly = self.characteristic_polynomial(self.v_max_mps)
        if not is_hurwitz(poly):
            warnings.warn(f"Yamauchi gains are unstable at v_max = {self.v_max_mps} m/s: need "
                          f"k_omega*k_phi > k_eta*v, got {self.k_omega * self.k_phi:.3g} <= "
                          f"{self.k_eta * self.v_max_mps:.3g}", RuntimeWarning, stacklevel=2)
        fastest = float(np.max(np.abs(np.roots(poly))))
        if fastest * self.dt_s > POLE_DT_LIMIT:
            warnings.warn(f"fastest closed-loop pole {fastest:.3g} rad/s is too fast for "
                          f"dt_s = {self.dt_s} s (|λ| dt > {POLE_DT_LIMIT}); the discrete loop "
                          "may oscillate", RuntimeWarning, stacklevel=2)

    @classmethod
    def from_poles(cls, pole_rps: float, speed_mps: float, *, v_max_mps: float,
                   omega_max_rps: float, dt_s: float, use_feedforward: bool = True,
                   ) -> YamauchiController:
        """Gains placing a triple closed-loop pole at ``-pole_rps`` for ``speed_mps``.

        (s + p)³ = s³ + 3p s² + 3p² s + p³, so k_ω = 3p, k_φ = 3p², k_η = p³ / v. The limits,
        ``dt_s`` and ``use_feedforward`` are the constructor's.
        """
        for name, value in (("pole_rps", pole_rps), ("speed_mps", speed_mps)):
            if not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {value!r}")
        p = float(pole_rps)
        return cls(v_max_mps, omega_max_rps, dt_s, k_eta=p**3 / speed_mps, k_phi=3.0 * p**2,
                   k_omega=3.0 * p, use_feedforward=use_feedforward)

    def characteristic_polynomial(self, speed_mps: float) -> np.ndarray:
        """Coefficients [1, k_ω, k_φ, k_η v] of the linearised closed loop at ``speed_mps``."""
        return np.array([1.0, self.k_omega, self.k_phi, self.k_eta * speed_mps])

    def steady_cross_track_m(self, slip_angle_rad: float) -> float:
        """Closed-form steady cross-track error [m] on a straight under constant slip β.

        η = k_φ (β - β̂) / k_η, with β̂ = β when the feed-forward is on.
        """
        return 0.0 if self.use_feedforward else self.k_phi * slip_angle_rad / self.k_eta

    def initial_state(self, obs: np.ndarray) -> np.ndarray:
        """Start from the measured relative yaw rate ω - vκ (bumpless when already turning)."""
        rel = obs[:, OBS_YAW_RATE] - obs[:, OBS_SPEED] * obs[:, OBS_CURVATURE]
        return rel[:, None].copy()

    def command(self, obs: np.ndarray, state: np.ndarray,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        eta = obs[:, OBS_CROSS_TRACK]  # η: distance from the path, > 0 left [m]
        phi = obs[:, OBS_HEADING_ERROR]  # φ: yaw - path heading [rad]
        beta = obs[:, OBS_SLIP_ANGLE] if self.use_feedforward else 0.0  # β̂ feed-forward [rad]
        kappa = obs[:, OBS_CURVATURE]
        v_ref = obs[:, OBS_REF_SPEED]
        omega_rel = obs[:, OBS_YAW_RATE] - obs[:, OBS_SPEED] * kappa  # ω relative to path [rad/s]
        omega_dot = -(self.k_eta * eta + self.k_phi * (phi + beta) + self.k_omega * omega_rel)
        feedforward = v_ref * kappa  # reference yaw rate of the path at the commanded speed
        u = state[:, 0] + omega_dot * self.dt_s
        u = np.clip(u, -self.omega_max_rps - feedforward, self.omega_max_rps - feedforward)
        return v_ref, feedforward + u, u[:, None]
