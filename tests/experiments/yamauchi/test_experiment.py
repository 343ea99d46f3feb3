"""Endo's n as the paper identified it (every rotation run of a tilt, Yamauchi §2.4, Fig. 4)
and the n the odometry uses (training runs only), on a few short real rotation runs."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.envs.estimation import odometry_geometry
from slipenv.experiments.yamauchi import experiment
from slipenv.experiments.yamauchi.experiment import identify
from slipenv.experiments.yamauchi.rotation import collect_runs, split_runs
from slipenv.experiments.yamauchi.settings import Settings
from slipenv.experiments.yamauchi.slips import fit_n
from slipenv.vehicles.presets import tracked_patako

TILT = 8.0


@pytest.fixture(scope="module")
def identified():
    """Three 45° turns each way at 30 °/s on 8°, a third held out by run."""
    cfg = Settings(tilts_deg=(TILT,), turn_rates_dps=(30.0,), repeats=3, rotation_deg=45.0)
    rng = np.random.default_rng(0)
    train, test = split_runs(collect_runs(cfg, rng, False), cfg, rng)
    geom = odometry_geometry(tracked_patako())
    return cfg, geom, train, test, identify(cfg, train, test, geom)


def test_the_reported_n_pools_every_rotation_run_of_the_tilt(identified):
    cfg, geom, train, test, ident = identified
    assert train and test
    fit = ident["fits"][TILT]
    on_train = fit_n(train, geom, cfg.smooth_steps)[0]
    on_test = fit_n(test, geom, cfg.smooth_steps)[0]
    assert fit.n_samples == on_train.n_samples + on_test.n_samples
    assert fit.n == pytest.approx(fit_n(train + test, geom, cfg.smooth_steps)[0].n, rel=1e-12)
    assert len(ident["samples"][TILT]["v_l"]) == sum(len(r.t_s) for r in train + test)


def test_the_odometrys_n_is_fitted_on_the_training_runs_only(identified):
    cfg, geom, train, _, ident = identified
    on_train = fit_n(train, geom, cfg.smooth_steps)[0]
    assert ident["training_fits"][TILT].n == pytest.approx(on_train.n, rel=1e-12)
    assert ident["training_fits"][TILT].n_samples == on_train.n_samples
    assert ident["n_by_tilt"][TILT] == ident["training_fits"][TILT].n
    # the held-out samples move the pooled fit: the two are different measures
    assert ident["fits"][TILT].n_samples > on_train.n_samples


def test_n_by_turning_direction_pools_training_and_held_out_runs(identified):
    cfg, geom, train, test, ident = identified
    ccw = [r for r in train + test if r.direction > 0]
    expected = fit_n(ccw, geom, cfg.smooth_steps)[0].n
    assert ident["n_by_direction"][f"{TILT:g}_ccw"] == pytest.approx(expected, rel=1e-12)


def test_n_per_turning_direction_for_the_odometry_comes_from_the_training_runs_only(identified):
    """The odometry scored with Endo's n per tilt and turning direction sees no held-out run:
    each direction's n is the fit on that direction's training runs, and both directions'
    held-out runs are replayed with it."""
    cfg, geom, train, test, ident = identified
    for d, name in ((1, "ccw"), (-1, "cw")):
        on_train = fit_n([r for r in train if r.direction == d], geom, cfg.smooth_steps)[0]
        fit = ident["training_fits_by_direction"][f"{TILT:g}_{name}"]
        assert fit.n == pytest.approx(on_train.n, rel=1e-12)
        scored = ident["by_dir"][name]["n_by_direction"]
        assert {r.name for r in scored["test_runs"]} == {
            r.name for r in test if r.direction == d}
        assert not set(scored["model"].train_runs) & {r.name for r in test}


def test_the_true_slips_and_slip_angle_leave_only_the_gyros_error(identified):
    """The limits of the held-out replay: the truth in place of Endo's slips and of Eq. 9's β
    leaves a small fraction of gyrodometry's error (the gyro's heading error): 0.04 / 0.09
    counter-clockwise / clockwise in the full run, where Endo's slip ratios alone (the true β)
    leave 0.54 / 0.63 and Eq. 9's β alone (the true slips) 0.38 / 0.42."""
    ident = identified[-1]
    for entry in ident["by_dir"].values():
        lim, gyro = entry["limits_rmse_m"], entry["odometry_rmse_m"]["gyrodometry"]
        both = lim["slip_compensated_true_slips_true_beta"]
        assert both < 0.15 * gyro  # 0.05 / 0.03 here


def test_cross_validation_holds_every_run_out_once_and_pools_its_errors(identified,
                                                                         monkeypatch):
    cfg, geom, train, test, _ = identified
    runs = train + test
    seen = []
    real = experiment.score_direction

    def spy(cfg_, fit_on, held, geom_, direction, n_by_tilt):
        out = real(cfg_, fit_on, held, geom_, direction, n_by_tilt)
        names = {r.name for r in held if r.direction == direction}
        assert not names & {r.name for r in fit_on}  # never fitted on a run it scores
        seen.append((direction, names, out["squared_errors_m2"]))
        return out

    monkeypatch.setattr(experiment, "score_direction", spy)
    ratio = experiment.cross_validated_ratio(cfg, runs, geom, np.random.default_rng(1))
    assert len(seen) == cfg.cv_folds * 2
    for direction, key in ((1, "ccw"), (-1, "cw")):
        held = [name for d, names, _ in seen if d == direction for name in names]
        assert sorted(held) == sorted(r.name for r in runs if r.direction == direction)
        pooled = {k: np.concatenate([e[k] for d, _, e in seen if d == direction])
                  for k in ("slip_compensated", "gyrodometry")}
        assert ratio[key] == pytest.approx(
            np.sqrt(pooled["slip_compensated"].mean() / pooled["gyrodometry"].mean()), rel=1e-12)
