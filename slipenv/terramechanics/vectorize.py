"""Array versions of the scalar force laws, derived generically (each law is written once).

The force laws of this package are written once, as float functions of one wheel (in C,
``_laws.h``, bound by the Python API), because the simulation calls them per wheel and per
physics substep, where numpy's per-call overhead on one wheel costs more than the physics
(DESIGN §6). Analysis, tests and the diagnosis want them on arrays; this module derives those
array versions from the scalar functions instead of restating them:

* `array_law(law)`: any scalar function of floats, broadcast over numpy arrays;
* `forces_on_arrays(kernel_of, slip, tan_beta, load_n, soil)`: a per-wheel kernel
  ``(slip, tan_beta, load_n) -> (fx, fy, resistance)`` bound to a soil (`kernel_of(soil)`),
  evaluated element by element, with a soil of floats or of per-element arrays.

Both loop in Python (one scalar call per element), so they are for analysis, not the hot path.
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from slipenv.terramechanics.soil import SoilParams

__all__ = ["Kernel", "array_law", "forces_on_arrays"]

Kernel = Callable[[float, float, float], tuple[float, float, float]]
"""A force law bound to one soil: ``(slip, tan_beta, load_n) -> (fx_n, fy_n, resistance_n)``."""


def array_law(law: Callable[..., Any], n_out: int = 1, name: str | None = None,
              doc: str | None = None) -> Callable[..., Any]:
    """The scalar function `law` evaluated element-wise on broadcast numpy arrays.

    Parameters
    ----------
    law : callable
        A function of plain floats (fixed number of positional parameters) returning one float
        or a tuple of `n_out` floats.
    n_out : int
        Number of values `law` returns.
    name, doc : str, optional
        ``__name__`` and ``__doc__`` of the array version (default: those of `law`).

    Returns
    -------
    callable
        Takes array_like arguments as `law` does (by position or name) and returns a float
        ndarray of their broadcast shape (0-d for scalar arguments), or a tuple of `n_out`
        of them.
    """
    signature = inspect.signature(law)
    ufunc = np.frompyfunc(law, len(signature.parameters), n_out)

    def on_arrays(*args: ArrayLike, **kwargs: ArrayLike) -> Any:
        bound = signature.bind(*args, **kwargs)
        bound.apply_defaults()
        out = ufunc(*bound.args)
        if n_out == 1:
            return np.asarray(out, dtype=float)
        return tuple(np.asarray(o, dtype=float) for o in out)

    on_arrays.__name__ = on_arrays.__qualname__ = name or law.__name__
    on_arrays.__doc__ = doc if doc is not None else law.__doc__
    return on_arrays


def forces_on_arrays(kernel_of: Callable[[SoilParams], Kernel], slip: ArrayLike,
                     tan_beta: ArrayLike, load_n: ArrayLike,
                     soil: SoilParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(fx_n, fy_n, resistance_n)`` on arrays from a per-soil scalar kernel factory.

    Parameters
    ----------
    kernel_of : callable
        ``kernel_of(soil_of_floats) -> kernel``, e.g. a force model's ``scalar_kernel``.
    slip, tan_beta, load_n : array_like
        Broadcast together; loads below 0 count as 0 (no contact: no force, no resistance).
    soil : SoilParams
        Floats (one soil) or arrays broadcasting with the inputs (a soil per element); one
        kernel is built per distinct soil.

    Returns
    -------
    fx_n, fy_n, resistance_n : ndarray
        Float arrays of the broadcast shape.
    """
    load = np.maximum(np.asarray(load_n, dtype=float), 0.0)
    if not any(np.ndim(v) for v in soil):
        kernel = kernel_of(SoilParams(*(float(v) for v in soil)))
        out = np.frompyfunc(kernel, 3, 3)(slip, tan_beta, load)
    else:
        kernels: dict[tuple[float, ...], Kernel] = {}

        def per_element(s: float, tb: float, w: float, *fields: float) -> tuple[float, ...]:
            kernel = kernels.get(fields)
            if kernel is None:
                kernel = kernels[fields] = kernel_of(SoilParams(*fields))
            return kernel(s, tb, w)

        out = np.frompyfunc(per_element, 3 + len(soil), 3)(slip, tan_beta, load, *soil)
    fx, fy, res = (np.asarray(o, dtype=float) for o in out)
    return fx, fy, res
