"""Slip-compensated odometry (Yamauchi Eq. 1-10) against gyrodometry and Endo on a side slope."""

import math
from dataclasses import replace

import numpy as np
import pytest

from slipenv.estimators.base import Estimator
from slipenv.estimators.gyrodometry import Gyrodometry
from slipenv.estimators.skid_steer.endo import EndoOdometry
from slipenv.estimators.skid_steer.identification import (
    SlipAngleModel,
    fit_endo_n,
    fit_slip_angle_runs,
)
from slipenv.estimators.skid_steer.yamauchi import (
    SlipCompensatedOdometry,
    next_angular_displacement,
    rotation_radius_m,
)
from tests.estimators import skid_steer_synth as synth

GEOM = synth.GEOMETRY
EXACT = SlipAngleModel(coef=synth.BETA_COEF, std_err=(0.0,) * 4, residual_std=0.0)


@pytest.fixture(scope="module")
def trained():
    """Endo's n and the Eq. 9 model identified from the synthetic rotation runs (§2.3).

    The synthetic world obeys Eq. 9 at every angular displacement, so here the fitted model may
    extrapolate to the circle's 2π (no ``feature_range`` clip); a real slope does not.
    """
    rng = np.random.default_rng(21)
    runs = synth.rotation_runs(rng)
    fit = fit_endo_n(**synth.noisy_endo_samples(runs, rng))
    model = fit_slip_angle_runs(synth.slip_runs(runs, rng, 0.01))
    return fit.n, replace(model, feature_range=None)


@pytest.mark.parametrize("seed", [31, 32, 33])
def test_side_slope_circle_beats_gyrodometry(trained, seed):
    # Held-out run: the paper's r = 0.25 m circle at 5 cm/s on a 15° slope, one loop.
    n, model = trained
    circle = synth.simulate_run(0.05, 0.2, 0.8, math.radians(15.0), 0.0, 2 * math.pi / 0.16,
                                np.random.default_rng(seed))
    rmse = {}
    for name, est in (
        ("gyro", Gyrodometry(GEOM)),
        ("endo", EndoOdometry(GEOM, n)),
        ("yamauchi", SlipCompensatedOdometry(GEOM, n, model)),
    ):
        xy, estimates = synth.run_estimator(est, circle)
        rmse[name] = synth.position_rmse(xy, circle)
    print(f"\nposition RMSE [m] {rmse}, improvement {1 - rmse['yamauchi'] / rmse['gyro']:.1%}")
    assert rmse["yamauchi"] <= 0.4 * rmse["gyro"]
    assert rmse["yamauchi"] < rmse["endo"] < rmse["gyro"]
    beta_hat = np.array([e.slip_angle_rad for e in estimates[1:]])
    assert np.sqrt(np.mean((beta_hat - circle.beta[1:]) ** 2)) < 0.01  # fed forward to control


def test_online_features_match_the_paper_definitions():
    # Noise-free sensors, exact n and model: the estimator's regressors are the true ones.
    run = synth.simulate_run(0.05, -0.3, 0.7, math.radians(8.0), 0.5, 4.0, np.random.default_rng(0),
                             gyro_std=0.0, roll_std=0.0)
    _, est = synth.run_estimator(SlipCompensatedOdometry(GEOM, synth.N_TRUE, EXACT), run)
    extras = np.array([[e.extras[k] for k in ("roll_rad", "angular_displacement_rad",
                                              "rotation_radius_m")] for e in est[1:]])
    np.testing.assert_allclose(extras, run.features[1:], atol=3e-3)  # encoder quantisation
    np.testing.assert_allclose([e.slip_angle_rad for e in est[1:]], run.beta[1:], atol=1e-3)


def test_straight_driving_does_not_blow_up():
    rng = np.random.default_rng(4)
    frames = synth.constant_frames(0.1, 0.1, 0.0, n=300)
    frames = [replace(f, gyro_z_rad_s=0.003 * rng.standard_normal(), roll_rad=0.2) for f in frames]
    est = synth.feed(SlipCompensatedOdometry(GEOM, 0.824, EXACT), frames)
    last = est[-1]
    assert all(math.isfinite(e.x_m) and math.isfinite(e.slip_angle_rad) for e in est)
    assert all(e.extras["angular_displacement_rad"] == 0.0 for e in est)
    assert all(e.extras["rotation_radius_m"] == 1.0 for e in est)
    beta = synth.beta_law(0.2, 0.0, 1.0)  # constant crab angle of straight driving on this model
    assert last.slip_angle_rad == pytest.approx(beta)
    assert math.hypot(last.x_m, last.y_m) == pytest.approx(1.5 / math.cos(beta), rel=1e-3)


def test_slip_angle_is_clipped():
    wild = SlipAngleModel(coef=(10.0, 0.0, 0.0, 0.0), std_err=(0.0,) * 4, residual_std=0.0)
    est = synth.feed(SlipCompensatedOdometry(GEOM, 0.824, wild, max_slip_angle_rad=0.5),
                     synth.constant_frames(0.1, 0.1, 0.0, n=5))
    assert est[-1].slip_angle_rad == 0.5


def test_rotation_radius_closed_forms():
    # The paper's 5 cm/s at 10 °/s is a 0.286 m radius; straight -> clip; at rest -> 0.
    assert rotation_radius_m(0.05, math.radians(10.0), 1.0) == pytest.approx(0.2865, abs=1e-4)
    assert rotation_radius_m(-0.05, 0.25, 1.0) == pytest.approx(0.2)
    radii = rotation_radius_m([0.05, 0.0, 0.0], [0.0, 0.3, 0.0], 1.0)
    np.testing.assert_array_equal(radii, [1.0, 0.0, 0.0])
    with pytest.raises(ValueError, match="max_radius_m"):
        rotation_radius_m(0.05, 0.1, -1.0)


def test_angular_displacement_restarts():
    assert next_angular_displacement(0.5, 0.1, 0.2, 0.02) == pytest.approx(0.6)
    assert next_angular_displacement(0.5, -0.1, -0.2, 0.02) == pytest.approx(-0.1)  # reversal
    assert next_angular_displacement(0.5, 0.001, 0.01, 0.02) == 0.0  # straight
    assert next_angular_displacement(0.5, -0.1, -0.2, None) == pytest.approx(0.4)


def test_validation():
    assert isinstance(SlipCompensatedOdometry(GEOM, 0.824, EXACT), Estimator)
    with pytest.raises(ValueError, match="beta_model"):
        SlipCompensatedOdometry(GEOM, 0.824, synth.BETA_COEF)
    with pytest.raises(ValueError, match="n must"):
        SlipCompensatedOdometry(GEOM, float("nan"), EXACT)
    with pytest.raises(ValueError, match="max_slip_angle_rad"):
        SlipCompensatedOdometry(GEOM, 0.824, EXACT, max_slip_angle_rad=2.0)
    with pytest.raises(ValueError, match="straight_yaw_rate_rps"):
        SlipCompensatedOdometry(GEOM, 0.824, EXACT, straight_yaw_rate_rps=-1.0)
    frames = synth.constant_frames(0.1, 0.1, 0.0, n=3)
    est = SlipCompensatedOdometry(GEOM, 0.824, EXACT)
    est.reset(0.0, 0.0, 0.0, frames[0])
    with pytest.raises(ValueError, match="frame.roll_rad"):
        est.update(replace(frames[1], roll_rad=float("nan")))
    est.update(frames[2])
    with pytest.raises(ValueError, match="out of order"):
        est.update(frames[1])
