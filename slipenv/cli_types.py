"""Argument types shared by the command line's parsers (standard library only).

Each raises ``argparse.ArgumentTypeError`` with a one-line reason, which argparse turns into
``slipenv CMD: error: argument --x: ...`` and status 2.
"""

from __future__ import annotations

import argparse


def _integer(text: str, low: int, what: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer") from None
    if value < low:
        raise argparse.ArgumentTypeError(f"must be {what}, got {value}")
    return value


def positive_int(text: str) -> int:
    """An integer >= 1."""
    return _integer(text, 1, ">= 1")


def non_negative_int(text: str) -> int:
    """An integer >= 0 (seeds)."""
    return _integer(text, 0, ">= 0")
