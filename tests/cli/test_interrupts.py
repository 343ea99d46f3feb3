"""Ctrl-C in any command: one line saying where the partial results are (or that nothing was
written), status 130, no traceback."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from slipenv.cli import main
from slipenv.cli_outputs import INTERRUPTED_STATUS, interrupted_message, partial_results

ENV = "slipenv/HuskySand-v0"
GRID = """
env_ids: [slipenv/TrackedSlopeCircle-v0]
policies: [baseline, feedback]
seeds: [0, 1, 2, 3, 4, 5, 6, 7]
env_kwargs: {path_kwargs: {radius_m: 0.25, speed_mps: 0.05, loops: 0.3}}
max_steps: 400
"""


def ctrl_c(*args, **kwargs):
    raise KeyboardInterrupt


def interrupted(capsys, argv: list[str]) -> str:
    assert main(argv) == INTERRUPTED_STATUS == 130
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "Traceback" not in err, err
    assert lines[0].startswith(f"slipenv {argv[0]}: interrupted; ")
    return lines[0]


@pytest.fixture
def place(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    Path("grid.yaml").write_text(GRID)
    Path("log").mkdir()
    return tmp_path


def test_run_interrupted_during_the_episode_says_nothing_was_written(monkeypatch, place,
                                                                     capsys):
    import slipenv.run

    monkeypatch.setattr(slipenv.run, "run_episode", ctrl_c)
    line = interrupted(capsys, ["run", ENV, "--out", "o", "--quiet"])
    assert line == "slipenv run: interrupted; nothing written"


def test_evaluate_interrupted_during_the_episodes_says_nothing_was_written(monkeypatch, place,
                                                                          capsys):
    import slipenv.evaluation.evaluator

    monkeypatch.setattr(slipenv.evaluation.evaluator, "evaluate", ctrl_c)
    line = interrupted(capsys, ["evaluate", ENV, "--out", "o", "--json", "e.json"])
    assert line.endswith("interrupted; nothing written")
    assert list(Path("o").iterdir()) == [] and not Path("e.json").exists()


def test_sweep_interrupted_names_its_finished_cells_and_how_to_resume(monkeypatch, place,
                                                                      capsys):
    import slipenv.evaluation.sweep

    def one_cell_then_ctrl_c(cells, out_dir, **kwargs):
        (Path(out_dir) / "cells").mkdir()
        (Path(out_dir) / "cells" / f"{cells[0].key}.json").write_text("{}")
        raise KeyboardInterrupt

    monkeypatch.setattr(slipenv.evaluation.sweep, "run_sweep", one_cell_then_ctrl_c)
    line = interrupted(capsys, ["sweep", "grid.yaml", "--out", "s"])
    assert line == ("slipenv sweep: interrupted; partial results in "
                    f"{Path('s', 'cells')} (the same command runs the rest)")


def test_train_interrupted_names_the_model_it_saved(monkeypatch, place, capsys):
    import slipenv.agents.train

    def saves_then_ctrl_c(*args, out, **kwargs):
        Path(out, "config.json").write_text("{}")
        Path(out, "interrupted.zip").write_bytes(b"PK")
        raise KeyboardInterrupt

    monkeypatch.setattr(slipenv.agents.train, "train", saves_then_ctrl_c)
    line = interrupted(capsys, ["train", ENV, "--out", "t", "--quiet"])
    assert line == f"slipenv train: interrupted; partial results in {Path('t', 'interrupted.zip')}"


def test_train_interrupted_before_a_model_exists_names_the_run_folder(monkeypatch, place,
                                                                      capsys):
    import slipenv.agents.train

    def logs_then_ctrl_c(*args, out, **kwargs):
        Path(out, "config.json").write_text("{}")
        raise KeyboardInterrupt

    monkeypatch.setattr(slipenv.agents.train, "train", logs_then_ctrl_c)
    assert interrupted(capsys, ["train", ENV, "--out", "t", "--quiet"]).endswith(
        "interrupted; partial results in t")


def test_fit_soil_interrupted_during_the_fit_says_nothing_was_written(monkeypatch, place,
                                                                      capsys):
    import slipenv.testbed.csv_format
    import slipenv.testbed.report

    monkeypatch.setattr(slipenv.testbed.csv_format, "read_testbed", lambda directory: None)
    monkeypatch.setattr(slipenv.testbed.report, "analyse", ctrl_c)
    line = interrupted(capsys, ["fit-soil", "bed", "--json", "f.json", "--report", "rep"])
    assert line == "slipenv fit-soil: interrupted; nothing written"
    assert not Path("f.json").exists()


def test_diagnose_interrupted_is_one_line_too(monkeypatch, place, capsys):
    import slipenv.diagnose.cli

    monkeypatch.setattr(slipenv.diagnose.cli, "main", ctrl_c)
    assert interrupted(capsys, ["diagnose", "log"]) == (
        "slipenv diagnose: interrupted; nothing written")


def test_the_innermost_block_with_results_names_them_and_empty_places_do_not(tmp_path):
    empty, full = tmp_path / "empty", tmp_path / "full"
    empty.mkdir()
    full.mkdir()
    (full / "a.csv").write_text("x")
    with pytest.raises(KeyboardInterrupt) as caught:
        with partial_results(full):
            with partial_results(tmp_path / "missing.zip", empty, None, note="never shown"):
                raise KeyboardInterrupt
    assert interrupted_message(caught.value) == f"interrupted; partial results in {full}"
    with pytest.raises(KeyboardInterrupt) as caught:
        with partial_results(full / "a.csv", note="resume with the same command"):
            with partial_results(full):
                raise KeyboardInterrupt
    assert interrupted_message(caught.value) == f"interrupted; partial results in {full}"
    assert interrupted_message(KeyboardInterrupt()) == "interrupted; nothing written"


@pytest.mark.skipif(os.name != "posix", reason="sends SIGINT to a process group")
def test_a_real_ctrl_c_stops_a_parallel_sweep_at_once_without_worker_tracebacks(place):
    # A terminal's Ctrl-C reaches the whole process group: the pool's workers too.
    cmd = [sys.executable, "-m", "slipenv.cli", "sweep", "grid.yaml", "--out", "s",
           "--workers", "2", "--quiet"]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True,
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    cells = Path("s", "cells")
    deadline = time.monotonic() + 120
    while not any(cells.glob("*.json")) and time.monotonic() < deadline:
        time.sleep(0.2)
    assert any(cells.glob("*.json")), "no cell finished in 120 s"
    os.killpg(proc.pid, signal.SIGINT)
    stopped = time.monotonic()
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert time.monotonic() - stopped < 10  # the queued cells were dropped, not run
    assert err.strip().splitlines() == [
        f"slipenv sweep: interrupted; partial results in {cells} (the same command runs the "
        "rest)"]
    assert len(list(cells.glob("*.json"))) < 16
