"""The offline filter passes over a recorded drive (Lindgren §5: the four EKF schemes and,
as only a simulation can, an oracle that knows the true soil)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from slipenv.contracts import wrap_angles
from slipenv.estimators.lindgren import LindgrenEKF

from .recording import Recording, quiet_estimator
from .settings import HEADLINE, Variant


@dataclass
class FilterRun:
    """One offline filter pass.

    Attributes
    ----------
    est : np.ndarray, shape (K, 3)
        Estimated (x [m], y [m], yaw [rad]) at every frame.
    P : np.ndarray, shape (K, 3, 3)
        Their covariances.
    ekf : LindgrenEKF
        The filter after the pass (its innovation history and skip counts).
    """

    est: np.ndarray
    P: np.ndarray
    ekf: LindgrenEKF


def run_filter(rec: Recording, name: str, cut_s: float = math.inf,
               inertial: bool = True,
               variants: Mapping[str, Variant] = HEADLINE.variants) -> FilterRun:
    """Run one filter (``"scheme1"``..``"scheme4"``, ``"oracle"`` or a name of ``variants``,
    the block's :attr:`~.settings.Setting.variants`) over the recorded frames.

    Bearings after ``cut_s`` [s] are removed; ``inertial=False`` removes the gyro,
    accelerometer and inclinometer readings (laser and odometers only). The no-slip schemes
    (2, 3) use the recording's measured radius if it has one.
    """
    variant = variants[name] if name in variants else Variant(name)
    scheme = variant.scheme
    params = dataclasses.replace(rec.params, **variant.noise)
    geometry = rec.geometry
    if (scheme in ("scheme2", "scheme3") and rec.no_slip_radius_m is not None
            and not variant.nominal_radius):
        geometry = dataclasses.replace(geometry, wheel_radius_m=rec.no_slip_radius_m)
    oracle = rec.oracle if scheme == "oracle" else None
    if oracle is not None and variant.secant_k_s:
        if rec.k_s_secant_nm is None:
            raise ValueError(f"{name}: the recording has no calibration (secant k_s)")
        oracle = dataclasses.replace(oracle, k_s=(rec.k_s_secant_nm,) * 2)
    ekf = LindgrenEKF(geometry, scheme=4 if oracle else int(scheme[-1]), params=params,
                      beacons_xy=rec.beacons_xy, oracle=oracle)
    none = np.zeros(0)
    est, cov = [], []
    with quiet_estimator():
        for k, frame in enumerate(rec.frames):
            if frame.t_s > cut_s:
                frame = dataclasses.replace(frame, beacon_bearings_rad=none, beacon_times_s=none)
            if not inertial:
                frame = dataclasses.replace(frame, gyro_z_rad_s=math.nan, acc_x_mps2=math.nan,
                                            acc_y_mps2=math.nan, roll_rad=math.nan,
                                            pitch_rad=math.nan)
            e = ekf.reset(*rec.truth[0], frame) if k == 0 else ekf.update(frame)
            est.append((e.x_m, e.y_m, e.yaw_rad))
            cov.append(e.cov)
    return FilterRun(np.array(est), np.array(cov), ekf)


def pose_errors(run: FilterRun, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position error [m], shape (K,), and (x, y, yaw) error truth - estimate, shape (K, 3),
    the yaw error wrapped to (-π, π]."""
    err = truth - run.est
    err[:, 2] = wrap_angles(err[:, 2])
    return np.hypot(err[:, 0], err[:, 1]), err


def soil_estimate(run: FilterRun) -> dict:
    """The filter's final soil states: effective radii R_w [m] and k_s [N m], left/right."""
    x = run.ekf.estimate().extras
    return {"R_w_m": [x["R_wl_m"], x["R_wr_m"]], "k_s": [x["k_sl"], x["k_sr"]]}
