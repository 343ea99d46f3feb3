"""What ``--policy`` may name: the built-in path followers, a saved SB3 model, or any object.

A policy *spec* is resolved once, before any episode runs (so a typo fails fast), into a
:class:`PolicySource` that builds the per-env predictor: the baseline's gains depend on the
env's reference speed and control period, and a residual agent needs its env wrapped.

=================  ========================================================================
name               policy
=================  ========================================================================
``baseline``       Yamauchi §3 law with slip-angle feed-forward (Eq. 10), poles scaled to
                   the path's speed (``slipenv.controllers.baseline``; also ``yamauchi``)
``feedback``       the same law without the feed-forward (Eq. 9): β̂ ignored (also
                   ``yamauchi_feedback``)
``pure_pursuit``   pure pursuit (``slipenv.controllers.pure_pursuit``)
``stanley``        Stanley's law (``slipenv.controllers.stanley``)
PATH               a stable-baselines3 ``.zip``; the algorithm is read from a ``config.json``
                   next to it (key ``algo``) or detected from the saved file itself
=================  ========================================================================

A model trained on the residual wrapper (``slipenv.agents.residual``) acts through it: its
action is a correction to the base controller's. Its ``.zip`` records the composition (the
saved action space is a ``ResidualBox``), so the file alone, or the loaded SB3 object, is
scored the same as its run folder; for models saved before the file recorded it, the run's
``config.json`` still tells.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import gymnasium as gym

from slipenv.controllers.baseline import baseline_controller

BUILTIN_POLICIES: dict[str, str] = {
    "baseline": "yamauchi",
    "feedback": "yamauchi_feedback",
    "pure_pursuit": "pure_pursuit",
    "stanley": "stanley",
}
"""Built-in policy name -> ``baseline_controller`` name."""
CONTROLLER_ALIASES: dict[str, str] = {controller: name for name, controller
                                      in BUILTIN_POLICIES.items() if controller != name}
"""``slipenv run --controller`` names accepted for the same policies (``yamauchi`` is
``baseline``, ``yamauchi_feedback`` is ``feedback``)."""

# SB3 algorithms a saved model may come from, with a key only that algorithm saves
# (PPO and A2C share ActorCriticPolicy; only PPO saves ``clip_range``).
_POLICY_CLASS_ALGOS = {"sac.policies": "sac", "td3.policies": "td3", "ddpg": "ddpg",
                       "dqn.policies": "dqn"}


@dataclass(frozen=True)
class PolicySource:
    """A resolved policy: a label, and how to build its predictor for one env.

    Attributes
    ----------
    label : str
        What the results call it (the name, the model path, or the object's class name).
    kind : str
        ``"builtin"``, ``"model"`` or ``"object"``.
    key : str
        A stable identity for caches and sweep-cell hashes (the object's ``id`` for objects).
    """

    label: str
    kind: str
    key: str
    _obj: Any = field(default=None, repr=False, compare=False)
    model_path: str | None = None
    algo: str | None = None
    residual: dict | None = None

    def wrap_env(self, env: gym.Env) -> gym.Env:
        """The env the policy acts in: residual agents act through the baseline wrapper."""
        if self.residual is None:
            return env
        from slipenv.agents.residual import ResidualActionWrapper

        return ResidualActionWrapper(env, **self.residual)

    def build(self, env: gym.Env) -> Any:
        """A predictor (SB3 ``predict``) for ``env`` (as returned by :meth:`wrap_env`).

        Raises
        ------
        ValueError
            If the model was made for other observation or action shapes than ``env``'s.
        """
        if self.kind == "builtin":
            return baseline_controller(env, BUILTIN_POLICIES[self.label])
        model = (self._obj if self.kind == "object"
                 else _load_model(self.algo or "", self.model_path or ""))
        for name in ("observation_space", "action_space"):
            mine, envs = getattr(model, name, None), getattr(env, name, None)
            if (isinstance(mine, gym.spaces.Box) and isinstance(envs, gym.spaces.Box)
                    and mine.shape != envs.shape):
                raise ValueError(f"policy {self.label}: made for an {name} of shape "
                                 f"{mine.shape}, but {env.spec.id if env.spec else 'the env'} "
                                 f"has {envs.shape}: it was trained on another env")
        return model


def _load_model(algo: str, path: str) -> Any:
    import stable_baselines3 as sb3

    cls = getattr(sb3, algo.upper())
    return cls.load(path, device="cpu")


def detect_algo(model_path: str | Path) -> str:
    """The SB3 algorithm of a saved ``.zip``: ``config.json`` next to it, else the file itself.

    Raises
    ------
    ValueError
        If the file is missing, is not an SB3 archive, or its algorithm cannot be told.
    """
    path = Path(model_path)
    if not path.is_file():
        raise ValueError(f"--policy: no such model file {str(path)!r} (and not one of "
                         f"{', '.join(BUILTIN_POLICIES)})")
    config = _model_config(path)
    if "algo" in config:
        algo = str(config["algo"]).lower()
    else:
        try:
            with zipfile.ZipFile(path) as zf:
                data = json.loads(zf.read("data"))
        except (zipfile.BadZipFile, KeyError, json.JSONDecodeError) as exc:
            raise ValueError(f"--policy: {str(path)!r} is not a stable-baselines3 model "
                             f"archive ({exc})") from None
        module = str(data.get("policy_class", {}).get("__module__", ""))
        algo = next((a for key, a in _POLICY_CLASS_ALGOS.items() if key in module), "")
        if not algo and "common.policies" in module:
            algo = "ppo" if "clip_range" in data else "a2c"
        if not algo:
            raise ValueError(f"--policy: cannot tell the algorithm of {str(path)!r} (policy "
                             f"module {module!r}); put {{\"algo\": ...}} in a config.json "
                             "next to it")
    import stable_baselines3 as sb3

    if not hasattr(sb3, algo.upper()):
        raise ValueError(f"--policy: unknown algorithm {algo!r} for {str(path)!r}")
    return algo


def _model_config(path: Path) -> dict:
    """The training config saved next to a model (``config.json``), or ``{}``."""
    for candidate in (path.with_suffix(".json"), path.parent / "config.json"):
        if candidate.is_file() and candidate != path:
            try:
                loaded = json.loads(candidate.read_text())
            except json.JSONDecodeError as exc:
                raise ValueError(f"--policy: bad JSON in {str(candidate)!r}: {exc}") from None
            if isinstance(loaded, dict):
                return loaded
    return {}


def saved_composition(path: str | Path) -> dict | None:
    """The residual composition recorded in an SB3 ``.zip`` (its saved action space), or None.

    Read from the archive's JSON (``data``), without unpickling or loading the weights.

    Raises
    ------
    ValueError
        If the archive says its model is residual but does not say on which controller.
    """
    from slipenv.agents.residual import ResidualBox

    try:
        with zipfile.ZipFile(path) as zf:
            space = json.loads(zf.read("data")).get("action_space", {})
    except (zipfile.BadZipFile, KeyError, json.JSONDecodeError, OSError):
        return None
    if not isinstance(space, dict) or ResidualBox.__name__ not in str(space.get(":type:", "")):
        return None
    controller, scale = space.get("residual_controller"), space.get("residual_scale")
    kwargs = space.get("residual_controller_kwargs", {})
    if not isinstance(controller, str) or not isinstance(scale, int | float) \
            or not isinstance(kwargs, dict):
        raise ValueError(f"--policy: {str(path)!r} holds a residual agent but not its "
                         "composition (base controller, scale): it cannot be scored "
                         "without them")
    return {**kwargs, "controller": controller, "scale": float(scale)}


def _residual_options(config: dict) -> dict | None:
    """Residual-wrapper options from a training config (keys ``residual``, ``residual_scale``
    and ``controller``, as written by ``slipenv train``), or None for a plain agent."""
    residual = config.get("residual", False)
    if not residual:
        return None
    options: dict[str, Any] = {}
    if isinstance(residual, dict):
        options.update(residual)
    for key, name in (("residual_scale", "scale"), ("scale", "scale"),
                      ("controller", "controller")):
        if key in config and name not in options:
            options[name] = config[key]
    return options


def resolve_policy(policy: Any) -> PolicySource:
    """Resolve a ``--policy`` value or a policy object; fails fast on a bad name or path.

    Parameters
    ----------
    policy : str, os.PathLike, PolicySource or object
        A built-in name, a path to an SB3 ``.zip``, or anything with SB3's ``predict``
        (a controller, an SB3 model) or a callable ``obs -> action``.

    Raises
    ------
    ValueError
        On an unknown name, a missing file, or an archive whose algorithm cannot be told.
    """
    if isinstance(policy, PolicySource):
        return policy
    if isinstance(policy, str | Path):
        name = CONTROLLER_ALIASES.get(str(policy), str(policy))
        if name in BUILTIN_POLICIES:
            return PolicySource(label=name, kind="builtin", key=name)
        looks_like_path = name.endswith(".zip") or "/" in name or Path(name).exists()
        if not looks_like_path:
            raise ValueError(f"--policy: unknown policy {name!r}; use one of "
                             f"{', '.join(BUILTIN_POLICIES)} or a path to an SB3 .zip")
        algo = detect_algo(name)
        residual = saved_composition(name)
        if residual is None:  # a model saved before the zip recorded it: its run's config
            residual = _residual_options(_model_config(Path(name)))
        resolved = str(Path(name).resolve())
        return PolicySource(label=name, kind="model", key=f"model:{resolved}",
                            model_path=resolved, algo=algo, residual=residual)
    if hasattr(policy, "predict") or callable(policy):
        from slipenv.agents.residual import residual_composition

        return PolicySource(label=type(policy).__name__, kind="object",
                            key=f"object:{type(policy).__qualname__}:{id(policy)}", _obj=policy,
                            residual=residual_composition(policy))
    raise ValueError(f"policy must be a name, a model path or an object with predict(), "
                     f"got {policy!r}")


PolicyLike = str | Path | PolicySource | Callable[..., Any] | Any
