"""s_x(β), Reina Eq. 12: the piecewise model and its least-squares fit."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.estimators.reina import SlipRatioModel, fit_slip_ratio_model


def test_model_is_flat_below_beta0_and_linear_above_for_either_drift_side() -> None:
    m = SlipRatioModel(s_x0=0.1, k_per_rad=1.5, beta0_rad=math.radians(5.0))
    assert m(math.radians(3.0)) == pytest.approx(0.1)
    assert m(math.radians(15.0)) == pytest.approx(0.1 + 1.5 * math.radians(10.0))
    assert m(-math.radians(15.0)) == pytest.approx(m(math.radians(15.0)))
    np.testing.assert_allclose(m(np.radians([0.0, 5.0, 25.0])),
                               [0.1, 0.1, 0.1 + 1.5 * math.radians(20.0)])


def test_fit_recovers_known_parameters_within_their_standard_errors() -> None:
    rng = np.random.default_rng(4)
    truth = SlipRatioModel(s_x0=0.12, k_per_rad=1.1, beta0_rad=math.radians(6.0))
    beta = rng.uniform(-math.radians(25.0), math.radians(25.0), 300)
    s = truth(beta) + rng.normal(0.0, 0.01, beta.size)
    fit = fit_slip_ratio_model(beta, s)
    got = (fit.model.s_x0, fit.model.k_per_rad, fit.model.beta0_rad)
    want = (truth.s_x0, truth.k_per_rad, truth.beta0_rad)
    for g, w, e in zip(got, want, fit.std_errors, strict=True):
        assert abs(g - w) < 4.0 * e
    assert fit.model.s_x0 == pytest.approx(0.12, abs=0.005)
    assert fit.model.k_per_rad == pytest.approx(1.1, rel=0.08)
    assert math.degrees(fit.model.beta0_rad) == pytest.approx(6.0, abs=1.0)
    assert fit.rms == pytest.approx(0.01, rel=0.15)


def test_fit_is_exact_on_noise_free_samples() -> None:
    truth = SlipRatioModel(s_x0=0.05, k_per_rad=0.8, beta0_rad=0.1)
    beta = np.linspace(0.0, 0.4, 41)
    fit = fit_slip_ratio_model(beta, truth(beta))
    assert fit.model.s_x0 == pytest.approx(0.05, abs=1e-6)
    assert fit.model.k_per_rad == pytest.approx(0.8, abs=1e-5)
    assert fit.model.beta0_rad == pytest.approx(0.1, abs=1e-5)


@pytest.mark.parametrize(("kwargs", "name"), [({"s_x0": 1.2, "k_per_rad": 1.0}, "s_x0"),
                                              ({"s_x0": 0.1, "k_per_rad": np.nan}, "k_per_rad"),
                                              ({"s_x0": 0.1, "k_per_rad": 1.0,
                                                "beta0_rad": -0.1}, "beta0_rad")])
def test_bad_model_parameters_name_the_field(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        SlipRatioModel(**kwargs)


def test_fit_rejects_too_few_or_mismatched_samples() -> None:
    with pytest.raises(ValueError, match="at least 4"):
        fit_slip_ratio_model([0.1, 0.2], [0.1, 0.2])
    with pytest.raises(ValueError, match="same length"):
        fit_slip_ratio_model([0.1, 0.2, 0.3, 0.4], [0.1, 0.2])
