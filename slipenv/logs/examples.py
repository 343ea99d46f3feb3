"""Example logs shipped inside the package: two real runs and one generated log.

``path(name)`` is the slipenv-log/1 folder of an example, ready for ``read_log`` or
``slipenv diagnose`` (``slipenv diagnose --example NAME`` runs on it):

- ``borealtc``: BorealTC run SNOW/05, a Clearpath Husky A200 on snow, converted by
  ``slipenv.logs.borealtc`` (wheel speeds, motor currents, IMU; no ground truth). Dataset by
  LaRocque, Guimont-Martin, Duclos, Giguère, Pomerleau (IROS 2024), CC0 1.0.
- ``optiodom``: OptiOdom run square/230620202042/run-01, a small differential-drive robot
  driving a clockwise square on a lab floor with OptiTrack ground truth, converted by
  ``slipenv.logs.optiodom``. By Sousa, Petry, Moreira, Costa (J. Intell. Robot. Syst. 2022),
  MIT license; the license text is in the example's folder.
- ``synthetic``: a one-minute log of the farm vehicle from ``slipenv.diagnose.synth`` with one
  effect hidden in the simulated physics; ``meta.json["synth"]`` names it (``effect``) with
  the values set (``world``) and the effective ones (``truth``).

Each real example keeps its source's attribution in ``meta.json`` (``source``, ``notes``) and
in a file beside the log. How each was made is in ``slipenv/data/examples/README.md``;
``write_real_examples`` redoes the two real ones from the datasets.
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

from slipenv.logs.borealtc import list_borealtc_runs, load_borealtc_run
from slipenv.logs.io import write_log
from slipenv.logs.optiodom import list_optiodom_runs, load_optiodom_run

NAMES = ("borealtc", "optiodom", "synthetic")
"""The shipped examples, in the order ``slipenv diagnose --example`` lists them."""
DESCRIPTIONS = {
    "borealtc": "real, Husky A200 on snow, BorealTC SNOW/05, CC0 1.0, no ground truth",
    "optiodom": "real, differential drive with OptiTrack truth, OptiOdom, MIT",
    "synthetic": "generated, one effect hidden in the physics, named in its meta.json",
}
"""One line per example (``slipenv diagnose --help``)."""
BOREALTC_RUN = ("SNOW", 5)
"""(terrain, index) of the shipped BorealTC run: turns enough to show the snow's yaw slip."""
OPTIODOM_RUN = ("square", "230620202042", 1)
"""(path type, session, run) of the shipped OptiOdom run."""


def root() -> Path:
    """The folder holding the example logs (inside the installed package)."""
    return Path(str(resources.files("slipenv") / "data" / "examples"))


def path(name: str) -> Path:
    """The log folder of example ``name`` (one of ``NAMES``).

    Raises
    ------
    ValueError
        If ``name`` is not an example (the message lists them).
    FileNotFoundError
        If the package was installed without its data files.
    """
    if name not in NAMES:
        raise ValueError(f"unknown example {name!r}; the examples are {', '.join(NAMES)}")
    folder = root() / name
    if not (folder / "meta.json").is_file():
        raise FileNotFoundError(f"example log {name!r} missing at {folder}: the package was "
                                "installed without its data files")
    return folder


def write_real_examples(data_root: str | Path, out_dir: str | Path | None = None
                        ) -> dict[str, Path]:
    """Convert the two shipped real runs from the datasets again (how they were made).

    Parameters
    ----------
    data_root : str or Path
        Folder holding ``borealtc-husky/`` and ``optiodom-diffdrive/``.
    out_dir : str or Path, optional
        Where to write ``borealtc/`` and ``optiodom/``; the package's example folder if None.

    Returns
    -------
    dict
        Example name -> written log folder.
    """
    data, out = Path(data_root), Path(out_dir) if out_dir is not None else root()
    terrain, index = BOREALTC_RUN
    boreal = next((r for r in list_borealtc_runs(data / "borealtc-husky")
                   if (r.terrain, r.index) == (terrain, index)), None)
    path_type, session, number = OPTIODOM_RUN
    opti = next((r for r in list_optiodom_runs(data / "optiodom-diffdrive")
                 if (r.path_type, r.session, r.run) == (path_type, session, number)), None)
    if boreal is None or opti is None:
        raise FileNotFoundError(f"the example runs are not in {data}: expected "
                                f"borealtc-husky/{terrain}/pro_{index:02d}.csv and "
                                f"optiodom-diffdrive/{path_type}/{session}/"
                                f"{session}_run-{number:02d}.csv")
    return {
        "borealtc": write_log(load_borealtc_run(boreal), out / "borealtc",
                              require_ground_truth=False),
        "optiodom": write_log(load_optiodom_run(opti), out / "optiodom"),
    }
