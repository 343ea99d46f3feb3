"""Bad input on the command line: status 2, one line naming the problem, before any work."""

from __future__ import annotations

import argparse

import pytest

from slipenv.cli import SUBCOMMANDS, build_parser, main

ENV = "slipenv/HuskySand-v0"


@pytest.fixture
def no_work(monkeypatch):
    """Every long-running entry point fails the test if it is reached."""

    def forbidden(*args, **kwargs):
        raise AssertionError("long work started before the input was checked")

    import slipenv.agents.train
    import slipenv.bench
    import slipenv.experiments
    import slipenv.run

    monkeypatch.setattr(slipenv.run, "run_episode", forbidden)
    monkeypatch.setattr(slipenv.bench, "run_bench", forbidden)
    monkeypatch.setattr(slipenv.agents.train, "train", forbidden)
    monkeypatch.setattr(slipenv.experiments, "experiment", forbidden)


def one_line_error(capsys, argv: list[str], *needles: str) -> str:
    assert main(argv) == 2, argv
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert "Traceback" not in captured.err and captured.out == ""
    for needle in needles:
        assert needle in lines[0], (needle, lines[0])
    return lines[0]


@pytest.mark.parametrize("argv", [
    ["run", "slipenv/Nope-v0"],
    ["bench", "slipenv/Nope-v0"],
    ["bench", ENV, "slipenv/Nope-v0"],
    ["train", "slipenv/Nope-v0"],
])
def test_an_unknown_env_id_is_one_line_with_the_registered_ids(no_work, capsys, argv):
    line = one_line_error(capsys, argv, "unknown env id 'slipenv/Nope-v0'")
    assert "slipenv/HuskySand-v0" in line  # lists what is registered


def test_a_near_miss_env_id_gets_a_suggestion(no_work, capsys):
    one_line_error(capsys, ["run", "slipenv/HuskySnd-v0"], "did you mean 'slipenv/HuskySand-v0'")


@pytest.mark.parametrize("argv, option", [
    (["run", ENV, "--seed", "-1"], "--seed"),
    (["run", ENV, "--max-steps", "0"], "--max-steps"),
    (["run", ENV, "--max-steps", "-3"], "--max-steps"),
    (["run", ENV, "--max-steps", "ten"], "--max-steps"),
    (["bench", ENV, "--steps", "0"], "--steps"),
    (["bench", ENV, "--repeats", "-2"], "--repeats"),
    (["train", ENV, "--timesteps", "0"], "--timesteps"),
    (["train", ENV, "--timesteps", "-100"], "--timesteps"),
    (["train", ENV, "--seed", "-1"], "--seed"),
    (["train", ENV, "--n-envs", "0"], "--n-envs"),
    (["train", ENV, "--episodes", "0"], "--episodes"),
    (["train", ENV, "--algo", "dqn"], "--algo"),
    (["reproduce", "yamauchi", "--seed", "-1"], "--seed"),
    (["diagnose", ".", "--seed", "-5"], "--seed"),
])
def test_a_bad_number_or_choice_names_its_option(no_work, capsys, argv, option):
    one_line_error(capsys, argv, option)


def test_an_unknown_experiment_or_missing_log_folder_is_one_line(no_work, capsys, tmp_path):
    one_line_error(capsys, ["reproduce", "nonsense"], "unknown experiment 'nonsense'")
    one_line_error(capsys, ["diagnose", str(tmp_path / "missing")], "no such log folder")


@pytest.mark.parametrize("argv, needles", [
    (["reproduce", "yamauchi", "--vehicle", "husky"],
     ("--vehicle", "unknown tracked vehicle 'husky'", "tracked_patako_wong_chiang")),
    (["reproduce", "yamauchi", "--soil", "mud"], ("--soil", "unknown soil 'mud'", "dry_sand")),
    (["reproduce", "lindgren", "--soil", "dry_sand"], ("--soil only applies to yamauchi",)),
    (["reproduce", "reina", "--vehicle", "tracked_patako_wong_chiang", "--soil", "dry_sand"],
     ("--vehicle and --soil only apply to yamauchi", "not reina")),
    (["reproduce", "yamauchi", "--soil", "dry_sand", "--save-model", "m.json"],
     ("--save-model",)),
])
def test_a_world_the_experiment_cannot_run_is_one_line_before_the_work(no_work, capsys, tmp_path,
                                                                        argv, needles):
    one_line_error(capsys, argv + ["--out", str(tmp_path / "out")], *needles)
    assert not (tmp_path / "out").exists()


@pytest.fixture
def blocked(tmp_path):
    """A path nothing can be written under, even as root: its parent is a file."""
    wall = tmp_path / "a_file"
    wall.write_text("not a folder")
    return wall / "out"


@pytest.mark.parametrize("argv, option", [
    (["run", ENV, "--out", "{blocked}"], "--out"),
    (["run", ENV, "--json", "{blocked}/m.json"], "--json"),
    (["bench", ENV, "--json", "{blocked}/b.json"], "--json"),
    (["train", ENV, "--out", "{blocked}"], "--out"),
    (["reproduce", "yamauchi", "--out", "{blocked}"], "--out"),
    (["reproduce", "yamauchi", "--json", "{blocked}/r.json"], "--json"),
])
def test_an_unwritable_output_fails_before_the_work(no_work, capsys, blocked, argv, option):
    argv = [a.format(blocked=blocked) for a in argv]
    one_line_error(capsys, argv, option, "cannot write there")


def test_a_folder_given_as_a_json_file_is_refused(no_work, capsys, tmp_path):
    one_line_error(capsys, ["run", ENV, "--json", str(tmp_path)], "--json", "is a folder")


def test_a_bad_hyperparameter_file_fails_before_training(no_work, capsys, tmp_path):
    bad = tmp_path / "ppo.yml"
    bad.write_text(f"{ENV}:\n  n_timesteps: 1000\n  learnin_rate: 0.1\n")
    one_line_error(capsys, ["train", ENV, "--hyperparams", str(bad)],
                   "'learnin_rate' is not a PPO argument", "did you mean 'learning_rate'")


def subparsers() -> dict[str, argparse.ArgumentParser]:
    parser = build_parser()
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return dict(action.choices)


def test_every_subcommand_is_in_the_dispatch_table_and_every_option_shows_help_and_default():
    parsers = subparsers()
    assert set(parsers) == set(SUBCOMMANDS)
    for name, parser in parsers.items():
        text = parser.format_help()
        for action in parser._actions:
            if isinstance(action, argparse._HelpAction):
                continue
            assert action.help, f"{name} {action.dest} has no help text"
            if action.option_strings and not action.required:
                assert action.default is not argparse.SUPPRESS
                assert f"(default: {action.default})" in " ".join(text.split()), \
                    f"{name} {action.option_strings[0]} does not show its default"


def test_every_option_states_its_default_once_and_a_required_one_shows_none():
    for name, parser in subparsers().items():
        formatter = parser._get_formatter()
        for action in parser._actions:
            if not action.option_strings or isinstance(action, argparse._HelpAction):
                continue
            shown = " ".join(formatter._expand_help(action).split())
            where = f"{name} {action.option_strings[0]}: {shown}"
            assert shown.lower().count("default") == (0 if action.required else 1), where


def test_evaluate_help_prints_each_default_once(capsys):
    assert main(["evaluate", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert text.count("(default: baseline)") == 1 and "(default baseline)" not in text
    assert "(default: runs/evaluate/{env}_{policy})" in text


def test_the_advertised_controllers_are_exactly_the_accepted_ones(capsys, tmp_path):
    from slipenv.controllers.baseline import BASELINE_NAMES
    from slipenv.evaluation.policies import BUILTIN_POLICIES

    run = subparsers()["run"]
    action = next(a for a in run._actions if a.dest == "controller")
    # the controllers, and `slipenv evaluate --policy`'s names for the same ones
    assert set(action.choices) == set(BASELINE_NAMES) | set(BUILTIN_POLICIES)
    help_text = " ".join(run.format_help().split())
    assert "{" + ",".join(action.choices) + "}" in help_text
    for name in action.choices:  # each one advertised is accepted and drives the env
        assert main(["run", ENV, "--controller", name, "--max-steps", "5", "--quiet",
                     "--out", str(tmp_path / name)]) == 0
        assert f"controller {BUILTIN_POLICIES.get(name, name)}" in capsys.readouterr().out
    one_line_error(capsys, ["run", ENV, "--controller", "mpc"], "--controller", "invalid choice")


def test_version_is_printed(capsys):
    from importlib.metadata import version

    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"slipenv {version('slipenv')}"
