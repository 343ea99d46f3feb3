"""Run a grid of evaluations on local processes or Ray, resumably, into one table.

Every cell (one episode) writes its own result file ``OUT/cells/<cell key>.json`` as soon as
it finishes (written to a temporary name, then renamed, so a killed run never leaves half a
file). A re-run skips the cells whose file exists, so an interrupted grid resumes where it
stopped. The table is gathered from the files of the grid's cells, in grid order:
``OUT/results.csv`` always, ``OUT/results.parquet`` too when pyarrow is installed
(``pip install slipenv[parquet]``).

Backends: ``local`` — a process pool (``spawn``, ``workers`` processes) with a progress bar;
``ray`` — one Ray task per cell, on a local Ray started on the fly or on the cluster at
``address`` (``pip install slipenv[ray]``).
"""

from __future__ import annotations

import csv
import json
import os
import signal
import sys
import threading
from collections.abc import Callable, Iterator, Sequence
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np

from slipenv.evaluation.grid import Cell

BACKENDS = ("local", "ray")
TABLE_KEYS = ("env_id", "variation", "policy", "seed")
SUMMARY_METRICS = ("success", "cross_track_rmse_m", "mean_cross_track_m", "energy_j",
                   "odometry_final_error_m", "ape_rmse_m")


def run_cell(cell: dict, out_dir: str) -> dict:
    """Run one cell (a :meth:`Cell.to_dict`) and write its result file; returns the row.

    A module-level function of plain data, so a process pool or a Ray worker can run it.
    """
    from slipenv.evaluation.evaluator import run_episode
    from slipenv.evaluation.policies import resolve_policy

    metrics, _ = run_episode(resolve_policy(cell["policy"]), cell["env_id"], cell["seed"],
                             cell["env_kwargs"], cell["max_steps"])
    row = {**{k: cell[k] for k in TABLE_KEYS},
           **{k: v for k, v in metrics.items() if k != "seed"}, "cell": cell["key"]}
    target = Path(out_dir) / "cells" / f"{cell['key']}.json"
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp = target.with_suffix(f".tmp{os.getpid()}")
    tmp.write_text(json.dumps({"cell": cell, "row": row}, indent=1, default=_nan_safe))
    os.replace(tmp, target)
    return row


def _nan_safe(obj: Any) -> Any:
    if isinstance(obj, np.generic):
        return obj.item()
    raise TypeError(f"not JSON serialisable: {obj!r}")


def finished(cells: Sequence[Cell], out_dir: str | Path) -> set[str]:
    """Keys of the cells whose result file exists."""
    folder = Path(out_dir) / "cells"
    return {c.key for c in cells if (folder / f"{c.key}.json").is_file()}


def _progress(total: int, quiet: bool):
    from tqdm.auto import tqdm

    return tqdm(total=total, unit="cell", desc="sweep", disable=quiet, file=sys.stderr)


def run_local(todo: list[dict], out_dir: str, workers: int, quiet: bool) -> None:
    """Run cells on a ``spawn`` process pool (``workers`` = 1 runs them in this process)."""
    bar = _progress(len(todo), quiet)
    try:
        if workers <= 1:
            for cell in todo:
                run_cell(cell, out_dir)
                bar.update(1)
            return
        import multiprocessing
        from concurrent.futures import ProcessPoolExecutor, as_completed

        from slipenv.envs.compiled import warm_up

        warm_up()  # compiled here once, not by every worker at the same time on a cold cache
        ctx = multiprocessing.get_context("spawn")
        with ProcessPoolExecutor(max_workers=workers, mp_context=ctx,
                                 initializer=_leave_ctrl_c_to_the_parent) as pool:
            with _workers_ignore_ctrl_c():  # the workers start during the submissions
                futures = [pool.submit(run_cell, cell, out_dir) for cell in todo]
            try:
                for fut in as_completed(futures):
                    fut.result()  # re-raise a cell's error here
                    bar.update(1)
            except KeyboardInterrupt:
                _stop_now(pool)
                raise
    finally:
        bar.close()


def _leave_ctrl_c_to_the_parent() -> None:
    """Pool initializer. Ctrl-C reaches every process of the terminal's group: workers ignore
    it (no traceback per worker) and the parent stops them (:func:`_stop_now`)."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@contextmanager
def _workers_ignore_ctrl_c() -> Iterator[None]:
    """Processes started inside the block ignore Ctrl-C from their first instruction (an
    ignored signal stays ignored across ``exec``), not only once the initializer has run
    after their imports. Only the main thread may change signal handlers; elsewhere the
    initializer alone does it."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous)


def _stop_now(pool) -> None:
    """Drop the queued cells and end the running ones. A cell's result file appears by an
    atomic rename, so an ended cell leaves no result file (at most a ``.tmp`` one) and runs
    again on resume."""
    # The executor has no public way to end running tasks; its worker table (stable since
    # Python 3.3) is emptied by shutdown(), so it is read first.
    workers = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in workers:
        process.terminate()


class RayUnavailable(RuntimeError):
    """Ray is not installed or cannot start (the message is one line for the user)."""


def run_ray(todo: list[dict], out_dir: str, workers: int, quiet: bool,
            address: str | None = None) -> None:
    """Run cells as Ray tasks: a local Ray with ``workers`` CPUs, or the cluster at
    ``address`` (``ray://host:10001`` or ``auto``)."""
    try:
        import ray
    except ImportError:
        raise RayUnavailable("the ray backend needs Ray: pip install 'slipenv[ray]'") from None
    started = False
    if not ray.is_initialized():
        try:
            kwargs: dict[str, Any] = {"include_dashboard": False, "log_to_driver": False,
                                      "logging_level": "ERROR"}
            if address is None:
                kwargs["num_cpus"] = max(workers, 1)
                # Workers must import this very slipenv (an editable or PYTHONPATH checkout).
                kwargs["runtime_env"] = {"env_vars": {"PYTHONPATH": os.pathsep.join(
                    p for p in sys.path if p)}}
            ray.init(address=address, **kwargs)
            started = True
        except Exception as exc:  # noqa: BLE001  (Ray raises many kinds; the user needs one line)
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
            raise RayUnavailable(f"Ray could not start ({first})") from None
    remote = ray.remote(num_cpus=1)(run_cell)
    bar = _progress(len(todo), quiet)
    try:
        pending = [remote.remote(cell, str(Path(out_dir).resolve())) for cell in todo]
        try:
            while pending:
                done, pending = ray.wait(pending, num_returns=1)
                ray.get(done)
                bar.update(len(done))
        except KeyboardInterrupt:
            for ref in pending:  # a cluster would otherwise run the rest of the grid
                ray.cancel(ref, force=True)
            raise
    finally:
        bar.close()
        if started:
            ray.shutdown()


def gather(cells: Sequence[Cell], out_dir: str | Path) -> list[dict]:
    """The grid's rows from its result files, in grid order (a missing file is an error)."""
    folder = Path(out_dir) / "cells"
    rows = []
    for cell in cells:
        target = folder / f"{cell.key}.json"
        if not target.is_file():
            raise RuntimeError(f"cell {cell.key} ({cell.env_id}, {cell.variation}, "
                               f"{cell.policy}, seed {cell.seed}) has no result file")
        saved = json.loads(target.read_text())["row"]
        # Labels from this grid (an identical cell may have run under another label).
        rows.append({**{k: getattr(cell, k) for k in TABLE_KEYS},
                     **{k: v for k, v in saved.items() if k not in TABLE_KEYS}})
    return rows


def write_table(rows: list[dict], out_dir: str | Path) -> list[Path]:
    """``results.csv`` (floats as Python's shortest exact repr), plus ``results.parquet``
    when pyarrow is installed; returns the files written."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    columns = list(rows[0])
    with open(out / "results.csv", "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=columns)
        writer.writeheader()
        writer.writerows(rows)
    written = [out / "results.csv"]
    try:
        import pyarrow as pa
        import pyarrow.parquet as pq
    except ImportError:
        return written
    pq.write_table(pa.Table.from_pylist(rows), out / "results.parquet")
    return written + [out / "results.parquet"]


def summarize(rows: list[dict]) -> str:
    """Mean of the main metrics per (env id, variation, policy) over seeds, as a table."""
    groups: dict[tuple, list[dict]] = {}
    for row in rows:
        groups.setdefault((row["env_id"], row["variation"], row["policy"]), []).append(row)
    head = ["env_id", "variation", "policy", "n",
            *("success_rate" if k == "success" else k for k in SUMMARY_METRICS)]
    body = []
    for (env_id, variation, policy), members in groups.items():
        means = [float(np.mean([float(m[k]) for m in members])) for k in SUMMARY_METRICS]
        body.append([env_id, variation, policy, str(len(members)),
                     *(f"{v:.4g}" for v in means)])
    widths = [max(len(r[k]) for r in [head, *body]) for k in range(len(head))]
    lines = ["  ".join(h.ljust(w) for h, w in zip(head, widths, strict=True))]
    lines += ["  ".join(c.ljust(w) for c, w in zip(r, widths, strict=True)) for r in body]
    return "\n".join(lines)


def run_sweep(cells: Sequence[Cell], out_dir: str | Path, backend: str = "local",
              workers: int | None = None, address: str | None = None, quiet: bool = False,
              log: Callable[[str], None] = print) -> list[dict]:
    """Run the cells not yet finished in ``out_dir``, then gather and write the table.

    Parameters
    ----------
    cells : sequence of Cell
        From :func:`slipenv.evaluation.grid.load_grid`.
    backend : {"local", "ray"}
    workers : int, optional
        Processes (local) or CPUs of the local Ray; default ``os.cpu_count()``.
    address : str, optional
        Ray cluster to join (ray backend only).

    Returns
    -------
    list of dict
        The table's rows in grid order.
    """
    if backend not in BACKENDS:
        raise ValueError(f"--backend must be one of {', '.join(BACKENDS)}, got {backend!r}")
    if address is not None and backend != "ray":
        raise ValueError("--address joins a Ray cluster: use it with --backend ray")
    out = str(Path(out_dir))
    done = finished(cells, out)
    todo, seen = [], set(done)
    for cell in cells:
        if cell.key not in seen:  # identical cells (same hash) run once
            seen.add(cell.key)
            todo.append(cell.to_dict())
    workers = max(1, min(workers or os.cpu_count() or 1, len(todo) or 1))
    log(f"sweep: {len(cells)} cells, {len(cells) - len(todo)} already done, {len(todo)} to "
        f"run on {backend} ({workers} worker{'s' if workers > 1 else ''})")
    if todo:
        if backend == "local":
            run_local(todo, out, workers, quiet)
        else:
            run_ray(todo, out, workers, quiet, address)
    rows = gather(cells, out)
    for path in write_table(rows, out):
        log(f"table: {path}")
    return rows
