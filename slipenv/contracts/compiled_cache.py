"""numba's on-disk cache, kept true to the source it was compiled from.

numba keys a cached function on the modification time and size of the file that defines it.
A compiled function that calls compiled functions of other files carries their code too, so
after an edit of only a callee's file (the track model's `track.py` under
`track_soil._substep`, the Lindgren observation models under the filter's frame kernel) numba
would load the caller's old machine code. Each compiled module calls
:func:`refresh_stale_cache` with the files its kernels are built from; when their content differs
from the content its cache was built on, the module's cached functions are deleted and compile
again on first use.

Installed (non-editable) copies never change under their cache and need none of this; a
read-only ``__pycache__`` is left alone.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import pathlib

__all__ = ["refresh_stale_cache", "sources_digest"]


def sources_digest(*files: str | os.PathLike[str]) -> str:
    """SHA-256 over the bytes of ``files``, each prefixed by its name (order-independent)."""
    h = hashlib.sha256()
    for path in sorted(pathlib.Path(f) for f in files):
        h.update(path.name.encode())
        h.update(path.read_bytes())
    return h.hexdigest()


def refresh_stale_cache(entry_file: str | os.PathLike[str],
                        *dependency_files: str | os.PathLike[str]) -> bool:
    """Delete numba's cache of ``entry_file``'s functions if it or ``dependency_files`` changed.

    ``dependency_files`` relative to ``entry_file``'s folder, or absolute.
    The digest of the sources is kept next to the cache
    (``__pycache__/<module>.sources.sha256``). Returns whether cached functions were deleted.
    """
    entry = pathlib.Path(entry_file)
    cache_dir = entry.parent / "__pycache__"
    digest = sources_digest(entry, *(entry.parent / f for f in dependency_files))
    stamp = cache_dir / f"{entry.stem}.sources.sha256"
    with contextlib.suppress(OSError):  # no stamp yet: the cache's source is unknown
        if stamp.read_text() == digest:
            return False
    stale = [p for pattern in (f"{entry.stem}.*.nbi", f"{entry.stem}.*.nbc")
             for p in cache_dir.glob(pattern)]
    try:
        for path in stale:
            path.unlink(missing_ok=True)
        cache_dir.mkdir(exist_ok=True)
        # written whole then renamed: a process importing at the same time reads the old stamp
        # or the new one, never half of one
        tmp = stamp.with_name(f"{stamp.name}.{os.getpid()}.tmp")
        tmp.write_text(digest)
        os.replace(tmp, stamp)
    except OSError:
        return False
    return bool(stale)
