"""The onboard sensors: each a small class with ``measure(truth, rng) -> reading``.

Every random draw comes from the ``np.random.Generator`` passed in (the env's, seeded by
``reset(seed)``). Readings follow the log-format conventions (REP 103, SI units).
"""

from __future__ import annotations

import math

import numpy as np

from slipenv.contracts.angles import wrap_angle
from slipenv.contracts.constants import G_MPS2
from slipenv.contracts.frame import SensorFrame
from slipenv.sensors.noise import SensorNoise
from slipenv.sim.simulator import VehicleTruth


class WheelEncoders:
    """Incremental encoders on each drive channel: cumulative integer counts.

    Quantisation is the encoder's only error (Lindgren §2.4: 285 counts/rad).
    """

    def __init__(self, counts_per_rad: float) -> None:
        self.counts_per_rad = counts_per_rad

    def measure(self, truth: VehicleTruth, rng: np.random.Generator) -> np.ndarray:
        return np.floor(truth.channel_angle_rad * self.counts_per_rad).astype(np.int64)


class TorqueSensors:
    """Wheel torque per channel with relative noise and an uncalibrated scale."""

    def __init__(self, rel_std: float, scale: float) -> None:
        self.rel_std, self.scale = rel_std, scale

    def measure(self, truth: VehicleTruth, rng: np.random.Generator) -> np.ndarray:
        return self.from_normals(truth, rng.standard_normal(truth.channel_torque_nm.shape))

    def from_normals(self, truth: VehicleTruth, e: np.ndarray) -> np.ndarray:
        """The reading given one standard normal draw per channel, ``e``."""
        tq = truth.channel_torque_nm
        noise = e * self.rel_std * (np.abs(tq) + 1e-3)
        return self.scale * (tq + noise)


class Imu:
    """Forward/lateral accelerometers (specific force, m/s²) and yaw gyro (rad/s).

    The gyro integrates: it reads the rotation about body z over the sample interval divided
    by the interval (``VehicleTruth.mean_yaw_rate_rad_s``), as a MEMS gyro does behind its
    decimation filter, so the readings times their intervals sum to the body's turn however
    its rate varies between samples. ``sampling="instant"`` reads the rate at the sample
    instant instead (a gyro sampled without an anti-alias filter).
    """

    SAMPLINGS = ("mean", "instant")

    def __init__(self, noise: SensorNoise, sampling: str = "mean") -> None:
        if sampling not in self.SAMPLINGS:
            raise ValueError(f"gyro sampling {sampling!r} is not one of {self.SAMPLINGS}")
        self.std_ax = math.sqrt(noise.acc_x_var_g2) * G_MPS2
        self.std_ay = math.sqrt(noise.acc_y_var_g2) * G_MPS2
        self.std_g = math.sqrt(noise.gyro_var_rad2_s2)
        self.bias = noise.gyro_bias_rad_s
        self.sampling = sampling

    def measure(self, truth: VehicleTruth, rng: np.random.Generator) -> tuple[float, float, float]:
        return self.from_normals(truth, rng.standard_normal(3))

    def from_normals(self, truth: VehicleTruth, e: np.ndarray) -> tuple[float, float, float]:
        """The reading given three standard normal draws ``e`` (x, y, gyro)."""
        ax, ay, _ = truth.specific_force_body_mps2
        rate = truth.mean_yaw_rate_rad_s if self.sampling == "mean" else truth.yaw_rate_rad_s
        return (
            ax + self.std_ax * e[0],
            ay + self.std_ay * e[1],
            rate + self.bias + self.std_g * e[2],
        )


class Inclinometer:
    """Roll and pitch [rad] with white noise."""

    def __init__(self, std_rad: float) -> None:
        self.std = std_rad

    def measure(self, truth: VehicleTruth, rng: np.random.Generator) -> tuple[float, float]:
        return self.from_normals(truth, rng.standard_normal(2))

    def from_normals(self, truth: VehicleTruth, e: np.ndarray) -> tuple[float, float]:
        """The reading given two standard normal draws ``e`` (roll, pitch)."""
        return truth.roll_rad + self.std * e[0], truth.pitch_rad + self.std * e[1]


class Compass:
    """Heading counter-clockwise from world x [rad], wrapped to [-π, π)."""

    def __init__(self, std_rad: float) -> None:
        self.std = std_rad

    def measure(self, truth: VehicleTruth, rng: np.random.Generator) -> float:
        return self.from_normal(truth, rng.standard_normal())

    def from_normal(self, truth: VehicleTruth, e: float) -> float:
        """The reading given one standard normal draw ``e``."""
        return wrap_angle(truth.yaw_rad + self.std * e)


class SensorSuite:
    """All onboard sensors of a vehicle, producing one :class:`SensorFrame` per step.

    Parameters
    ----------
    counts_per_rad : float
        Encoder resolution [counts/rad].
    noise : SensorNoise
        Noise levels.
    beacons : object | None
        Optional exteroceptive scanner with ``scan(t_s, x_m, y_m, yaw_rad, rng) -> (bearings,
        times)`` (``slipenv.sensors.beacons.BeaconScanner``).
    gyro_sampling : str
        ``"mean"`` (the rate-integrating gyro, default) or ``"instant"`` (:class:`Imu`).
    """

    def __init__(self, counts_per_rad: float, noise: SensorNoise, beacons=None,
                 gyro_sampling: str = "mean") -> None:
        self.encoders = WheelEncoders(noise.counts_per_rad or counts_per_rad)
        self.torque = TorqueSensors(noise.torque_rel_std, noise.torque_scale)
        self.imu = Imu(noise, gyro_sampling)
        self.inclinometer = Inclinometer(noise.incl_std_rad)
        self.compass = Compass(noise.compass_std_rad)
        self.beacons = beacons

    def reset(self) -> None:
        """Start a new episode (the beacon scanner starts sweeping at the next frame)."""
        if self.beacons is not None:
            self.beacons.reset()

    def measure(self, truth: VehicleTruth, rng: np.random.Generator) -> SensorFrame:
        """Read every sensor once (in a fixed order, so the random stream is reproducible)."""
        enc = self.encoders.measure(truth, rng)
        # The torque, IMU, inclinometer and compass noise in one draw: the generator gives
        # the same numbers in the same order as one draw per sensor (torque, 3, 2, 1).
        n = truth.channel_torque_nm.shape[0]
        e = rng.standard_normal(n + 6)
        torque = self.torque.from_normals(truth, e[:n])
        ax, ay, gz = self.imu.from_normals(truth, e[n:n + 3])
        roll, pitch = self.inclinometer.from_normals(truth, e[n + 3:n + 5])
        heading = self.compass.from_normal(truth, float(e[n + 5]))
        bearings, times = np.zeros(0), np.zeros(0)
        if self.beacons is not None:
            x, y, _ = truth.position_m
            bearings, times = self.beacons.scan(truth.t_s, x, y, truth.yaw_rad, rng)
        return SensorFrame(
            t_s=truth.t_s, enc_counts=enc, wheel_torque_nm=torque, gyro_z_rad_s=gz,
            acc_x_mps2=ax, acc_y_mps2=ay, roll_rad=roll, pitch_rad=pitch, heading_rad=heading,
            beacon_bearings_rad=bearings, beacon_times_s=times,
        )
