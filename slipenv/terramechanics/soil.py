"""Soil parameter sets: a validated frozen dataclass and the plain tuple the force laws take.

`Soil` is the user-facing record (SI units, one documented field per parameter, validated on
construction). `SoilParams` is its numeric image: a NamedTuple whose fields are floats for one
soil, or numpy arrays of shape (n_wheels,) when a soil map gives every wheel its own soil. Every
force law in this package takes a `SoilParams`; none takes a `Soil`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

__all__ = ["Soil", "SoilParams", "PARAM_FIELDS"]


class SoilParams(NamedTuple):
    """Numeric soil parameters, floats or arrays of shape (n,); fields as in `Soil`.

    `deformable` is 1.0 (deformable) or 0.0 (rigid) so that soil maps can blend it. Treat the
    tuple, and any arrays in it, as immutable: the simulation binds force kernels to it.
    """

    cohesion_pa: float | np.ndarray
    friction_angle_rad: float | np.ndarray
    shear_modulus_m: float | np.ndarray
    k_c: float | np.ndarray
    k_phi: float | np.ndarray
    n_exp: float | np.ndarray
    mu: float | np.ndarray
    c_x_n: float | np.ndarray
    c_y_n: float | np.ndarray
    a_x: float | np.ndarray
    a_y: float | np.ndarray
    reference_load_n: float | np.ndarray
    rolling_radius_scale: float | np.ndarray
    deformable: float | np.ndarray


PARAM_FIELDS: tuple[str, ...] = SoilParams._fields
"""Names of the numeric soil fields, in `SoilParams` order."""

# Fields that must be strictly positive (they divide something); all others must be >= 0.
_POSITIVE = frozenset({"shear_modulus_m", "n_exp", "mu", "reference_load_n",
                       "rolling_radius_scale"})
# Strict upper bounds: tan(phi) must be finite; Bekker's rigid-wheel sinkage has (3 - n).
_UPPER = {"friction_angle_rad": math.pi / 2.0, "n_exp": 3.0}


@dataclass(frozen=True)
class Soil:
    """One soil (or rigid surface), in SI units, with the source of every field.

    Raises
    ------
    ValueError
        On construction, naming the field and value, when a number is NaN, infinite, negative,
        zero where it divides (K, n, mu, reference load, radius scale), or beyond its bound
        (friction angle >= 90 deg, n >= 3), or when k_c = k_phi = 0.
    """

    name: str
    """Preset key, e.g. ``"lunar_simulant"``."""
    cohesion_pa: float
    """Cohesion c [Pa] of the Mohr-Coulomb strength q_max = c + sigma tan(phi) (Lindgren Eq. 3;
    Reina Table 2)."""
    friction_angle_rad: float
    """Internal friction angle phi [rad] (Lindgren Eq. 3; Reina Table 2)."""
    shear_modulus_m: float
    """Janosi-Hanamoto shear deformation modulus K [m] (Lindgren Eq. 2)."""
    k_c: float
    """Bekker cohesive modulus k_c [N/m^(n+1)] of p = (k_c/b + k_phi) z^n (Bekker's
    pressure-sinkage law; Wong, Theory of Ground Vehicles, Ch. 2)."""
    k_phi: float
    """Bekker frictional modulus k_phi [N/m^(n+2)] (same law)."""
    n_exp: float
    """Bekker sinkage exponent n [-], 0 < n < 3 (same law)."""
    mu: float
    """Maximum soil adhesion coefficient mu [-] of Reina's model (Reina Eq. 5-6, Table 3)."""
    c_x_n: float
    """Longitudinal slip stiffness C_x [N] (Reina Eq. 5, Table 3), fitted at `reference_load_n`."""
    c_y_n: float
    """Lateral slip stiffness C_y [N] (Reina Eq. 6, Table 3), fitted at `reference_load_n`."""
    a_x: float
    """High-slip slope A_x [-] of the longitudinal curve (Reina Eq. 5, Table 3)."""
    a_y: float
    """High-slip slope A_y [-] of the lateral curve (Reina Eq. 6, Table 3)."""
    reference_load_n: float
    """Wheel load W_ref [N] at which C_x and C_y were fitted (Reina Sec. 3.2: 6.6 kg)."""
    rolling_radius_scale: float
    """Effective rolling radius / nominal radius on this surface [-]; 1.0 on concrete. Lindgren
    Sec. 3.2: 0.283 m and 0.287 m on soil against 0.275 m on concrete."""
    deformable: bool
    """True when the surface sinks under load (Bekker compaction applies)."""
    _params: SoilParams = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name:
            raise ValueError(f"Soil field name={self.name!r} must be a non-empty string")
        if not isinstance(self.deformable, bool):
            raise ValueError(f"Soil field deformable={self.deformable!r} must be a bool")
        for key in PARAM_FIELDS[:-1]:
            _check_field(key, getattr(self, key))
        if self.k_c == 0.0 and self.k_phi == 0.0:
            raise ValueError(f"Soil {self.name!r}: fields k_c=0.0 and k_phi=0.0; at least one "
                             "must be > 0 (use a large k_phi for rigid ground)")
        values = [float(getattr(self, key)) for key in PARAM_FIELDS[:-1]]
        object.__setattr__(self, "_params", SoilParams._make([*values, float(self.deformable)]))

    def params(self) -> SoilParams:
        """The numeric fields as a `SoilParams` of floats (built once, cached)."""
        return self._params


def _check_field(key: str, value: object) -> None:
    """Raise ValueError naming `key` and `value` unless `value` is admissible for `key`."""
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise ValueError(f"Soil field {key}={value!r} must be a real number")
    number = float(value)
    if not math.isfinite(number):
        raise ValueError(f"Soil field {key}={value!r} must be finite")
    if number < 0.0:
        raise ValueError(f"Soil field {key}={value!r} must be >= 0")
    if key in _POSITIVE and number == 0.0:
        raise ValueError(f"Soil field {key}={value!r} must be > 0")
    if key in _UPPER and number >= _UPPER[key]:
        raise ValueError(f"Soil field {key}={value!r} must be < {_UPPER[key]:.6g}")
