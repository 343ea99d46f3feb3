"""Fit slipenv's force laws to test-bed measurements; compare them on held-out trials.

Each law is evaluated through slipenv's own force model (`slipenv.terramechanics.models`) with
a soil whose fitted fields are replaced, so a fitted soil reproduces the measurements in the
simulation: the prediction of the carriage force is the model's F_x minus its motion
resistance (the test bed measures the net force, Reina §3) and its F_y. Fields the data cannot
identify (Bekker constants, rolling radius) stay those of a base soil.

Laws and fitted fields:

* ``reina`` (Reina Eq. 5-9): mu, c_x_n, c_y_n, a_x, a_y, at reference_load_n = the median load;
* ``janosi`` (Janosi-Hanamoto integrated over the patch, Okello Eq. 18-20) and ``linear``
  (Lindgren Eq. 24): cohesion_pa, friction_angle_rad, shear_modulus_m; with loads within 20 %
  of each other c and tan(phi) enter only as A c + W tan(phi), so cohesion is held at the base
  soil's value and only phi and K are fitted.

Least squares (scipy ``least_squares``, trust-region reflective, bounds) on the F_x and F_y
residuals in newtons; standard errors from the Jacobian, cov = (J^T J)^-1 RSS/(m - p).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import least_squares

from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import force_model_by_name
from slipenv.terramechanics.soil import Soil
from slipenv.testbed.csv_format import TestBedData

__all__ = ["LAWS", "LawFit", "fit_law", "heldout_rmse", "predict"]

LAWS = ("janosi", "reina", "linear")
_BOUNDS = {"mu": (1e-3, 3.0), "c_x_n": (1e-3, 1e5), "c_y_n": (1e-3, 1e5), "a_x": (0.0, 1.0),
           "a_y": (0.0, 1.0), "cohesion_pa": (0.0, 1e6), "friction_angle_rad": (1e-3, 1.5),
           "shear_modulus_m": (1e-4, 1.0)}


@dataclass(frozen=True)
class LawFit:
    """One law fitted to all trials.

    Attributes
    ----------
    law : str
        ``reina``, ``janosi`` or ``linear``.
    names : tuple of str
        Fitted soil fields.
    values, std_errors : ndarray
        Their estimates and standard errors (units of the `Soil` fields).
    soil : Soil
        The base soil with the fitted fields replaced.
    residual_fx_n, residual_fy_n : ndarray
        Measured minus predicted force per trial [N].
    """

    law: str
    names: tuple[str, ...]
    values: np.ndarray
    std_errors: np.ndarray
    soil: Soil
    residual_fx_n: np.ndarray
    residual_fy_n: np.ndarray

    def parameters(self) -> dict[str, list[float]]:
        """``{name: [value, standard_error]}``."""
        return {n: [float(v), float(e)] for n, v, e in zip(self.names, self.values,
                                                           self.std_errors, strict=True)}


def geometry_of(data: TestBedData) -> ContactGeometry:
    """The wheel's contact geometry from ``meta.json``."""
    m = data.meta
    return ContactGeometry(radius_m=float(m["wheel_radius_m"]), width_m=float(m["wheel_width_m"]),
                           contact_length_m=float(m["contact_length_m"]))


def fitted_names(law: str, data: TestBedData) -> tuple[str, ...]:
    """The soil fields `law` is fitted on for these data (see the module)."""
    if law == "reina":
        return ("mu", "c_x_n", "c_y_n", "a_x", "a_y")
    if law in ("janosi", "linear"):
        w = data.normal_load_n
        if np.ptp(w) > 0.2 * float(np.mean(w)):
            return ("cohesion_pa", "friction_angle_rad", "shear_modulus_m")
        return ("friction_angle_rad", "shear_modulus_m")
    raise ValueError(f"unknown law {law!r}; known: {', '.join(LAWS)}")


def _with(base: Soil, data: TestBedData, names, values) -> Soil:
    fields = dict(zip(names, (float(v) for v in values), strict=True))
    return replace(base, name=f"{base.name}_fitted",
                   reference_load_n=float(np.median(data.normal_load_n)), **fields)


def predict(law: str, soil: Soil, data: TestBedData, index=slice(None)):
    """Predicted carriage forces (fx_n, fy_n) [N] of `law` with `soil` for the trials `index`.

    F_x is the model's thrust minus its motion resistance (the net force the bed measures).
    """
    model = force_model_by_name(law, geometry_of(data))
    params = soil.params()
    s, tb, w = data.slip_ratio[index], data.tan_beta[index], data.normal_load_n[index]
    fx, fy = model(s, tb, w, params)
    return fx - model.resistance_n(w, params), fy


def _solve(law: str, base: Soil, data: TestBedData, index, names):
    x0 = np.array([float(getattr(base, n)) for n in names])
    lo = np.array([_BOUNDS[n][0] for n in names])
    hi = np.array([_BOUNDS[n][1] for n in names])
    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
    fx_m, fy_m = data.fx_n[index], data.fy_n[index]

    def residuals(x: np.ndarray) -> np.ndarray:
        fx, fy = predict(law, _with(base, data, names, x), data, index)
        return np.concatenate((fx - fx_m, fy - fy_m))

    return least_squares(residuals, x0, bounds=(lo, hi), x_scale="jac", method="trf",
                         xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=400)


def fit_law(law: str, data: TestBedData, base: Soil) -> LawFit:
    """Fit `law` to all trials of `data`; unfitted soil fields come from `base`.

    Raises
    ------
    ValueError
        If `law` is unknown, or there are no more trials than twice the parameters.
    """
    names = fitted_names(law, data)
    m, p = 2 * data.n, len(names)
    if m <= p:
        raise ValueError(f"{data.n} trials cannot fit the {p} parameters of law {law!r}")
    sol = _solve(law, base, data, slice(None), names)
    rss = float(sol.fun @ sol.fun)
    jac = np.asarray(sol.jac)
    cov = np.linalg.pinv(jac.T @ jac) * rss / (m - p)
    soil = _with(base, data, names, sol.x)
    fx, fy = predict(law, soil, data)
    return LawFit(law, names, sol.x.copy(), np.sqrt(np.maximum(np.diag(cov), 0.0)), soil,
                  data.fx_n - fx, data.fy_n - fy)


def heldout_rmse(law: str, data: TestBedData, base: Soil, folds: int = 5,
                 seed: int = 0) -> dict[str, float]:
    """k-fold cross-validated RMS error [N] of F_x and F_y, folds by trial (seeded shuffle).

    Each fold's trials are predicted by the law fitted on the others.
    """
    k = min(int(folds), data.n)
    if k < 2:
        raise ValueError(f"held-out comparison needs >= 2 trials, got {data.n}")
    names = fitted_names(law, data)
    order = np.random.default_rng(seed).permutation(data.n)
    err_x, err_y = np.empty(data.n), np.empty(data.n)
    for fold in np.array_split(order, k):
        train = np.setdiff1d(order, fold)
        sol = _solve(law, base, data, train, names)
        fx, fy = predict(law, _with(base, data, names, sol.x), data, fold)
        err_x[fold], err_y[fold] = data.fx_n[fold] - fx, data.fy_n[fold] - fy
    return {"fx": float(math.sqrt(np.mean(err_x ** 2))),
            "fy": float(math.sqrt(np.mean(err_y ** 2)))}
