"""Force models: the injection contract the simulation calls at every wheel contact.

A force model is built once per wheel set with the wheels' `ContactGeometry`. Bound to one soil
it is a per-wheel float kernel, ``model.scalar_kernel(soil)``:
``(slip, tan_beta, load_n) -> (fx_n, fy_n, resistance_n)``. For slipenv's three models the
binding is a `KernelConstants` (`kernel_constants`) and the kernel is the C law of
``slipenv/terramechanics/_laws.h`` (``laws_kernel``), the one text the simulation's substep
loop runs too; the models add the contact geometry, Bekker compaction and rolling resistance
(`bekker`); Reina's law is a net force and gets compaction only on request
(`ReinaForceModel`). A subclass that changes the law (its `kernel_constants` is None) keeps
its own Python kernel, which the substep loop calls back.

The array interface of the `ForceModel` protocol, ``model(slip, tan_beta, load_n, soil)`` and
``model.resistance_n(load_n, soil)`` on arrays of shape (n,) with a `SoilParams` of floats or
of arrays (a soil map), is derived from the kernel element by element
(`vectorize.forces_on_arrays`): for analysis, tests and the diagnosis, not the hot path.
`wheel_kernel(model, soil)` gives the kernel of any `ForceModel`.
"""

from __future__ import annotations

import copy
import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, NamedTuple, Protocol, runtime_checkable

import numpy as np

import slipenv.terramechanics._laws as _laws
from slipenv.terramechanics.bekker import track_compaction_law, wheel_compaction_law
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.soil import SoilParams
from slipenv.terramechanics.vectorize import Kernel, forces_on_arrays

__all__ = ["DEFAULT_EXCAVATION_DEPTH_M", "DEFAULT_UNIT_WEIGHT_N_M3", "SLIP_SINKAGE_MODES",
           "WHEEL_SLIP_SINKAGE", "ForceModel", "JanosiForceModel", "KernelConstants",
           "LinearSlipForceModel", "ReinaForceModel", "FORCE_MODELS", "dug_depth_resistance",
           "dug_depth_step", "force_model_by_name", "slip_angle_convention",
           "slip_sinkage_resistance", "wheel_kernel"]


@runtime_checkable
class ForceModel(Protocol):
    """What the simulation injects at each contact (convention: `slipenv.terramechanics.contact`).

    ``__call__(slip, tan_beta, load_n, soil)`` returns ``(fx_n, fy_n)`` of shape (n,) in the
    wheel's heading frame: fx > 0 pushes forward; fy opposes lateral sliding,
    sign(fy) = -sign(tan_beta). ``resistance_n(load_n, soil)`` returns the magnitude (>= 0) of
    the motion resistance (compaction + rolling), applied against the direction of travel.
    A model may also offer ``scalar_kernel(soil)`` (see `wheel_kernel`), the fast path, and
    ``slip_angle_convention`` (`slip_angle_convention`), the tan_beta its law takes.
    """

    def __call__(self, slip: np.ndarray, tan_beta: np.ndarray, load_n: np.ndarray,
                 soil: SoilParams) -> tuple[np.ndarray, np.ndarray]: ...

    def resistance_n(self, load_n: np.ndarray, soil: SoilParams) -> np.ndarray: ...


def wheel_kernel(model: ForceModel, soil: SoilParams) -> Kernel:
    """The per-wheel float kernel ``(slip, tan_beta, load_n) -> (fx_n, fy_n, resistance_n)``.

    Uses the model's ``scalar_kernel(soil)`` hook when it has one (all of slipenv's models and
    wrappers do); any other `ForceModel` is wrapped, correct but slower (one array call of
    length 1 per evaluation).

    Parameters
    ----------
    model : ForceModel
        The force law.
    soil : SoilParams
        One soil, with float fields.
    """
    hook = getattr(model, "scalar_kernel", None)
    if hook is not None:
        kernel: Kernel = hook(soil)
        return kernel

    def array_kernel(slip: float, tan_beta: float, load_n: float) -> tuple[float, float, float]:
        w = np.array([load_n])
        fx, fy = model(np.array([slip]), np.array([tan_beta]), w, soil)
        return float(fx[0]), float(fy[0]), float(model.resistance_n(w, soil)[0])

    return array_kernel


def slip_angle_convention(model: ForceModel) -> str:
    """The slip angle `model`'s law takes: ``"reina"`` or ``"sliding"``.

    ``"reina"``: tan_beta = v_lat/|v_x| (Reina Eq. 4), the convention Reina's law was fitted
    in. ``"sliding"``: tan_beta = v_lat/max(|r omega|, |v_x|), (s, tan_beta) along the contact
    point's sliding velocity, the shear displacement per unit patch length of the Janosi and
    linear laws (`JanosiForceModel`). The simulation relaxes the slip state to the model's
    convention (`slip_dynamics.relax_slip`). Read from the model's ``slip_angle_convention``
    attribute; a wrapper without one (a model with a ``base`` law, such as the diagnosis's
    scaled-slip wrapper) takes its base's; any other law the sliding one.
    """
    law: Any = model
    for _ in range(32):  # wrappers of wrappers, never a cycle
        convention = getattr(law, "slip_angle_convention", None)
        if convention is not None:
            if convention not in ("reina", "sliding"):
                raise ValueError(f"slip_angle_convention={convention!r} of {law!r} must be "
                                 "'reina' or 'sliding'")
            return str(convention)
        law = getattr(law, "base", None)
        if law is None:
            break
    return "sliding"


class KernelConstants(NamedTuple):
    """A force model bound to one soil, as its C law reads it (``_laws.h``, ``LawsKernel``;
    field order is the C side's).

    ``kind`` names the law (0 Janosi, 1 linear, 2 Reina); the fields a law does not use are 0.
    """

    kind: int
    cohesion_force_n: float  # A c (Janosi, linear; Lindgren Eq. 3)
    tan_phi: float
    shear_ratio: float  # L/K = 1/B
    kappa: float  # lateral_stiffness_ratio (Janosi, linear)
    mu: float  # Reina Eq. 5-9
    c_x_n: float  # C_x, over W_ref when scaled
    c_y_n: float
    a_x: float
    a_y: float
    scaled: bool  # Reina: the law at W = 1 times W
    gross: bool  # Reina with compaction: gross thrust
    gross_c_x_n: float  # C_x as given, for the gross thrust
    reference_load_n: float  # W_ref when scaled, else 0
    rolling_resistance_coeff: float  # f_r
    compaction_gamma: float  # gamma of gamma W^e (0: rigid ground or none)
    compaction_exponent: float  # e
    slip_sinkage: bool = False  # add `slip_sinkage_resistance`
    sinkage_gamma: float = 0.0  # the wheel's Bekker compaction gamma W^e, for slip sinkage
    sinkage_exponent: float = 1.0
    width_m: float = 0.0  # b, D, k_c, k_phi, n of its static sinkage (`bekker`)
    diameter_m: float = 0.0
    k_c: float = 0.0
    k_phi: float = 0.0
    n_exp: float = 1.0
    cohesion_pa: float = 0.0  # c, phi, gamma_s of the bulldozing (`sidewall`)
    friction_angle_rad: float = 0.0
    unit_weight_n_m3: float = 0.0
    sinkage_state: bool = False  # the simulation's dug-depth state (`dug_depth_step`)
    excavation_depth_m: float = 0.0  # delta [m] of `dug_depth_step`


SLIP_SINKAGE_MODES = (None, "bulldozing", "full", "accumulated")
"""Values of the models' ``slip_sinkage`` option: None, off (the resistance at the static
sinkage only); ``"bulldozing"``, the soil the slip digs out below the static rut, Lyasko's
instantaneous slip sinkage, is bulldozed ahead of the wheel (`slip_sinkage_resistance`);
``"full"``, that plus the Bekker compaction at the slip sinkage; ``"accumulated"``, the depth
dug is a state of each wheel that grows with the distance slid and relaxes over the distance
rolled (`dug_depth_step`), and that soil is bulldozed ahead of the wheel
(`dug_depth_resistance`)."""

WHEEL_SLIP_SINKAGE: str | None = "accumulated"
"""The models' default ``slip_sinkage`` (`SLIP_SINKAGE_MODES`) for a wheel's contact (a
track's contact never takes it: `slipenv.terramechanics.track` has its own law); on rigid
ground every mode is off."""

DEFAULT_EXCAVATION_DEPTH_M = 2e-3
"""delta [m] of the ``"accumulated"`` slip sinkage (`dug_depth_step`): the depth a wheel digs
per patch length it slides. The slipping rim drags the soil of a shear band of thickness t_b,
whose speed falls linearly from the slip speed at the rim to 0 below it, so it carries
t_b |r omega - v|/2 per unit width out through the rear of its patch; spread over the patch
length sigma that lowers the patch at t_b |r omega - v|/(2 sigma): delta = t_b/2. The band in
sand is 10-20 grain diameters thick (Roscoe, Geotechnique 20(2), 1970; about 16 d50 in
Muhlhaus and Vardoulakis, Geotechnique 37(3), 1987); 2 mm is half of 16 d50 at d50 = 0.25 mm,
a medium-fine sand (assumed: slipenv's soils carry no grain size)."""

DEFAULT_UNIT_WEIGHT_N_M3 = 1.5e3 * 9.81
"""Soil unit weight gamma_s [N/m^3] of the bulldozing term when none is given: a dry sand of
bulk density 1.5 t/m^3 (assumed; loose to medium dry sands are 1.4-1.7 t/m^3, Wong, Theory of
Ground Vehicles, Ch. 2; Toyoura sand 1.335 t/m^3 loose)."""


def slip_sinkage_resistance(slip: float, load_n: float, constants: KernelConstants) -> float:
    """Resistance [N] a wheel slipping at `slip` adds to its static motion resistance.

    Lyasko's slip sinkage z = z0 (1 + i)/(1 - 0.5 i), i = |s| clipped to [0, 1] (Lyasko,
    "Slip sinkage effect in soil-vehicle mechanics", J. Terramech. 47 (2010) 21-31), raises
    the Bekker compaction R_c = b k_eq z^(n+1)/(n+1) (Wong, Theory of Ground Vehicles, Ch. 5)
    from R_c0 to R_c0 f^(n+1), and the soil the slip digs out below the static rut, depth
    z0 (f - 1), is bulldozed ahead of the wheel's front: b R_b(z0 (f - 1)), Bekker's
    R_b(h) = D_1 (c h + D_2 gamma_s h^2/2) per unit width (Bekker, Theory of Land Locomotion,
    1956, pp. 280-282; `sidewall.bulldozing_resistance_n_per_m`). Zero at zero slip, >= 0 and
    non-decreasing in |s|; a skidding wheel (s < 0, locked at s = -1) counts as the slip of
    the same magnitude (assumed: Lyasko measured driven wheels). The C law
    ``laws_slip_sinkage_resistance`` of ``_laws.h``, with the wheel's static sinkage
    `bekker.wheel_sinkage_float_m` at `load_n` and its compaction gamma W^e. 0 unless
    ``constants.slip_sinkage``.
    """
    c = constants
    if not c.slip_sinkage or load_n <= 0.0:
        return 0.0
    z0 = _laws.wheel_sinkage_m(load_n, c.width_m, c.diameter_m, c.k_c, c.k_phi, c.n_exp)
    rc0 = _laws.motion_resistance_n(load_n, 0.0, c.sinkage_gamma, c.sinkage_exponent)
    return _laws.slip_sinkage_resistance_n(slip, rc0, c.n_exp, z0, c.width_m, c.cohesion_pa,
                                           c.friction_angle_rad, c.unit_weight_n_m3)


def dug_depth_step(dug_m: float, rim_mps: float, v_long_mps: float, dt_over_sigma: float,
                   delta_m: float, cap_m: float) -> float:
    """One substep of the depth [m] a wheel has dug below its static rut (slip sinkage as a
    state): sigma dd/dt = delta |r omega - v| - v_roll d, clipped to [0, cap].

    A slipping rim carries soil out from under its patch to its rear, the excavation behind
    slip sinkage (Lyasko, J. Terramech. 47 (2010) 21-31); the rate law is that mass balance
    over the patch: delta [m] is the depth dug per patch length sigma slid
    (`DEFAULT_EXCAVATION_DEPTH_M`), so the depth grows with the distance slid. Rolling onto
    fresh soil at v_roll = min(|r omega|, |v|) (r omega and v the same way, else 0) replaces
    the patch over one patch length: the depth relaxes as exp(-x/sigma) over the distance x
    rolled. Steady state d = delta s/(1 - |s|) (Wong's slip s, |s| < 1, drive or braking); a
    wheel spinning in place or locked and skidding rolls onto nothing and digs until `cap_m`.
    Backward Euler with h = dt/sigma: d' = (d + h delta |r omega - v|)/(1 + h v_roll). The C
    law ``laws_slip_sinkage_step`` of ``_laws.h``, which the simulation runs.
    """
    return _laws.slip_sinkage_step(dug_m, rim_mps, v_long_mps, dt_over_sigma, delta_m, cap_m)


def dug_depth_resistance(dug_m: float, load_n: float, constants: KernelConstants) -> float:
    """Resistance [N] a wheel dug `dug_m` below its static rut adds to its static one.

    The dug soil is bulldozed ahead of the wheel's front, b R_b(d) (Bekker, Theory of Land
    Locomotion, 1956, pp. 280-282; `sidewall.bulldozing_resistance_n_per_m`), and, where the
    constants carry the wheel's compaction (``sinkage_gamma``), the Bekker compaction grows
    from R_c0 to R_c0 ((z0 + d)/z0)^(n+1) (Wong, Theory of Ground Vehicles, Ch. 5), z0 the
    static sinkage at `load_n`. The C law ``laws_dug_resistance``; 0 at d = 0 or W <= 0.
    """
    c = constants
    if load_n <= 0.0:
        return 0.0
    z0 = _laws.wheel_sinkage_m(load_n, c.width_m, c.diameter_m, c.k_c, c.k_phi, c.n_exp)
    rc0 = _laws.motion_resistance_n(load_n, 0.0, c.sinkage_gamma, c.sinkage_exponent)
    return _laws.dug_resistance_n(dug_m, rc0, c.n_exp, z0, c.width_m, c.cohesion_pa,
                                  c.friction_angle_rad, c.unit_weight_n_m3)


class _PatchModel(ABC):
    """Kernel assembly, Bekker + rolling resistance and the derived array interface.

    A subclass binds its force law to a soil's constants (`_forces`, `kernel_constants`).
    Constructor arguments as documented on `JanosiForceModel`.
    """

    # The slip angle the law takes (`slip_angle_convention`): the shear laws', along the
    # sliding velocity.
    slip_angle_convention = "sliding"

    def __init__(self, geometry: ContactGeometry, rolling_resistance_coeff: float = 0.01,
                 lateral_stiffness_ratio: float = 1.0,
                 slip_sinkage: str | None = WHEEL_SLIP_SINKAGE,
                 soil_unit_weight_n_m3: float = DEFAULT_UNIT_WEIGHT_N_M3,
                 excavation_depth_m: float = DEFAULT_EXCAVATION_DEPTH_M) -> None:
        if not isinstance(geometry, ContactGeometry):
            raise TypeError(f"geometry must be a ContactGeometry, got {type(geometry).__name__}")
        coeff = float(rolling_resistance_coeff)
        if not (math.isfinite(coeff) and coeff >= 0.0):
            raise ValueError(f"rolling_resistance_coeff={rolling_resistance_coeff!r} must be "
                             "finite and >= 0")
        ratio = float(lateral_stiffness_ratio)
        if not (math.isfinite(ratio) and ratio > 0.0):
            raise ValueError(f"lateral_stiffness_ratio={lateral_stiffness_ratio!r} must be "
                             "finite and > 0")
        unit_weight = float(soil_unit_weight_n_m3)
        if not (math.isfinite(unit_weight) and unit_weight >= 0.0):
            raise ValueError(f"soil_unit_weight_n_m3={soil_unit_weight_n_m3!r} must be finite "
                             "and >= 0")
        excavation = float(excavation_depth_m)
        if not (math.isfinite(excavation) and excavation >= 0.0):
            raise ValueError(f"excavation_depth_m={excavation_depth_m!r} must be finite and "
                             ">= 0")
        if slip_sinkage not in SLIP_SINKAGE_MODES:
            raise ValueError(f"slip_sinkage={slip_sinkage!r} must be one of "
                             f"{SLIP_SINKAGE_MODES!r}")
        if geometry.is_track and slip_sinkage == WHEEL_SLIP_SINKAGE:
            slip_sinkage = None  # the wheels' default; a track's contact has its own law
        if slip_sinkage is not None and geometry.is_track:
            raise ValueError("slip_sinkage is the rigid wheel's law; a track's contact "
                             "(ContactGeometry.track_length_m) has its own "
                             "(slipenv.terramechanics.track)")
        self.geometry = geometry
        self.rolling_resistance_coeff = coeff
        self.lateral_stiffness_ratio = ratio
        self.slip_sinkage = slip_sinkage
        self.soil_unit_weight_n_m3 = unit_weight
        self.excavation_depth_m = excavation

    @abstractmethod
    def _forces(self, soil: SoilParams) -> Callable[[float, float, float], tuple[float, float]]:
        """The class's force law with `soil`'s constants bound: ``(slip, tan_beta, load_n) ->
        (fx_n, fy_n)`` in floats (constants bound by closure: star-arguments cost more than the
        law in the hot path)."""

    def _patch_constants(self, soil: SoilParams) -> tuple[float, float, float]:
        """(A c [N], tan phi, L/K): F_max = A c + W tan phi (Lindgren Eq. 3) and 1/B."""
        g = self.geometry
        return (float(g.area_m2 * np.asarray(soil.cohesion_pa, dtype=float)),
                float(np.tan(soil.friction_angle_rad)),
                float(g.shear_length_m / np.asarray(soil.shear_modulus_m, dtype=float)))

    def _shear_law_forces(
            self, soil: SoilParams, law: Callable[..., tuple[float, float]],
    ) -> Callable[[float, float, float], tuple[float, float]]:
        """`law`, a patch shear law of ``_laws`` (``(slip, tan_beta, load_n, A c, tan phi, L/K,
        kappa) -> (fx, fy)``), bound to `soil`'s `_patch_constants` and the model's kappa."""
        ac, tan_phi, ratio = self._patch_constants(soil)
        kappa = self.lateral_stiffness_ratio

        def forces(slip: float, tan_beta: float, load_n: float) -> tuple[float, float]:
            return law(slip, tan_beta, load_n, ac, tan_phi, ratio, kappa)
        return forces

    def _compaction(self, soil: SoilParams) -> tuple[float, float]:
        """(gamma, e) of the Bekker compaction resistance gamma W^e of this contact (`bekker`)."""
        g = self.geometry
        if g.is_track:
            gamma, exponent = track_compaction_law(g.width_m, g.contact_length_m, soil.k_c,
                                                   soil.k_phi, soil.n_exp, soil.deformable)
            gamma = gamma * g.rut_share
        else:
            gamma, exponent = wheel_compaction_law(g.width_m, 2.0 * g.radius_m, soil.k_c,
                                                   soil.k_phi, soil.n_exp, soil.deformable)
        return float(gamma), float(exponent)

    def _slip_sinkage_constants(self, soil: SoilParams) -> dict[str, Any]:
        """The slip-sinkage fields of `KernelConstants` (`slip_sinkage_resistance`), by name:
        off unless asked for and the ground is deformable."""
        deformable = float(soil.deformable)
        if self.slip_sinkage is None or deformable <= 0.0:
            return {}  # the NamedTuple's defaults: off
        g = self.geometry
        gamma, exponent = wheel_compaction_law(g.width_m, 2.0 * g.radius_m, soil.k_c,
                                               soil.k_phi, soil.n_exp, deformable)
        state = self.slip_sinkage == "accumulated"
        return {"slip_sinkage": not state, "sinkage_state": state,
                "excavation_depth_m": self.excavation_depth_m if state else 0.0,
                "sinkage_gamma": float(gamma) if self.slip_sinkage == "full" else 0.0,
                "sinkage_exponent": float(exponent), "width_m": float(g.width_m),
                "diameter_m": 2.0 * float(g.radius_m), "k_c": float(soil.k_c),
                "k_phi": float(soil.k_phi), "n_exp": float(soil.n_exp),
                "cohesion_pa": float(soil.cohesion_pa),
                "friction_angle_rad": float(soil.friction_angle_rad),
                "unit_weight_n_m3": self.soil_unit_weight_n_m3}

    # The C law's name for the class's force law (`kernel_constants`, ``_laws.h``).
    _COMPILED_KIND: int | None = None

    def kernel_constants(self, soil: SoilParams) -> KernelConstants | None:
        """This model bound to `soil`, as the C law (``_laws.h``, ``laws_kernel``) reads it.

        None for a subclass, which may change the law: it keeps its own Python kernel
        (`_forces`), which the substep loop calls back."""
        if self._COMPILED_KIND is None or type(self) not in _COMPILED_MODELS:
            return None
        ac, tan_phi, ratio = self._patch_constants(soil)
        gamma, exponent = self._compaction(soil)
        return KernelConstants(self._COMPILED_KIND, ac, tan_phi, ratio,
                               self.lateral_stiffness_ratio, 0.0, 0.0, 0.0, 0.0, 0.0, False,
                               False, 0.0, 0.0, self.rolling_resistance_coeff, gamma, exponent,
                               **self._slip_sinkage_constants(soil))

    def scalar_kernel(self, soil: SoilParams) -> Kernel:
        """The per-wheel float function ``(slip, tan_beta, load_n) -> (fx, fy, resistance)``.

        The force law of the class with `soil`'s constants bound once; the resistance is
        gamma W^e + f_r W (Bekker compaction, zero on rigid ground, plus rolling). ``soil``
        must have float fields; the kernel expects ``load_n`` > 0 (the array interface
        clamps loads at 0: no contact, no force). For slipenv's classes this is the C law
        bound to `kernel_constants` (``_laws.Kernel``); a subclass gets its `_forces` plus
        the same resistance.
        """
        constants = self.kernel_constants(soil)
        if constants is not None:
            law: Kernel = _laws.Kernel(constants)
            return law
        gamma, exponent = self._compaction(soil)
        forces, f_r = self._forces(soil), self.rolling_resistance_coeff
        resistance = _laws.motion_resistance_n
        sink = KernelConstants(0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, False, False,
                               0.0, 0.0, 0.0, 0.0, 1.0, **self._slip_sinkage_constants(soil))
        if not sink.slip_sinkage:
            def kernel(slip: float, tan_beta: float,
                       load_n: float) -> tuple[float, float, float]:
                fx, fy = forces(slip, tan_beta, load_n)
                return fx, fy, resistance(load_n, f_r, gamma, exponent)
            return kernel

        def sinking(slip: float, tan_beta: float, load_n: float) -> tuple[float, float, float]:
            fx, fy = forces(slip, tan_beta, load_n)
            res = resistance(load_n, f_r, gamma, exponent)
            return fx, fy, res + slip_sinkage_resistance(slip, load_n, sink)
        return sinking

    def __call__(self, slip: np.ndarray, tan_beta: np.ndarray, load_n: np.ndarray,
                 soil: SoilParams) -> tuple[np.ndarray, np.ndarray]:
        """Forces (fx_n, fy_n) [N] on arrays, from `scalar_kernel`; arguments as in `ForceModel`.

        Loads <= 0 give no force; `soil` may hold one array per field (a soil per element).
        """
        fx, fy, _ = forces_on_arrays(self.scalar_kernel, slip, tan_beta, load_n, soil)
        return fx, fy

    def resistance_n(self, load_n: np.ndarray, soil: SoilParams) -> np.ndarray:
        """Motion resistance gamma W^e + f_r W [N] (>= 0): Bekker compaction plus rolling.

        Parameters
        ----------
        load_n : ndarray, shape (n,)
            Normal loads W [N]; negative values count as 0.
        soil : SoilParams
            Soil under each wheel (floats or arrays of shape (n,)).
        """
        return forces_on_arrays(self.scalar_kernel, 0.0, 0.0, load_n, soil)[2]

    def with_geometry(self, geometry: ContactGeometry) -> _PatchModel:
        """The same law and options on another contact geometry (e.g. a castor's own wheel,
        whose Bekker compaction differs from the driven wheels')."""
        if not isinstance(geometry, ContactGeometry):
            raise TypeError(f"geometry must be a ContactGeometry, got {type(geometry).__name__}")
        model = copy.copy(self)
        model.geometry = geometry
        return model

    def scalar(self, slip: float, tan_beta: float, load_n: float,
               soil: SoilParams) -> tuple[float, float, float]:
        """``(fx_n, fy_n, resistance_n)`` of one wheel in floats (builds the kernel each call;
        bind it once with `scalar_kernel` where it is called often)."""
        return self.scalar_kernel(soil)(slip, tan_beta, load_n)

    def __repr__(self) -> str:
        aniso = (f", lateral_stiffness_ratio={self.lateral_stiffness_ratio!r}"
                 if self.lateral_stiffness_ratio != 1.0 else "")
        if self.slip_sinkage is not None:
            aniso += (f", slip_sinkage={self.slip_sinkage!r}, "
                      f"soil_unit_weight_n_m3={self.soil_unit_weight_n_m3!r}")
        if self.slip_sinkage == "accumulated":
            aniso += f", excavation_depth_m={self.excavation_depth_m!r}"
        return (f"{type(self).__name__}({self.geometry!r}, "
                f"rolling_resistance_coeff={self.rolling_resistance_coeff!r}{aniso})")


class JanosiForceModel(_PatchModel):
    """Janosi-Hanamoto shear integrated over the patch, with combined slip by direction.

    The law is `janosi.janosi_forces`: isotropic Janosi-Hanamoto shear (Lindgren Eq. 2) with
    the Mohr-Coulomb limit (Eq. 3) integrated over the patch gives the resultant
    F(sigma) = F_max g(sigma L/K), g the Okello bracket (Eq. 18-20), directed against the slip
    velocity, sigma = sqrt(s^2 + tan^2 beta) the combined slip of Reina Eq. 7:

        fx = F (s/sigma),   fy = -F (tan_beta/sigma),   F_max = A c + W tan phi.

    Why by direction: the soil has one shear strength, not one per axis, so the resultant can
    never exceed the Mohr-Coulomb limit F_max, lateral slip costs traction as in Reina's
    friction ellipse (Eq. 11), and pure longitudinal slip reduces exactly to Okello's curve.
    L is the shear length (`ContactGeometry.shear_length_m`). No contact (W <= 0), no force.

    Slip angle: the sliding-velocity convention (``slip_angle_convention = "sliding"``). The
    shear displacement of Lindgren Eq. 2 at x along the patch is the sliding velocity
    (r omega - v, v_lat) times the time x/(r omega) the rim point has been in contact (Wong,
    Theory of Ground Vehicles, Ch. 5: j = i x), so the law's (s, tan_beta) is that velocity
    over r omega in drive: tan_beta = v_lat/(r omega) = (1 - s) v_lat/v_x, and the split by
    direction is along the sliding velocity. Reina's tan(beta) = v_lat/v_x (Reina Eq. 4) would
    overstate the lateral displacement by 1/(1 - s).

    Parameters
    ----------
    geometry : ContactGeometry
        Contact geometry, the same for all wheels the model is called with.
    rolling_resistance_coeff : float
        f_r [-] of the rolling resistance f_r W of the tyre itself (hysteresis), present on
        every surface including rigid ground; default 0.01, a tyre on concrete (Wong, Ch. 1:
        0.01-0.015). `resistance_n` adds Bekker compaction on deformable soil.
    lateral_stiffness_ratio : float
        kappa [-], > 0: the soil's lateral small-slip stiffness over its longitudinal one
        (`janosi.janosi_forces`, lateral anisotropy; Reina measured C_y/C_x = 3.6 on loose
        soil, Reina Table 3). Default 1, isotropic: no slipenv soil has a measured value.
    slip_sinkage : None | "bulldozing" | "full" | "accumulated"
        Resistance added by slip (`SLIP_SINKAGE_MODES`): None (default) the resistance at the
        static sinkage only; ``"bulldozing"`` the soil a slipping or skidding wheel digs out
        below its static rut (Lyasko's slip sinkage, instantaneous in slip:
        `slip_sinkage_resistance`) is bulldozed ahead of its front (Bekker); ``"full"`` also
        the Bekker compaction at the slip sinkage; ``"accumulated"`` the depth dug is a state
        of each wheel in the simulation, growing with the distance slid and relaxing over the
        distance rolled (`dug_depth_step`), bulldozed ahead of the front
        (`dug_depth_resistance`; the kernel itself has no memory and adds nothing). Rigid
        wheels only (a track's contact raises ValueError); the state runs for slipenv's own
        laws (a subclass's Python kernel gets none). Measured, rover and Husky on loose
        sand, 10 s at full command: ``"bulldozing"`` stalls them on 10 deg slopes they climb
        without it at slip 0.44-0.60 (the Husky on the flat too: the launch at slip 0.7-0.9
        digs it in), ``"full"`` stalls every wheeled vehicle on the flat;
        ``"accumulated"`` moves their speed by at most 0.2 % on the flat and 0.7-6.6 % on
        10 deg (the Husky's slip 0.60 -> 0.63), and stops the rover commanded up 20 deg, or
        braked on 20-25 deg, after it has slid 0.35-1.0 m.
    soil_unit_weight_n_m3 : float
        gamma_s [N/m^3] >= 0 of the bulldozing term; default `DEFAULT_UNIT_WEIGHT_N_M3`.
    excavation_depth_m : float
        delta [m] >= 0 of the ``"accumulated"`` state, the depth dug per patch length slid;
        default `DEFAULT_EXCAVATION_DEPTH_M`.
    """

    _COMPILED_KIND = 0

    def _forces(self, soil: SoilParams) -> Callable[[float, float, float], tuple[float, float]]:
        return self._shear_law_forces(soil, _laws.janosi_forces)


class LinearSlipForceModel(_PatchModel):
    """Lindgren's linear slip law, F_x = (k_s/r) s, saturated at the Mohr-Coulomb limit.

    The law is `lindgren.linear_slip_forces`: k_s = T_max/(2B) (Lindgren Eq. 24) with
    T_max = r (A c + W tan phi) and B = K/L, the initial slope of the Janosi model, which it
    matches to 2 % while sigma L/K < 0.059 (Eq. 23). The lateral force uses the same stiffness
    on tan_beta, and the resultant is capped at F_max:

        (fx, fy) = (s, -tan_beta) F_max min(sigma/(2B), 1)/sigma.

    No contact (W <= 0), no force. Constructor arguments as in `JanosiForceModel`
    (``lateral_stiffness_ratio`` kappa scales tan_beta the same way).
    """

    _COMPILED_KIND = 1

    def _forces(self, soil: SoilParams) -> Callable[[float, float, float], tuple[float, float]]:
        # lateral anisotropy as in `JanosiForceModel`: tan_beta -> kappa tan_beta
        return self._shear_law_forces(soil, _laws.linear_slip_forces)


class ReinaForceModel(_PatchModel):
    """Reina's combined longitudinal/lateral model (Reina Eq. 5-9), mu/C/A from the soil.

    The law is `reina.reina_forces`. Reina fitted Eq. 5 to the force the test bed's sensor
    measured at the carriage (Reina §3): the *net* (drawbar) force, with the wheel's motion
    resistance already inside it. So by default this model adds no Bekker compaction: its
    resistance is only the rolling term f_r W (`rolling_resistance_coeff`, bearing and
    hysteresis losses of the vehicle that the test bed's carriage did not see; 0 gives the
    strictly net law). Adding compaction on top of the net law counts the rut twice (audit in
    physics-notes §1, defect 1: 46 % slip on flat ground instead of about 1 %).

    Parameters
    ----------
    geometry : ContactGeometry
        Used only for the optional compaction (Reina's model has no geometry).
    rolling_resistance_coeff : float
        f_r [-] as in `JanosiForceModel`; default 0.01.
    scale_stiffness_with_load : bool
        Reina's C_x, C_y [N] were fitted on one wheel at one load, W_ref
        (`SoilParams.reference_load_n`, 6.6 kg). If True (default) they are scaled by W/W_ref,
        so the traction coefficient F/W is a function of slip alone and a soil fitted on a
        light rover wheel carries over to heavier vehicles; at W = W_ref this is Reina's
        model exactly. If False, C_x and C_y are used as given (Reina Eq. 5-6 verbatim).
    compaction : bool
        If True (opt-in), add the Bekker compaction resistance R_c = gamma W^e (`bekker`) as a
        separate term and use Reina's curve as *gross* thrust: the thrust becomes
        F_x + R_c (1 - e^{-y}) s/sigma, y = C_x sigma/(mu W) (Eq. 5's own saturation shape,
        i.e. mu raised to mu + R_c/W), so that thrust minus R_c gives back the measured net
        curve at high slip and -R_c (a freely rolling wheel cutting a rut) at zero slip.
        The lateral force stays Eq. 6-9.
    slip_sinkage, soil_unit_weight_n_m3, excavation_depth_m
        As in `JanosiForceModel`. Reina's curve is a measured net force, which holds the
        slip sinkage over the slips it was measured at; the instantaneous modes add it again
        there, and are meant for the slips beyond (a wheel spinning or locked on a slope);
        ``"accumulated"`` adds a few millimetres at those slips (delta s/(1 - s)) and digs
        without bound only where the wheel stops rolling.

    Notes
    -----
    Evaluated as fx = s k_x(sigma), fy = -tan_beta k_y(sigma) (see `reina`), k floored at 0.
    Its slip angle is Reina's, tan_beta = v_lat/v_x (Reina Eq. 4; ``slip_angle_convention =
    "reina"``), the convention Table 3 was fitted in; the simulation relaxes the lateral slip
    state to it (`slip_dynamics.relax_slip` with ``forward_reference``), so in drive the law
    is not fed the sliding-velocity tan_beta = (1 - s) v_lat/v_x of the shear laws.
    With scaling, F = W F_1(s, tan_beta), F_1 Reina's law at unit load with C/W_ref. Zero
    load gives zero force either way.
    """

    def __init__(self, geometry: ContactGeometry, rolling_resistance_coeff: float = 0.01,
                 scale_stiffness_with_load: bool = True, compaction: bool = False,
                 slip_sinkage: str | None = WHEEL_SLIP_SINKAGE,
                 soil_unit_weight_n_m3: float = DEFAULT_UNIT_WEIGHT_N_M3,
                 excavation_depth_m: float = DEFAULT_EXCAVATION_DEPTH_M) -> None:
        super().__init__(geometry, rolling_resistance_coeff, slip_sinkage=slip_sinkage,
                         soil_unit_weight_n_m3=soil_unit_weight_n_m3,
                         excavation_depth_m=excavation_depth_m)
        self.scale_stiffness_with_load = bool(scale_stiffness_with_load)
        self.compaction = bool(compaction)

    _COMPILED_KIND = 2
    slip_angle_convention = "reina"

    def _reina_constants(self, soil: SoilParams) -> tuple[float, float, float, float, float]:
        """(mu, C_x, C_y, A_x, A_y) of Eq. 5-9 as the law uses them: with load scaling,
        C = c W/W_ref makes F proportional to W at a given slip, so the law is W times the law
        at W = 1 with C/W_ref."""
        mu, c_x, c_y = float(soil.mu), float(soil.c_x_n), float(soil.c_y_n)
        if self.scale_stiffness_with_load:
            w_ref = float(soil.reference_load_n)
            c_x, c_y = c_x / w_ref, c_y / w_ref
        return mu, c_x, c_y, float(soil.a_x), float(soil.a_y)

    def kernel_constants(self, soil: SoilParams) -> KernelConstants | None:
        """As `_PatchModel.kernel_constants`, for Reina's law (and its gross thrust)."""
        if type(self) is not ReinaForceModel:
            return None
        mu, c_x, c_y, a_x, a_y = self._reina_constants(soil)
        scaled = self.scale_stiffness_with_load
        gamma, exponent = self._compaction(soil)
        return KernelConstants(self._COMPILED_KIND, 0.0, 0.0, 0.0, 1.0, mu, c_x, c_y, a_x, a_y,
                               scaled, self.compaction, float(soil.c_x_n),
                               float(soil.reference_load_n) if scaled else 0.0,
                               self.rolling_resistance_coeff, gamma, exponent,
                               **self._slip_sinkage_constants(soil))

    def _forces(self, soil: SoilParams) -> Callable[[float, float, float], tuple[float, float]]:
        mu, c_x, c_y, a_x, a_y = self._reina_constants(soil)
        law = _laws.reina_forces
        if not self.scale_stiffness_with_load:
            def verbatim(slip: float, tan_beta: float, load_n: float) -> tuple[float, float]:
                return law(slip, tan_beta, load_n, mu, c_x, c_y, a_x, a_y)
            return verbatim

        def scaled(slip: float, tan_beta: float, load_n: float) -> tuple[float, float]:
            fx, fy = law(slip, tan_beta, 1.0, mu, c_x, c_y, a_x, a_y)
            return fx * load_n, fy * load_n
        return scaled

    def _compaction(self, soil: SoilParams) -> tuple[float, float]:
        """(gamma, e) of the compaction term: (0, 1) unless ``compaction`` was asked for."""
        return super()._compaction(soil) if self.compaction else (0.0, 1.0)

    def scalar_kernel(self, soil: SoilParams) -> Kernel:
        """As `_PatchModel.scalar_kernel`; with ``compaction`` the thrust is the gross one."""
        kernel = super().scalar_kernel(soil)
        if not self.compaction or isinstance(kernel, _laws.Kernel):
            return kernel
        gamma, exponent = self._compaction(soil)
        mu, c_x = float(soil.mu), float(soil.c_x_n)
        # y = C_x sigma/(mu W); with load scaling C_x = c_x W/W_ref, so W cancels.
        w_ref = float(soil.reference_load_n) if self.scale_stiffness_with_load else None
        extra = _laws.reina_gross_extra_n

        def gross(slip: float, tan_beta: float, load_n: float) -> tuple[float, float, float]:
            fx, fy, res = kernel(slip, tan_beta, load_n)
            w_y = w_ref if w_ref is not None else load_n
            return fx + extra(slip, tan_beta, load_n, gamma, exponent, c_x, mu, w_y), fy, res
        return gross

    def __repr__(self) -> str:
        return (f"{super().__repr__()[:-1]}, "
                f"scale_stiffness_with_load={self.scale_stiffness_with_load!r}, "
                f"compaction={self.compaction!r})")


# The classes whose law is the C one of `kernel_constants` (a subclass may change the law).
_COMPILED_MODELS = (JanosiForceModel, LinearSlipForceModel)

FORCE_MODELS: Mapping[str, Callable[..., ForceModel]] = MappingProxyType({
    "janosi": JanosiForceModel,
    "linear": LinearSlipForceModel,
    "reina": ReinaForceModel,
})
"""Force model classes by name."""


def force_model_by_name(name: str, geometry: ContactGeometry, **options: Any) -> ForceModel:
    """Build the force model called `name` ("janosi", "linear" or "reina") for `geometry`.

    Extra keyword `options` go to the class (e.g. ``rolling_resistance_coeff``).

    Raises
    ------
    ValueError
        If `name` is unknown; the message names it and lists the known names.
    """
    try:
        cls = FORCE_MODELS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown force model {name!r}; known models: "
                         f"{', '.join(sorted(FORCE_MODELS))}") from None
    return cls(geometry, **options)
