"""Sweeps: one table from a tiny grid, resumable, the same with the local and Ray backends."""

from __future__ import annotations

import argparse

import pytest

from slipenv.evaluation import sweep, sweep_cli
from slipenv.evaluation.grid import load_grid

TINY = """
env_ids: [slipenv/TrackedSlopeCircle-v0]
policies: [baseline, feedback]
seeds: [0, 1]
soils: [toyoura_sand, loose_sand]
env_kwargs: {path_kwargs: {radius_m: 0.25, speed_mps: 0.05, loops: 0.1}}
max_steps: 60
"""


@pytest.fixture
def grid(tmp_path):
    path = tmp_path / "tiny.yaml"
    path.write_text(TINY)
    return path


def _cli(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    sweep_cli.add_parser(parser.add_subparsers())
    args = parser.parse_args(argv)
    return args.func(args)


def test_local_sweep_writes_one_row_per_cell_and_a_summary(grid, tmp_path, capsys):
    out = tmp_path / "out"
    assert _cli(["sweep", str(grid), "--out", str(out), "--workers", "2", "--quiet"]) == 0
    lines = (out / "results.csv").read_text().splitlines()
    assert len(lines) == 1 + 8
    assert lines[0].startswith("env_id,variation,policy,seed,steps,")
    assert len(list((out / "cells").glob("*.json"))) == 8
    printed = capsys.readouterr().out
    assert "soil=loose_sand" in printed and "feedback" in printed


def test_an_interrupted_sweep_resumes_without_rerunning_finished_cells(grid, tmp_path,
                                                                       monkeypatch):
    cells = load_grid(grid)
    out = tmp_path / "out"
    # "Interrupted" after three cells: only their result files exist.
    sweep.run_sweep(cells[:3], out, workers=1, quiet=True, log=lambda _: None)
    ran: list[str] = []
    real = sweep.run_cell

    def counting(cell, out_dir):
        ran.append(cell["key"])
        return real(cell, out_dir)

    monkeypatch.setattr(sweep, "run_cell", counting)
    rows = sweep.run_sweep(cells, out, workers=1, quiet=True, log=lambda _: None)
    assert sorted(ran) == sorted(c.key for c in cells[3:])
    assert [r["cell"] for r in rows] == [c.key for c in cells]
    ran.clear()
    sweep.run_sweep(cells, out, workers=1, quiet=True, log=lambda _: None)
    assert ran == []


def test_the_table_does_not_depend_on_workers_or_resumption(grid, tmp_path):
    cells = load_grid(grid)
    sweep.run_sweep(cells, tmp_path / "a", workers=1, quiet=True, log=lambda _: None)
    sweep.run_sweep(cells[::2], tmp_path / "b", workers=2, quiet=True, log=lambda _: None)
    sweep.run_sweep(cells, tmp_path / "b", workers=2, quiet=True, log=lambda _: None)
    assert (tmp_path / "a" / "results.csv").read_text() == (
        tmp_path / "b" / "results.csv").read_text()


def test_a_grid_typo_exits_2_with_one_line_before_any_work(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text(TINY.replace("soils:", "soil:"))
    out = tmp_path / "out"
    assert _cli(["sweep", str(bad), "--out", str(out)]) == 2
    err = capsys.readouterr().err
    assert "unknown key 'soil'; did you mean 'soils'?" in err and err.count("\n") == 1
    assert not out.exists()


def test_address_without_the_ray_backend_is_an_error(grid, capsys):
    assert _cli(["sweep", str(grid), "--address", "auto"]) == 2
    assert "--address joins a Ray cluster" in capsys.readouterr().err


@pytest.mark.slow
def test_ray_backend_gives_the_same_table_as_the_local_backend(grid, tmp_path):
    ray = pytest.importorskip("ray", reason="Ray is not installed (pip install 'slipenv[ray]')")
    cells = load_grid(grid)
    sweep.run_sweep(cells, tmp_path / "local", workers=2, quiet=True, log=lambda _: None)
    try:
        sweep.run_sweep(cells, tmp_path / "ray", backend="ray", workers=2, quiet=True,
                        log=lambda _: None)
    except sweep.RayUnavailable as exc:
        pytest.skip(f"Ray cannot start here: {exc}")
    assert not ray.is_initialized()
    assert (tmp_path / "local" / "results.csv").read_text() == (
        tmp_path / "ray" / "results.csv").read_text()
