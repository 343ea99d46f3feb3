"""The fitted slip model the tracked env observes with, as version-controlled data.

``slipenv/data/yamauchi_slip_model.json`` is read by the env registration through
:mod:`importlib.resources` (:data:`MODEL_FILE`) and never written by the package at run time.
A maintainer refreshes it with ``slipenv reproduce yamauchi --save-model PATH`` in a source
checkout, reviews the diff and commits it; :func:`save_model` refuses to write into an
installed package (``site-packages``/``dist-packages``), where a file would silently change
what every user of that installation observes.
"""

from __future__ import annotations

import json
from pathlib import Path as FsPath

from slipenv.envs.registration import yamauchi_model_file

MODEL_FILE = yamauchi_model_file()
"""The shipped model (an :mod:`importlib.resources` path; read it, do not write it)."""

INSTALLED_DIRS = ("site-packages", "dist-packages")


def model_record(model, n: float, source: str) -> dict:
    """What the model file holds: the Eq. 9 regression, Endo's n and how they were made."""
    return {"beta_model": model.to_dict(), "n": n, "source": source}


def model_path(path: str | FsPath, allow_installed: bool = False) -> FsPath:
    """``path`` resolved, checked as a place to write the model file.

    Raises
    ------
    ValueError
        If ``path`` lies inside an installed package's folder (``site-packages`` or
        ``dist-packages``) and ``allow_installed`` is False, or if ``path`` is not a str
        or path (e.g. the old ``save_model=True``).
    """
    if isinstance(path, bool) or not isinstance(path, (str, FsPath)):
        raise ValueError(f"save_model must be a file path, got {path!r}")
    out = FsPath(path).expanduser().resolve()
    if not allow_installed and any(part in INSTALLED_DIRS for part in out.parts):
        raise ValueError(f"save_model: refusing to write {out} inside an installed package; "
                         "write it in a source checkout (slipenv/data/) and commit it")
    return out


def save_model(record: dict, path: str | FsPath, allow_installed: bool = False) -> FsPath:
    """Write ``record`` as JSON to ``path`` (folder created), checked by :func:`model_path`."""
    out = model_path(path, allow_installed)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(record, indent=2) + "\n")
    return out
