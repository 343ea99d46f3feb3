"""Lindgren's navigation EKF: inertial, odometric and beacon-bearing fusion, with or without the
slip-aware odometric model (Lindgren Eq. 4-17 and 32-41; the four schemes of §5).

Symbols follow filterpy and the paper: ``x`` state (n,), ``P`` its covariance (n, n), ``F``
process Jacobian, ``Q`` process noise, ``H`` observation Jacobian (n_z, n), ``R`` observation
noise (n_z, n_z), ``y`` innovation (n_z,), ``S = H P H' + R`` its covariance, ``K`` the gain
(Lindgren's W, Eq. 10). The models are the plain functions of :mod:`.models` (state, process)
and :mod:`.observations`; :mod:`.kernel` strings them into one frame's predictions and updates.
All three are compiled by numba from their text (cached on disk), and that is the only
implementation: the tests check it against finite differences, against filterpy's textbook
Kalman filter on a linear-Gaussian case, and for consistency (NEES, NIS) on data drawn from
the filter's own model.

Why not ``filterpy.kalman.ExtendedKalmanFilter``: the filter runs several sequential updates
per step with a different ``h`` and ``R`` for each sensor, predicts to the time stamp of every
asynchronous bearing, and must look at the innovation and its ``S`` before committing an update
(nearest-innovation data association and a χ² gate on bearings, a slip range check on
odometry); filterpy's ``update`` commits at once, keeps one ``dim_z``, and deep-copies its
state on every call. The class here keeps the bookkeeping (validation, skips, history,
restore); the arithmetic of a frame is one compiled call, :func:`.kernel.filter_frame`.

A frame that fails validation raises ``ValueError`` before anything changes; the kernel writes
the frame into a new state vector and only reads the old one, so any error while processing a
frame leaves the state of before it.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable
from typing import Any

import numpy as np
from numba.core import types as nb_types
from scipy import stats

from slipenv.contracts import PoseEstimate, SensorFrame, wrap_angle

from ..base import OdometryGeometry, check_frame_time
from . import kernel
from . import models as lm
from . import observations as lo
from .models import OracleSoil
from .params import LindgrenNoise, Scheme, parse_scheme

__all__ = ["LindgrenEKF", "LindgrenNoise", "OracleSoil", "Scheme", "parse_scheme", "SENSORS"]

logger = logging.getLogger(__name__)
logger.addHandler(logging.NullHandler())  # records reach the app's handlers, never bare stderr
_ROUTINE_SKIPS = frozenset({"bearing_gated"})  # counted in extras['skipped'], not logged

SENSORS = ("gyro", "acc", "tilt", "odo", "bearing")  # keys of LindgrenEKF.history
_NO_BEARINGS = np.zeros(0)
_EMPTY = (0,)  # the shape of a frame's bearings when no scan arrived
_MAX_TALLIES = 256  # status patterns a filter remembers the skip counts of (a handful occur)
_F64 = np.dtype(np.float64)  # an unpickled array's dtype is an equal, other object
_N_OUT_ROWS, _OUT_AT = kernel.N_OUT_ROWS, kernel.OUT_AT
_S_T_STATE, _S_X, _S_COUNTS, _S_TORQUE = (kernel.S_T_STATE, kernel.S_X, kernel.S_COUNTS,
                                          kernel.S_TORQUE)
# LindgrenEKF._estimate unpacks the kernel's values in one go, in this order
assert (kernel.R_CODE, kernel.R_POSE, kernel.R_SLIP_ANGLE, kernel.R_SOIL, kernel.R_INV_SHAPE,
        kernel.R_K_BETA) == (0, 1, 6, 7, 11, 13)
_construct = PoseEstimate.construct
_OUT_SENSORS = (("gyro", kernel.OUT_GYRO, 1), ("acc", kernel.OUT_ACC, 2),
                ("tilt", kernel.OUT_TILT, 2), ("odo", kernel.OUT_ODO, 2))
_ODO_SKIPS = {kernel.INVALID_SOIL: "odo_invalid_soil", kernel.TORQUE_NAN: "torque_nan",
              kernel.SLIP_OUT_OF_RANGE: "slip_out_of_range"}


_F64_STRIDES = (8,)  # a contiguous 1-D float64 array's
# the frame kernel's argument types as LindgrenEKF.update passes them: five contiguous 1-D
# float64 arrays (state, spare, context, bearing times and values), eleven floats, ``out``
_FRAME_SIG = ((nb_types.float64[::1],) * 5 + (nb_types.float64,) * 11
              + (nb_types.float64[:, ::1],))
_ENTRY: list[Any] = [None, None]  # the frame kernel's dispatcher, and what update calls for it


def _frame_entry(dispatcher: Any) -> Callable[..., Any]:
    """What :meth:`LindgrenEKF.update` calls for the frame kernel ``dispatcher``: its compiled
    code for :data:`_FRAME_SIG` itself (from numba's cache, or compiled), without the
    dispatcher's typing of 17 arguments and search for their overload at every frame (~1 µs at
    an env step); the dispatcher when it is not numba's (``NUMBA_DISABLE_JIT=1``, a stand-in).
    The entry checks no argument's type: only arrays of the signature's may go to it (or
    read-only ones: the kernel never writes the bearings)."""
    compile_sig = getattr(dispatcher, "compile", None)
    entry = dispatcher if compile_sig is None else compile_sig(_FRAME_SIG)
    _ENTRY[:] = dispatcher, entry
    return entry


def _status(out: np.ndarray, m: int) -> tuple[int, ...]:
    """The status codes of a frame with m bearings from the kernel's ``out`` (as one vector):
    bearings, then gyro, accelerometers, inclinometer, odometers."""
    at = _OUT_AT + 2 * m + kernel.N_OUT_FIXED
    return tuple(int(code) for code in out[at:at + m + 4].tolist())


def compiled_available() -> bool:
    """True when the filter runs compiled (numba), False under ``NUMBA_DISABLE_JIT=1``."""
    from numba.core import config

    # numba fills its config module from the NUMBA_* variables at run time.
    return not config.DISABLE_JIT  # type: ignore[attr-defined]


def warm_up() -> None:
    """Compile the filter's code now, or load it from numba's on-disk cache when it is there.

    The first filter after an install or an edit of the filter's source compiles it (tens of
    seconds); later ones load it (a fraction of a second). Call this in a parent process before
    starting worker processes that build filters: numba's cache is not safe against several
    processes writing it at the same time, so they should find it written.
    """
    geometry = OdometryGeometry(wheel_radius_m=0.3, track_width_m=1.0, counts_per_rad=100.0)
    ekf = LindgrenEKF(geometry, Scheme.ALL_SLIP, beacons_xy=np.array([[10.0, 0.0]]))
    ekf.reset(0.0, 0.0, 0.0, SensorFrame(0.0, np.zeros(2), np.zeros(2)))
    ekf.update(SensorFrame(0.05, np.zeros(2), np.zeros(2), gyro_z_rad_s=0.0, acc_x_mps2=0.0,
                           acc_y_mps2=0.0, pitch_rad=0.0, roll_rad=0.0,
                           beacon_bearings_rad=np.zeros(1), beacon_times_s=np.array([0.05])))
    ekf.predict_to(0.1)


class LindgrenEKF:
    """Lindgren's navigation EKF in one of the four schemes of §5, scheme 5 (Okello's curve in
    place of the linear torque/slip law), or the oracle variant.

    Parameters
    ----------
    geometry : OdometryGeometry
        Nominal radius R_w, track width W, encoder resolution 1/Γ and the left/right wheel
        groups (counts and torques are averaged within a group).
    scheme : int or str
        1 "laser_inertial", 2 "odometry_only", 3 "all_no_slip", 4 "all_slip",
        5 "all_slip_okello".
    params : LindgrenNoise, optional
        Noise, prior and gating parameters; the paper's variances by default. With
        ``lateral_slip_sigma0 > 0`` the state gains the lateral slip gain k_β (any scheme).
    beacons_xy : np.ndarray, shape (m, 2), optional
        Surveyed beacon positions [m]. Required by scheme 1; without it, bearings are skipped.
    oracle : OracleSoil, optional
        Scheme 4 only: fix R_w and k_s to these true values instead of estimating them
        (9-state filter with the Eq. 37 observation model).

    Attributes
    ----------
    x : np.ndarray, shape (n,)
        State (layout in :mod:`.models`): n = 13 for scheme 4 (R_w, k_s estimated), 15 for
        scheme 5 (R_w, k_s, 1/B), else 9; one more with the lateral slip gain k_β (last).
    P : np.ndarray, shape (n, n)
        State covariance. ``x`` and ``P`` are read-only copies of the filter's state: an
        array read here never changes afterwards, writing into it raises, and the filter
        changes only when ``x`` or ``P`` is set whole.
    history : dict[str, list[tuple[float, np.ndarray, np.ndarray]]]
        Per sensor (:data:`SENSORS`), every accepted innovation as ``(t, y, S)`` (read-only).
    skipped : dict[str, int]
        Counts of measurements skipped or rejected, by reason: ``bearing_gated`` (failed the
        χ² gate), ``bearing_nan``, ``bearing_no_map``, ``gyro_nan``, ``acc_nan``, ``tilt_nan``,
        ``torque_nan`` and ``slip_out_of_range`` (slip-model odometry: a wheel spinning or
        locked by its own counts, or a soil estimate that puts the torque at the model's
        pole), ``odo_invalid_soil`` and ``bearing_invalid_soil`` (an update that would make
        R_w or k_s non-positive or take the soil estimate out of the slip model's range for
        the measured torque, undone).

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
        self.slip_model = self.scheme in (Scheme.ALL_SLIP, Scheme.ALL_SLIP_OKELLO)
        self.estimates_soil = self.slip_model and oracle is None
        self.uses_odometry = self.scheme != Scheme.LASER_INERTIAL
        self.uses_exteroceptive = self.scheme != Scheme.ODOMETRY_ONLY
        self.lateral_slip = self.params.lateral_slip_sigma0 > 0.0
        self._okello = self.scheme == Scheme.ALL_SLIP_OKELLO
        if self.scheme == Scheme.ALL_SLIP_OKELLO:
            n_soil = lm.N_OKELLO
        else:
            n_soil = lm.N_SLIP if self.estimates_soil else lm.N_BASE
        self.n = n_soil + self.lateral_slip
        self.state_names = lm.state_names(self.n)
        p = self.params
        if not self.uses_odometry:
            odo_mode = -1
        elif not self.slip_model:
            odo_mode = 0
        else:
            odo_mode = 1
        soil = lo.NO_SOIL if oracle is None else oracle.as_array()
        # the kernel's context: cfg, the beacon map and the workspaces in one array
        n_beacons = 0 if beacons_xy is None else len(beacons_xy)
        b_at = kernel.N_CFG + len(soil)
        w_at = b_at + 2 * n_beacons
        i_at = w_at + kernel.work_size(self.n)
        ctx = np.empty(kernel.context_size(self.n, len(soil), n_beacons))
        cfg = ctx[:b_at]
        cfg[[kernel.C_JERK_V, kernel.C_JERK_W, kernel.C_TILT_PSD, kernel.C_RADIUS_VAR,
             kernel.C_KS_VAR]] = (p.jerk_psd_v, p.jerk_psd_omega, p.tilt_psd,
                                  p.radius_var_per_m, p.k_s_rel_var_per_m)
        cfg[[kernel.C_R_GYRO, kernel.C_R_AX, kernel.C_R_AY, kernel.C_R_TILT,
             kernel.C_R_BEARING]] = (p.gyro_var_rad2ps2, p.acc_x_var_g2, p.acc_y_var_g2,
                                     p.tilt_var_rad2, p.bearing_var_rad2)
        cfg[kernel.C_GATE] = float(stats.chi2.ppf(p.bearing_gate_prob, 1))
        cfg[kernel.C_R_ODO] = p.odometer_var_rad2 * geometry.counts_per_rad**2
        cfg[[kernel.C_TRACK, kernel.C_CPR, kernel.C_RADIUS]] = (
            geometry.track_width_m, geometry.counts_per_rad, geometry.wheel_radius_m)
        cfg[kernel.C_MAX_SLIP] = p.max_slip
        cfg[kernel.C_B_VAR] = p.inv_shape_var_per_m
        cfg[kernel.C_KBETA_VAR] = p.lateral_slip_var_per_m
        cfg[kernel.C_INERTIAL] = float(self.uses_exteroceptive)
        cfg[kernel.C_ODO_MODE] = odo_mode
        cfg[[kernel.C_BEACONS_AT, kernel.C_WORK_AT, kernel.C_IWORK_AT]] = b_at, w_at, i_at
        cfg[kernel.N_CFG:] = soil
        if beacons_xy is not None:
            ctx[b_at:w_at] = beacons_xy.ravel()
        self._ctx, self._cfg = ctx, cfg
        # the compiled predictions' and updates' temporaries, reused from frame to frame
        self._work, self._iwork = ctx[w_at:i_at], ctx[i_at:].view(np.int64)
        self._left, self._right = list(geometry.left), list(geometry.right)
        # one wheel per side (the farm vehicle): read it directly, without averaging
        self._single = (self._left[0], self._right[0]) if len(self._left) == len(
            self._right) == 1 else None
        self._min_wheels = max(self._left + self._right) + 1
        if oracle is not None:
            r_w, k_s = oracle.wheel_radius_m, oracle.k_s
        else:  # only read when the soil is not estimated: the nominal radius, no slip model
            r_w, k_s = (geometry.wheel_radius_m,) * 2, (math.nan, math.nan)
        self._fixed_soil = float(r_w[0]), float(r_w[1]), float(k_s[0]), float(k_s[1])
        # sensors whose status is ACCEPTED in a frame where nothing is skipped
        self._n_sensors = 3 * self.uses_exteroceptive + self.uses_odometry
        self._tallies: dict[tuple, tuple[int, tuple]] = {}  # see _count_skips
        # The state vector (layout kernel.S_*): the time the state refers to, the side-mean
        # cumulative counts and torques (left, right) of the last frame, x and P. A frame
        # writes the next one into the spare, which then changes place with it: nothing
        # outside the filter sees either (x and P are read as copies).
        self._state_size, self._p_at = kernel.state_size(self.n), _S_X + self.n
        self._state, self._spare = np.zeros(self._state_size), np.empty(self._state_size)
        self._state[_S_TORQUE:_S_TORQUE + 2] = math.nan
        self._state[self._p_at:] = np.eye(self.n).ravel()
        self._clear_history()
        self.skipped: dict[str, int] = {}
        self._t: float | None = None  # time of the last frame [s]

    @property
    def x(self) -> np.ndarray:
        """The state (n,), a read-only copy (see the class's attributes): writing into it
        raises instead of silently leaving the filter as it was; set ``x`` whole instead."""
        out = self._state[_S_X:self._p_at].copy()
        out.flags.writeable = False
        return out

    @x.setter
    def x(self, value: np.ndarray) -> None:
        self._state[_S_X:self._p_at] = value

    @property
    def P(self) -> np.ndarray:  # noqa: N802  (the Kalman filter's symbol)
        """The state covariance (n, n), a read-only copy (set ``P`` whole to change it)."""
        out = self._state[self._p_at:].reshape(self.n, self.n).copy()
        out.flags.writeable = False
        return out

    @P.setter
    def P(self, value: np.ndarray) -> None:  # noqa: N802
        self._state[self._p_at:] = np.asarray(value, dtype=float).ravel()

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
        if self.scheme == Scheme.ALL_SLIP_OKELLO:
            x[lm.IBL:lm.IBR + 1] = p.inv_shape0
            sig = np.concatenate([sig, [p.inv_shape_sigma0] * 2])
        if self.lateral_slip:
            sig = np.concatenate([sig, [p.lateral_slip_sigma0]])  # k_β starts at 0
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
        counts = self._side_counts(frame) if self.uses_odometry else (0.0, 0.0)
        torque = self._side_torque(frame)
        state = self._state
        self._t = state[_S_T_STATE] = float(frame.t_s)
        state[_S_COUNTS:_S_COUNTS + 2] = counts
        state[_S_TORQUE:_S_TORQUE + 2] = torque
        state[_S_X:self._p_at] = x
        state[self._p_at:] = P.ravel()
        self._clear_history()
        self.skipped = {}
        return self.estimate()

    def _clear_history(self) -> None:
        self._frames: list[tuple[float, np.ndarray, np.ndarray]] = []
        self._history: dict[str, list[tuple[float, np.ndarray, np.ndarray]]] = {
            s: [] for s in SENSORS}
        self._n_history = 0  # frames expanded into _history
        self._n_bearings_used = 0

    # -- step ----------------------------------------------------------------------------------
    def update(self, frame: SensorFrame) -> PoseEstimate:
        """Predict to the frame, fusing its bearings at their own times on the way, then update
        with the inertial sensors, inclinometer and odometers at the frame time."""
        # This runs at every control step of an env: the usual frame (one wheel per side,
        # numpy arrays, bearings in order) takes the shortest way through, anything else the
        # checks and conversions of the helpers below, with the same result.
        t_prev = self._t
        if t_prev is None:
            raise RuntimeError("LindgrenEKF.update called before reset")
        t = float(frame.t_s)
        if not t_prev < t < math.inf:
            check_frame_time(t_prev, frame)  # raises: not finite, or not after the last frame
        try:  # one wheel per side, 1-D arrays: anything else raises here and takes the helpers
            i, j = self._single  # type: ignore[misc]
            c, tq = frame.enc_counts.tolist(), frame.wheel_torque_nm.tolist()
            count_l, count_r = float(c[i]), float(c[j])
            torque_l, torque_r = float(tq[i]), float(tq[j])
        except (TypeError, AttributeError, IndexError):
            count_l, count_r, torque_l, torque_r = self._readings(frame)
        n_bad = 0
        dispatcher = kernel.filter_frame
        call = _ENTRY[1] if _ENTRY[0] is dispatcher else _frame_entry(dispatcher)
        if self.uses_exteroceptive:
            bearing_z, bearing_t = frame.beacon_bearings_rad, frame.beacon_times_s
            # the usual frame's arrays go to the kernel as they are (it checks their order),
            # and they are the entry's type: float64 (numpy's own descriptor: an `is` instead
            # of a cold dtype comparison), 1-D, contiguous
            if not (type(bearing_z) is type(bearing_t) is np.ndarray
                    and bearing_z.dtype is bearing_t.dtype is _F64
                    and bearing_z.strides == bearing_t.strides == _F64_STRIDES):
                if (type(bearing_z) is type(bearing_t) is np.ndarray
                        and bearing_z.shape == bearing_t.shape == _EMPTY):
                    # no scan this frame (numpy gives an empty array the strides (0,)): the
                    # entry's own empty array, not the dispatcher's typing of every argument
                    bearing_t = bearing_z = _NO_BEARINGS
                else:
                    bearing_t, bearing_z, n_bad = self._frame_bearings(frame)
                    call = dispatcher  # it types whatever arrays these are
        else:
            bearing_t = bearing_z = _NO_BEARINGS
        # Python floats: numba's dispatcher types them faster than numpy scalars
        gyro, acc_x, acc_y = (float(frame.gyro_z_rad_s), float(frame.acc_x_mps2),
                              float(frame.acc_y_mps2))
        pitch, roll = float(frame.pitch_rad), float(frame.roll_rad)
        state, new = self._state, self._spare
        m = len(bearing_t)
        out = np.empty((m + _N_OUT_ROWS, 3))  # the history and the estimate keep views
        r = call(state, new, self._ctx, bearing_t, bearing_z, t_prev, t, gyro, acc_x, acc_y,
                  pitch, roll, count_l, count_r, torque_l, torque_r, out)
        n_accepted = r[0]  # R_CODE
        if n_accepted < 0.0:
            bearing_t, bearing_z, n_bad, out, r = self._refilter(
                frame, n_accepted, t_prev, t, gyro, acc_x, acc_y, pitch, roll, count_l, count_r,
                torque_l, torque_r)
            m, n_accepted = len(bearing_t), r[0]
        self._state, self._spare, self._t = new, state, t
        self._frames.append((t, bearing_t, out))
        if n_accepted == m + self._n_sensors and not n_bad:  # all accepted
            self._n_bearings_used += m
        else:
            self._count_skips(_status(out.ravel(), m), n_bad)
        return self._estimate(r, out[:3])

    def _refilter(self, frame: SensorFrame, code: float, *args: float) -> tuple:
        """The frame the kernel returned ``code`` for (< 0): raise with the counts, or run it
        again with its bearings sorted and filtered (late ones raise); returns the bearings'
        times and values, the number of non-finite ones, ``out`` and the kernel's values."""
        if code == kernel.BAD_COUNTS:
            self._side_counts(frame)  # raises with the counts
            raise RuntimeError("LindgrenEKF: the kernel rejected the frame's counts")
        # bearings out of order or NaN, or late (then this raises)
        bearing_t, bearing_z, n_bad = self._frame_bearings(frame)
        out = np.empty((len(bearing_t) + _N_OUT_ROWS, 3))
        r = kernel.filter_frame(self._state, self._spare, self._ctx, bearing_t, bearing_z, *args,
                                out)
        if r[0] < 0.0:  # never: _frame_bearings returns what the kernel accepts
            raise RuntimeError("LindgrenEKF: the kernel rejected the frame's bearings")
        return bearing_t, bearing_z, n_bad, out, r

    def _readings(self, frame: SensorFrame) -> tuple[float, float, float, float]:
        """Side-mean counts (NaN for the schemes without odometry) and torques, (left, right),
        of any frame."""
        counts = self._side_counts(frame) if self.uses_odometry else (math.nan, math.nan)
        return (*counts, *self._side_torque(frame))

    def _count_skips(self, status: tuple[int, ...], n_bad: int) -> None:
        """Count the frame's skipped measurements by reason: ``status`` holds the status codes
        of :func:`.kernel.filter_frame` (m bearings, then gyro, acc, tilt, odo), ``n_bad`` the
        non-finite bearings it never saw."""
        # A frame's codes repeat from frame to frame (a sensor that is missing stays missing),
        # so what they add to the counts is worked out once per pattern and reused.
        key = (status, n_bad)
        tally = self._tallies.get(key)
        if tally is None:
            tally = self._tally(status, n_bad)
            if len(self._tallies) < _MAX_TALLIES:
                self._tallies[key] = tally
        n_used, reasons = tally
        self._n_bearings_used += n_used
        for reason, n in reasons:
            self._skip(reason, n)

    def _tally(self, status: tuple[int, ...], n_bad: int) -> tuple[int, tuple]:
        """What a frame's status codes (:meth:`_count_skips`) add up to: (bearings used,
        ((reason, count), ...)) in the order the reasons first occur."""
        m = len(status) - 4
        reasons: dict[str, int] = {}

        def add(reason: str, n: int = 1) -> None:
            reasons[reason] = reasons.get(reason, 0) + n

        if n_bad > 0:
            add("bearing_nan", n_bad)
        n_used = 0
        for code in status[:m]:
            if code == kernel.ACCEPTED:
                n_used += 1
            elif code == kernel.INVALID_SOIL:
                add("bearing_invalid_soil")
            else:
                add("bearing_gated" if code == kernel.GATED else "bearing_no_map")
        if self.uses_exteroceptive:
            for sensor, code in zip(("gyro", "acc", "tilt"), status[m:m + 3], strict=True):
                if code != kernel.ACCEPTED:
                    add(f"{sensor}_nan")
        if self.uses_odometry and status[m + 3] != kernel.ACCEPTED:
            add(_ODO_SKIPS[status[m + 3]])
        return n_used, tuple(reasons.items())

    @property
    def history(self) -> dict[str, list[tuple[float, np.ndarray, np.ndarray]]]:
        """Per sensor (:data:`SENSORS`), every accepted innovation as ``(t, y, S)``.

        Built on demand from the frames' raw kernel outputs (views into them), so a filter
        whose history nobody reads does not pay for it."""
        hist = self._history
        for t, bearing_t, rows in self._frames[self._n_history:]:
            m = len(bearing_t)
            flat = rows.ravel()
            status, out = _status(flat, m), flat[_OUT_AT:]
            for j in range(m):
                if status[j] == kernel.ACCEPTED:
                    hist["bearing"].append((float(bearing_t[j]), out[2 * j:2 * j + 1],
                                            out[2 * j + 1:2 * j + 2].reshape(1, 1)))
            for k, (sensor, at, nz) in enumerate(_OUT_SENSORS):
                if status[m + k] == kernel.ACCEPTED:
                    o = 2 * m + at
                    hist[sensor].append((t, out[o:o + nz],
                                         out[o + nz:o + nz + nz * nz].reshape(nz, nz)))
        self._n_history = len(self._frames)
        return hist

    def predict_to(self, t_s: float) -> None:
        """Propagate ``x`` and ``P`` to time ``t_s`` (Lindgren Eq. 6-7); no-op if not later."""
        state, new = self._state, self._spare
        tau = t_s - float(state[_S_T_STATE])
        if tau <= 0.0:
            return
        new[:] = state
        kernel.predict_into(new[_S_X:self._p_at], new[self._p_at:].reshape(self.n, self.n),
                            tau, self._cfg, self._work, self._iwork)
        new[_S_T_STATE] = t_s
        self._state, self._spare = new, state

    def estimate(self) -> PoseEstimate:
        """The current estimate; ``extras`` holds R_w, k_s (scheme 5: Okello's B per wheel, as
        ``okello_Bl``, ``okello_Br``), with a lateral slip state ``k_beta_rad_per_g`` and the
        ``slip_angle_rad`` β̂ it gives now (also the estimate's ``slip_angle_rad``), and the
        skip counts."""
        state, p_at = self._state, self._p_at
        cov = state[p_at:].reshape(self.n, self.n)[:3, :3].copy()
        return self._estimate(kernel.estimate_values(state[_S_X:p_at], 0.0), cov)

    def _estimate(self, r: tuple[float, ...], cov: np.ndarray) -> PoseEstimate:
        """:meth:`estimate` from the values ``r`` of :func:`.kernel.estimate_values` and the
        covariance of the pose ``cov`` (3, 3), an array nothing writes."""
        # β̂ feeds a path follower's slip-angle feed-forward (Yamauchi Eq. 10); 0 without k_β.
        _, x_m, y_m, yaw, speed, yaw_rate, slip_angle, r_l, r_r, k_l, k_r, b_l, b_r, k_beta = r
        if not self.estimates_soil:
            r_l, r_r, k_l, k_r = self._fixed_soil
        extras: dict[str, object] = {"R_wl_m": r_l, "R_wr_m": r_r, "k_sl": k_l, "k_sr": k_r}
        if self._okello:
            extras["okello_Bl"] = 1.0 / b_l if b_l != 0.0 else math.inf
            extras["okello_Br"] = 1.0 / b_r if b_r != 0.0 else math.inf
        if self.lateral_slip:
            extras["k_beta_rad_per_g"] = k_beta
            extras["slip_angle_rad"] = slip_angle
        skipped = self.skipped
        extras["n_bearings_used"] = self._n_bearings_used
        extras["n_skipped"] = sum(skipped.values()) if skipped else 0
        extras["skipped"] = skipped.copy()
        return _construct(x_m, y_m, yaw, speed, yaw_rate, slip_angle, cov, extras)

    # -- input validation ----------------------------------------------------------------------
    def _side_counts(self, frame: SensorFrame) -> tuple[float, float]:
        """Mean cumulative counts of the (left, right) wheel group."""
        counts = frame.enc_counts
        single = self._single
        if (single is not None and type(counts) is np.ndarray and counts.ndim == 1
                and len(counts) >= self._min_wheels):
            left, right = float(counts[single[0]]), float(counts[single[1]])
            if not (math.isfinite(left) and math.isfinite(right)):
                raise ValueError(f"non-finite encoder counts at t = {frame.t_s}: "
                                 f"{[left, right]}")
            return left, right
        idx = self._left + self._right
        if not isinstance(counts, np.ndarray) or counts.ndim != 1 or len(counts) <= max(idx):
            counts = np.asarray(counts, dtype=float)
            if counts.ndim != 1 or len(counts) <= max(idx):
                raise ValueError(f"enc_counts has shape {counts.shape}; the geometry needs "
                                 f"wheel indices {idx}")
        c = counts.tolist()
        lefts = [float(c[i]) for i in self._left]
        rights = [float(c[i]) for i in self._right]
        if not all(math.isfinite(v) for v in lefts + rights):
            raise ValueError(f"non-finite encoder counts at t = {frame.t_s}: {lefts + rights}")
        # the same left-to-right sum np.mean does for these few values
        return sum(lefts) / len(lefts), sum(rights) / len(rights)

    def _side_torque(self, frame: SensorFrame) -> tuple[float, float]:
        """Mean torque of the (left, right) wheel group; NaN when the frame has none."""
        torque = frame.wheel_torque_nm
        single = self._single
        if (single is not None and type(torque) is np.ndarray and torque.ndim == 1
                and len(torque) >= self._min_wheels):
            return float(torque[single[0]]), float(torque[single[1]])
        if not isinstance(torque, np.ndarray):
            torque = np.asarray(torque, dtype=float)
        if torque.ndim != 1 or len(torque) <= max(self._left + self._right):
            return math.nan, math.nan
        tq = torque.tolist()
        left = [float(tq[i]) for i in self._left]
        right = [float(tq[i]) for i in self._right]
        return sum(left) / len(left), sum(right) / len(right)

    def _frame_bearings(self, frame: SensorFrame) -> tuple[np.ndarray, np.ndarray, int]:
        """Times and values of the finite bearings, sorted by time, and the number of
        non-finite ones."""
        z, tb = frame.beacon_bearings_rad, frame.beacon_times_s
        if (type(z) is np.ndarray and type(tb) is np.ndarray and z.dtype == _F64
                and tb.dtype == _F64 and z.ndim == 1 and tb.shape == z.shape):
            if z.size == 0:
                return _NO_BEARINGS, _NO_BEARINGS, 0
        else:
            z = np.atleast_1d(np.asarray(z, dtype=float))
            tb = np.atleast_1d(np.asarray(tb, dtype=float))
        if z.shape != tb.shape or z.ndim != 1:
            raise ValueError(f"beacon_bearings_rad {z.shape} and beacon_times_s {tb.shape} "
                             "must be 1-D of one length")
        if z.size == 0:
            return _NO_BEARINGS, _NO_BEARINGS, 0
        t_prev, t_now = self._t, float(frame.t_s)
        tl, zl = tb.tolist(), z.tolist()
        if t_prev < tl[0] and tl[-1] <= t_now:  # the usual frame: finite, in order, in range
            usual, last = True, t_prev
            for t_b, z_b in zip(tl, zl, strict=True):
                if not (t_b > last and math.isfinite(z_b)):
                    usual = False
                    break
                last = t_b
            if usual:
                return tb, z, 0
        pairs, n_bad, late = [], 0, []
        for t_b, z_b in zip(tl, zl, strict=True):
            if not (math.isfinite(t_b) and math.isfinite(z_b)):
                n_bad += 1
            elif t_b <= t_prev or t_b > t_now:
                late.append(t_b)
            else:
                pairs.append((t_b, z_b))
        if late:
            raise ValueError(f"bearing times {np.array(late)} lie outside this frame's interval "
                             f"({self._t}, {frame.t_s}]")
        if not pairs:
            return _NO_BEARINGS, _NO_BEARINGS, n_bad
        pairs.sort(key=lambda pair: pair[0])  # stable, as np.argsort(kind="stable")
        tz = np.array(pairs)
        return tz[:, 0].copy(), tz[:, 1].copy(), n_bad

    def _skip(self, reason: str, n: int = 1) -> None:
        if n <= 0:
            return
        # A bearing outside the χ² gate is the gate doing its job (clutter, a wrong beacon),
        # not a fault, so it is only counted; anything else is worth one warning.
        if reason not in self.skipped and reason not in _ROUTINE_SKIPS:
            logger.warning("LindgrenEKF: skipping measurement (%s); further ones are counted "
                           "in PoseEstimate.extras['skipped']", reason)
        elif logger.isEnabledFor(logging.DEBUG):  # a call per frame otherwise, for nothing
            logger.debug("LindgrenEKF: skipping %d measurement(s) (%s)", n, reason)
        self.skipped[reason] = self.skipped.get(reason, 0) + n
