"""The error raised for a log that breaks the slipenv-log/1 contract."""

from __future__ import annotations

from pathlib import Path


class LogFormatError(ValueError):
    """A measured log that does not follow ``log-format.md`` (slipenv-log/1).

    The message always names the file and, where they apply, the place in it: for
    ``signals.csv`` the 1-based *data row* (the header is not counted) together with the
    1-based *line* number of the file, and the column; for ``meta.json`` the 1-based line
    and the key path (``vehicle.kind``) or, for a JSON syntax error, the character position.

    Parameters
    ----------
    path : str or Path
        The offending file (``meta.json``, ``signals.csv``) or log folder.
    reason : str
        What is wrong, in words.
    row : int, optional
        1-based data row of ``signals.csv`` (row 1 is the first sample after the header).
    line : int, optional
        1-based line number in the file.
    column : str, optional
        Column name (``signals.csv``), key path (``meta.json``) or character position.
    column_label : str
        How ``column`` is introduced in the message: ``"column"``, ``"key"`` or
        ``"character"``.

    Attributes
    ----------
    path : Path
    row : int or None
    line : int or None
    column : str or None
    reason : str
    """

    def __init__(
        self,
        path: str | Path,
        reason: str,
        *,
        row: int | None = None,
        line: int | None = None,
        column: str | None = None,
        column_label: str = "column",
    ) -> None:
        self.path = Path(path)
        self.reason = reason
        self.row = row
        self.line = line
        self.column = column
        where: list[str] = []
        if row is not None:
            where.append(f"data row {row}" + (f" (line {line})" if line is not None else ""))
        elif line is not None:
            where.append(f"line {line}")
        if column is not None:
            where.append(f"{column_label} {column}" if column_label == "character"
                         else f"{column_label} '{column}'")
        location = ", ".join(where)
        super().__init__(f"{self.path}: {location + ': ' if location else ''}{reason}")

    def __reduce__(self) -> tuple[object, ...]:
        # Keep the error picklable (pytest-xdist ships exceptions between processes).
        return (_rebuild, (str(self.path), self.reason, self.row, self.line, self.column,
                           str(self)))


def _rebuild(path: str, reason: str, row: int | None, line: int | None, column: str | None,
             message: str) -> LogFormatError:
    err = LogFormatError(path, reason, row=row, line=line, column=column)
    err.args = (message,)
    return err
