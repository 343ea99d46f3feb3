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

__all__ = ["ForceModel", "JanosiForceModel", "KernelConstants", "LinearSlipForceModel",
           "ReinaForceModel", "FORCE_MODELS", "force_model_by_name", "wheel_kernel"]


@runtime_checkable
class ForceModel(Protocol):
    """What the simulation injects at each contact (convention: `slipenv.terramechanics.contact`).

    ``__call__(slip, tan_beta, load_n, soil)`` returns ``(fx_n, fy_n)`` of shape (n,) in the
    wheel's heading frame: fx > 0 pushes forward; fy opposes lateral sliding,
    sign(fy) = -sign(tan_beta). ``resistance_n(load_n, soil)`` returns the magnitude (>= 0) of
    the motion resistance (compaction + rolling), applied against the direction of travel.
    A model may also offer ``scalar_kernel(soil)`` (see `wheel_kernel`), the fast path.
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


class _PatchModel(ABC):
    """Kernel assembly, Bekker + rolling resistance and the derived array interface.

    A subclass binds its force law to a soil's constants (`_forces`, `kernel_constants`).
    Constructor arguments as documented on `JanosiForceModel`.
    """

    def __init__(self, geometry: ContactGeometry, rolling_resistance_coeff: float = 0.01,
                 lateral_stiffness_ratio: float = 1.0) -> None:
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
        self.geometry = geometry
        self.rolling_resistance_coeff = coeff
        self.lateral_stiffness_ratio = ratio

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
                               False, 0.0, 0.0, self.rolling_resistance_coeff, gamma, exponent)

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

        def kernel(slip: float, tan_beta: float, load_n: float) -> tuple[float, float, float]:
            fx, fy = forces(slip, tan_beta, load_n)
            return fx, fy, resistance(load_n, f_r, gamma, exponent)
        return kernel

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

    Notes
    -----
    Evaluated as fx = s k_x(sigma), fy = -tan_beta k_y(sigma) (see `reina`), k floored at 0.
    With scaling, F = W F_1(s, tan_beta), F_1 Reina's law at unit load with C/W_ref. Zero
    load gives zero force either way.
    """

    def __init__(self, geometry: ContactGeometry, rolling_resistance_coeff: float = 0.01,
                 scale_stiffness_with_load: bool = True, compaction: bool = False) -> None:
        super().__init__(geometry, rolling_resistance_coeff)
        self.scale_stiffness_with_load = bool(scale_stiffness_with_load)
        self.compaction = bool(compaction)

    _COMPILED_KIND = 2

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
                               self.rolling_resistance_coeff, gamma, exponent)

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
