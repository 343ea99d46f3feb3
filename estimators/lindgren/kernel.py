"""The arithmetic of one frame of Lindgren's EKF: prediction (Lindgren Eq. 6-7) and the Kalman
updates (Eq. 8-11) with the models of :mod:`.models` and :mod:`.observations`, compiled with
numba from this text.

:class:`~slipenv.estimators.lindgren.ekf.LindgrenEKF` keeps the bookkeeping (frame validation,
skip counts, innovation history, the estimate) and calls
:func:`filter_frame` once per frame: at 20 Hz a frame holds ~2.8 predictions and ~5.6 updates
on 13 x 13 arrays, which in numpy cost the per-call overhead (~0.5 µs a call), not the
arithmetic. One compiled call per frame runs them all, from the filter's state vector (time,
last readings, ``x``, ``P``) into a new one.

Numerical choices. The prediction computes the upper triangle of ``F P F' + Q`` and mirrors it,
so P leaves it exactly symmetric. The update, with ``S = H P H' + R = L L'`` (Cholesky) and the
optimal gain ``K = P H' S⁻¹`` (Lindgren's W, Eq. 10), turns the Joseph form
``(I - K H) P (I - K H)' + K R K'`` into Lindgren's Eq. 9, ``P - W S W' = P - A A'`` with
``A = P H' L⁻ᵀ``: a symmetric rank-n_z downdate, again computed on one triangle and mirrored,
at a third of the work of the product form.

Okello's inverse shape b = 1/B (scheme 5) is physical only at b >= 0: the curve saturates
(T -> T_max as s grows), and b < 0 would bend it the other way. Under a near-constant torque
the odometers cannot tell a curvature from a radius, and the unconstrained filter settles on
b < 0 with a radius off by centimetres. :func:`constrain_shape` keeps the constraint after
every update (see there and :func:`clamp_nonnegative` for how, and why not b = exp(c)).

The soil states must also carry the measured torques inside the small-slip model: an update
that would take them out (a bearing can move k_s through its correlation with the position)
is not applied (:func:`update_into`), and a soil estimate found outside is clipped to its
boundary before the odometer update (:func:`constrain_slip`). The odometers are skipped only
for a wheel that spins or locks by its own counts, judged with the state's uncertainty
(:func:`wheels_slip_beyond`). Measured on the reproduction's drives: a check of the slip the
soil estimate gives the torque rejected every later odometer reading once k_s had dropped at
the end of a turn, so the soil estimate could never be corrected again, and after the laser
cut the filter ran on its process model alone (single drives ended 40 m to 1 km off).

``NUMBA_DISABLE_JIT=1`` runs all of it as plain Python (slow, for debugging).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from slipenv.contracts import angles
from slipenv.contracts.compiled_cache import refresh_stale_cache

from .models import (
    G_MPS2,
    IA2,
    IBL,
    IBR,
    IKL,
    IKR,
    IOM,
    IRL,
    IRR,
    ITH,
    IV,
    IX,
    IY,
    N_OKELLO,
    N_SLIP,
    lateral_accel_g,
    lateral_index,
    process_F_into,
    process_fx_into,
    process_Q_into,
    soil_size,
    wrap,
)
from .observations import (
    bearing_H_into,
    ins_H_into,
    ins_hx_into,
    nearest_beacon,
    odo_H_into,
    odo_hx_into,
    odo_slip_H_into,
    odo_slip_hx_into,
    okello_slip_factor_inverse,
    slip_law,
    slip_params,
    tilt_H_into,
    tilt_hx_into,
    wheel_slip_model,
)

# the frame kernel carries the compiled code of the models and observations it calls
refresh_stale_cache(__file__, "models.py", "observations.py", angles.__file__)

# Layout of the filter's constant configuration vector ``cfg``: noise, geometry, and the
# sensors it fuses (C_INERTIAL 1.0 or 0.0, C_ODO_MODE the ``odo_mode`` of filter_frame), then
# from N_CFG on the oracle's soil, if any (the ``soil`` of the observation models).
(C_JERK_V, C_JERK_W, C_TILT_PSD, C_RADIUS_VAR, C_KS_VAR, C_R_GYRO, C_R_AX, C_R_AY, C_R_TILT,
 C_R_BEARING, C_GATE, C_R_ODO, C_TRACK, C_CPR, C_RADIUS, C_MAX_SLIP, C_B_VAR,
 C_KBETA_VAR, C_INERTIAL, C_ODO_MODE, C_BEACONS_AT, C_WORK_AT, C_IWORK_AT) = range(23)
N_CFG = 23
# A filter's context ``ctx`` (:func:`context_size`) is ``cfg``, then at C_BEACONS_AT the beacon
# map (x, y per beacon), at C_WORK_AT the float workspace (:func:`work_size`) and at
# C_IWORK_AT the integer one (:func:`iwork_size`, int64 in float64 memory): one array
# argument of filter_frame where there were four, each typed and unboxed at every call.

# Layout of a filter's state vector ``state`` (:func:`state_size`): the time the state refers
# to, the cumulative counts and the torques (left, right) of the last frame, then x (n) and
# P (n x n, row-major).
S_T_STATE, S_COUNTS, S_TORQUE, S_X = 0, 1, 3, 5

# Layout of the estimate's values (:func:`estimate_values`), a tuple of floats: a code (what
# filter_frame returns: the number of accepted measurements, or BAD_*), x, y, θ, v, Ω, the
# slip angle β̂, R_w and k_s (left, right), Okello's 1/B (left, right) and k_β; NaN where the
# state has no such entry (β̂ = 0).
R_CODE, R_POSE, R_SLIP_ANGLE, R_SOIL, R_INV_SHAPE, R_K_BETA, N_RESULT = 0, 1, 6, 7, 11, 13, 14

# Status codes of :func:`filter_frame`, per measurement.
ACCEPTED = 1
GATED = 0  # bearing outside the χ² gate
NOT_MEASURED = -1  # NaN reading, or no beacon map for a bearing
INVALID_SOIL = -2  # odometry update that would make R_w or k_s <= 0: not applied
TORQUE_NAN = -3
SLIP_OUT_OF_RANGE = -4

# What :func:`filter_frame` returns for a frame it leaves to the caller: counts not finite
# (the odometric schemes), or bearings not finite, not in time order, out of the frame's
# interval or of two lengths.
BAD_COUNTS = -1
BAD_BEARINGS = -2

# Layout of ``out``, shape (m + N_OUT_ROWS, 3) for m bearings: its first three rows are the
# covariance of the pose (x, y, θ) after the frame, and from entry OUT_AT of it as one
# row-major vector come per bearing (y, S), then gyro (y, S), then y (2) and S (2 x 2) of the
# accelerometers, the inclinometer and the odometers (at OUT_AT + 2 m + OUT_*), then a status
# code per bearing, gyro, accelerometers, inclinometer and odometers (from
# OUT_AT + 2 m + N_OUT_FIXED), the number of those codes that are ACCEPTED, and two unused.
OUT_AT = 9
OUT_GYRO, OUT_ACC, OUT_TILT, OUT_ODO, N_OUT_FIXED = 0, 2, 8, 14, 20
N_OUT_ROWS = (OUT_AT + N_OUT_FIXED + 5 + 2) // 3
# filter_frame's own temporaries, at the end of ``work`` (after those of predict_into and
# update_into): torques, y and S and R of a one- and of a two-dimensional measurement, a
# predicted measurement h (up to 3), then (frame_work_size) its Jacobian H, up to 3 x n
N_FRAME_WORK = 18


@njit(cache=True)
def predict(x: np.ndarray, P: np.ndarray, tau: float, cfg: np.ndarray) -> None:
    """Propagate ``x`` and ``P`` in place over τ (Lindgren Eq. 6-7): ``x ← f(x)`` (θ wrapped),
    ``P ← F P F' + Q`` with f, F and Q of :mod:`.models`."""
    n = x.shape[0]
    predict_into(x, P, tau, cfg, np.empty(work_size(n)), np.empty(iwork_size(n), np.int64))


@njit(cache=True)
def work_size(n: int) -> int:
    """Length of the float workspace of :func:`predict_into`, :func:`update_into` and
    :func:`filter_frame` (the last :func:`frame_work_size` entries, which the others leave)."""
    return 4 * n * n + 3 * n + 8 + frame_work_size(n)


@njit(cache=True)
def frame_work_size(n: int) -> int:
    """Length of :func:`filter_frame`'s own temporaries at the end of its workspace: the
    measurements' h and H, which must outlive :func:`update_into`'s use of the workspace."""
    return N_FRAME_WORK + 3 * n


@njit(cache=True)
def iwork_size(n: int) -> int:
    """Length of the integer workspace of :func:`predict_into`."""
    return n * n + n + 1


@njit(cache=True)
def state_size(n: int) -> int:
    """Length of the state vector of an n-state filter (layout: ``S_*``)."""
    return S_X + n + n * n


@njit(cache=True)
def state_dim(size: int) -> int:
    """n of a state vector of ``size`` entries: the root of n² + n = size - S_X."""
    return (int(math.sqrt(4 * (size - S_X) + 1)) - 1) // 2


def context_size(n: int, n_soil: int, n_beacons: int) -> int:
    """Length of the context of an n-state filter with ``n_soil`` oracle soil values and
    ``n_beacons`` beacons (layout: ``C_*``)."""
    return N_CFG + n_soil + 2 * n_beacons + work_size(n) + iwork_size(n)


@njit(cache=True)
def predict_into(x: np.ndarray, P: np.ndarray, tau: float, cfg: np.ndarray, work: np.ndarray,
                 iwork: np.ndarray) -> None:
    """:func:`predict` with its temporaries in the workspaces ``work`` (:func:`work_size`) and
    ``iwork`` (:func:`iwork_size`): a frame predicts about three times, and allocating its
    arrays each time cost as much as the arithmetic."""
    n = x.shape[0]
    nn = n * n
    F = work[:nn].reshape((n, n))
    Q = work[nn:2 * nn].reshape((n, n))
    FP = work[2 * nn:3 * nn].reshape((n, n))
    vals = work[3 * nn:4 * nn]  # F's non-zero entries, row by row (32 of 196 for n = 14)
    xp = work[4 * nn:4 * nn + n]  # f(x), apart from x: process_fx_into reads x throughout
    cols = iwork[:nn]  # their columns
    start = iwork[nn:nn + n + 1]  # row i's entries: start[i] to start[i + 1]
    process_F_into(x, tau, F, cfg[C_TILT_PSD])
    process_Q_into(x, tau, cfg[C_JERK_V], cfg[C_JERK_W], cfg[C_TILT_PSD], cfg[C_RADIUS_VAR],
                   cfg[C_KS_VAR], cfg[C_B_VAR], cfg[C_KBETA_VAR], Q)
    process_fx_into(x, tau, cfg[C_TILT_PSD], xp)
    xp[ITH] = wrap(xp[ITH])
    for i in range(n):
        x[i] = xp[i]
    # F is mostly the identity: list its non-zero entries once, then both products visit
    # only those; packed one row after the other, the prediction took 15 % less time than
    # with a table of n slots per row
    nnz = 0
    for i in range(n):
        start[i] = nnz
        for k in range(n):
            f = F[i, k]
            if f != 0.0:
                cols[nnz] = k
                vals[nnz] = f
                nnz += 1
    start[n] = nnz
    for i in range(n):
        for j in range(n):
            FP[i, j] = 0.0
        for t in range(start[i], start[i + 1]):
            k, f = cols[t], vals[t]
            for j in range(n):
                FP[i, j] += f * P[k, j]
    # P = FP F' + Q on the upper triangle, a column j at a time: its entries i <= j gather
    # FP's columns over row j of F's non-zeros (each entry sums in the same order as an entry
    # at a time did, at 14 % less time: 38 short loops over i instead of 105 over the entries)
    acc = xp  # the column's partial sums; f(x) is in x already
    for j in range(n):
        for i in range(j + 1):
            acc[i] = Q[i, j]
        for t in range(start[j], start[j + 1]):
            k, f = cols[t], vals[t]
            for i in range(j + 1):
                acc[i] += FP[i, k] * f
        for i in range(j + 1):
            P[i, j] = acc[i]
            P[j, i] = acc[i]


@njit(cache=True)
def update(x: np.ndarray, P: np.ndarray, y: np.ndarray, H: np.ndarray, R: np.ndarray,
           gate: float, soil_from: int, S_out: np.ndarray) -> int:
    """Kalman update in place with innovation ``y`` (n_z,), Jacobian ``H`` (n_z, n) and noise
    ``R`` (n_z, n_z) (Lindgren Eq. 8-11); θ is wrapped.

    Returns :data:`ACCEPTED`; :data:`GATED`, changing neither x nor P, when
    ``y' S⁻¹ y > gate``; :data:`INVALID_SOIL`, changing neither, when ``soil_from >= 0`` and
    the updated state would have an entry <= 0 from index ``soil_from`` to ``IKR`` (R_w, k_s).
    ``S`` (flattened) goes into ``S_out`` in every case.
    """
    n = x.shape[0]
    return update_into(x, P, y, H, R, gate, soil_from, S_out, np.empty(work_size(n)),
                       np.full(2, math.nan), np.zeros(0), math.inf)


@njit(cache=True)
def update_into(x: np.ndarray, P: np.ndarray, y: np.ndarray, H: np.ndarray, R: np.ndarray,
                gate: float, soil_from: int, S_out: np.ndarray, work: np.ndarray,
                torque: np.ndarray, soil: np.ndarray, max_slip: float) -> int:
    """:func:`update` with its temporaries in the workspace ``work`` (:func:`work_size`, at
    most two measurements), as :func:`predict_into`; with ``soil_from >= 0`` it also keeps
    the soil estimate in the slip model's domain for the measured ``torque`` (NaN: none):
    an update that would leave it a slip (:func:`soil_slip_extent`) above ``max_slip``, or
    above what it had if that was more, changes nothing and returns :data:`INVALID_SOIL`.

    Why the filter asks this of bearings too, not only of odometers: a bearing, through the
    soil states' correlation with the position, can move k_s as far as an odometer can, and
    did in the reproduction's drives. A soil estimate that gives the torque a slip beyond the
    model's range (k_s below |T| / ``max_slip``, or T beyond Okello's T_max) makes the
    odometers' model useless exactly where they are the only sensors that can correct it.
    """
    n, nz = x.shape[0], y.shape[0]
    PHt = work[:n * nz].reshape((n, nz))
    for i in range(n):
        for a in range(nz):
            PHt[i, a] = 0.0
    for a in range(nz):
        for k in range(n):
            h = H[a, k]
            if h != 0.0:
                for i in range(n):
                    PHt[i, a] += P[i, k] * h
    S = work[n * nz:n * nz + nz * nz].reshape((nz, nz))
    for a in range(nz):
        for b in range(nz):
            S[a, b] = R[a, b]
    for a in range(nz):
        for b in range(nz):
            for k in range(n):
                S[a, b] += H[a, k] * PHt[k, b]
    for a in range(nz):
        for b in range(a):
            S[a, b] = S[b, a] = 0.5 * (S[a, b] + S[b, a])
    for a in range(nz):
        for b in range(nz):
            S_out[a * nz + b] = S[a, b]
    # Cholesky S = L L' in place: L in the lower triangle of S (few allocations: at 20 Hz the
    # filter runs some 350 of these small updates a second, where allocating costs as much as
    # the arithmetic)
    L = S
    for a in range(nz):
        for b in range(a + 1):
            s = L[a, b]
            for k in range(b):
                s -= L[a, k] * L[b, k]
            L[a, b] = math.sqrt(s) if a == b else s / L[b, b]
    u = work[n * nz + nz * nz:n * nz + nz * nz + nz]  # L u = y, in place
    for a in range(nz):
        u[a] = y[a]
    for a in range(nz):
        s = u[a]
        for k in range(a):
            s -= L[a, k] * u[k]
        u[a] = s / L[a, a]
    nis = 0.0  # y' S⁻¹ y = |L⁻¹ y|²
    for a in range(nz):
        nis += u[a] * u[a]
    if nis > gate:
        return GATED
    w = u  # L' w = u: w = S⁻¹ y, in place (row a needs only the w[k] of k > a)
    for a in range(nz - 1, -1, -1):
        s = w[a]
        for k in range(a + 1, nz):
            s -= L[k, a] * w[k]
        w[a] = s / L[a, a]
    if soil_from >= 0:  # the soil must stay in its domain: check before changing anything
        base = n * nz + nz * nz + nz
        cand = work[base:base + n]
        for i in range(n):
            xi = x[i]
            for a in range(nz):
                xi += PHt[i, a] * w[a]
            cand[i] = xi
        for i in range(soil_from, IKR + 1):
            if not cand[i] > 0.0:
                return INVALID_SOIL
        after = soil_slip_extent(cand, torque, soil)
        if not (after <= max_slip or after <= soil_slip_extent(x, torque, soil)):
            return INVALID_SOIL
        for i in range(n):
            x[i] = cand[i]
    else:
        for i in range(n):
            for a in range(nz):
                x[i] += PHt[i, a] * w[a]
    x[ITH] = wrap(x[ITH])
    A = PHt  # A = P H' L⁻ᵀ in place, row by row: L Aᵢ' = (P H')ᵢ'
    for i in range(n):
        for a in range(nz):
            s = A[i, a]
            for k in range(a):
                s -= L[a, k] * A[i, k]
            A[i, a] = s / L[a, a]
    for i in range(n):
        for j in range(i, n):
            d = P[i, j]
            for a in range(nz):
                d -= A[i, a] * A[j, a]
            P[i, j] = d
            P[j, i] = d
    return ACCEPTED


SLIP_GATE_SIGMAS = 3.0  # the wheels' ground speed interval of the slip range check (99.7 %)


@njit(cache=True)
def wheels_slip_beyond(x: np.ndarray, P: np.ndarray, tau: float, dcount_l: float,
                       dcount_r: float, track_width_m: float, counts_per_rad: float,
                       soil: np.ndarray, max_slip: float, h0: np.ndarray,
                       H0: np.ndarray) -> bool:
    """True when a wheel's counts over the interval show a slip of ``max_slip`` or more for
    every ground speed within :data:`SLIP_GATE_SIGMAS` standard deviations of the state's:
    a wheel that spins or locks, outside the small-slip model (Lindgren Eq. 24).

    Slip is ``1 - z₀ / c`` for c counts where rolling without slip gives z₀ (Eq. 15 with the
    wheel's radius, Lindgren Eq. 32's ground speed over rim speed); one count of quantisation
    is allowed. Why by the counts and the state's uncertainty: the slip the soil estimate
    gives the measured torque, or the counts against the state's speed alone, both decide
    with what the odometers are there to correct. A soil estimate or a yaw rate gone wrong
    (the state lagging the end of a turn, with no gyro) then rejects every later odometer
    reading, and nothing corrects it again. Here the state's uncertainty grows while the
    odometers are rejected, until they are taken again. ``h0`` (2,) and ``H0`` (2, n) are
    workspace.
    """
    r_w, _ = slip_params(x, soil)
    odo_hx_into(x, tau, 1.0, track_width_m, counts_per_rad, h0)  # no-slip counts × R_w
    odo_H_into(x, tau, 1.0, track_width_m, counts_per_rad, H0)
    n = x.shape[0]
    for i in range(2):
        c = dcount_l if i == 0 else dcount_r
        var = 0.0
        for j in range(n):
            if H0[i, j] != 0.0:
                for k in range(n):
                    var += H0[i, j] * P[j, k] * H0[i, k]
        z0 = h0[i] / r_w[i]
        half = SLIP_GATE_SIGMAS * math.sqrt(max(var, 0.0)) / r_w[i]
        off = max(z0 - half - c, c - z0 - half, 0.0)  # counts outside the no-slip interval
        if off > max_slip * abs(c) + 1.0:
            return True
    return False


@njit(cache=True)
def soil_slip_extent(x: np.ndarray, torque: np.ndarray, soil: np.ndarray) -> float:
    """The largest |slip| the state's soil gives the measured ``torque`` (:func:`wheel_slip`,
    Lindgren Eq. 24, or Okello's curve): ``inf`` where a radius or k_s is not positive or the
    torque reaches the curve's T_max, 0 without a torque reading."""
    r_w, k_s = slip_params(x, soil)
    for i in range(2):
        if not (r_w[i] > 0.0 and k_s[i] > 0.0):
            return math.inf
    if not (math.isfinite(torque[0]) and math.isfinite(torque[1])):
        return 0.0
    okello = soil_size(x.shape[0]) == N_OKELLO
    worst = 0.0
    for i in range(2):  # |s| is even in the direction of travel: σ = 1
        s = slip_law(abs(torque[i]) / k_s[i], k_s[i], x[IBL + i] if okello else 0.0,
                     okello)[0]
        if not math.isfinite(s):
            return math.inf
        worst = max(worst, abs(s))
    return worst


@njit(cache=True)
def mills_lambda(alpha: float) -> float:
    """λ(α) = φ(α) / (1 - Φ(α)), the inverse Mills ratio of the standard normal: the shift, in
    standard deviations, of the mean of N(0, 1) truncated to values >= α. For α > 5 by the
    continued fraction (1 - Φ) / φ = 1 / (α + 1 / (α + 2 / (α + ...))), where 1 - Φ underflows
    or loses its digits."""
    if alpha <= 5.0:
        return math.sqrt(2.0 / math.pi) * math.exp(-0.5 * alpha * alpha) / math.erfc(
            alpha / math.sqrt(2.0))
    cf = alpha
    for k in range(40, 0, -1):
        cf = alpha + k / cf
    return cf


@njit(cache=True)
def clamp_nonnegative(x: np.ndarray, P: np.ndarray, i: int) -> None:
    """Impose ``x_i >= 0`` in place on a Gaussian estimate ``N(x, P)`` with ``x_i < 0``.

    The estimate moves to the mode of the density truncated to ``x_i >= 0``, the constrained
    MAP: x_i = 0, and every other state to its conditional mean there, ``x -= P e_i μ / σ²``
    (μ = x_i, σ² = P_ii; the estimate projection of Simon and Chia, "Kalman filtering with
    state equality constraints", IEEE Trans. AES 38(1), 2002, for an active inequality).
    P_ii becomes the mean square error of that estimate under the truncated density,
    ``E[x_i² | x_i >= 0] = σ² (1 + αλ - λ² + (λ - α)²)`` with α = -μ/σ and
    λ = :func:`mills_lambda` (α) (the truncated normal's mean μ + σλ and variance
    σ² (1 + αλ - λ²): Johnson, Kotz and Balakrishnan, Continuous Univariate Distributions 1,
    §13.10.1), and the rest of P shrinks with it along the regression on x_i,
    ``P -= P e_i e_i' P (1 - E[x_i²] / σ²) / σ²``.

    Why this and not the two textbook choices: projecting P too (P_ii = 0) tells the filter
    it knows x_i exactly, so an early violation under a wide prior freezes x_i at 0 for
    hundreds of metres; the truncated density's mean (Simon and Simon, Int. J. Systems
    Science 41(2), 2010) puts x_i at σλ > 0, a curvature the data never showed (with the
    prior's σ = 8, about 6). Measured on the tests' 120 s synthetic drive on Okello's curve
    (1/B = 7, scheme 5 with k_β, bearings cut at 60 s): this finds 1/B = 5.9 / 6.3 and ends
    1.37 m off; projecting P freezes 1/B at 0.01 / 1.2 (1.99 m); the truncated mean ends at
    6.4 / 5.4 (1.42 m), but on the linear soil at 3.5 / 0.1 where this ends at 1.9 / 0.1.
    Where the move would make R_w or k_s <= 0, only x_i is set (never met in the
    reproduction's drives).
    """
    n = x.shape[0]
    var = P[i, i]
    mu = x[i]
    if not var > 0.0:
        x[i] = 0.0
        return
    sd = math.sqrt(var)
    alpha = -mu / sd
    lam = mills_lambda(alpha)
    shrink = min(max(1.0 + alpha * lam - lam * lam + (lam - alpha) ** 2, 0.0), 1.0)
    dmu = -mu
    for j in range(IRL, IKR + 1):
        if not x[j] + P[j, i] * dmu / var > 0.0:
            x[i] = 0.0
            return
    for j in range(n):
        x[j] += P[j, i] * dmu / var
    x[i] = 0.0
    x[ITH] = wrap(x[ITH])
    # P -= c P eᵢ eᵢ' P, on the upper triangle and mirrored, with P's column i as it was: the
    # entries off row and column i first, then those of row and column i, P_ii last, so that
    # every one reads the column before it changes (in place of a copy of the column, which
    # would be the frame kernel's only heap allocation; see filter_frame)
    c = (1.0 - shrink) / var
    for a in range(n):
        if a == i:
            continue
        for b in range(a, n):
            if b != i:
                d = P[a, b] - P[a, i] * P[b, i] * c
                P[a, b] = d
                P[b, a] = d
    for a in range(n):
        if a != i:
            d = (P[a, i] - P[a, i] * P[i, i] * c if a < i
                 else P[i, a] - P[i, i] * P[a, i] * c)
            P[a, i] = d
            P[i, a] = d
    P[i, i] = P[i, i] - P[i, i] * P[i, i] * c


@njit(cache=True)
def constrain_shape(x: np.ndarray, P: np.ndarray) -> None:
    """Keep Okello's inverse shapes b = 1/B >= 0 (scheme 5; a no-op for other layouts).

    An update that leaves b < 0 is followed by :func:`clamp_nonnegative`: b to 0 (the linear
    law, the curve's limit), the states correlated with it (the radius it was trading
    against) to their conditional means there. The second wheel's clamp moves the first
    wheel's b by their correlation, so the left one is checked again, and a last round-off
    below 0 is set to 0. A reparametrisation b = exp(c) or softplus(c) would keep b > 0 too,
    but never reach the linear law the ablation world is made of: c would run off to -∞ with
    a vanishing Jacobian, and the filter would stop learning b exactly where the data are
    linear. The clamp keeps the linear law a reachable state and costs nothing while b > 0.
    """
    if soil_size(x.shape[0]) != N_OKELLO:
        return
    for i in (IBL, IBR, IBL):
        if x[i] < 0.0:
            clamp_nonnegative(x, P, i)
    for i in (IBL, IBR):
        x[i] = max(x[i], 0.0)


@njit(cache=True)
def constrain_slip(x: np.ndarray, torque: np.ndarray, max_slip: float) -> None:
    """Keep the soil states (13 or 15-state layouts) such that each wheel's measured torque
    has a slip below ``max_slip`` (Lindgren Eq. 24, or Okello's curve), in place.

    Called for a wheel whose counts show it rolls within that range
    (:func:`wheels_slip_beyond`): a soil estimate that gives its torque a larger slip, or puts
    it beyond Okello's T_max, is outside the small-slip model where the data are, and the
    odometers' model of it is useless (at T_max its prediction has a pole). k_s is clipped to
    at least |T| / ``max_slip``, then, for Okello's curve, 1/B to at most the value that gives
    that slip; the odometer update then corrects them further. Clipped, not moved with the
    other states to their conditional means as :func:`clamp_nonnegative` moves 1/B: at the
    end of a turn that regression on a soil state swung v and Ω by metres per second
    (measured on the reproduction's drives), the correlations there being the linearisation's.
    """
    okello = soil_size(x.shape[0]) == N_OKELLO
    for i in range(2):
        t = abs(torque[i])
        if t == 0.0:
            continue
        ik = IKL + i
        if not (x[ik] > 0.0 and t / x[ik] < max_slip):
            x[ik] = t / max_slip
        if not okello:
            continue
        s_lin = t / x[ik]
        # okello (True here) rather than a literal True: slip_law is then compiled once
        if not slip_law(s_lin, x[ik], x[IBL + i], okello)[0] < max_slip:
            x[IBL + i] = 2.0 * okello_slip_factor_inverse(max_slip / s_lin) / s_lin


@njit(cache=True)
def _diag2_into(R: np.ndarray, a: float, b: float) -> None:
    R[0, 0], R[0, 1], R[1, 0], R[1, 1] = a, 0.0, 0.0, b


@njit(cache=True)
def _record(out: np.ndarray, at: int, y: np.ndarray, S: np.ndarray) -> None:
    nz = y.shape[0]
    for a in range(nz):
        out[at + a] = y[a]
    for k in range(nz * nz):
        out[at + nz + k] = S[k]


@njit(cache=True)
def estimate_values(x: np.ndarray, code: float) -> tuple:
    """The values of the estimate of state ``x`` (layout: ``R_*``), after ``code``. β̂ is
    ``atan(k_β a_y)`` with the lateral specific force of Eq. 14, the body slip angle a path
    follower feeds forward (Yamauchi Eq. 10)."""
    n, nan = x.shape[0], math.nan
    ns, ik = soil_size(n), lateral_index(n)
    slip_angle = math.atan(x[ik] * lateral_accel_g(x[IV], x[IOM], x[IA2])) if ik >= 0 else 0.0
    k_beta = x[ik] if ik >= 0 else nan
    r_l, r_r, k_l, k_r = (x[IRL], x[IRR], x[IKL], x[IKR]) if ns >= N_SLIP else (
        nan, nan, nan, nan)
    b_l, b_r = (x[IBL], x[IBR]) if ns == N_OKELLO else (nan, nan)
    # float(): the plain Python run (NUMBA_DISABLE_JIT) gives Python floats too
    return (float(code), float(x[IX]), float(x[IY]), float(x[ITH]), float(x[IV]),
            float(x[IOM]), float(slip_angle), float(r_l), float(r_r), float(k_l), float(k_r),
            float(b_l), float(b_r), float(k_beta))


@njit(cache=True)
def _rejected(code: float) -> tuple:
    """What :func:`filter_frame` returns for a frame it leaves to the caller."""
    nan = math.nan
    return (float(code), nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan, nan)


@njit(cache=True)
def _finish(x: np.ndarray, P: np.ndarray, state: np.ndarray, status: np.ndarray,
            out: np.ndarray, cov: np.ndarray, t_state: float) -> tuple:
    """The end of :func:`filter_frame`: the time into ``state``, the number of accepted
    measurements after the status codes in ``out``, the pose covariance into ``cov``; returns
    the estimate's values with that number."""
    state[S_T_STATE] = t_state
    n_accepted = 0.0
    for k in range(status.shape[0]):
        n_accepted += status[k] == ACCEPTED
    out[3 * (status.shape[0] - 4) + N_OUT_FIXED + 4] = n_accepted
    for i in range(3):
        for j in range(3):
            cov[3 * i + j] = P[i, j]
    return estimate_values(x, n_accepted)


# Without numba's reference-counted runtime (NRT): the frame kernel and everything it calls
# neither allocate nor keep an array, so their array views need no reference counts. With it,
# each view and each array passed to a callee took an atomic increment and a decrement through
# a call into the runtime (hundreds of call sites, with the exit paths), and each array argument a
# heap-allocated record at every call; without it the frame took 11-18 % less time, measured on
# FarmField-v0's frames (bitwise the same results).
def nrt_free_options(options: type | None = None) -> dict:
    """``{"_nrt": False}`` where numba's CPU target knows that option (numba's own, private:
    a release may drop it), else ``{}``: without it the kernel compiles with the runtime, the
    same results some 15 % slower, instead of failing at its first call. ``options``: the
    target-options class to ask (numba's ``CPUTargetOptions`` by default)."""
    if options is None:
        try:
            from numba.core.cpu import CPUTargetOptions as options
        except ImportError:
            return {}
    return {"_nrt": False} if hasattr(options, "_nrt") else {}


@njit(cache=True, **nrt_free_options())
def filter_frame(
    state: np.ndarray, new: np.ndarray, ctx: np.ndarray, bearing_t: np.ndarray,
    bearing_z: np.ndarray, t_prev: float, t: float, gyro_z: float, acc_x: float, acc_y: float,
    pitch: float, roll: float, count_l: float, count_r: float, torque_l: float,
    torque_r: float, out_rows: np.ndarray,
) -> tuple:
    """One frame from the filter's ``state`` (layout ``S_*``) into ``new``, the same layout:
    each bearing at its own time (predict to it, nearest-innovation association, χ²-gated
    update, Lindgren Eq. 17), predict to ``t``, then gyro and accelerometers (Eq. 14) and
    inclinometer when ``cfg[C_INERTIAL]``, then odometers over the frame interval
    τ = ``t - t_prev``: by ``cfg[C_ODO_MODE]``, Eq. 15 (0), Eq. 37 (1) with the slip model of
    the state's layout (R_w, k_s and for 15 states Okello's 1/B from ``x``) or, for 9 states,
    the oracle's soil ``cfg[N_CFG:]`` ``[R_wl, R_wr, k_sl, k_sr]``; none (-1). ``cfg``, the
    beacon map and the workspaces are the parts of ``ctx`` (``C_*``).

    The odometers' counts over the interval are ``count_*`` (cumulative) less the last
    frame's, and the torque is the mean of ``torque_*`` and the last frame's reading (the
    reading alone where the last one is NaN); both readings go into ``new`` for the next
    frame (the counts only in the odometric schemes).

    ``out_rows`` (m + :data:`N_OUT_ROWS`, 3) receives the covariance of the pose (x, y, θ)
    after the frame, the innovation ``y`` and its ``S`` of each accepted measurement, a
    status code per bearing, then gyro, accelerometers, inclinometer, odometers, and the
    number of accepted ones (layout: ``OUT_*``). Returns :func:`estimate_values` of the new
    state after that number: the caller builds the estimate from Python floats, with no
    numpy call. The frame's readings are plain floats and everything else rides in six
    arrays: this call is made at every control step, and its dispatch costs ~0.1 µs per
    array argument it types and unboxes.

    Returns :data:`BAD_COUNTS` (the other values NaN) when an odometric scheme's counts are
    not finite, and :data:`BAD_BEARINGS` unless the bearings are finite, in time order, in
    the frame's interval ``(t_prev, t]`` and as many as their times (the caller sorts and
    filters them, or rejects the frame, and calls again); ``state`` is only read, so a frame
    that fails leaves the filter as it was. The checks are here because a Python loop over the
    bearings of every frame cost a tenth of the filter's step.
    """
    m = bearing_t.shape[0]
    b_at, w_at, i_at = int(ctx[C_BEACONS_AT]), int(ctx[C_WORK_AT]), int(ctx[C_IWORK_AT])
    cfg, soil = ctx[:b_at], ctx[N_CFG:b_at]
    beacons_xy = ctx[b_at:w_at].reshape(((w_at - b_at) // 2, 2))
    work, iwork = ctx[w_at:i_at], ctx[i_at:].view(np.int64)
    W, cpr, max_slip = cfg[C_TRACK], cfg[C_CPR], cfg[C_MAX_SLIP]
    inertial, odo_mode, tau = cfg[C_INERTIAL] != 0.0, int(cfg[C_ODO_MODE]), t - t_prev
    if odo_mode >= 0 and not (math.isfinite(count_l) and math.isfinite(count_r)):
        return _rejected(float(BAD_COUNTS))
    if bearing_z.shape[0] != m:
        return _rejected(float(BAD_BEARINGS))
    last = t_prev
    for j in range(m):
        tb = bearing_t[j]
        if not (tb > t_prev and tb >= last and tb <= t and math.isfinite(bearing_z[j])):
            return _rejected(float(BAD_BEARINGS))
        last = tb
    flat = out_rows.reshape(out_rows.size)
    cov, out = flat[:OUT_AT], flat[OUT_AT:]
    for k in range(new.shape[0]):
        new[k] = state[k]
    t_state = state[S_T_STATE]
    n = state_dim(new.shape[0])
    x, P = new[S_X:S_X + n], new[S_X + n:].reshape((n, n))
    dcount_l, dcount_r = count_l - state[S_COUNTS], count_r - state[S_COUNTS + 1]
    if odo_mode >= 0:
        new[S_COUNTS], new[S_COUNTS + 1] = count_l, count_r
    a0, a1 = state[S_TORQUE], state[S_TORQUE + 1]
    new[S_TORQUE], new[S_TORQUE + 1] = torque_l, torque_r
    # the mean torque over the interval
    torque_l = 0.5 * (a0 + torque_l) if math.isfinite(a0) else torque_l
    torque_r = 0.5 * (a1 + torque_r) if math.isfinite(a1) else torque_r
    # the soil states, where the state has them, must stay in the model's domain
    soil_from = IRL if soil_size(n) >= N_SLIP else -1
    # the inertial updates' "no soil check", -1 as a run-time value: a literal -1 made numba
    # compile a second update_into for it (2,900 more instructions, both run every frame,
    # and a frame's cost at an env step is mostly fetching its code)
    no_soil = min(soil_from, -1)
    status = out[2 * m + N_OUT_FIXED:3 * m + N_OUT_FIXED + 4]
    # the frame's temporaries live in the workspace and the models write into it: each heap
    # allocation cost about what its arithmetic did (FarmField's filter made 58 a frame)
    tmp = work[work.shape[0] - frame_work_size(n):]
    T, y1, S1, R1 = tmp[0:2], tmp[2:3], tmp[3:4], tmp[4:5].reshape((1, 1))
    y2, S2, R2 = tmp[5:7], tmp[7:11], tmp[11:15].reshape((2, 2))
    h, H = tmp[15:18], tmp[N_FRAME_WORK:N_FRAME_WORK + 3 * n].reshape((3, n))
    T[0], T[1] = torque_l, torque_r
    for j in range(m):
        if bearing_t[j] > t_state:
            predict_into(x, P, bearing_t[j] - t_state, cfg, work, iwork)
            t_state = bearing_t[j]
        if beacons_xy.shape[0] == 0:
            status[j] = NOT_MEASURED
            continue
        b, y1[0] = nearest_beacon(x, bearing_z[j], beacons_xy)
        R1[0, 0] = cfg[C_R_BEARING]
        bearing_H_into(x, beacons_xy[b], H[0:1])
        status[j] = update_into(x, P, y1, H[0:1], R1, cfg[C_GATE], soil_from, S1, work, T,
                                soil, max_slip)
        constrain_shape(x, P)
        out[2 * j], out[2 * j + 1] = y1[0], S1[0]
    if t > t_state:
        predict_into(x, P, t - t_state, cfg, work, iwork)
        t_state = t
    base = 2 * m
    for k in range(4):
        status[m + k] = NOT_MEASURED
    if inertial:
        if math.isfinite(gyro_z):  # g1 = Ω
            ins_hx_into(x, h)
            ins_H_into(x, H)
            y1[0] = gyro_z - h[2]
            R1[0, 0] = cfg[C_R_GYRO]
            status[m] = update_into(x, P, y1, H[2:3], R1, math.inf, no_soil, S1, work, T, soil,
                                    max_slip)
            constrain_shape(x, P)
            _record(out, base + OUT_GYRO, y1, S1)
        if math.isfinite(acc_x) and math.isfinite(acc_y):  # [a1/g, a2/g]
            ins_hx_into(x, h)
            ins_H_into(x, H)
            y2[0], y2[1] = acc_x / G_MPS2 - h[0], acc_y / G_MPS2 - h[1]
            _diag2_into(R2, cfg[C_R_AX], cfg[C_R_AY])
            status[m + 1] = update_into(x, P, y2, H[0:2], R2, math.inf, no_soil, S2, work, T,
                                        soil, max_slip)
            constrain_shape(x, P)
            _record(out, base + OUT_ACC, y2, S2)
        if math.isfinite(pitch) and math.isfinite(roll):  # REP 103 -> Lindgren's α1, α2
            tilt_hx_into(x, h[0:2])
            tilt_H_into(x, H[0:2])
            y2[0], y2[1] = -pitch - h[0], -roll - h[1]
            _diag2_into(R2, cfg[C_R_TILT], cfg[C_R_TILT])
            status[m + 2] = update_into(x, P, y2, H[0:2], R2, math.inf, no_soil, S2, work, T,
                                        soil, max_slip)
            constrain_shape(x, P)
            _record(out, base + OUT_TILT, y2, S2)
    if odo_mode < 0:
        return _finish(x, P, new, status, out, cov, t_state)
    h2, H2 = h[0:2], H[0:2]
    if odo_mode == 0:
        odo_hx_into(x, tau, cfg[C_RADIUS], W, cpr, h2)
        odo_H_into(x, tau, cfg[C_RADIUS], W, cpr, H2)
    else:
        if not (math.isfinite(torque_l) and math.isfinite(torque_r)):
            status[m + 3] = TORQUE_NAN
            return _finish(x, P, new, status, out, cov, t_state)
        if wheels_slip_beyond(x, P, tau, dcount_l, dcount_r, W, cpr, soil, max_slip, h2,
                              H2):
            status[m + 3] = SLIP_OUT_OF_RANGE  # Eq. 24 is a small-slip model
            return _finish(x, P, new, status, out, cov, t_state)
        if soil_from >= 0:
            constrain_slip(x, T, max_slip)
        # the wheel as a loop variable: literal 0 and 1 made numba compile the slip model
        # twice more (see no_soil)
        pole = False
        for side in range(2):
            pole = pole or not abs(wheel_slip_model(x, tau, T, W, soil, side)[0]) < 1.0
        if pole:  # the model's pole: no prediction
            status[m + 3] = SLIP_OUT_OF_RANGE
            return _finish(x, P, new, status, out, cov, t_state)
        odo_slip_hx_into(x, tau, T, W, cpr, soil, h2)
        odo_slip_H_into(x, tau, T, W, cpr, soil, H2)
    y2[0], y2[1] = dcount_l - h2[0], dcount_r - h2[1]
    _diag2_into(R2, cfg[C_R_ODO], cfg[C_R_ODO])
    status[m + 3] = update_into(x, P, y2, H2, R2, math.inf, soil_from, S2, work, T, soil,
                                max_slip)
    constrain_shape(x, P)
    _record(out, base + OUT_ODO, y2, S2)
    return _finish(x, P, new, status, out, cov, t_state)
