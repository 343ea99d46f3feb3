"""The pytest plugin as a user sees it: a test file outside the repo using ``slipenv_eval``."""

from __future__ import annotations

import importlib.metadata

pytest_plugins = ["pytester"]

USER_TESTS = '''
import gymnasium as gym
import pytest

from slipenv.controllers import baseline_controller

ENV = "slipenv/TrackedSlopeCircle-v0"
SHORT = {"path_kwargs": {"radius_m": 0.25, "speed_mps": 0.05, "loops": 0.1}}


class WrongWay:
    """The baseline with its steering command reversed."""

    def __init__(self):
        env = gym.make(ENV, **SHORT)
        self.base = baseline_controller(env)
        env.close()

    def reset(self):
        self.base.reset()

    def predict(self, obs, state=None, episode_start=None, deterministic=True):
        action, _ = self.base.predict(obs)
        action = action.copy()
        action[..., 1] *= -1.0
        return action, None


def test_baseline_tracks_the_slope(slipenv_eval):
    ev = slipenv_eval("baseline", ENV, seeds=range(2), **SHORT)
    assert ev.cross_track_rmse_m < 0.08
    ev.assert_below("cross_track_rmse_m", 0.08)


def test_baseline_completes_the_path(slipenv_eval):
    slipenv_eval("baseline", ENV, seeds=range(2), **SHORT).assert_above("success_rate", 0.99)


def test_the_cache_ran_each_seed_once(slipenv_eval_cache):
    assert slipenv_eval_cache.episodes_run == 2


def test_wrong_way_controller_completes_the_path(slipenv_eval):
    # Its episodes end where it leaves the corridor: success, not the RMSE of what is left
    # of them, tells it from the baseline.
    slipenv_eval(WrongWay(), ENV, seeds=[0, 1], **SHORT).assert_above("success_rate", 0.99)
'''


def test_the_plugin_is_registered_under_the_pytest11_entry_point():
    found = [e for e in importlib.metadata.entry_points(group="pytest11")
             if "slipenv" in e.value]
    assert [(e.name, e.value) for e in found] == [("slipenv", "slipenv.evaluation.pytest_plugin")]


def test_user_test_file_passes_for_the_baseline_and_fails_readably_for_a_wrong_way_controller(
        pytester):
    pytester.makepyfile(test_user=USER_TESTS)
    result = pytester.runpytest_subprocess("-p", "no:cacheprovider", "-q")
    result.assert_outcomes(passed=3, failed=1)
    result.stdout.fnmatch_lines([
        "*AssertionError: success_rate = 0 is not > 0.99 (WrongWay on "
        "slipenv/TrackedSlopeCircle-v0, seeds [[]0, 1]); worst episode: seed * with "
        "success = False (left the path corridor)",
        "FAILED test_user.py::test_wrong_way_controller_completes_the_path*",
    ])
