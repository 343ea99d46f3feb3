"""Residual RL: the agent learns a correction on top of the baseline path follower.

action = clip(baseline(obs) + scale * residual, -1, 1). With a zero residual the wrapped env
behaves exactly like the baseline controller, so training starts from a working policy.

Two faces of the same composition (:func:`compose_residual`):

- :class:`ResidualActionWrapper` wraps an env for training: the agent's action *is* the
  residual;
- :class:`ResidualPolicy` wraps a trained model for use on the *plain* env: its ``predict``
  returns the composed action, so it is evaluated, exported or rolled out like any controller.

A model trained on the wrapper carries its composition: the wrapper's action space is a
:class:`ResidualBox` (a ``Box`` that also names the base controller, its keyword arguments and
the scale), and stable-baselines3 saves a model's action space in its ``.zip``. So any model
trained on the wrapper -- by ``slipenv train``, rl-zoo3 or a user's own script -- can be
recomposed from the file alone (:func:`residual_composition`).
"""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from slipenv.controllers.baseline import baseline_controller


def _check_scale(scale: float) -> float:
    scale = float(scale)
    if not (0.0 < scale <= 1.0):
        raise ValueError(f"scale must be in (0, 1], got {scale!r}")
    return scale


class ResidualBox(gym.spaces.Box):
    """The residual wrapper's action space: the env's ``Box`` plus the composition it stands for.

    Equal to the plain ``Box`` of the same bounds (so SB3 loads the model next to the plain
    env), it is saved with the model and tells a loader how to turn the model's action, a
    residual, back into the env's action.

    Parameters
    ----------
    low, high, shape, dtype
        As ``gymnasium.spaces.Box``.
    controller : str
        Base controller name (``slipenv.controllers.baseline.BASELINE_NAMES``).
    controller_kwargs : dict
        Its keyword arguments (JSON-able).
    scale : float
        Residual authority as a fraction of the action range.
    """

    def __init__(self, low: Any, high: Any, shape: Any = None, dtype: Any = np.float32, *,
                 controller: str = "yamauchi", controller_kwargs: dict | None = None,
                 scale: float = 0.3) -> None:
        super().__init__(low, high, shape, dtype)
        self.residual_controller = str(controller)
        self.residual_controller_kwargs = dict(controller_kwargs or {})
        self.residual_scale = _check_scale(scale)

    def composition(self) -> dict[str, Any]:
        """The :class:`ResidualActionWrapper` keyword arguments that rebuild this composition.

        Raises
        ------
        ValueError
            If the saved space lacks its composition (a damaged or foreign pickle).
        """
        try:
            controller, scale = self.residual_controller, self.residual_scale
            kwargs = dict(self.residual_controller_kwargs)
        except AttributeError as exc:
            raise ValueError(f"a residual action space without its composition ({exc}): "
                             "cannot tell which base controller the residual adds to") from None
        return {**kwargs, "controller": controller, "scale": _check_scale(scale)}

    def __repr__(self) -> str:
        box = super().__repr__()  # "Box(low, high, shape, dtype)"
        return (f"Residual{box[:-1]}, controller={self.residual_controller!r}, "
                f"scale={self.residual_scale})")


def residual_composition(obj: Any) -> dict[str, Any] | None:
    """The residual composition a model (or an action space) records, or None if it has none.

    Parameters
    ----------
    obj : SB3 model, gymnasium space or any object
        Read through its ``action_space`` (a model) or as the space itself.

    Returns
    -------
    dict or None
        :class:`ResidualActionWrapper` keyword arguments (``controller``, ``scale`` and the
        controller's own), or None for a model trained on the plain env.
    """
    space = obj if isinstance(obj, gym.spaces.Space) else getattr(obj, "action_space", None)
    return space.composition() if isinstance(space, ResidualBox) else None


def compose_residual(base_action: np.ndarray, residual: np.ndarray, scale: float) -> np.ndarray:
    """clip(base + scale * residual, -1, 1) as float32 (any matching shapes)."""
    out = np.asarray(base_action, dtype=np.float32) + scale * np.asarray(residual,
                                                                          dtype=np.float32)
    return np.clip(out, -1.0, 1.0).astype(np.float32)


class ResidualActionWrapper(gym.ActionWrapper):
    """Adds the baseline controller's action to the agent's (scaled) residual action.

    Parameters
    ----------
    env : gym.Env
        A slipenv environment.
    scale : float
        Residual authority as a fraction of the action range (0 < scale <= 1).
    controller : str
        Baseline controller name (``slipenv.controllers.baseline.BASELINE_NAMES``).
    **controller_kwargs
        Passed to :func:`~slipenv.controllers.baseline.baseline_controller`.
    """

    def __init__(self, env: gym.Env, scale: float = 0.3, controller: str = "yamauchi",
                 **controller_kwargs: Any) -> None:
        super().__init__(env)
        self.scale = _check_scale(scale)
        self.baseline = baseline_controller(env, controller, **controller_kwargs)
        space = env.action_space
        if not isinstance(space, gym.spaces.Box):
            raise TypeError(f"the residual wrapper needs a Box action space, got {space}")
        # A model trained here saves this space: the zip then names the composition.
        self.action_space = ResidualBox(space.low, space.high, space.shape, space.dtype,
                                        controller=controller,
                                        controller_kwargs=controller_kwargs, scale=self.scale)
        self._obs: np.ndarray | None = None

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self.baseline.reset()
        self._obs = obs
        return obs, info

    def step(self, action):
        obs, reward, terminated, truncated, info = super().step(action)
        self._obs = obs
        info["residual_action"] = np.asarray(action, dtype=np.float32)
        return obs, reward, terminated, truncated, info

    def action(self, action: np.ndarray) -> np.ndarray:
        if self._obs is None:
            raise RuntimeError("call reset() before step()")
        return compose_residual(self.baseline.act(self._obs), action, self.scale)


class ResidualPolicy:
    """A trained residual model and the baseline, composed into one policy for the plain env.

    Parameters
    ----------
    model : object with SB3's ``predict``
        Trained on a :class:`ResidualActionWrapper` env.
    baseline : Controller
        The baseline it was trained on (``baseline_controller(env, controller)``).
    scale : float
        The wrapper's ``scale`` at training time.

    Notes
    -----
    Follows SB3's ``PolicyPredictor`` protocol (``predict``) and has ``act`` and ``reset``
    like the controllers; call ``reset`` at each episode start (``slipenv.rollout`` does).
    """

    def __init__(self, model: Any, baseline: Any, scale: float = 0.3) -> None:
        if not hasattr(model, "predict"):
            raise TypeError(f"model needs SB3's predict(), got {type(model).__name__}")
        self.model, self.baseline, self.scale = model, baseline, _check_scale(scale)

    @classmethod
    def from_model(cls, model: Any, env: gym.Env) -> ResidualPolicy:
        """The composed policy of a model trained on :class:`ResidualActionWrapper`, for ``env``.

        For users of ``PPO.load(...)``: the model's own ``predict`` returns the residual only.

        Raises
        ------
        ValueError
            If the model records no residual composition (it was trained on the plain env).
        """
        options = residual_composition(model)
        if options is None:
            raise ValueError(f"{type(model).__name__} records no residual composition: it "
                             "was trained on the plain env, use it as it is")
        scale = options.pop("scale")
        controller = options.pop("controller")
        return cls(model, baseline_controller(env, controller, **options), scale)

    def reset(self) -> None:
        """Forget the baseline's internal state (a new episode starts)."""
        self.baseline.reset()

    def predict(self, observation: np.ndarray, state: tuple[np.ndarray, ...] | None = None,
                episode_start: np.ndarray | None = None, deterministic: bool = True,
                ) -> tuple[np.ndarray, tuple[np.ndarray, ...] | None]:
        """The composed action; ``state`` is the baseline's (the model is an MLP)."""
        base, base_state = self.baseline.predict(observation, state, episode_start,
                                                 deterministic)
        residual, _ = self.model.predict(observation, deterministic=deterministic)
        return compose_residual(base, residual, self.scale), base_state

    def act(self, obs: np.ndarray) -> np.ndarray:
        """Action for one observation (or a batch)."""
        return self.predict(obs)[0]
