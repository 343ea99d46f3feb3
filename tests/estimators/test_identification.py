"""Identification of Endo's n and the slip-angle regression from synthetic rotation runs."""

import json

import numpy as np
import pytest

from slipenv.estimators.skid_steer.identification import (
    SlipAngleModel,
    evaluate,
    evaluate_runs,
    fit_endo_n,
    fit_slip_angle_regression,
    fit_slip_angle_runs,
    train_test_split_runs,
    true_slips,
)
from slipenv.estimators.skid_steer.kinematics import body_velocity
from tests.estimators import skid_steer_synth as synth

BETA_NOISE = 0.01  # [rad] motion-capture slip-angle noise


@pytest.fixture(scope="module")
def runs():
    return synth.rotation_runs(np.random.default_rng(7))


def test_fit_endo_n_recovers_n(runs):
    fit = fit_endo_n(**synth.noisy_endo_samples(runs, np.random.default_rng(11)))
    print(f"\nEndo n = {fit.n:.4f} ± {fit.std_err:.4f}, CI95 {fit.ci95}, {fit.n_samples} samples")
    assert fit.ci95[0] <= synth.N_TRUE <= fit.ci95[1]
    assert fit.n == pytest.approx(synth.N_TRUE, rel=0.02)
    assert json.loads(json.dumps(fit.to_dict()))["n_samples"] == fit.n_samples


def test_fit_endo_n_drops_ill_defined_samples():
    # Exact data plus straight-driving samples (both slips 0) and a stopped track.
    v_l = np.array([0.02, 0.05, -0.1, 0.1, 0.0, 0.04])
    v_r = np.array([0.09, 0.12, 0.1, 0.1, 0.1, 0.02])
    alpha_r = np.array([0.1, 0.05, 0.2, 0.0, 0.3, -0.2])
    alpha_l = -np.sign(v_r * v_l) * np.abs(v_r / np.where(v_l == 0, 1, v_l)) ** 0.8 * alpha_r
    fit = fit_endo_n(v_l, v_r, alpha_l, alpha_r)
    assert fit.n_samples == 4 and fit.n == pytest.approx(0.8, abs=1e-12)
    with pytest.raises(ValueError, match="usable samples"):
        fit_endo_n(v_l[3:5], v_r[3:5], alpha_l[3:5], alpha_r[3:5])
    with pytest.raises(ValueError, match="alpha_r"):
        fit_endo_n(v_l, v_r, alpha_l, alpha_r[:-1])


def test_true_slips_inverts_kinematics():
    omega_l, omega_r, r = np.array([1.0, -2.0]), np.array([3.0, 2.5]), 0.06
    truth = np.array([[0.2, -0.3, 0.1], [0.1, 0.15, -0.2]])  # rows (α_l, α_r, β)
    v_x, v_y, omega = body_velocity(r * omega_l, r * omega_r, *truth.T, 0.41)
    a_l, a_r, beta = true_slips(omega_l, omega_r, r, v_x, omega, v_y, 0.41)
    np.testing.assert_allclose(np.c_[a_l, a_r, beta], truth, rtol=0, atol=1e-12)
    with pytest.raises(ValueError, match="sprocket_radius_m"):
        true_slips(omega_l, omega_r, -0.06, v_x, omega, v_y, 0.41)
    with pytest.raises(ValueError, match="tread_m"):
        true_slips(omega_l, omega_r, r, v_x, omega, v_y, -0.41)


def test_regression_recovers_coefficients_on_held_out_runs(runs):
    rng = np.random.default_rng(12)
    train, test = train_test_split_runs(synth.slip_runs(runs, rng, BETA_NOISE), 0.25, rng)
    assert len(test) == 9 and not {r.name for r in train} & {r.name for r in test}
    model = fit_slip_angle_runs(train)
    z = (np.array(model.coef) - synth.BETA_COEF) / np.array(model.std_err)
    rmse = evaluate_runs(model, test)
    print(f"\nEq. 9 coef {np.round(model.coef, 4)}, z {np.round(z, 2)}, held-out RMSE {rmse:.4f}")
    assert np.all(np.abs(z) < 3.0)
    assert model.residual_std == pytest.approx(BETA_NOISE, rel=0.1)
    assert rmse < 1.2 * BETA_NOISE
    with pytest.raises(ValueError, match="held-out"):
        evaluate_runs(model, train[:1])
    restored = SlipAngleModel.from_dict(json.loads(json.dumps(model.to_dict())))
    assert restored == model


def test_regression_exact_data_and_validation(runs):
    features = np.vstack([r.features for r in runs])
    beta = synth.beta_law(*features.T)
    model = fit_slip_angle_regression(features, beta)
    np.testing.assert_allclose(model.coef, synth.BETA_COEF, atol=1e-10)
    assert evaluate(model, features, beta) < 1e-10
    assert model.predict(0.1, 0.5, 0.2) == pytest.approx(synth.beta_law(0.1, 0.5, 0.2))
    with pytest.raises(ValueError, match="features"):
        fit_slip_angle_regression(features[:, :2], beta)
    with pytest.raises(ValueError, match="beta"):
        fit_slip_angle_regression(features, beta[:-1])
    with pytest.raises(ValueError, match="rank"):
        fit_slip_angle_regression(np.c_[features[:, :2], np.full(len(beta), 0.3)], beta)
    with pytest.raises(ValueError, match="unknown"):
        SlipAngleModel.from_dict({**model.to_dict(), "coeff": [0, 0, 0, 0]})


def test_split_is_by_run_and_validated():
    items = list(range(10))
    a = train_test_split_runs(items, 0.3, np.random.default_rng(0))
    b = train_test_split_runs(items, 0.3, np.random.default_rng(0))
    assert a == b and len(a[1]) == 3 and sorted(a[0] + a[1]) == items
    with pytest.raises(ValueError, match="test_fraction"):
        train_test_split_runs(items, 1.0, np.random.default_rng(0))
    with pytest.raises(ValueError, match="runs"):
        train_test_split_runs(items[:1], 0.5, np.random.default_rng(0))


def test_regression_does_not_extrapolate_beyond_its_training_range(runs):
    """A circle's angular displacement reaches 2π; the paper's runs stop near π/2."""
    features = np.vstack([r.features for r in runs])
    model = fit_slip_angle_regression(features, synth.beta_law(*features.T))
    lo, hi = features.min(axis=0), features.max(axis=0)
    np.testing.assert_allclose(model.feature_range, np.c_[lo, hi])
    inside = (lo + hi) / 2
    assert model.predict(*inside) == pytest.approx(synth.beta_law(*inside))
    far = inside.copy()
    far[1] = hi[1] + 2.0 * np.pi  # one more lap
    at_edge = inside.copy()
    at_edge[1] = hi[1]
    assert model.predict(*far) == pytest.approx(synth.beta_law(*at_edge))
    unclipped = SlipAngleModel(model.coef, model.std_err, model.residual_std)  # older files
    assert unclipped.predict(*far) == pytest.approx(synth.beta_law(*far))
    with pytest.raises(ValueError, match="feature_range"):
        SlipAngleModel(model.coef, model.std_err, 0.0, feature_range=((0, 1), (1, 0), (0, 1)))
