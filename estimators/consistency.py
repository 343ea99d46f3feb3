"""Filter consistency statistics (Bar-Shalom and Fortmann 1988, as used by Lindgren §5).

Usable on any filter's innovation record: a sequence of ``(t, y, S)`` tuples (time [s],
innovation, shape (n_z,), and its covariance, shape (n_z, n_z)), or the stacked arrays
returned by :func:`stack_innovations`. The three criteria of Lindgren §5:

1. state errors compatible with their covariance — :func:`nees` (simulation only);
2. innovations compatible with their covariance — time-averaged NIS, Eq. 43, against the
   χ² band, Eq. 44 (Wilson-Hilferty) and the exact ``scipy.stats.chi2`` quantiles;
3. innovations white — normalised autocorrelation, Eq. 42, against ±1.96/√K.

Tables 2 and 3 of the paper are the mean and variance of ρ̄(l) over the lags and the
time-averaged NIS; :class:`ConsistencyReport` holds those numbers and prints them.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import stats

InnovationRecord = tuple[float, np.ndarray, np.ndarray]


def stack_innovations(
    records: Iterable[InnovationRecord],
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Stack ``(t, y, S)`` records of one sensor into arrays.

    Returns
    -------
    t : np.ndarray, shape (K,)
    y : np.ndarray, shape (K, n_z)
    S : np.ndarray, shape (K, n_z, n_z)
    """
    records = list(records)
    if not records:
        raise ValueError("no innovations recorded")
    t = np.array([r[0] for r in records], dtype=float)
    y = np.array([np.atleast_1d(r[1]) for r in records], dtype=float)
    S = np.array([np.atleast_2d(r[2]) for r in records], dtype=float)
    return t, y, S


def _as_2d(y: np.ndarray) -> np.ndarray:
    y = np.asarray(y, dtype=float)
    return y[:, None] if y.ndim == 1 else y


def nis(y: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Normalised innovation squared ``ν' S⁻¹ ν`` per sample.

    Parameters
    ----------
    y : np.ndarray, shape (K, n_z) or (K,)
    S : np.ndarray, shape (K, n_z, n_z) or (K,)

    Returns
    -------
    np.ndarray, shape (K,)
    """
    y = _as_2d(y)
    S = np.asarray(S, dtype=float).reshape(len(y), y.shape[1], y.shape[1])
    return np.einsum("ki,ki->k", y, np.linalg.solve(S, y[..., None])[..., 0])


def time_averaged_nis(y: np.ndarray, S: np.ndarray) -> float:
    """Time-averaged NIS ``ε̄_ν = (1/K) Σ ν' S⁻¹ ν`` (Lindgren Eq. 43)."""
    return float(np.mean(nis(y, S)))


def nees(x_err: np.ndarray, P: np.ndarray) -> np.ndarray:
    """Normalised estimation error squared ``x̃' P⁻¹ x̃`` per sample.

    Parameters
    ----------
    x_err : np.ndarray, shape (K, n)
        True minus estimated state, angle components already wrapped.
    P : np.ndarray, shape (K, n, n)
        The filter's covariance.

    Returns
    -------
    np.ndarray, shape (K,)
    """
    return nis(x_err, P)


def wilson_hilferty_quantile(dof: float, u: float) -> float:
    """Approximate χ² quantile ``n [1 - 2/(9n) + u √(2/(9n))]³`` (Lindgren Eq. 44).

    Parameters
    ----------
    dof : float
        Degrees of freedom n.
    u : float
        Standard normal quantile, Pr(G > u) = α for the upper-α point.
    """
    a = 2.0 / (9.0 * dof)
    return dof * (1.0 - a + u * math.sqrt(a)) ** 3


def chi2_mean_band(
    n_samples: int, dim: int, significance: float = 0.05, method: str = "exact"
) -> tuple[float, float]:
    """Two-sided band for the mean of ``n_samples`` independent χ²(dim) variables.

    ``n_samples · mean`` is χ² with ``n_samples · dim`` degrees of freedom, so the band is
    ``[χ²(α/2 lower), χ²(α/2 upper)] / n_samples``. For Lindgren's K = 1099, n_z = 2 at 5 %
    this is [1.883, 2.120].

    Parameters
    ----------
    n_samples : int
        K, the number of NIS (or NEES) values averaged.
    dim : int
        n_z (or n_x), the dimension of each.
    significance : float
        Total probability outside the band.
    method : {"exact", "wilson_hilferty"}
        scipy's χ² quantiles, or the paper's normal approximation Eq. 44.

    Returns
    -------
    tuple[float, float]
    """
    if n_samples < 1 or dim < 1 or not 0.0 < significance < 1.0:
        raise ValueError("need n_samples >= 1, dim >= 1 and 0 < significance < 1")
    n = n_samples * dim
    lo_p, hi_p = 0.5 * significance, 1.0 - 0.5 * significance
    if method == "exact":
        lo, hi = stats.chi2.ppf(lo_p, n), stats.chi2.ppf(hi_p, n)
    elif method == "wilson_hilferty":
        lo = wilson_hilferty_quantile(n, float(stats.norm.ppf(lo_p)))
        hi = wilson_hilferty_quantile(n, float(stats.norm.ppf(hi_p)))
    else:
        raise ValueError(f"method must be 'exact' or 'wilson_hilferty', got {method!r}")
    return float(lo) / n_samples, float(hi) / n_samples


def whiten(y: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Innovations scaled to unit covariance, ``L⁻¹ ν`` with ``S = L L'``, shape (K, n_z)."""
    y = _as_2d(y)
    S = np.asarray(S, dtype=float).reshape(len(y), y.shape[1], y.shape[1])
    L = np.linalg.cholesky(S)
    return np.linalg.solve(L, y[..., None])[..., 0]


def autocorrelation(
    y: np.ndarray, lags: Sequence[int] | np.ndarray, S: np.ndarray | None = None
) -> np.ndarray:
    """Normalised innovation autocorrelation ρ̄(l) (Lindgren Eq. 42).

    ``ρ̄(l) = Σ ν(k)' ν(k+l) / √(Σ ν(k)' ν(k) · Σ ν(k+l)' ν(k+l))``, the sums over the
    K - l overlapping pairs. For zero-mean white innovations and l > 0 it is approximately
    N(0, 1/K) for scalar innovations (the paper's statement) and N(0, 1/(K n_z)) for n_z
    components, so the paper's ±1.96/√K interval is conservative for vector innovations.

    Parameters
    ----------
    y : np.ndarray, shape (K, n_z) or (K,)
        Innovations in time order.
    lags : sequence of int, each in [1, K)
    S : np.ndarray, shape (K, n_z, n_z), optional
        If given, innovations are whitened first (:func:`whiten`), which keeps samples with a
        large S from dominating; the paper uses the raw innovations (None).

    Returns
    -------
    np.ndarray, shape (len(lags),)
    """
    v = _as_2d(y) if S is None else whiten(y, S)
    K = len(v)
    out = np.empty(len(lags))
    for i, lag in enumerate(lags):
        if not 0 < lag < K:
            raise ValueError(f"lag {lag} outside [1, {K})")
        a, b = v[: K - lag], v[lag:]
        out[i] = np.sum(a * b) / math.sqrt(np.sum(a * a) * np.sum(b * b))
    return out


def autocorrelation_summary(rho: np.ndarray, n_samples: int) -> tuple[float, float, float]:
    """(mean, variance, share inside ±1.96/√K) of ρ̄ over lags (Lindgren Table 2, §5 text)."""
    rho = np.asarray(rho, dtype=float)
    bound = 1.96 / math.sqrt(n_samples)
    return float(np.mean(rho)), float(np.var(rho)), float(np.mean(np.abs(rho) <= bound))


@dataclass(frozen=True)
class ConsistencyReport:
    """Consistency statistics of one innovation stream (Lindgren Tables 2-3).

    Attributes
    ----------
    name : str
        Stream name (e.g. "odo").
    n_samples : int
        K.
    dim : int
        n_z.
    nis_mean : float
        Time-averaged NIS, Eq. 43.
    band_wilson_hilferty : tuple[float, float]
        95 % band from Eq. 44.
    band_exact : tuple[float, float]
        95 % band from scipy's χ² quantiles.
    lags : np.ndarray, shape (L,)
    rho : np.ndarray, shape (L,)
        ρ̄(l), Eq. 42.
    rho_mean, rho_var : float
        Mean and variance of ρ̄ over the lags (Table 2).
    rho_share_inside : float
        Share of lags with |ρ̄| <= 1.96/√K.
    """

    name: str
    n_samples: int
    dim: int
    nis_mean: float
    band_wilson_hilferty: tuple[float, float]
    band_exact: tuple[float, float]
    lags: np.ndarray
    rho: np.ndarray
    rho_mean: float
    rho_var: float
    rho_share_inside: float

    @property
    def nis_consistent(self) -> bool:
        """True when the time-averaged NIS lies in the exact 95 % band."""
        return self.band_exact[0] <= self.nis_mean <= self.band_exact[1]

    def table(self) -> str:
        """A plain-text table of the statistics."""
        wh, ex = self.band_wilson_hilferty, self.band_exact
        rows = [
            ("stream", self.name),
            ("K, n_z", f"{self.n_samples}, {self.dim}"),
            ("time-averaged NIS (Eq. 43)", f"{self.nis_mean:.4f}"),
            ("95 % band, Eq. 44", f"{wh[0]:.4f} - {wh[1]:.4f}"),
            ("95 % band, exact chi2", f"{ex[0]:.4f} - {ex[1]:.4f}"),
            ("NIS inside band", "yes" if self.nis_consistent else "no"),
            (f"autocorrelation lags {int(self.lags[0])}-{int(self.lags[-1])}: mean",
             f"{self.rho_mean:.4f}"),
            ("autocorrelation variance", f"{self.rho_var:.4f}"),
            (f"share inside +-{1.96 / math.sqrt(self.n_samples):.4f}",
             f"{100.0 * self.rho_share_inside:.2f} %"),
        ]
        width = max(len(k) for k, _ in rows)
        return "\n".join(f"{k:<{width}}  {v}" for k, v in rows)


def consistency_report(
    records: Iterable[InnovationRecord] | tuple[np.ndarray, np.ndarray],
    name: str = "",
    lags: Sequence[int] | None = None,
    significance: float = 0.05,
    whiten_innovations: bool = False,
) -> ConsistencyReport:
    """NIS and whiteness statistics of one innovation stream.

    Parameters
    ----------
    records : iterable of (t, y, S), or a tuple (y, S) of stacked arrays
        One sensor's innovations in time order.
    name : str
        Label for the table.
    lags : sequence of int, optional
        Autocorrelation lags; default 1 .. min(50, K // 4).
    significance : float
        Of the NIS band.
    whiten_innovations : bool
        Whiten before the autocorrelation (see :func:`autocorrelation`).
    """
    if isinstance(records, tuple) and len(records) == 2 and isinstance(records[0], np.ndarray):
        y, S = _as_2d(records[0]), np.asarray(records[1], dtype=float)
    else:
        _, y, S = stack_innovations(records)
    K, n_z = y.shape
    if lags is None:
        lags = range(1, max(2, min(50, K // 4) + 1))
    lags_arr = np.asarray(list(lags), dtype=int)
    rho = autocorrelation(y, lags_arr, S if whiten_innovations else None)
    mean, var, share = autocorrelation_summary(rho, K)
    return ConsistencyReport(
        name=name, n_samples=K, dim=n_z, nis_mean=time_averaged_nis(y, S),
        band_wilson_hilferty=chi2_mean_band(K, n_z, significance, "wilson_hilferty"),
        band_exact=chi2_mean_band(K, n_z, significance, "exact"),
        lags=lags_arr, rho=rho, rho_mean=mean, rho_var=var, rho_share_inside=share,
    )
