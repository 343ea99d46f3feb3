"""The tree passes the linter configured in pyproject.toml (ruff), which also bans the bare
top-level names ``estimators``, ``controllers`` and ``agents`` (one import root)."""

from __future__ import annotations

import pathlib
import shutil
import subprocess
import tomllib

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]


def _ruff() -> list[str]:
    exe = shutil.which("ruff")
    if exe is None:
        pytest.skip("ruff is not installed (it is in the test extra)")
    return [exe]


def test_the_tree_passes_ruff():
    done = subprocess.run([*_ruff(), "check", "--no-cache", "."], cwd=ROOT, capture_output=True,
                          text=True)
    assert done.returncode == 0, done.stdout[-4000:]


def test_a_bare_top_level_import_fails_the_lint(tmp_path):
    bad = tmp_path / "user_code.py"
    bad.write_text("from estimators.base import OdometryGeometry\n\nprint(OdometryGeometry)\n")
    done = subprocess.run([*_ruff(), "check", "--no-cache", "--config",
                           str(ROOT / "pyproject.toml"), str(bad)], capture_output=True, text=True)
    assert done.returncode == 1 and "TID251" in done.stdout, done.stdout


def test_ruff_is_declared_for_the_tests():
    extras = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"][
        "optional-dependencies"]["test"]
    assert any(r.startswith("ruff") for r in extras)
