"""Every output path of every command is checked before the work: one line naming the option
and the reason, status 2, and the check itself leaves nothing behind."""

from __future__ import annotations

from pathlib import Path

import pytest

from slipenv.cli import main
from slipenv.cli_outputs import OutputPathError, output_dir, output_file

ENV = "slipenv/HuskySand-v0"
GRID = """
env_ids: [slipenv/TrackedSlopeCircle-v0]
policies: [baseline]
seeds: [0]
"""
HAS_PROC = Path("/proc/self").is_dir()


@pytest.fixture
def no_work(monkeypatch):
    """Every long-running entry point of every command fails the test if it is reached."""

    def forbidden(*args, **kwargs):
        raise AssertionError("long work started before the outputs were checked")

    import slipenv.agents.train
    import slipenv.bench
    import slipenv.diagnose.cli
    import slipenv.evaluation.evaluator
    import slipenv.evaluation.sweep
    import slipenv.experiments
    import slipenv.run
    import slipenv.testbed.csv_format
    import slipenv.testbed.report

    for module, name in [(slipenv.run, "run_episode"), (slipenv.bench, "run_bench"),
                         (slipenv.agents.train, "train"), (slipenv.experiments, "experiment"),
                         (slipenv.evaluation.evaluator, "evaluate"),
                         (slipenv.evaluation.sweep, "run_sweep"),
                         (slipenv.testbed.csv_format, "read_testbed"),
                         (slipenv.testbed.report, "analyse"), (slipenv.diagnose.cli, "main")]:
        monkeypatch.setattr(module, name, forbidden)


@pytest.fixture
def place(tmp_path, monkeypatch):
    """A working folder holding a grid file, a log folder, and ``runs`` as a FILE."""
    monkeypatch.chdir(tmp_path)
    Path("grid.yaml").write_text(GRID)
    Path("log").mkdir()
    Path("runs").write_text("a file where the default output folder would go")
    Path("existing_folder").mkdir()
    return tmp_path


def one_line(capsys, argv: list[str]) -> str:
    assert main(argv) == 2, argv
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert "Traceback" not in captured.err and captured.out == ""
    return lines[0]


# Defaults under runs/ while `runs` is a file: each command's own default output folder.
RUNS_IS_A_FILE = [
    ["run", ENV],
    ["evaluate", ENV],
    ["sweep", "grid.yaml"],
    ["train", ENV],
    ["reproduce", "yamauchi"],
]


@pytest.mark.parametrize("argv", RUNS_IS_A_FILE, ids=lambda a: a[0])
def test_runs_being_a_file_is_one_line_before_the_work(no_work, place, capsys, argv):
    line = one_line(capsys, argv)
    assert f"slipenv {argv[0]}: error: --out 'runs/" in line
    assert "cannot write there ('runs' is a file, not a folder)" in line


FOLDER_AS_FILE = [
    ["run", ENV, "--out", "o", "--json", "existing_folder"],
    ["bench", ENV, "--json", "existing_folder"],
    ["evaluate", ENV, "--out", "ev", "--json", "existing_folder"],
    ["reproduce", "yamauchi", "--out", "rep", "--json", "existing_folder"],
    ["diagnose", "log", "--json", "existing_folder"],
    ["fit-soil", "bed", "--json", "existing_folder"],
]


@pytest.mark.parametrize("argv", FOLDER_AS_FILE, ids=lambda a: a[0])
def test_a_folder_named_as_a_json_file_is_one_line_before_the_work(no_work, place, capsys,
                                                                   argv):
    line = one_line(capsys, argv)
    assert "--json 'existing_folder': is a folder, not a file" in line


FILE_AS_FOLDER = [
    (["run", ENV, "--out", "grid.yaml"], "--out"),
    (["evaluate", ENV, "--out", "grid.yaml"], "--out"),
    (["sweep", "grid.yaml", "--out", "grid.yaml"], "--out"),
    (["train", ENV, "--out", "grid.yaml"], "--out"),
    (["diagnose", "log", "--report", "grid.yaml"], "--report"),
    (["fit-soil", "bed", "--json", "f.json", "--report", "grid.yaml"], "--report"),
]


@pytest.mark.parametrize("argv, option", FILE_AS_FOLDER, ids=[a[0] for a, _ in FILE_AS_FOLDER])
def test_a_file_named_as_an_output_folder_is_one_line_before_the_work(no_work, place, capsys,
                                                                      argv, option):
    line = one_line(capsys, argv)
    assert f"{option} 'grid.yaml': is a file, not a folder" in line
    assert Path("grid.yaml").read_text() == GRID  # untouched


UNDER_PROC = [
    (["run", ENV, "--out", "/proc/slipenv_out"], "--out"),
    (["run", ENV, "--out", "o", "--json", "/proc/m.json"], "--json"),
    (["evaluate", ENV, "--out", "/proc/slipenv_out"], "--out"),
    (["evaluate", ENV, "--out", "o", "--json", "/proc/e.json"], "--json"),
    (["sweep", "grid.yaml", "--out", "/proc/slipenv_out"], "--out"),
    (["train", ENV, "--out", "/proc/slipenv_out"], "--out"),
    (["bench", ENV, "--json", "/proc/b.json"], "--json"),
    (["reproduce", "yamauchi", "--out", "o", "--save-model", "/proc/m.json"], "--save-model"),
    (["reproduce", "yamauchi", "--out", "o", "--docs", "/proc/docs"], "--docs"),
    (["diagnose", "log", "--json", "/proc/d.json"], "--json"),
    (["diagnose", "log", "--report", "/proc/report"], "--report"),
    (["fit-soil", "bed", "--json", "/proc/f.json"], "--json"),
    (["fit-soil", "bed", "--json", "f.json", "--report", "/proc/report"], "--report"),
]


@pytest.mark.skipif(not HAS_PROC, reason="needs Linux's /proc")
@pytest.mark.parametrize("argv, option", UNDER_PROC, ids=[a[0] + o for a, o in UNDER_PROC])
def test_a_path_under_proc_is_one_line_before_the_work(no_work, place, capsys, argv, option):
    # /proc is a folder that even root cannot create files in: only writing tells.
    line = one_line(capsys, argv)
    assert f"{option} '/proc/" in line and "cannot write there" in line
    assert "does not take new files in '/proc'" in line


WRITABLE = [
    ["run", ENV, "--out", "o", "--json", "o/m.json"],
    ["bench", ENV, "--json", "b.json"],
    ["evaluate", ENV, "--out", "o", "--json", "e.json"],
    ["sweep", "grid.yaml", "--out", "o"],
    ["train", ENV, "--out", "o"],
    ["reproduce", "yamauchi", "--out", "o", "--json", "r.json"],
    ["diagnose", "log", "--json", "d.json", "--report", "rep"],
    ["fit-soil", "bed", "--json", "f.json", "--report", "rep"],
]


@pytest.mark.parametrize("argv", WRITABLE, ids=lambda a: a[0])
def test_with_writable_outputs_each_command_reaches_its_work(no_work, place, argv):
    # The tests above would pass vacuously if the work were not where no_work watches.
    with pytest.raises(AssertionError, match="long work started"):
        main(argv)


def test_a_checked_new_file_is_not_left_behind_and_an_existing_one_is_unchanged(tmp_path):
    new = tmp_path / "deep" / "er" / "m.json"
    assert output_file(new, "--json") == new
    assert not new.exists() and new.parent.is_dir()
    old = tmp_path / "old.json"
    old.write_text("kept")
    output_file(old, "--json")
    assert old.read_text() == "kept"
    assert output_file(None, "--json") is None


def test_a_checked_folder_is_created_and_holds_no_probe_file(tmp_path):
    folder = output_dir(tmp_path / "a" / "b", "--out")
    assert folder.is_dir() and list(folder.iterdir()) == []


def test_a_parent_that_is_a_file_is_named_in_the_reason(tmp_path):
    wall = tmp_path / "wall"
    wall.write_text("")
    with pytest.raises(OutputPathError, match=r"^--json '.*/wall/x/m\.json': cannot write "
                                              r"there \('.*/wall' is a file, not a folder\)$"):
        output_file(wall / "x" / "m.json", "--json")
    assert wall.read_text() == ""

