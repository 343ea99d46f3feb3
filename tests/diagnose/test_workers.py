"""``slipenv.diagnose.workers``: the diagnosis's fits on worker processes, with the same
outcome bit for bit as in one process."""

from __future__ import annotations

import dataclasses
import json
import multiprocessing
import os
import pickle
import warnings

import numpy as np
import pytest
from threadpoolctl import threadpool_info

from slipenv.cli import main as slipenv_main
from slipenv.diagnose import select as selection
from slipenv.diagnose import workers
from slipenv.diagnose.cli import diagnose
from slipenv.diagnose.effects import EFFECTS
from slipenv.diagnose.fit import Problem, layout, unpack
from slipenv.diagnose.kinematic import KinematicTruth, kinematic_log
from slipenv.diagnose.replay import build_segments


def _diagnose(log, jobs: int) -> dict:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return diagnose([log], "<kinematic>", jobs=jobs)[0]


def test_a_diagnosis_on_two_worker_processes_is_the_one_of_one_process_bit_for_bit(
        traced_radius_diagnosis, monkeypatch):
    # right wheel 1.5 % larger, with a torque column: every effect is tried, soil maps
    # included, and forward selection fits joint models (the one-process diagnosis is shared)
    one = traced_radius_diagnosis.report
    steps = []
    step = selection._step
    monkeypatch.setattr(selection, "_step", lambda *a: steps.append(list(a[5])) or step(*a))
    two = _diagnose(traced_radius_diagnosis.log, 2)
    assert one["cause"] == "rolling_radius"
    tried = {c["cause"] for c in one["candidates"] if c.get("untestable") is None}
    assert {"soil_map", "soil_patch", "torque_slip"} <= tried
    assert steps and steps == traced_radius_diagnosis.joined and "soil_map" in steps[0]
    assert json.dumps(one, default=repr) == json.dumps(two, default=repr)
    assert not multiprocessing.active_children()  # the workers ended with the diagnosis


def test_every_effects_parameters_cross_to_a_worker_process_and_back():
    log = kinematic_log(31, KinematicTruth(0.1, 0.1015, 0.5), duration_s=30.0, with_torque=True)
    seg = build_segments([log])
    for name in EFFECTS:
        params = unpack((name,), [b.start for _, b in layout((name,), seg)])
        assert pickle.loads(pickle.dumps(params)) == params, name


def test_the_diagnosis_runs_blas_on_one_thread_and_restores_it_after():
    before = [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]
    with workers.Workers(2):
        inside = [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"]
    assert inside and set(inside) == {1}
    assert [p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"] == before


def test_a_failing_fit_reaches_the_caller_from_a_worker_and_no_worker_is_left():
    log = kinematic_log(31, KinematicTruth(0.1, 0.1015, 0.5), duration_s=30.0)
    problem = Problem.from_segments(build_segments([log]))
    with workers.Workers(2) as pool:
        failing = pool.fit(problem, ("no_such_effect",))
        with pytest.raises(ValueError, match="unknown effect 'no_such_effect'"):
            failing.result()
        good = pool.fit(problem, ("track_width",)).result()
    assert not multiprocessing.active_children()
    inline = workers.INLINE.fit(problem, ("track_width",)).result()
    np.testing.assert_array_equal(good.x, inline.x)


@pytest.mark.parametrize("jobs", [0, -1, 1.5, True, "2", None])
def test_a_worker_count_that_is_not_a_whole_number_of_at_least_one_is_refused(jobs):
    with pytest.raises(ValueError, match="jobs must be a whole number"):
        workers.Workers(jobs)


def test_the_command_line_refuses_zero_jobs_naming_the_option(tmp_path, capsys):
    assert slipenv_main(["diagnose", str(tmp_path), "--jobs", "0"]) == 2
    assert "--jobs: must be >= 1, got 0" in capsys.readouterr().err


def _killed(*args) -> None:
    os._exit(9)  # as the kernel's out-of-memory killer would end a worker


def test_a_worker_process_that_dies_is_a_clear_error_naming_the_way_out(monkeypatch):
    from slipenv.diagnose.cli import DiagnosisError

    log = kinematic_log(31, KinematicTruth(0.1, 0.1015, 0.5), duration_s=30.0)
    # the workers are forked after this, so they run the patched fit: killed mid-diagnosis
    monkeypatch.setattr(workers, "fit", _killed)
    with pytest.raises(DiagnosisError, match="<kinematic>: a worker process .* --jobs 1"):
        _diagnose(log, 2)
    assert not multiprocessing.active_children()


def test_the_python_entry_refuses_a_bad_worker_count_before_any_work():
    with pytest.raises(ValueError, match="jobs must be a whole number"):
        diagnose([], "<nothing>", jobs=0)


def test_a_fit_whose_inputs_do_not_pickle_runs_here_with_a_warning_and_the_same_result():
    from slipenv.diagnose.effects.track_width import TrackWidth

    @dataclasses.dataclass(frozen=True)
    class LocalWidth(TrackWidth):  # defined in a function: pickle cannot find it
        pass

    log = kinematic_log(31, KinematicTruth(0.1, 0.1015, 0.5), duration_s=30.0)
    problem = Problem.from_segments(build_segments([log]))
    start = {"track_width": LocalWidth(0.51)}
    with workers.Workers(2) as pool, pytest.warns(RuntimeWarning, match="track_width runs"):
        here = pool.fit(problem, ("track_width",), None, start).result()
    np.testing.assert_array_equal(
        here.x, workers.INLINE.fit(problem, ("track_width",), None, start).result().x)
