"""Choosing a thing by name: one "did you mean" for every registry and option in slipenv."""

from __future__ import annotations

import difflib
from collections.abc import Iterable, Mapping
from typing import TypeVar

T = TypeVar("T")


def did_you_mean(name: object, choices: Iterable[object]) -> str:
    """``"; did you mean 'x'?"`` for the choice closest to ``name``, or ``""`` if none is close.

    A choice that contains ``name`` counts as close when none is by spelling (``"sand"`` hints
    ``"loose_sand"``).
    """
    options = sorted(map(str, choices))
    close = difflib.get_close_matches(str(name), options, n=1)
    close = close or [c for c in options if str(name) and str(name) in c][:1]
    return f"; did you mean {close[0]!r}?" if close else ""


def lookup(table: Mapping[str, T], name: str, what: str) -> T:
    """``table[name]``, or a ``ValueError`` naming the unknown ``what``, the closest name and
    every known one."""
    try:
        return table[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown {what} {name!r}{did_you_mean(name, table)}; known {what}s: "
                         f"{', '.join(sorted(table))}") from None
