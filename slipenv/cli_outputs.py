"""What a command writes: its output paths checked before the work, and where an interrupted
command left its partial results.

Every ``slipenv`` subcommand checks its outputs with :func:`output_dir` and :func:`output_file`
before any long work starts, so a path that cannot be written costs the user one line (status 2),
not the results of an hour's run. A check writes for real (it creates the folder, or creates and
removes the file) because only the file system knows: permission bits say nothing to root, and
``/proc`` or a read-only mount look like ordinary folders.

A Ctrl-C is reported once, by ``slipenv.cli.main``: "interrupted; partial results in PATH" when
the work was inside a :func:`partial_results` block whose path holds something, else
"interrupted; nothing written"; status :data:`INTERRUPTED_STATUS`.
"""

from __future__ import annotations

import errno
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import overload

__all__ = ["INTERRUPTED_STATUS", "OutputPathError", "interrupted_message", "output_dir",
           "output_file", "partial_results"]

INTERRUPTED_STATUS = 130
"""Exit status after Ctrl-C: 128 + SIGINT, as a shell reports a process the signal ended."""

_PARTIAL = "slipenv_partial_results"
"""Attribute of the ``KeyboardInterrupt`` that names the partial results (innermost wins)."""


class OutputPathError(ValueError):
    """An output path that cannot be written; the message names the option and the reason."""


def _quoted(path: Path | str) -> str:
    return repr(str(path))


def _reason(exc: OSError, where: Path) -> str:
    """The user's words for why ``where`` could not be written."""
    if exc.errno == errno.ENOENT:  # the parent exists (it was just made): e.g. under /proc
        return f"the file system does not take new files in {_quoted(where)}"
    if exc.errno in (errno.EACCES, errno.EPERM):
        return f"permission denied in {_quoted(where)}"
    if exc.errno == errno.EROFS:
        return f"{_quoted(where)} is on a read-only file system"
    return exc.strerror or str(exc)


def _blocking_file(path: Path) -> Path | None:
    """The nearest existing part of ``path`` (``path`` included) when it is not a folder."""
    for part in (path, *path.parents):
        if part.exists() or part.is_symlink():
            return None if part.is_dir() else part
    return None


def _fail(option: str, path: Path | str, reason: str) -> OutputPathError:
    return OutputPathError(f"{option} {_quoted(path)}: {reason}")


def output_dir(path: str | Path, option: str) -> Path:
    """Create the folder ``path`` (with its parents) and prove a file can be written in it.

    Raises
    ------
    OutputPathError
        ``path`` or one of its parents is a file, or the folder cannot be written; the
        message is one line naming ``option``.
    """
    return _make_dir(Path(path), option, path)


def _make_dir(folder: Path, option: str, shown: str | Path) -> Path:
    """:func:`output_dir` of ``folder``; errors name ``shown`` (the path the user gave)."""
    wall = _blocking_file(folder)
    if wall is not None:
        what = "is a file, not a folder" if wall == Path(shown) else \
            f"cannot write there ({_quoted(wall)} is a file, not a folder)"
        raise _fail(option, shown, what)
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        made = next((p for p in folder.parents if p.is_dir()), Path("."))
        raise _fail(option, shown, f"cannot write there ({_reason(exc, made)})") from None
    _create_and_remove(folder / f".slipenv-write-test-{os.getpid()}", option, shown)
    return folder


@overload
def output_file(path: str | Path, option: str) -> Path: ...


@overload
def output_file(path: None, option: str) -> None: ...


def output_file(path: str | Path | None, option: str) -> Path | None:
    """Prove that the file ``path`` can be written (``None`` passes through).

    Its folder is created; the file itself is left as it was: an existing file is opened for
    appending and closed unchanged, a new one is created and removed.

    Raises
    ------
    OutputPathError
        ``path`` is a folder, a parent is a file, or it cannot be written (one line naming
        ``option``).
    """
    if path is None:
        return None
    file = Path(path)
    if file.is_dir():
        raise _fail(option, path, "is a folder, not a file")
    try:
        if file.exists():
            fd = os.open(file, os.O_WRONLY | os.O_APPEND | os.O_NONBLOCK)
            os.close(fd)
            return file
    except OSError as exc:  # the file exists: its own permissions or kind are the reason
        reason = (exc.strerror or str(exc)).lower()
        raise _fail(option, path, f"cannot write to it ({reason})") from None
    _make_dir(file.parent, option, path)
    _create_and_remove(file, option, path)
    return file


def _create_and_remove(file: Path, option: str, shown: Path | str) -> None:
    """Create ``file`` (new) and remove it: as root, permission bits let everything through
    and ``/proc`` looks like a folder, so only a real write tells."""
    try:
        fd = os.open(file, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    except OSError as exc:
        raise _fail(option, shown, f"cannot write there ({_reason(exc, file.parent)})") from None
    os.close(fd)
    file.unlink()


def _holds_something(path: Path) -> bool:
    if path.is_dir():
        return any(path.iterdir())
    return path.exists()


@contextmanager
def partial_results(*paths: str | Path | None, note: str = "") -> Iterator[None]:
    """Within the block, a Ctrl-C names the first of ``paths`` that holds something (a file,
    or a folder with something in it) as the partial results; ``None`` entries are skipped.

    ``note`` is added in brackets (e.g. how to resume). An inner block's answer wins over an
    outer one's. The ``KeyboardInterrupt`` always propagates; ``slipenv.cli.main`` prints
    :func:`interrupted_message`.
    """
    try:
        yield
    except KeyboardInterrupt as exc:
        if getattr(exc, _PARTIAL, None) is None:
            for path in (Path(p) for p in paths if p is not None):
                if _holds_something(path):
                    setattr(exc, _PARTIAL, f"{path} ({note})" if note else str(path))
                    break
        raise


def interrupted_message(exc: BaseException) -> str:
    """"interrupted; partial results in PATH" or "interrupted; nothing written"."""
    where = getattr(exc, _PARTIAL, None)
    return f"interrupted; partial results in {where}" if where else "interrupted; nothing written"
