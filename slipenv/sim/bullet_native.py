"""Where pybullet keeps its physics clients, and on which pybullet builds the compiled loop may
read them natively.

The compiled wheel loop can read contacts, link and joint states and apply its forces through
Bullet's client C API, which the pybullet module exports, instead of through pybullet's Python
functions that wrap the same calls in tuples (``slipenv/sim/bullet_native.h``). It needs the C
handle behind a client id: pybullet keeps it in its static table ``sPhysicsClients1``, which
is not exported but is listed in the module's ELF symbol table. This module reads that table's
offset (and the offset of an exported function, whose address gives the module's load address)
from the file once per process.

The loop fills structs mirrored from pybullet's ``SharedMemoryPublic.h``, so it binds only on
the pybullet releases in `NATIVE_PYBULLET_VERSIONS` whose ``getAPIVersion()`` (the shared-memory
magic number bullet3 raises whenever it changes those structs incompatibly) is the one listed;
on any other build it reads through the Python API and `client_table` warns once, naming the
version. On a listed build three guards stay on (``bullet_native.h``): each struct pybullet
fills is followed by a canary region checked after every substep; the native readings are
compared with the Python API's bit for bit, in every value the loop acts on (a wheel without
contact has no contact patch to compare), on the first substep with contact and then on every
`VERIFY_EVERY`-th substep with contact. A failed check switches that loop to the Python API for
good (``WheelLoop.native_mismatch``) and warns once (`NativeReaderWarning`).

``SLIPENV_PYBULLET_API=1`` is the one switch: it makes the compiled loop read PyBullet through
its Python API everywhere (`python_api_forced`). Native access is also off where it cannot
work (no ELF symbol table, e.g. a stripped build or another platform).
"""

from __future__ import annotations

import functools
import importlib.metadata
import struct
import warnings
from collections.abc import Callable
from pathlib import Path
from typing import NamedTuple

from slipenv.contracts.switches import env_flag
from slipenv.pybullet_quiet import import_pybullet

__all__ = ["NATIVE_PYBULLET_VERSIONS", "PYBULLET_API_ENV", "VERIFY_EVERY", "ClientTable",
           "NativeReaderWarning", "client_table", "elf_symbols", "native_refusal",
           "pybullet_version", "python_api_forced", "warn_native_mismatch"]

PYBULLET_API_ENV = "SLIPENV_PYBULLET_API"

NATIVE_PYBULLET_VERSIONS: dict[str, int] = {
    # release: getAPIVersion(). The loop's struct mirrors match these builds: checked bit for bit
    # against the Python API on both (tests/sim/test_bullet_native.py), and both report the
    # magic number bullet3 has kept since its last struct change (October 2020).
    "3.2.6": 202010061,
    "3.2.7": 202010061,
}
"""The pybullet releases the native reader binds on, with the API version each reports."""

VERIFY_EVERY = 50
"""Compare the native readings with the Python API's on every this-many-th substep with contact
(after the first, which is always compared); 0 compares only the first. One comparison costs a
Python-API read, 20-35 µs on slipenv/Configurable-v0 (the loop's own read timer: 7 µs per
substep natively, 28 µs comparing on every substep), against 90-180 µs per substep for the
whole env step, so at 50 the comparisons cost about 0.5 % of an env step."""

_TABLE = "sPhysicsClients1"  # pybullet.c: static b3PhysicsClientHandle sPhysicsClients1[...]
_ANCHOR = "b3CanSubmitCommand"  # exported: its address gives the module's load address
_SHT_SYMTAB = 2

_warned: set[str] = set()


class NativeReaderWarning(RuntimeWarning):
    """The compiled loop reads PyBullet through its Python API, not natively, because the
    native reader is not trusted on this pybullet (unlisted version, or a check failed)."""


class ClientTable(NamedTuple):
    """pybullet's client table and the loop's checks, as `WheelLoop.bind_native` takes them."""

    path: str  # the loaded pybullet module
    offset: int  # of sPhysicsClients1 from the module's load address [bytes]
    n_clients: int  # entries in the table
    anchor_offset: int  # of b3CanSubmitCommand [bytes]
    verify_every: int  # compare with the Python API every this-many substeps with contact
    on_mismatch: Callable[[str], None]  # called with the reason when a check fails


def python_api_forced() -> bool:
    """True if ``SLIPENV_PYBULLET_API`` asks the compiled loop to use pybullet's Python API."""
    return env_flag(PYBULLET_API_ENV)


@functools.cache
def pybullet_version() -> str | None:
    """The installed pybullet release (``importlib.metadata``, read once: ~1 ms, and every
    reset builds an injector that asks), or None if it is not known."""
    try:
        return importlib.metadata.version("pybullet")
    except importlib.metadata.PackageNotFoundError:
        return None


def native_refusal(version: str | None = None, api_version: int | None = None) -> str | None:
    """Why the native reader must not bind on this pybullet, or None if it may.

    `version` and `api_version` default to the installed pybullet's release and
    ``getAPIVersion()``.
    """
    version = pybullet_version() if version is None else version
    if api_version is None:
        api_version = int(import_pybullet().getAPIVersion())
    listed = ", ".join(NATIVE_PYBULLET_VERSIONS)
    if version not in NATIVE_PYBULLET_VERSIONS:
        return (f"pybullet {version} is not one of the releases whose structs the native reader "
                f"mirrors ({listed})")
    if api_version != NATIVE_PYBULLET_VERSIONS[version]:
        return (f"pybullet {version} reports API version {api_version}, not "
                f"{NATIVE_PYBULLET_VERSIONS[version]} as the release the native reader mirrors")
    return None


def _warn_once(message: str) -> None:
    """Warn `message` (`NativeReaderWarning`) the first time it occurs in this process."""
    if message in _warned:
        return
    _warned.add(message)
    warnings.warn(message, NativeReaderWarning, stacklevel=3)


def warn_native_mismatch(reason: str) -> None:
    """The compiled loop's report of a failed check (`reason`): warn once per reason."""
    _warn_once(f"the native PyBullet reader failed a check on pybullet {pybullet_version()} "
               f"({reason}); the compiled loop reads PyBullet through its Python API")


def elf_symbols(path: str | Path, names: set[str]) -> dict[str, tuple[int, int]]:
    """``{name: (value, size)}`` of the `names` found in the ELF64 symbol table of `path`.

    Reads only the section headers, the symbol table and its string table (a few MB of a
    140 MB module). An empty dict if the file is not a little-endian ELF64 file or has no
    symbol table.
    """
    found: dict[str, tuple[int, int]] = {}
    wanted = {name.encode(): name for name in names}
    with open(path, "rb") as f:
        ident = f.read(64)
        if len(ident) < 64 or ident[:4] != b"\x7fELF" or ident[4] != 2 or ident[5] != 1:
            return found
        shoff, = struct.unpack_from("<Q", ident, 0x28)
        shentsize, shnum = struct.unpack_from("<HH", ident, 0x3A)
        f.seek(shoff)
        table = f.read(shentsize * shnum)
        sections = [struct.unpack_from("<IIQQQQIIQQ", table, i * shentsize)
                    for i in range(shnum)]
        for _, kind, _, _, offset, size, link, _, _, entsize in sections:
            if kind != _SHT_SYMTAB or entsize < 24 or link >= shnum:
                continue
            f.seek(offset)
            symbols = f.read(size)
            f.seek(sections[link][4])
            strings = f.read(sections[link][5])
            for st_name, _, _, _, value, sym_size in struct.iter_unpack("<IBBHQQ", symbols):
                end = strings.find(b"\0", st_name)
                name = wanted.get(strings[st_name:end])
                if name is not None and value:
                    found[name] = (value, sym_size)
    return found


@functools.cache
def _symbols(path: str) -> tuple[int, int, int] | None:
    """(table offset, entries, anchor offset) from the module file at `path` (read once)."""
    try:
        symbols = elf_symbols(path, {_TABLE, _ANCHOR})
    except OSError:
        return None
    if _TABLE not in symbols or _ANCHOR not in symbols:
        return None
    offset, size = symbols[_TABLE]
    n_clients = size // struct.calcsize("P")
    if n_clients < 1:
        return None
    return offset, n_clients, symbols[_ANCHOR][0]


def client_table() -> ClientTable | None:
    """pybullet's client table with the loop's checks, or None if native access is unavailable
    (not a listed pybullet release, `native_refusal`: warned once, naming the version; no ELF
    symbol table)."""
    refusal = native_refusal()
    if refusal is not None:
        _warn_once(f"{refusal}; the compiled loop reads PyBullet through its Python API")
        return None
    path = getattr(import_pybullet(), "__file__", None)
    found = _symbols(str(path)) if path else None
    if found is None:
        return None
    offset, n_clients, anchor = found
    return ClientTable(str(path), offset, n_clients, anchor, VERIFY_EVERY, warn_native_mismatch)
