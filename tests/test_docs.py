"""The README is a front page and the MkDocs site holds the manual: the README stays short and
links only to pages that exist, every page of docs/ is in the site's navigation, and neither
the docs nor the source cite tracker numbers or commit ids (history lives in CHANGELOG.md).

The strict build itself (broken links, unresolved API references) runs here: the ``test``
extra installs MkDocs."""

from __future__ import annotations

import pathlib
import re
import subprocess
import sys

import yaml

ROOT = pathlib.Path(__file__).resolve().parents[1]
README = (ROOT / "README.md").read_text()
DOCS = ROOT / "docs"
# A tracker reference ("issue", "issues", optional "#", a number); a 7-40 digit hex word with a
# letter and a digit that
# is not a number (dates and dataset session ids are all digits, 1.52843e6 is a float).
TRACKER = re.compile(r"\b[Ii]ssues? #?\d+")
COMMIT = re.compile(r"(?<![.\d])\b(?!\d+e\d+\b)(?=[0-9a-f]*[a-f])(?=[0-9a-f]*\d)[0-9a-f]{7,40}\b")
# Where a commit id is a source's provenance, not this repository's history: the real datasets'
# upstream commits (slipenv/logs adapters and the real-data page cite the exact data version).
PROVENANCE = re.compile(r"(optiodom|BorealTC)[^\n]{0,40}commit|\"commit\":", re.I)


def _nav_pages(nav) -> list[str]:
    out = []
    for entry in nav:
        value = next(iter(entry.values())) if isinstance(entry, dict) else entry
        out += _nav_pages(value) if isinstance(value, list) else [value]
    return out


def _mkdocs_config() -> dict:
    # mkdocs.yml may carry !!python tags in other projects; this one is plain YAML.
    return yaml.safe_load((ROOT / "mkdocs.yml").read_text())


def test_the_readme_is_a_front_page_of_at_most_300_lines():
    assert len(README.splitlines()) <= 300


def test_the_readme_quick_start_holds_exactly_the_two_commands():
    section = re.search(r"^## Quick start$(.*?)^## ", README, re.M | re.S).group(1)
    blocks = re.findall(r"```bash\n(.*?)```", section, re.S)
    commands = [line for block in blocks for line in block.splitlines() if line.strip()]
    assert commands == [
        "pip install torch==2.13.0 && pip install -e . && slipenv run slipenv/FarmField-v0",
        'pip install torch==2.13.0 && pip install -e ".[test]" && python -m pytest -q -n 2',
    ]


def test_every_relative_link_of_the_readme_exists():
    links = re.findall(r"\]\(([^)#\s]+)(?:#[^)]*)?\)", README)
    relative = [link for link in links if "://" not in link]
    assert relative, "the README links into docs/"
    missing = [link for link in relative if not (ROOT / link).exists()]
    assert not missing, missing


def test_every_docs_page_is_in_the_site_navigation():
    config = _mkdocs_config()
    in_nav = set(_nav_pages(config["nav"]))
    on_disk = {p.relative_to(DOCS).as_posix() for p in DOCS.rglob("*.md")}
    assert on_disk - in_nav == set()
    assert in_nav - on_disk == set()


def _text_files():
    for pattern in ("*.md", "*.py", "*.c", "*.h", "*.toml", "*.yml", "*.yaml", ".ci/run"):
        for path in ROOT.rglob(pattern) if "/" not in pattern else [ROOT / pattern]:
            rel = path.relative_to(ROOT)
            if rel.parts[0] in {"runs", "build", "site", ".git"} or ".egg-info" in str(rel):
                continue
            if rel.as_posix() in {"CHANGELOG.md", "tests/test_docs.py"}:  # history; the checker
                continue
            yield rel, path.read_text(errors="replace")


def test_no_tracker_numbers_or_commit_ids_in_docs_or_source():
    hits = []
    for rel, text in _text_files():
        for number, line in enumerate(text.splitlines(), 1):
            if TRACKER.search(line) or (COMMIT.search(line) and not PROVENANCE.search(line)):
                hits.append(f"{rel}:{number}: {line.strip()[:90]}")
    assert not hits, "\n".join(hits)


def test_the_commit_id_check_catches_a_commit_and_spares_numbers():
    assert COMMIT.search("before the physics of commit a1b2c3d")
    reference = "(see " + "issue" + " 1)"  # built here so this file holds no reference itself
    assert COMMIT.search(reference) is None and TRACKER.search(reference)
    assert COMMIT.search("session 250620201738, 1.52843e6") is None


def test_the_site_builds_strictly(tmp_path):
    done = subprocess.run([sys.executable, "-m", "mkdocs", "build", "--strict", "-q",
                           "-d", str(tmp_path / "site")], cwd=ROOT, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-4000:]
