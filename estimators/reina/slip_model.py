"""Longitudinal slip as a function of the slip angle, s_x(β) (Reina §3.3, Eq. 12).

Sign conventions (physics-notes §3): s_x = 1 - V_x/(r ω) (Eq. 3), positive while driving; the
model is applied to |β| because a drift to either side uses up the same longitudinal adhesion
(the friction ellipse is symmetric in β). Eq. 15 as printed reads V_x = r ω (1 - s_x0 + k(β - β0))
above β0; with Eq. 3 and Eq. 12 it must be V_x = r ω (1 - s_x0 - k(β - β0)) = r ω (1 - s_x(β)),
which is what :class:`SCompOdometry` uses.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares


@dataclass(frozen=True)
class SlipRatioModel:
    """s_x(β) = s_x0 for |β| <= β0, s_x0 + k (|β| - β0) above (Eq. 12).

    Attributes
    ----------
    s_x0 : float
        Slip ratio without lateral drift for the slope at hand [-], in (-1, 1).
    k_per_rad : float
        Growth of the slip ratio with the slip angle [1/rad].
    beta0_rad : float
        Slip angle where the growth starts [rad], >= 0.
    """

    s_x0: float
    k_per_rad: float
    beta0_rad: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.s_x0) and -1.0 < self.s_x0 < 1.0):
            raise ValueError(f"SlipRatioModel.s_x0 must be in (-1, 1), got {self.s_x0!r}")
        if not math.isfinite(self.k_per_rad):
            raise ValueError(f"SlipRatioModel.k_per_rad must be finite, got {self.k_per_rad!r}")
        if not (math.isfinite(self.beta0_rad) and self.beta0_rad >= 0.0):
            raise ValueError(f"SlipRatioModel.beta0_rad must be >= 0, got {self.beta0_rad!r}")

    def __call__(self, beta_rad: ArrayLike) -> np.ndarray | float:
        """Slip ratio at slip angle(s) ``beta_rad`` [rad]."""
        b = np.abs(np.asarray(beta_rad, dtype=float))
        s = self.s_x0 + self.k_per_rad * np.maximum(b - self.beta0_rad, 0.0)
        return float(s) if s.ndim == 0 else s


@dataclass(frozen=True)
class SlipRatioFit:
    """A fitted :class:`SlipRatioModel` with its uncertainty.

    Attributes
    ----------
    model : SlipRatioModel
        Least-squares parameters.
    std_errors : tuple of float
        Standard errors of (s_x0, k [1/rad], β0 [rad]) from the Jacobian at the optimum.
    rms : float
        Root-mean-square residual [-].
    """

    model: SlipRatioModel
    std_errors: tuple[float, float, float]
    rms: float


def _linear_fit(b: np.ndarray, s: np.ndarray, beta0: float) -> tuple[float, float, float]:
    design = np.column_stack([np.ones_like(b), np.maximum(b - beta0, 0.0)])
    coef, *_ = np.linalg.lstsq(design, s, rcond=None)
    return float(coef[0]), float(coef[1]), float(np.sum((design @ coef - s) ** 2))


def fit_slip_ratio_model(beta_rad: ArrayLike, s_x: ArrayLike, n_grid: int = 60) -> SlipRatioFit:
    """Least-squares s_x0, k and β0 of Eq. 12 from samples (β, s_x).

    β0 is first located on a grid over the sampled |β| (s_x0 and k are linear given β0), then
    all three are refined together with ``scipy.optimize.least_squares``.

    Parameters
    ----------
    beta_rad, s_x : array_like, shape (n,)
        Slip angles [rad] and slip ratios [-]; n >= 4, finite.
    n_grid : int
        β0 grid size for the start.
    """
    b = np.abs(np.asarray(beta_rad, dtype=float).ravel())
    s = np.asarray(s_x, dtype=float).ravel()
    if b.shape != s.shape:
        raise ValueError(f"beta_rad and s_x must have the same length, got {b.size} and {s.size}")
    if b.size < 4:
        raise ValueError(f"fit_slip_ratio_model needs at least 4 samples, got {b.size}")
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(s))):
        raise ValueError("beta_rad and s_x must be finite")
    grid = np.linspace(0.0, np.quantile(b, 0.8), n_grid)
    costs = [_linear_fit(b, s, g)[2] for g in grid]
    beta0 = float(grid[int(np.argmin(costs))])
    s0, k, _ = _linear_fit(b, s, beta0)

    def residual(p: np.ndarray) -> np.ndarray:
        return p[0] + p[1] * np.maximum(b - p[2], 0.0) - s

    res = least_squares(residual, [s0, k, beta0], bounds=([-1.0, -np.inf, 0.0],
                                                           [1.0, np.inf, float(b.max())]))
    dof = max(b.size - 3, 1)
    sigma2 = float(np.sum(res.fun ** 2)) / dof
    jtj = res.jac.T @ res.jac
    cov = np.linalg.pinv(jtj) * sigma2
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    errors = (float(se[0]), float(se[1]), float(se[2]))
    s0, k, beta0 = (float(v) for v in res.x)
    return SlipRatioFit(SlipRatioModel(float(np.clip(s0, -0.999, 0.999)), k, max(beta0, 0.0)),
                        errors, float(np.sqrt(np.mean(res.fun ** 2))))
