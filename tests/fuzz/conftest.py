"""Shared pieces of the fuzz suite: a hard per-case time limit and the settings profile.

Every property runs few examples (the suite runs in CI on every change, in well under a
minute) and each case must finish within its time limit: a hang is a failure, not a stall.
"""

from __future__ import annotations

import contextlib
import os
import signal
import tempfile
from collections.abc import Iterator
from datetime import timedelta
from pathlib import Path

from hypothesis import HealthCheck, Phase, settings
from hypothesis import strategies as st
from hypothesis.configuration import set_hypothesis_home_dir

# Hypothesis' caches go to the temp folder, not into the checkout.
set_hypothesis_home_dir(os.path.join(tempfile.gettempdir(), "slipenv-hypothesis"))

CASE_LIMIT_S = 20.0  # hard bound per case (signal), far above a normal case's ~1 s

# ``SLIPENV_FUZZ_EXAMPLES=500 pytest tests/fuzz`` for a longer hunt than CI's.
FUZZ = settings(
    max_examples=int(os.environ.get("SLIPENV_FUZZ_EXAMPLES", "40")),
    deadline=timedelta(seconds=CASE_LIMIT_S),
    database=None,  # no .hypothesis folder in the checkout
    phases=[Phase.explicit, Phase.reuse, Phase.generate, Phase.shrink],  # no patch files
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)


class CaseTimeout(Exception):
    """A fuzz case ran past its time limit (something hangs)."""


@contextlib.contextmanager
def time_limit(seconds: float = CASE_LIMIT_S) -> Iterator[None]:
    """Raise :class:`CaseTimeout` in the main thread if the block runs over ``seconds``."""

    def expire(signum, frame):
        raise CaseTimeout(f"fuzz case still running after {seconds} s")

    previous = signal.signal(signal.SIGALRM, expire)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0.0)
        signal.signal(signal.SIGALRM, previous)


def names_in(value, prefix: str = "") -> set[str]:
    """Every key name in a (nested) kwargs dict: what an error message may name."""
    out: set[str] = set()
    if isinstance(value, dict):
        for key, inner in value.items():
            out.add(str(key))
            out |= names_in(inner)
    return out


CSV_CORRUPTIONS = ("cell", "row_len", "drop_column", "swap_rows", "truncate")


def corrupt_csv(path: Path, kind: str, k: int, cell: str) -> None:
    """Corrupt the CSV file ``path`` in place: one ``cell`` written into a data row, a row one
    field short or long, a column dropped, two rows swapped, or the text cut (``k`` picks
    where)."""
    rows = [line.split(",") for line in path.read_text().splitlines()]
    if kind == "cell":
        r = 1 + k % (len(rows) - 1)
        rows[r][k % len(rows[r])] = cell.replace(",", ";").replace("\n", " ")
    elif kind == "row_len":
        r = 1 + k % (len(rows) - 1)
        rows[r] = rows[r][:-1] if k % 2 else rows[r] + ["1"]
    elif kind == "drop_column":
        c = k % len(rows[0])
        rows = [row[:c] + row[c + 1:] for row in rows]
    elif kind == "swap_rows":
        a, b = 1 + k % (len(rows) - 1), 1 + (k // 7) % (len(rows) - 1)
        rows[a], rows[b] = rows[b], rows[a]
    elif kind == "truncate":
        text = "\n".join(",".join(row) for row in rows)
        path.write_text(text[: k % (len(text) + 1)])
        return
    else:
        raise ValueError(f"not a CSV corruption: {kind!r}")
    path.write_text("\n".join(",".join(row) for row in rows) + "\n")


def corruptions(other_kinds: tuple[str, ...], cells, meta_values, meta_keys):
    """Cases ``(kind, k, cell, meta value, meta key)``: a CSV corruption (a cell twice as
    likely) or one of ``other_kinds`` (meta data, bytes), ``k`` picking where."""
    kinds = st.sampled_from(["cell", *CSV_CORRUPTIONS, *other_kinds])
    return st.tuples(kinds, st.integers(0, 10**6), cells, meta_values,
                     st.sampled_from(meta_keys))
