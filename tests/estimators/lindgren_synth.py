"""Synthetic sensor frames generated with the Lindgren EKF's own models.

The truth follows the process model of :mod:`slipenv.estimators.lindgren.models` (Eq. 13,
second-order form), driven either by white jerk with exactly the filter's ``Q`` (for consistency
checks: a filter fed this data should pass its χ² tests) or by a speed and yaw-rate reference
such as Lindgren's straight lines with alternating 180° turns. Sensors are the filter's observation
models plus white Gaussian noise of the filter's variances: accelerometers and gyro (Eq. 14),
inclinometer, odometer counts by the slip-aware Eq. 37 with the true R_w and k_s in the state
(Eq. 15 when the torque is zero; Okello's curve when the state carries its 1/B; the lateral
slip of the process model when it carries k_β), and bearings from a :class:`BeaconScanner`. No
PyBullet: this tests the estimator against its own assumptions; the PyBullet environments test
it against physics. It lives with the tests because it drives the sensor class
(:class:`slipenv.sensors.beacons.BeaconScanner`), which the estimators may not import.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from slipenv.contracts import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren import models as lm
from slipenv.estimators.lindgren import observations as lo
from slipenv.estimators.lindgren.params import LindgrenNoise
from slipenv.sensors.beacons import BeaconScanner


@dataclass(frozen=True)
class SynthRun:
    """A synthetic run.

    Attributes
    ----------
    t_s : np.ndarray, shape (K + 1,)
        Frame times [s].
    truth : np.ndarray, shape (K + 1, n)
        True state at each frame, n = 13, 14, 15 or 16 (layout of
        :mod:`slipenv.estimators.lindgren.models`; θ unwrapped).
    frames : list[SensorFrame]
        K + 1 frames; ``frames[0]`` is for ``reset``.
    """

    t_s: np.ndarray
    truth: np.ndarray
    frames: list[SensorFrame]


def truth0() -> np.ndarray:
    """The 13-state truth the synthetic runs start from: the farm vehicle's soil radii
    (0.283 / 0.287 m) and a stiffer soil than the filter's prior."""
    x0 = np.zeros(lm.N_SLIP)
    x0[[lm.IX, lm.IY]] = (-8.0, -4.0)
    x0[lm.IRL:lm.IRR + 1] = (0.283, 0.287)
    x0[lm.IKL:] = (2500.0, 2200.0)
    return x0


def torque(t: float, x: np.ndarray) -> np.ndarray:
    """Varying drive torque, more on the outer wheel in turns [N m]."""
    base = 150.0 + 100.0 * math.sin(2.0 * math.pi * t / 7.0)
    return np.array([base - 300.0 * x[lm.IOM], base + 300.0 * x[lm.IOM]])


def straight_and_turn(
    speed_mps: float = 1.0, radius_m: float = 4.0, straight_s: float = 8.0
) -> Callable[[float], tuple[float, float]]:
    """Reference (v, Ω) for straights joined by alternating left and right 180° turns.

    Lindgren §5's second path. Returns a function of time [s] giving the reference speed
    [m/s] and yaw rate [rad/s].
    """
    turn_s = math.pi * radius_m / speed_mps
    period = straight_s + turn_s

    def reference(t_s: float) -> tuple[float, float]:
        k, phase = divmod(t_s, period)
        if phase < straight_s:
            return speed_mps, 0.0
        return speed_mps, (1.0 if int(k) % 2 == 0 else -1.0) * speed_mps / radius_m

    return reference


def _sample(rng: np.random.Generator, cov: np.ndarray) -> np.ndarray:
    """One N(0, cov) draw for a possibly singular covariance."""
    w, V = np.linalg.eigh(cov)
    return V @ (np.sqrt(np.clip(w, 0.0, None)) * rng.standard_normal(len(w)))


def simulate(
    geometry: OdometryGeometry,
    x0: np.ndarray,
    n_steps: int,
    dt_s: float,
    rng: np.random.Generator,
    noise: LindgrenNoise | None = None,
    reference: Callable[[float], tuple[float, float]] | None = None,
    response_time_s: float = 0.5,
    torque: Callable[[float, np.ndarray], np.ndarray] | None = None,
    scanner: BeaconScanner | None = None,
    process_noise: bool = True,
    soil_drift: bool = False,
) -> SynthRun:
    """Simulate the filter's model and its sensors.

    Parameters
    ----------
    geometry : OdometryGeometry
        Track width, encoder resolution and wheel grouping (one wheel per side is enough).
    x0 : np.ndarray, shape (13,), (15,) or one more with k_β
        Initial true state including the true R_w, k_s, and Okello's 1/B and the lateral slip
        gain k_β when it has them (held constant).
    n_steps : int
        Number of frames after the first.
    dt_s : float
        Frame interval [s].
    rng : np.random.Generator
        Source of all randomness.
    noise : LindgrenNoise, optional
        Process and measurement noise (the filter's defaults when None).
    reference : callable t -> (v_ref, Ω_ref), optional
        If given, v̇ and Ω̇ are set each step to close the gap to the reference with time
        constant ``response_time_s`` [s]; process noise still acts on top when enabled.
    response_time_s : float
        See ``reference``.
    torque : callable (t, x) -> (T_left, T_right), optional
        Measured wheel torque (zero when None, which makes Eq. 37 into Eq. 15).
    scanner : BeaconScanner, optional
        Bearing sensor; no bearings when None.
    process_noise : bool
        Add white jerk and tilt noise with the filter's ``Q``.
    soil_drift : bool
        Let R_w and k_s (1/B, k_β) random-walk with distance as the filter's ``Q`` assumes
        (Lindgren §4); otherwise they stay at their ``x0`` values.

    Returns
    -------
    SynthRun
    """
    p = LindgrenNoise() if noise is None else noise
    g = geometry
    n_wheels = max(g.left + g.right) + 1
    torque_fn = torque if torque is not None else (lambda t, x: np.zeros(2))
    x = np.array(x0, dtype=float)
    if lm.soil_size(len(x)) not in (lm.N_SLIP, lm.N_OKELLO):
        raise ValueError(f"x0 must be a slip-model state (13 or 15 entries, plus k_β), got "
                         f"{x.shape}")
    sd = {"odo": math.sqrt(p.odometer_var_rad2) * g.counts_per_rad,
          "ax": math.sqrt(p.acc_x_var_g2) * lm.G_MPS2, "ay": math.sqrt(p.acc_y_var_g2) * lm.G_MPS2,
          "gyro": math.sqrt(p.gyro_var_rad2ps2), "tilt": math.sqrt(p.tilt_var_rad2)}
    if scanner is not None:
        scanner.reset(0.0, x[lm.IX], x[lm.IY], x[lm.ITH])

    def per_wheel(side_values: np.ndarray) -> np.ndarray:
        out = np.zeros(n_wheels)
        out[list(g.left)], out[list(g.right)] = side_values[0], side_values[1]
        return out

    def frame(t: float, x: np.ndarray, counts: np.ndarray, T: np.ndarray,
              bearings: tuple[np.ndarray, np.ndarray]) -> SensorFrame:
        acc = lm.G_MPS2 * lo.ins_hx(x)[:2]
        return SensorFrame(
            t_s=t, enc_counts=per_wheel(counts), wheel_torque_nm=per_wheel(T),
            gyro_z_rad_s=float(x[lm.IOM] + sd["gyro"] * rng.standard_normal()),
            acc_x_mps2=float(acc[0] + sd["ax"] * rng.standard_normal()),
            acc_y_mps2=float(acc[1] + sd["ay"] * rng.standard_normal()),
            pitch_rad=float(-x[lm.IA1] + sd["tilt"] * rng.standard_normal()),
            roll_rad=float(-x[lm.IA2] + sd["tilt"] * rng.standard_normal()),
            beacon_bearings_rad=bearings[0], beacon_times_s=bearings[1])

    counts = np.zeros(2)
    T = np.asarray(torque_fn(0.0, x), dtype=float)
    empty = (np.zeros(0), np.zeros(0))
    truth, frames = [x.copy()], [frame(0.0, x, counts, T, empty)]
    for k in range(1, n_steps + 1):
        t = k * dt_s
        if reference is not None:
            v_ref, om_ref = reference(t - dt_s)
            x[lm.IVD] = (v_ref - x[lm.IV]) / response_time_s
            x[lm.IOMD] = (om_ref - x[lm.IOM]) / response_time_s
        xs = x if soil_drift else x[:lm.N_BASE]
        Q = lm.process_Q(xs, dt_s, p.jerk_psd_v, p.jerk_psd_omega, p.tilt_psd,
                         p.radius_var_per_m, p.k_s_rel_var_per_m, p.inv_shape_var_per_m,
                         p.lateral_slip_var_per_m)
        x = lm.process_fx(x, dt_s, p.tilt_psd)
        if process_noise:
            x[:len(xs)] += _sample(rng, Q)
        T_new = np.asarray(torque_fn(t, x), dtype=float)
        dc = lo.odo_slip_hx(x, dt_s, 0.5 * (T + T_new), g.track_width_m, g.counts_per_rad,
                             lo.NO_SOIL)
        counts = counts + dc + sd["odo"] * rng.standard_normal(2)
        T = T_new
        bearings = empty if scanner is None else scanner.scan(
            t, x[lm.IX], x[lm.IY], x[lm.ITH], rng)
        truth.append(x.copy())
        frames.append(frame(t, x, counts, T, bearings))
    return SynthRun(np.arange(n_steps + 1) * dt_s, np.array(truth), frames)
