"""Controllers as policies: act/predict contract, batching, SB3 evaluate_policy, registry."""

from __future__ import annotations

import math

import gymnasium as gym
import numpy as np
import pytest

from slipenv.contracts import observation as ob
from slipenv.controllers import (
    CONTROLLERS,
    OBS_NAMES,
    Policy,
    YamauchiController,
    build_observation,
    controller_by_name,
)
from slipenv.paths import circle, straight


def _random_obs(rng: np.random.Generator, n: int, scale: float = 1.0) -> np.ndarray:
    obs = rng.normal(size=(n, ob.OBS_DIM)) * scale
    obs[:, ob.OBS_REF_SPEED] = np.abs(obs[:, ob.OBS_REF_SPEED])
    return obs.astype(np.float32)


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_act_returns_float32_actions_within_bounds(scaling, name):
    ctrl = controller_by_name(name, **scaling)
    assert isinstance(ctrl, Policy)
    rng = np.random.default_rng(0)
    for obs in _random_obs(rng, 200, scale=50.0):
        action = ctrl.act(obs)
        assert action.shape == (2,) and action.dtype == np.float32
        assert np.all(np.abs(action) <= 1.0)


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_batched_predict_matches_one_controller_per_env(scaling, name):
    rng = np.random.default_rng(1)
    streams = _random_obs(rng, 3 * 10).reshape(10, 3, ob.OBS_DIM)
    batched = controller_by_name(name, **scaling)
    singles = [controller_by_name(name, **scaling) for _ in range(3)]
    state, starts = None, np.ones(3, dtype=bool)
    for step in streams:
        actions, state = batched.predict(step, state=state, episode_start=starts)
        starts = np.zeros(3, dtype=bool)
        assert actions.shape == (3, 2) and actions.dtype == np.float32
        expected = np.stack([c.act(o) for c, o in zip(singles, step, strict=True)])
        np.testing.assert_allclose(actions, expected, atol=1e-6)
    if batched.state_dim:
        assert state is not None and state[0].shape == (3, batched.state_dim)
    else:
        assert state is None


def test_episode_start_resets_only_the_flagged_rows(scaling):
    ctrl = YamauchiController(**scaling)
    obs = np.zeros((2, ob.OBS_DIM), dtype=np.float32)
    obs[:, ob.OBS_CROSS_TRACK] = 1.0
    _, state = ctrl.predict(obs, episode_start=np.array([True, True]))
    _, state = ctrl.predict(obs, state=state, episode_start=np.array([False, False]))
    _, state = ctrl.predict(obs, state=state, episode_start=np.array([True, False]))
    assert state is not None
    assert state[0][0, 0] == pytest.approx(-ctrl.k_eta * ctrl.dt_s)  # one step after reset
    assert state[0][1, 0] == pytest.approx(-3 * ctrl.k_eta * ctrl.dt_s)


def test_reset_forgets_internal_state(scaling):
    ctrl = YamauchiController(**scaling)
    obs = np.zeros(ob.OBS_DIM, dtype=np.float32)
    obs[ob.OBS_CROSS_TRACK] = 1.0
    first = ctrl.act(obs)
    ctrl.act(obs)
    ctrl.reset()
    np.testing.assert_array_equal(ctrl.act(obs), first)


def test_malformed_observations_are_rejected(scaling):
    ctrl = YamauchiController(**scaling)
    with pytest.raises(ValueError, match="shape"):
        ctrl.act(np.zeros(11))
    bad = np.zeros(ob.OBS_DIM)
    bad[ob.OBS_CROSS_TRACK] = np.nan
    with pytest.raises(ValueError, match="non-finite"):
        ctrl.act(bad)


def test_observation_layout_is_the_documented_table():
    indices = [getattr(ob, n) for n in dir(ob) if n.startswith("OBS_") and n not in
               ("OBS_DIM", "OBS_NAMES", "OBS_LOW", "OBS_HIGH")]
    assert sorted(indices) == list(range(ob.OBS_DIM)) == list(range(len(OBS_NAMES)))
    assert OBS_NAMES[ob.OBS_CROSS_TRACK] == "cross_track_m"
    assert OBS_NAMES[ob.OBS_SLIP_ANGLE] == "slip_angle_est_rad"
    path = straight(10.0, 1.5)
    proj = path.project(2.5, 0.3)
    obs = build_observation(2.5, 0.3, -3.0, 1.2, 0.1, proj, slip_angle_est_rad=0.05)
    assert obs.dtype == np.float32 and obs.shape == (ob.OBS_DIM,)
    assert obs[ob.OBS_HEADING_ERROR] == pytest.approx(-3.0)
    assert obs[ob.OBS_COS_YAW] == pytest.approx(math.cos(-3.0))
    assert obs[ob.OBS_CROSS_TRACK] == pytest.approx(0.3)
    assert obs[ob.OBS_PROGRESS] == pytest.approx(0.25)
    assert obs[ob.OBS_REF_SPEED] == pytest.approx(1.5)
    assert obs[ob.OBS_SLIP_ANGLE] == pytest.approx(0.05)


class _UnicycleEnv(gym.Env):
    """Minimal path-following env for ``evaluate_policy``: perfect pose, 20 Hz, no slip."""

    observation_space = gym.spaces.Box(-np.inf, np.inf, (ob.OBS_DIM,), np.float32)
    action_space = gym.spaces.Box(-1.0, 1.0, (2,), np.float32)

    def __init__(self, v_max: float, omega_max: float, dt: float) -> None:
        self.path = circle(2.0, 1.0, loops=0.5)
        self.v_max, self.omega_max, self.dt = v_max, omega_max, dt

    def _obs(self) -> np.ndarray:
        self.proj = self.path.project(self.x, self.y, self.proj.s if self.proj else None)
        return build_observation(self.x, self.y, self.yaw, self.v, self.w, self.proj)

    def reset(self, *, seed=None, options=None):
        super().reset(seed=seed)
        self.x, self.y, self.yaw = self.path.start_pose()
        self.y += float(self.np_random.uniform(-0.3, 0.3))
        self.v = self.w = 0.0
        self.proj = None
        return self._obs(), {}

    def step(self, action):
        self.v, self.w = float(action[0]) * self.v_max, float(action[1]) * self.omega_max
        self.x += self.v * self.dt * math.cos(self.yaw + 0.5 * self.w * self.dt)
        self.y += self.v * self.dt * math.sin(self.yaw + 0.5 * self.w * self.dt)
        self.yaw += self.w * self.dt
        obs = self._obs()
        return obs, -abs(self.proj.cross_track_m), self.proj.remaining_m < 0.05, False, {}


@pytest.mark.parametrize("name", sorted(CONTROLLERS))
def test_sb3_evaluate_policy_runs_controllers_on_a_vec_env(scaling, name):
    from stable_baselines3.common.env_util import make_vec_env
    from stable_baselines3.common.evaluation import evaluate_policy

    venv = make_vec_env(lambda: gym.wrappers.TimeLimit(
        _UnicycleEnv(scaling["v_max_mps"], scaling["omega_max_rps"], scaling["dt_s"]),
        max_episode_steps=300), n_envs=2, seed=0)
    mean_reward, _ = evaluate_policy(controller_by_name(name, **scaling), venv,
                                     n_eval_episodes=4, warn=False)
    # Mean |cross-track| per step stays well under the 0.3 m initial offset.
    assert -mean_reward / (math.pi * 2.0 / (1.0 * scaling["dt_s"])) < 0.1


def test_unknown_controller_name_lists_the_known_ones(scaling):
    with pytest.raises(ValueError, match="known controllers: pure_pursuit, stanley, yamauchi"):
        controller_by_name("mpc", **scaling)
