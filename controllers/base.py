"""The policy contract and the base class that makes a control law usable as a policy.

Every controller answers both ``act(obs)`` (one observation, the env loop) and
stable-baselines3's ``predict(obs, state, episode_start, deterministic)`` (batched observations
of shape (n_envs, 12) from a VecEnv), so ``evaluate_policy`` compares controllers with trained
agents directly (STYLE §7). Subclasses write one vectorised method, :meth:`Controller.command`,
in physical units; the base class scales, clips and keeps any per-env internal state.
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from typing import ClassVar, Protocol, runtime_checkable

import numpy as np

from slipenv.contracts.observation import ACT_DIM, OBS_DIM


@runtime_checkable
class Policy(Protocol):
    """Anything that maps observations to actions in [-1, 1]^2 (float32)."""

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Action for one observation of shape (12,) (or a batch of shape (n, 12))."""
        ...

    def predict(self, observation: np.ndarray, state: tuple[np.ndarray, ...] | None = None,
                episode_start: np.ndarray | None = None, deterministic: bool = True,
                ) -> tuple[np.ndarray, tuple[np.ndarray, ...] | None]:
        """stable-baselines3's ``PolicyPredictor.predict``."""
        ...

    def reset(self) -> None:
        """Forget internal state (call at episode start when using ``act``)."""
        ...


def _positive(name: str, value: float) -> float:
    value = float(value)
    if not (math.isfinite(value) and value > 0.0):
        raise ValueError(f"{name} must be finite and > 0, got {value!r}")
    return value


class Controller(ABC):
    """Base class for control laws acting on the observation of ``slipenv.contracts.observation``.

    Parameters
    ----------
    v_max_mps : float
        Forward speed that maps to action 1 [m/s].
    omega_max_rps : float
        Yaw rate that maps to action 1 [rad/s].
    dt_s : float
        Control period of the env [s] (used by laws that integrate).

    Notes
    -----
    Internal state (``state_dim`` floats per env, e.g. an integrated yaw-rate command) lives
    in ``self._state`` for ``act`` and is also returned by ``predict`` as a one-element tuple,
    so SB3 threads it through ``evaluate_policy``; rows with ``episode_start`` set are
    re-initialised from their observation.
    """

    state_dim: ClassVar[int] = 0

    def __init__(self, v_max_mps: float, omega_max_rps: float, dt_s: float) -> None:
        self.v_max_mps = _positive("v_max_mps", v_max_mps)
        self.omega_max_rps = _positive("omega_max_rps", omega_max_rps)
        self.dt_s = _positive("dt_s", dt_s)
        self._state: np.ndarray | None = None

    @abstractmethod
    def command(self, obs: np.ndarray, state: np.ndarray,
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The control law, vectorised over envs.

        Parameters
        ----------
        obs : np.ndarray, shape (n, 12), float64
        state : np.ndarray, shape (n, state_dim)

        Returns
        -------
        v_mps, omega_rps : np.ndarray, shape (n,)
            Commanded forward speed [m/s] and yaw rate [rad/s] (clipped by the caller).
        new_state : np.ndarray, shape (n, state_dim)
        """

    def initial_state(self, obs: np.ndarray) -> np.ndarray:
        """State at an episode start, shape (n, state_dim); zeros unless overridden."""
        return np.zeros((obs.shape[0], self.state_dim))

    def reset(self) -> None:
        """Forget the internal state; the next call starts a new episode."""
        self._state = None

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Action for ``obs`` (shape (12,) -> (2,), or (n, 12) -> (n, 2)), float32 in [-1, 1]."""
        return self.predict(obs)[0]

    def predict(self, observation: np.ndarray, state: tuple[np.ndarray, ...] | None = None,
                episode_start: np.ndarray | None = None, deterministic: bool = True,
                ) -> tuple[np.ndarray, tuple[np.ndarray, ...] | None]:
        """stable-baselines3 ``predict``: batched or single observations.

        Parameters
        ----------
        observation : np.ndarray, shape (12,) or (n_envs, 12)
        state : tuple of np.ndarray, optional
            ``(state array of shape (n_envs, state_dim),)`` as returned by the previous call;
            ``None`` uses the internal state (or a fresh one if the batch size changed).
        episode_start : np.ndarray of bool, shape (n_envs,), optional
            Rows to re-initialise before acting.
        deterministic : bool
            Ignored: every control law here is deterministic.

        Returns
        -------
        action : np.ndarray, shape (2,) or (n_envs, 2), float32 in [-1, 1]
        state : tuple of np.ndarray or None
            ``None`` for stateless controllers.
        """
        obs = np.asarray(observation, dtype=np.float64)
        single = obs.ndim == 1
        batch = obs.reshape(1, -1) if single else obs
        if batch.ndim != 2 or batch.shape[1] != OBS_DIM:
            raise ValueError(f"observation must have shape ({OBS_DIM},) or (n_envs, {OBS_DIM}),"
                             f" got {obs.shape}")
        if not np.all(np.isfinite(batch)):
            raise ValueError("observation contains non-finite values")
        n = batch.shape[0]
        if state is not None:
            st = np.array(state[0], dtype=np.float64).reshape(n, self.state_dim)
        elif self._state is not None and self._state.shape[0] == n:
            st = self._state.copy()
        else:
            st = self.initial_state(batch)
        if episode_start is not None:
            starting = np.asarray(episode_start, dtype=bool).reshape(n)
            if starting.any():
                st[starting] = self.initial_state(batch)[starting]
        v, omega, new_state = self.command(batch, st)
        action = np.empty((n, ACT_DIM), dtype=np.float32)
        action[:, 0] = np.clip(v / self.v_max_mps, -1.0, 1.0)
        action[:, 1] = np.clip(omega / self.omega_max_rps, -1.0, 1.0)
        self._state = new_state
        return (action[0] if single else action,
                (new_state.copy(),) if self.state_dim else None)
