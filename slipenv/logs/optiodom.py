"""Adapter: OptiOdom differential-drive runs (OptiTrack ground truth) -> slipenv-log/1.

Source: github.com/sousarbarb/optiodom (commit 8e025fd7, ``data/diff/``), by Ricardo B. Sousa,
Marcelo R. Petry, António P. Moreira and Paulo G. Costa (INESC TEC / FEUP), "OptiOdom: a
Generic Approach for Odometry Calibration of Wheeled Mobile Robots", J. Intell. Robot. Syst.,
2022. MIT license, (c) 2021 the authors; the attribution travels in each log's ``meta.json``.

Layout: ``<root>/<path type>/<session>/<session>_run-NN.csv`` (no header, 20 Hz: time [s],
ground-truth x, y [m] and heading [rad] relative to the start pose, then tick increments of
the *right* wheel (column 5) and the *left* wheel (column 6)) beside
``<session>_metadata.csv`` (``ngear``, ``encRes``, ``Li`` [m], ``Di`` [m] right then left, and
the synchronisation windows). Some files may start with a UTF-8 byte-order mark. Every file is
read plain (``.csv``, the source repository's layout) or gzip-compressed (``.csv.gz``); a run
whose session has no metadata file is skipped with a ``UserWarning`` naming the file.

The metadata ``Li``/``Di`` are the parameters the robot's own odometry used in that session;
they differ between sessions (Li 0.2 or 0.205 m, Di 0.084 or 0.085 m) and are the nominal
values here. The ground-truth heading is continuous (unwrapped), as in the source.
"""

from __future__ import annotations

import gzip
import math
import re
import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from slipenv.logs.errors import LogFormatError
from slipenv.logs.log import Log
from slipenv.logs.meta import LogMeta

PATH_TYPES = ("square", "circular", "ivanjko")
SOURCE = {
    "dataset": "OptiOdom (data/diff, June 2020 sessions)",
    "url": "https://github.com/sousarbarb/optiodom",
    "commit": "8e025fd7a30c7152132e0ae53ba23bbc909f5a81",
    "authors": ["Ricardo B. Sousa", "Marcelo R. Petry", "António P. Moreira", "Paulo G. Costa"],
    "paper": "OptiOdom: a Generic Approach for Odometry Calibration of Wheeled Mobile Robots, "
             "J. Intell. Robot. Syst., 2022",
    "license": "MIT, (c) 2021 the authors",
}
_RUN_FILE = re.compile(r"^(?P<session>\d+)_run-(?P<run>\d+)\.csv(?P<gz>\.gz)?$")


@dataclass(frozen=True)
class OptiOdomRun:
    """One OptiOdom run file.

    Attributes
    ----------
    csv_path : Path
        ``<session>_run-NN.csv``.
    metadata_path : Path
        The session's ``<session>_metadata.csv``.
    path_type : str
        ``square``, ``circular`` or ``ivanjko``.
    session : str
        Session name (DDMMYYYYhhmm).
    run : int
        Run number NN (1-based, as in the file name).
    """

    csv_path: Path
    metadata_path: Path
    path_type: str
    session: str
    run: int

    @property
    def name(self) -> str:
        return f"{self.path_type}_{self.session}_run-{self.run:02d}"


def list_optiodom_runs(root: str | Path) -> list[OptiOdomRun]:
    """All runs under ``root`` (the dataset folder), sorted by name.

    Files are found plain or gzip-compressed (the plain one wins when both are there). A run
    whose session has no ``<session>_metadata.csv[.gz]`` is left out with a warning: its
    wheel geometry and encoder resolution are in that file.
    """
    runs = []
    for path_type in PATH_TYPES:
        found: dict[tuple[str, int], Path] = {}
        for csv_path in sorted(Path(root, path_type).glob("*/*_run-*.csv*")):
            match = _RUN_FILE.match(csv_path.name)
            if match is None:
                continue
            key = (match["session"], int(match["run"]))
            if key not in found or not match["gz"]:
                found[key] = csv_path
        for (session, run), csv_path in sorted(found.items()):
            metadata = _plain_or_gz(csv_path.parent / f"{session}_metadata.csv")
            if metadata is None:
                warnings.warn(f"OptiOdom run {csv_path}: no {session}_metadata.csv(.gz) beside "
                              "it (wheel diameters, wheelbase, encoder resolution); run skipped",
                              stacklevel=2)
                continue
            runs.append(OptiOdomRun(csv_path, metadata, path_type, session, run))
    return runs


def _plain_or_gz(path: Path) -> Path | None:
    """``path`` if it is a file, else ``path.gz`` if that is, else None."""
    for candidate in (path, path.with_name(path.name + ".gz")):
        if candidate.is_file():
            return candidate
    return None


def _read_text(path: Path) -> str:
    """A plain or gzip-compressed file's text (a UTF-8 byte-order mark dropped)."""
    raw = gzip.decompress(path.read_bytes()) if path.suffix == ".gz" else path.read_bytes()
    return raw.decode("utf-8-sig")


def read_optiodom_metadata(path: str | Path) -> dict[str, list[float]]:
    """Parse ``<session>_metadata.csv`` into key -> numeric values (empty cells dropped)."""
    out: dict[str, list[float]] = {}
    for line in _read_text(Path(path)).splitlines():
        cells = [c.strip() for c in line.split(",")]
        if not cells[0]:
            continue
        values = []
        for cell in cells[1:]:
            try:
                values.append(float(cell))
            except ValueError:
                continue  # empty cells and the text value of 'type'
        out[cells[0]] = values
    return out


def _read_run_table(path: Path) -> np.ndarray:
    rows = []
    for line_no, line in enumerate(_read_text(path).splitlines(), 1):
        if not line.strip():
            continue
        cells = line.split(",")
        if len(cells) != 6:
            raise LogFormatError(path, f"{len(cells)} cells, expected 6", line=line_no)
        try:
            rows.append([float(c) for c in cells])
        except ValueError:
            raise LogFormatError(path, "non-numeric cell", line=line_no) from None
    return np.array(rows, dtype=np.float64).reshape(-1, 6)


def load_optiodom_run(run: OptiOdomRun) -> Log:
    """Convert one run into a validated diff_drive log.

    Encoder counts are the cumulative sums of the tick increments (right wheel = column 5,
    left = column 6); ``counts_per_rad = ngear * encRes / (2 pi)`` (445.1 counts/rad for
    43.7 x 64); wheel radius = mean nominal diameter / 2; track width = ``Li``.

    Returns
    -------
    Log
        Columns ``t, enc_left, enc_right, gt_x, gt_y, gt_yaw``.
    """
    md = read_optiodom_metadata(run.metadata_path)
    for key, count in (("ngear", 1), ("encRes", 1), ("Li", 1), ("Di", 2)):
        if len(md.get(key, [])) < count:
            raise LogFormatError(run.metadata_path, f"no {key!r} row with {count} number(s) "
                                 "(the session's wheel and encoder parameters)")
    table = _read_run_table(run.csv_path)
    d_right, d_left = md["Di"][0], md["Di"][1]
    counts_per_rad = md["ngear"][0] * md["encRes"][0] / (2.0 * math.pi)
    k = run.run - 1
    window = {name: md[name][k] for name in ("gt_ti", "gt_tf", "odo_ti", "odo_tf")
              if len(md.get(name, [])) > k}
    meta = LogMeta.new(
        "diff_drive", ["left", "right"],
        wheel_radius_m=0.25 * (d_right + d_left),
        track_width_m=md["Li"][0],
        counts_per_rad=counts_per_rad,
        terrain_description="indoor lab floor (OptiTrack arena)",
        notes=(f"OptiOdom run {run.name}, converted by slipenv. Source: {SOURCE['url']} "
               f"(commit {SOURCE['commit'][:8]}, data/diff/), by {', '.join(SOURCE['authors'])};"
               f" {SOURCE['paper']}. License: {SOURCE['license']}. Ground truth: OptiTrack, "
               "relative to the start pose, heading unwrapped. Wheel radius and track width "
               "are the session's nominal (robot-odometry) values from the metadata file."),
        source=dict(SOURCE),
        optiodom={
            "path_type": run.path_type, "session": run.session, "run": run.run,
            "file": f"{run.path_type}/{run.session}/{run.csv_path.name}",
            "ngear": md["ngear"][0], "encRes": md["encRes"][0], "Li_m": md["Li"][0],
            "Di_right_m": d_right, "Di_left_m": d_left, "sync_windows_s": window,
        },
    )
    return Log.from_arrays(
        meta,
        t=table[:, 0],
        enc_left=np.cumsum(table[:, 5]),
        enc_right=np.cumsum(table[:, 4]),
        gt_x=table[:, 1],
        gt_y=table[:, 2],
        gt_yaw=table[:, 3],
    )
