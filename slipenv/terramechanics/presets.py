"""Soil presets with their sources, and lookup by name.

Sources: Reina = Reina et al. 2010 (Tables 2-3); Lindgren = Lindgren et al. 2002 (Sec. 3.2);
Wong = J. Y. Wong, *Theory of Ground Vehicles* (terrain-value table of Ch. 2, Bekker and
Mohr-Coulomb values per soil). "assumed" marks a value the sources leave out, chosen from the
literature range and explained in the comment.

Reina's Table 3 (mu, C_x, C_y, A_x, A_y) was fitted only for the lunar simulant. For the other
deformable soils mu, C_x and C_y are Table 3 scaled by the ratio, on Reina's own test wheel
(r = 92 mm, b = 110 mm, W = 6.6 kg), of what the Janosi/Bekker models predict for that soil to
what they predict for the simulant: mu by (A c + W tan phi)/W, C_x and C_y by the small-slip
stiffness (A c + W tan phi) L/(2K) (Lindgren Eq. 24), with the contact length L = r
acos(1 - z/r) from Bekker sinkage z. A_x and A_y keep Table 3's values (assumed).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from types import MappingProxyType

from slipenv.terramechanics.soil import Soil

__all__ = ["LUNAR_SIMULANT", "LOOSE_SAND", "FIELD_LOAM", "TOYOURA_SAND", "DRY_SAND", "CONCRETE",
           "SOILS", "soil_by_name"]

_REINA_WHEEL_LOAD_N = 6.6 * 9.80665  # [N] Reina Sec. 3.2: W = 6.6 kg on the test bed

LUNAR_SIMULANT = Soil(
    name="lunar_simulant",
    cohesion_pa=800.0,                      # Reina Table 2 (FJS-1, Kanamori et al. 1998)
    friction_angle_rad=math.radians(30.0),  # Reina Table 2
    shear_modulus_m=0.018,                  # assumed: Wong/Bekker lunar soil, K = 1.8 cm
    k_c=1.4e3,                              # assumed: Wong/Bekker lunar soil
    k_phi=820e3,                            # assumed: Wong/Bekker lunar soil
    n_exp=1.0,                              # assumed: Wong/Bekker lunar soil
    mu=0.6,                                 # Reina Table 3
    c_x_n=55.0,                             # Reina Table 3
    c_y_n=200.0,                            # Reina Table 3
    a_x=0.02,                               # Reina Table 3
    a_y=0.04,                               # Reina Table 3
    reference_load_n=_REINA_WHEEL_LOAD_N,   # Reina Sec. 3.2
    rolling_radius_scale=1.0,               # assumed: rigid rover wheel, no tyre deflection
    deformable=True,
)

LOOSE_SAND = Soil(
    name="loose_sand",
    cohesion_pa=600.0,                      # Reina Table 2 (from Wong): 0.2-1.0 kPa, midpoint
    friction_angle_rad=math.radians(29.0),  # Reina Table 2: 26-32 deg, midpoint
    shear_modulus_m=0.025,                  # assumed: Wong, K of loose sand about 2.5 cm
    k_c=0.99e3,                             # assumed: Wong, dry sand (LLL)
    k_phi=1528.43e3,                        # assumed: Wong, dry sand (LLL)
    n_exp=1.1,                              # assumed: Wong, dry sand (LLL)
    mu=0.56,                                # assumed: Table 3 scaled (module docstring)
    c_x_n=35.0,                             # assumed: Table 3 scaled
    c_y_n=127.0,                            # assumed: Table 3 scaled
    a_x=0.02,                               # assumed: Reina Table 3
    a_y=0.04,                               # assumed: Reina Table 3
    reference_load_n=_REINA_WHEEL_LOAD_N,
    rolling_radius_scale=1.0,               # assumed: rigid rover wheel
    deformable=True,
)

FIELD_LOAM = Soil(
    name="field_loam",
    # Lindgren's field soil at Silsoe is not characterised in the paper; a sandy loam is assumed
    # and all strength values are Wong's sandy loam (LLL, 15 % moisture).
    cohesion_pa=1.72e3,                     # assumed: Wong, sandy loam (LLL, 15 %)
    friction_angle_rad=math.radians(29.0),  # assumed: Wong, sandy loam (LLL, 15 %)
    shear_modulus_m=0.025,                  # assumed: upper end of Wong's 1-2.5 cm; Lindgren
    #                                         sees a near-linear torque/slip curve (Fig. 2),
    #                                         which needs B = K/L not small
    k_c=5.27e3,                             # assumed: Wong, sandy loam (LLL, 15 %)
    k_phi=1515.04e3,                        # assumed: Wong, sandy loam (LLL, 15 %)
    n_exp=0.7,                              # assumed: Wong, sandy loam (LLL, 15 %)
    mu=0.57,                                # assumed: Table 3 scaled
    c_x_n=16.5,                             # assumed: Table 3 scaled
    c_y_n=60.0,                             # assumed: Table 3 scaled
    a_x=0.02,                               # assumed: Reina Table 3
    a_y=0.04,                               # assumed: Reina Table 3
    reference_load_n=_REINA_WHEEL_LOAD_N,
    rolling_radius_scale=0.285 / 0.275,     # Lindgren Sec. 3.2: mean of 0.283/0.287 m on soil
    #                                         over 0.275 m on concrete
    deformable=True,
)

TOYOURA_SAND = Soil(
    name="toyoura_sand",
    # Yamauchi's loosely poured Toyoura sand (a dry, uniform quartz sand, JGS standard sand).
    # Strength and shear deformation: the Tohoku space-robotics group's Toyoura sand set, as
    # in G. Ishigami's TerraDyn soil definition file "Toyoura Std. Sand" (2007, revised 2012;
    # a public copy found by code search): c = 0, phi = 38 deg, K = 28.3 mm, rho = 1.49 g/cm^3.
    # Its pressure-sinkage set (n = 1.703, k_c = 0, k_phi = 1203.54, units unstated, read as
    # kN/m^(n+2); the file divides it by g, softer still) belongs to the group's 0.1 m wide
    # wheel; under Patako's 0.11 x 0.48 m track it gives 28 mm static and 90-100 mm turning
    # sinkage (Lyasko's slip sinkage at 0.8-0.9 slip), and the simulated Patako then turns
    # 20 deg in 12 s at 30 deg/s where the paper's made its 90 deg rotations at 10-30 deg/s
    # (Yamauchi Sec. 2.3): rejected by that measurement. The Bekker constants are therefore
    # the closest sourced dry loose silica sand's, Wong's dry sand (LLL, as ``dry_sand``),
    # with 3 mm static sinkage.
    # Lateral behaviour: no separate lateral constants; the track model's side walls take
    # Rankine's passive pressure from phi and c (K_p = tan^2(45 + phi/2) = 4.2, no cohesion
    # term) and the Janosi shear acts along the sliding direction, isotropic in K.
    cohesion_pa=0.0,                        # Ishigami (TerraDyn Toyoura set): cohesionless
    friction_angle_rad=math.radians(38.0),  # Ishigami (TerraDyn Toyoura set)
    shear_modulus_m=0.0283,                 # Ishigami (TerraDyn Toyoura set): 28.3 mm
    k_c=0.99e3,                             # Wong, dry sand (LLL) (comment above)
    k_phi=1528.43e3,                        # Wong, dry sand (LLL)
    n_exp=1.1,                              # Wong, dry sand (LLL)
    mu=0.71,                                # assumed: Table 3 scaled (module docstring)
    c_x_n=39.4,                             # assumed: Table 3 scaled
    c_y_n=143.5,                            # assumed: Table 3 scaled
    a_x=0.02,                               # assumed: Reina Table 3
    a_y=0.04,                               # assumed: Reina Table 3
    reference_load_n=_REINA_WHEEL_LOAD_N,
    rolling_radius_scale=1.0,               # assumed: rigid rover wheel
    deformable=True,
)

DRY_SAND = Soil(
    name="dry_sand",
    # A dry, loose silica sand for the Yamauchi experiments (their Toyoura sand was poured
    # loose into a 0.2 m box; no bevameter set for it was found). Every Bekker and strength
    # value is the Land Locomotion Laboratory's dry sand as tabulated by Wong (Theory of Ground
    # Vehicles, Ch. 2, table of terrain values: n = 1.1, k_c = 0.99 kN/m^(n+1), k_phi =
    # 1528.43 kN/m^(n+2), c = 1.04 kPa, phi = 28 deg). The 30 kg Patako sinks ~3 mm on it
    # (2.9 kPa ground pressure), against 0.06 mm on LETE sand.
    cohesion_pa=1.04e3,                     # Wong, dry sand (LLL)
    friction_angle_rad=math.radians(28.0),  # Wong, dry sand (LLL)
    shear_modulus_m=0.025,                  # Wong Ch. 2 (after Bekker): K about 2.5 cm for
    #                                         loose sand (1 cm at maximum compaction)
    k_c=0.99e3,                             # Wong, dry sand (LLL)
    k_phi=1528.43e3,                        # Wong, dry sand (LLL)
    n_exp=1.1,                              # Wong, dry sand (LLL)
    mu=0.56,                                # assumed: as loose_sand (Reina Table 3 scaled)
    c_x_n=35.0,                             # assumed: as loose_sand
    c_y_n=127.0,                            # assumed: as loose_sand
    a_x=0.02,                               # assumed: Reina Table 3
    a_y=0.04,                               # assumed: Reina Table 3
    reference_load_n=_REINA_WHEEL_LOAD_N,
    rolling_radius_scale=1.0,               # assumed: rigid wheel
    deformable=True,
)

CONCRETE = Soil(
    name="concrete",
    # Rigid ground: traction is limited by rubber-on-concrete friction, so (c, phi) describe the
    # tyre-ground interface, not the concrete: adhesion is folded into tan(phi) = 0.8.
    cohesion_pa=0.0,                        # assumed: interface adhesion folded into phi
    friction_angle_rad=math.atan(0.8),      # assumed: tyre on dry concrete, peak mu 0.8-0.9
    shear_modulus_m=0.001,                  # assumed: tread shear only (~1 mm), so the slip
    #                                         stiffness is tyre-like, about 10-20 W per unit slip
    k_c=0.0,                                # unused: not deformable
    k_phi=1e12,                             # effectively rigid; unused: not deformable
    n_exp=1.0,                              # unused: not deformable
    mu=0.8,                                 # assumed: tyre on dry concrete
    c_x_n=650.0,                            # assumed: ~10 W_ref, tyre-like slip stiffness
    c_y_n=650.0,                            # assumed: = C_x, no bulldozing on rigid ground
    a_x=0.1,                                # assumed: sliding friction ~ 0.875 of peak
    a_y=0.1,                                # assumed: as a_x
    reference_load_n=_REINA_WHEEL_LOAD_N,
    rolling_radius_scale=1.0,               # Lindgren Sec. 3.2: the reference surface
    deformable=False,
)

SOILS: Mapping[str, Soil] = MappingProxyType(
    {s.name: s for s in (LUNAR_SIMULANT, LOOSE_SAND, FIELD_LOAM, TOYOURA_SAND, DRY_SAND, CONCRETE)}
)
"""All presets by name (read-only)."""


def soil_by_name(name: str) -> Soil:
    """Return the preset called `name`.

    Raises
    ------
    ValueError
        If `name` is not a preset; the message names it and lists the known names.
    """
    try:
        return SOILS[name]
    except (KeyError, TypeError):
        known = ", ".join(sorted(SOILS))
        raise ValueError(f"unknown soil {name!r}; known soils: {known}") from None
