"""Parameters of the Lindgren EKF: the four schemes of Lindgren §5, a fifth with Okello's curve
in place of the linear torque/slip law, and the noise set."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from enum import IntEnum

from .models import TILT_SIGMA_RAD


class Scheme(IntEnum):
    """The four EKF schemes of Lindgren §5, and scheme 5 (beyond the paper): scheme 4 with
    Okello's curve (Eq. 18-20) per wheel in place of its linear limit, Eq. 24."""

    LASER_INERTIAL = 1  # laser scanner and inertial sensors: the reference ("ground truth")
    ODOMETRY_ONLY = 2  # odometers only, no slip model
    ALL_NO_SLIP = 3  # all sensors, odometry by Eq. 15
    ALL_SLIP = 4  # all sensors, odometry by the slip-aware Eq. 37
    ALL_SLIP_OKELLO = 5  # all sensors, Eq. 37 with Okello's curve (k_s and 1/B per wheel)


def parse_scheme(scheme: int | str | Scheme) -> Scheme:
    """Scheme from its number (1-5) or name ("laser_inertial", ..., "all_slip_okello")."""
    if isinstance(scheme, str) and not scheme.isdigit():
        try:
            return Scheme[scheme.strip().upper()]
        except KeyError:
            names = ", ".join(s.name.lower() for s in Scheme)
            raise ValueError(f"unknown scheme {scheme!r}; use 1-5 or one of {names}") from None
    try:
        return Scheme(int(scheme))
    except ValueError:
        raise ValueError(f"unknown scheme {scheme!r}; use 1-5") from None


@dataclass(frozen=True)
class LindgrenNoise:
    """Noise, prior and gating parameters of :class:`LindgrenEKF`.

    Measurement variances are the paper's (Lindgren §2.4) unless marked assumed; process
    noise and priors are chosen here (the paper gives none).

    Attributes
    ----------
    odometer_var_rad2 : float
        Odometer variance per wheel and interval [rad²] (3.1e-6 ≈ (half a count)² at
        285 counts/rad); the filter uses ``odometer_var_rad2 · counts_per_rad²`` [counts²].
    acc_x_var_g2, acc_y_var_g2 : float
        Forward and lateral accelerometer variances [g²] (4.5e-4, 3.0e-4).
    gyro_var_rad2ps2 : float
        Yaw gyro variance [(rad/s)²] (6.5e-5).
    bearing_var_rad2 : float
        Beacon bearing variance [rad²] (1e-4).
    tilt_var_rad2 : float
        Inclinometer pitch and roll variance [rad²] (assumed: 3e-5, about 0.3°).
    jerk_psd_v : float
        Forward jerk spectral density driving v̇ [m²/s⁵] (chosen: 0.5, i.e. v̇ may change by
        about 0.7 m/s² in one second, a gentle field vehicle with speed changes).
    jerk_psd_omega : float
        Yaw jerk spectral density driving Ω̇ [rad²/s⁵] (chosen: 0.5, enough to follow the step
        in Ω at the start of a 4 m arc, about 0.25 rad/s, within a second).
    tilt_psd : float
        Pitch and roll spectral density [rad²/s] (chosen: 1e-4, 0.01 rad/√s of terrain
        change): their short-time random walk; over longer times they stay within the field's
        slope prior, reverting to level with correlation time 2σ²/q = 50 s
        (:func:`.models.tilt_decay`, σ = :data:`.models.TILT_SIGMA_RAD`).
    radius_var_per_m : float
        Growth of R_w variance per metre travelled [m²/m] (chosen: 1e-6, 1 mm/√m).
    k_s_rel_var_per_m : float
        Growth of k_s variance per metre, relative to k_s² [1/m] (chosen: 1e-4, 1 %/√m).
    bearing_gate_prob : float
        χ²(1) probability of the bearing validation gate (0.999: gate at NIS 10.8). 1 disables
        the gate: nearest-innovation association alone, as in the paper (Lindgren §2.4). The
        gate (not in the paper) guards against clutter, but a filter whose odometry is trusted
        beyond its accuracy (scheme 3 on soil) then rejects the bearings that would correct it.
    max_slip : float
        Odometry updates with |T / k_s| above this are skipped (Eq. 24 is a small-slip model).
    sigma0_xy_m, sigma0_yaw_rad : float
        Prior standard deviation of the reset pose [m], [rad].
    sigma0_v_mps, sigma0_omega_rps : float
        Prior std of speed and yaw rate at reset (both start at 0) [m/s], [rad/s].
    sigma0_vdot_mps2, sigma0_omegadot_rps2 : float
        Prior std of the accelerations (start at 0) [m/s²], [rad/s²].
    sigma0_tilt_rad : float
        Prior std of pitch and roll when the frame has no inclinometer reading [rad] (the
        field's slope prior, :data:`.models.TILT_SIGMA_RAD`, which the filter's tilt process
        keeps as its stationary std).
    radius_rel_sigma0 : float
        Prior std of R_w relative to the nominal radius (5 %: 0.275 m ± 14 mm covers
        Lindgren's 0.283/0.287 m on soil).
    k_s0 : float
        Prior k_s, in the torque sensor's unit (2000 for N m: a wheel carrying about 3 kN on
        soil with T_max ≈ 500 N m and Okello's B ≈ 0.12, k_s = T_max / (2B), Eq. 24).
    k_s_rel_sigma0 : float
        Prior std of k_s relative to ``k_s0``.
    inv_shape0 : float
        Scheme 5: prior of the state b = 1/B, the inverse of Okello's shape B [-]; 0 (default)
        starts from the linear law, the curve's limit b → 0, and lets the data bend it. The
        filter keeps b >= 0 (Okello's curve saturates; :func:`.kernel.constrain_shape`).
    inv_shape_sigma0 : float
        Scheme 5: prior std of b [-] (8: B = 0.12, the value behind ``k_s0``, is 1σ away).
    inv_shape_var_per_m : float
        Scheme 5: growth of the variance of b per metre travelled [1/m] (chosen: 0.01,
        0.1/√m, about 1 %/√m of the prior).
    lateral_slip_sigma0 : float
        Prior std of the lateral slip gain k_β [rad/g] (``tan β = k_β a_y``, see
        :mod:`.models`), whose prior mean is 0. 0 (default): the filter has no lateral slip
        state, the paper's model (a gain known to be zero needs no state). Lindgren's vehicle
        simulated on field loam crabs with k_β ≈ 2.5 rad/g (β ≈ 0.9° at 0.0064 g on the 4 m
        circles); 3 covers it.
    lateral_slip_var_per_m : float
        Growth of k_β's variance per metre travelled [rad²/g²/m] (chosen: 1e-3, 0.03 rad/g
        per √m).
    """

    odometer_var_rad2: float = 3.1e-6
    acc_x_var_g2: float = 4.5e-4
    acc_y_var_g2: float = 3.0e-4
    gyro_var_rad2ps2: float = 6.5e-5
    bearing_var_rad2: float = 1e-4
    tilt_var_rad2: float = 3.0e-5
    jerk_psd_v: float = 0.5
    jerk_psd_omega: float = 0.5
    tilt_psd: float = 1e-4
    radius_var_per_m: float = 1e-6
    k_s_rel_var_per_m: float = 1e-4
    bearing_gate_prob: float = 0.999
    max_slip: float = 0.5
    sigma0_xy_m: float = 0.05
    sigma0_yaw_rad: float = 0.02
    sigma0_v_mps: float = 0.1
    sigma0_omega_rps: float = 0.05
    sigma0_vdot_mps2: float = 0.2
    sigma0_omegadot_rps2: float = 0.2
    sigma0_tilt_rad: float = TILT_SIGMA_RAD
    radius_rel_sigma0: float = 0.05
    k_s0: float = 2000.0
    k_s_rel_sigma0: float = 0.5
    inv_shape0: float = 0.0
    inv_shape_sigma0: float = 8.0
    inv_shape_var_per_m: float = 1e-2
    lateral_slip_sigma0: float = 0.0
    lateral_slip_var_per_m: float = 1e-3

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if f.name in ("lateral_slip_sigma0", "inv_shape0"):
                if not (math.isfinite(value) and value >= 0.0):
                    raise ValueError(f"LindgrenNoise.{f.name} must be finite and >= 0, got "
                                     f"{value!r}")
            elif not (math.isfinite(value) and value > 0.0):
                raise ValueError(f"LindgrenNoise.{f.name} must be finite and > 0, got {value!r}")
        if self.max_slip >= 1.0:
            raise ValueError("LindgrenNoise.max_slip must be < 1")
        if self.bearing_gate_prob > 1.0:
            raise ValueError("LindgrenNoise.bearing_gate_prob must be <= 1 (1: no gate)")
