"""Physically plausible ranges of every slipenv-log/1 quantity (``log-format.md``).

A value outside its range is not a measurement of a ground vehicle but a corrupted cell, a unit
mistake or an overflow: ``read_log`` rejects it naming file, row and column (or key), before a
diagnosis turns it into ``inf``. The ranges are deliberately wide (a toy rover to a mining
truck, seconds to decades of time stamps) so that no real log trips them.

==========================  =========================  ==========================================
quantity                    allowed                    why
==========================  =========================  ==========================================
``t``                       |t| <= 1e10 s              Unix time until the year 2286
``enc_<wheel>``             |counts| <= 2**53          float64 holds integers exactly up to 2**53
``cmd_<wheel>``             |v| <= 1000 rad/s          ~10 000 rpm: faster than any wheel motor
``torque_<wheel>``          |T| <= 1e6 N m             above a 400 t haul truck's wheel motor
``steer_<wheel>``           |δ| <= π rad               a steering angle is an angle
``gyro_z``                  |ω| <= 100 rad/s           MEMS gyros saturate near 35 rad/s
``acc_x``, ``acc_y``        |a| <= 1000 m/s²           100 g: beyond any accelerometer's range
``roll``                    |φ| <= π rad               Z-Y-X Euler angle
``pitch``                   |θ| <= π/2 rad             Z-Y-X Euler angle
``heading``, ``gt_yaw``     |ψ| <= 1e4 rad             may be unwrapped (1600 turns)
``gt_x``, ``gt_y``          |p| <= 2e7 m               half the Earth's circumference (UTM fits)
``vehicle.wheel_radius_m``  (0, 2] m                   the largest tyres (``VehicleSpec`` too)
``vehicle.track_width_m``   (0, 10] m                  a mining truck's ~8 m (``VehicleSpec``)
``vehicle.wheelbase_m``     (0, 20] m                  as ``VehicleSpec``
``vehicle.counts_per_rad``  (0, 1e7]
``vehicle.mass_kg``         (0, 1e5] kg                100 t, as ``VehicleSpec``
``terrain.slope_deg``       [0, 60] deg                nothing drives up a steeper plane
``terrain.slope_downhill``  [-360, 360] deg
``_azimuth_deg``
==========================  =========================  ==========================================

Rates between consecutive samples (a single corrupted cell inside the ranges above still
shows as a jump no vehicle makes):

==========================  =========================  ==========================================
rate                        allowed                    why
==========================  =========================  ==========================================
``enc_<wheel>`` / Δt         <= 1000 rad/s             as ``cmd_<wheel>`` (counts / counts_per_rad)
``gt_x``, ``gt_y`` / Δt      <= 1000 m/s               three times the speed of sound
==========================  =========================  ==========================================

Other (extra) columns are only required to be finite.
"""

from __future__ import annotations

import math

import numpy as np

# (column prefix or name, largest magnitude, unit) -- a prefix ends with "_".
SIGNAL_BOUNDS: tuple[tuple[str, float, str], ...] = (
    ("t", 1e10, "s"),
    ("enc_", float(2**53), "counts"),
    ("cmd_", 1000.0, "rad/s"),
    ("torque_", 1e6, "N m"),
    ("steer_", math.pi, "rad"),
    ("gyro_z", 100.0, "rad/s"),
    ("acc_x", 1000.0, "m/s^2"),
    ("acc_y", 1000.0, "m/s^2"),
    ("roll", math.pi, "rad"),
    ("pitch", math.pi / 2, "rad"),
    ("heading", 1e4, "rad"),
    ("gt_yaw", 1e4, "rad"),
    ("gt_x", 2e7, "m"),
    ("gt_y", 2e7, "m"),
)

# meta.json: key path -> (low, high, low inclusive); high is inclusive.
META_BOUNDS: dict[tuple[str, str], tuple[float, float, bool]] = {
    ("vehicle", "wheel_radius_m"): (0.0, 2.0, False),
    ("vehicle", "track_width_m"): (0.0, 10.0, False),
    ("vehicle", "wheelbase_m"): (0.0, 20.0, False),
    ("vehicle", "counts_per_rad"): (0.0, 1e7, False),
    ("vehicle", "mass_kg"): (0.0, 1e5, False),
    ("terrain", "slope_deg"): (0.0, 60.0, True),
    ("terrain", "slope_downhill_azimuth_deg"): (-360.0, 360.0, True),
}


# (column prefix or name, largest rate magnitude, unit); rates between consecutive measured
# samples, encoders converted to wheel angle with ``vehicle.counts_per_rad``.
RATE_BOUNDS: tuple[tuple[str, float, str], ...] = (
    ("enc_", 1000.0, "rad/s"),
    ("gt_x", 1000.0, "m/s"),
    ("gt_y", 1000.0, "m/s"),
)


def rate_bound(column: str, wheels: list[str]) -> tuple[float, str] | None:
    """(largest rate magnitude, unit) of a column whose jumps are bounded, else None."""
    for name, limit, unit in RATE_BOUNDS:
        if name.endswith("_") and column.startswith(name) and column[len(name):] in wheels:
            return limit, unit
        if column == name:
            return limit, unit
    return None


def first_rate_out_of_bounds(t: np.ndarray, values: np.ndarray, limit: float,
                             scale: float = 1.0) -> int | None:
    """Index of the first sample whose change from the previous measured (finite) sample,
    divided by ``scale`` and by the time between them, exceeds ``limit`` (None: none does).

    ``t`` must be strictly increasing; NaN values are skipped (not measured).
    """
    ok = np.flatnonzero(np.isfinite(values) & np.isfinite(t))
    if ok.size < 2:
        return None
    dt = np.diff(t[ok])
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        rate = np.abs(np.diff(values[ok])) / scale / dt
    bad = np.flatnonzero(rate > limit)
    return int(ok[bad[0] + 1]) if bad.size else None


def signal_bound(column: str, wheels: list[str]) -> tuple[float, str] | None:
    """(largest magnitude, unit) of a contract column, or None for an extra column."""
    for name, limit, unit in SIGNAL_BOUNDS:
        if name.endswith("_") and column.startswith(name) and column[len(name):] in wheels:
            return limit, unit
        if column == name:
            return limit, unit
    return None


def first_out_of_bounds(values: np.ndarray, limit: float) -> int | None:
    """Index of the first finite value with magnitude above ``limit`` (NaN = not measured)."""
    with np.errstate(invalid="ignore"):
        bad = np.flatnonzero(np.abs(values) > limit)
    return int(bad[0]) if bad.size else None


def meta_value_ok(keys: tuple[str, str], value: float) -> bool:
    """Whether a finite meta number lies in its plausible range (True for unbounded keys)."""
    if keys not in META_BOUNDS:
        return True
    low, high, low_inclusive = META_BOUNDS[keys]
    above_low = value >= low if low_inclusive else value > low
    return above_low and value <= high


def meta_range_text(keys: tuple[str, str]) -> str:
    low, high, low_inclusive = META_BOUNDS[keys]
    return f"{'[' if low_inclusive else '('}{low:g}, {high:g}]"
