"""Static types of every package: mypy, configured in pyproject.toml ``[tool.mypy]``, passes on
its ``files`` (every package folder the distribution installs: slipenv, estimators, controllers,
agents), and the same configuration does catch a wrong annotation.

mypy runs from the repository root: ``slipenv`` is installed editable through an import hook
that mypy does not follow, so outside the root it would see every ``slipenv`` import as missing
(``ignore_missing_imports``) and type it ``Any``; the second test would then pass no error.
"""

from __future__ import annotations

import pathlib
import subprocess
import sys
import tomllib

ROOT = pathlib.Path(__file__).resolve().parents[1]
CONFIG = ROOT / "pyproject.toml"


def run_mypy(*args: str | pathlib.Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "mypy", "--config-file", str(CONFIG), *map(str, args)],
        cwd=ROOT, capture_output=True, text=True, timeout=300,
    )


def configured_sources() -> list[pathlib.Path]:
    """The modules mypy checks: every ``.py`` and ``.pyi`` (a compiled module's stub) file,
    a module with both counted once, as mypy does."""
    files = tomllib.loads(CONFIG.read_text())["tool"]["mypy"]["files"]
    found = [p for f in files for p in (ROOT / f).rglob("*.py*") if p.suffix in (".py", ".pyi")]
    return sorted({p.with_suffix("") for p in found})


def test_mypy_checks_every_package_folder_the_distribution_installs():
    tool = tomllib.loads(CONFIG.read_text())["tool"]
    installed = set(tool["setuptools"]["package-dir"].values())
    assert {"slipenv", "estimators"} <= installed
    assert set(tool["mypy"]["files"]) == installed


def test_every_package_passes_mypy_with_the_project_configuration():
    sources = configured_sources()
    assert any("contracts" in p.parts for p in sources)
    assert any(p.parts[-2:] == ("estimators", "__init__") for p in sources)
    done = run_mypy()
    assert done.returncode == 0, done.stdout + done.stderr
    # every configured file was checked (an emptied ``files`` list would also exit 0)
    assert f"no issues found in {len(sources)} source files" in done.stdout, done.stdout


SNIPPET = '''\
from slipenv.contracts import PoseEstimate, wrap_angle


def heading_error(yaw_rad: float, path_heading_rad: float) -> {returns}:
    return wrap_angle(yaw_rad - path_heading_rad)


def slip_angle(estimate: PoseEstimate) -> float:
    return estimate.slip_angle_rad
'''


def test_the_configuration_rejects_a_wrong_return_annotation(tmp_path):
    wrong = tmp_path / "wrong.py"
    wrong.write_text(SNIPPET.format(returns="str"))  # wrap_angle returns float
    done = run_mypy(wrong)
    assert done.returncode == 1, done.stdout + done.stderr
    # mypy's cache keys results by module and content, so it may print the path of an earlier
    # run's identical snippet: match the file name only
    assert "wrong.py:5: error: Incompatible return value type" in done.stdout, done.stdout
    assert "Found 1 error in 1 file" in done.stdout


def test_the_same_snippet_with_the_right_annotation_passes(tmp_path):
    right = tmp_path / "right.py"
    right.write_text(SNIPPET.format(returns="float"))
    done = run_mypy(right)
    assert done.returncode == 0, done.stdout + done.stderr


def test_the_configuration_rejects_an_unannotated_estimator_function(tmp_path):
    # contracts and estimators must stay fully annotated (the [[tool.mypy.overrides]] block)
    package = tmp_path / "estimators"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "untyped.py").write_text("def gain(x):\n    return 2 * x\n")
    # its own cache: a second module named ``estimators`` must not replace the real one's entry
    done = run_mypy("--cache-dir", tmp_path / "mypy_cache", package / "untyped.py")
    assert done.returncode == 1, done.stdout + done.stderr
    assert "Function is missing a type annotation" in done.stdout, done.stdout
