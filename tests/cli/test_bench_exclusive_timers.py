"""The breakdown's timers count a nested timed call once (``_observe`` calls the
timed path projection; counting it in both moved its time out of ``rest`` twice)."""

from __future__ import annotations

import time

import slipenv.bench as bench


def test_nested_timed_call_is_counted_once_and_for_its_own_key():
    timers = bench._Timers()
    inner = timers.wrap(lambda: time.sleep(0.02), "observation_reward")
    outer = timers.wrap(lambda: inner(), "observation_reward")
    outer()
    assert 0.02 <= timers.seconds["observation_reward"] < 0.035  # twice would be >= 0.04

    other = bench._Timers()
    inner = other.wrap(lambda: time.sleep(0.02), "truth")
    outer = other.wrap(lambda: (inner(), time.sleep(0.01)), "sensors")
    outer()
    assert 0.02 <= other.seconds["truth"] < 0.03
    assert 0.01 <= other.seconds["sensors"] < 0.02  # its own 10 ms, not the inner 20 ms too
