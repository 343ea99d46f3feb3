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
arithmetic. The update below is filterpy's, taken apart so the innovation can be inspected
first; the tests check a step of the class against the plain functions and filterpy's
``ExtendedKalmanFilter.update`` to 1e-12.

Cost (issue 15): at 20 Hz with ~1.7 bearings a step the filter makes ~2.8 predictions and ~5.6
updates per step, each a handful of 13 x 13 numpy calls, so the per-call overhead of numpy
(~0.5 µs) is what it costs, not the arithmetic. Hence the prediction's ``f(x)``, ``F`` and ``Q``
are written out in plain floats into preallocated buffers (bit-for-bit the plain functions of
:mod:`.models`, tested), the odometric and bearing models likewise per wheel and per beacon,
directly measured states (gyro: Ω; inclinometer: α1, α2) read columns of P instead of
multiplying by a one-hot H, and state and covariance are replaced, never written into, so a
failed frame restores them from references. That numpy filter is the reference; on top of it,
the compiled kernel ``_ekf`` (``_ekf.c``, built by ``pip install``; ``compiled=`` and
``SLIPENV_LINDGREN_NUMPY=1`` choose) runs the same prediction and the bearing, inertial and
odometric updates in place on one copy of ``x`` and ``P`` per frame, one C call each, leaving
the bookkeeping (validation, skips, history, restore) here: ~5x cheaper (~120 -> ~20-30 µs per
FarmField step, scheme 4), the same ``f(x)``, ``F`` and ``Q`` bit for bit, ``x`` and ``P``
equal to the numpy filter's to rounding (BLAS sums in another order; 1e-9 relative over a
FarmField-length run, tested in ``tests/estimators/test_lindgren_compiled.py``, ~4e-14
observed). ``benchmarks/estimator_cost.py`` measures both.

Numerical choices: with ``S = H P H' + R = L L'`` (Cholesky, closed form for n_z <= 2) and the
optimal gain ``K = P H' S⁻¹``, the Joseph form ``(I - K H) P (I - K H)' + K R K'`` equals
``P - A A'`` with ``A = P H' L⁻ᵀ``, which is how the covariance is updated: a symmetric
rank-n_z downdate (numpy's ``A @ A.T`` goes through BLAS ``syrk``), so P stays exactly
symmetric without a symmetrising pass. Predictions are symmetrised. The outputs equal the
former product-form Joseph implementation to 1e-12 relative on a frozen FarmField run of every
scheme (``tests/estimators/test_lindgren_reference.py``). A frame that fails validation raises
``ValueError`` before anything changes; any error while processing a frame restores the state
from before it.
"""

from __future__ import annotations

import importlib
import logging
import math
from types import ModuleType

import numpy as np
from scipy import stats

from slipenv.contracts import PoseEstimate, SensorFrame, wrap_angle
from slipenv.contracts.switches import env_flag, pure_python

from ..base import OdometryGeometry, check_frame_time
from . import models as lm
from .models import OracleSoil
from .params import LindgrenNoise, Scheme, parse_scheme


def _load_kernel() -> ModuleType | None:
    """The compiled prediction and updates (``_ekf.c``, built by ``pip install`` where there is
    a C compiler), or None."""
    try:
        return importlib.import_module("slipenv.estimators.lindgren._ekf")
    except ImportError:  # pragma: no cover - depends on the build
        return None


_compiled_kernel = _load_kernel()

__all__ = ["LindgrenEKF", "LindgrenNoise", "OracleSoil", "Scheme", "parse_scheme", "SENSORS"]

logger = logging.getLogger(__name__)
_ROUTINE_SKIPS = frozenset({"bearing_gated"})  # counted in extras['skipped'], not logged

SENSORS = ("gyro", "acc", "tilt", "odo", "bearing")  # keys of LindgrenEKF.history
# Set to 1 to run every LindgrenEKF made with ``compiled=None`` on the numpy reference (as the
# package-wide ``SLIPENV_PURE_PYTHON`` does, slipenv.contracts.switches).
FORCE_NUMPY_ENV = "SLIPENV_LINDGREN_NUMPY"


def compiled_available() -> bool:
    """True when the compiled kernel ``slipenv.estimators.lindgren._ekf`` is importable."""
    return _compiled_kernel is not None


def _select_kernel(compiled: bool | None) -> ModuleType | None:
    """The compiled kernel to use, or None for the numpy reference (see ``LindgrenEKF``)."""
    if compiled is None:
        if env_flag(FORCE_NUMPY_ENV) or pure_python():
            return None
        return _compiled_kernel
    if compiled and _compiled_kernel is None:
        raise ValueError("compiled=True but the extension slipenv.estimators.lindgren._ekf is "
                         "not built (reinstall with a C compiler: pip install -e .)")
    return _compiled_kernel if compiled else None


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
    compiled : bool, optional
        Run the prediction and the updates in the compiled kernel ``_ekf`` (True; ValueError
        if it is not built) or in numpy (False, the reference). None (default): the kernel
        when it is built, unless ``SLIPENV_LINDGREN_NUMPY=1`` or ``SLIPENV_PURE_PYTHON=1`` is
        set in the environment. The two agree to rounding (1e-9 relative over a
        FarmField-length run, tested); numpy stays the reference the tests hold both to.

    Attributes
    ----------
    compiled : bool
        Whether this filter runs on the compiled kernel.
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
        compiled: bool | None = None,
    ) -> None:
        self._ext = _select_kernel(compiled)
        self.compiled = self._ext is not None
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
        self._r_bearing = float(p.bearing_var_rad2)
        self._r_gyro = float(p.gyro_var_rad2ps2)
        self._gate = float(stats.chi2.ppf(p.bearing_gate_prob, 1))
        self._qpars = (p.jerk_psd_v, p.jerk_psd_omega, p.tilt_psd, p.radius_var_per_m,
                       p.k_s_rel_var_per_m)
        self._left, self._right = list(geometry.left), list(geometry.right)
        self._alloc_buffers()
        self.x = np.zeros(self.n)
        self.P = np.eye(self.n)
        self.history: dict[str, list[tuple[float, np.ndarray, np.ndarray]]] = {
            s: [] for s in SENSORS}
        self.skipped: dict[str, int] = {}
        self._t: float | None = None  # time of the last frame [s]
        self._t_state = 0.0  # time the state refers to [s]
        self._counts = (0.0, 0.0)  # side-mean cumulative counts (left, right) at the last frame
        self._torque = (math.nan, math.nan)  # side-mean torque (left, right) at the last frame

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
        self._counts = self._side_counts(frame) if self.uses_odometry else (0.0, 0.0)
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
        # Every numpy predict and update binds new arrays to x and P (never writes into the old
        # ones); the compiled kernel works in place on one fresh copy per frame. Either way the
        # arrays from before the frame are untouched, so references are enough to restore them.
        saved = (self.x, self.P, self._t_state, dict(self.skipped),
                 [len(v) for v in self.history.values()])
        try:
            if self._ext is not None:
                self.x, self.P = self.x.copy(), self.P.copy()
            if n_bad:
                self._skip("bearing_nan", n_bad)
            for t_b, z_b in bearings:
                self._predict_to(t_b)
                self._update_bearing(t_b, z_b)
            self._predict_to(t)
            if self.uses_exteroceptive:
                self._update_inertial(frame, t)
            if self.uses_odometry:
                (a0, a1), (b0, b1) = self._torque, torque
                t_bar = (0.5 * (a0 + b0) if math.isfinite(a0) else b0,
                         0.5 * (a1 + b1) if math.isfinite(a1) else b1)
                dcounts = (counts[0] - self._counts[0], counts[1] - self._counts[1])
                self._update_odometry(t, tau, dcounts, t_bar)
        except Exception:
            self.x, self.P, self._t_state, self.skipped = saved[:4]
            for hist, n in zip(self.history.values(), saved[4], strict=True):
                del hist[n:]
            raise
        self._t, self._counts, self._torque = t, counts, torque
        return self.estimate()

    def predict_to(self, t_s: float) -> None:
        """Propagate ``x`` and ``P`` to time ``t_s`` (Lindgren Eq. 6-7); no-op if not later.

        ``x`` and ``P`` are replaced by new arrays, never written into."""
        if self._ext is not None and t_s > self._t_state:
            self.x, self.P = np.array(self.x, dtype=float), np.array(self.P, dtype=float)
        self._predict_to(t_s)

    def _predict_to(self, t_s: float) -> None:
        """:meth:`predict_to`, in place on ``x`` and ``P`` with the compiled kernel."""
        tau = t_s - self._t_state
        if tau <= 0.0:
            return
        if self._ext is not None:  # the same f(x), F and Q, written into x, F, Q and P
            self._ext.predict(self.x, self.P, self._F, self._Q, tau, *self._qpars)
        else:
            x, F, Q = self._process(tau)
            P = F @ self.P @ F.T + Q
            self.P = 0.5 * (P + P.T)
            self.x = x
        self._t_state = t_s

    def _process(self, tau: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """``(f(x), F, Q)`` over τ: :func:`.models.process_fx` (θ wrapped), :func:`.process_F`
        and :func:`.process_Q` written out in plain floats, term by term in the same order, so
        that they are bit-for-bit equal to those functions (tested) at a fraction of the cost.
        ``F`` and ``Q`` are the filter's own buffers, overwritten by the next call."""
        p = self.params
        xs = self.x.tolist()
        px, py, th, v, om, vd, omd, a1, a2 = xs[:9]
        # process_fx and process_F (Eq. 13, 7); shared left-to-right prefixes of their terms
        ht = 0.5 * tau
        tt = ht * tau  # 0.5 τ²
        v_bar = v + ht * vd
        dth = tau * (om + ht * omd)
        th_mid = th + 0.5 * dth
        c, s = math.cos(th_mid), math.sin(th_mid)
        cd, sd = math.cos(dth), math.sin(dth)
        da1 = -sd * a1 - cd * a2
        da2 = cd * a1 - sd * a2
        tv = tau * v_bar
        ntvs = -tau * v_bar * s
        tvc = tv * c
        self._F.flat[self._F_idx] = [
            ntvs, tau * c, tt * c, ntvs * 0.5 * tau, ntvs * 0.25 * tau * tau,
            tvc, tau * s, tt * s, tvc * 0.5 * tau, tvc * 0.25 * tau * tau,
            tau, tt, tau, tau,
            cd, -sd, sd, cd, tau * da1, tt * da1, tau * da2, tt * da2]
        xs[:9] = [px + tvc, py + tv * s, wrap_angle(th + dth), v + tau * vd, om + tau * omd,
                  vd, omd, cd * a1 - sd * a2, sd * a1 + cd * a2]
        # process_Q: white jerk on the along-track and yaw chains (jerk_block), tilt walks
        t2 = tau * tau
        t3 = t2 * tau
        b00, b01, b02 = t3 * t2 / 20.0, t2 * t2 / 8.0, t3 / 6.0
        b11, b12 = t3 / 3.0, t2 / 2.0
        qv, qw = p.jerk_psd_v, p.jerk_psd_omega
        q00, q01, q02 = qv * b00, qv * b01, qv * b02
        q_tilt = p.tilt_psd * tau
        qu = [q01 * c, q01 * s, q02 * c, q02 * s]
        q = [q00 * (c * c), q00 * (c * s), q00 * (s * c), q00 * (s * s), *qu,
             qv * b11, qv * b12, qv * b12, qv * tau,
             qw * b00, qw * b01, qw * b02, qw * b01, qw * b11, qw * b12, qw * b02, qw * b12,
             qw * tau, q_tilt, q_tilt, *qu]
        if self.n == lm.N_SLIP:
            d = abs(v_bar) * tau
            q_r = p.radius_var_per_m * d
            q += [q_r, q_r, p.k_s_rel_var_per_m * d * xs[lm.IKL] ** 2,
                  p.k_s_rel_var_per_m * d * xs[lm.IKR] ** 2]
        Q = self._Q
        Q.flat[self._Q_idx] = q
        return np.array(xs), self._F, Q

    def _alloc_buffers(self) -> None:
        """Preallocate F, Q and the observation Jacobians with their constant entries."""
        n = self.n
        self._F = np.eye(n)
        f_cells = [(lm.IX, lm.ITH), (lm.IX, lm.IV), (lm.IX, lm.IVD), (lm.IX, lm.IOM),
                   (lm.IX, lm.IOMD), (lm.IY, lm.ITH), (lm.IY, lm.IV), (lm.IY, lm.IVD),
                   (lm.IY, lm.IOM), (lm.IY, lm.IOMD), (lm.ITH, lm.IOM), (lm.ITH, lm.IOMD),
                   (lm.IV, lm.IVD), (lm.IOM, lm.IOMD), (lm.IA1, lm.IA1), (lm.IA1, lm.IA2),
                   (lm.IA2, lm.IA1), (lm.IA2, lm.IA2), (lm.IA1, lm.IOM), (lm.IA1, lm.IOMD),
                   (lm.IA2, lm.IOM), (lm.IA2, lm.IOMD)]
        self._F_idx = np.ravel_multi_index(tuple(np.array(f_cells).T), (n, n))
        yaw = (lm.ITH, lm.IOM, lm.IOMD)
        q_cells = [(0, 0), (0, 1), (1, 0), (1, 1), (0, lm.IV), (1, lm.IV), (0, lm.IVD),
                   (1, lm.IVD), (lm.IV, lm.IV), (lm.IV, lm.IVD), (lm.IVD, lm.IV),
                   (lm.IVD, lm.IVD)]
        q_cells += [(i, j) for i in yaw for j in yaw]
        q_cells += [(lm.IA1, lm.IA1), (lm.IA2, lm.IA2)]
        q_cells += [(lm.IV, 0), (lm.IV, 1), (lm.IVD, 0), (lm.IVD, 1)]  # the symmetric ones
        if n == lm.N_SLIP:
            q_cells += [(lm.IRL, lm.IRL), (lm.IRR, lm.IRR), (lm.IKL, lm.IKL), (lm.IKR, lm.IKR)]
        self._Q = np.zeros((n, n))
        self._Q_idx = np.ravel_multi_index(tuple(np.array(q_cells).T), (n, n))
        self._H_acc = np.zeros((2, n))
        self._H_acc[0, lm.IVD], self._H_acc[0, lm.IA1], self._H_acc[1, lm.IA2] = (
            1.0 / lm.G_MPS2, 1.0, -1.0)
        self._H_odo = np.zeros((2, n))
        self._h_bearing = np.zeros(n)
        self._h_bearing[lm.ITH] = -1.0
        if self.beacons_xy is not None:
            self._bx = np.ascontiguousarray(self.beacons_xy[:, 0])
            self._by = np.ascontiguousarray(self.beacons_xy[:, 1])

    def estimate(self) -> PoseEstimate:
        """The current estimate; ``extras`` holds R_w, k_s and the skip counts."""
        xs = self.x.tolist()
        r_w: tuple[float, float]  # effective rolling radius (left, right) [m]
        k_s: tuple[float, float]  # torque/slip gradient (left, right) [torque unit]
        if self.estimates_soil:
            r_w, k_s = (xs[lm.IRL], xs[lm.IRR]), (xs[lm.IKL], xs[lm.IKR])
        elif self.oracle is not None:
            r_w, k_s = self.oracle.wheel_radius_m, self.oracle.k_s
        else:
            r_w, k_s = (self.geometry.wheel_radius_m,) * 2, (math.nan, math.nan)
        extras = {"R_wl_m": float(r_w[0]), "R_wr_m": float(r_w[1]),
                  "k_sl": float(k_s[0]), "k_sr": float(k_s[1]),
                  "n_bearings_used": len(self.history["bearing"]),
                  "n_skipped": sum(self.skipped.values()), "skipped": dict(self.skipped)}
        return PoseEstimate(xs[lm.IX], xs[lm.IY], xs[lm.ITH], speed_mps=xs[lm.IV],
                            yaw_rate_rps=xs[lm.IOM], cov=self.P[:3, :3].copy(), extras=extras)

    # -- input validation ----------------------------------------------------------------------
    def _side_counts(self, frame: SensorFrame) -> tuple[float, float]:
        """Mean cumulative counts of the (left, right) wheel group."""
        counts = frame.enc_counts
        idx = self._left + self._right
        if not isinstance(counts, np.ndarray) or counts.ndim != 1 or len(counts) <= max(idx):
            counts = np.asarray(counts, dtype=float)
            if counts.ndim != 1 or len(counts) <= max(idx):
                raise ValueError(f"enc_counts has shape {counts.shape}; the geometry needs "
                                 f"wheel indices {idx}")
        c = counts.tolist()
        left = [float(c[i]) for i in self._left]
        right = [float(c[i]) for i in self._right]
        if not all(math.isfinite(v) for v in left + right):
            raise ValueError(f"non-finite encoder counts at t = {frame.t_s}: {left + right}")
        # the same left-to-right sum np.mean does for these few values
        return sum(left) / len(left), sum(right) / len(right)

    def _side_torque(self, frame: SensorFrame) -> tuple[float, float]:
        """Mean torque of the (left, right) wheel group; NaN when the frame has none."""
        torque = frame.wheel_torque_nm
        if not isinstance(torque, np.ndarray):
            torque = np.asarray(torque, dtype=float)
        if torque.ndim != 1 or len(torque) <= max(self._left + self._right):
            return math.nan, math.nan
        tq = torque.tolist()
        left = [float(tq[i]) for i in self._left]
        right = [float(tq[i]) for i in self._right]
        return sum(left) / len(left), sum(right) / len(right)

    def _frame_bearings(self, frame: SensorFrame) -> tuple[list[tuple[float, float]], int]:
        """Finite (time, bearing) pairs sorted by time, and the number of non-finite ones."""
        z = np.atleast_1d(np.asarray(frame.beacon_bearings_rad, dtype=float))
        tb = np.atleast_1d(np.asarray(frame.beacon_times_s, dtype=float))
        if z.shape != tb.shape or z.ndim != 1:
            raise ValueError(f"beacon_bearings_rad {z.shape} and beacon_times_s {tb.shape} "
                             "must be 1-D of one length")
        if z.size == 0:
            return [], 0
        t_prev, t_now = self._t, float(frame.t_s)
        pairs, n_bad, late = [], 0, []
        for t_b, z_b in zip(tb.tolist(), z.tolist(), strict=True):
            if not (math.isfinite(t_b) and math.isfinite(z_b)):
                n_bad += 1
            elif t_b <= t_prev or t_b > t_now:
                late.append(t_b)
            else:
                pairs.append((t_b, z_b))
        if late:
            raise ValueError(f"bearing times {np.array(late)} lie outside this frame's interval "
                             f"({self._t}, {frame.t_s}]")
        pairs.sort(key=lambda pair: pair[0])  # stable, as np.argsort(kind="stable")
        return pairs, n_bad

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
    # The covariance update. With P H' and S = H P H' + R = L L' (Cholesky), the optimal gain
    # K = P H' S⁻¹ turns the Joseph form (I - K H) P (I - K H)' + K R K' into
    #     P - A A',   A = P H' L⁻ᵀ,
    # which is how it is computed (A A' by BLAS syrk, or the outer product a aᵀ for a scalar
    # measurement), so P stays exactly symmetric without a symmetrising pass, at a third of the
    # n x n work of the product form. The
    # outputs match the former product-form implementation to 1e-12 relative (tests/estimators/
    # test_lindgren_reference.py, a frozen FarmField run of every scheme).
    def _update(self, sensor: str, t: float, y: np.ndarray, H: np.ndarray | slice,
                R: np.ndarray, gate: float | None = None, soil_from: int = -1) -> int:
        """Kalman update with innovation ``y`` (Lindgren Eq. 8-11); record it.

        ``H`` has shape (2, n), or is the slice of two states measured directly (rows of the
        identity: ``P H'`` is then two columns of P); ``R`` has shape (2, 2) (the filter's
        vector sensors). Returns 1 when committed; 0, changing nothing, when ``y' S⁻¹ y``
        exceeds ``gate``; -1, changing nothing, when ``soil_from >= 0`` and the updated state
        has an entry <= 0 from index ``soil_from`` on (R_w, k_s).
        """
        if isinstance(H, slice):
            PHt = self.P[:, H]
            S = PHt[H] + R
        else:
            PHt = self.P @ H.T
            S = H @ PHt + R
        (s00, s01), (s10, s11) = S.tolist()
        s01 = 0.5 * (s01 + s10)
        det = s00 * s11 - s01 * s01
        y0, y1 = y.tolist()
        w0, w1 = (s11 * y0 - s01 * y1) / det, (s00 * y1 - s01 * y0) / det  # S⁻¹ y
        if gate is not None and y0 * w0 + y1 * w1 > gate:
            return 0
        x = self.x + PHt @ np.array([w0, w1])
        x[lm.ITH] = wrap_angle(x[lm.ITH])
        if soil_from >= 0 and np.any(x[soil_from:] <= 0.0):
            return -1
        l00 = math.sqrt(s00)
        l10 = s01 / l00
        l11 = math.sqrt(s11 - l10 * l10)
        A = PHt @ np.array([[1.0 / l00, -l10 / (l00 * l11)], [0.0, 1.0 / l11]])  # P H' L⁻ᵀ
        self.x = x
        self.P = self.P - A @ A.T  # A A' by numpy's syrk path: exactly symmetric
        self.history[sensor].append((t, y, S))
        return 1

    def _update_scalar(self, sensor: str, t: float, y: float, h: np.ndarray | int, r: float,
                       gate: float | None = None) -> bool:
        """:meth:`_update` for one scalar measurement: ``h`` shape (n,), or the index ``i`` of
        a state measured directly (``h = e_i``); variance ``r``."""
        if isinstance(h, int):  # h = e_h: P h is a column of P, h' P h a diagonal entry
            ph = self.P[:, h]
            s = float(ph[h]) + r
        else:
            ph = self.P @ h
            s = float(h @ ph) + r
        if gate is not None and y * y / s > gate:
            return False
        x = self.x + ph * (y / s)
        x[lm.ITH] = wrap_angle(x[lm.ITH])
        a = ph * (1.0 / math.sqrt(s))
        self.x = x
        self.P = self.P - np.multiply.outer(a, a)
        self.history[sensor].append((t, np.array([y]), np.array([[s]])))
        return True

    def _update_inertial(self, frame: SensorFrame, t: float) -> None:
        """Yaw gyro, then the accelerometer pair, then the inclinometer (Lindgren Eq. 14)."""
        if self._ext is not None:  # the same three updates, in place
            out = np.empty(14)  # y, S of each: (1, 1) gyro, (2, 2, 2) acc, (2, 2, 2) tilt
            used = self._ext.update_inertial(
                self.x, self.P, self._H_acc, self._R_acc, self._R_tilt, frame.gyro_z_rad_s,
                frame.acc_x_mps2, frame.acc_y_mps2, frame.pitch_rad, frame.roll_rad,
                self._r_gyro, out)
            hist = self.history
            if used & 1:
                hist["gyro"].append((t, out[0:1], out[1:2].reshape(1, 1)))
            else:
                self._skip("gyro_nan")
            if used & 2:
                hist["acc"].append((t, out[2:4], out[4:8].reshape(2, 2)))
            else:
                self._skip("acc_nan")
            if used & 4:
                hist["tilt"].append((t, out[8:10], out[10:14].reshape(2, 2)))
            else:
                self._skip("tilt_nan")
            return
        gz = frame.gyro_z_rad_s
        if math.isfinite(gz):  # g1 = Ω
            self._update_scalar("gyro", t, gz - float(self.x[lm.IOM]), lm.IOM,
                                self._R_gyro[0, 0])
        else:
            self._skip("gyro_nan")
        ax, ay = frame.acc_x_mps2, frame.acc_y_mps2
        if math.isfinite(ax) and math.isfinite(ay):  # [a1/g, a2/g] of Eq. 14
            _, _, _, v, om, vd, _, a1, a2 = self.x[:9].tolist()
            g = lm.G_MPS2
            y = np.array([ax / g - (vd / g + a1), ay / g - (v * om / g - a2)])
            H = self._H_acc
            H[1, lm.IV], H[1, lm.IOM] = om / g, v / g
            self._update("acc", t, y, H, self._R_acc)
        else:
            self._skip("acc_nan")
        pitch, roll = frame.pitch_rad, frame.roll_rad
        if math.isfinite(pitch) and math.isfinite(roll):  # REP 103 -> Lindgren's α1, α2
            y = np.array([-pitch - float(self.x[lm.IA1]), -roll - float(self.x[lm.IA2])])
            self._update("tilt", t, y, slice(lm.IA1, lm.IA2 + 1), self._R_tilt)
        else:
            self._skip("tilt_nan")

    def _update_odometry(self, t: float, tau: float, dcounts: tuple[float, float],
                         torque: tuple[float, float]) -> None:
        """Counts over the frame interval by Eq. 15 (schemes 2-3) or Eq. 37 (scheme 4).

        The predictions and Jacobians are :func:`.observations.odo_hx`, :func:`.odo_H`,
        :func:`.odo_slip_hx`, :func:`.odo_slip_H` and :func:`.wheel_slip` written out per
        wheel in plain floats, term by term in the same order.
        """
        g = self.geometry
        W, cpr = g.track_width_m, g.counts_per_rad
        if self._ext is not None:  # the same model and update, in place
            if not self.slip_model:
                mode, r_w, k_s = 0, (g.wheel_radius_m, g.wheel_radius_m), (1.0, 1.0)
            elif self.oracle is not None:
                mode, r_w, k_s = 1, self.oracle.wheel_radius_m, self.oracle.k_s
            else:
                mode, r_w, k_s = 2, (1.0, 1.0), (1.0, 1.0)  # read from the state
            out = np.empty(6)  # y (2), S (2, 2)
            status = self._ext.update_odometry(
                self.x, self.P, self._H_odo, self._R_odo, tau, dcounts[0], dcounts[1],
                torque[0], torque[1], W, cpr, mode, r_w[0], r_w[1], k_s[0], k_s[1],
                self.params.max_slip, out)
            if status == 1:
                self.history["odo"].append((t, out[0:2], out[2:6].reshape(2, 2)))
            else:
                self._skip({-1: "odo_invalid_soil", -2: "torque_nan",
                            -3: "slip_out_of_range"}[status])
            return
        xs = self.x.tolist()
        v_mid = xs[lm.IV] - 0.5 * tau * xs[lm.IVD]
        om_mid = xs[lm.IOM] - 0.5 * tau * xs[lm.IOMD]
        half_w = 0.5 * W
        v_w = (v_mid + -half_w * om_mid, v_mid + half_w * om_mid)  # mean wheel speeds [m/s]
        H = self._H_odo
        if not self.slip_model:  # Eq. 15-16
            gain = tau * cpr / g.wheel_radius_m
            y = np.array([dcounts[0] - gain * v_w[0], dcounts[1] - gain * v_w[1]])
            dz = (gain, gain)
        else:  # Eq. 37-41
            if not (math.isfinite(torque[0]) and math.isfinite(torque[1])):
                self._skip("torque_nan")
                return
            if self.oracle is not None:
                r_w, k_s = self.oracle.wheel_radius_m, self.oracle.k_s
            else:
                r_w, k_s = (xs[lm.IRL], xs[lm.IRR]), (xs[lm.IKL], xs[lm.IKR])
            sigma = tuple(1.0 if v >= 0.0 else -1.0 for v in v_w)
            if any(abs(sigma[i] * torque[i] / k_s[i]) >= self.params.max_slip for i in (0, 1)):
                self._skip("slip_out_of_range")
                return
            den = [k_s[i] - sigma[i] * torque[i] for i in (0, 1)]
            y = np.array([dcounts[i] - tau * cpr * v_w[i] * k_s[i] / (r_w[i] * den[i])
                          for i in (0, 1)])
            dz = (tau * cpr * k_s[0] / (r_w[0] * den[0]),  # Eq. 38
                  tau * cpr * k_s[1] / (r_w[1] * den[1]))
            if self.oracle is None:
                H[0, lm.IRL] = -(dz[0] * v_w[0]) / r_w[0]  # Eq. 40
                H[1, lm.IRR] = -(dz[1] * v_w[1]) / r_w[1]
                H[0, lm.IKL], H[1, lm.IKR] = (  # Eq. 41
                    -tau * cpr * sigma[i] * torque[i] * v_w[i] / (r_w[i] * (den[i] * den[i]))
                    for i in (0, 1))
        d_om = (-dz[0] * 0.5 * W, dz[1] * 0.5 * W)  # Eq. 39
        H[0, lm.IV], H[1, lm.IV] = dz
        H[0, lm.IOM], H[1, lm.IOM] = d_om
        H[0, lm.IVD], H[1, lm.IVD] = -0.5 * tau * dz[0], -0.5 * tau * dz[1]
        H[0, lm.IOMD], H[1, lm.IOMD] = -0.5 * tau * d_om[0], -0.5 * tau * d_om[1]
        if self._update("odo", t, y, H, self._R_odo,
                        soil_from=lm.IRL if self.estimates_soil else -1) == -1:
            self._skip("odo_invalid_soil")

    def _update_bearing(self, t: float, z: float) -> None:
        """One bearing (Lindgren Eq. 17): nearest-innovation association, χ² gate, update.

        The beacon chosen is the one with the smallest wrapped innovation, i.e. the largest
        ``cos(z + θ - atan2(Y_b - y, X_b - x))`` (:func:`.observations.nearest_beacon`); its
        innovation and Jacobian are :func:`.bearing_residual` and :func:`.bearing_H`.
        """
        if self.beacons_xy is None:
            self._skip("bearing_no_map")
            return
        if self._ext is not None:  # the same association, innovation and update, in place
            y_arr, S = np.empty(1), np.empty((1, 1))
            if self._ext.update_bearing(self.x, self.P, self._bx, self._by, z,
                                        self._r_bearing, self._gate, y_arr, S):
                self.history["bearing"].append((t, y_arr, S))
            else:
                self._skip("bearing_gated")
            return
        px, py, th = self.x[:3].tolist()
        dx_all, dy_all = self._bx - px, self._by - py
        j = int(np.argmax(np.cos((z + th) - np.arctan2(dy_all, dx_all))))
        dx, dy = float(dx_all[j]), float(dy_all[j])
        y = wrap_angle(z - wrap_angle(math.atan2(dy, dx) - th))
        r2 = dx * dx + dy * dy
        h = self._h_bearing
        h[lm.IX], h[lm.IY] = dy / r2, -dx / r2
        if not self._update_scalar("bearing", t, y, h, self._R_bearing[0, 0], self._gate):
            self._skip("bearing_gated")
