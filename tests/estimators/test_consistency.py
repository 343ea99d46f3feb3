"""Consistency statistics against hand-computed values and the paper's numbers."""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy import stats

from slipenv.estimators.consistency import (
    ConsistencyReport,
    autocorrelation,
    autocorrelation_summary,
    chi2_mean_band,
    consistency_report,
    nees,
    nis,
    stack_innovations,
    time_averaged_nis,
    whiten,
    wilson_hilferty_quantile,
)


def test_paper_band_k1099_nz2() -> None:
    """Lindgren §5: K = 1099, n_z = 2, 5 % significance gives 1.8831 - 2.1204 (Eq. 44)."""
    lo, hi = chi2_mean_band(1099, 2, 0.05, "wilson_hilferty")
    assert lo == pytest.approx(1.8831, abs=5e-4)
    assert hi == pytest.approx(2.1204, abs=5e-4)
    lo_x, hi_x = chi2_mean_band(1099, 2, 0.05, "exact")
    assert lo_x == pytest.approx(stats.chi2.ppf(0.025, 2198) / 1099, rel=1e-12)
    assert hi_x == pytest.approx(stats.chi2.ppf(0.975, 2198) / 1099, rel=1e-12)
    assert (lo_x, hi_x) == pytest.approx((lo, hi), abs=1e-5)  # Eq. 44 is that good here


def test_wilson_hilferty_against_scipy() -> None:
    for n, rel in ((10, 1e-2), (100, 1e-3), (2198, 1e-4)):
        for p in (0.025, 0.5, 0.975):
            approx = wilson_hilferty_quantile(n, float(stats.norm.ppf(p)))
            assert approx == pytest.approx(stats.chi2.ppf(p, n), rel=rel)
    with pytest.raises(ValueError, match="method"):
        chi2_mean_band(10, 2, 0.05, "normal")
    with pytest.raises(ValueError):
        chi2_mean_band(0, 2)


def test_nis_by_hand() -> None:
    y = np.array([[1.0, 0.0], [0.0, 2.0], [1.0, 1.0]])
    S = np.array([np.eye(2), np.diag([1.0, 4.0]), [[2.0, 1.0], [1.0, 2.0]]])
    # third: S⁻¹ = [[2, -1], [-1, 2]] / 3, so ν'S⁻¹ν = (2 - 1 - 1 + 2) / 3 = 2/3
    np.testing.assert_allclose(nis(y, S), [1.0, 1.0, 2.0 / 3.0], rtol=1e-12)
    assert time_averaged_nis(y, S) == pytest.approx((2.0 + 2.0 / 3.0) / 3.0, rel=1e-12)
    np.testing.assert_allclose(nis(np.array([2.0, 3.0]), np.array([4.0, 9.0])), [1.0, 1.0])
    np.testing.assert_allclose(nees(y, S), nis(y, S))


def test_autocorrelation_by_hand() -> None:
    v = np.array([1.0, -1.0, 1.0, -1.0])
    # lag 1: Σ ν(k)ν(k+1) = -3 over three pairs, each sum of squares 3 → -1; lag 2: +1
    np.testing.assert_allclose(autocorrelation(v, [1, 2]), [-1.0, 1.0])
    v2 = np.array([[1.0, 0.0], [0.0, 2.0], [1.0, 1.0]])
    # lag 1: pairs (1,0)·(0,2) + (0,2)·(1,1) = 2; Σ|a|² = 1 + 4, Σ|b|² = 4 + 2
    assert autocorrelation(v2, [1])[0] == pytest.approx(2.0 / math.sqrt(5.0 * 6.0))
    with pytest.raises(ValueError, match="lag"):
        autocorrelation(v, [4])


def test_white_noise_inside_and_ar1_outside() -> None:
    rng = np.random.default_rng(42)
    K = 2000
    lags = np.arange(1, 51)
    white = rng.standard_normal((K, 2))
    mean, var, share = autocorrelation_summary(autocorrelation(white, lags), K)
    assert share >= 0.9
    assert abs(mean) < 2.0 / math.sqrt(K)
    assert var == pytest.approx(1.0 / (2 * K), rel=0.3)  # 1/(K n_z) for n_z = 2
    ar = np.zeros(K)
    e = rng.standard_normal(K)
    for k in range(1, K):
        ar[k] = 0.9 * ar[k - 1] + e[k]
    rho = autocorrelation(ar, lags)
    assert rho[0] == pytest.approx(0.9, abs=0.03)
    assert rho[9] == pytest.approx(0.9**10, abs=0.1)
    assert autocorrelation_summary(rho, K)[2] == 0.0


def test_whitening_removes_a_varying_scale() -> None:
    rng = np.random.default_rng(1)
    n = rng.standard_normal(500)
    scale = np.linspace(0.1, 10.0, 500)
    np.testing.assert_allclose(whiten(scale * n, scale**2)[:, 0], n, rtol=1e-12)
    np.testing.assert_allclose(autocorrelation(scale * n, [1, 2], S=scale**2),
                               autocorrelation(n, [1, 2]), rtol=1e-12)


def test_summary_by_hand() -> None:
    mean, var, share = autocorrelation_summary(np.array([0.0, 0.1, -0.1, 0.3]), 100)
    assert (mean, share) == pytest.approx((0.075, 0.75))
    assert var == pytest.approx(np.var([0.0, 0.1, -0.1, 0.3]))


def test_report_on_consistent_and_inconsistent_records() -> None:
    rng = np.random.default_rng(7)
    K = 1099
    S = np.array([[0.5, 0.1], [0.1, 0.3]])
    L = np.linalg.cholesky(S)
    good = [(0.05 * k, L @ rng.standard_normal(2), S) for k in range(K)]
    report = consistency_report(good, "odo")
    assert isinstance(report, ConsistencyReport)
    assert report.nis_consistent
    assert report.band_exact == pytest.approx((1.8835, 2.1200), abs=1e-3)
    assert report.rho_share_inside > 0.9
    table = report.table()
    assert "odo" in table and "1099, 2" in table and f"{report.nis_mean:.4f}" in table
    biased = [(t, y + 1.0, s) for t, y, s in good]  # a constant bias: NIS up, innovations
    bad = consistency_report(biased, "biased")  # correlated
    assert not bad.nis_consistent and bad.nis_mean > 2.5
    assert bad.rho_mean > 0.5 and bad.rho_share_inside == 0.0
    t, y, s = stack_innovations(good)
    assert t.shape == (K,) and y.shape == (K, 2) and s.shape == (K, 2, 2)
    from_arrays = consistency_report((y, s), "odo")
    assert from_arrays.nis_mean == pytest.approx(report.nis_mean, rel=1e-12)
    with pytest.raises(ValueError, match="no innovations"):
        stack_innovations([])
