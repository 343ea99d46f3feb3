"""State layout and process model of Lindgren's navigation EKF, as plain functions.

Every function takes the state vector ``x`` first and returns a prediction or its Jacobian, so
the filter (:mod:`slipenv.estimators.lindgren.ekf`, through :mod:`.kernel`), the synthetic
data generator (:mod:`tests.estimators.lindgren_synth`) and the tests share one copy of the
maths (Lindgren, Hague, Probert Smith and Marchant, "Relating torque and slip in an odometric
model for an autonomous agricultural vehicle", Eq. 12-13 and §4). The observation models
(Eq. 14-17, 37-41) are in :mod:`slipenv.estimators.lindgren.observations`.

State (Lindgren Eq. 12, extended for the slip-aware model of §4)::

    index  symbol  unit      meaning
    0      x       m         position, world x
    1      y       m         position, world y
    2      θ       rad       heading, counter-clockwise from world x
    3      v       m/s       forward speed
    4      Ω       rad/s     yaw rate
    5      v̇       m/s²      forward acceleration
    6      Ω̇       rad/s²    yaw acceleration
    7      α1      rad       pitch, nose UP positive (Lindgren's sign; SensorFrame pitch is -α1)
    8      α2      rad       roll, RIGHT side up positive (SensorFrame roll is -α2)
    9      R_wl    m         effective rolling radius, left wheel      } slip-aware
    10     R_wr    m         effective rolling radius, right wheel     } model only
    11     k_sl    T units   torque/slip gradient, left  (T = k_s s)   } (13 states)
    12     k_sr    T units   torque/slip gradient, right               }
    13     b_l     -         inverse Okello shape 1/B, left           } Okello's curve
    14     b_r     -         inverse Okello shape 1/B, right          } (scheme 5, 15 states)
    last   k_β     rad/g     lateral slip gain, tan β = k_β a_y        optional, any scheme

The lateral slip gain is the one state beyond the paper's that any layout may carry, always as
the last entry (n = 10, 14 or 16): the body's velocity at the reference point leans by the
slip angle β off the heading, ``tan β = k_β a_y``, where ``a_y = v Ω / g - α2`` is the
lateral specific force (Eq. 14's predicted lateral accelerometer reading, in g). The side force
the tyres carry is m a_y; a linear side-force/slip-angle law (the small-slip limit of the same
Janosi shear that gives Eq. 24 longitudinally) makes β proportional to it, so one gain describes
both turn directions and any radius or speed, where a random-walk β would lag behind every
change of turn. It is estimated like k_s: random walk with variance growing with distance.
Without it (the paper's model) the filter explains a crab by a heading bias, which the bearings
then turn into a position bias across the track.

The signs of α1 and α2 are the ones that make Eq. 14 hold for a specific-force accelerometer:
nose-up pitch adds +g α1 to the forward reading, right-side-up roll adds -g α2 to the
lateral (leftward) reading. ``k_s`` is in whatever unit the torque sensor reports: torque only
ever enters as the ratio ``T / k_s``, so an uncalibrated torque scale is absorbed by ``k_s``
(Lindgren §3.2: "the units of T and T_max are unimportant").

Departures from the paper, each for a stated reason:

* Eq. 13 is an Euler step. :func:`process_fx` integrates the same continuous model (constant
  v̇ and Ω̇ over τ) to second order: the filter also predicts over the short, irregular
  intervals between asynchronous bearings, and the Euler heading lag τΩ/2 biases the position
  sideways by v τ Ω / 2 every step (6 mm per metre on Lindgren's 4 m circles at 20 Hz). To
  first order in τ the two are identical.
* The paper's pitch-rate input u = α̇1 comes from a pitch gyro that ``SensorFrame`` does not
  carry, so pitch and roll follow a process model here, turned into each other through the
  heading change as the vehicle yaws on a tilted plane (the coupling the paper applies to α2,
  here as an exact rotation so that it stays bounded at any yaw rate), and observed by the
  inclinometer when the frame has one. The process is the first-order Gauss-Markov one
  (:func:`tilt_decay`) with the field's slope prior :data:`TILT_SIGMA_RAD` as its stationary
  standard deviation, not a random walk: a field's tilt stays within its slope, and on a drive
  without an inclinometer nothing else bounds its covariance. Measured on the reproduction's
  straights without inertial sensors (a flat field), the random walk let the filters with the
  lateral slip gain explain part of the crab by the tilt, which the 180° turns rotate into the
  roll of ``a_y``: tilt states of several degrees for the slip models and tens of degrees for
  the oracle with k_β, whose slip angle then ran away. The Gauss-Markov tilt lowers both, but
  cannot stop a runaway driven through the product k_β α2 by a wrong soil model (the oracle's
  k_s on the curved law).

Speed: these functions are the code the filter runs. ``@njit(cache=True)`` compiles this same
text with numba (the compiled machine code is cached in ``__pycache__``, so only the first run
on a machine pays the compile); ``NUMBA_DISABLE_JIT=1`` runs it as the plain Python it reads as.
Those the filter calls at every prediction have an ``_into`` twin that writes into an array the
caller owns (the filter's workspace); the allocating function calls it, so each model is
written once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from slipenv.contracts import angles, wrap_angle
from slipenv.contracts.compiled_cache import refresh_stale_cache

refresh_stale_cache(__file__, angles.__file__)  # the models call the compiled wrap_angle

G_MPS2 = 9.80665  # standard gravity [m/s²]; Eq. 14 accelerations are in units of g
# [rad] the field's slope prior, the stationary std of pitch and roll (about 2.9°: a field a
# farm vehicle works is within a few degrees of level; the filter's prior at reset,
# LindgrenNoise.sigma0_tilt_rad, is the same belief)
TILT_SIGMA_RAD = 0.05

IX, IY, ITH, IV, IOM, IVD, IOMD, IA1, IA2 = range(9)
IRL, IRR, IKL, IKR = 9, 10, 11, 12
IBL, IBR = 13, 14
N_BASE = 9  # the paper's state, Eq. 12
N_SLIP = 13  # plus R_w and k_s per wheel, §4
N_OKELLO = 15  # plus Okello's inverse shape 1/B per wheel (Eq. 18-20)
STATE_NAMES = ("x", "y", "theta", "v", "omega", "v_dot", "omega_dot", "alpha1", "alpha2",
               "R_wl", "R_wr", "k_sl", "k_sr", "b_l", "b_r")
LATERAL_NAME = "k_beta"


@njit(cache=True)
def lateral_index(n: int) -> int:
    """Index of the lateral slip gain k_β in a state of length n, or -1 when it has none."""
    if n == N_BASE + 1 or n == N_SLIP + 1 or n == N_OKELLO + 1:
        return n - 1
    return -1


@njit(cache=True)
def soil_size(n: int) -> int:
    """Length of the state without its lateral slip gain: N_BASE, N_SLIP or N_OKELLO."""
    return n - 1 if lateral_index(n) >= 0 else n


def state_names(n: int) -> tuple[str, ...]:
    """Names of the entries of a state of length n (one of 9, 10, 13, 14, 15, 16)."""
    base = soil_size(n)
    if base not in (N_BASE, N_SLIP, N_OKELLO):
        raise ValueError(f"no Lindgren state layout has {n} entries")
    return STATE_NAMES[:base] + ((LATERAL_NAME,) if base != n else ())


# the contracts' angle wrap to (-π, π], compiled for the filter's compiled code
wrap = njit(cache=True)(wrap_angle)


@dataclass(frozen=True)
class OracleSoil:
    """The true soil parameters, for the oracle filter that knows them (the limit to compare to).

    Attributes
    ----------
    wheel_radius_m : tuple[float, float]
        True effective rolling radius (left, right) [m] (Lindgren: 0.283, 0.287 on soil).
    k_s : tuple[float, float]
        True torque/slip gradient (left, right) in the torque sensor's unit (Eq. 24).
    """

    wheel_radius_m: tuple[float, float]
    k_s: tuple[float, float]

    def __post_init__(self) -> None:
        for name in ("wheel_radius_m", "k_s"):
            value = tuple(float(v) for v in getattr(self, name))
            if len(value) != 2 or not all(math.isfinite(v) and v > 0.0 for v in value):
                raise ValueError(f"OracleSoil.{name} must be two finite values > 0, got {value!r}")
            object.__setattr__(self, name, value)

    def as_array(self) -> np.ndarray:
        """``[R_wl, R_wr, k_sl, k_sr]``, the form the compiled observation models take."""
        return np.array([*self.wheel_radius_m, *self.k_s])


# ---------------------------------------------------------------------------------------------
# Process model (Eq. 13) and process noise
# ---------------------------------------------------------------------------------------------
@njit(cache=True)
def lateral_accel_g(v: float, omega: float, alpha2: float) -> float:
    """Lateral specific force ``a_y = v Ω / g - α2`` [g] (Lindgren Eq. 14, second row)."""
    return v * omega / G_MPS2 - alpha2


@njit(cache=True)
def tilt_decay(tau: float, tilt_psd: float) -> float:
    """Factor ``φ = exp(-τ q / (2 σ²))`` by which pitch and roll revert to level over τ.

    The first-order Gauss-Markov process with stationary variance σ² = :data:`TILT_SIGMA_RAD` ²
    whose short-time spectral density is q = ``tilt_psd``: over τ ≪ 2σ²/q it is the random walk
    of density q, over longer times it stays within σ. Its discrete noise is σ² (1 - φ²)
    (:func:`process_Q`; the first-order Gauss-Markov process of Brown and Hwang, Introduction
    to Random Signals and Applied Kalman Filtering, ch. 2). With
    q = 1e-4 rad²/s and σ = 0.05 rad the correlation time 2σ²/q is 50 s (25 m at 0.5 m/s).
    """
    return math.exp(-0.5 * tau * tilt_psd / (TILT_SIGMA_RAD * TILT_SIGMA_RAD))


@njit(cache=True)
def process_fx(x: np.ndarray, tau: float, tilt_psd: float) -> np.ndarray:
    """Predict the state τ seconds ahead (Lindgren Eq. 13, second-order integration).

    With a lateral slip gain k_β (the last entry of a 10, 14 or 16-state ``x``) the velocity
    leans off the heading by β, ``tan β = k_β a_y`` (:func:`lateral_accel_g`): the position
    moves by ``τ v̄ (cos θm - tan β sin θm, sin θm + tan β cos θm)``, v being the forward
    (body x) speed the odometers see. β is evaluated at the interval's mean speed and yaw rate.

    Parameters
    ----------
    x : np.ndarray, shape (n,), n = 9, 13 or 15, plus one with a lateral slip gain
        State at the start of the interval (layout in the module docstring).
    tau : float
        Prediction interval [s].
    tilt_psd : float
        Pitch and roll spectral density [rad²/s]: sets how fast they revert to level
        (:func:`tilt_decay`).

    Returns
    -------
    np.ndarray, shape (n,)
        State at the end of the interval. θ is not wrapped (the filter wraps it), so the
        function stays smooth for finite differences. R_w, k_s, 1/B and k_β are constant.
    """
    xp = np.empty(x.shape[0])
    process_fx_into(x, tau, tilt_psd, xp)
    return xp


@njit(cache=True)
def process_fx_into(x: np.ndarray, tau: float, tilt_psd: float, xp: np.ndarray) -> None:
    """:func:`process_fx` written into ``xp`` (n,), another array than ``x`` (the filter's
    workspace, as :func:`process_F_into`)."""
    for i in range(x.shape[0]):
        xp[i] = x[i]
    v_bar = x[IV] + 0.5 * tau * x[IVD]  # mean speed over the interval [m/s]
    om_bar = x[IOM] + 0.5 * tau * x[IOMD]  # mean yaw rate [rad/s]
    dth = tau * om_bar  # heading change [rad]
    th_mid = x[ITH] + 0.5 * dth
    c, s = math.cos(th_mid), math.sin(th_mid)
    il = lateral_index(x.shape[0])
    if il >= 0:
        tb = x[il] * lateral_accel_g(v_bar, om_bar, x[IA2])  # tan β
        xp[IX] = x[IX] + tau * v_bar * (c - tb * s)
        xp[IY] = x[IY] + tau * v_bar * (s + tb * c)
    else:
        xp[IX] = x[IX] + tau * v_bar * c
        xp[IY] = x[IY] + tau * v_bar * s
    xp[ITH] = x[ITH] + dth
    xp[IV] = x[IV] + tau * x[IVD]
    xp[IOM] = x[IOM] + tau * x[IOMD]
    # a ground tilt seen from a yawing body: (α1, α2) turn through the heading change, and
    # revert towards level as the vehicle moves over the field
    phi = tilt_decay(tau, tilt_psd)
    cd, sd = phi * math.cos(dth), phi * math.sin(dth)
    xp[IA1] = cd * x[IA1] - sd * x[IA2]
    xp[IA2] = sd * x[IA1] + cd * x[IA2]


@njit(cache=True)
def process_F(x: np.ndarray, tau: float, tilt_psd: float) -> np.ndarray:
    """Jacobian ``F = ∂f/∂x`` of :func:`process_fx` (Lindgren Eq. 7), shape (n, n)."""
    F = np.empty((x.shape[0], x.shape[0]))
    process_F_into(x, tau, F, tilt_psd)
    return F


@njit(cache=True)
def process_F_into(x: np.ndarray, tau: float, F: np.ndarray, tilt_psd: float) -> None:
    """:func:`process_F` written into ``F`` (n, n), for the filter's per-frame workspace: the
    filter predicts a few times per frame, where allocating costs as much as the arithmetic."""
    n = x.shape[0]
    for i in range(n):
        for j in range(n):
            F[i, j] = 0.0
        F[i, i] = 1.0
    v_bar = x[IV] + 0.5 * tau * x[IVD]
    om_bar = x[IOM] + 0.5 * tau * x[IOMD]
    dth = tau * om_bar
    th_mid = x[ITH] + 0.5 * dth
    c, s = math.cos(th_mid), math.sin(th_mid)
    il = lateral_index(n)
    p = tau * v_bar
    # x' = x + τ v̄ (cos θm - t sin θm), y' = y + τ v̄ (sin θm + t cos θm), t = tan β,
    # v̄ = v + τ v̇/2, Ω̄ = Ω + τ Ω̇/2, θm = θ + τ Ω̄/2
    if il >= 0:
        a_y = lateral_accel_g(v_bar, om_bar, x[IA2])
        tb = x[il] * a_y
        ux, uy = c - tb * s, s + tb * c  # direction of travel (unnormalised)
        dux, duy = -s - tb * c, c - tb * s  # its derivative with respect to θm
        # derivatives of t with respect to v̄, Ω̄, α2 and k_β
        t_v, t_om, t_a2, t_k = x[il] * om_bar / G_MPS2, x[il] * v_bar / G_MPS2, -x[il], a_y
        F[IX, il] = -p * s * t_k
        F[IY, il] = p * c * t_k
        F[IX, IA2] = -p * s * t_a2
        F[IY, IA2] = p * c * t_a2
    else:
        ux, uy, dux, duy = c, s, -s, c
        t_v = t_om = 0.0
    # ∂/∂v̄ and ∂/∂Ω̄ of the position, then through v̄(v, v̇) and Ω̄(Ω, Ω̇)
    dxv = tau * ux - p * s * t_v
    dyv = tau * uy + p * c * t_v
    dxo = p * dux * 0.5 * tau - p * s * t_om
    dyo = p * duy * 0.5 * tau + p * c * t_om
    F[IX, ITH] = p * dux
    F[IY, ITH] = p * duy
    F[IX, IV] = dxv
    F[IY, IV] = dyv
    F[IX, IVD] = 0.5 * tau * dxv
    F[IY, IVD] = 0.5 * tau * dyv
    F[IX, IOM] = dxo
    F[IY, IOM] = dyo
    F[IX, IOMD] = 0.5 * tau * dxo
    F[IY, IOMD] = 0.5 * tau * dyo
    F[ITH, IOM] = tau
    F[ITH, IOMD] = 0.5 * tau * tau
    F[IV, IVD] = tau
    F[IOM, IOMD] = tau
    phi = tilt_decay(tau, tilt_psd)
    cd, sd = phi * math.cos(dth), phi * math.sin(dth)
    F[IA1, IA1] = cd
    F[IA1, IA2] = -sd
    F[IA2, IA1] = sd
    F[IA2, IA2] = cd
    da1 = -sd * x[IA1] - cd * x[IA2]  # ∂α1'/∂(Δθ)
    da2 = cd * x[IA1] - sd * x[IA2]  # ∂α2'/∂(Δθ)
    F[IA1, IOM] = tau * da1
    F[IA1, IOMD] = 0.5 * tau * tau * da1
    F[IA2, IOM] = tau * da2
    F[IA2, IOMD] = 0.5 * tau * tau * da2


@njit(cache=True)
def jerk_block(tau: float, psd: float) -> np.ndarray:
    """Discretised continuous white-jerk noise for a (position, rate, acceleration) chain.

    Equals ``filterpy.common.Q_continuous_white_noise(3, tau, psd)`` (tested).

    Parameters
    ----------
    tau : float
        Interval [s].
    psd : float
        Jerk power spectral density [unit²/s⁵].

    Returns
    -------
    np.ndarray, shape (3, 3)
    """
    q00, q01, q02, q11, q12, q22 = jerk_entries(tau, psd)
    q = np.empty((3, 3))
    q[0, 0], q[0, 1], q[0, 2] = q00, q01, q02
    q[1, 0], q[1, 1], q[1, 2] = q01, q11, q12
    q[2, 0], q[2, 1], q[2, 2] = q02, q12, q22
    return q


@njit(cache=True)
def jerk_entries(tau: float, psd: float) -> tuple[float, float, float, float, float, float]:
    """The upper triangle of :func:`jerk_block`, ``(q00, q01, q02, q11, q12, q22)``: the form
    :func:`process_Q_into` takes it in, without an array to allocate at every prediction."""
    t2 = tau * tau
    t3 = t2 * tau
    return (psd * t3 * t2 / 20.0, psd * t2 * t2 / 8.0, psd * t3 / 6.0, psd * t3 / 3.0,
            psd * t2 / 2.0, psd * tau)


@njit(cache=True)
def process_Q(
    x: np.ndarray,
    tau: float,
    jerk_psd_v: float,
    jerk_psd_omega: float,
    tilt_psd: float,
    radius_var_per_m: float = 0.0,
    k_s_rel_var_per_m: float = 0.0,
    b_var_per_m: float = 0.0,
    k_beta_var_per_m: float = 0.0,
) -> np.ndarray:
    """Process noise covariance ``Q`` over τ (Lindgren Eq. 7 and the end of §4).

    White jerk drives the (along-track distance, v, v̇) and (θ, Ω, Ω̇) chains; the distance
    noise is laid along the mean heading in (x, y). Pitch and roll are Gauss-Markov processes
    with stationary variance σ² (:func:`tilt_decay`): σ² (1 - φ²) each. For the
    slip models the variances of R_w and k_s (and Okello's 1/B, and k_β) grow in proportion to
    the distance travelled in the interval, ``d = |v + τ v̇/2| τ`` (Lindgren §4: "increasing
    their corresponding variances ... in proportion to the distance travelled"); k_s's growth
    is relative to its current estimate so that it does not depend on the torque sensor's
    scale.

    Parameters
    ----------
    x : np.ndarray, shape (n,)
        State at the start of the interval.
    tau : float
        Interval [s].
    jerk_psd_v : float
        Forward jerk spectral density [m²/s⁵].
    jerk_psd_omega : float
        Yaw jerk spectral density [rad²/s⁵].
    tilt_psd : float
        Pitch and roll spectral density [rad²/s] (short-time random walk, :func:`tilt_decay`).
    radius_var_per_m : float
        Growth of each R_w variance per metre travelled [m²/m].
    k_s_rel_var_per_m : float
        Growth of each k_s variance per metre travelled, relative to k_s² [1/m].
    b_var_per_m : float
        Growth of each inverse Okello shape (1/B) variance per metre travelled [1/m]
        (15-state model).
    k_beta_var_per_m : float
        Growth of the lateral slip gain's variance per metre travelled [rad²/(g² m)] (states
        with a lateral slip gain).

    Returns
    -------
    np.ndarray, shape (n, n)
    """
    Q = np.empty((x.shape[0], x.shape[0]))
    process_Q_into(x, tau, jerk_psd_v, jerk_psd_omega, tilt_psd, radius_var_per_m,
                   k_s_rel_var_per_m, b_var_per_m, k_beta_var_per_m, Q)
    return Q


@njit(cache=True)
def process_Q_into(
    x: np.ndarray,
    tau: float,
    jerk_psd_v: float,
    jerk_psd_omega: float,
    tilt_psd: float,
    radius_var_per_m: float,
    k_s_rel_var_per_m: float,
    b_var_per_m: float,
    k_beta_var_per_m: float,
    Q: np.ndarray,
) -> None:
    """:func:`process_Q` written into ``Q`` (n, n) (the filter's workspace, as
    :func:`process_F_into`)."""
    n = x.shape[0]
    for i in range(n):
        for j in range(n):
            Q[i, j] = 0.0
    v_bar = x[IV] + 0.5 * tau * x[IVD]
    th_mid = x[ITH] + 0.5 * tau * (x[IOM] + 0.5 * tau * x[IOMD])
    u = (math.cos(th_mid), math.sin(th_mid))
    w00, w01, w02, w11, w12, w22 = jerk_entries(tau, jerk_psd_omega)
    # the (θ, Ω, Ω̇) chain
    Q[ITH, ITH], Q[ITH, IOM], Q[ITH, IOMD] = w00, w01, w02
    Q[IOM, ITH], Q[IOM, IOM], Q[IOM, IOMD] = w01, w11, w12
    Q[IOMD, ITH], Q[IOMD, IOM], Q[IOMD, IOMD] = w02, w12, w22
    # the along-track chain (s, v, v̇), with the distance s laid along u in (x, y)
    v00, v01, v02, v11, v12, v22 = jerk_entries(tau, jerk_psd_v)
    Q[IV, IV], Q[IV, IVD], Q[IVD, IV], Q[IVD, IVD] = v11, v12, v12, v22
    for i in range(2):
        for j in range(2):
            Q[i, j] = v00 * u[i] * u[j]
        Q[i, IV] = Q[IV, i] = v01 * u[i]
        Q[i, IVD] = Q[IVD, i] = v02 * u[i]
    # σ² (1 - φ²), without the cancellation of 1 - φ² at short τ
    sig2 = TILT_SIGMA_RAD * TILT_SIGMA_RAD
    Q[IA1, IA1] = Q[IA2, IA2] = -sig2 * math.expm1(-tau * tilt_psd / sig2)
    d = abs(v_bar) * tau
    base = soil_size(n)
    if base >= N_SLIP:
        Q[IRL, IRL] = Q[IRR, IRR] = radius_var_per_m * d
        Q[IKL, IKL] = k_s_rel_var_per_m * d * x[IKL] ** 2
        Q[IKR, IKR] = k_s_rel_var_per_m * d * x[IKR] ** 2
    if base == N_OKELLO:
        Q[IBL, IBL] = Q[IBR, IBR] = b_var_per_m * d
    if base != n:
        Q[n - 1, n - 1] = k_beta_var_per_m * d
