"""A kinematic unicycle with optional constant side-slip, closed around a controller.

ẋ = v cos(ψ + β), ẏ = v sin(ψ + β), ψ̇ = ω: the body slides sideways at the slip angle β
(Yamauchi Eq. 2, 5-6), so a controller that holds the heading on the path drifts off it.
The observation is built from the true pose (a perfect estimator) with β̂ given separately.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pytest

from slipenv.contracts.observation import build_observation
from slipenv.controllers.base import Controller
from slipenv.paths import Path

DT_S = 0.05  # [s] control period (20 Hz, as the env)
SUBSTEPS = 10  # integration substeps per control period
V_MAX_MPS = 2.0  # [m/s]
OMEGA_MAX_RPS = 1.5  # [rad/s]


@dataclass
class Trace:
    """Closed-loop history, one entry per control step."""

    t_s: np.ndarray
    cross_track_m: np.ndarray
    heading_error_rad: np.ndarray
    s_m: np.ndarray
    actions: np.ndarray

    def steady(self, fraction: float = 0.3) -> np.ndarray:
        """Cross-track errors over the last ``fraction`` of the run [m]."""
        return self.cross_track_m[int(len(self.cross_track_m) * (1.0 - fraction)):]


def simulate(controller: Controller, path: Path, *, duration_s: float, beta_rad: float = 0.0,
             beta_hat_rad: float | None = None, offset_m: float = 0.0,
             heading_offset_rad: float = 0.0) -> Trace:
    """Run ``controller`` on the unicycle along ``path`` from its start pose, shifted
    ``offset_m`` to the left and rotated by ``heading_offset_rad``."""
    x, y, psi = path.start_pose()
    x, y = x - offset_m * math.sin(psi), y + offset_m * math.cos(psi)
    psi += heading_offset_rad
    beta_hat = beta_rad if beta_hat_rad is None else beta_hat_rad
    v = omega = 0.0
    s_hint = None
    controller.reset()
    rows = []
    for k in range(int(round(duration_s / DT_S))):
        proj = path.project(x, y, s_hint)
        s_hint = proj.s
        obs = build_observation(x, y, psi, v, omega, proj, slip_angle_est_rad=beta_hat)
        action = controller.act(obs)
        rows.append((k * DT_S, proj.cross_track_m, obs[8], proj.s, *action))
        v = float(action[0]) * controller.v_max_mps
        omega = float(action[1]) * controller.omega_max_rps
        h = DT_S / SUBSTEPS
        for _ in range(SUBSTEPS):
            mid = psi + 0.5 * omega * h + beta_rad
            x, y, psi = x + v * h * math.cos(mid), y + v * h * math.sin(mid), psi + omega * h
    a = np.asarray(rows)
    return Trace(a[:, 0], a[:, 1], a[:, 2], a[:, 3], a[:, 4:6])


@pytest.fixture
def run():
    """The closed-loop simulator as a fixture (tests call ``run(controller, path, ...)``)."""
    return simulate


@pytest.fixture
def scaling() -> dict[str, float]:
    """Controller constructor arguments matching the simulated vehicle and control period."""
    return {"v_max_mps": V_MAX_MPS, "omega_max_rps": OMEGA_MAX_RPS, "dt_s": DT_S}
