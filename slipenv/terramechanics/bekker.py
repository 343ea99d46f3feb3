"""Bekker sinkage and compaction resistance of rigid wheels and tracks.

Bekker's pressure-sinkage law p = (k_c/b + k_phi) z^n gives, for a rigid wheel of diameter D and
width b carrying W, the sinkage

    z = (3 W / ((3 - n)(k_c + b k_phi) sqrt(D)))^(2/(2n+1)),

for a track of contact length L, z = (W/(b L (k_c/b + k_phi)))^(1/n), and in both cases the work
of pressing a rut of depth z per unit distance travelled, the compaction resistance

    R_c = b (k_c/b + k_phi) z^(n+1)/(n+1)

(standard Bekker theory; Wong, Theory of Ground Vehicles, Ch. 2 and 5). Both are power laws in
the load, R_c = gamma W^e, which is how the force models evaluate them per physics substep.
On non-deformable ground there is no rut and R_c = 0. All functions broadcast, except the
float ones the simulation calls per wheel (`wheel_sinkage_float_m`, `rut_following_compaction_n`,
`rut_load_ratio`), whose one implementation is C (``_laws.h``, which the substep loop runs).
`pressure_sinkage_m` and `compaction_resistance_n` take floats or numpy arrays as they are,
without conversions: the track model (`track`) evaluates them on its cells every substep.

Multi-pass (`rut_following_compaction_n`). Soil unloaded and reloaded follows a steep, nearly
elastic line up to the maximum pressure it has already carried, and the virgin
pressure-sinkage curve only beyond it (Wong, Theory of Ground Vehicles, 4th ed., §2.4,
repetitive loading; Wong, Terramechanics and Off-Road Vehicle Engineering, 2nd ed., Ch. 2).
A wheel running in the rut of a leading wheel therefore does the compaction work only below
that rut: R_c = b k_eq (z_f^{n+1} - z_rut^{n+1})/(n+1), zero when it sinks no deeper. This
neglects the (small) reloading work and the extra sinkage slip adds on later passes, which
Holm measured on repeated tyre passes (Holm, J. Terramechanics 6(3), 1969): it is an upper
bound on the multi-pass reduction, and therefore opt-in. A follower of another geometry (a
castor behind a driven wheel) meets its own compaction at the leader's rut depth; as both
are power laws with the same exponent, that is its own law at an equivalent load
(`rut_load_ratio`).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

import slipenv.terramechanics._laws as _laws
from slipenv.terramechanics.vectorize import array_law

__all__ = [
    "slip_sinkage_factor",
    "wheel_sinkage_m",
    "pressure_sinkage_m",
    "track_sinkage_m",
    "compaction_resistance_n",
    "wheel_compaction_law",
    "track_compaction_law",
    "rut_following_compaction_n",
    "rut_load_ratio",
]


def slip_sinkage_factor(slip: float) -> float:
    """Lyasko's slip-sinkage factor z/z0 = (1 + i)/(1 - 0.5 i), slip i clipped to [0, 1]
    (Lyasko, "Slip sinkage effect in soil-vehicle mechanics", J. Terramech. 47 (2010) 21-31):
    a wheel slipping at i sinks to f z0, z0 its static sinkage; 1 at i = 0, 4 at i = 1.
    The C law ``laws_slip_sinkage_factor`` (``_laws.h``), which the simulation runs when a
    force model's ``slip_sinkage`` is on (`models.slip_sinkage_resistance`).
    """
    return _laws.slip_sinkage_factor(slip)


def wheel_sinkage_float_m(load_n: float, width_m: float, diameter_m: float, k_c: float,
                          k_phi: float, n_exp: float) -> float:
    """Static sinkage z [m] of one rigid wheel (Bekker; Wong Ch. 5), in floats.

    z = (3 W/((3 - n)(k_c + b k_phi) sqrt(D)))^(2/(2n+1)), negative loads counting as 0
    (arguments as in `wheel_sinkage_m`, which is this function on arrays). The simulator and the
    rear camera evaluate it per wheel at every control step.
    """
    return _laws.wheel_sinkage_m(load_n, width_m, diameter_m, k_c, k_phi, n_exp)


wheel_sinkage_m = array_law(wheel_sinkage_float_m, name="wheel_sinkage_m", doc="""\
Static sinkage z [m] of a rigid wheel (Bekker; Wong Ch. 5), on broadcast arrays.

`wheel_sinkage_float_m` element by element: z = (3 W/((3 - n)(k_c + b k_phi) sqrt(D)))^(2/(2n+1)).

Parameters
----------
load_n : array_like
    Wheel load W [N]; negative loads count as 0.
width_m, diameter_m : array_like
    Wheel width b and diameter D [m].
k_c, k_phi, n_exp : array_like
    Bekker moduli k_c [N/m^(n+1)], k_phi [N/m^(n+2)] and exponent n (0 < n < 3).
""")


def pressure_sinkage_m(pressure_pa: float | np.ndarray, width_m: float | np.ndarray,
                       k_c: float | np.ndarray, k_phi: float | np.ndarray,
                       n_exp: float | np.ndarray) -> float | np.ndarray:
    """Sinkage z = (p/(k_c/b + k_phi))^(1/n) [m] under a uniform pressure p on a contact of
    width b: Bekker's pressure-sinkage law p = (k_c/b + k_phi) z^n solved for z (Wong Ch. 2).

    Negative pressures count as 0. Floats or numpy arrays (broadcast), without conversions:
    the track model calls it on its cells at every physics substep, where each conversion
    costs more than the arithmetic.

    Parameters
    ----------
    pressure_pa : float or ndarray
        Pressure p [Pa].
    width_m : float or ndarray
        Width b [m] of the track (k_c is per unit width).
    k_c, k_phi, n_exp : float or ndarray
        Bekker moduli and exponent (n > 0).
    """
    return (np.maximum(pressure_pa, 0.0) * (1.0 / (k_c / width_m + k_phi))) ** (1.0 / n_exp)


def track_sinkage_m(load_n: ArrayLike, width_m: ArrayLike, length_m: ArrayLike,
                    k_c: ArrayLike, k_phi: ArrayLike, n_exp: ArrayLike) -> np.ndarray:
    """Sinkage z [m] of a track (or track segment) under uniform pressure W/(b L) (Bekker).

    `pressure_sinkage_m` at p = W/(b L), on any array_like.

    Parameters
    ----------
    load_n : array_like
        Load W [N] carried by the contact length L; negative loads count as 0.
    width_m, length_m : array_like
        Track width b and contact length L [m].
    k_c, k_phi, n_exp : array_like
        Bekker moduli and exponent (n > 0).
    """
    width = np.asarray(width_m, dtype=float)
    pressure = np.asarray(load_n, dtype=float) / (width * np.asarray(length_m))
    return np.asarray(pressure_sinkage_m(pressure, width, np.asarray(k_c), np.asarray(k_phi),
                                         np.asarray(n_exp, dtype=float)))


def compaction_resistance_n(sinkage_m: float | np.ndarray, width_m: float | np.ndarray,
                            k_c: float | np.ndarray, k_phi: float | np.ndarray,
                            n_exp: float | np.ndarray) -> float | np.ndarray:
    """Compaction resistance R_c = b (k_c/b + k_phi) z^(n+1)/(n+1) [N] (Bekker; Wong Ch. 2, 5):
    the work of pressing a rut of depth z, b int_0^z p dz, per unit distance travelled.

    Negative sinkage counts as 0. Floats or numpy arrays (broadcast), without conversions, as
    `pressure_sinkage_m` (the track model evaluates it every substep).

    Parameters
    ----------
    sinkage_m : float or ndarray
        Rut depth z [m].
    width_m : float or ndarray
        Width b [m] of the wheel or track.
    k_c, k_phi, n_exp : float or ndarray
        Bekker moduli and exponent.
    """
    return ((k_c + width_m * k_phi) / (n_exp + 1.0)) * np.maximum(sinkage_m, 0.0) ** (n_exp + 1.0)


def wheel_compaction_law(width_m: float, diameter_m: float, k_c: ArrayLike, k_phi: ArrayLike,
                         n_exp: ArrayLike,
                         deformable: ArrayLike = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(gamma, e) with R_c = gamma W^e for a rigid wheel: the two formulas above combined.

    e = (2n+2)/(2n+1); gamma is multiplied by `deformable` (1.0 soft, 0.0 rigid ground, or a
    blend from a soil map) so that R_c = 0 on non-deformable ground.
    """
    n = np.asarray(n_exp, dtype=float)
    k_eq_b = np.asarray(k_c) + width_m * np.asarray(k_phi)
    alpha = 3.0 / ((3.0 - n) * k_eq_b * np.sqrt(diameter_m))
    exponent = (2.0 * n + 2.0) / (2.0 * n + 1.0)
    gamma = np.asarray(deformable) * k_eq_b / (n + 1.0) * alpha ** exponent
    return gamma, exponent


def track_compaction_law(width_m: float, length_m: float, k_c: ArrayLike, k_phi: ArrayLike,
                         n_exp: ArrayLike,
                         deformable: ArrayLike = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """(gamma, e) with R_c = gamma W^e for a track carrying W over length L; e = (n+1)/n."""
    n = np.asarray(n_exp, dtype=float)
    k_eq_b = np.asarray(k_c) + width_m * np.asarray(k_phi)
    exponent = (n + 1.0) / n
    gamma = np.asarray(deformable) * k_eq_b / (n + 1.0) * (1.0 / (length_m * k_eq_b)) ** exponent
    return gamma, exponent


def rut_following_compaction_n(compaction_n: float, rut_compaction_n: float) -> float:
    """Compaction resistance [N] of a wheel in the rut of a leading wheel (module docstring).

    With the follower's geometry for both, R_c(z) = b k_eq z^{n+1}/(n+1) is monotone in the
    sinkage, so the work below the rut is R_c(z_f) - R_c(z_rut): the follower's own compaction
    minus that of the rut's depth, floored at 0 (a lighter follower sinks no deeper).

    Parameters
    ----------
    compaction_n : float
        R_c of the follower on virgin soil [N] (its load, its geometry).
    rut_compaction_n : float
        R_c at the rut's depth, i.e. of the same geometry under the leader's load [N].
    """
    return _laws.rut_following_compaction_n(compaction_n, rut_compaction_n)


def rut_load_ratio(width_m: float, diameter_m: float, leader_width_m: float,
                   leader_diameter_m: float, k_c: float, k_phi: float) -> float:
    """Load ratio q such that a follower's compaction at the depth of a leader's rut is its
    own wheel law at the load q W_leader (plain floats).

    The leader (b_L, D_L) carrying W_L sinks to z_L = (alpha_L W_L)^(2/(2n+1)), alpha =
    3/((3 - n) k_eq sqrt(D)), k_eq = k_c + b k_phi (`wheel_sinkage_m`); the follower's
    compaction at that depth, b_f k_eq,f z_L^(n+1)/(n+1) (`compaction_resistance_n`), equals its
    wheel law gamma_f W^e (`wheel_compaction_law`, e = (2n+2)/(2n+1)) at W = (alpha_L/alpha_f)
    W_L, so q = alpha_L/alpha_f = k_eq,f sqrt(D_f)/(k_eq,L sqrt(D_L)), independent of n. Exactly
    1.0 for the same geometry.
    """
    return _laws.rut_load_ratio(width_m, diameter_m, leader_width_m, leader_diameter_m,
                                k_c, k_phi)
