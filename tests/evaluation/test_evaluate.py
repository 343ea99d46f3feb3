"""``evaluate`` and ``slipenv evaluate`` on short tracked-slope episodes."""

from __future__ import annotations

import argparse
import json

import gymnasium as gym
import numpy as np
import pytest

from slipenv.controllers import baseline_controller
from slipenv.evaluation import evaluate_cli
from slipenv.evaluation.evaluator import evaluate
from slipenv.evaluation.trajectory import ape_translation, read_tum

from .conftest import SHORT, TRACKED


def _cli(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    evaluate_cli.add_parser(parser.add_subparsers())
    args = parser.parse_args(argv)
    return args.func(args)


def test_same_seed_gives_the_same_evaluation_bit_for_bit():
    first = evaluate("baseline", TRACKED, [3, 4], SHORT)
    again = evaluate("baseline", TRACKED, [3, 4], SHORT)
    assert json.dumps(first.to_dict()) == json.dumps(again.to_dict())
    for a, b in zip(first.traces, again.traces, strict=True):
        for x, y in zip(a.arrays(), b.arrays(), strict=True):
            np.testing.assert_array_equal(x, y)


def test_a_seeds_episode_does_not_depend_on_the_other_seeds_evaluated():
    alone = evaluate("baseline", TRACKED, [4], SHORT)
    with_other = evaluate("baseline", TRACKED, [3, 4], SHORT)
    assert alone.per_episode[0] == with_other.per_episode[1]


def test_different_seeds_give_different_episodes():
    ev = evaluate("baseline", TRACKED, [0, 1], SHORT)
    a, b = ev.per_episode
    assert a["energy_j"] != b["energy_j"]
    assert a["cross_track_rmse_m"] != b["cross_track_rmse_m"]


def test_json_document_has_the_issue_fields_and_per_episode_records():
    ev = evaluate("feedback", TRACKED, [0, 1], SHORT)
    doc = ev.to_dict()
    assert doc["policy"] == "feedback" and doc["env_id"] == TRACKED
    assert doc["episodes"] == 2 and doc["seeds"] == [0, 1]
    for key in ("cross_track_rmse_m", "mean_cross_track_m", "success_rate", "energy_j",
                "odometry_final_error_m", "odometry_mean_error_m", "ape_rmse_m",
                "rpe_rmse_m"):
        assert isinstance(doc["metrics"][key], float), key
    assert [ep["seed"] for ep in doc["per_episode"]] == [0, 1]
    # The summary is the mean over episodes; success is judged on the truth by the env.
    assert doc["metrics"]["cross_track_rmse_m"] == pytest.approx(
        np.mean([ep["cross_track_rmse_m"] for ep in doc["per_episode"]]), rel=1e-12)
    assert doc["metrics"]["success_rate"] == 1.0
    assert all(ep["end_reason"] == "path complete" for ep in doc["per_episode"])


def test_an_object_with_predict_is_evaluated_like_the_named_baseline():
    env = gym.make(TRACKED, **SHORT)
    controller = baseline_controller(env)
    env.close()
    by_object = evaluate(controller, TRACKED, [2], SHORT)
    by_name = evaluate("baseline", TRACKED, [2], SHORT)
    assert by_object.per_episode == by_name.per_episode
    assert by_object.policy == "YamauchiController"


def test_assert_below_failure_names_metric_bound_and_worst_seed():
    ev = evaluate("baseline", TRACKED, [0, 1], SHORT)
    ev.assert_below("cross_track_rmse_m", 1.0).assert_above("success_rate", 0.5)
    worst = max(ev.per_episode, key=lambda e: e["cross_track_rmse_m"])["seed"]
    with pytest.raises(AssertionError, match=rf"cross_track_rmse_m = .* is not < 0\.001 .*"
                                             rf"worst episode: seed {worst}"):
        ev.assert_below("cross_track_rmse_m", 0.001)


@pytest.mark.parametrize(("argv", "needle"), [
    (["slipenv/NoSuch-v0"], "unknown slipenv env id"),
    ([TRACKED, "--policy", "basline"], "unknown policy 'basline'"),
    ([TRACKED, "--policy", "runs/none/model.zip"], "no such model file"),
    ([TRACKED, "--env-kwargs", "{soil: 1"], "--env-kwargs: not valid JSON"),
    ([TRACKED, "--env-kwargs", '{"soyl": "loose_sand"}'], "did you mean 'soil'"),
])
def test_cli_bad_input_exits_2_with_one_line_before_any_work(argv, needle, capsys, tmp_path):
    out = tmp_path / "out"
    assert _cli(["evaluate", *argv, "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert needle in err and err.count("\n") == 1
    assert not out.exists()


def test_cli_writes_table_json_plot_and_tum_trajectories(tmp_path, capsys):
    out, js = tmp_path / "ev", tmp_path / "ev.json"
    code = _cli(["evaluate", TRACKED, "--policy", "stanley", "--episodes", "2", "--seed", "5",
                 "--env-kwargs", json.dumps(SHORT), "--json", str(js), "--out", str(out),
                 "--quiet"])
    assert code == 0
    printed = capsys.readouterr().out
    assert "stanley on slipenv/TrackedSlopeCircle-v0: 2 episodes, seeds [5, 6]" in printed
    doc = json.loads(js.read_text())
    assert doc["seeds"] == [5, 6] and doc["env_kwargs"] == SHORT
    assert (out / "evaluation.png").stat().st_size > 10_000
    t, truth = read_tum(out / "tum" / "seed_5_truth.tum")
    _, est = read_tum(out / "tum" / "seed_5_estimate.tum")
    # Re-scored from the files, APE gives back the JSON's number (evo would, unaligned).
    ape = ape_translation(est, truth)
    assert float(np.sqrt(np.mean(ape**2))) == pytest.approx(
        doc["per_episode"][0]["ape_rmse_m"], rel=1e-12)
    assert np.all(np.diff(t) > 0)
