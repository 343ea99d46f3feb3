"""Short episodes for the evaluation tests: a tenth of the tracked vehicle's slope circle
(~77 steps, ~0.5 s of CPU per episode)."""

from __future__ import annotations

import pytest

TRACKED = "slipenv/TrackedSlopeCircle-v0"
SHORT = {"path_kwargs": {"radius_m": 0.25, "speed_mps": 0.05, "loops": 0.1}}


@pytest.fixture
def short_kwargs() -> dict:
    return {"path_kwargs": dict(SHORT["path_kwargs"])}
