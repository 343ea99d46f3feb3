"""Dropped envs release their PyBullet client; resets do not grow native memory."""

from __future__ import annotations

import gc

import gymnasium as gym
import numpy as np
import pybullet as p
import pytest

import slipenv  # noqa: F401

MAX_CLIENT_ID = 512  # PyBullet hands out small ids; scan well beyond the 30 envs made here


def connected_clients() -> int:
    return sum(p.isConnected(i) for i in range(MAX_CLIENT_ID))


def rss_mib() -> float:
    with open("/proc/self/statm") as fh:
        return int(fh.read().split()[1]) * 4096 / 2**20


def test_thirty_envs_dropped_without_close_leave_no_client_and_bounded_memory():
    before = connected_clients()
    for _ in range(5):  # warm up caches and allocator pools
        env = gym.make("slipenv/HuskySand-v0")
        env.reset(seed=0)
        del env
    rss0 = rss_mib()
    for k in range(30):
        env = gym.make("slipenv/HuskySand-v0")
        env.reset(seed=k)
        del env  # no close(): the simulator's finalizer disconnects
    assert connected_clients() == before  # released at once, without gc.collect()
    gc.collect()
    # Before the finalizer each client kept ~40 MiB: 30 would be 1.2 GiB.
    assert rss_mib() - rss0 < 60.0


def test_close_disconnects_and_is_idempotent():
    env = gym.make("slipenv/HuskySand-v0")
    env.reset(seed=0)
    client = env.unwrapped.physics_client_id
    assert p.isConnected(client)
    env.close()
    assert not p.isConnected(client)
    env.close()


@pytest.mark.parametrize("call", ["step", "reset"])
def test_step_or_reset_after_close_is_a_runtime_error_saying_the_env_is_closed(call):
    env = gym.make("slipenv/HuskySand-v0")
    env.reset(seed=0)
    env.close()
    with pytest.raises(RuntimeError, match=rf"env is closed: {call}\(\) after close\(\)"):
        env.step(env.action_space.sample()) if call == "step" else env.reset(seed=1)
    with pytest.raises(RuntimeError, match="env is closed"):  # the raw env, no wrappers
        env.unwrapped.step(np.zeros(2)) if call == "step" else env.unwrapped.reset(seed=1)


def test_a_thousand_farm_resets_stay_within_two_mib():
    # FarmField rebuilt its vehicle at every reset, leaking ~22 KB of native shapes each
    # time (22 MB per 1000); the body is now rewound instead.
    env = gym.make("slipenv/FarmField-v0").unwrapped
    try:
        for k in range(50):
            env.reset(seed=k)
        rss0 = rss_mib()
        for k in range(1000):
            env.reset(seed=k)
        assert rss_mib() - rss0 < 2.0
    finally:
        env.close()
