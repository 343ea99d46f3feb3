"""Per-env hyperparameters in rl-zoo3's YAML layout, read by ``slipenv train`` and rl-zoo3 alike.

The shipped files are ``hyperparams/{ppo,sac,td3}.yml`` beside this module (package data; copy
one, edit it and pass it with ``--hyperparams``). Each maps an env id (or ``default``) to a dict
of rl-zoo3 keys:

- ``n_timesteps`` (total env steps), ``policy`` (``MlpPolicy``), ``n_envs``;
- ``env_wrapper``: ``slipenv.agents.residual.ResidualActionWrapper`` (optionally as
  ``{name: {scale: 0.3}}``) makes the agent learn a residual on the baseline;
- ``env_kwargs``: extra ``gymnasium.make`` keyword arguments;
- ``noise_type`` (``normal`` | ``ornstein-uhlenbeck``) and ``noise_std`` for off-policy
  exploration noise;
- ``policy_kwargs`` as a dict or rl-zoo3's string form (``"dict(net_arch=[64, 64])"``);
- any other key is a keyword argument of the SB3 algorithm (``learning_rate`` may be rl-zoo3's
  ``"lin_3e-4"`` linear schedule).

So ``python -m rl_zoo3.train --gym-packages slipenv --env slipenv/HuskySand-v0 --algo ppo
--conf-file <file>`` trains with the same settings. Keys rl-zoo3 knows but ``slipenv train``
does not implement (``normalize``, ``frame_stack``, callbacks ...) are a ``ValueError``.
"""

from __future__ import annotations

import difflib
import inspect
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

HYPERPARAMS_DIR = Path(__file__).resolve().parent / "hyperparams"
"""Folder of the shipped YAML files (``ppo.yml``, ``sac.yml``, ``td3.yml``)."""
RESIDUAL_WRAPPER = "slipenv.agents.residual.ResidualActionWrapper"
"""The ``env_wrapper`` value that means residual learning on the baseline."""
_UNSUPPORTED = ("normalize", "frame_stack", "callback", "vec_env_wrapper", "monitor_kwargs",
                "replay_buffer_class", "replay_buffer_kwargs", "eval_env_wrapper")


def hyperparams_path(algo: str) -> Path:
    """The shipped YAML file of ``algo`` (``ValueError`` if there is none)."""
    path = HYPERPARAMS_DIR / f"{algo}.yml"
    if not path.is_file():
        known = sorted(p.stem for p in HYPERPARAMS_DIR.glob("*.yml"))
        raise ValueError(f"no hyperparameter file for algorithm {algo!r}; shipped: {known}")
    return path


def read_entry(env_id: str, path: str | Path) -> dict[str, Any]:
    """The entry of ``env_id`` (else ``default``) in the rl-zoo3 YAML file ``path``.

    Raises
    ------
    ValueError
        If the file cannot be read or parsed, or has neither ``env_id`` nor ``default``.
    """
    path = Path(path)
    try:
        data = yaml.safe_load(path.read_text())
    except OSError as exc:
        raise ValueError(f"hyperparameter file {path}: {exc.strerror or exc}") from None
    except yaml.YAMLError as exc:
        raise ValueError(f"hyperparameter file {path} is not valid YAML: {exc}") from None
    if not isinstance(data, dict):
        raise ValueError(f"hyperparameter file {path}: expected a mapping of env ids")
    entry = data.get(env_id, data.get("default"))
    if entry is None:
        hint = difflib.get_close_matches(env_id, [str(k) for k in data], n=1)
        raise ValueError(f"hyperparameter file {path} has no entry {env_id!r} (and no "
                         f"'default')" + (f"; did you mean {hint[0]!r}?" if hint else ""))
    if not isinstance(entry, dict):
        raise ValueError(f"hyperparameter file {path}: entry {env_id!r} must be a mapping")
    return dict(entry)


@dataclass(frozen=True)
class Hyperparams:
    """One env's training settings, split by who consumes them.

    Attributes
    ----------
    n_timesteps : int
        Default total env steps.
    n_envs : int
        Default number of parallel envs.
    policy : str
        SB3 policy name.
    residual : bool
        ``env_wrapper`` is the residual wrapper.
    residual_scale : float
        Its ``scale`` (residual authority, fraction of the action range).
    env_kwargs : dict
        ``gymnasium.make`` keyword arguments.
    noise : tuple of (str, float) or None
        ``(noise_type, noise_std)`` for off-policy exploration.
    algo_kwargs : dict
        Keyword arguments of the SB3 algorithm, as written in the file (JSON-able).
    source : str
        The file they came from.
    """

    n_timesteps: int
    n_envs: int
    policy: str
    residual: bool
    residual_scale: float
    env_kwargs: dict = field(default_factory=dict)
    noise: tuple[str, float] | None = None
    algo_kwargs: dict = field(default_factory=dict)
    source: str = ""


def _wrapper(value: Any, where: str) -> tuple[bool, float]:
    """(residual?, scale) from an rl-zoo3 ``env_wrapper`` value."""
    if value is None:
        return False, 0.3
    if isinstance(value, list):
        if len(value) != 1:
            raise ValueError(f"{where}: env_wrapper: slipenv train supports one wrapper, "
                             f"got {len(value)}")
        value = value[0]
    name, kwargs = (value, {}) if isinstance(value, str) else next(iter(value.items()))
    if name != RESIDUAL_WRAPPER:
        raise ValueError(f"{where}: env_wrapper {name!r} is not supported by slipenv train "
                         f"(only {RESIDUAL_WRAPPER})")
    unknown = set(kwargs or {}) - {"scale"}
    if unknown:
        raise ValueError(f"{where}: env_wrapper options {sorted(unknown)} unknown; "
                         "the residual wrapper takes 'scale'")
    return True, float((kwargs or {}).get("scale", 0.3))


def parse(entry: dict[str, Any], algo_cls: type, where: str) -> Hyperparams:
    """Split an rl-zoo3 entry and validate its algorithm keys against ``algo_cls``."""
    entry = dict(entry)
    bad = [k for k in _UNSUPPORTED if k in entry]
    if bad:
        raise ValueError(f"{where}: {bad} not supported by slipenv train (use rl_zoo3)")
    residual, scale = _wrapper(entry.pop("env_wrapper", None), where)
    noise = None
    if "noise_type" in entry:
        noise = (str(entry.pop("noise_type")), float(entry.pop("noise_std", 0.1)))
        if noise[0] not in ("normal", "ornstein-uhlenbeck"):
            raise ValueError(f"{where}: noise_type {noise[0]!r} unknown; "
                             "use 'normal' or 'ornstein-uhlenbeck'")
    params = inspect.signature(algo_cls).parameters  # the constructor's, without self
    allowed = set(params) - {"policy", "env"}
    hp = Hyperparams(
        n_timesteps=int(float(entry.pop("n_timesteps", 100_000))),
        n_envs=int(entry.pop("n_envs", 1)), policy=str(entry.pop("policy", "MlpPolicy")),
        residual=residual, residual_scale=scale, env_kwargs=dict(entry.pop("env_kwargs", {})),
        noise=noise, algo_kwargs=entry, source=where,
    )
    for key in entry:
        if key not in allowed:
            hint = difflib.get_close_matches(key, sorted(allowed), n=1)
            raise ValueError(f"{where}: {key!r} is not a {algo_cls.__name__} argument"
                             + (f"; did you mean {hint[0]!r}?" if hint else ""))
    if hp.n_timesteps < 1 or hp.n_envs < 1:
        raise ValueError(f"{where}: n_timesteps and n_envs must be >= 1")
    return hp


def _linear(initial: float) -> Callable[[float], float]:
    def schedule(progress_remaining: float) -> float:
        return progress_remaining * initial

    return schedule


def algo_kwargs_for_sb3(kwargs: dict[str, Any], n_actions: int,
                        noise: tuple[str, float] | None) -> dict[str, Any]:
    """The file's algorithm keys as SB3 objects: schedules, ``policy_kwargs``, action noise."""
    import torch
    from stable_baselines3.common.noise import NormalActionNoise, OrnsteinUhlenbeckActionNoise

    out = dict(kwargs)
    for key, value in kwargs.items():
        if isinstance(value, str) and value.startswith("lin_"):
            out[key] = _linear(float(value[4:]))
    if isinstance(out.get("policy_kwargs"), str):
        # rl-zoo3 writes policy_kwargs as Python text; evaluate it with only dict and torch.nn.
        out["policy_kwargs"] = eval(out["policy_kwargs"],  # noqa: S307
                                    {"__builtins__": {}, "dict": dict, "nn": torch.nn})
    if noise is not None:
        kind, std = noise
        cls = NormalActionNoise if kind == "normal" else OrnsteinUhlenbeckActionNoise
        out["action_noise"] = cls(mean=np.zeros(n_actions), sigma=std * np.ones(n_actions))
    return out
