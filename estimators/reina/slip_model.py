"""Longitudinal slip as a function of the slip angle and the pitch, s_x(β, θ) (Reina §3.3, Eq. 12).

Sign conventions (physics-notes §3): s_x = 1 - V_x/(r ω) (Eq. 3), positive while driving; the
model is applied to |β| because a drift to either side uses up the same longitudinal adhesion
(the friction ellipse is symmetric in β). Eq. 15 as printed reads V_x = r ω (1 - s_x0 + k(β - β0))
above β0; with Eq. 3 and Eq. 12 it must be V_x = r ω (1 - s_x0 - k(β - β0)) = r ω (1 - s_x(β)),
which is what :class:`SCompOdometry` uses.

The pitch term. Reina §3.3 finds s_x0 where the pure-slip traction curve F_x0(s) (Eq. 5) meets
the tractive effort of the slope, and notes that s_x0 and k grow with the inclination, so that
"by measuring the current pitch angle of the robot" the model could follow the ground. Per unit
normal load N = W cos θ (the load Eq. 5 scales with) the effort of a climb θ is tan θ, so
s_x0(θ) solves f(s) = tan θ with f = F_x0/N; differentiating,

    d s_x0 / d tan θ = 1 / f'(s_x0),   f'(s) = (C_x/N) e^{-C_x s/(μ N)} - A_x    (from Eq. 5),

the inverse slope of the traction curve at the operating point (Reina Fig. 9 and 12). About a
reference climb θ_ref this gives the term k_θ (tan θ - tan θ_ref) added to Eq. 12; k_θ is fitted
with s_x0, k and β0 rather than computed, since the estimator does not know the soil. The
growth of k with θ (a β·θ cross term) is left out: over the slopes of one drive it is second order.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares


@dataclass(frozen=True)
class SlipRatioModel:
    """s_x = s_x0 + k max(|β| - β0, 0) + k_θ (tan θ - tan θ_ref) (Eq. 12 with a pitch term).

    Attributes
    ----------
    s_x0 : float
        Slip ratio without lateral drift at the reference climb θ_ref [-], in (-1, 1).
    k_per_rad : float
        Growth of the slip ratio with the slip angle [1/rad].
    beta0_rad : float
        Slip angle where the growth starts [rad], >= 0.
    k_pitch : float
        Growth of the slip ratio with the tangent of the climb angle [-] (0: Eq. 12 as printed,
        the pitch is ignored).
    pitch_ref_rad : float
        Reference climb angle θ_ref [rad], nose up positive, in (-π/2, π/2).
    """

    s_x0: float
    k_per_rad: float
    beta0_rad: float = 0.0
    k_pitch: float = 0.0
    pitch_ref_rad: float = 0.0

    def __post_init__(self) -> None:
        if not (math.isfinite(self.s_x0) and -1.0 < self.s_x0 < 1.0):
            raise ValueError(f"SlipRatioModel.s_x0 must be in (-1, 1), got {self.s_x0!r}")
        if not math.isfinite(self.k_per_rad):
            raise ValueError(f"SlipRatioModel.k_per_rad must be finite, got {self.k_per_rad!r}")
        if not (math.isfinite(self.beta0_rad) and self.beta0_rad >= 0.0):
            raise ValueError(f"SlipRatioModel.beta0_rad must be >= 0, got {self.beta0_rad!r}")
        if not math.isfinite(self.k_pitch):
            raise ValueError(f"SlipRatioModel.k_pitch must be finite, got {self.k_pitch!r}")
        if not (math.isfinite(self.pitch_ref_rad) and abs(self.pitch_ref_rad) < 0.5 * math.pi):
            raise ValueError("SlipRatioModel.pitch_ref_rad must be in (-pi/2, pi/2), got "
                             f"{self.pitch_ref_rad!r}")

    def __call__(self, beta_rad: ArrayLike, pitch_rad: ArrayLike | None = None
                 ) -> np.ndarray | float:
        """Slip ratio at slip angle(s) ``beta_rad`` [rad] and climb angle(s) ``pitch_rad``.

        ``pitch_rad`` is the climb angle θ [rad], nose up positive; None or NaN entries stand
        for θ_ref (no pitch correction).
        """
        b = np.abs(np.asarray(beta_rad, dtype=float))
        s = self.s_x0 + self.k_per_rad * np.maximum(b - self.beta0_rad, 0.0)
        if pitch_rad is not None and self.k_pitch != 0.0:
            dt = np.tan(np.asarray(pitch_rad, dtype=float)) - math.tan(self.pitch_ref_rad)
            s = s + self.k_pitch * np.where(np.isfinite(dt), dt, 0.0)
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
    k_pitch_std_error : float
        Standard error of k_θ (NaN when the pitch was not fitted).
    """

    model: SlipRatioModel
    std_errors: tuple[float, float, float]
    rms: float
    k_pitch_std_error: float = math.nan


def _design(b: np.ndarray, beta0: float, dtan: np.ndarray | None) -> np.ndarray:
    cols = [np.ones_like(b), np.maximum(b - beta0, 0.0)]
    if dtan is not None:
        cols.append(dtan)
    return np.column_stack(cols)


def _linear_fit(b: np.ndarray, s: np.ndarray, beta0: float, dtan: np.ndarray | None
                ) -> tuple[np.ndarray, float]:
    design = _design(b, beta0, dtan)
    coef, *_ = np.linalg.lstsq(design, s, rcond=None)
    return coef, float(np.sum((design @ coef - s) ** 2))


def fit_slip_ratio_model(beta_rad: ArrayLike, s_x: ArrayLike, n_grid: int = 60, *,
                         pitch_rad: ArrayLike | None = None) -> SlipRatioFit:
    """Least-squares s_x0, k and β0 of Eq. 12 (and k_θ if pitches are given) from samples.

    β0 is first located on a grid over the sampled |β| (the other parameters are linear given
    β0), then all are refined together with ``scipy.optimize.least_squares``. With
    ``pitch_rad`` the reference climb θ_ref is the samples' mean climb, so s_x0 stays the slip
    ratio without drift on the slope at hand.

    Parameters
    ----------
    beta_rad, s_x : array_like, shape (n,)
        Slip angles [rad] and slip ratios [-]; n >= 4 (5 with pitches), finite.
    n_grid : int
        β0 grid size for the start.
    pitch_rad : array_like, shape (n,), optional
        Climb angles θ [rad], nose up positive, finite, within ±90° (e.g. the inclinometer's).
    """
    b = np.abs(np.asarray(beta_rad, dtype=float).ravel())
    s = np.asarray(s_x, dtype=float).ravel()
    if b.shape != s.shape:
        raise ValueError(f"beta_rad and s_x must have the same length, got {b.size} and {s.size}")
    if not (np.all(np.isfinite(b)) and np.all(np.isfinite(s))):
        raise ValueError("beta_rad and s_x must be finite")
    dtan, theta_ref = None, 0.0
    if pitch_rad is not None:
        th = np.asarray(pitch_rad, dtype=float).ravel()
        if th.shape != b.shape:
            raise ValueError(f"pitch_rad must have the length of beta_rad ({b.size}), got "
                             f"{th.size}")
        if not (np.all(np.isfinite(th)) and np.all(np.abs(th) < 0.5 * math.pi)):
            raise ValueError("pitch_rad must be finite and within (-pi/2, pi/2)")
        tan_th = np.tan(th)
        theta_ref = math.atan(float(np.mean(tan_th)))
        dtan = tan_th - math.tan(theta_ref)
    n_par = 3 if dtan is None else 4
    if b.size < n_par + 1:
        raise ValueError(f"fit_slip_ratio_model needs at least {n_par + 1} samples, got {b.size}")
    grid = np.linspace(0.0, np.quantile(b, 0.8), n_grid)
    costs = [_linear_fit(b, s, g, dtan)[1] for g in grid]
    beta0 = float(grid[int(np.argmin(costs))])
    coef, _ = _linear_fit(b, s, beta0, dtan)

    def residual(p: np.ndarray) -> np.ndarray:
        r = p[0] + p[1] * np.maximum(b - p[2], 0.0) - s
        return r if dtan is None else r + p[3] * dtan

    start = [coef[0], coef[1], beta0] + ([] if dtan is None else [coef[2]])
    lower = [-1.0, -np.inf, 0.0] + ([] if dtan is None else [-np.inf])
    upper = [1.0, np.inf, float(b.max())] + ([] if dtan is None else [np.inf])
    res = least_squares(residual, start, bounds=(lower, upper))
    dof = max(b.size - n_par, 1)
    sigma2 = float(np.sum(res.fun ** 2)) / dof
    cov = np.linalg.pinv(res.jac.T @ res.jac) * sigma2
    se = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    s0, k, beta0 = (float(v) for v in res.x[:3])
    k_pitch = float(res.x[3]) if dtan is not None else 0.0
    model = SlipRatioModel(float(np.clip(s0, -0.999, 0.999)), k, max(beta0, 0.0), k_pitch,
                           theta_ref)
    return SlipRatioFit(model, (float(se[0]), float(se[1]), float(se[2])),
                        float(np.sqrt(np.mean(res.fun ** 2))),
                        float(se[3]) if dtan is not None else math.nan)
