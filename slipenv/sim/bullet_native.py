"""Where pybullet keeps its physics clients, for the compiled loop's native queries (issue 15).

The compiled wheel loop can read contacts, link and joint states and apply its forces through
Bullet's client C API, which the pybullet module exports, instead of through pybullet's Python
functions that wrap the same calls in tuples (``slipenv/sim/bullet_native.h``). It needs the C
handle behind a client id: pybullet keeps it in its static table ``sPhysicsClients1``, which
is not exported but is listed in the module's ELF symbol table. This module reads that table's
offset (and the offset of an exported function, whose address gives the module's load address)
from the file once per process.

Nothing here is trusted blindly: the loop compares its first native readings with the Python
API's bit for bit and falls back to the Python API if they differ (``WheelLoop.native_mismatch``).
Native access is off where it cannot work (no ELF symbol table, e.g. a stripped build or another
platform) and with ``SLIPENV_PYBULLET_API=1`` (`python_api_forced`).
"""

from __future__ import annotations

import functools
import struct
from pathlib import Path
from typing import NamedTuple

from slipenv.contracts.switches import env_flag
from slipenv.pybullet_quiet import import_pybullet

__all__ = ["PYBULLET_API_ENV", "ClientTable", "client_table", "elf_symbols", "python_api_forced"]

PYBULLET_API_ENV = "SLIPENV_PYBULLET_API"

_TABLE = "sPhysicsClients1"  # pybullet.c: static b3PhysicsClientHandle sPhysicsClients1[...]
_ANCHOR = "b3CanSubmitCommand"  # exported: its address gives the module's load address
_SHT_SYMTAB = 2


class ClientTable(NamedTuple):
    """pybullet's client table, as `WheelLoop.bind_native` takes it."""

    path: str  # the loaded pybullet module
    offset: int  # of sPhysicsClients1 from the module's load address [bytes]
    n_clients: int  # entries in the table
    anchor_offset: int  # of b3CanSubmitCommand [bytes]


def python_api_forced() -> bool:
    """True if ``SLIPENV_PYBULLET_API`` asks the compiled loop to use pybullet's Python API."""
    return env_flag(PYBULLET_API_ENV)


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
def client_table() -> ClientTable | None:
    """pybullet's client table, or None if native access is unavailable (read once)."""
    path = getattr(import_pybullet(), "__file__", None)
    if not path:
        return None
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
    return ClientTable(str(path), offset, n_clients, symbols[_ANCHOR][0])
