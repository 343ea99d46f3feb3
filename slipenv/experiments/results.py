"""Writing an experiment's result: standard JSON, the printed table, the figures and the page."""

from __future__ import annotations

import json
import math
from collections.abc import Callable, Sequence
from pathlib import Path as FsPath
from typing import Any

import numpy as np


def finite(obj: Any) -> Any:
    """``obj`` with NaN/inf replaced by None and numpy values by Python ones (standard JSON)."""
    if isinstance(obj, dict):
        return {k: finite(v) for k, v in obj.items()}
    if isinstance(obj, (list, tuple)):
        return [finite(v) for v in obj]
    if isinstance(obj, np.ndarray):
        return finite(obj.tolist())
    if isinstance(obj, (float, np.floating)):
        return float(obj) if math.isfinite(obj) else None
    if isinstance(obj, np.integer):
        return int(obj)
    if isinstance(obj, np.bool_):
        return bool(obj)
    return obj


def write_json(result: dict, json_path: str | FsPath) -> FsPath:
    """Write ``result`` as indented standard JSON, creating the folder."""
    out = FsPath(json_path)
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out, "w") as fh:
        json.dump(finite(result), fh, indent=2)
    return out


def publish(result: dict, table: str, figures: Sequence[str | FsPath],
            json_path: str | FsPath | None, docs_dir: str | FsPath | None,
            write_page: Callable[[dict, Any, Any], FsPath], notes: Sequence[str] = ()) -> None:
    """How every ``slipenv reproduce`` ends: print the paper-vs-simulation `table` and where
    the `figures` went (and any `notes`), write the result as JSON to `json_path` and the docs
    page with `write_page(result, figures, docs_dir)`, each when asked."""
    print(table)
    print("figures: " + ", ".join(str(f) for f in figures))
    for line in notes:
        print(line)
    if json_path:
        print(f"metrics: {write_json(result, json_path)}")
    if docs_dir is not None:
        print(f"page: {write_page(result, figures, docs_dir)}")
