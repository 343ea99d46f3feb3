"""Replaying the rotation runs' sensor frames through the odometries (Yamauchi §2.4, Fig. 6):
gyrodometry, Endo's odometry and slip-compensated odometry, scored against the truth."""

from __future__ import annotations

import math

import numpy as np

from slipenv.contracts import wrap_angle
from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.skid_steer import EndoOdometry, SlipCompensatedOdometry

from .rotation import RotationRun
from .settings import ORACLE_MAX_SLIP_ANGLE_RAD


class TrueSlipAngle:
    """An oracle in Eq. 9's slot: predicts whatever true slip angle the caller last set, and
    holds the step's true forward ground speed for :class:`TrueSlipOdometry`.

    Only the experiment's *limit* measurements use it, to separate what the slip-angle
    regression costs from what Endo's slip ratios cost; no estimator or env observation sees
    ground truth.
    """

    def __init__(self) -> None:
        self.beta_rad = 0.0
        self.forward_mps = 0.0

    def observe(self, run: RotationRun, k: int) -> None:
        """Take the truth of the step from frame k-1 to frame k of ``run``: the slip angle at
        frame k and the forward speed V_x of the step, the true displacement projected on the
        true heading at mid-step."""
        self.beta_rad = float(run.slip_angle[k])
        (x0, y0, yaw0), (x1, y1, yaw1) = run.pose[k - 1], run.pose[k]
        yaw = yaw0 + 0.5 * wrap_angle(yaw1 - yaw0)
        dt = float(run.t_s[k] - run.t_s[k - 1])
        self.forward_mps = ((x1 - x0) * math.cos(yaw) + (y1 - y0) * math.sin(yaw)) / dt

    def predict(self, roll, angular_displacement, rotation_radius):
        return np.full(np.shape(roll), self.beta_rad)


class TrueSlipOdometry(SlipCompensatedOdometry):
    """Slip-compensated odometry with the true track slips in place of Endo's Eq. 7-8 (a
    limit): the slip velocities keep Eq. 7 with the gyro rate, and their sum is what the
    true forward speed makes it by Eq. 1, ``s_l + s_r = v_l + v_r - 2 V_x``."""

    def __init__(self, geometry, n: float, beta_model, oracle: TrueSlipAngle, **kw) -> None:
        super().__init__(geometry, n, beta_model, **kw)
        self.oracle = oracle

    def slip_velocities(self, v_l: float, v_r: float, yaw_rate: float) -> tuple[float, float]:
        differential = self.geometry.track_width_m * yaw_rate - (v_r - v_l)  # Eq. 7
        common = v_l + v_r - 2.0 * self.oracle.forward_mps  # Eq. 1
        return 0.5 * (common + differential), 0.5 * (common - differential)


def replay(estimator, run: RotationRun,
           oracle: TrueSlipAngle | None = None) -> tuple[np.ndarray, list[dict]]:
    """Feed a run's sensor frames to ``estimator`` from the true start pose: (k, 2) xy, extras.

    With ``oracle`` (the estimator's β model or slips), it observes each step's truth
    before that step's frame is fed.
    """
    x, y, yaw = run.pose[0]
    est = estimator.reset(x, y, yaw, run.frames[0])
    xy, extras = [(est.x_m, est.y_m)], [dict(est.extras)]
    for k, frame in enumerate(run.frames[1:], start=1):
        if oracle is not None:
            oracle.observe(run, k)
        est = estimator.update(frame)
        xy.append((est.x_m, est.y_m))
        extras.append(dict(est.extras))
    return np.array(xy), extras


def true_beta_odometry(geom, n: float, oracle: TrueSlipAngle,
                       n_clockwise: float | None = None) -> SlipCompensatedOdometry:
    """Slip-compensated odometry with the true slip angle in place of Eq. 9 (a limit)."""
    return SlipCompensatedOdometry(geom, n, oracle, max_slip_angle_rad=ORACLE_MAX_SLIP_ANGLE_RAD,
                                   n_clockwise=n_clockwise)


def odometry_errors(runs: list[RotationRun], geom, n_by_tilt: dict[float, float],
                    model, n_clockwise_by_tilt: dict[float, float] | None = None
                    ) -> dict[str, np.ndarray]:
    """Squared position errors [m²] pooled over ``runs``: the three odometries, and the limits.

    With ``n_clockwise_by_tilt`` Endo's odometries take ``n_by_tilt`` on counter-clockwise
    steps and it on clockwise ones (:class:`~slipenv.estimators.skid_steer.EndoOdometry`).
    The limits replace what the odometry infers by the truth: ``slip_compensated_true_beta``
    the slip angle (what a perfect regression would leave, i.e. the cost of Endo's slip
    ratios), ``slip_compensated_true_slips`` the track slips (the cost of Eq. 9's β), and
    ``slip_compensated_true_slips_true_beta`` both (what is left is the gyro's heading error).
    """
    keys = ("gyrodometry", "endo", "slip_compensated", "slip_compensated_true_beta",
            "slip_compensated_true_slips", "slip_compensated_true_slips_true_beta")
    out: dict[str, list] = {k: [] for k in keys}
    for run in runs:
        n = n_by_tilt[run.tilt_deg]
        kw = {"n_clockwise": (n_clockwise_by_tilt or {}).get(run.tilt_deg)}
        oracle = TrueSlipAngle()
        estimators = (
            (Gyrodometry(geom), None), (EndoOdometry(geom, n, **kw), None),
            (SlipCompensatedOdometry(geom, n, model, **kw), None),
            (true_beta_odometry(geom, n, oracle, **kw), oracle),
            (TrueSlipOdometry(geom, n, model, oracle), oracle),
            (TrueSlipOdometry(geom, n, oracle, oracle,
                              max_slip_angle_rad=ORACLE_MAX_SLIP_ANGLE_RAD), oracle))
        for key, (est, truth) in zip(keys, estimators, strict=True):
            xy, _ = replay(est, run, truth)
            out[key].append(np.sum((xy - run.pose[:, :2]) ** 2, axis=1))
    return {k: np.concatenate(v) for k, v in out.items()}
