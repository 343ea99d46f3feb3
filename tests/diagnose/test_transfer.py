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
from slipenv.diagnose.select import (
    MIN_DRIFT,
    MIN_GAIN,
    TIE_GAIN,
    TIMES_LEFT,
    _richest_that_wins,
    _separates,
)

TRUE_WIDTH = 0.505  # nominal 0.5 m: 1 % wider


def _problem(logs):
    return Problem.from_segments(build_segments(logs))


def _three_transfers(logs):
    problem = _problem(logs)
    parts, by = horizon.whole_parts(logs)
    return [horizon.transfer(problem, parts, by, s) for s in
            (("track_width",), ("rolling_radius",), ("track_width", "rolling_radius"))]


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


def _parts(after, travel_m=1.0) -> horizon.Transfer:
    """Held-out parts with mean square error 1 before and ``after`` after (position RMSE
    1 m → √after m), each ``travel_m`` long."""
    n = len(after)
    return horizon.Transfer(("track_width",), "run", np.ones(n), np.array(after),
                            np.ones(n), np.sqrt(after), np.ones(n), np.ones(n), models=[],
                            xs=np.zeros((n, 1)), yaw_before=np.ones(n),
                            yaw_after=np.zeros(n), travel_m=travel_m)


def test_a_scale_the_held_out_parts_disagree_on_is_not_a_material_change():
    # a clean skid-steer log's halves: the width and radii fitted on each half lengthen one
    # held-out half's distance by 1.4 % and shorten the other's by 1.0 %, and remove a drift
    # of 0.1 %: no scale the halves share, so not material (the false alarm this rule ends)
    t = _parts([0.5, 0.35], travel_m=30.0)
    t.pos_after = np.full(2, 0.995)
    t.yaw_after = np.ones(2)
    t.scales = np.array([[1.0015, 0.9905], [1.0011, 1.0139]])
    assert t.scale_change() == pytest.approx(0.0022, abs=1e-4)
    assert not t.passes(MIN_GAIN, MIN_DRIFT)
    # the same size of change, the same way on both halves, is material
    t.scales = np.array([[1.0015, 1.0095], [1.0011, 1.0139]])
    assert t.scale_change() == pytest.approx(0.0117, abs=1e-4)
    assert t.passes(MIN_GAIN, MIN_DRIFT)
    # against another model, the signed difference of the two, median over the parts
    other = _parts([0.5, 0.35], travel_m=30.0)
    other.scales = np.array([[1.0, 1.0], [1.0, 1.02]])
    assert t.scale_change(other) == pytest.approx(np.median([0.0095, -0.0061]), abs=1e-6)


def test_worse_on_half_the_parts_or_in_sum_fails_the_transfer():
    assert _parts([0.1, 0.1, 0.1]).passes(MIN_GAIN, MIN_DRIFT)
    assert not _parts([0.1, 1.2, 1.1, 0.1]).passes(MIN_GAIN, MIN_DRIFT)  # two of four worse
    assert _parts([0.1, 1.2, 0.1, 0.1]).passes(MIN_GAIN, MIN_DRIFT)  # one of four worse
    assert not _parts([0.9, 0.9]).passes(MIN_GAIN, MIN_DRIFT)  # a 10 % gain is not material
    assert not _parts([0.1, 1.05]).passes(MIN_GAIN, MIN_DRIFT)  # one of two halves worse


def test_a_half_made_worse_by_less_than_a_material_drift_does_not_fail_the_transfer():
    # 1 m RMS before over 60 m; after, √1.3 m: 0.14 m more, a drift of 0.40 % of the distance
    # (under MIN_DRIFT, 0.5 %): the strict test calls it worse, the harm test does not
    t = _parts([0.1, 1.3], travel_m=60.0)
    assert t.worse and not t.materially_worse(MIN_DRIFT)
    assert t.passes(MIN_GAIN, MIN_DRIFT)
    # the same ratio over 40 m is a 0.60 % drift: material harm, no transfer
    assert not _parts([0.1, 1.3], travel_m=40.0).passes(MIN_GAIN, MIN_DRIFT)
    # however small each part's harm, worse in sum is worse
    assert _parts([1.05, 1.05], travel_m=1e6).materially_worse(MIN_DRIFT)


@pytest.mark.parametrize("seed", [21, 22])
def test_a_track_width_error_transfers_between_the_halves_of_one_run(seed):
    log = kinematic_log(seed, KinematicTruth(0.1, 0.1, TRUE_WIDTH), duration_s=120.0)
    problem = _problem([log])
    parts, by = horizon.whole_parts([log])
    t = horizon.transfer(problem, parts, by, ("track_width",))
    assert t.passes(MIN_GAIN, MIN_DRIFT), t.as_dict(MIN_DRIFT)
    assert t.ratio < 0.2  # the model of one half removes most of the other half's drift
    fitted = horizon.fit_whole(problem, parts, ("track_width",))
    assert fitted.x[0] == pytest.approx(TRUE_WIDTH, rel=2e-3)


@pytest.mark.parametrize("seed", [31, 32, 33])
def test_on_a_clean_log_no_geometric_model_transfers(seed):
    tested = _three_transfers([kinematic_log(seed, duration_s=120.0)])
    for t in tested:
        assert not t.passes(MIN_GAIN, MIN_DRIFT), t.as_dict(MIN_DRIFT)
    assert _richest_that_wins(tested) == (None, [])


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
    assert not any(t["error_ratio"] < 1.0 - MIN_GAIN and not t["makes_parts_materially_worse"]
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


def _nested(before, simpler, richer, material=False):
    before, simpler, richer = (np.asarray(a, float) for a in (before, simpler, richer))
    floor = horizon.fall_floor(before, richer, TIE_GAIN, TIMES_LEFT if material else np.inf)
    return horizon.richer_wins(before, simpler, richer, floor)


def test_a_richer_model_lower_on_every_held_out_part_beyond_the_spread_wins():
    # width 0.45 of the nominal error, width and radii 0.40, run after run: a fall of 0.05
    # of the nominal error with a spread of 0.01 is far beyond one standard error
    before = np.ones(6)
    simpler = np.array([0.45, 0.44, 0.46, 0.45, 0.47, 0.43])
    richer = simpler - np.array([0.05, 0.04, 0.06, 0.05, 0.04, 0.06])
    mean, se, lower = horizon.paired_fall(before, simpler, richer)
    assert mean == pytest.approx(0.05) and lower == 6
    assert se == pytest.approx(np.std([0.05, 0.04, 0.06, 0.05, 0.04, 0.06], ddof=1) / np.sqrt(6))
    assert _nested(before, simpler, richer)


def test_a_richer_model_lower_in_sum_but_on_half_the_parts_loses():
    assert not _nested(np.ones(4), [0.5, 0.5, 0.5, 0.5], [0.1, 0.1, 0.6, 0.6])


def test_a_richer_model_lower_on_most_parts_but_within_its_uncertainty_loses():
    # three small falls and one large one against a large loss: in sum and on most parts
    # lower, but the mean fall (0.044) is below its standard error (about 0.15)
    d = np.array([0.02, 0.02, 0.02, -0.4, 0.56])
    simpler = np.ones(5)
    mean, se, lower = horizon.paired_fall(np.ones(5), simpler, simpler - d)
    assert lower == 4 and 0 < mean < se
    assert not _nested(np.ones(5), simpler, simpler - d)


def test_two_fits_that_both_leave_only_noise_tie_whatever_the_ratio_of_their_residuals():
    # a richer model that changes neither the distance nor the turn (not material) removes
    # 80 % of what the simpler leaves, on both halves, but that is 0.08 % of the nominal
    # error: below the tie floor, the simpler stays
    before = np.ones(2)
    simpler = np.array([1e-3, 1e-3])
    assert not _nested(before, simpler, 0.2 * simpler)
    assert _nested(before, 100 * simpler, 20 * simpler)  # the same ratio at 8 % wins


def test_a_material_fall_many_times_what_the_richer_model_leaves_wins_below_the_nominal_floor():
    # a turn-scale error makes the nominal error large: the width alone leaves 0.05 % of
    # it, the radii (a distance scale too) 0.002 %, on both halves. The fall is 0.05 % of
    # the nominal error, below the 1 % floor, but 20 times what the radii leave
    before = np.ones(2)
    simpler = np.array([5.0e-4, 5.8e-4])
    richer = np.array([1.5e-5, 3.1e-5])
    floor = horizon.fall_floor(before, richer, TIE_GAIN, TIMES_LEFT)
    assert floor == pytest.approx(TIMES_LEFT * 2.3e-5)
    assert _nested(before, simpler, richer, material=True)
    # the same numbers from a richer model that changes nothing material: noise, it ties
    assert not _nested(before, simpler, richer, material=False)
    # a fall of less than TIMES_LEFT times what the richer model leaves ties as well
    assert not _nested(before, simpler, simpler / (TIMES_LEFT + 0.9), material=True)
    assert _nested(before, simpler, simpler / (TIMES_LEFT + 1.1), material=True)
    # where the richer model leaves much, the nominal floor is the smaller one and decides
    assert horizon.fall_floor(before, np.array([0.4, 0.4]), TIE_GAIN, TIMES_LEFT) == TIE_GAIN


def test_a_distance_scale_on_a_one_way_circle_names_the_radii_not_the_width():
    # right wheel 1.5 % larger on a circle driven one way: the width alone takes the turn
    # (the ratio and the width are not separable there) but not the 0.75 % longer distance,
    # a fall of many times what the radii leave on both halves, far below 1 % of the
    # nominal error (the turn error dominates it)
    truth = KinematicTruth(0.1, 0.1015, 0.5)
    log = kinematic_log(3, truth, duration_s=60.0, route="circle")
    tested = _three_transfers([log])
    width, radii, _ = tested
    assert width.passes(MIN_GAIN, MIN_DRIFT)
    best, versus = _richest_that_wins(tested)
    assert best is radii, versus
    assert versus[0]["material"] and versus[0]["mean_fall"] < TIE_GAIN
    assert np.allclose(radii.xs, [truth.radius_left_m, truth.radius_right_m], rtol=2e-3)


def test_on_a_width_only_one_way_circle_the_radii_do_not_replace_the_width():
    # there the radius ratio and the mean radius reproduce the width's turn exactly: no
    # distance left to explain, so the radii fit noise and the width stays
    log = kinematic_log(3, KinematicTruth(0.1, 0.1, TRUE_WIDTH), duration_s=60.0, route="circle")
    best, versus = _richest_that_wins(_three_transfers([log]))
    assert best is not None and best.effects == ("track_width",), versus


def test_the_fall_is_judged_on_the_nominal_models_mean_error_not_each_parts_own():
    # the first half the nominal model predicts almost exactly: the 0.0009 the simpler model
    # leaves there is noise, and its fall to 0.0002 is 78 % of that half's own nominal
    # error but 0.5 % of the mean one; with the other half's 0.4 %, the models tie
    before = np.array([0.01, 0.29])
    simpler, richer = np.array([0.0009, 0.0016]), np.array([0.0002, 0.001])
    mean, se, lower = horizon.paired_fall(before, simpler, richer)
    assert mean == pytest.approx(0.5 * (0.0007 + 0.0006) / 0.15) and lower == 2
    assert se == pytest.approx(0.5 * (0.0007 - 0.0006) / 0.15)
    # (on each half's own scale the mean fall would be 3.6 %, above the floor)
    assert not _nested(before, simpler, richer)


def test_on_a_radius_only_log_the_width_does_not_join_the_radii():
    # the width fitted beside the radii lowers the held-out error on both halves of this
    # log, by a sliver (it fits what is left: noise), far below the tie floor
    log = kinematic_log(5, KinematicTruth(0.1, 0.1015, 0.5), duration_s=120.0)
    best, versus = _richest_that_wins(_three_transfers([log]))
    assert best is not None and best.effects == ("rolling_radius",), versus


def test_on_a_width_only_log_the_radii_do_not_join_the_width():
    # the radii fitted beside the width lower the held-out error on both halves of this
    # log, by 0.7 % of the mean nominal error: below the tie floor, though on the first
    # half's own nominal error, which is 3 % of the second's, the fall is 5.6 %
    log = kinematic_log(16, KinematicTruth(0.1, 0.1, TRUE_WIDTH), duration_s=120.0)
    best, versus = _richest_that_wins(_three_transfers([log]))
    assert best is not None and best.effects == ("track_width",), versus


def test_radii_that_change_no_distance_do_not_join_the_width_however_much_they_cut_its_residue():
    # on this width-only log the width and radii (radii within 0.01 % of nominal) leave a
    # sixth of what the width alone leaves on both halves: a re-split of the same geometry,
    # not material, so only the nominal floor could admit it and it does not
    log = kinematic_log(7, KinematicTruth(0.1, 0.1, TRUE_WIDTH), duration_s=120.0)
    best, versus = _richest_that_wins(_three_transfers([log]))
    assert best is not None and best.effects == ("track_width",), versus
    (v,) = [v for v in versus if len(v["richer"]) == 2]
    assert v["lower_on_parts"] == 2 and not v["material"] and v["floor"] == TIE_GAIN


def test_radii_that_every_held_out_run_confirms_are_named_though_below_the_material_drift():
    # wheels 0.4 % large (a distance scale below the 0.5 % a cause must reach alone) and a
    # 1 % wider track: leave-one-run-out, the radii lower every held-out run's path error
    radius = 0.1 * 1.004
    truth = KinematicTruth(radius, radius, TRUE_WIDTH)
    logs = [kinematic_log(seed, truth, duration_s=60.0) for seed in (20, 21, 22)]
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        report, _ = diagnose(logs, "<session>")
    assert report["cause"] == "track_width", report["candidates"]
    assert report["also"] == ["rolling_radius"], report["transfer"]
    tr = report["transfer"]
    (v,) = tr["versus"]
    assert v["richer_wins"] and v["lower_on_parts"] == 3
    assert v["mean_fall"] > max(v["standard_error"], TIE_GAIN)
    for side in ("left", "right"):
        value, se = report["parameters"][f"radius_{side}_m"]
        assert abs(value - radius) < 3 * se + 2e-4 * radius
        assert abs(value / 0.1 - 1.0) < MIN_DRIFT  # the distance it changes is not material
    value, se = report["parameters"]["track_width_m"]
    assert abs(value - TRUE_WIDTH) < 3 * se + 2e-4 * TRUE_WIDTH


def _made(effects, after):
    n = len(after)
    return horizon.Transfer(effects, "half", np.ones(n), np.array(after, float), np.ones(n),
                            np.zeros(n), np.ones(n), np.ones(n), models=[],
                            xs=np.zeros((n, 1)), yaw_before=np.ones(n), yaw_after=np.zeros(n))


def test_where_the_held_out_paths_tie_the_radii_the_segments_named_stay_against_the_width():
    # the width and the radii are not nested: on paths that do not tell them apart, the
    # width replaces the named radii only by beating them, and the width and radii together
    # only by beating the radii
    width = _made(("track_width",), [0.16, 0.05])
    radii = _made(("rolling_radius",), [0.11, 0.05])
    both = _made(("track_width", "rolling_radius"), [0.11, 0.052])
    kept, versus = _richest_that_wins([width, radii, both], {"rolling_radius"})
    assert kept is radii
    assert [v["simpler"] for v in versus] == [["rolling_radius"], ["rolling_radius"]]
    # nothing named: the fewest parameters come first, and the radii do not beat the width
    # on one half of two
    assert _richest_that_wins([width, radii, both])[0] is width
    # the richer model lower by 0.05 of the nominal error on both halves is kept
    better = _made(("track_width", "rolling_radius"), [0.06, 0.0])
    assert _richest_that_wins([width, radii, better], {"rolling_radius"})[0] is better


def test_a_circle_driven_one_way_does_not_separate_the_radius_ratio_from_the_width():
    # so there the width, fewer parameters, is tried before radii the segments named
    circle = kinematic_log(3, KinematicTruth(0.1, 0.1015, 0.5), duration_s=60.0, route="circle")
    mixed = kinematic_log(3, KinematicTruth(0.1, 0.1015, 0.5), duration_s=60.0)
    assert not _separates(_problem([circle]))
    assert _separates(_problem([mixed]))
