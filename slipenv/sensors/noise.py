"""Sensor noise levels (DESIGN §4, Lindgren §2.2 and §4) as one frozen dataclass."""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

# Largest value of each field that still describes a working sensor (beyond it the reading
# is noise, not a measurement): 1 g^2 accelerometer variance, 1 (rad/s)^2 gyro variance and
# 1 rad/s bias, 100 % torque noise, a 100x torque scale, pi rad angle noise.
MAX_NOISE = {
    "counts_per_rad": 1e7, "acc_x_var_g2": 1.0, "acc_y_var_g2": 1.0, "gyro_var_rad2_s2": 1.0,
    "gyro_bias_rad_s": 1.0, "torque_rel_std": 1.0, "torque_scale": 100.0,
    "incl_std_rad": math.pi, "compass_std_rad": math.pi,
}


@dataclass(frozen=True)
class SensorNoise:
    """Noise of every onboard sensor; zero everywhere gives perfect sensors.

    Attributes
    ----------
    counts_per_rad : float | None
        Encoder resolution [counts/rad]; ``None`` takes the vehicle's (Lindgren: 285).
    acc_x_var_g2, acc_y_var_g2 : float
        Accelerometer variances [g^2] (Lindgren Eq. 14: 4.5e-4 forward, 3.0e-4 lateral).
    gyro_var_rad2_s2 : float
        Yaw gyro variance [(rad/s)^2] (Lindgren: 6.5e-5).
    gyro_bias_rad_s : float
        Constant yaw-gyro offset [rad/s] (a log-format effect, 0 by default).
    torque_rel_std : float
        Relative standard deviation of the wheel torque sensors (assumed 5 %).
    torque_scale : float
        Uncalibrated torque sensor scale (Lindgren: the scale need not be known).
    incl_std_rad : float
        Inclinometer noise standard deviation [rad] (assumed 0.5°).
    compass_std_rad : float
        Compass noise standard deviation [rad] (assumed 2°).

    Notes
    -----
    Every field is a finite number >= 0 (the gyro bias may be negative) and at most
    :data:`MAX_NOISE` in magnitude; anything else is a ``ValueError`` naming the field.
    """

    counts_per_rad: float | None = None
    acc_x_var_g2: float = 4.5e-4
    acc_y_var_g2: float = 3.0e-4
    gyro_var_rad2_s2: float = 6.5e-5
    gyro_bias_rad_s: float = 0.0
    torque_rel_std: float = 0.05
    torque_scale: float = 1.0
    incl_std_rad: float = math.radians(0.5)
    compass_std_rad: float = math.radians(2.0)

    def __post_init__(self) -> None:
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None and f.name == "counts_per_rad":
                continue
            if (not isinstance(value, (int, float)) or isinstance(value, bool)
                    or not math.isfinite(value)):
                raise ValueError(f"SensorNoise.{f.name} must be a finite number, got {value!r}")
            if f.name != "gyro_bias_rad_s" and value < 0:
                raise ValueError(f"SensorNoise.{f.name} must be >= 0, got {value!r}")
            if abs(value) > MAX_NOISE[f.name]:
                raise ValueError(f"SensorNoise.{f.name} must be <= {MAX_NOISE[f.name]:g} in "
                                 f"magnitude (a working sensor), got {value!r}")
        if self.counts_per_rad is not None and self.counts_per_rad <= 0:
            raise ValueError(f"SensorNoise.counts_per_rad must be > 0, got {self.counts_per_rad}")

    @classmethod
    def perfect(cls) -> SensorNoise:
        """Noise-free sensors (encoders still quantise)."""
        return cls(acc_x_var_g2=0.0, acc_y_var_g2=0.0, gyro_var_rad2_s2=0.0, torque_rel_std=0.0,
                   incl_std_rad=0.0, compass_std_rad=0.0)
