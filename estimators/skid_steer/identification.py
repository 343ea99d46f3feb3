"""Identification of the skid-steer slip models from rotation runs (Yamauchi §2.2-2.4).

(a) Endo's exponent n: Eq. 8 in log form, ``log|α_l/α_r| = n log|v_r/v_l|``, fitted by least squares
    through the origin on samples where both slips are well defined (Yamauchi Fig. 4).
(b) The slip-angle regression of Eq. 9, ``β = a1 + a2·roll + a3·(angular displacement)
    + a4·(rotation radius)``, by least squares (Eq. 10) with ordinary standard errors.

Training targets come from ground truth (motion capture in the paper, the simulator here):
:func:`true_slips` inverts Eq. 1-7. The regression must be judged on runs it was not fitted on;
:func:`train_test_split_runs` splits by run (samples inside a run are strongly correlated, so a
split by sample would leak), and :func:`fit_slip_angle_runs` / :func:`evaluate_runs` refuse to
score a model on a run it was trained on.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass, fields
from typing import Any, TypeVar

import numpy as np
from numpy.typing import ArrayLike

from .kinematics import check_tread, slips_from_body_velocity

T = TypeVar("T")
FEATURE_NAMES = ("roll_rad", "angular_displacement_rad", "rotation_radius_m")


@dataclass(frozen=True)
class EndoFit:
    """Least-squares estimate of Endo's exponent (Eq. 8).

    Attributes
    ----------
    n : float
        Exponent [-].
    std_err : float
        Standard error of n [-].
    ci95 : tuple[float, float]
        95 % confidence interval of n (Student t, n_samples - 1 degrees of freedom).
    n_samples : int
        Samples used after the well-definedness filter.
    """

    n: float
    std_err: float
    ci95: tuple[float, float]
    n_samples: int

    def to_dict(self) -> dict:
        """JSON-serialisable dict of the fields (tuples become lists)."""
        return _json_dict(self)


@dataclass(frozen=True)
class SlipAngleModel:
    """Fitted slip-angle regression ``β = a1 + a2·roll + a3·Δψ + a4·R`` (Eq. 9).

    Attributes
    ----------
    coef : tuple[float, float, float, float]
        (a1 [rad], a2 [rad/rad], a3 [rad/rad], a4 [rad/m]) for regressors
        [1, roll [rad], angular displacement [rad], rotation radius [m]].
    std_err : tuple[float, float, float, float]
        Ordinary least-squares standard errors of ``coef``.
    residual_std : float
        Standard deviation of the training residuals (k - 4 degrees of freedom) [rad].
    n_samples : int
        Training samples k.
    train_runs : tuple[str, ...]
        Names of the runs fitted on (empty when fitted from bare arrays).
    feature_range : tuple of three (min, max) pairs, or None
        Range of each regressor in the training data [rad, rad, m]. :meth:`predict` clips the
        regressors into it: a linear fit says nothing outside its data, and Eq. 9's angular
        displacement in particular grows without bound on a circle (2π per lap) while the
        paper's training rotations stop near π/2. None (models saved before this field): no
        clipping.
    """

    coef: tuple[float, float, float, float]
    std_err: tuple[float, float, float, float]
    residual_std: float
    n_samples: int = 0
    train_runs: tuple[str, ...] = ()
    feature_range: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        if len(self.coef) != 4 or len(self.std_err) != 4:
            raise ValueError("SlipAngleModel.coef and std_err need 4 entries (Eq. 9: a1..a4)")
        if self.feature_range is not None:
            rng = tuple(tuple(float(v) for v in pair) for pair in self.feature_range)
            if len(rng) != 3 or any(len(p) != 2 or not p[0] <= p[1] for p in rng):
                raise ValueError("SlipAngleModel.feature_range needs 3 (min, max) pairs with "
                                 f"min <= max (roll, angular displacement, radius), got {rng}")
            object.__setattr__(self, "feature_range", rng)

    def predict(
        self, roll: ArrayLike, angular_displacement: ArrayLike, rotation_radius: ArrayLike
    ) -> np.ndarray:
        """Slip angle β [rad] from roll [rad], angular displacement [rad], rotation radius [m].

        Each regressor is first clipped into ``feature_range`` (when set).
        """
        if type(roll) is float and type(angular_displacement) is float \
                and type(rotation_radius) is float:
            # One sample per odometry step: the same IEEE operations on plain floats, without
            # numpy's per-call cost on 0-d arrays; bit-identical to the array path.
            regressors = [roll, angular_displacement, rotation_radius]
            if self.feature_range is not None:
                regressors = [min(max(x, lo), hi)
                              for x, (lo, hi) in zip(regressors, self.feature_range, strict=True)]
            value = float(self.coef[0])
            for a, x in zip(self.coef[1:], regressors, strict=True):
                value = value + float(a) * x
            return np.asarray(value)
        xs = [np.asarray(x, dtype=float) for x in (roll, angular_displacement, rotation_radius)]
        if self.feature_range is not None:
            xs = [np.clip(x, lo, hi) for x, (lo, hi) in zip(xs, self.feature_range, strict=True)]
        beta = np.asarray(self.coef[0], dtype=float)
        for a, x in zip(self.coef[1:], xs, strict=True):
            beta = beta + a * x
        return beta

    def to_dict(self) -> dict:
        """JSON-serialisable dict of the fields (tuples become lists)."""
        return _json_dict(self)

    @classmethod
    def from_dict(cls, d: dict) -> SlipAngleModel:
        """Inverse of :meth:`to_dict`; unknown keys are an error."""
        unknown = set(d) - {f.name for f in fields(cls)}
        if unknown:
            raise ValueError(f"unknown SlipAngleModel keys: {sorted(unknown)}")
        kwargs: dict[str, Any] = {k: tuple(v) if isinstance(v, list) else v for k, v in d.items()}
        return cls(**kwargs)


@dataclass(frozen=True)
class SlipRun:
    """One run's regression data (Yamauchi §2.3: one rotation of about 90° under fixed conditions).

    Attributes
    ----------
    name : str
        Unique run name.
    features : np.ndarray, shape (k, 3)
        Columns roll [rad], angular displacement [rad], rotation radius [m] (``FEATURE_NAMES``).
    beta : np.ndarray, shape (k,)
        True slip angle [rad].
    """

    name: str
    features: np.ndarray
    beta: np.ndarray

    def __post_init__(self) -> None:
        _check_features(self.features, self.beta)


def _four(values: ArrayLike) -> tuple[float, float, float, float]:
    """The four Eq. 9 coefficients (or their errors) as a tuple of floats."""
    a1, a2, a3, a4 = (float(v) for v in np.asarray(values, dtype=float))
    return a1, a2, a3, a4


def _json_dict(obj: EndoFit | SlipAngleModel) -> dict:
    return {k: list(v) if isinstance(v, tuple) else v for k, v in asdict(obj).items()}


def _as_1d(name: str, value: ArrayLike) -> np.ndarray:
    arr = np.asarray(value, dtype=float)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    return arr


def _check_features(features: ArrayLike, beta: ArrayLike) -> tuple[np.ndarray, np.ndarray]:
    x, y = np.asarray(features, dtype=float), _as_1d("beta", beta)
    if x.ndim != 2 or x.shape[1] != 3:
        raise ValueError(f"features must have shape (k, 3) {FEATURE_NAMES}, got {x.shape}")
    if x.shape[0] != y.shape[0]:
        raise ValueError(f"features has {x.shape[0]} rows but beta has {y.shape[0]} samples")
    if not (np.all(np.isfinite(x)) and np.all(np.isfinite(y))):
        raise ValueError("features and beta must be finite")
    return x, y


def true_slips(
    omega_l: ArrayLike, omega_r: ArrayLike, sprocket_radius_m: float,
    v_x: ArrayLike, yaw_rate: ArrayLike, v_y: ArrayLike, tread_m: float,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """True slip ratios and slip angle from ground truth (inverse of Yamauchi Eq. 1-7).

    Parameters
    ----------
    omega_l, omega_r : array_like
        Sprocket angular speeds [rad/s]; input track speeds are ``v = R ω``.
    sprocket_radius_m : float
        Sprocket radius R [m], > 0.
    v_x, yaw_rate, v_y : array_like
        True body-frame velocity of the reference point [m/s] and yaw rate [rad/s].
    tread_m : float
        Tread 2d [m], > 0.

    Returns
    -------
    alpha_l, alpha_r, beta : np.ndarray
        Slip ratios [-] (NaN for a sprocket at rest) and slip angle [rad].
    """
    radius = float(sprocket_radius_m)
    if not (math.isfinite(radius) and radius > 0.0):
        raise ValueError(f"sprocket_radius_m must be finite and > 0, got {sprocket_radius_m!r}")
    v_l = radius * np.asarray(omega_l, dtype=float)
    v_r = radius * np.asarray(omega_r, dtype=float)
    return slips_from_body_velocity(v_l, v_r, v_x, v_y, yaw_rate, check_tread(tread_m))


def fit_endo_n(
    v_l: ArrayLike, v_r: ArrayLike, alpha_l: ArrayLike, alpha_r: ArrayLike,
    *, min_slip: float = 1e-2, min_speed_mps: float = 1e-3,
) -> EndoFit:
    """Fit Endo's exponent n by log-log least squares through the origin (Eq. 8, Fig. 4).

    Model ``y = n x`` with ``x = log|v_r/v_l|``, ``y = log|α_l/α_r|``. A sample is used only when
    all four values are finite, ``|α_l|, |α_r| >= min_slip`` (near-straight driving has both slips
    near 0 and a meaningless ratio), ``|v_l|, |v_r| >= min_speed_mps`` and the sign agrees with
    Eq. 8, ``sgn(α_l/α_r) = -sgn(v_r v_l)``.

    Parameters
    ----------
    v_l, v_r : array_like, shape (k,)
        Input track speeds [m/s].
    alpha_l, alpha_r : array_like, shape (k,)
        True slip ratios [-] (:func:`true_slips`).
    min_slip : float
        Smallest usable slip magnitude [-].
    min_speed_mps : float
        Smallest usable track speed [m/s].

    Returns
    -------
    EndoFit
        ``n = Σxy / Σx²``, ``std_err = s / sqrt(Σx²)`` with ``s² = Σ(y - n x)² / (m - 1)``.
    """
    named = (("v_l", v_l), ("v_r", v_r), ("alpha_l", alpha_l), ("alpha_r", alpha_r))
    arrays = [_as_1d(name, value) for name, value in named]
    if len({a.shape for a in arrays}) != 1:
        sizes = [a.size for a in arrays]
        raise ValueError(f"v_l, v_r, alpha_l, alpha_r must have equal lengths, got {sizes}")
    vl, vr, al, ar = arrays
    with np.errstate(invalid="ignore"):
        keep = (
            np.isfinite(vl) & np.isfinite(vr) & np.isfinite(al) & np.isfinite(ar)
            & (np.abs(al) >= min_slip) & (np.abs(ar) >= min_slip)
            & (np.abs(vl) >= min_speed_mps) & (np.abs(vr) >= min_speed_mps)
            & (np.sign(al * ar) == -np.sign(vl * vr))
        )
    m = int(np.count_nonzero(keep))
    x = np.log(np.abs(vr[keep] / vl[keep]))
    y = np.log(np.abs(al[keep] / ar[keep]))
    sxx = float(x @ x)
    if m < 3 or sxx <= 1e-12 * m:
        raise ValueError(
            f"v_l/v_r/alpha_l/alpha_r: {m} usable samples with spread Σx² = {sxx:.3g}; need "
            "turning runs at several track-speed ratios"
        )
    n = float(x @ y) / sxx
    s2 = float(np.sum((y - n * x) ** 2)) / (m - 1)
    se = math.sqrt(s2 / sxx)
    # scipy.stats takes most of a second to import; only the fit's interval needs it.
    from scipy import stats

    half = float(stats.t.ppf(0.975, m - 1)) * se
    return EndoFit(n=n, std_err=se, ci95=(n - half, n + half), n_samples=m)


def fit_slip_angle_regression(
    features: ArrayLike, beta: ArrayLike, *, train_runs: Sequence[str] = ()
) -> SlipAngleModel:
    """Least-squares fit of Eq. 9 minimising Eq. 10.

    Parameters
    ----------
    features : array_like, shape (k, 3)
        Roll [rad], angular displacement [rad], rotation radius [m] per sample.
    beta : array_like, shape (k,)
        True slip angle B_i [rad].
    train_runs : sequence of str
        Names of the runs the samples come from (recorded in the model).

    Returns
    -------
    SlipAngleModel
        Coefficients, OLS standard errors ``sqrt(diag(s² (XᵀX)⁻¹))`` with ``s² = RSS/(k-4)``.
    """
    x, y = _check_features(features, beta)
    design = np.column_stack([np.ones(x.shape[0]), x])
    k = design.shape[0]
    if k <= 4 or np.linalg.matrix_rank(design) < 4:
        raise ValueError(
            f"features: {k} samples of rank {np.linalg.matrix_rank(design)}; Eq. 9 needs more than "
            "4 samples with varying roll, angular displacement and rotation radius"
        )
    coef, *_ = np.linalg.lstsq(design, y, rcond=None)
    residual = y - design @ coef
    s2 = float(residual @ residual) / (k - 4)
    cov = s2 * np.linalg.inv(design.T @ design)
    return SlipAngleModel(
        coef=_four(coef),
        std_err=_four(np.sqrt(np.diag(cov))),
        residual_std=math.sqrt(s2),
        n_samples=k,
        train_runs=tuple(train_runs),
        feature_range=tuple((float(lo), float(hi)) for lo, hi in zip(x.min(0), x.max(0),
                                                                        strict=True)),
    )


def evaluate(model: SlipAngleModel, features: ArrayLike, beta: ArrayLike) -> float:
    """Root-mean-square error of ``model`` on held-out samples [rad]."""
    x, y = _check_features(features, beta)
    if x.shape[0] == 0:
        raise ValueError("features: no samples to evaluate on")
    err = model.predict(x[:, 0], x[:, 1], x[:, 2]) - y
    return float(np.sqrt(np.mean(err * err)))


def stack_runs(runs: Sequence[SlipRun]) -> tuple[np.ndarray, np.ndarray]:
    """Concatenate runs into (features (k, 3), beta (k,))."""
    if not runs:
        raise ValueError("runs must not be empty")
    return np.vstack([r.features for r in runs]), np.concatenate([r.beta for r in runs])


def fit_slip_angle_runs(runs: Sequence[SlipRun]) -> SlipAngleModel:
    """Fit Eq. 9 on whole runs, recording their names in ``SlipAngleModel.train_runs``."""
    names = [r.name for r in runs]
    if len(set(names)) != len(names):
        raise ValueError(f"runs: names must be unique, got {names}")
    return fit_slip_angle_regression(*stack_runs(runs), train_runs=names)


def evaluate_runs(model: SlipAngleModel, runs: Sequence[SlipRun]) -> float:
    """Held-out RMSE [rad] over whole runs; ``ValueError`` if any was used for training."""
    leaked = sorted({r.name for r in runs} & set(model.train_runs))
    if leaked:
        raise ValueError(f"runs {leaked} were used to fit the model; evaluate held-out runs only")
    return evaluate(model, *stack_runs(runs))


def train_test_split_runs(
    runs: Sequence[T], test_fraction: float, rng: np.random.Generator
) -> tuple[list[T], list[T]]:
    """Split whole runs (never samples) into training and test sets.

    Parameters
    ----------
    runs : sequence
        Runs (e.g. :class:`SlipRun`), at least 2.
    test_fraction : float
        Fraction of runs held out, in (0, 1); at least one run goes to each side.
    rng : np.random.Generator
        Seeded generator for the permutation.
    """
    if not (0.0 < test_fraction < 1.0):
        raise ValueError(f"test_fraction must be in (0, 1), got {test_fraction!r}")
    if len(runs) < 2:
        raise ValueError(f"runs: need at least 2 runs to split, got {len(runs)}")
    n_test = min(max(1, round(test_fraction * len(runs))), len(runs) - 1)
    order = rng.permutation(len(runs))
    test = set(order[:n_test].tolist())
    return [r for i, r in enumerate(runs) if i not in test], [runs[i] for i in sorted(test)]
