"""Convert the real datasets (OptiOdom, BorealTC) into slipenv-log/1 folders.

The datasets live in ``<data_root>/optiodom-diffdrive`` and ``<data_root>/borealtc-husky``
(see their READMEs). ``data_root`` defaults to ``$SLIPENV_REAL_DATA`` or, failing that, the
project's shared data folder ``../shared/data/real`` beside the repository.

Output layout::

    <out_dir>/optiodom/<path type>_<session>_run-NN/{meta.json, signals.csv}
    <out_dir>/borealtc/<TERRAIN>_NN/{meta.json, signals.csv}   (no ground truth)
"""

from __future__ import annotations

import os
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
        Folder holding ``optiodom-diffdrive/`` and ``borealtc-husky/``; a missing dataset
        folder is skipped. Defaults to ``default_data_root()``.
    progress : bool
        Show a tqdm progress bar.

    Returns
    -------
    list of Path
        The written log folders, OptiOdom first.
    """
    root = Path(data_root) if data_root is not None else default_data_root()
    out = Path(out_dir)
    jobs: list[OptiOdomRun | BorealRun] = []
    jobs += list_optiodom_runs(root / OPTIODOM_DIR)
    jobs += list_borealtc_runs(root / BOREALTC_DIR)
    written: list[Path] = []
    for job in tqdm(jobs, desc="converting real logs", unit="run", disable=not progress):
        if isinstance(job, OptiOdomRun):
            written.append(write_log(load_optiodom_run(job), out / "optiodom" / job.name))
        else:
            written.append(write_log(load_borealtc_run(job), out / "borealtc" / job.name,
                                     require_ground_truth=False))
    return written
