"""Force models: the injection contract the simulation calls every physics substep.

A force model is built once per wheel set with the wheels' `ContactGeometry` and then called as
``model(slip, tan_beta, load_n, soil) -> (fx_n, fy_n)`` and ``model.resistance_n(load_n, soil)``
with arrays of shape (n_wheels,) (the slip/sign convention is in `contact`). The soil is a
`SoilParams` of floats (uniform soil) or of arrays of shape (n,) (a soil map). Constants derived
from the soil are cached by the identity of the `SoilParams` object, so a uniform soil costs
nothing per call; a soil map producing a new tuple each call pays for one re-derivation.

The per-call arithmetic is written out here, in as few numpy calls as possible, because this is
the hot path; the plain functions it restates (`janosi`, `reina`, `bekker`) are the reference,
and the tests hold the classes to them to 1e-12.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import Any, Protocol, runtime_checkable

import numpy as np

from slipenv.terramechanics.bekker import track_compaction_law, wheel_compaction_law
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.janosi import okello_secant
from slipenv.terramechanics.soil import SoilParams

__all__ = ["ForceModel", "JanosiForceModel", "LinearSlipForceModel", "ReinaForceModel",
           "FORCE_MODELS", "force_model_by_name"]

_X_SMALL = 1e-5  # [-] as `janosi.okello_secant`: below it h(x) uses its series
_SIXTH = 1.0 / 6.0
_ZERO = np.asarray(0.0)
_ONE = np.asarray(1.0)
_NEG_TINY = np.asarray(-1e-300)
_TINY_LOAD_N = np.asarray(1e-12)  # [N] floor of W where Reina's paper form divides by it
_UNIFORM_CACHE_SIZE = 32  # single soils whose derived constants a model keeps


@runtime_checkable
class ForceModel(Protocol):
    """What the simulation injects at each contact (convention: `slipenv.terramechanics.contact`).

    ``__call__(slip, tan_beta, load_n, soil)`` returns ``(fx_n, fy_n)`` of shape (n,) in the
    wheel's heading frame: fx > 0 pushes forward; fy opposes lateral sliding,
    sign(fy) = -sign(tan_beta). ``resistance_n(load_n, soil)`` returns the magnitude (>= 0) of
    the motion resistance (compaction + rolling), applied against the direction of travel.
    """

    def __call__(self, slip: np.ndarray, tan_beta: np.ndarray, load_n: np.ndarray,
                 soil: SoilParams) -> tuple[np.ndarray, np.ndarray]: ...

    def resistance_n(self, load_n: np.ndarray, soil: SoilParams) -> np.ndarray: ...


class _PatchModel(ABC):
    """Soil-constant cache and Bekker + rolling resistance shared by the concrete models.

    Constructor arguments as documented on `JanosiForceModel`.
    """

    def __init__(self, geometry: ContactGeometry, rolling_resistance_coeff: float = 0.01) -> None:
        if not isinstance(geometry, ContactGeometry):
            raise TypeError(f"geometry must be a ContactGeometry, got {type(geometry).__name__}")
        coeff = float(rolling_resistance_coeff)
        if not (math.isfinite(coeff) and coeff >= 0.0):
            raise ValueError(f"rolling_resistance_coeff={rolling_resistance_coeff!r} must be "
                             "finite and >= 0")
        self.geometry = geometry
        self.rolling_resistance_coeff = coeff
        self._f_r = np.asarray(coeff)
        self._soil: SoilParams | None = None
        self._k: tuple[np.ndarray, ...] = ()
        self._gamma = _ZERO
        self._exponent = _ONE
        self._rigid = True
        self._uniform: dict[int, tuple[Any, ...]] = {}
        self._scalar_cache: dict[int, tuple[Any, ...]] = {}

    def _use(self, soil: SoilParams) -> None:
        """Switch to `soil`'s constants (called only when the soil object changes).

        Constants of single soils (float fields) stay in a small table keyed by object identity,
        so a vehicle moving between a few uniform soils never re-derives them; soils with array
        fields (a blend from a soil map, new each call) are derived afresh.
        """
        entry = self._uniform.get(id(soil))
        if entry is None or entry[0] is not soil:
            entry = (soil, *self._all_constants(soil))
            if isinstance(soil.cohesion_pa, float) and len(self._uniform) < _UNIFORM_CACHE_SIZE:
                self._uniform[id(soil)] = entry
        self._soil, self._gamma, self._exponent, self._rigid, self._k = entry

    def _all_constants(self, soil: SoilParams) -> tuple[Any, ...]:
        """(gamma, e, rigid, force-law constants) of `soil` for this geometry."""
        g = self.geometry
        if g.is_track:
            gamma, exponent = track_compaction_law(g.width_m, g.contact_length_m, soil.k_c,
                                                   soil.k_phi, soil.n_exp, soil.deformable)
            gamma = gamma * g.rut_share
        else:
            gamma, exponent = wheel_compaction_law(g.width_m, 2.0 * g.radius_m, soil.k_c,
                                                   soil.k_phi, soil.n_exp, soil.deformable)
        gamma = np.asarray(gamma)
        return gamma, np.asarray(exponent), not np.any(gamma), self._derive(soil)

    @abstractmethod
    def _derive(self, soil: SoilParams) -> tuple[np.ndarray, ...]:
        """Soil constants the subclass's force law needs, as numpy arrays (0-d or (n,))."""

    def _mohr_coulomb(self, soil: SoilParams) -> tuple[np.ndarray, np.ndarray]:
        """(A c, tan phi): the terms of F_max = A c + W tan phi (Lindgren Eq. 3)."""
        return (np.asarray(self.geometry.area_m2 * np.asarray(soil.cohesion_pa, dtype=float)),
                np.asarray(np.tan(soil.friction_angle_rad), dtype=float))

    def resistance_n(self, load_n: np.ndarray, soil: SoilParams) -> np.ndarray:
        """Motion resistance gamma W^e + f_r W [N] (>= 0): Bekker compaction plus rolling.

        Parameters
        ----------
        load_n : ndarray, shape (n,)
            Normal loads W [N]; negative values count as 0.
        soil : SoilParams
            Soil under each wheel (floats or arrays of shape (n,)).
        """
        if soil is not self._soil:
            self._use(soil)
        w = np.maximum(load_n, _ZERO)
        if self._rigid:
            return self._f_r * w
        return self._gamma * w ** self._exponent + self._f_r * w

    def scalar_kernel(self, soil: SoilParams) -> Callable[[float, float, float],
                                                          tuple[float, float, float]]:
        """A per-wheel float function ``(slip, tan_beta, load_n) -> (fx, fy, resistance)``.

        The same law as `__call__` and `resistance_n` (the tests hold them together to 1e-12)
        with the soil's constants bound once, restated with `math` because numpy's per-call
        overhead on one wheel costs more than the physics step (DESIGN §6). The simulation
        builds one kernel per wheel per control step. ``soil`` must have float fields; the
        kernel expects ``load_n`` > 0.
        """
        gamma, exponent, rigid, k = self._all_constants(soil)
        gamma, exponent, k = float(gamma), float(exponent), tuple(float(v) for v in k)
        forces, f_r = self._scalar_forces, self.rolling_resistance_coeff

        if rigid:
            def kernel(slip: float, tan_beta: float, load_n: float):
                fx, fy = forces(slip, tan_beta, load_n, k)
                return fx, fy, f_r * load_n
        else:
            def kernel(slip: float, tan_beta: float, load_n: float):
                fx, fy = forces(slip, tan_beta, load_n, k)
                return fx, fy, f_r * load_n + gamma * load_n ** exponent
        return kernel

    def scalar(self, slip: float, tan_beta: float, load_n: float,
               soil: SoilParams) -> tuple[float, float, float]:
        """``(fx_n, fy_n, resistance_n)`` of one wheel in plain floats (see `scalar_kernel`)."""
        entry = self._scalar_cache.get(id(soil))
        if entry is None or entry[0] is not soil:
            if len(self._scalar_cache) >= _UNIFORM_CACHE_SIZE:
                self._scalar_cache.clear()
            entry = (soil, self.scalar_kernel(soil))
            self._scalar_cache[id(soil)] = entry
        return entry[1](slip, tan_beta, load_n)

    @abstractmethod
    def _scalar_forces(self, slip: float, tan_beta: float, load_n: float,
                       k: tuple[float, ...]) -> tuple[float, float]:
        """The force law of `__call__` for one wheel, constants ``k`` from `_derive`."""

    def __repr__(self) -> str:
        return (f"{type(self).__name__}({self.geometry!r}, "
                f"rolling_resistance_coeff={self.rolling_resistance_coeff!r})")


class JanosiForceModel(_PatchModel):
    """Janosi-Hanamoto shear integrated over the patch, with combined slip by direction.

    The soil under the patch is sheared along the direction of the slip velocity, so the shear
    displacement at distance x behind the front edge is x (s, tan_beta) and its magnitude is
    x sigma with sigma = sqrt(s^2 + tan^2 beta) (the combined slip of Reina Eq. 7). Isotropic
    Janosi-Hanamoto shear (Lindgren Eq. 2) with the Mohr-Coulomb limit (Eq. 3), integrated
    over the patch, gives the resultant F(sigma) = F_max g(sigma L/K), g the Okello bracket
    (Eq. 18-20), directed against the slip velocity:

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
    """

    def _derive(self, soil: SoilParams) -> tuple[np.ndarray, ...]:
        ac, tan_phi = self._mohr_coulomb(soil)
        inv_b = np.asarray(self.geometry.shear_length_m / np.asarray(soil.shear_modulus_m,
                                                                     dtype=float))
        return ac, tan_phi, inv_b

    def __call__(self, slip: np.ndarray, tan_beta: np.ndarray, load_n: np.ndarray,
                 soil: SoilParams) -> tuple[np.ndarray, np.ndarray]:
        """Forces (fx_n, fy_n) [N], shape (n,); arguments as in `ForceModel`."""
        if soil is not self._soil:
            self._use(soil)
        ac, tan_phi, inv_b = self._k
        w = np.maximum(load_n, _ZERO)
        f_max = (w * tan_phi + ac) * np.sign(w)
        x = np.hypot(slip, tan_beta) * inv_b
        secant = f_max * okello_secant(x) * inv_b  # F/sigma [N per unit slip]
        fy = secant * tan_beta
        np.negative(fy, out=fy)
        return secant * slip, fy

    def _scalar_forces(self, slip, tan_beta, load_n, k):
        ac, tan_phi, inv_b = k
        f_max = load_n * tan_phi + ac
        x = math.hypot(slip, tan_beta) * inv_b
        xc = x if x > _X_SMALL else _X_SMALL
        h = (math.expm1(-xc) + xc) / (xc * xc) + (xc - x) * _SIXTH  # okello_secant
        secant = f_max * h * inv_b
        return secant * slip, -secant * tan_beta


class LinearSlipForceModel(_PatchModel):
    """Lindgren's linear slip law, F_x = (k_s/r) s, saturated at the Mohr-Coulomb limit.

    k_s = T_max/(2B) (Lindgren Eq. 24) with T_max = r (A c + W tan phi) and B = K/L, so the
    force stiffness is k_s/r = F_max L/(2K): the initial slope of the Janosi model, which it
    matches to 2 % while sigma L/K < 0.059 (Eq. 23: relative error ~ s/(3B)). The lateral
    force uses the same stiffness on tan_beta, and the resultant is capped at F_max:

        (fx, fy) = (s, -tan_beta) F_max min(sigma/(2B), 1)/sigma.

    No contact (W <= 0), no force. Constructor arguments as in `JanosiForceModel`.
    """

    def _derive(self, soil: SoilParams) -> tuple[np.ndarray, ...]:
        ac, tan_phi = self._mohr_coulomb(soil)
        half_inv_b = np.asarray(0.5 * self.geometry.shear_length_m
                                / np.asarray(soil.shear_modulus_m, dtype=float))
        return ac, tan_phi, half_inv_b

    def __call__(self, slip: np.ndarray, tan_beta: np.ndarray, load_n: np.ndarray,
                 soil: SoilParams) -> tuple[np.ndarray, np.ndarray]:
        """Forces (fx_n, fy_n) [N], shape (n,); arguments as in `ForceModel`."""
        if soil is not self._soil:
            self._use(soil)
        ac, tan_phi, half_inv_b = self._k
        w = np.maximum(load_n, _ZERO)
        f_max = (w * tan_phi + ac) * np.sign(w)
        excess = np.maximum(np.hypot(slip, tan_beta) * half_inv_b, _ONE)
        secant = f_max * half_inv_b / excess  # F/sigma [N per unit slip]
        fy = secant * tan_beta
        np.negative(fy, out=fy)
        return secant * slip, fy

    def _scalar_forces(self, slip, tan_beta, load_n, k):
        ac, tan_phi, half_inv_b = k
        excess = math.hypot(slip, tan_beta) * half_inv_b
        secant = (load_n * tan_phi + ac) * half_inv_b / (excess if excess > 1.0 else 1.0)
        return secant * slip, -secant * tan_beta


class ReinaForceModel(_PatchModel):
    """Reina's combined longitudinal/lateral model (Reina Eq. 5-9), mu/C/A from the soil.

    Parameters
    ----------
    geometry : ContactGeometry
        Used only for the resistance (Reina's model has no geometry).
    rolling_resistance_coeff : float
        As in `JanosiForceModel`.
    scale_stiffness_with_load : bool
        Reina's C_x, C_y [N] were fitted on one wheel at one load, W_ref
        (`SoilParams.reference_load_n`, 6.6 kg). If True (default) they are scaled by W/W_ref,
        so the traction coefficient F/W is a function of slip alone and a soil fitted on a
        light rover wheel carries over to heavier vehicles; at W = W_ref this is Reina's
        model exactly. If False, C_x and C_y are used as given (Reina Eq. 5-6 verbatim).

    Notes
    -----
    Evaluated as fx = s k_x(sigma), fy = -tan_beta k_y(sigma) (see `reina`), k floored at 0.
    With scaling, zero load gives exactly zero force; without, the floor W >= 1e-12 N leaves
    at most mu 1e-12 N.
    """

    def __init__(self, geometry: ContactGeometry, rolling_resistance_coeff: float = 0.01,
                 scale_stiffness_with_load: bool = True) -> None:
        super().__init__(geometry, rolling_resistance_coeff)
        self.scale_stiffness_with_load = bool(scale_stiffness_with_load)

    def _derive(self, soil: SoilParams) -> tuple[np.ndarray, ...]:
        mu = np.asarray(soil.mu, dtype=float)
        c_x = np.asarray(soil.c_x_n, dtype=float)
        c_y = np.asarray(soil.c_y_n, dtype=float)
        # per unit load if scaled (k = W (c/W_ref p - A)), absolute otherwise (k = C p - W A)
        per = np.asarray(soil.reference_load_n, dtype=float) if self.scale_stiffness_with_load \
            else _ONE
        return (np.asarray(-c_x / (mu * per)), np.asarray(c_x / per), np.asarray(soil.a_x),
                np.asarray(-c_y / (mu * per)), np.asarray(-c_y / per), np.asarray(soil.a_y))

    def __call__(self, slip: np.ndarray, tan_beta: np.ndarray, load_n: np.ndarray,
                 soil: SoilParams) -> tuple[np.ndarray, np.ndarray]:
        """Forces (fx_n, fy_n) [N], shape (n,); arguments as in `ForceModel`."""
        if soil is not self._soil:
            self._use(soil)
        nkx, cx, ax, nky, ncy, ay = self._k
        sigma = np.hypot(slip, tan_beta)
        if self.scale_stiffness_with_load:
            w = np.maximum(load_n, _ZERO)
            ny = np.minimum(sigma * nkx, _NEG_TINY)  # -y_x = -C_x sigma/(mu W_ref)
            kx = np.maximum(cx * np.expm1(ny) / ny - ax, _ZERO)  # k_x/W
            ny = np.minimum(sigma * nky, _NEG_TINY)
            nk_y = np.minimum(ncy * np.expm1(ny) / ny + ay, _ZERO)  # -k_y/W
            return slip * kx * w, tan_beta * nk_y * w
        w = np.maximum(load_n, _TINY_LOAD_N)
        sigma /= w
        ny = np.minimum(sigma * nkx, _NEG_TINY)  # -y_x = -C_x sigma/(mu W)
        kx = np.maximum(cx * np.expm1(ny) / ny - w * ax, _ZERO)
        ny = np.minimum(sigma * nky, _NEG_TINY)
        nk_y = np.minimum(ncy * np.expm1(ny) / ny + w * ay, _ZERO)
        return slip * kx, tan_beta * nk_y

    def _scalar_forces(self, slip, tan_beta, load_n, k):
        nkx, cx, ax, nky, ncy, ay = k
        sigma = math.hypot(slip, tan_beta)
        if self.scale_stiffness_with_load:
            w = load_n
        else:
            w = load_n if load_n > 1e-12 else 1e-12
            sigma /= w
        ny = min(sigma * nkx, -1e-300)
        kx = max(cx * math.expm1(ny) / ny - (ax if self.scale_stiffness_with_load else w * ax),
                 0.0)
        ny = min(sigma * nky, -1e-300)
        nk_y = min(ncy * math.expm1(ny) / ny + (ay if self.scale_stiffness_with_load
                                                else w * ay), 0.0)
        if self.scale_stiffness_with_load:
            return slip * kx * w, tan_beta * nk_y * w
        return slip * kx, tan_beta * nk_y

    def __repr__(self) -> str:
        return (f"{super().__repr__()[:-1]}, "
                f"scale_stiffness_with_load={self.scale_stiffness_with_load!r})")


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
