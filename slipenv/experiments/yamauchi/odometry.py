"""Replaying the rotation runs' sensor frames through the odometries (Yamauchi §2.4, Fig. 6):
gyrodometry, Endo's odometry and slip-compensated odometry, scored against the truth."""

from __future__ import annotations

import numpy as np

from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.skid_steer import EndoOdometry, SlipCompensatedOdometry

from .rotation import RotationRun
from .settings import ORACLE_MAX_SLIP_ANGLE_RAD


class TrueSlipAngle:
    """An oracle in Eq. 9's slot: predicts whatever true slip angle the caller last set.

    Only the experiment's *limit* measurements use it, to separate what the slip-angle
    regression costs from what Endo's slip ratios cost; no estimator or env observation sees
    ground truth.
    """

    def __init__(self) -> None:
        self.beta_rad = 0.0

    def predict(self, roll, angular_displacement, rotation_radius):
        return np.full(np.shape(roll), self.beta_rad)


def replay(estimator, run: RotationRun,
           oracle: TrueSlipAngle | None = None) -> tuple[np.ndarray, list[dict]]:
    """Feed a run's sensor frames to ``estimator`` from the true start pose: (k, 2) xy, extras.

    With ``oracle`` (the estimator's β model), it is set to each frame's true slip angle
    before that frame is fed.
    """
    x, y, yaw = run.pose[0]
    est = estimator.reset(x, y, yaw, run.frames[0])
    xy, extras = [(est.x_m, est.y_m)], [dict(est.extras)]
    for k, frame in enumerate(run.frames[1:], start=1):
        if oracle is not None:
            oracle.beta_rad = float(run.slip_angle[k])
        est = estimator.update(frame)
        xy.append((est.x_m, est.y_m))
        extras.append(dict(est.extras))
    return np.array(xy), extras


def true_beta_odometry(geom, n: float, oracle: TrueSlipAngle) -> SlipCompensatedOdometry:
    """Slip-compensated odometry with the true slip angle in place of Eq. 9 (a limit)."""
    return SlipCompensatedOdometry(geom, n, oracle, max_slip_angle_rad=ORACLE_MAX_SLIP_ANGLE_RAD)


def odometry_errors(runs: list[RotationRun], geom, n_by_tilt: dict[float, float],
                    model) -> dict[str, np.ndarray]:
    """Squared position errors [m²] pooled over ``runs``: the three odometries, and the limit.

    ``slip_compensated_true_beta`` is the slip-compensated odometry with the true slip angle in
    place of Eq. 9: what a perfect regression would leave, i.e. the cost of Endo's slip ratios.
    """
    out: dict[str, list] = {"gyrodometry": [], "endo": [], "slip_compensated": [],
                            "slip_compensated_true_beta": []}
    for run in runs:
        n = n_by_tilt[run.tilt_deg]
        oracle = TrueSlipAngle()
        for key, est in (("gyrodometry", Gyrodometry(geom)), ("endo", EndoOdometry(geom, n)),
                         ("slip_compensated", SlipCompensatedOdometry(geom, n, model)),
                         ("slip_compensated_true_beta", true_beta_odometry(geom, n, oracle))):
            xy, _ = replay(est, run, oracle if key.endswith("true_beta") else None)
            out[key].append(np.sum((xy - run.pose[:, :2]) ** 2, axis=1))
    return {k: np.concatenate(v) for k, v in out.items()}
