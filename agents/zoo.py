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
--conf-file <file>`` trains with the same settings, and its saved model, like ``slipenv
train``'s, records the residual composition (the wrapper's action space is saved with it), so
``slipenv evaluate --policy`` and the pytest fixture score it as it acts. Keys rl-zoo3 knows
but ``slipenv train`` does not implement (``normalize``, ``frame_stack``, callbacks ...) are
a ``ValueError``, and so is any value of the wrong type or range (one line naming the file,
the entry and the key), before SB3 would stop on an ``AssertionError`` or a ``TypeError`` deep
in its constructor.
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
# Constructor arguments ``slipenv train`` sets itself (the seed and log folder come from its
# own options; exploration noise from ``noise_type``).
_SET_BY_TRAIN = ("seed", "device", "verbose", "tensorboard_log", "action_noise",
                 "rollout_buffer_class", "rollout_buffer_kwargs", "_init_setup_model")
# Integer arguments that may be 0 (-1 means "as many as collected" / "only at the start").
_INT_MIN = {"learning_starts": 0, "verbose": 0}
_INT_MINUS_ONE_OK = ("gradient_steps", "sde_sample_freq")
# Float arguments that may be 0, and those that are fractions (at most 1).
_FLOAT_ZERO_OK = ("ent_coef", "vf_coef", "gae_lambda", "target_policy_noise",
                  "target_noise_clip")
_FRACTIONS = ("gamma", "gae_lambda", "tau")
_SCHEDULES = ("learning_rate", "clip_range", "clip_range_vf")


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
    if isinstance(value, dict) and len(value) == 1:
        name, kwargs = next(iter(value.items()))
    elif isinstance(value, str):
        name, kwargs = value, {}
    else:
        raise ValueError(f"{where}: env_wrapper must be a wrapper name or {{name: options}}, "
                         f"got {value!r}")
    if not isinstance(kwargs or {}, dict):
        raise ValueError(f"{where}: env_wrapper options must be a mapping, got {kwargs!r}")
    if name != RESIDUAL_WRAPPER:
        raise ValueError(f"{where}: env_wrapper {name!r} is not supported by slipenv train "
                         f"(only {RESIDUAL_WRAPPER})")
    unknown = set(kwargs or {}) - {"scale"}
    if unknown:
        raise ValueError(f"{where}: env_wrapper options {sorted(unknown)} unknown; "
                         "the residual wrapper takes 'scale'")
    scale = (kwargs or {}).get("scale", 0.3)
    if isinstance(scale, bool) or not isinstance(scale, int | float):
        raise ValueError(f"{where}: env_wrapper scale must be a number, got {scale!r}")
    return True, float(scale)


def parse(entry: dict[str, Any], algo_cls: type, where: str) -> Hyperparams:
    """Split an rl-zoo3 entry and validate every key against ``algo_cls``.

    Raises
    ------
    ValueError
        One line, ``"<where>: <key>: ..."``, for an unknown or unsupported key, a value of the
        wrong type, or a value out of range.
    """
    entry = dict(entry)
    bad = [k for k in _UNSUPPORTED if k in entry]
    if bad:
        raise ValueError(f"{where}: {bad} not supported by slipenv train (use rl_zoo3)")
    own = [k for k in _SET_BY_TRAIN if k in entry]
    if own:
        raise ValueError(f"{where}: {', '.join(own)}: set by slipenv train itself (its --seed; "
                         "noise_type/noise_std for action noise); remove from the file")
    residual, scale = _wrapper(entry.pop("env_wrapper", None), where)
    if not 0.0 < scale <= 1.0:
        raise ValueError(f"{where}: env_wrapper scale must be in (0, 1], got {scale}")
    noise = None
    if "noise_type" in entry:
        noise = (str(entry.pop("noise_type")),
                 _number(entry.pop("noise_std", 0.1), "noise_std", where, minimum=0.0))
        if noise[0] not in ("normal", "ornstein-uhlenbeck"):
            raise ValueError(f"{where}: noise_type {noise[0]!r} unknown; "
                             "use 'normal' or 'ornstein-uhlenbeck'")
    elif "noise_std" in entry:
        raise ValueError(f"{where}: noise_std without noise_type ('normal' or "
                         "'ornstein-uhlenbeck')")
    env_kwargs = entry.pop("env_kwargs", {})
    if not isinstance(env_kwargs, dict):
        raise ValueError(f"{where}: env_kwargs must be a mapping, got {env_kwargs!r}")
    policy = entry.pop("policy", "MlpPolicy")
    aliases = getattr(algo_cls, "policy_aliases", {})
    if not isinstance(policy, str) or (aliases and policy not in aliases):
        raise ValueError(f"{where}: policy must be one of {sorted(aliases)}, got {policy!r}")
    hp = Hyperparams(
        n_timesteps=_integer(entry.pop("n_timesteps", 100_000), "n_timesteps", where),
        n_envs=_integer(entry.pop("n_envs", 1), "n_envs", where), policy=policy,
        residual=residual, residual_scale=scale, env_kwargs=dict(env_kwargs),
        noise=noise, algo_kwargs=entry, source=where,
    )
    params = inspect.signature(algo_cls).parameters  # the constructor's, without self
    allowed = set(params) - {"policy", "env"}
    for key, value in entry.items():
        if key not in allowed:
            hint = difflib.get_close_matches(key, sorted(allowed), n=1)
            raise ValueError(f"{where}: {key!r} is not a {algo_cls.__name__} argument"
                             + (f"; did you mean {hint[0]!r}?" if hint else ""))
        _check_value(key, value, params[key].default, where)
    if "batch_size" in entry and entry["batch_size"] < 2 and algo_cls.__name__ == "PPO":
        raise ValueError(f"{where}: batch_size must be >= 2 for PPO (advantages are "
                         f"normalised over a minibatch), got {entry['batch_size']}")
    return hp


def _integer(value: Any, key: str, where: str, minimum: int = 1) -> int:
    """``value`` as an int >= ``minimum`` (YAML's ``!!float 1e5`` accepted when whole)."""
    if isinstance(value, float) and value.is_integer():
        value = int(value)
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{where}: {key} must be an integer, got {value!r}")
    if value < minimum:
        raise ValueError(f"{where}: {key} must be >= {minimum}, got {value}")
    return value


def _number(value: Any, key: str, where: str, minimum: float = 0.0, strict: bool = True,
            maximum: float | None = None) -> float:
    """``value`` as a finite float above ``minimum`` (or equal, if not ``strict``)."""
    if isinstance(value, bool) or not isinstance(value, int | float) \
            or not np.isfinite(value):
        raise ValueError(f"{where}: {key} must be a number, got {value!r}")
    low_ok = value > minimum if strict else value >= minimum
    if not low_ok or (maximum is not None and value > maximum):
        bounds = (f"{'(' if strict else '['}{minimum:g}, "
                  f"{'inf)' if maximum is None else f'{maximum:g}]'}")
        raise ValueError(f"{where}: {key} must be in {bounds}, got {value}")
    return float(value)


def _check_value(key: str, value: Any, default: Any, where: str) -> None:
    """One algorithm keyword's type and range, told by its SB3 default and the tables above."""
    if key == "policy_kwargs":
        if isinstance(value, str):
            try:
                _policy_kwargs_from_text(value)
            except Exception as exc:  # noqa: BLE001 -- any failure of the text is the user's
                raise ValueError(f"{where}: policy_kwargs {value!r} is not a dict(...) "
                                 f"expression: {type(exc).__name__}: {exc}") from None
        elif not isinstance(value, dict):
            raise ValueError(f"{where}: policy_kwargs must be a mapping or 'dict(...)' text, "
                             f"got {value!r}")
        return
    if key == "train_freq":
        if isinstance(value, list | tuple):
            if len(value) != 2 or value[1] not in ("step", "episode"):
                raise ValueError(f"{where}: train_freq must be an integer or [n, 'step' | "
                                 f"'episode'], got {value!r}")
            _integer(value[0], key, where)
        else:
            _integer(value, key, where)
        return
    if key in ("ent_coef", "target_entropy") and isinstance(value, str):
        if key == "ent_coef" and value.startswith("auto_"):
            _number(_float_or(value[5:], key, where), key, where)
        elif value != "auto":
            raise ValueError(f"{where}: {key} must be a number or 'auto', got {value!r}")
        return
    if key == "target_entropy":
        _number(value, key, where, minimum=-np.inf)
        return
    if key in _SCHEDULES:
        if value is None and key == "clip_range_vf":
            return
        if isinstance(value, str) and value.startswith("lin_"):
            value = _float_or(value[4:], key, where)
        _number(value, key, where)
        return
    if isinstance(default, bool):
        if not isinstance(value, bool):
            raise ValueError(f"{where}: {key} must be true or false, got {value!r}")
    elif isinstance(default, int):
        if key in _INT_MINUS_ONE_OK and value == -1:
            return
        _integer(value, key, where, minimum=_INT_MIN.get(key, 1))
    elif isinstance(default, float) or key == "target_kl":
        if value is None and key == "target_kl":
            return
        _number(value, key, where, strict=key not in _FLOAT_ZERO_OK,
                maximum=1.0 if key in _FRACTIONS else None)


def _float_or(text: str, key: str, where: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ValueError(f"{where}: {key}: {text!r} is not a number") from None


def _policy_kwargs_from_text(text: str) -> dict[str, Any]:
    """rl-zoo3's ``policy_kwargs`` text evaluated with only ``dict`` and ``torch.nn``."""
    import torch

    value = eval(text, {"__builtins__": {}, "dict": dict, "nn": torch.nn})  # noqa: S307
    if not isinstance(value, dict):
        raise TypeError(f"evaluates to {type(value).__name__}, not a dict")
    return value


def _linear(initial: float) -> Callable[[float], float]:
    def schedule(progress_remaining: float) -> float:
        return progress_remaining * initial

    return schedule


def algo_kwargs_for_sb3(kwargs: dict[str, Any], n_actions: int,
                        noise: tuple[str, float] | None) -> dict[str, Any]:
    """The file's algorithm keys as SB3 objects: schedules, ``policy_kwargs``, action noise."""
    from stable_baselines3.common.noise import NormalActionNoise, OrnsteinUhlenbeckActionNoise

    out = dict(kwargs)
    for key, value in kwargs.items():
        if isinstance(value, str) and value.startswith("lin_"):
            out[key] = _linear(float(value[4:]))
    if isinstance(out.get("train_freq"), list):  # YAML has no tuples; SB3 wants (n, unit)
        out["train_freq"] = tuple(out["train_freq"])
    if isinstance(out.get("policy_kwargs"), str):  # rl-zoo3 writes it as Python text
        out["policy_kwargs"] = _policy_kwargs_from_text(out["policy_kwargs"])
    if noise is not None:
        kind, std = noise
        cls = NormalActionNoise if kind == "normal" else OrnsteinUhlenbeckActionNoise
        out["action_noise"] = cls(mean=np.zeros(n_actions), sigma=std * np.ones(n_actions))
    return out
