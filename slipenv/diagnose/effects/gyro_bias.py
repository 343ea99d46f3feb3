"""``gyro_bias``: a constant offset in the yaw-rate sensor.

Gyro channel: the heading integrated from the gyro alone, minus the bias, against the
ground-truth heading. Simulation: ``SensorNoise.gyro_bias_rad_s``. Hidden in the tests (both
kinds): an offset of 0.005-0.03 rad/s either way, taken one to one by the sensor model.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np

from slipenv.diagnose.effects.base import (
    Bound,
    DrawContext,
    Effect,
    Hidden,
    Hiding,
    Scalar,
    Term,
    finite,
)
from slipenv.diagnose.effects.world import WorldEdit
from slipenv.diagnose.segments import Segments
from slipenv.sensors.noise import SensorNoise


@dataclass(frozen=True)
class GyroBias(Term):
    """Yaw-rate sensor offset b [rad/s] (measured = true + b)."""

    bias_rad_s: float

    def __post_init__(self) -> None:
        finite(self)

    def gyro_rate(self, seg: Segments, rate: np.ndarray) -> np.ndarray:
        return rate - self.bias_rad_s


def applicable(seg: Segments) -> str | None:
    return None if seg.gyro is not None else "no gyro_z column"


def bounds(seg: Segments) -> dict[str, Bound]:
    return {"bias_rad_s": Bound(0.0, -1.0, 1.0, 0.01)}


def apply(edit: WorldEdit, p: GyroBias) -> None:
    noise = edit.config.sensor_noise
    assert isinstance(noise, SensorNoise)  # SlipEnvConfig keeps a spec, whatever it was given
    edit.replace["sensor_noise"] = dataclasses.replace(noise, gyro_bias_rad_s=p.bias_rad_s)


def draw(rng: np.random.Generator, ctx: DrawContext) -> Hidden:
    return Hidden(GyroBias(float(rng.uniform(0.005, 0.03) * rng.choice([-1.0, 1.0]))))


EFFECT = Effect(
    name="gyro_bias",
    meaning="constant offset in the yaw-rate sensor",
    params=GyroBias, bounds=bounds, apply=apply, rank=8, applicable=applicable,
    channel="gyro", contract=(Scalar("bias_rad_s", "gyro_bias_rad_s"),),
    hiding=Hiding(("diff_drive", "skid_steer", "rover4ws"), draw, columns=frozenset({"imu"}),
                  exact=True),
)
