"""The sensor frame: everything the vehicle's sensors report at one control step.

This is the contract between the simulation (or a measured log) and the estimators: the
estimators in ``estimators/`` consume ``SensorFrame`` objects and never see PyBullet or ground
truth. Units are SI; frames follow ROS REP 103 (body x forward, y left, z up).
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields
from typing import ClassVar

import numpy as np


@dataclass(frozen=True, eq=False)
class SensorFrame:
    """One time-stamped set of sensor readings.

    Attributes
    ----------
    t_s : float
        Time stamp [s].
    enc_counts : np.ndarray, shape (n_wheels,), int64
        Cumulative encoder counts per wheel (or per track sprocket), left side first, in the
        order of the vehicle's ``wheel_names``.
    wheel_torque_nm : np.ndarray, shape (n_wheels,)
        Measured drive torque per wheel [N m], > 0 drives the vehicle forward. NaN if the
        vehicle carries no torque sensor.
    gyro_z_rad_s : float
        Yaw rate about body z [rad/s], counter-clockwise positive.
    acc_x_mps2, acc_y_mps2 : float
        Body-frame specific force (what an accelerometer reads, gravity included) [m/s^2].
    roll_rad, pitch_rad : float
        Inclinometer attitude [rad]; roll > 0 lifts the left side, pitch > 0 lowers the nose.
    heading_rad : float
        Compass heading, counter-clockwise from world x [rad].
    beacon_bearings_rad : np.ndarray, shape (k,)
        Unidentified bearings to beacons measured since the last frame, relative to the body
        x axis [rad] (Lindgren Eq. 17). Empty when no scan arrived.
    beacon_times_s : np.ndarray, shape (k,)
        Time stamp of each bearing [s].
    steer_rad : np.ndarray, shape (n_wheels,)
        Measured steering angle per wheel [rad] (zeros on vehicles without steering).
    """

    t_s: float
    enc_counts: np.ndarray
    wheel_torque_nm: np.ndarray
    gyro_z_rad_s: float = float("nan")
    acc_x_mps2: float = float("nan")
    acc_y_mps2: float = float("nan")
    roll_rad: float = float("nan")
    pitch_rad: float = float("nan")
    heading_rad: float = float("nan")
    beacon_bearings_rad: np.ndarray = field(default_factory=lambda: np.zeros(0))
    beacon_times_s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    steer_rad: np.ndarray = field(default_factory=lambda: np.zeros(0))

    def __eq__(self, other: object) -> bool:
        """Field-wise equality (arrays compared element-wise, NaN equal to NaN)."""
        if not isinstance(other, SensorFrame):
            return NotImplemented
        return all(
            np.array_equal(np.asarray(getattr(self, f.name)), np.asarray(getattr(other, f.name)),
                           equal_nan=True)
            for f in fields(self)
        )

    # Mutable arrays inside: not hashable. Defining __eq__ already sets __hash__ to None at run
    # time; the annotation tells type checkers (typeshed spells unhashable types this way).
    __hash__: ClassVar[None]  # type: ignore[assignment]
