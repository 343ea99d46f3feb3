"""The breakdown's timers count a nested timed call once (``_observe`` calls the
timed path projection; counting it in both moved its time out of ``rest`` twice).

The timed work advances a fake clock by exact amounts: sleeping instead would make the
upper bounds depend on how busy the machine is."""

from __future__ import annotations

import pytest

import slipenv.bench as bench


class FakeClock:
    """``time.perf_counter`` that moves only when work is done."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now

    def work(self, seconds: float) -> None:
        self.now += seconds


def test_nested_timed_call_is_counted_once_and_for_its_own_key(monkeypatch):
    clock = FakeClock()
    monkeypatch.setattr(bench.time, "perf_counter", clock)
    timers = bench._Timers()
    inner = timers.wrap(lambda: clock.work(0.02), "observation_reward")
    outer = timers.wrap(lambda: inner(), "observation_reward")
    outer()
    assert timers.seconds["observation_reward"] == pytest.approx(0.02)  # twice would be 0.04

    other = bench._Timers()
    inner = other.wrap(lambda: clock.work(0.02), "truth")
    outer = other.wrap(lambda: (inner(), clock.work(0.01)), "sensors")
    outer()
    assert other.seconds["truth"] == pytest.approx(0.02)
    assert other.seconds["sensors"] == pytest.approx(0.01)  # its own 10 ms, not the inner 20 too
