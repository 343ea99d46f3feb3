"""Reina's semi-empirical combined longitudinal/lateral wheel-soil model (Reina Eq. 5-12).

Pure-slip reference curves (Eq. 5-6)

    F_x0(s)      = W (mu (1 - e^{-C_x s/(mu W)}) - A_x s)
    F_y0(tan b)  = W (mu (1 - e^{-C_y tan b/(mu W)}) - A_y tan b)

are evaluated at the total slip sigma = sqrt(s^2 + tan^2 b) (Eq. 7) and split by direction,
F_x = (s/sigma) F_x0(sigma), F_y = (tan b/sigma) F_y0(sigma) (Eq. 8-9). Table 3 (lunar
simulant): mu = 0.6, C_x = 55 N, C_y = 200 N, A_x = 0.02, A_y = 0.04, fitted at W = 6.6 kg.

Written as F_x = s k_x(sigma) with k_x = C_x (1 - e^{-y})/y - W A_x, y = C_x sigma/(mu W), the
split has no 0/0 at sigma = 0. Sign convention of this package: F_x has the sign of s; F_y
opposes lateral sliding, F_y = -(tan b/sigma) F_y0(sigma) (Reina's Eq. 9 gives its magnitude).
Departure from the paper: k_x, k_y are floored at 0, so beyond sigma = mu/A (30 for Table 3,
far outside the fitted 0-0.8 slip, 5-25 deg) the force stays at 0 instead of changing sign.

`reina_forces` is the law in plain floats, as the simulation calls it per wheel and per substep;
its one implementation is C (``_laws.h``, which the substep loop runs). The array functions
`reina_forces_n`, `reina_reference_force_n` and `exp_secant` are derived from the same scalar
code.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

import slipenv.terramechanics._laws as _laws
from slipenv.terramechanics.vectorize import array_law

__all__ = [
    "exp_secant",
    "reina_forces",
    "reina_reference_force_n",
    "reina_forces_n",
    "reina_max_longitudinal_force_n",
]


def _exp_secant(y: float) -> float:
    """(1 - e^{-y})/y for one float y >= 0 (``_laws.h``, the text `exp_secant` is derived from)."""
    return _laws.exp_secant(y)


exp_secant = array_law(_exp_secant, name="exp_secant", doc="""\
(1 - e^{-y})/y for y >= 0, equal to 1 at y = 0 (exact to rounding, no 0/0); on arrays.
""")


def _reference_force_n(slip: float, load_n: float, mu: float, stiffness_n: float,
                       high_slip_slope: float) -> float:
    a = abs(slip)
    return slip * (stiffness_n * _laws.exp_secant(stiffness_n * a / (mu * load_n))
                   - load_n * high_slip_slope)


reina_reference_force_n = array_law(_reference_force_n, name="reina_reference_force_n",
                                    doc="""\
Pure-slip reference force W (mu (1 - e^{-C s/(mu W)}) - A s) [N] (Reina Eq. 5-6), on arrays.

Eq. 5 with (C_x, A_x) and the slip ratio s, or Eq. 6 with (C_y, A_y) and tan(beta). Reina
states it for s >= 0; here it is extended as an odd function of s. Evaluated as s k(|s|) with
k = C (1 - e^{-y})/y - W A, y = C |s|/(mu W), the form `reina_forces` uses, without its floor.

Parameters
----------
slip : array_like
    s_x [-] (Eq. 5) or tan(beta) [-] (Eq. 6).
load_n : array_like
    Vertical wheel load W [N], > 0.
mu : array_like
    Maximum soil adhesion coefficient [-].
stiffness_n : array_like
    C_x or C_y [N]: slope of the curve at zero slip.
high_slip_slope : array_like
    A_x or A_y [-]: slope of the curve at high slip, in units of W.
""")


def reina_forces(slip: float, tan_beta: float, load_n: float, mu: float, c_x_n: float,
                 c_y_n: float, a_x: float, a_y: float) -> tuple[float, float]:
    """Combined-slip forces (F_x, F_y) [N] of one wheel, in plain floats (Reina Eq. 5-9).

    The pure-slip curves (Eq. 5-6) at the total slip sigma = sqrt(s^2 + tan^2 beta) (Eq. 7),
    split by direction (Eq. 8-9), as F_x = s k_x(sigma), F_y = -tan_beta k_y(sigma) with
    k = C (1 - e^{-y})/y - W A, y = C sigma/(mu W), each k floored at 0 (see the module).

    Parameters
    ----------
    slip : float
        Slip ratio s [-] (Reina Eq. 3; > 0 in drive).
    tan_beta : float
        Tangent of the slip angle, v_lateral/|v_longitudinal| [-] (Reina Eq. 4), the
        convention Table 3 was fitted in; the simulation's lateral slip state relaxes to it
        for this law (`slip_dynamics.relax_slip` with ``forward_reference``).
    load_n : float
        Vertical load W [N]; W <= 0 (no contact) gives no force.
    mu, c_x_n, c_y_n, a_x, a_y : float
        Reina Table 3 parameters: mu [-], C_x [N], C_y [N], A_x [-], A_y [-].

    Returns
    -------
    fx_n, fy_n : float
        F_x with the sign of s; F_y opposing the lateral sliding, sign(F_y) = -sign(tan beta).
        At tan beta = 0, F_x = F_x0(s) (Eq. 5); at s = 0, -F_y = F_y0(tan beta) (Eq. 6).
    """
    return _laws.reina_forces(slip, tan_beta, load_n, mu, c_x_n, c_y_n, a_x, a_y)


reina_forces_n = array_law(reina_forces, n_out=2, name="reina_forces_n", doc="""\
`reina_forces` (Reina Eq. 5-9) on arrays: arguments broadcast, returns (fx_n, fy_n) arrays.
""")


def reina_max_longitudinal_force_n(tan_beta: ArrayLike, load_n: ArrayLike,
                                   mu: ArrayLike) -> np.ndarray:
    """Saturation of F_x as s -> 1, mu W / sqrt(1 + tan^2 beta) [N] (Reina Eq. 10, A_x ~ 0)."""
    return np.asarray(mu) * np.asarray(load_n) / np.hypot(1.0, tan_beta)
