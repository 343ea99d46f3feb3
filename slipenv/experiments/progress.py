"""Progress bars of the experiments (tqdm, imported only when a bar is shown)."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any


def step_bar(progress: bool, total: int, desc: str) -> Any:
    """A bar of ``total`` env steps for :func:`slipenv.rollout.rollout`, or None."""
    if not progress:
        return None
    from tqdm import tqdm

    return tqdm(total=total, desc=desc, unit="step", leave=False)


def iterate(items: Iterable, progress: bool, desc: str) -> Iterable:
    """``items``, wrapped in a bar when ``progress``."""
    if not progress:
        return items
    from tqdm import tqdm

    return tqdm(items, desc=desc, leave=False)
