"""Janosi-Hanamoto shear, the Mohr-Coulomb limit, and the Okello thrust-slip curve.

A contact patch of length L, width b (area A = bL) carrying load W on soil (c, phi, K): the soil
under the patch at distance x behind its front edge has been sheared by j = s x (slip s), so its
shear stress is q(x) = (c + p tan phi)(1 - e^{-sx/K}) (Lindgren Eq. 2-3, uniform pressure
p = W/A). Integrating q over the patch gives the thrust

    F(s) = (A c + W tan phi) [1 - (K/(sL)) (1 - e^{-sL/K})],

which is Okello's curve C_T = A[1 - (B/s)(1 - e^{-s/B})] (Lindgren Eq. 18-20) with amplitude
F_max = A c + W tan phi and shape B = K/L.

`janosi_forces` is the combined-slip force law the simulation injects, in plain floats (it is
called per wheel and per physics substep); its one implementation is C (``_laws.h``, which the
substep loop runs). `okello_secant` is its curve's shape on arrays, derived from the same C
function (``okello_h``). `shear_strength_pa` and `janosi_stress_pa`, the local stress law, take
floats or numpy arrays as they are (the track model evaluates them on its cells every
substep); the other functions broadcast over any array_like.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

import slipenv.terramechanics._laws as _laws
from slipenv.terramechanics.vectorize import array_law

__all__ = [
    "janosi_forces",
    "shear_strength_pa",
    "janosi_stress_pa",
    "mohr_coulomb_strength_pa",
    "janosi_shear_stress_pa",
    "okello_secant",
    "okello_traction",
    "max_thrust_n",
    "patch_thrust_n",
    "small_slip_stiffness",
]


def shear_strength_pa(pressure_pa: float | np.ndarray, cohesion_pa: float | np.ndarray,
                      tan_phi: float | np.ndarray) -> float | np.ndarray:
    """Mohr-Coulomb shear strength tau_max = c + p tan phi [Pa] (Wong Eq. 2.54; Lindgren Eq. 3).

    Floats or numpy arrays (broadcast), without conversions: the track model calls it on its
    cells at every physics substep (`track.cell_forces`), where each conversion costs more
    than the arithmetic.

    Parameters
    ----------
    pressure_pa : float or ndarray
        Normal stress p [Pa].
    cohesion_pa : float or ndarray
        Cohesion c [Pa].
    tan_phi : float or ndarray
        tan of the internal friction angle phi [-].
    """
    return pressure_pa * tan_phi + cohesion_pa


def janosi_stress_pa(j_abs_m: float | np.ndarray, strength_pa: float | np.ndarray,
                     shear_modulus_m: float | np.ndarray) -> float | np.ndarray:
    """Janosi-Hanamoto shear stress tau = tau_max (1 - e^{-|j|/K}) [Pa] (Wong Eq. 2.56;
    Lindgren Eq. 2), of the magnitude |j| >= 0 of the shear displacement.

    Floats or numpy arrays (broadcast), without conversions, as `shear_strength_pa`.

    Parameters
    ----------
    j_abs_m : float or ndarray
        |j| [m].
    strength_pa : float or ndarray
        Mohr-Coulomb strength tau_max [Pa] (`shear_strength_pa`).
    shear_modulus_m : float or ndarray
        Shear deformation modulus K [m].
    """
    return -(strength_pa * np.expm1(j_abs_m * (-1.0 / shear_modulus_m)))


def mohr_coulomb_strength_pa(normal_stress_pa: ArrayLike, cohesion_pa: ArrayLike,
                             friction_angle_rad: ArrayLike) -> np.ndarray:
    """Maximum soil shear strength q_max = c + sigma tan(phi) [Pa] (Lindgren Eq. 3).

    `shear_strength_pa` of the friction angle, on any array_like.

    Parameters
    ----------
    normal_stress_pa : array_like
        Normal stress sigma [Pa].
    cohesion_pa : array_like
        Cohesion c [Pa].
    friction_angle_rad : array_like
        Internal friction angle phi [rad].
    """
    return np.asarray(shear_strength_pa(np.asarray(normal_stress_pa, dtype=float),
                                        np.asarray(cohesion_pa), np.tan(friction_angle_rad)))


def janosi_shear_stress_pa(shear_displacement_m: ArrayLike, max_shear_stress_pa: ArrayLike,
                           shear_modulus_m: ArrayLike) -> np.ndarray:
    """Janosi-Hanamoto shear stress q = q_max (1 - e^{-j/K}) [Pa] (Lindgren Eq. 2).

    `janosi_stress_pa` extended as an odd function of j: a shear displacement in the opposite
    direction gives the opposite stress. Takes any array_like.

    Parameters
    ----------
    shear_displacement_m : array_like
        Shear displacement j [m].
    max_shear_stress_pa : array_like
        Mohr-Coulomb strength q_max [Pa] (`mohr_coulomb_strength_pa`).
    shear_modulus_m : array_like
        Shear deformation modulus K [m].
    """
    j = np.asarray(shear_displacement_m, dtype=float)
    return np.sign(j) * janosi_stress_pa(np.abs(j), np.asarray(max_shear_stress_pa),
                                         np.asarray(shear_modulus_m, dtype=float))


def _okello_h(x: float) -> float:
    """h(x) of `okello_secant` for one float x >= 0 (``_laws.h``, which the array version and
    `janosi_forces` evaluate)."""
    return _laws.okello_h(x)


okello_secant = array_law(_okello_h, name="okello_secant", doc="""\
Secant slope h(x) = g(x)/x = (x - 1 + e^{-x})/x^2 of Okello's normalised curve, x >= 0.

g(x) = 1 - (1 - e^{-x})/x is the bracket of Lindgren Eq. 18 at x = s/B, so the thrust is
F = F_max x h(x). h(0) = 1/2 (the limit of Lindgren Eq. 23); there is no 0/0 anywhere: below
x = 1e-5 the closed form, which loses ~4 eps/x to cancellation, gives way to its value at 1e-5
plus the first-order Taylor term h'(0) = -1/6 (error < x^2/24). Relative error below 1e-10 for
all x >= 0. Takes and returns arrays (0-d for a scalar).
""")


def janosi_forces(slip: float, tan_beta: float, load_n: float, cohesion_force_n: float,
                  tan_phi: float, shear_ratio: float,
                  lateral_ratio: float = 1.0) -> tuple[float, float]:
    """Janosi-Hanamoto shear integrated over a patch, combined slip split by direction [N].

    The soil under the patch is sheared along the slip velocity, so the shear displacement at
    distance x behind the front edge is x (s, tan_beta), of magnitude x sigma with
    sigma = sqrt(s^2 + tan^2 beta) (the combined slip of Reina Eq. 7). Isotropic Janosi shear
    (Lindgren Eq. 2) with the Mohr-Coulomb limit (Eq. 3) integrated over the patch gives the
    resultant F = F_max g(sigma L/K), g the Okello bracket (Eq. 18-20), against the slip
    velocity:

        fx = F s/sigma,   fy = -F tan_beta/sigma,   F_max = A c + W tan phi.

    Written as F/sigma = F_max h(x) L/K with x = sigma L/K (`okello_secant`), there is no 0/0
    at sigma = 0. Pure longitudinal slip reduces exactly to `patch_thrust_n`.

    Lateral anisotropy (optional, ``lateral_ratio`` kappa != 1): the soil's lateral shear
    deformation modulus is K/kappa, so the lateral displacement is mobilised kappa times faster:
    the combined slip becomes sigma = sqrt(s^2 + (kappa tan_beta)^2) and
    fy = -F kappa tan_beta/sigma. The small-slip lateral stiffness is kappa times the
    longitudinal one (Reina measured C_y/C_x = 3.6 on loose soil, Reina Table 3: the side wall
    bulldozes), while the resultant still saturates at the one Mohr-Coulomb limit F_max.
    kappa = 1 is the isotropic law above, exactly.

    Parameters
    ----------
    slip, tan_beta : float
        Slip ratio s [-] and tan of the slip angle [-] (convention of `contact`).
    load_n : float
        Normal load W [N]; W <= 0 (no contact) gives no force.
    cohesion_force_n : float
        A c [N]: contact area times soil cohesion.
    tan_phi : float
        tan of the soil's internal friction angle [-].
    shear_ratio : float
        L/K = 1/B [-]: shear length over the shear deformation modulus.
    lateral_ratio : float
        kappa = K_x/K_y [-], > 0: lateral over longitudinal small-slip stiffness; 1 (default)
        is isotropic.

    Returns
    -------
    fx_n, fy_n : float
        fx with the sign of s; fy opposing the lateral sliding, sign(fy) = -sign(tan_beta).
    """
    return _laws.janosi_forces(slip, tan_beta, load_n, cohesion_force_n, tan_phi, shear_ratio,
                               lateral_ratio)


def okello_traction(slip: ArrayLike, amplitude: ArrayLike, shape_b: ArrayLike) -> np.ndarray:
    """Okello's traction curve C_T = A [1 - (B/s)(1 - e^{-s/B})] (Lindgren Eq. 18, 20).

    Extended to braking as an odd function of s; finite at s = 0 (value 0, slope A/(2B)).

    Parameters
    ----------
    slip : array_like
        Slip ratio s [-].
    amplitude : array_like
        A: the value approached as s -> infinity (C_T in Eq. 18, T_max in Eq. 20, F_max here).
    shape_b : array_like
        B [-], > 0; for a patch of length L on soil of modulus K, B = K/L.
    """
    s = np.asarray(slip, dtype=float)
    return np.asarray(amplitude) * (s / shape_b) * okello_secant(np.abs(s) / shape_b)


def max_thrust_n(load_n: ArrayLike, area_m2: ArrayLike, cohesion_pa: ArrayLike,
                 friction_angle_rad: ArrayLike) -> np.ndarray:
    """Mohr-Coulomb thrust limit F_max = A c + W tan(phi) [N] of a contact patch.

    Lindgren Eq. 3 integrated over a patch of area A [m^2] carrying load W [N].
    """
    return np.asarray(area_m2) * cohesion_pa + np.asarray(load_n) * np.tan(friction_angle_rad)


def patch_thrust_n(slip: ArrayLike, load_n: ArrayLike, area_m2: ArrayLike,
                   contact_length_m: ArrayLike, cohesion_pa: ArrayLike,
                   friction_angle_rad: ArrayLike, shear_modulus_m: ArrayLike) -> np.ndarray:
    """Thrust of a patch, F = (A c + W tan phi)[1 - (K/(sL))(1 - e^{-sL/K})] [N].

    Janosi-Hanamoto shear (Lindgren Eq. 2) with Mohr-Coulomb strength (Eq. 3) integrated over
    the patch: Okello's curve (Eq. 18-20) with B = K/L. Odd in s (braking pushes backwards).

    Parameters
    ----------
    slip : array_like
        Slip ratio s [-], > 0 in drive.
    load_n : array_like
        Normal load W [N].
    area_m2 : array_like
        Contact area A [m^2].
    contact_length_m : array_like
        Contact length L [m] over which the shear displacement builds up.
    cohesion_pa, friction_angle_rad, shear_modulus_m : array_like
        Soil c [Pa], phi [rad], K [m].
    """
    f_max = max_thrust_n(load_n, area_m2, cohesion_pa, friction_angle_rad)
    return okello_traction(slip, f_max, np.asarray(shear_modulus_m) / contact_length_m)


def small_slip_stiffness(max_value: ArrayLike, shape_b: ArrayLike) -> np.ndarray:
    """Initial slope k = T_max/(2B) of Okello's curve (Lindgren Eq. 23-24).

    Parameters
    ----------
    max_value : array_like
        Amplitude of the curve: T_max [N m] gives k_s [N m], F_max [N] gives dF/ds [N].
    shape_b : array_like
        B = K/L [-].
    """
    return np.asarray(max_value) / (2.0 * np.asarray(shape_b))
