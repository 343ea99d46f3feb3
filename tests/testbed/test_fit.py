"""Fitting the force laws to virtual test-bed data: known parameters back, wrong laws named."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.terramechanics.presets import LUNAR_SIMULANT
from slipenv.testbed.csv_format import read_testbed
from slipenv.testbed.fit import fit_law, fitted_names, heldout_rmse
from slipenv.testbed.report import analyse
from tests.testbed.conftest import NOISE_N


@pytest.fixture(scope="module")
def reina_report(reina_bed_dir):
    return analyse(read_testbed(reina_bed_dir), LUNAR_SIMULANT)


def test_reina_parameters_are_recovered_within_3_standard_errors(reina_report):
    report, _ = reina_report
    params = report["laws"]["reina"]["parameters"]
    for name, (value, se) in params.items():
        truth = getattr(LUNAR_SIMULANT, name)
        assert se > 0.0 and abs(value - truth) < 3.0 * se, (name, value, se, truth)
    # mu, C_x, C_y are well determined; A_x, A_y (high-slip slopes) barely at s <= 0.6.
    for name in ("mu", "c_x_n", "c_y_n"):
        assert params[name][1] < 0.1 * getattr(LUNAR_SIMULANT, name), name


def test_the_generating_law_predicts_best_and_within_the_noise(reina_report):
    report, _ = reina_report
    assert report["best"] == "reina"
    assert report["law_is_adequate"]
    assert report["heldout_over_noise"] < 1.5
    rmse = report["laws"]["reina"]["heldout_rmse_n"]
    assert rmse["fx"] < 1.5 * NOISE_N and rmse["fy"] < 1.5 * NOISE_N


def test_janosi_parameters_are_recovered_within_3_standard_errors(janosi_bed_dir):
    data = read_testbed(janosi_bed_dir)
    # One load: c and tan(phi) enter only as A c + W tan(phi), so cohesion stays the base's.
    assert fitted_names("janosi", data) == ("friction_angle_rad", "shear_modulus_m")
    fit = fit_law("janosi", data, LUNAR_SIMULANT)
    for name, (value, se) in fit.parameters().items():
        assert abs(value - getattr(LUNAR_SIMULANT, name)) < 3.0 * se, name


def test_a_law_fitted_to_another_laws_data_is_called_wrong(janosi_bed_dir):
    """Reina's law fitted to Janosi data: not just bad parameters, a named shape misfit."""
    report, _ = analyse(read_testbed(janosi_bed_dir), LUNAR_SIMULANT)
    assert report["best"] == "janosi"
    reina = report["laws"]["reina"]
    assert reina["misfit"]["systematic"]
    assert reina["heldout_over_noise"] > 5.0
    assert any("F_x" in f for f in reina["misfit"]["findings"])


def test_data_with_a_traction_peak_make_the_best_law_wrong_and_name_the_peak(peaked_bed_dir):
    report, _ = analyse(read_testbed(peaked_bed_dir), LUNAR_SIMULANT)
    assert not report["law_is_adequate"]
    assert "law is wrong" in report["verdict"]
    assert "a peak the law cannot make" in report["verdict"]
    assert report["heldout_over_noise"] > 3.0


def test_heldout_error_needs_two_trials(reina_bed_dir):
    data = read_testbed(reina_bed_dir)
    with pytest.raises(ValueError, match="unknown law 'pacejka'"):
        fit_law("pacejka", data, LUNAR_SIMULANT)
    assert np.isfinite(heldout_rmse("linear", data, LUNAR_SIMULANT, folds=3)["fx"])
