"""Slip identification from the rotation runs (Yamauchi §2.2-2.4): the true track slips and
slip angle, Endo's n per tilt (Eq. 8, Fig. 4) and the Eq. 9 regressors (Fig. 5)."""

from __future__ import annotations

import numpy as np

from slipenv.estimators.skid_steer import SlipCompensatedOdometry
from slipenv.estimators.skid_steer.identification import SlipRun, fit_endo_n, true_slips

from .odometry import replay
from .rotation import RotationRun
from .settings import Settings


class NoSlipAngle:
    """A β model that predicts 0: runs SlipCompensatedOdometry just for its regressors."""

    def predict(self, roll, angular_displacement, rotation_radius):
        return np.zeros(np.shape(roll))


def _window(k: int, w: int) -> tuple[np.ndarray, np.ndarray]:
    idx = np.arange(k)
    return np.clip(idx - w // 2, 0, k - 1), np.clip(idx + w // 2, 0, k - 1)


def run_slips(run: RotationRun, geom, w: int) -> dict[str, np.ndarray]:
    """Input track speeds (encoders) and true slips of a run, as derivatives over ``w`` steps.

    Like the paper's motion-capture derivatives, both the encoder speeds and the true body
    velocity are taken over the same centred window (slips by Yamauchi Eq. 1-7).
    """
    angles = np.array([f.enc_counts for f in run.frames], dtype=float) / geom.counts_per_rad
    k = len(run.t_s)
    i0, i1 = _window(k, w)
    dt = np.maximum(run.t_s[i1] - run.t_s[i0], 1e-9)
    left = angles[:, list(geom.left)].mean(axis=1)
    right = angles[:, list(geom.right)].mean(axis=1)
    omega_l, omega_r = (left[i1] - left[i0]) / dt, (right[i1] - right[i0]) / dt
    box = np.ones(w) / w
    smooth = [np.convolve(np.pad(x, w // 2, mode="edge"), box, mode="valid")[:k]
              for x in (run.v_body[:, 0], run.v_body[:, 1], run.yaw_rate)]
    alpha_l, alpha_r, beta = true_slips(omega_l, omega_r, geom.wheel_radius_m, smooth[0],
                                        smooth[2], smooth[1], geom.track_width_m)
    r = geom.wheel_radius_m
    return {"v_l": r * omega_l, "v_r": r * omega_r, "alpha_l": alpha_l, "alpha_r": alpha_r,
            "beta": beta, "speed": np.hypot(smooth[0], smooth[1])}


def fit_n(runs: list[RotationRun], geom, w: int):
    """Endo's n (Eq. 8) by log-log least squares over the samples of ``runs``: (fit, samples)."""
    s = [run_slips(r, geom, w) for r in runs]
    cat = {k: np.concatenate([x[k] for x in s]) for k in ("v_l", "v_r", "alpha_l", "alpha_r")}
    return fit_endo_n(cat["v_l"], cat["v_r"], cat["alpha_l"], cat["alpha_r"]), cat


def slip_run(run: RotationRun, geom, n: float, cfg: Settings,
             n_clockwise: float | None = None) -> SlipRun:
    """Eq. 9 regressors computed online exactly as the odometry does (with Endo's ``n``, and
    ``n_clockwise`` on clockwise steps when given), and the true β."""
    odometry = SlipCompensatedOdometry(geom, n, NoSlipAngle(), n_clockwise=n_clockwise)
    _, extras = replay(odometry, run)
    x = np.array([[e["roll_rad"], e["angular_displacement_rad"], e["rotation_radius_m"]]
                  for e in extras[1:]])
    truth = run_slips(run, geom, cfg.smooth_steps)
    keep = truth["speed"][1:] >= cfg.min_speed_mps
    return SlipRun(run.name, x[keep], truth["beta"][1:][keep])
