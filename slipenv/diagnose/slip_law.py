"""A force law with scaled slip stiffnesses and shifted zero-force slips, for extended worlds.

The diagnosis carries slip effects into the PyBullet world by wrapping the world's force law
(``SlipEnvConfig.force_model``) in :class:`ScaledSlip`; the test generator hides effects the
same way.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np

from slipenv.terramechanics import wheel_kernel
from slipenv.terramechanics.models import ReinaForceModel, force_model_by_name


class ScaledSlipForceModel:
    """A force law with scaled slip stiffnesses and shifted zero-force slips.

    At small slip the longitudinal and side stiffnesses are ``long_scale`` and ``lat_scale``
    times the base law's; the wheel rolls free at slip s_x(β) = s_x0 + k_β max(|β| - β0, 0)
    (Reina Eq. 12) and drifts free at slip angle β_0. For Reina's law the stiffnesses C_x,
    C_y of the soil are scaled (the friction limit and the combined-slip coupling stay those
    of the real slips); the isotropic Janosi and linear laws have one stiffness, K, so their
    slip inputs are scaled instead: ``base((s - s_x) a_long, (tan β - tan β_0) a_lat)``.
    """

    def __init__(self, base, long_scale=1.0, lat_scale=1.0, lat_offset_rad=0.0,
                 s_x0=0.0, k_beta=0.0, beta0_rad=0.0) -> None:
        self.base = base
        self.long_scale, self.lat_scale = float(long_scale), float(lat_scale)
        self.tan_offset = math.tan(lat_offset_rad)
        self.s_x0, self.k_beta, self.beta0 = float(s_x0), float(k_beta), float(beta0_rad)
        self._reina = isinstance(innermost(base), ReinaForceModel)
        self._soils: dict[int, tuple] = {}

    def _soil(self, soil):
        if not self._reina:
            return soil
        hit = self._soils.get(id(soil))
        if hit is None or hit[0] is not soil:
            if len(self._soils) > 64:
                self._soils.clear()
            hit = (soil, soil._replace(c_x_n=soil.c_x_n * self.long_scale,
                                       c_y_n=soil.c_y_n * self.lat_scale))
            self._soils[id(soil)] = hit
        return hit[1]

    def _input_scales(self) -> tuple[float, float]:
        return (1.0, 1.0) if self._reina else (self.long_scale, self.lat_scale)

    def __call__(self, slip, tan_beta, load_n, soil):
        beta = np.abs(np.arctan(tan_beta))
        shift = self.s_x0 + self.k_beta * np.maximum(beta - self.beta0, 0.0)
        ls, la = self._input_scales()
        return self.base((np.asarray(slip) - shift) * ls,
                         (np.asarray(tan_beta) - self.tan_offset) * la, load_n, self._soil(soil))

    def resistance_n(self, load_n, soil):
        return self.base.resistance_n(load_n, soil)

    def scalar_kernel(self, soil):
        """Float kernel ``(slip, tan_beta, load) -> (fx, fy, resistance)`` (the hot path)."""
        inner = wheel_kernel(self.base, self._soil(soil))
        (ls, la), off = self._input_scales(), self.tan_offset
        sx0, kb, b0 = self.s_x0, self.k_beta, self.beta0

        def kernel(slip: float, tan_beta: float, load_n: float):
            shift = sx0 + kb * max(abs(math.atan(tan_beta)) - b0, 0.0) if (sx0 or kb) else 0.0
            return inner((slip - shift) * ls, (tan_beta - off) * la, load_n)

        return kernel


def innermost(model):
    """The force law under any :class:`ScaledSlipForceModel` wrappers."""
    while isinstance(model, ScaledSlipForceModel):
        model = model.base
    return model


@dataclasses.dataclass(frozen=True)
class ScaledSlip:
    """Force-model factory (``SlipEnvConfig.force_model``) wrapping ``base`` in the above.

    ``base`` is a force-law name, a model instance or a factory of the wheel's contact
    geometry; ``options`` are the keyword arguments of :class:`ScaledSlipForceModel`, sorted.
    """

    base: Any
    options: tuple[tuple[str, float], ...]

    def __call__(self, geometry):
        base = self.base
        if isinstance(base, str):
            base = force_model_by_name(base, geometry)
        elif not hasattr(base, "resistance_n"):
            base = base(geometry)
        return ScaledSlipForceModel(base, **dict(self.options))


def scaled(force_model: Any, **options: float) -> ScaledSlip:
    """``force_model`` wrapped in a :class:`ScaledSlip` with ``options`` (sorted by name)."""
    return ScaledSlip(force_model, tuple(sorted(options.items())))
