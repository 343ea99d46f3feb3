"""The import rules of the package (docs/architecture.md), checked on the source with ``ast``.

Layers, lowest first; a module may import its own layer's modules and lower layers only:

    contracts <- terramechanics, paths <- vehicles, terrain <- sim <- sensors <- logs, rollout
    <- envs <- {experiments, diagnose, agents, evaluation, run, bench} <- cli

Estimators import only the contracts; controllers only the contracts and the paths; nothing
imports the command line; no module imports another module's ``_private`` name; no import
circle between modules. Imports inside functions count: a lazy import is still a dependency.
"""

from __future__ import annotations

import ast
import pathlib
from collections.abc import Iterator

import pytest

ROOT = pathlib.Path(__file__).resolve().parents[1]
# folder -> installed package name (pyproject.toml [tool.setuptools] package-dir)
FOLDERS = {"slipenv": "slipenv", "estimators": "slipenv.estimators",
           "controllers": "slipenv.controllers", "agents": "slipenv.agents"}

LAYERS: dict[str, int] = {
    "slipenv.contracts": 0,
    # standard library only: every command checks its outputs and arguments the same way
    "slipenv.cli_outputs": 0, "slipenv.cli_types": 0,
    "slipenv.terramechanics": 1, "slipenv.paths": 1,
    "slipenv.vehicles": 2, "slipenv.terrain": 2,
    "slipenv.sim": 3,
    "slipenv.sensors": 4,
    "slipenv.logs": 5, "slipenv.rollout": 5,  # the loop needs only gymnasium and contracts
    "slipenv.envs": 6,
    "slipenv.experiments": 7, "slipenv.diagnose": 7, "slipenv.agents": 7,
    "slipenv.evaluation": 7, "slipenv.run": 7, "slipenv.bench": 7, "slipenv.testbed": 7,
    "slipenv.cli": 8,
    "slipenv": 8,  # the package root registers the envs
}
# Layers with a narrower rule than their rank: they may import only these.
ONLY: dict[str, tuple[str, ...]] = {
    "slipenv.estimators": ("slipenv.contracts",),
    "slipenv.controllers": ("slipenv.contracts", "slipenv.paths"),
}
# Modules that are leaves or tools beside the layers (no package imports them).
EXEMPT = ("slipenv.pybullet_quiet",)
# Public members of stdlib types whose names start with an underscore.
PUBLIC_UNDERSCORE = {"_replace", "_asdict", "_fields", "_make", "_field_defaults"}


def module_name(path: pathlib.Path) -> str:
    rel = path.relative_to(ROOT)
    parts = [FOLDERS[rel.parts[0]], *rel.parts[1:]]
    parts[-1] = parts[-1].removesuffix(".py")
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def source_modules(root: pathlib.Path = ROOT) -> dict[str, pathlib.Path]:
    out = {}
    for folder in FOLDERS:
        for path in sorted((root / folder).rglob("*.py")):
            out[module_name(path)] = path
    return out


def imports_of(name: str, path: pathlib.Path) -> Iterator[tuple[str, str | None, int]]:
    """(imported module, imported member or None, line) for every import in the file."""
    tree = ast.parse(path.read_text(), filename=str(path))
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            for alias in node.names:
                yield alias.name, None, node.lineno
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package.split(".")
                base = base[: len(base) - node.level + 1]
                mod = ".".join(base + ([node.module] if node.module else []))
            else:
                mod = node.module or ""
            for alias in node.names:
                yield mod, alias.name, node.lineno


def layer_of(module: str) -> tuple[str, int] | None:
    best = None
    for prefix, rank in {**LAYERS, **dict.fromkeys(ONLY, -1)}.items():
        if module == prefix or module.startswith(prefix + "."):
            if best is None or len(prefix) > len(best[0]):
                best = (prefix, rank)
    return best


def violations(modules: dict[str, pathlib.Path]) -> list[str]:
    found = []
    for name, path in modules.items():
        if name.startswith(EXEMPT):
            continue
        own = layer_of(name)
        assert own is not None, f"{name} belongs to no layer: add it to LAYERS in {__file__}"
        for mod, member, line in imports_of(name, path):
            where = f"{path.relative_to(ROOT)}:{line}"
            if mod.split(".")[0] in ("estimators", "controllers", "agents"):
                found.append(f"{where} imports the bare name {mod!r}")
                continue
            if not (mod == "slipenv" or mod.startswith("slipenv.")):
                continue
            target_mod = f"{mod}.{member}" if member and f"{mod}.{member}" in modules else mod
            if member and member.startswith("_") and not member.startswith("__") \
                    and target_mod == mod and mod != name:
                found.append(f"{where} imports the private name {member!r} of {mod}")
            target = layer_of(target_mod)
            if target is None or target_mod.startswith(EXEMPT):
                continue
            if own[0] in ONLY:
                if target[0] != own[0] and target[0] not in ONLY[own[0]]:
                    found.append(f"{where}: {name} may import only {ONLY[own[0]]}, "
                                 f"imports {target_mod}")
            elif target[0] == "slipenv.cli" and own[0] != "slipenv.cli":
                found.append(f"{where}: nothing imports the command line ({name})")
            elif target[1] > own[1]:
                found.append(f"{where}: {name} (layer {own[0]}) imports the higher layer "
                             f"{target_mod} ({target[0]})")
    return found


def import_cycles(modules: dict[str, pathlib.Path]) -> list[list[str]]:
    graph: dict[str, set[str]] = {}
    for name, path in modules.items():
        deps = set()
        for mod, member, _ in imports_of(name, path):
            target = f"{mod}.{member}" if member and f"{mod}.{member}" in modules else mod
            if target in modules and target != name and not name.startswith(target + "."):
                deps.add(target)
        graph[name] = deps
    # Tarjan's strongly connected components
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on: set[str] = set()
    cycles: list[list[str]] = []

    def visit(v: str) -> None:
        index[v] = low[v] = len(index)
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                cycles.append(sorted(comp))

    for v in graph:
        if v not in index:
            visit(v)
    return cycles


def private_attribute_reads(modules: dict[str, pathlib.Path]) -> list[str]:
    """``obj._name`` on anything but ``self``, ``cls`` or ``super()`` (another object's
    internals; ``p`` and ``np`` are pybullet's and numpy's own module-level names)."""
    found = []
    for path in modules.values():
        tree = ast.parse(path.read_text(), filename=str(path))
        for node in ast.walk(tree):
            if (isinstance(node, ast.Attribute) and node.attr.startswith("_")
                    and not node.attr.startswith("__") and node.attr not in PUBLIC_UNDERSCORE
                    and not (isinstance(node.value, ast.Name)
                             and node.value.id in ("self", "cls", "p", "np", "sys"))
                    and not (isinstance(node.value, ast.Call)
                             and isinstance(node.value.func, ast.Name)
                             and node.value.func.id == "super")):
                found.append(f"{path.relative_to(ROOT)}:{node.lineno} reads .{node.attr}")
    return found


def test_every_module_respects_the_layers():
    assert violations(source_modules()) == []


def test_no_import_circles_between_modules():
    assert import_cycles(source_modules()) == []


def test_no_module_reads_another_objects_private_attributes():
    assert private_attribute_reads(source_modules()) == []


@pytest.fixture
def fake_root(tmp_path, monkeypatch):
    monkeypatch.setattr(__import__(__name__, fromlist=["ROOT"]), "ROOT", tmp_path)
    for folder in FOLDERS:
        (tmp_path / folder).mkdir()
    return tmp_path


def _write(root: pathlib.Path, files: dict[str, str]) -> dict[str, pathlib.Path]:
    for rel, text in files.items():
        (root / rel).parent.mkdir(parents=True, exist_ok=True)
        (root / rel).write_text(text)
    return source_modules(root)


def test_a_reversed_import_is_caught(fake_root):
    mods = _write(fake_root, {
        "slipenv/contracts/__init__.py": "",
        "slipenv/terramechanics/__init__.py": "from slipenv.envs.slip_env import SlipEnv\n",
        "slipenv/envs/__init__.py": "", "slipenv/envs/slip_env.py": "SlipEnv = 1\n",
    })
    found = violations(mods)
    assert len(found) == 1 and "higher layer slipenv.envs.slip_env" in found[0]


def test_an_estimator_importing_the_simulator_is_caught(fake_root):
    mods = _write(fake_root, {
        "estimators/__init__.py": "", "estimators/ekf.py": "from slipenv.sensors import beacons\n",
        "slipenv/sensors/__init__.py": "", "slipenv/sensors/beacons.py": "",
    })
    assert any("may import only" in v for v in violations(mods))


def test_bare_names_private_imports_and_the_cli_are_caught(fake_root):
    mods = _write(fake_root, {
        "slipenv/run.py": "import estimators.base\nfrom slipenv.sim.wheel_soil import _kernel\n"
                          "from slipenv.cli import main\n",
        "slipenv/sim/__init__.py": "", "slipenv/sim/wheel_soil.py": "",
        "slipenv/cli.py": "",
    })
    found = "\n".join(violations(mods))
    assert "bare name 'estimators.base'" in found
    assert "private name '_kernel'" in found
    assert "nothing imports the command line" in found


def test_a_relative_import_circle_is_caught(fake_root):
    mods = _write(fake_root, {
        "slipenv/diagnose/__init__.py": "",
        "slipenv/diagnose/replay.py": "from .segments import cut\n",
        "slipenv/diagnose/segments.py": "from . import replay\ncut = 1\n",
    })
    assert import_cycles(mods) == [["slipenv.diagnose.replay", "slipenv.diagnose.segments"]]


def test_reading_another_objects_private_attribute_is_caught(fake_root):
    mods = _write(fake_root, {"slipenv/envs/__init__.py": "def f(sim):\n    return sim._rows\n"})
    assert private_attribute_reads(mods) == ["slipenv/envs/__init__.py:2 reads ._rows"]
