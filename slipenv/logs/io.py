"""Reading and writing slipenv-log/1 folders (``meta.json`` + ``signals.csv``).

Extra columns beyond the contract's table (e.g. ``current_left`` [A] from BorealTC) are read
and written like any other numeric column: the contract lists the columns it gives meaning to
but does not forbid others, so slipenv keeps them and tools ignore what they do not know.
"""

from __future__ import annotations

import csv
import io
import json
import math
from pathlib import Path
from typing import NoReturn

import numpy as np

from slipenv.logs.errors import LogFormatError
from slipenv.logs.log import Log, validate_signals
from slipenv.logs.meta import LogMeta, validate_meta

META_FILE = "meta.json"
SIGNALS_FILE = "signals.csv"


def read_log(path: str | Path, *, require_ground_truth: bool = True) -> Log:
    """Read and validate a slipenv-log/1 folder.

    Parameters
    ----------
    path : str or Path
        The log folder holding ``meta.json`` and ``signals.csv``.
    require_ground_truth : bool
        The contract requires ground-truth columns ``gt_x, gt_y, gt_yaw`` with values at some
        samples. Pass ``False`` to accept a log without any (e.g. the BorealTC conversions);
        the log is then outside the contract and only usable where no truth is needed.

    Returns
    -------
    Log
        Every column as float64 [SI units, counts for ``enc_*``]; empty or ``nan`` cells are
        NaN ("not measured").

    Raises
    ------
    LogFormatError
        Naming the file, the 1-based data row and file line, and the column (or, for
        ``meta.json``, the line and key path).
    """
    folder = Path(path)
    if not folder.is_dir():
        raise LogFormatError(folder, "not a log folder (expected meta.json + signals.csv)")
    meta = _read_meta(folder / META_FILE)
    signals, lines = _read_signals(folder / SIGNALS_FILE)
    validate_signals(meta, signals, folder / SIGNALS_FILE,
                     require_ground_truth=require_ground_truth, lines=lines, header_line=1)
    return Log(meta, signals, path=folder)


def write_log(log: Log, path: str | Path, *, require_ground_truth: bool = True) -> Path:
    """Validate ``log`` and write it as a slipenv-log/1 folder (created if needed).

    Floats are written with ``repr`` (shortest text that reads back bit-identical), encoder
    counts as integers, NaN as an empty cell. ``meta.json`` keeps every key of ``log.meta``.

    Parameters
    ----------
    log : Log
    path : str or Path
        Target folder; existing ``meta.json``/``signals.csv`` in it are replaced.
    require_ground_truth : bool
        See ``read_log``.

    Returns
    -------
    Path
        The folder.
    """
    folder = Path(path)
    validate_meta(log.meta.data, folder / META_FILE)
    validate_signals(log.meta, log.signals, folder / SIGNALS_FILE,
                     require_ground_truth=require_ground_truth)
    folder.mkdir(parents=True, exist_ok=True)
    text = json.dumps(log.meta.data, indent=2, allow_nan=False, ensure_ascii=False)
    (folder / META_FILE).write_text(text + "\n", encoding="utf-8")
    names = list(log.signals)
    if names[0] != "t":
        names.remove("t")
        names.insert(0, "t")
    enc = {f"enc_{w}" for w in log.meta.wheels}
    cells = [_format_column(log.signals[n], integer=n in enc) for n in names]
    buf = io.StringIO()
    buf.write(",".join(names) + "\n")
    for row in zip(*cells, strict=True):
        buf.write(",".join(row))
        buf.write("\n")
    (folder / SIGNALS_FILE).write_text(buf.getvalue(), encoding="utf-8")
    return folder


def _format_column(values: np.ndarray, *, integer: bool) -> list[str]:
    if integer:
        return [str(int(v)) for v in values.tolist()]
    return ["" if math.isnan(v) else repr(v) for v in values.tolist()]


def _read_meta(path: Path) -> LogMeta:
    if not path.is_file():
        raise LogFormatError(path, "missing file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise LogFormatError(path, "not UTF-8 text") from None
    try:
        data = json.loads(text, parse_constant=_reject_constant)
    except json.JSONDecodeError as err:
        raise LogFormatError(path, f"invalid JSON ({err.msg})", line=err.lineno,
                             column=str(err.colno), column_label="character") from None
    except ValueError as err:
        raise LogFormatError(path, f"invalid JSON ({err})") from None
    validate_meta(data, path, text)
    return LogMeta(data)


def _reject_constant(name: str) -> float:
    raise ValueError(f"{name} is not valid JSON")


def _read_signals(path: Path) -> tuple[dict[str, np.ndarray], np.ndarray]:
    """Parse ``signals.csv`` into float64 columns and the 1-based line of each data row."""
    if not path.is_file():
        raise LogFormatError(path, "missing file")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise LogFormatError(path, "not UTF-8 text") from None
    with io.StringIO(text, newline="") as fh:
        reader = csv.reader(fh)
        try:
            header = next(reader)
        except StopIteration:
            raise LogFormatError(path, "empty file (no header row)", line=1) from None
        names = [h.strip() for h in header]
        for k, name in enumerate(names):
            if not name:
                raise LogFormatError(path, f"empty column name at position {k + 1}", line=1)
            if name in names[:k]:
                raise LogFormatError(path, "duplicate column name", line=1, column=name)
        rows: list[list[str]] = []
        lines: list[int] = []
        blank: list[int] = []
        for row in reader:
            if not row or (len(row) == 1 and not row[0].strip()):
                blank.append(reader.line_num)
                continue
            if blank:  # a blank line followed by more data: not a trailing newline
                raise LogFormatError(path, "blank line inside the data",
                                     row=len(rows) + 1, line=blank[0])
            if len(row) != len(names):
                _ragged(path, names, row, len(rows) + 1, reader.line_num)
            rows.append(row)
            lines.append(reader.line_num)
    line_arr = np.asarray(lines, dtype=np.int64)
    signals: dict[str, np.ndarray] = {}
    for j, name in enumerate(names):
        signals[name] = _parse_column([r[j] for r in rows], path, name, line_arr)
    return signals, line_arr


def _ragged(path: Path, names: list[str], row: list[str], index: int, line: int) -> NoReturn:
    if len(row) < len(names):
        raise LogFormatError(path, f"{len(row)} cells, header has {len(names)}",
                             row=index, line=line, column=names[len(row)])
    raise LogFormatError(path, f"{len(row)} cells, header has {len(names)} (extra cells after "
                         f"the last column)", row=index, line=line, column=names[-1])


def _parse_column(cells: list[str], path: Path, name: str, lines: np.ndarray) -> np.ndarray:
    normalised = [c.strip() or "nan" for c in cells]
    try:
        return np.array(normalised, dtype=np.float64)
    except ValueError:
        pass
    out = np.empty(len(normalised))
    for i, cell in enumerate(normalised):  # slow path: find the offending cell
        try:
            out[i] = float(cell)
        except ValueError:
            raise LogFormatError(path, f"non-numeric value {cell!r}", row=i + 1,
                                 line=int(lines[i]), column=name) from None
    return out
