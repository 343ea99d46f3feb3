"""numba's disk cache follows the source of every file a compiled function is built from."""

from __future__ import annotations

import os
import pathlib
import subprocess
import sys
import textwrap

from slipenv.contracts.compiled_cache import refresh_stale_cache, sources_digest


def cached_files(folder: pathlib.Path) -> set[str]:
    return {p.name for p in (folder / "__pycache__").glob("*.nb[ic]")}


def fake_cache(folder: pathlib.Path, *names: str) -> None:
    (folder / "__pycache__").mkdir(exist_ok=True)
    for name in names:
        (folder / "__pycache__" / name).write_text("machine code")


def test_an_edit_of_a_dependency_deletes_only_the_entry_modules_cache(tmp_path):
    (tmp_path / "entry.py").write_text("x = 1\n")
    (tmp_path / "dep.py").write_text("y = 1\n")
    fake_cache(tmp_path, "entry.f-3.py311.nbi", "entry.f-3.py311.1.nbc", "dep.g-1.py311.nbi")
    # no stamp yet: the cache's source is unknown, so it goes
    assert refresh_stale_cache(tmp_path / "entry.py", "dep.py")
    assert cached_files(tmp_path) == {"dep.g-1.py311.nbi"}

    fake_cache(tmp_path, "entry.f-3.py311.nbi")
    assert not refresh_stale_cache(tmp_path / "entry.py", "dep.py")  # unchanged: kept
    assert "entry.f-3.py311.nbi" in cached_files(tmp_path)

    (tmp_path / "dep.py").write_text("y = 2\n")
    assert refresh_stale_cache(tmp_path / "entry.py", "dep.py")
    assert cached_files(tmp_path) == {"dep.g-1.py311.nbi"}


def test_the_digest_depends_on_content_not_on_argument_order(tmp_path):
    a, b = tmp_path / "a.py", tmp_path / "b.py"
    a.write_text("1")
    b.write_text("2")
    assert sources_digest(a, b) == sources_digest(b, a)
    before = sources_digest(a, b)
    b.write_text("3")
    assert sources_digest(a, b) != before


def test_a_compiled_caller_runs_its_callees_new_code_after_only_the_callee_changed(tmp_path):
    # the failure this guards against: numba keys the caller's cache on the caller's file alone
    (tmp_path / "callee.py").write_text(textwrap.dedent("""
        from numba import njit

        @njit(cache=True)
        def value():
            return 1.0
    """))
    (tmp_path / "caller.py").write_text(textwrap.dedent("""
        from numba import njit

        from slipenv.contracts.compiled_cache import refresh_stale_cache
        from callee import value

        refresh_stale_cache(__file__, "callee.py")

        @njit(cache=True)
        def twice():
            return 2.0 * value()
    """))
    env = {**os.environ, "PYTHONPATH": f"{tmp_path}{os.pathsep}{os.environ.get('PYTHONPATH', '')}"}
    env.pop("NUMBA_DISABLE_JIT", None)

    def run() -> str:
        out = subprocess.run([sys.executable, "-c", "from caller import twice; print(twice())"],
                             cwd=tmp_path, env=env, capture_output=True, text=True, check=True)
        return out.stdout.strip()

    assert run() == "2.0"
    assert any(n.startswith("caller.twice") for n in cached_files(tmp_path))
    (tmp_path / "callee.py").write_text((tmp_path / "callee.py").read_text()
                                        .replace("return 1.0", "return 5.0"))
    assert run() == "10.0"
