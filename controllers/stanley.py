"""Stanley path tracking (Thrun et al. 2006), adapted to a body-twist (unicycle) command.

PythonRobotics style: the front axle of a bicycle steers by the heading error plus a term
that drives its cross-track error to zero,

    δ = θ_e + atan2(-k e_fa, k_soft + v),    ω = v tan(δ) / L.

For a unicycle the "front axle" is a virtual point a wheelbase ``L`` ahead of the reference
point: commanding ω = v tan(δ) / L makes that point move in direction yaw + δ, exactly like a
bicycle's front wheel, so Stanley's convergence argument carries over to it.

From the observation alone, the front point's cross-track error e_fa and the path heading
at its foot come from the osculating arc (:mod:`controllers.local_path`). Because Stanley puts
the *front* point on the path, on a circle of radius R the reference point runs about
L² / (2R) inside it (0.03 m for L = 0.5 m, R = 4 m).
"""

from __future__ import annotations

import numpy as np

from slipenv.contracts import wrap_angle
from slipenv.contracts.observation import (
    OBS_CROSS_TRACK,
    OBS_CURVATURE,
    OBS_HEADING_ERROR,
    OBS_REF_SPEED,
)

from .base import Controller
from .local_path import arc_heading, arc_offset


class StanleyController(Controller):
    """Stanley steering of a virtual front axle.

    Parameters
    ----------
    v_max_mps, omega_max_rps, dt_s : float
        Action scaling [m/s], [rad/s] and control period [s] (see :class:`Controller`).
    k_e : float
        Cross-track gain k [1/s]: near the path the front point's error decays as e^{-k t}.
        Default 1.0 1/s.
    wheelbase_m : float
        Distance L from the reference point to the virtual front axle [m]. Default 0.5 m.
    k_soft_mps : float
        Softening speed k_soft [m/s] keeping atan2(k e, k_soft + v) sane near standstill.
        Default 0.1 m/s.
    max_steer_rad : float
        Virtual steering limit [rad]. Default 0.7 rad (40°).
    """

    def __init__(self, v_max_mps: float, omega_max_rps: float, dt_s: float, k_e: float = 1.0,
                 wheelbase_m: float = 0.5, k_soft_mps: float = 0.1,
                 max_steer_rad: float = 0.7) -> None:
        super().__init__(v_max_mps, omega_max_rps, dt_s)
        for name, value in (("k_e", k_e), ("wheelbase_m", wheelbase_m),
                            ("k_soft_mps", k_soft_mps), ("max_steer_rad", max_steer_rad)):
            if not (np.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {value!r}")
        if max_steer_rad >= 0.5 * np.pi:
            raise ValueError(f"max_steer_rad must be < pi/2, got {max_steer_rad!r}")
        self.k_e, self.wheelbase_m = float(k_e), float(wheelbase_m)
        self.k_soft_mps, self.max_steer_rad = float(k_soft_mps), float(max_steer_rad)

    def command(self, obs: np.ndarray, state: np.ndarray,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        v = obs[:, OBS_REF_SPEED]
        kappa = obs[:, OBS_CURVATURE]
        phi = obs[:, OBS_HEADING_ERROR]  # yaw in the path frame [rad]
        L = self.wheelbase_m
        px = L * np.cos(phi)  # virtual front axle, path frame [m]
        py = obs[:, OBS_CROSS_TRACK] + L * np.sin(phi)
        e_fa = arc_offset(kappa, px, py)  # front-axle cross-track, > 0 left [m]
        theta_e = wrap_angle(arc_heading(kappa, px, py) - phi)  # heading error at the front
        delta = theta_e + np.arctan2(-self.k_e * e_fa, self.k_soft_mps + v)  # steering [rad]
        delta = np.clip(delta, -self.max_steer_rad, self.max_steer_rad)
        return v, v * np.tan(delta) / L, state
