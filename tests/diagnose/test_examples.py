"""``slipenv diagnose --example``: the shipped logs diagnose from a clone or a pip install."""

from __future__ import annotations

import json

import pytest

import slipenv.cli
from slipenv.logs import read_log
from slipenv.logs.examples import path


def run(*argv) -> int:
    return slipenv.cli.main(["diagnose", *map(str, argv), "--quiet", "--jobs", "1"])


def test_diagnosis_of_the_generated_example_names_its_hidden_effect(tmp_path, capsys):
    out = tmp_path / "d.json"
    assert run("--example", "synthetic", "--json", out) == 0
    report = json.loads(out.read_text())
    hidden = read_log(path("synthetic")).meta.data["synth"]
    assert report["cause"] == hidden["effect"]
    for name, true_value in hidden["truth"].items():
        value, se = report["parameters"][name]
        assert abs(value - true_value) < max(4 * se, 1e-3 * true_value), name
    assert report["gain"]["after"] < 0.5 * report["gain"]["before"]
    assert f"cause: {hidden['effect']}" in capsys.readouterr().out


def test_bare_example_flag_diagnoses_the_generated_log(tmp_path):
    out = tmp_path / "d.json"
    assert run("--example", "--json", out) == 0
    assert json.loads(out.read_text())["log"] == str(path("synthetic"))


@pytest.mark.filterwarnings("error")
def test_the_real_examples_diagnose_without_error_or_warning(tmp_path, capsys):
    boreal, opti = tmp_path / "boreal.json", tmp_path / "opti.json"
    assert run("--example", "borealtc", "--json", boreal) == 0
    report = json.loads(boreal.read_text())
    assert report["ground_truth"] == "none" and report["cause"] == "track_width"
    assert run("--example", "optiodom", "--json", opti) == 0
    report = json.loads(opti.read_text())
    assert report["format"] == "slipenv-diagnosis/1" and report["log"] == str(path("optiodom"))
    assert capsys.readouterr().err == ""


def test_unknown_example_is_a_one_line_error(capsys):
    assert run("--example", "husky") == 2
    err = capsys.readouterr().err
    assert "invalid choice: 'husky'" in err and len(err.strip().splitlines()) == 1


@pytest.mark.parametrize("argv", [[], ["some/log", "--example", "optiodom"]])
def test_exactly_one_of_log_folder_and_example_is_needed(argv, capsys):
    assert run(*argv) == 2
    err = capsys.readouterr().err.strip()
    assert "--example" in err and len(err.splitlines()) == 1
