"""Transfer as the test: geometric models fitted on whole dead-reckoned paths, replayed whole
over the held-out runs (or halves of a run), and named only when that transfer is material."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from slipenv.diagnose import horizon
from slipenv.diagnose.cli import diagnose
from slipenv.diagnose.fit import Problem
from slipenv.diagnose.kinematic import KinematicTruth, kinematic_log
from slipenv.diagnose.replay import build_segments
from slipenv.diagnose.select import MIN_DRIFT, MIN_GAIN

TRUE_WIDTH = 0.505  # nominal 0.5 m: 1 % wider


def _problem(logs):
    return Problem.from_segments(build_segments(logs))


def test_one_run_is_cut_in_halves_two_runs_in_four_and_three_runs_whole():
    logs = [kinematic_log(seed, duration_s=30.0) for seed in (1, 2, 3)]
    one, by_one = horizon.whole_parts(logs[:1])
    two, by_two = horizon.whole_parts(logs[:2])
    three, by_three = horizon.whole_parts(logs)
    assert (len(one), by_one) == (2, "half")
    assert (len(two), by_two) == (4, "half")
    assert (len(three), by_three) == (3, "run")
    # whole runs: every part starts on the run's first sample and spans it all
    assert np.all(three.start == 0)
    assert np.all(three.gt_ok.sum(axis=1) == [len(log.t) for log in logs])
    # halves: the second starts where the first ends, so together they cover the run
    assert one.start[1] == one.gt_ok[0].sum() - 1


def test_jackknife_covariance_is_the_spread_of_the_leave_one_out_fits():
    xs = np.array([[1.0, 2.0], [3.0, 2.0], [2.0, 5.0]])
    t = horizon.Transfer(("track_width",), "run", *(np.ones(3) for _ in range(6)),
                         models=[], xs=xs, yaw_before=np.ones(3), yaw_after=np.ones(3))
    d = xs - xs.mean(axis=0)
    assert np.allclose(t.jackknife_cov(), 2.0 / 3.0 * d.T @ d)
    assert t.jackknife_cov()[0, 0] == pytest.approx(2.0 / 3.0 * 2.0)


def test_motion_scales_are_the_closed_forms_of_a_wider_track_and_larger_wheels():
    from slipenv.diagnose.effects.rolling_radius import RollingRadius
    from slipenv.diagnose.effects.track_width import TrackWidth

    parts, _ = horizon.whole_parts([kinematic_log(3, duration_s=60.0)])
    part = parts.take(np.array([0]))
    # turn = (r_R Δφ_R - r_L Δφ_L) / W, distance = (r_R Δφ_R + r_L Δφ_L) / 2
    assert horizon.motion_scales(part, {"track_width": TrackWidth(0.505)}) == \
        pytest.approx([0.5 / 0.505, 1.0], rel=1e-9)
    assert horizon.motion_scales(part, {"rolling_radius": RollingRadius(0.101, 0.101)}) == \
        pytest.approx([1.01, 1.01], rel=1e-9)


def test_worse_on_half_the_parts_or_in_sum_fails_the_transfer():
    def made(after):
        n = len(after)
        return horizon.Transfer(("track_width",), "run", np.ones(n), np.array(after),
                                np.ones(n), np.zeros(n), np.ones(n), np.ones(n), models=[],
                                xs=np.zeros((n, 1)), yaw_before=np.ones(n),
                                yaw_after=np.zeros(n))

    assert made([0.1, 0.1, 0.1]).passes(MIN_GAIN, MIN_DRIFT)
    assert not made([0.1, 1.2, 1.1, 0.1]).passes(MIN_GAIN, MIN_DRIFT)  # two of four worse
    assert made([0.1, 1.2, 0.1, 0.1]).passes(MIN_GAIN, MIN_DRIFT)  # one of four worse
    assert not made([0.9, 0.9]).passes(MIN_GAIN, MIN_DRIFT)  # a 10 % gain is not material
    assert not made([0.1, 1.05]).passes(MIN_GAIN, MIN_DRIFT)  # one of two halves worse


@pytest.mark.parametrize("seed", [21, 22])
def test_a_track_width_error_transfers_between_the_halves_of_one_run(seed):
    log = kinematic_log(seed, KinematicTruth(0.1, 0.1, TRUE_WIDTH), duration_s=120.0)
    problem = _problem([log])
    parts, by = horizon.whole_parts([log])
    t = horizon.transfer(problem, parts, by, ("track_width",))
    assert t.passes(MIN_GAIN, MIN_DRIFT), t.as_dict()
    assert t.ratio < 0.2  # the model of one half removes most of the other half's drift
    fitted = horizon.fit_whole(problem, parts, ("track_width",))
    assert fitted.x[0] == pytest.approx(TRUE_WIDTH, rel=2e-3)


@pytest.mark.parametrize("seed", [31, 32, 33])
def test_on_a_clean_log_no_geometric_model_transfers(seed):
    log = kinematic_log(seed, duration_s=120.0)
    problem = _problem([log])
    parts, by = horizon.whole_parts([log])
    for effects in (("track_width",), ("track_width", "rolling_radius")):
        t = horizon.transfer(problem, parts, by, effects)
        assert not t.passes(MIN_GAIN, MIN_DRIFT), t.as_dict()


def test_a_session_is_judged_leave_one_run_out_and_its_model_fitted_on_all_paths():
    truth = KinematicTruth(0.1, 0.1, TRUE_WIDTH)
    logs = [kinematic_log(seed, truth, duration_s=60.0) for seed in (41, 42, 43)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report, _ = diagnose(logs, "<session>")
    assert report["cause"] == "track_width", report["candidates"]
    value, se = report["parameters"]["track_width_m"]
    assert abs(value - TRUE_WIDTH) < 3 * se
    tr = report["transfer"]
    assert tr["held_out_by"] == "run" and tr["parts"] == 3
    assert tr["chosen"]["effects"] == ["track_width"]
    assert max(tr["chosen"]["per_part_error_ratio"]) < 0.5  # every held-out run gains
    assert report["gain"]["evaluated_on"].startswith("held-out run replayed whole")
    assert report["gain"]["relative"] > 0.5


def test_clean_session_names_nothing_and_says_no_model_transfers():
    logs = [kinematic_log(seed, duration_s=60.0) for seed in (51, 52, 53)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report, _ = diagnose(logs, "<session>")
    assert report["cause"] == "none"
    assert report["transfer"]["decision"] == "none transfers"
    assert not any(t["error_ratio"] < 1.0 - MIN_GAIN and not t["makes_a_part_worse"]
                   for t in report["transfer"]["tested"])


def test_a_radius_error_is_not_given_a_track_width_the_held_out_halves_do_not_need():
    # right wheel 1.5 % large: the radii explain both halves; a width on top removes no
    # material drift beyond them, so parsimony keeps it out
    log = kinematic_log(61, KinematicTruth(0.1, 0.1015, 0.5), duration_s=120.0)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report, _ = diagnose([log], "<kinematic>")
    assert report["cause"] == "rolling_radius", report["candidates"]
    assert "track_width" not in report["also"]
    tested = {"+".join(t["effects"]): t for t in report["transfer"]["tested"]}
    assert tested["rolling_radius"]["transfers"]
    value, se = report["parameters"]["radius_right_m"]
    assert abs(value - 0.1015) < 3 * se + 2e-4 * 0.1015  # the allowance of test_single_log
