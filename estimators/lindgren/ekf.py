"""Lindgren's navigation EKF: inertial, odometric and beacon-bearing fusion, with or without the
slip-aware odometric model (Lindgren Eq. 4-17 and 32-41; the four schemes of §5).

Symbols follow filterpy and the paper: ``x`` state (n,), ``P`` its covariance (n, n), ``F``
process Jacobian, ``Q`` process noise, ``H`` observation Jacobian (n_z, n), ``R`` observation
noise (n_z, n_z), ``y`` innovation (n_z,), ``S = H P H' + R`` its covariance, ``K`` the gain
(Lindgren's W, Eq. 10). The models themselves are the plain functions of
:mod:`.models` (state, process) and :mod:`.observations`.

Why plain numpy rather than ``filterpy.kalman.ExtendedKalmanFilter``: the filter runs several
sequential updates per step with a different ``h`` and ``R`` for each sensor, predicts to the
time stamp of every asynchronous bearing, and must look at the innovation and its ``S`` before
committing an update (nearest-innovation data association and a χ² gate on bearings, a slip
range check on odometry); filterpy's ``update`` commits at once, keeps one ``dim_z``, and
deep-copies its state on every call, which at ~5-7 updates per 20 Hz step costs more than the
arithmetic. The update below is filterpy's (same Joseph form), taken apart so the innovation can
be inspected first; the tests check a step of the class against the plain functions and
filterpy's ``ExtendedKalmanFilter.update`` to 1e-12.

Numerical choices: the covariance update uses the Joseph form
``P = (I - K H) P (I - K H)' + K R K'``, which stays symmetric positive definite under
round-off and for any gain; ``P`` is symmetrised after every predict and update. A frame that
fails validation raises ``ValueError`` before anything changes; any error while processing a
frame restores the state from before it.
"""

from __future__ import annotations

import logging
import math

import numpy as np
from scipy import stats

from slipenv.contracts import PoseEstimate, SensorFrame, wrap_angle

from ..base import OdometryGeometry, check_frame_time
from . import models as lm
from . import observations as lo
from .models import OracleSoil
from .params import LindgrenNoise, Scheme, parse_scheme

__all__ = ["LindgrenEKF", "LindgrenNoise", "OracleSoil", "Scheme", "parse_scheme", "SENSORS"]

logger = logging.getLogger(__name__)
_ROUTINE_SKIPS = frozenset({"bearing_gated"})  # counted in extras['skipped'], not logged

SENSORS = ("gyro", "acc", "tilt", "odo", "bearing")  # keys of LindgrenEKF.history


class LindgrenEKF:
    """Lindgren's navigation EKF in one of the four schemes of §5, or the oracle variant.

    Parameters
    ----------
    geometry : OdometryGeometry
        Nominal radius R_w, track width W, encoder resolution 1/Γ and the left/right wheel
        groups (counts and torques are averaged within a group).
    scheme : int or str
        1 "laser_inertial", 2 "odometry_only", 3 "all_no_slip", 4 "all_slip".
    params : LindgrenNoise, optional
        Noise, prior and gating parameters; the paper's variances by default.
    beacons_xy : np.ndarray, shape (m, 2), optional
        Surveyed beacon positions [m]. Required by scheme 1; without it, bearings are skipped.
    oracle : OracleSoil, optional
        Scheme 4 only: fix R_w and k_s to these true values instead of estimating them
        (9-state filter with the Eq. 37 observation model).

    Attributes
    ----------
    x : np.ndarray, shape (n,)
        State, n = 13 for scheme 4 (R_w, k_s estimated), else 9.
    P : np.ndarray, shape (n, n)
        State covariance.
    history : dict[str, list[tuple[float, np.ndarray, np.ndarray]]]
        Per sensor (:data:`SENSORS`), every accepted innovation as ``(t, y, S)``.
    skipped : dict[str, int]
        Counts of measurements skipped or rejected, by reason: ``bearing_gated`` (failed the
        χ² gate), ``bearing_nan``, ``bearing_no_map``, ``gyro_nan``, ``acc_nan``, ``tilt_nan``,
        ``torque_nan`` and ``slip_out_of_range`` (slip-model odometry), ``odo_invalid_soil``
        (an odometry update that would make R_w or k_s non-positive, undone).

    Notes
    -----
    Torque enters only as ``T / k_s`` (Eq. 37), so the torque sensor needs no calibration:
    k_s is estimated in the sensor's own unit, and ``LindgrenNoise.k_s0`` should be a guess in
    that unit. The torque over a frame interval is the mean of the readings at its two ends.
    Per frame the order is: bearings at their own time stamps (predicting to each), then
    predict to the frame time, gyro, accelerometers, inclinometer, odometers.
    """

    def __init__(
        self,
        geometry: OdometryGeometry,
        scheme: int | str | Scheme = Scheme.ALL_SLIP,
        params: LindgrenNoise | None = None,
        beacons_xy: np.ndarray | None = None,
        oracle: OracleSoil | None = None,
    ) -> None:
        self.geometry = geometry
        self.scheme = parse_scheme(scheme)
        self.params = LindgrenNoise() if params is None else params
        if oracle is not None and self.scheme != Scheme.ALL_SLIP:
            raise ValueError("the oracle variant uses scheme 4's slip model; pass scheme=4")
        self.oracle = oracle
        if beacons_xy is not None:
            beacons_xy = np.asarray(beacons_xy, dtype=float)
            if beacons_xy.ndim != 2 or beacons_xy.shape[1] != 2 or len(beacons_xy) == 0:
                raise ValueError(f"beacons_xy must have shape (m, 2), got {beacons_xy.shape}")
            if not np.all(np.isfinite(beacons_xy)):
                raise ValueError("beacons_xy must be finite")
        elif self.scheme == Scheme.LASER_INERTIAL:
            raise ValueError("scheme 1 (laser_inertial) needs beacons_xy")
        self.beacons_xy = beacons_xy
        self.slip_model = self.scheme == Scheme.ALL_SLIP
        self.estimates_soil = self.slip_model and oracle is None
        self.uses_odometry = self.scheme != Scheme.LASER_INERTIAL
        self.uses_exteroceptive = self.scheme != Scheme.ODOMETRY_ONLY
        self.n = lm.N_SLIP if self.estimates_soil else lm.N_BASE
        p = self.params
        self._R_odo = np.eye(2) * p.odometer_var_rad2 * geometry.counts_per_rad**2
        self._R_acc = np.diag([p.acc_x_var_g2, p.acc_y_var_g2])
        self._R_gyro = np.array([[p.gyro_var_rad2ps2]])
        self._R_tilt = np.eye(2) * p.tilt_var_rad2
        self._R_bearing = np.array([[p.bearing_var_rad2]])
        self._gate = float(stats.chi2.ppf(p.bearing_gate_prob, 1))
        self._I = np.eye(self.n)
        self._left, self._right = list(geometry.left), list(geometry.right)
        self.x = np.zeros(self.n)
        self.P = np.eye(self.n)
        self.history: dict[str, list[tuple[float, np.ndarray, np.ndarray]]] = {
            s: [] for s in SENSORS}
        self.skipped: dict[str, int] = {}
        self._t: float | None = None  # time of the last frame [s]
        self._t_state = 0.0  # time the state refers to [s]
        self._counts = np.zeros(2)  # side-mean cumulative counts at the last frame
        self._torque = np.full(2, np.nan)  # side-mean torque at the last frame

    # -- start ---------------------------------------------------------------------------------
    def initial_state(self, x_m: float, y_m: float, yaw_rad: float,
                      frame: SensorFrame) -> tuple[np.ndarray, np.ndarray]:
        """The prior ``(x, P)`` :meth:`reset` starts from: the given pose, at rest."""
        p, g = self.params, self.geometry
        x = np.zeros(self.n)
        x[[lm.IX, lm.IY, lm.ITH]] = x_m, y_m, wrap_angle(float(yaw_rad))
        sig = np.array([p.sigma0_xy_m, p.sigma0_xy_m, p.sigma0_yaw_rad, p.sigma0_v_mps,
                        p.sigma0_omega_rps, p.sigma0_vdot_mps2, p.sigma0_omegadot_rps2,
                        p.sigma0_tilt_rad, p.sigma0_tilt_rad])
        if math.isfinite(frame.pitch_rad) and math.isfinite(frame.roll_rad):
            x[lm.IA1], x[lm.IA2] = -frame.pitch_rad, -frame.roll_rad
            sig[[lm.IA1, lm.IA2]] = math.sqrt(p.tilt_var_rad2)
        if self.estimates_soil:
            x[lm.IRL:lm.IRR + 1] = g.wheel_radius_m
            x[lm.IKL:lm.IKR + 1] = p.k_s0
            sig = np.concatenate([sig, [p.radius_rel_sigma0 * g.wheel_radius_m] * 2,
                                  [p.k_s_rel_sigma0 * p.k_s0] * 2])
        return x, np.diag(sig**2)

    def reset(self, x_m: float, y_m: float, yaw_rad: float, frame: SensorFrame) -> PoseEstimate:
        """Start at a known pose, at rest, with the prior of ``params``."""
        return self.reset_state(*self.initial_state(x_m, y_m, yaw_rad, frame), frame)

    def reset_state(self, x: np.ndarray, P: np.ndarray, frame: SensorFrame) -> PoseEstimate:
        """Start from a full state ``x`` (n,) and covariance ``P`` (n, n) at ``frame``'s time."""
        x = np.array(x, dtype=float)
        P = np.array(P, dtype=float)
        if x.shape != (self.n,) or P.shape != (self.n, self.n):
            raise ValueError(f"need x of shape ({self.n},) and P of shape ({self.n}, {self.n})")
        if not (np.all(np.isfinite(x)) and np.allclose(P, P.T)):
            raise ValueError("x must be finite and P symmetric")
        np.linalg.cholesky(P)  # raises LinAlgError unless P is positive definite
        check_frame_time(None, frame)
        self._counts = self._side_counts(frame) if self.uses_odometry else np.zeros(2)
        self.x, self.P = x, P
        self._t = self._t_state = float(frame.t_s)
        self._torque = self._side_torque(frame)
        self.history = {s: [] for s in SENSORS}
        self.skipped = {}
        return self.estimate()

    # -- step ----------------------------------------------------------------------------------
    def update(self, frame: SensorFrame) -> PoseEstimate:
        """Predict to the frame, fusing its bearings at their own times on the way, then update
        with the inertial sensors, inclinometer and odometers at the frame time."""
        if self._t is None:
            raise RuntimeError("LindgrenEKF.update called before reset")
        tau = check_frame_time(self._t, frame)
        t = float(frame.t_s)
        counts = self._side_counts(frame) if self.uses_odometry else self._counts
        bearings, n_bad = self._frame_bearings(frame) if self.uses_exteroceptive else ([], 0)
        torque = self._side_torque(frame)
        saved = (self.x.copy(), self.P.copy(), self._t_state, dict(self.skipped),
                 {k: len(v) for k, v in self.history.items()})
        try:
            self._skip("bearing_nan", n_bad)
            for t_b, z_b in bearings:
                self.predict_to(t_b)
                self._update_bearing(t_b, z_b)
            self.predict_to(t)
            if self.uses_exteroceptive:
                self._update_inertial(frame, t)
            if self.uses_odometry:
                t_bar = np.where(np.isfinite(self._torque), 0.5 * (self._torque + torque), torque)
                self._update_odometry(t, tau, counts - self._counts, t_bar)
        except Exception:
            self.x, self.P, self._t_state, self.skipped = saved[:4]
            for k, n in saved[4].items():
                del self.history[k][n:]
            raise
        self._t, self._counts, self._torque = t, counts, torque
        return self.estimate()

    def predict_to(self, t_s: float) -> None:
        """Propagate ``x`` and ``P`` to time ``t_s`` (Lindgren Eq. 6-7); no-op if not later."""
        tau = t_s - self._t_state
        if tau <= 0.0:
            return
        p = self.params
        F = lm.process_F(self.x, tau)
        Q = lm.process_Q(self.x, tau, p.jerk_psd_v, p.jerk_psd_omega, p.tilt_psd,
                         p.radius_var_per_m, p.k_s_rel_var_per_m)
        self.x = lm.process_fx(self.x, tau)
        self.x[lm.ITH] = wrap_angle(self.x[lm.ITH])
        P = F @ self.P @ F.T + Q
        self.P = 0.5 * (P + P.T)
        self._t_state = t_s

    def estimate(self) -> PoseEstimate:
        """The current estimate; ``extras`` holds R_w, k_s and the skip counts."""
        x = self.x
        r_w: tuple[float, float]  # effective rolling radius (left, right) [m]
        k_s: tuple[float, float]  # torque/slip gradient (left, right) [torque unit]
        if self.estimates_soil:
            r_w, k_s = (x[lm.IRL], x[lm.IRR]), (x[lm.IKL], x[lm.IKR])
        elif self.oracle is not None:
            r_w, k_s = self.oracle.wheel_radius_m, self.oracle.k_s
        else:
            r_w, k_s = (self.geometry.wheel_radius_m,) * 2, (math.nan, math.nan)
        extras = {"R_wl_m": float(r_w[0]), "R_wr_m": float(r_w[1]),
                  "k_sl": float(k_s[0]), "k_sr": float(k_s[1]),
                  "n_bearings_used": len(self.history["bearing"]),
                  "n_skipped": sum(self.skipped.values()), "skipped": dict(self.skipped)}
        return PoseEstimate(float(x[lm.IX]), float(x[lm.IY]), float(x[lm.ITH]),
                            speed_mps=float(x[lm.IV]), yaw_rate_rps=float(x[lm.IOM]),
                            cov=self.P[:3, :3].copy(), extras=extras)

    # -- input validation ----------------------------------------------------------------------
    def _side_counts(self, frame: SensorFrame) -> np.ndarray:
        counts = np.asarray(frame.enc_counts, dtype=float)
        idx = self._left + self._right
        if counts.ndim != 1 or len(counts) <= max(idx):
            raise ValueError(f"enc_counts has shape {counts.shape}; the geometry needs wheel "
                             f"indices {idx}")
        if not np.all(np.isfinite(counts[idx])):
            raise ValueError(f"non-finite encoder counts at t = {frame.t_s}: {counts[idx]}")
        return np.array([counts[self._left].mean(), counts[self._right].mean()])

    def _side_torque(self, frame: SensorFrame) -> np.ndarray:
        torque = np.asarray(frame.wheel_torque_nm, dtype=float)
        if torque.ndim != 1 or len(torque) <= max(self._left + self._right):
            return np.full(2, np.nan)
        return np.array([torque[self._left].mean(), torque[self._right].mean()])

    def _frame_bearings(self, frame: SensorFrame) -> tuple[list[tuple[float, float]], int]:
        """Finite (time, bearing) pairs sorted by time, and the number of non-finite ones."""
        z = np.atleast_1d(np.asarray(frame.beacon_bearings_rad, dtype=float))
        tb = np.atleast_1d(np.asarray(frame.beacon_times_s, dtype=float))
        if z.shape != tb.shape or z.ndim != 1:
            raise ValueError(f"beacon_bearings_rad {z.shape} and beacon_times_s {tb.shape} "
                             "must be 1-D of one length")
        ok = np.isfinite(z) & np.isfinite(tb)
        late = ok & ((tb <= self._t) | (tb > frame.t_s))
        if np.any(late):
            raise ValueError(f"bearing times {tb[late]} lie outside this frame's interval "
                             f"({self._t}, {frame.t_s}]")
        order = np.argsort(tb[ok], kind="stable")
        pairs = list(zip(tb[ok][order].tolist(), z[ok][order].tolist(), strict=True))
        return pairs, int(np.sum(~ok))

    def _skip(self, reason: str, n: int = 1) -> None:
        if n <= 0:
            return
        # A bearing outside the χ² gate is the gate doing its job (clutter, a wrong beacon),
        # not a fault, so it is only counted; anything else is worth one warning.
        if reason not in self.skipped and reason not in _ROUTINE_SKIPS:
            logger.warning("LindgrenEKF: skipping measurement (%s); further ones are counted "
                           "in PoseEstimate.extras['skipped']", reason)
        else:
            logger.debug("LindgrenEKF: skipping %d measurement(s) (%s)", n, reason)
        self.skipped[reason] = self.skipped.get(reason, 0) + n

    # -- updates -------------------------------------------------------------------------------
    def _update(self, sensor: str, t: float, y: np.ndarray, H: np.ndarray, R: np.ndarray,
                gate: float | None = None) -> bool:
        """Kalman update with innovation ``y`` (Lindgren Eq. 8-11, Joseph form); record it.

        Returns False, changing nothing, when ``y' S⁻¹ y`` exceeds ``gate``.
        """
        PHt = self.P @ H.T
        S = H @ PHt + R
        S_inv = 1.0 / S if S.shape == (1, 1) else np.linalg.inv(S)  # n_z <= 3: inv is cheapest
        if gate is not None and float(y @ S_inv @ y) > gate:
            return False
        K = PHt @ S_inv
        self.x = self.x + K @ y
        self.x[lm.ITH] = wrap_angle(self.x[lm.ITH])
        I_KH = self._I - K @ H
        P = I_KH @ self.P @ I_KH.T + K @ R @ K.T
        self.P = 0.5 * (P + P.T)
        self.history[sensor].append((t, y, S))
        return True

    def _update_inertial(self, frame: SensorFrame, t: float) -> None:
        """Yaw gyro, then the accelerometer pair, then the inclinometer (Lindgren Eq. 14)."""
        if math.isfinite(frame.gyro_z_rad_s):
            y = frame.gyro_z_rad_s - lo.ins_hx(self.x)[2:]
            self._update("gyro", t, y, lo.ins_H(self.x)[2:], self._R_gyro)
        else:
            self._skip("gyro_nan")
        if math.isfinite(frame.acc_x_mps2) and math.isfinite(frame.acc_y_mps2):
            z = np.array([frame.acc_x_mps2, frame.acc_y_mps2]) / lm.G_MPS2  # [g], Eq. 14
            self._update("acc", t, z - lo.ins_hx(self.x)[:2], lo.ins_H(self.x)[:2], self._R_acc)
        else:
            self._skip("acc_nan")
        if math.isfinite(frame.pitch_rad) and math.isfinite(frame.roll_rad):
            z = np.array([-frame.pitch_rad, -frame.roll_rad])  # REP 103 -> Lindgren's α1, α2
            self._update("tilt", t, z - lo.tilt_hx(self.x), lo.tilt_H(self.x), self._R_tilt)
        else:
            self._skip("tilt_nan")

    def _update_odometry(self, t: float, tau: float, dcounts: np.ndarray,
                         torque: np.ndarray) -> None:
        """Counts over the frame interval by Eq. 15 (schemes 2-3) or Eq. 37 (scheme 4)."""
        g = self.geometry
        if not self.slip_model:
            args = (tau, g.wheel_radius_m, g.track_width_m, g.counts_per_rad)
            y = dcounts - lo.odo_hx(self.x, *args)
            self._update("odo", t, y, lo.odo_H(self.x, *args), self._R_odo)
            return
        if not np.all(np.isfinite(torque)):
            self._skip("torque_nan")
            return
        if np.any(np.abs(lo.wheel_slip(self.x, tau, torque, g.track_width_m, self.oracle))
                  >= self.params.max_slip):
            self._skip("slip_out_of_range")
            return
        x0, P0 = self.x, self.P
        W, cpr, soil = g.track_width_m, g.counts_per_rad, self.oracle
        y = dcounts - lo.odo_slip_hx(self.x, tau, torque, W, cpr, soil)
        self._update("odo", t, y, lo.odo_slip_H(self.x, tau, torque, W, cpr, soil), self._R_odo)
        if self.estimates_soil and np.any(self.x[lm.IRL:] <= 0.0):
            self.x, self.P = x0, P0
            del self.history["odo"][-1]
            self._skip("odo_invalid_soil")

    def _update_bearing(self, t: float, z: float) -> None:
        """One bearing (Lindgren Eq. 17): nearest-innovation association, χ² gate, update."""
        if self.beacons_xy is None:
            self._skip("bearing_no_map")
            return
        j, y = lo.nearest_beacon(self.x, z, self.beacons_xy)
        H = lo.bearing_H(self.x, self.beacons_xy[j])
        if not self._update("bearing", t, np.array([y]), H, self._R_bearing, self._gate):
            self._skip("bearing_gated")
