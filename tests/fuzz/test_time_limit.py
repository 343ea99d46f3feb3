"""The fuzz suite's per-case time limit really interrupts a hang."""

from __future__ import annotations

import time

import pytest

from .conftest import CaseTimeout, time_limit


def test_the_time_limit_interrupts_a_busy_loop():
    start = time.monotonic()
    with pytest.raises(CaseTimeout), time_limit(0.2):
        while True:
            pass
    assert time.monotonic() - start < 2.0


def test_the_time_limit_leaves_a_quick_block_alone_and_disarms():
    with time_limit(0.5):
        pass
    time.sleep(0.6)  # an armed timer would fire here
