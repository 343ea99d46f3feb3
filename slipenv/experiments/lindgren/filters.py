"""The offline filter passes over a recorded drive (Lindgren §5: the four EKF schemes and,
as only a simulation can, an oracle that knows the true soil)."""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np

from slipenv.contracts import SensorFrame, wrap_angles
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren import LindgrenEKF
from slipenv.estimators.lindgren.models import IA1, IA2

from .recording import Recording, quiet_estimator
from .settings import HEADLINE, LATERAL, LATERAL_FILTERS, Variant

_new = object.__new__
_setattr = object.__setattr__  # a frozen dataclass's own __setattr__ refuses every field


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
    tilt : np.ndarray, shape (K, 2)
        Its pitch and roll states (α1, α2) at every frame [rad].
    """

    est: np.ndarray
    P: np.ndarray
    ekf: LindgrenEKF
    tilt: np.ndarray


def run_filter(rec: Recording, name: str, cut_s: float = math.inf,
               inertial: bool = True,
               variants: Mapping[str, Variant] = HEADLINE.variants) -> FilterRun:
    """Run one filter (``"scheme1"``..``"scheme4"``, ``"oracle"`` or a name of ``variants``,
    the block's :attr:`~.settings.Setting.variants`) over the recorded frames.

    Bearings after ``cut_s`` [s] are removed; ``inertial=False`` removes the gyro,
    accelerometer and inclinometer readings (laser and odometers only). The no-slip schemes
    (2, 3) use the recording's measured radii if it has them (:func:`no_slip_odometry`); the
    slip-model schemes carry the lateral slip gain (:data:`~.settings.LATERAL`) unless the
    variant says otherwise (:attr:`~.settings.Variant.lateral`).
    """
    variant = variants[name] if name in variants else Variant(name)
    scheme = variant.scheme
    with_lateral = (scheme in LATERAL_FILTERS if variant.lateral is None else variant.lateral)
    lateral = LATERAL if with_lateral else {}
    params = dataclasses.replace(rec.params, **{**lateral, **variant.noise})
    geometry, count_scale = rec.geometry, None
    if (scheme in ("scheme2", "scheme3") and rec.no_slip_radii_m is not None
            and not variant.nominal_radius):
        if variant.one_radius:
            assert rec.no_slip_radius_m is not None  # measured with the per-side radii
            geometry = dataclasses.replace(geometry, wheel_radius_m=rec.no_slip_radius_m)
        else:
            radius, count_scale = no_slip_odometry(rec.no_slip_radii_m, geometry)
            geometry = dataclasses.replace(geometry, wheel_radius_m=radius)
    oracle = rec.oracle if scheme == "oracle" else None
    if oracle is not None and variant.secant_k_s:
        if rec.k_s_secant_nm is None:
            raise ValueError(f"{name}: the recording has no calibration (secant k_s)")
        oracle = dataclasses.replace(oracle, k_s=(rec.k_s_secant_nm,) * 2)
    ekf = LindgrenEKF(geometry, scheme=4 if oracle else int(scheme.removeprefix("scheme")),
                      params=params,
                      beacons_xy=rec.beacons_xy, oracle=oracle)
    none = np.zeros(0)
    # what the pass changes in a frame before the cut and after it, besides the counts
    before: dict[str, object] = ({} if inertial else
                                 {"gyro_z_rad_s": math.nan, "acc_x_mps2": math.nan,
                                  "acc_y_mps2": math.nan, "roll_rad": math.nan,
                                  "pitch_rad": math.nan})
    after = {**before, "beacon_bearings_rad": none, "beacon_times_s": none}
    est, cov, tilt = [], [], []
    with quiet_estimator():
        for k, frame in enumerate(rec.frames):
            changes = after if frame.t_s > cut_s else before
            if count_scale is not None:
                changes = {**changes, "enc_counts": frame.enc_counts * count_scale}
            if changes:
                frame = replace_readings(frame, changes)
            e = ekf.reset(*rec.truth[0], frame) if k == 0 else ekf.update(frame)
            est.append((e.x_m, e.y_m, e.yaw_rad))
            cov.append(e.cov)
            tilt.append(ekf.x[IA1:IA2 + 1])
    return FilterRun(np.array(est), np.array(cov), ekf, np.array(tilt))


def replace_readings(frame: SensorFrame, changes: Mapping[str, object]) -> SensorFrame:
    """``dataclasses.replace(frame, **changes)``: the same frame, built by setting the new
    frame's fields at once instead of through ``__init__``.

    :func:`run_filter` changes every frame of a dropout drive for every filter (some 600 000
    frames in a quick run), and ``dataclasses.replace`` walks the fields and sets each through
    ``object.__setattr__`` (~5 µs a frame, five times this). SensorFrame's ``__init__`` only
    sets its fields (no ``__post_init__``), so this gives the same frame; ``changes`` must name
    fields.
    """
    new = _new(SensorFrame)
    _setattr(new, "__dict__", {**frame.__dict__, **changes})
    return new


def no_slip_odometry(radii_m: tuple[float, float],
                     geometry: OdometryGeometry) -> tuple[float, np.ndarray]:
    """One radius and a per-wheel count scale that give a one-radius no-slip filter (Lindgren
    Eq. 15) each wheel's own effective radius.

    The no-slip model holds one R_w; a wheel of radius R_i turning c counts covers
    c R_i / Γ, which is what c R_i / R counts of a wheel of radius R cover. So the counts of
    each side are scaled by R_i / R, with R the mean of the two: the per-wheel odometer
    calibration an operator with one radius in the filter would apply.

    Returns
    -------
    tuple
        (R [m], scale per wheel of the frames' ``enc_counts``, shape (n_wheels,)).
    """
    radius = float(np.mean(radii_m))
    n = 1 + max(geometry.left + geometry.right)
    scale = np.ones(n)
    for side, r in zip((geometry.left, geometry.right), radii_m, strict=True):
        scale[list(side)] = r / radius
    return radius, scale


def pose_errors(run: FilterRun, truth: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Position error [m], shape (K,), and (x, y, yaw) error truth - estimate, shape (K, 3),
    the yaw error wrapped to (-π, π]."""
    err = truth - run.est
    err[:, 2] = wrap_angles(err[:, 2])
    return np.hypot(err[:, 0], err[:, 1]), err


def soil_estimate(run: FilterRun) -> dict:
    """The filter's final soil states: effective radii R_w [m] and k_s [N m], left/right, and
    any further float states a slip-model scheme reports in its extras (``other``)."""
    x = run.ekf.estimate().extras
    known = {"R_wl_m", "R_wr_m", "k_sl", "k_sr", "n_bearings_used", "n_skipped", "skipped"}
    return {"R_w_m": [x.get("R_wl_m"), x.get("R_wr_m")], "k_s": [x.get("k_sl"), x.get("k_sr")],
            "other": {k: v for k, v in x.items() if k not in known and isinstance(v, float)}}
