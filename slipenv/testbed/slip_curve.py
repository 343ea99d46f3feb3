"""The slip ratio a wheel needs on a slope as the slip angle grows, s_x(beta) (Reina Fig. 12).

Reina §3.3: climbing a slope of inclination theta at constant speed, each wheel must deliver the
tractive effort R_x = W sin(theta), W a quarter of the vehicle's weight. Its slip ratio solves
F_x(s_x, tan beta) = R_x with Reina's combined-slip law (Eq. 8); at beta = 0 that is s_x0. As the
slip angle grows, lateral slip uses up adhesion (the friction ellipse, Eq. 11) and s_x rises;
Reina approximates the rise linearly, s_x = s_x0 + k (beta - beta0) (Eq. 12). This module
solves the law numerically and fits Eq. 12 with `slipenv.estimators.reina.slip_model`.

The law is evaluated as slipenv's `ReinaForceModel` does, with C_x, C_y scaled by the wheel's
normal load over the soil's reference load (Reina's own C at W = W_ref), the normal load being
W cos(theta); the needed force is W sin(theta) plus an optional rolling resistance f_r W cos(theta).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import brentq

from slipenv.estimators.reina.slip_model import SlipRatioFit, fit_slip_ratio_model
from slipenv.terramechanics.reina import reina_forces
from slipenv.terramechanics.soil import Soil

__all__ = ["slip_ratio_for_slope", "fit_slip_ratio_for_slope"]


def slip_ratio_for_slope(beta_rad: ArrayLike, slope_deg: float, soil: Soil,
                         rolling_resistance_coeff: float = 0.0) -> np.ndarray:
    """s_x solving F_x(s_x, tan beta) = W sin(theta) + f_r W cos(theta) (Reina Eq. 8, Fig. 12).

    Parameters
    ----------
    beta_rad : array_like
        Slip angles beta [rad], |beta| < pi/2 (Reina Eq. 4: tan beta = v_y/v_x).
    slope_deg : float
        Inclination theta [deg], in [0, 90).
    soil : Soil
        Reina's parameters (mu, C_x, C_y, A_x, A_y, reference load).
    rolling_resistance_coeff : float
        f_r [-] added to the tractive effort (0: Reina's R_x = W sin(theta)).

    Returns
    -------
    ndarray
        s_x [-] in (0, 1]; NaN where the law cannot deliver the effort at any slip (the wheel
        digs in: Reina's "unstable, large drift" regime).
    """
    if not (math.isfinite(slope_deg) and 0.0 <= slope_deg < 90.0):
        raise ValueError(f"slope_deg={slope_deg!r} must be in [0, 90)")
    if not (math.isfinite(rolling_resistance_coeff) and rolling_resistance_coeff >= 0.0):
        raise ValueError(f"rolling_resistance_coeff={rolling_resistance_coeff!r} must be >= 0")
    theta = math.radians(slope_deg)
    # Per unit weight W: normal load cos(theta), C scaled by it (the law is W times its form at
    # unit load with C/W_ref), needed force sin(theta) + f_r cos(theta).
    c_x, c_y = soil.c_x_n / soil.reference_load_n, soil.c_y_n / soil.reference_load_n
    need = (math.sin(theta) + rolling_resistance_coeff * math.cos(theta)) / math.cos(theta)
    betas = np.asarray(beta_rad, dtype=float)
    out = np.full(betas.shape, np.nan)
    grid = np.linspace(0.0, 1.0, 201)  # F_x(0) = 0 < need, so the first crossing has j >= 1
    for i, b in np.ndenumerate(betas):
        if not abs(b) < math.pi / 2:
            raise ValueError(f"beta_rad={b!r} must be in (-pi/2, pi/2)")
        tan_b = math.tan(abs(b))

        def excess(s: float, tan_b: float = tan_b) -> float:
            return reina_forces(s, tan_b, 1.0, soil.mu, c_x, c_y, soil.a_x, soil.a_y)[0] - need

        if need <= 0.0:
            out[i] = 0.0
            continue
        # F_x(s) rises and may fall again (A_x > 0): the smallest s that delivers the effort.
        vals = np.array([excess(s) for s in grid])
        if np.any(vals >= 0.0):
            j = int(np.argmax(vals >= 0.0))
            out[i] = brentq(excess, grid[j - 1], grid[j], xtol=1e-12)
    return out


def fit_slip_ratio_for_slope(slope_deg: float, soil: Soil, max_beta_deg: float = 25.0,
                             n: int = 26, rolling_resistance_coeff: float = 0.0
                             ) -> tuple[SlipRatioFit, np.ndarray, np.ndarray]:
    """Reina Eq. 12 fitted to the numerical s_x(beta) on `slope_deg` (Reina Fig. 12).

    Returns the fit (`slipenv.estimators.reina.slip_model`), the slip angles [rad] and the
    solved slip ratios (NaN samples, beyond what the law can deliver, are left out of the fit).
    """
    if not (0.0 < max_beta_deg < 90.0 and n >= 4):
        raise ValueError(f"max_beta_deg={max_beta_deg!r} must be in (0, 90) and n={n!r} >= 4")
    beta = np.radians(np.linspace(0.0, max_beta_deg, n))
    s = slip_ratio_for_slope(beta, slope_deg, soil, rolling_resistance_coeff)
    ok = np.isfinite(s)
    if ok.sum() < 4:
        raise ValueError(f"the law cannot deliver the effort of a {slope_deg} deg slope at "
                         "4 or more of the slip angles")
    return fit_slip_ratio_model(beta[ok], s[ok]), beta, s
