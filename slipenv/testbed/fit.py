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
  soil's value and only phi and K are fitted;
* ``reina_sidewall``: Reina's law plus the side-wall bulldozing force of the sunken wheel
  against its lateral sliding (`slipenv.terramechanics.sidewall`, Ishigami et al. 2007), which
  friction does not bound: a side force above mu W. Fitted: Reina's five and the soil's unit
  weight gamma (cohesion and friction angle those of the base soil), at the trials' measured
  sinkage (``sinkage_m``), else the base soil's static Bekker sinkage. slipenv's simulation has
  no wheel side-wall force, so a soil from this law is never accepted for it.

The data's slip angle is in the ``slip_angle_definition`` of ``meta.json``: ``reina``, tan beta
= v_lat/v_x (Reina Eq. 4), or ``simulation``, v_lat/max(|r omega|, |v_x|), the direction of
the sliding velocity. Before fitting, each trial is converted to the slip state the simulation
feeds the law (`convert_slip_state`), in the law's own convention
(`slipenv.terramechanics.models.slip_angle_convention`: Reina's for Reina's law, the sliding
velocity's for the shear laws), so that the fitted soil reproduces the trials in simulation.

Least squares (scipy ``least_squares``, trust-region reflective, bounds) on the F_x and F_y
residuals in newtons. Standard errors from the Jacobian, cov = (J^T J)^-1 RSS/(m - rank), over
the parameters not at a bound; a parameter the fit pushed to a bound has none (its estimate is
the bound, not a measurement), and one along a direction the Jacobian cannot see (rank
deficiency: e.g. the lateral parameters from trials at zero slip angle) is not determined.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from slipenv.diagnose.numbers import determined
from slipenv.terramechanics.bekker import wheel_sinkage_float_m
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import force_model_by_name, slip_angle_convention
from slipenv.terramechanics.sidewall import sidewall_force_n
from slipenv.terramechanics.slip_dynamics import relax_slip
from slipenv.terramechanics.soil import Soil
from slipenv.testbed.csv_format import TestBedData

__all__ = ["LAWS", "SIDEWALL_LAW", "LawFit", "at_physical_limit", "convert_slip_state", "fit_law",
           "heldout_rmse", "law_input_definition", "parameter_uncertainty", "predict"]

LAWS = ("janosi", "reina", "linear")
SIDEWALL_LAW = "reina_sidewall"
DEFINITIONS = ("reina", "simulation")
_BOUNDS = {"mu": (1e-3, 3.0), "c_x_n": (1e-3, 1e5), "c_y_n": (1e-3, 1e5), "a_x": (0.0, 1.0),
           "a_y": (0.0, 1.0), "cohesion_pa": (0.0, 1e6), "friction_angle_rad": (1e-3, 1.5),
           "shear_modulus_m": (1e-4, 1.0), "unit_weight_n_m3": (0.0, 1e6)}
# Lower bounds that are physical limits (no cohesion, no slope of the saturated force, no
# side wall), not search limits: an estimate there is a legitimate value.
_PHYSICAL_LOWER = frozenset({"a_x", "a_y", "cohesion_pa", "unit_weight_n_m3"})
# Fields that are not `Soil` fields (they live in `LawFit.extras`).
_EXTRA = ("unit_weight_n_m3",)
# A starting unit weight: dry sand, about 1.6 t/m^3 (its plausible range is below).
_UNIT_WEIGHT0 = 1.6e4
PLAUSIBLE_UNIT_WEIGHT = (8e3, 2.5e4)  # [N/m^3] loose lunar simulant to dense wet sand
# An estimate within this fraction of its bound range from a bound is "at the bound".
_AT_BOUND = 1e-6
# Singular values below this fraction of the largest (columns scaled to unit norm) are a
# direction the trials do not see.
_RCOND = 1e-7

AT_BOUND, NOT_DETERMINED, DETERMINED = "at bound", "not determined", "determined"


@dataclass(frozen=True)
class LawFit:
    """One law fitted to all trials.

    Attributes
    ----------
    law : str
        ``reina``, ``janosi``, ``linear`` or ``reina_sidewall``.
    names : tuple of str
        Fitted fields (soil fields, and ``unit_weight_n_m3`` for the side-wall law).
    values, std_errors : ndarray
        Their estimates and standard errors (units of the `Soil` fields); the standard error is
        NaN at a bound and infinite where the data do not determine the parameter.
    status : tuple of str
        Per parameter: ``"determined"``, ``"not determined"`` or ``"at bound"``.
    soil : Soil
        The base soil with the fitted soil fields replaced.
    residual_fx_n, residual_fy_n : ndarray
        Measured minus predicted force per trial [N].
    extras : dict
        Fitted values that are not `Soil` fields (the side-wall law's unit weight).
    """

    law: str
    names: tuple[str, ...]
    values: np.ndarray
    std_errors: np.ndarray
    soil: Soil
    residual_fx_n: np.ndarray
    residual_fy_n: np.ndarray
    status: tuple[str, ...] = ()
    extras: dict = field(default_factory=dict)

    def parameters(self) -> dict[str, list]:
        """``{name: [value, standard_error]}``; the error is None at a bound and where the
        Jacobian cannot see the parameter (`status` says which; as in `slipenv.diagnose`, a
        finite error larger than the value is kept and the status says "not determined")."""
        return {n: [float(v), float(e) if math.isfinite(e) else None]
                for n, v, e in zip(self.names, self.values, self.std_errors, strict=True)}

    def parameter_status(self) -> dict[str, str]:
        """``{name: status}`` (see `status`)."""
        return dict(zip(self.names, self.status, strict=True))


def at_physical_limit(name: str, value: float) -> bool:
    """Whether `value` of fitted field `name` sits at a physical limit (cohesion 0, ...)
    rather than at a search bound of the fit."""
    lo, hi = _BOUNDS[name]
    return name in _PHYSICAL_LOWER and value - lo <= _AT_BOUND * (hi - lo)


def geometry_of(data: TestBedData) -> ContactGeometry:
    """The wheel's contact geometry from ``meta.json``."""
    m = data.meta
    return ContactGeometry(radius_m=float(m["wheel_radius_m"]), width_m=float(m["wheel_width_m"]),
                           contact_length_m=float(m["contact_length_m"]))


def fitted_names(law: str, data: TestBedData) -> tuple[str, ...]:
    """The fields `law` is fitted on for these data (see the module)."""
    if law == "reina":
        return ("mu", "c_x_n", "c_y_n", "a_x", "a_y")
    if law == SIDEWALL_LAW:
        return ("mu", "c_x_n", "c_y_n", "a_x", "a_y", "unit_weight_n_m3")
    if law in ("janosi", "linear"):
        w = data.normal_load_n
        if np.ptp(w) > 0.2 * float(np.mean(w)):
            return ("cohesion_pa", "friction_angle_rad", "shear_modulus_m")
        return ("friction_angle_rad", "shear_modulus_m")
    raise ValueError(f"unknown law {law!r}; known: {', '.join(LAWS + (SIDEWALL_LAW,))}")


def _force_law(law: str) -> str:
    return "reina" if law == SIDEWALL_LAW else law


def law_input_definition(model) -> str:
    """The slip-angle definition, in ``meta.json``'s words, of a force model's input:
    ``"reina"`` for a law in Reina's convention, ``"simulation"`` for one along the sliding
    velocity (`slipenv.terramechanics.models.slip_angle_convention`)."""
    return "reina" if slip_angle_convention(model) == "reina" else "simulation"


_STEADY_STEP = 1e15  # [s/m] h of `relax_slip` for its steady state


def convert_slip_state(slip, tan_beta, source: str, target: str):
    """(s, tan beta) given in definition `source` as the simulation feeds a law taking `target`.

    The data: s = (r omega - v)/max(|r omega|, |v|) (so v = 1 - s driving, 1 braking, in units
    of that maximum) and tan beta = v_lat/v (``reina``, Reina Eq. 4) or v_lat/max(|r omega|,
    |v|) (``simulation``). The law's input is the steady state of the relaxation, computed by
    `slipenv.terramechanics.slip_dynamics.relax_slip` itself: s = (r omega - v)/V,
    V = max(|r omega|, |v|, |v_lat|), and tan beta = v_lat/V (``simulation``: the sliding
    velocity's direction) or v_lat/max(|v|, |v_lat|) (``reina``: Reina's, +-1 beyond 45 deg).

    Raises
    ------
    ValueError
        For a ``simulation`` slip angle of 45 deg or more in the data (there |v_lat| may be the
        reference speed, and (s, tan beta) no longer give the velocities).
    """
    s = np.asarray(slip, dtype=float)
    t = np.asarray(tan_beta, dtype=float)
    for name in (source, target):
        if name not in DEFINITIONS:
            raise ValueError(f"slip_angle_definition {name!r} must be one of {DEFINITIONS}")
    if source == "simulation" and np.any(np.abs(t) >= 1.0):
        raise ValueError("a slip angle of 45 deg or more in the 'simulation' definition does "
                         "not give the wheel's velocities (the lateral speed may be the "
                         "reference): cannot convert it")
    rim, v = np.where(s > 0.0, 1.0, 1.0 + s), np.where(s > 0.0, 1.0 - s, 1.0)
    v_lat = t * v if source == "reina" else t
    # The relaxation's own steady state: one step with h = dt/sigma so large that the state
    # it starts from no longer counts (1e-15 relative).
    forward = target == "reina"
    rim, v, v_lat = np.broadcast_arrays(rim, v, v_lat)
    steady = [relax_slip(0.0, 0.0, float(r), float(u), float(w), _STEADY_STEP, forward)[:2]
              for r, u, w in zip(rim.ravel(), v.ravel(), v_lat.ravel(), strict=True)]
    out = np.array(steady, dtype=float).reshape(*rim.shape, 2)
    return out[..., 0], out[..., 1]


def sinkage_of(data: TestBedData, base: Soil, index=slice(None)) -> np.ndarray:
    """Per trial sinkage [m]: the measured ``sinkage_m``, else the base soil's static Bekker
    sinkage of the wheel under its load (Wong Ch. 5), capped at the radius."""
    g = geometry_of(data)
    z = np.array(data.sinkage_m[index], dtype=float)
    w = data.normal_load_n[index]
    for i in np.flatnonzero(~np.isfinite(z)):
        z[i] = wheel_sinkage_float_m(float(w[i]), g.width_m, 2.0 * g.radius_m, base.k_c,
                                     base.k_phi, base.n_exp)
    return np.minimum(z, g.radius_m)


def _split(names, values) -> tuple[dict[str, Any], dict[str, float]]:
    soil: dict[str, Any] = {}  # Soil fields, for dataclasses.replace
    extra: dict[str, float] = {}
    for n, v in zip(names, values, strict=True):
        (extra if n in _EXTRA else soil)[n] = float(v)
    return soil, extra


def _with(base: Soil, data: TestBedData, names, values) -> Soil:
    soil_fields, _ = _split(names, values)
    return replace(base, name=f"{base.name}_fitted",
                   reference_load_n=float(np.median(data.normal_load_n)), **soil_fields)


def predict(law: str, soil: Soil, data: TestBedData, index=slice(None),
            extras: dict | None = None):
    """Predicted carriage forces (fx_n, fy_n) [N] of `law` with `soil` for the trials `index`.

    F_x is the model's thrust minus its motion resistance (the net force the bed measures).
    The data's slip angle is first converted to the model's input definition. The side-wall
    law needs ``extras["unit_weight_n_m3"]``.
    """
    model = force_model_by_name(_force_law(law), geometry_of(data))
    params = soil.params()
    s, tb = convert_slip_state(data.slip_ratio[index], data.tan_beta[index],
                               data.meta.get("slip_angle_definition", "reina"),
                               law_input_definition(model))
    w = data.normal_load_n[index]
    fx, fy = model(s, tb, w, params)
    fx = fx - model.resistance_n(w, params)
    if law == SIDEWALL_LAW:
        gamma = float((extras or {})["unit_weight_n_m3"])
        r = geometry_of(data).radius_m
        wall = np.array([sidewall_force_n(z, r, soil.cohesion_pa, soil.friction_angle_rad,
                                          gamma) for z in sinkage_of(data, soil, index)])
        fy = fy - np.sign(data.tan_beta[index]) * wall  # against the lateral sliding
    return fx, fy


def _start(base: Soil, name: str) -> float:
    return _UNIT_WEIGHT0 if name == "unit_weight_n_m3" else float(getattr(base, name))


def _solve(law: str, base: Soil, data: TestBedData, index, names):
    x0 = np.array([_start(base, n) for n in names])
    lo = np.array([_BOUNDS[n][0] for n in names])
    hi = np.array([_BOUNDS[n][1] for n in names])
    x0 = np.clip(x0, lo + 1e-9, hi - 1e-9)
    fx_m, fy_m = data.fx_n[index], data.fy_n[index]

    def residuals(x: np.ndarray) -> np.ndarray:
        _, extra = _split(names, x)
        fx, fy = predict(law, _with(base, data, names, x), data, index, extra)
        return np.concatenate((fx - fx_m, fy - fy_m))

    return least_squares(residuals, x0, bounds=(lo, hi), x_scale="jac", method="trf",
                         xtol=1e-12, ftol=1e-12, gtol=1e-12, max_nfev=400)


def parameter_uncertainty(jac: np.ndarray, x: np.ndarray, lo: np.ndarray, hi: np.ndarray,
                          rss: float, active_mask=None) -> tuple[np.ndarray, tuple[str, ...]]:
    """Standard errors and status of least-squares estimates `x` (module docstring).

    A parameter at a bound (`active_mask` nonzero, or within a millionth of its range of a
    bound) gets a NaN error and ``"at bound"``; the others share cov = (J^T J)^+ RSS/(m - rank)
    over their columns of `jac`. One with a component along a null direction of the (column
    scaled) Jacobian gets an infinite error; any whose error exceeds its magnitude, or with no
    residual degree of freedom left, is ``"not determined"`` (`slipenv.diagnose.numbers`).
    """
    p = x.size
    near = (x - lo <= _AT_BOUND * (hi - lo)) | (hi - x <= _AT_BOUND * (hi - lo))
    at_bound = near if active_mask is None else near | (np.asarray(active_mask) != 0)
    se = np.full(p, np.nan)
    free = np.flatnonzero(~at_bound)
    if free.size:
        j = np.asarray(jac, dtype=float)[:, free]
        norms = np.linalg.norm(j, axis=0)
        scale = np.where(norms > 0.0, norms, 1.0)
        _, sv, vt = np.linalg.svd(j / scale, full_matrices=False)
        keep = sv > _RCOND * (sv[0] if sv.size and sv[0] > 0 else 1.0)
        rank = int(np.count_nonzero(keep))
        dof = j.shape[0] - rank
        sigma2 = rss / dof if dof > 0 else math.nan
        v_keep, v_null = vt[keep].T, vt[~keep].T
        var = (v_keep ** 2) @ (1.0 / sv[keep] ** 2) if rank else np.zeros(free.size)
        blind = (np.sum(v_null ** 2, axis=1) > 1e-6) | (norms == 0.0)
        se[free] = np.where(blind, math.inf, np.sqrt(var * sigma2) / scale)
    status = tuple(AT_BOUND if at_bound[i] else
                   (DETERMINED if determined(x[i], se[i]) else NOT_DETERMINED) for i in range(p))
    return se, status


def fit_law(law: str, data: TestBedData, base: Soil) -> LawFit:
    """Fit `law` to all trials of `data`; unfitted soil fields come from `base`.

    Raises
    ------
    ValueError
        If `law` is unknown, or there are no more residuals (2 per trial) than parameters.
    """
    names = fitted_names(law, data)
    m, p = 2 * data.n, len(names)
    if m <= p:
        raise ValueError(f"{data.n} trials cannot fit the {p} parameters of law {law!r}")
    sol = _solve(law, base, data, slice(None), names)
    lo = np.array([_BOUNDS[n][0] for n in names])
    hi = np.array([_BOUNDS[n][1] for n in names])
    se, status = parameter_uncertainty(np.asarray(sol.jac), sol.x, lo, hi,
                                       float(sol.fun @ sol.fun), sol.active_mask)
    soil = _with(base, data, names, sol.x)
    _, extras = _split(names, sol.x)
    fx, fy = predict(law, soil, data, extras=extras)
    return LawFit(law, names, sol.x.copy(), se, soil, data.fx_n - fx, data.fy_n - fy, status,
                  extras)


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
        _, extras = _split(names, sol.x)
        fx, fy = predict(law, _with(base, data, names, sol.x), data, fold, extras)
        err_x[fold], err_y[fold] = data.fx_n[fold] - fx, data.fy_n[fold] - fy
    return {"fx": float(math.sqrt(np.mean(err_x ** 2))),
            "fy": float(math.sqrt(np.mean(err_y ** 2)))}

