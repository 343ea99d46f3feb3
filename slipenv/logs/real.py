"""Convert the real datasets (OptiOdom, BorealTC) into slipenv-log/1 folders.

The datasets live in ``<data_root>/optiodom-diffdrive`` and ``<data_root>/borealtc-husky``
(see their READMEs). ``data_root`` is given, or read from ``$SLIPENV_REAL_DATA``, or, failing
both, the project's shared data folder ``../shared/data/real`` beside a source checkout. A
root holding neither dataset is an error naming the folder looked in; a root holding one of
them converts it with a warning naming the other's missing folder. A few runs of each ship
inside the package (``slipenv.logs.examples``), already converted.

Output layout::

    <out_dir>/optiodom/<path type>_<session>_run-NN/{meta.json, signals.csv}
    <out_dir>/borealtc/<TERRAIN>_NN/{meta.json, signals.csv}   (no ground truth)
"""

from __future__ import annotations

import os
import warnings
from pathlib import Path

from tqdm import tqdm

from slipenv.logs.borealtc import BorealRun, list_borealtc_runs, load_borealtc_run
from slipenv.logs.io import write_log
from slipenv.logs.optiodom import OptiOdomRun, list_optiodom_runs, load_optiodom_run

OPTIODOM_DIR = "optiodom-diffdrive"
BOREALTC_DIR = "borealtc-husky"


def default_data_root() -> Path:
    """``$SLIPENV_REAL_DATA`` if set, else ``<repository>/../shared/data/real``."""
    env = os.environ.get("SLIPENV_REAL_DATA")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[2].parent / "shared" / "data" / "real"


def convert_real_datasets(
    out_dir: str | Path,
    data_root: str | Path | None = None,
    *,
    progress: bool = True,
) -> list[Path]:
    """Write every OptiOdom and BorealTC run as a slipenv-log/1 folder.

    Parameters
    ----------
    out_dir : str or Path
        Output folder (created); existing logs of the same name are overwritten.
    data_root : str or Path, optional
        Folder holding ``optiodom-diffdrive/`` and/or ``borealtc-husky/``; a missing dataset
        folder is skipped with a warning. Defaults to ``default_data_root()``.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    list of Path
        The written log folders, OptiOdom first.

    Raises
    ------
    FileNotFoundError
        If ``data_root`` holds neither dataset, or no run in them (the message names the
        folder and how to point at the data).
    """
    root = Path(data_root) if data_root is not None else default_data_root()
    how = ("" if data_root is not None else
           " (the default: pass data_root=... or set SLIPENV_REAL_DATA to the folder holding "
           f"{OPTIODOM_DIR}/ and {BOREALTC_DIR}/)")
    present = [name for name in (OPTIODOM_DIR, BOREALTC_DIR) if (root / name).is_dir()]
    if not present:
        raise FileNotFoundError(f"no real dataset in {root}{how}: expected {OPTIODOM_DIR}/ "
                                f"and/or {BOREALTC_DIR}/ in it")
    for name in [n for n in (OPTIODOM_DIR, BOREALTC_DIR) if n not in present]:
        warnings.warn(f"{root / name} not found: that dataset is not converted", stacklevel=2)
    out = Path(out_dir)
    jobs: list[OptiOdomRun | BorealRun] = []
    jobs += list_optiodom_runs(root / OPTIODOM_DIR)
    jobs += list_borealtc_runs(root / BOREALTC_DIR)
    if not jobs:
        raise FileNotFoundError(f"no run files in {', '.join(str(root / n) for n in present)}"
                                f"{how}: expected <path type>/<session>/<session>_run-NN.csv "
                                "or <TERRAIN>/pro_NN.csv")
    written: list[Path] = []
    for job in tqdm(jobs, desc="converting real logs", unit="run", disable=not progress):
        if isinstance(job, OptiOdomRun):
            written.append(write_log(load_optiodom_run(job), out / "optiodom" / job.name))
        else:
            written.append(write_log(load_borealtc_run(job), out / "borealtc" / job.name,
                                     require_ground_truth=False))
    return written
