"""Pure pursuit path tracking (Coulter 1992), adapted to a body-twist (unicycle) command.

PythonRobotics style: steer along the circle through the vehicle and a target point a
look-ahead distance ahead on the path,

    curvature = 2 sin(α) / l_d,    ω = v · curvature,

α the angle of the target from the vehicle heading, l_d the distance to it.

Look-ahead from the observation alone: the target is the point ``L_f = k_la v_ref + L_min``
along the path from the projection, on the osculating arc of the observed curvature
(:mod:`controllers.local_path`). This is exact on straights and arcs (on a circle of radius R
the commanded curvature is exactly 1/R when on the path, so there is no steady offset) and
ignores curvature changes within ``L_f`` (it turns into a new arc only once the projection
reaches it).
"""

from __future__ import annotations

import numpy as np

from slipenv.contracts.observation import (
    OBS_CROSS_TRACK,
    OBS_CURVATURE,
    OBS_HEADING_ERROR,
    OBS_REF_SPEED,
)

from .base import Controller
from .local_path import arc_point


class PurePursuitController(Controller):
    """Pure pursuit on the observation's local path.

    Parameters
    ----------
    v_max_mps, omega_max_rps, dt_s : float
        Action scaling [m/s], [rad/s] and control period [s] (see :class:`Controller`).
    lookahead_gain_s : float
        k_la: look-ahead grows with speed, L_f = k_la v_ref + L_min [s]. Default 1.0 s.
    lookahead_min_m : float
        L_min: look-ahead at standstill [m]. Default 0.5 m.

    Notes
    -----
    Linearised on a straight, the cross-track error decays with time constant about
    L_f / (2 v): 0.75 s at 1 m/s with the defaults, slow enough for a 20 Hz loop.
    """

    def __init__(self, v_max_mps: float, omega_max_rps: float, dt_s: float,
                 lookahead_gain_s: float = 1.0, lookahead_min_m: float = 0.5) -> None:
        super().__init__(v_max_mps, omega_max_rps, dt_s)
        for name, value in (("lookahead_gain_s", lookahead_gain_s),
                            ("lookahead_min_m", lookahead_min_m)):
            if not (np.isfinite(value) and value > 0.0):
                raise ValueError(f"{name} must be finite and > 0, got {value!r}")
        self.lookahead_gain_s = float(lookahead_gain_s)
        self.lookahead_min_m = float(lookahead_min_m)

    def command(self, obs: np.ndarray, state: np.ndarray,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        v = obs[:, OBS_REF_SPEED]
        e = obs[:, OBS_CROSS_TRACK]  # vehicle at (0, e) in the path frame [m]
        phi = obs[:, OBS_HEADING_ERROR]  # vehicle heading in the path frame [rad]
        lookahead = self.lookahead_gain_s * np.abs(v) + self.lookahead_min_m  # L_f [m]
        tx, ty = arc_point(obs[:, OBS_CURVATURE], lookahead)  # target, path frame
        dx, dy = tx, ty - e
        alpha = np.arctan2(-np.sin(phi) * dx + np.cos(phi) * dy,
                           np.cos(phi) * dx + np.sin(phi) * dy)  # target bearing from heading
        curvature = 2.0 * np.sin(alpha) / np.hypot(dx, dy)  # [1/m]
        return v, v * curvature, state
