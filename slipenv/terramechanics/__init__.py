"""Wheel-soil force laws for slip-aware simulation: plain functions, no PyBullet.

Modules
-------
soil, presets
    `Soil` (validated, SI, sourced) and its numeric image `SoilParams`; the presets
    (Reina's lunar simulant and loose sand, Lindgren's field loam, Toyoura-like sand, concrete).
janosi, lindgren, reina, bekker
    Force laws, each citing its paper and equation: Janosi-Hanamoto shear and Okello's
    thrust curve (Lindgren Eq. 2-3, 18-24), the linear torque-slip law and the rolling-radius
    error (Lindgren Eq. 24-31), Reina's combined slip (Reina Eq. 5-12), Bekker sinkage and
    compaction resistance. The laws the simulation runs per wheel and substep are written
    once, in C (``_laws.h``: the force laws, the slip state, the dampers, the motion
    resistance, Bekker sinkage and multi-pass compaction), and bound by the Python API.
vectorize
    Their array versions, derived generically from the scalar code (`array_law`,
    `forces_on_arrays`).
contact, models
    The slip/sign convention (in `contact`'s docstring, used everywhere), `ContactGeometry`,
    and the `ForceModel` contract with its three implementations; `wheel_kernel(model, soil)`
    is the per-wheel float kernel the simulation calls at every physics substep.
slip_dynamics
    Slip as a state: the relaxation-length step, the two soil dampers and the rate-independent
    motion resistance (Pacejka §7.2.1; LuGre; Dupont et al. 2002), float functions of one
    wheel (the C laws of ``_laws.h``).
soil_map
    Soils varying over the ground: `UniformSoil`, `PatchSoilMap`, `GridSoilMap`
    (regions: `Circle`, `Rectangle`, their `Union` and `Intersection`).
"""

from slipenv.terramechanics.contact import ContactGeometry, slip_ratio
from slipenv.terramechanics.models import (
    FORCE_MODELS,
    ForceModel,
    JanosiForceModel,
    LinearSlipForceModel,
    ReinaForceModel,
    force_model_by_name,
    wheel_kernel,
)
from slipenv.terramechanics.presets import (
    CONCRETE,
    DRY_SAND,
    FIELD_LOAM,
    LOOSE_SAND,
    LUNAR_SIMULANT,
    SOILS,
    TOYOURA_SAND,
    soil_by_name,
)
from slipenv.terramechanics.slip_dynamics import (
    critical_damping_ns_per_m,
    lateral_soil_damping_n,
    longitudinal_soil_damping_n,
    relax_slip,
    resistance_along_travel_n,
)
from slipenv.terramechanics.soil import PARAM_FIELDS, Soil, SoilParams
from slipenv.terramechanics.soil_map import (
    Circle,
    GridSoilMap,
    Intersection,
    PatchSoilMap,
    Rectangle,
    Region,
    SoilMap,
    UniformSoil,
    Union,
)

__all__ = [
    "CONCRETE",
    "FIELD_LOAM",
    "FORCE_MODELS",
    "LOOSE_SAND",
    "LUNAR_SIMULANT",
    "PARAM_FIELDS",
    "SOILS",
    "DRY_SAND",
    "TOYOURA_SAND",
    "Circle",
    "ContactGeometry",
    "ForceModel",
    "GridSoilMap",
    "Intersection",
    "JanosiForceModel",
    "LinearSlipForceModel",
    "PatchSoilMap",
    "ReinaForceModel",
    "Rectangle",
    "Region",
    "Soil",
    "SoilMap",
    "SoilParams",
    "UniformSoil",
    "Union",
    "critical_damping_ns_per_m",
    "force_model_by_name",
    "lateral_soil_damping_n",
    "longitudinal_soil_damping_n",
    "relax_slip",
    "resistance_along_travel_n",
    "slip_ratio",
    "soil_by_name",
    "wheel_kernel",
]
