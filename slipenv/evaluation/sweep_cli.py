"""``slipenv sweep GRID.yaml [--backend local|ray] [--address ADDR] [--out DIR]``.

Registered by :mod:`slipenv.cli` with ``add_parser(sub)``; ``main(args)`` returns the exit code:
2 with one line on stderr for a bad grid file or an output folder that cannot be written
(before any episode), or when Ray is missing or cannot start. On Ctrl-C the finished cells stay
in ``OUT/cells``: the same command resumes.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Any

DEFAULT_OUT = "runs/sweep/{grid}"


def add_parser(sub: Any) -> argparse.ArgumentParser:
    """Add the ``sweep`` subcommand to ``sub`` (an ``add_subparsers()`` result)."""
    p = sub.add_parser("sweep", help="run an evaluation grid (env ids x soils x slopes x "
                                     "policies x seeds) locally or on Ray; resumable")
    p.add_argument("grid", help="grid file (YAML; see slipenv.evaluation.grid)")
    p.add_argument("--backend", default="local", choices=("local", "ray"),
                   help="local process pool or Ray tasks")
    p.add_argument("--address", default=None,
                   help="Ray cluster to join (e.g. auto or ray://host:10001; None: start "
                        "a local Ray)")
    p.add_argument("--workers", type=int, default=None,
                   help="processes / local Ray CPUs (None: all cores)")
    p.add_argument("--out", default=DEFAULT_OUT,
                   help="results folder ({grid} = the grid file's name without its suffix)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(func=main)
    return p


def _fail(message: str) -> int:
    print(f"slipenv sweep: error: {message}", file=sys.stderr)
    return 2


def main(args: argparse.Namespace) -> int:
    """Run ``slipenv sweep``; 0 on success, 2 on a bad grid, an output folder that cannot be
    written or an unavailable Ray."""
    from slipenv.cli_outputs import output_dir, partial_results
    from slipenv.evaluation.grid import load_grid
    from slipenv.evaluation.sweep import RayUnavailable, run_sweep, summarize

    try:
        if args.workers is not None and args.workers < 1:
            raise ValueError(f"--workers must be >= 1, got {args.workers}")
        if args.address is not None and args.backend != "ray":
            raise ValueError("--address joins a Ray cluster: use it with --backend ray")
        cells = load_grid(args.grid)
    except ValueError as exc:
        return _fail(str(exc).splitlines()[0])
    if args.backend == "ray":
        try:
            import ray  # noqa: F401
        except ImportError:
            return _fail("the ray backend needs Ray, which is not installed: "
                         "pip install 'slipenv[ray]'")
    try:
        template = args.out or DEFAULT_OUT
        out = output_dir(template.replace("{grid}", Path(args.grid).stem), "--out")
    except ValueError as exc:
        return _fail(str(exc))
    (out / "grid.yaml").write_text(Path(args.grid).read_text())
    try:
        with partial_results(out / "cells", note="the same command runs the rest"):
            rows = run_sweep(cells, out, backend=args.backend, workers=args.workers,
                             address=args.address, quiet=args.quiet)
    except RayUnavailable as exc:
        return _fail(str(exc))
    print(summarize(rows))
    return 0
