"""Turn a body twist (forward speed, yaw rate) into drive-channel commands.

Differential / skid-steer: ω_{l,r} = (v ∓ Ω W/2) / R (Lindgren Eq. 15-16 inverted, Yamauchi
Eq. 1-3 with zero slip). 4WS rover: each wheel points along its own contact velocity
(v - Ω y_i, Ω x_i) — kinematic double-Ackermann steering (Reina §2, bicycle model generalised).
The nominal radius is used: the commands are what the operator's controller would send.
"""

from __future__ import annotations

import math

from slipenv.vehicles.spec import VehicleSpec


def twist_to_commands(
    spec: VehicleSpec, v_mps: float, omega_rad_s: float
) -> tuple[list[float], list[float]]:
    """Channel wheel speeds [rad/s] and per-wheel steering angles [rad] for a body twist.

    Speeds are scaled down together (keeping the turn radius) when one would exceed
    ``spec.max_wheel_speed_rad_s``.
    """
    r = spec.wheel_radius_nominal_m
    steer = [0.0] * len(spec.wheels)
    if spec.kind == "rover4ws":
        speeds = []
        angles = {}
        for channel, (x, y) in zip(spec.channels, spec.channel_xy_m(), strict=True):
            vx, vy = v_mps - omega_rad_s * y, omega_rad_s * x
            delta = math.atan2(vy, vx) if (vx or vy) else 0.0
            speed = math.hypot(vx, vy) / r
            if delta > math.pi / 2:
                delta, speed = delta - math.pi, -speed
            elif delta < -math.pi / 2:
                delta, speed = delta + math.pi, -speed
            speeds.append(speed)
            angles[channel] = delta
        steer = [angles.get(w.channel, 0.0) if w.steered and w.channel is not None else 0.0
                 for w in spec.wheels]
    else:
        half = spec.track_width_m / 2
        left, right = (v_mps - omega_rad_s * half) / r, (v_mps + omega_rad_s * half) / r
        lefts = spec.left_channels  # a computed property: once, not once per channel
        speeds = [left if i in lefts else right for i in range(len(spec.channels))]
    peak = max(abs(s) for s in speeds)
    if peak > spec.max_wheel_speed_rad_s:
        scale = spec.max_wheel_speed_rad_s / peak
        speeds = [s * scale for s in speeds]
    return speeds, steer
