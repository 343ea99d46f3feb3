"""One import root: the distribution installs ``slipenv`` and nothing else at the top level."""

from __future__ import annotations

import pathlib
import shutil
import subprocess
import sys
import tomllib
import zipfile

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
PYPROJECT = tomllib.loads((ROOT / "pyproject.toml").read_text())
SETUPTOOLS = PYPROJECT["tool"]["setuptools"]


def _folder_packages() -> set[str]:
    found = set()
    for package, folder in SETUPTOOLS["package-dir"].items():
        for init in (ROOT / folder).rglob("__init__.py"):
            rel = init.parent.relative_to(ROOT / folder)
            found.add(".".join([package, *rel.parts]))
    return found


def test_the_package_list_names_every_folder_with_an_init():
    assert set(SETUPTOOLS["packages"]) == _folder_packages()


def test_the_users_folders_map_under_the_one_root():
    assert SETUPTOOLS["package-dir"] == {
        "slipenv": "slipenv", "slipenv.estimators": "estimators",
        "slipenv.controllers": "controllers", "slipenv.agents": "agents"}


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> pathlib.Path:
    # Built from a private copy of the source: pip builds in the tree it is given, and two
    # test workers building the checkout at once race on its build folder.
    src = tmp_path_factory.mktemp("src") / "slipenv"
    shutil.copytree(ROOT, src, ignore=shutil.ignore_patterns(
        ".git", "build", "runs", "*.egg-info", "__pycache__", ".pytest_cache", "*.so"))
    out = tmp_path_factory.mktemp("wheel")
    done = subprocess.run([sys.executable, "-m", "pip", "wheel", "--no-deps",
                           "--no-build-isolation", "-q", "-w", str(out), str(src)],
                          capture_output=True, text=True)
    assert done.returncode == 0, done.stderr[-3000:]
    return next(out.glob("slipenv-*.whl"))


def test_the_wheel_has_one_top_level_name(wheel):
    names = zipfile.ZipFile(wheel).namelist()
    tops = {n.split("/")[0] for n in names if not n.split("/")[0].endswith(".dist-info")}
    assert tops == {"slipenv"}
    assert "slipenv/estimators/__init__.py" in names
    assert "slipenv/controllers/__init__.py" in names
    assert "slipenv/agents/__init__.py" in names
    assert any(n.startswith("slipenv/data/") and n.endswith(".json") for n in names)
    # the example logs, with their licences, so `slipenv diagnose --example` works from a wheel
    for name in ("synthetic/signals.csv", "optiodom/LICENSE", "borealtc/ATTRIBUTION.md"):
        assert f"slipenv/data/examples/{name}" in names, name


def test_installed_wheel_imports_only_under_slipenv(wheel, tmp_path):
    site = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--no-deps", "-q", "--target",
                    str(site), str(wheel)], check=True, capture_output=True)
    script = (
        "import importlib.util, slipenv.estimators, slipenv.controllers, slipenv.agents\n"
        f"assert slipenv.estimators.__file__.startswith({str(site)!r})\n"
        "for bare in ('estimators', 'controllers', 'agents'):\n"
        "    assert importlib.util.find_spec(bare) is None, bare\n"
        "print('ok')\n"
    )
    # Run outside the repository, the wheel's folder first on the path.
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True,
                          text=True, env={"PYTHONPATH": str(site), "PATH": "/usr/bin:/bin"})
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "ok"


def test_editable_install_resolves_the_mapped_packages_outside_the_repo(tmp_path):
    script = ("import importlib.util, slipenv.estimators as e\n"
              "print(e.__file__)\n"
              "print(importlib.util.find_spec('estimators'))\n")
    done = subprocess.run([sys.executable, "-c", script], cwd=tmp_path, capture_output=True,
                          text=True, check=True)
    file, bare = done.stdout.split()
    assert pathlib.Path(file).resolve().parent == ROOT / "estimators"
    assert bare == "None"


def test_importing_slipenv_loads_neither_numba_nor_the_estimators():
    """``import slipenv`` registers the envs and nothing more: numba and scipy.stats (about
    1.5 s on the CI machine) load with the first estimator that needs them."""
    code = ("import sys, slipenv; print(sorted(m for m in ('numba', 'scipy.stats', "
            "'slipenv.estimators') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip().splitlines()[-1] == "[]"


def test_the_estimators_that_need_no_compiler_load_without_numba_or_scipy_stats():
    """The Lindgren filter (numba) and the Endo fit's interval (scipy.stats) load when used:
    an env with gyrodometry or Endo odometry does not pay a second for them."""
    code = ("import sys; from slipenv.estimators import Gyrodometry, EndoOdometry; "
            "print(sorted(m for m in ('numba', 'scipy.stats') if m in sys.modules)); "
            "from slipenv.estimators import LindgrenEKF; print('numba' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         check=True)
    assert out.stdout.strip().splitlines()[-2:] == ["[]", "True"]
