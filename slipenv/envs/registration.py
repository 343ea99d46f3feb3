"""Gymnasium registration of slipenv's environments.

Each registered id is :class:`~slipenv.envs.slip_env.SlipEnv` with a preset configuration;
every preset field can still be overridden with ``gymnasium.make(id, **kwargs)``.

=====================================  =====================================================
id                                     task
=====================================  =====================================================
``slipenv/FarmField-v0``               Lindgren's 2WD farm vehicle, 4 m circles on field loam
``slipenv/TrackedSlopeCircle-v0``      Yamauchi's tracked vehicle, r = 0.25 m circle, 15°
                                       sandy side slope, 5 cm/s; observes slip-compensated
                                       odometry and its slip angle estimate β̂
``slipenv/RoverMounds-v0``             Reina's 4WS rover crossing lunar-simulant sand with
                                       mounds (slalom at 8 cm/s)
``slipenv/RoverMoundsVisual-v0``       the same task observed as on Reina's rover: sComp
                                       odometry with FTrace's slip angle from the 5 Hz rear
                                       trace camera (render shows the camera beside the map)
``slipenv/HuskySand-v0``               pybullet_data's Husky on loose sand, s-curve
``slipenv/Configurable-v0``            everything a kwarg (defaults: Husky on loose sand,
                                       Janosi force law, 3 m circle, gyrodometry)
=====================================  =====================================================

Success is reaching the path's end inside a corridor that fits the path
(:func:`~slipenv.envs.config.corridor_for`: 0.4 of its smallest turning radius, at most 2 m):
1.6 m on FarmField, 0.1 m on TrackedSlopeCircle, 0.375 m on the rover slalom, 2 m on the
Husky's s-curve and 1.2 m on Configurable's 3 m circle.
"""

from __future__ import annotations

import difflib
import json
from importlib import resources
from importlib.resources.abc import Traversable

import gymnasium as gym

from slipenv.envs.config import SlipEnvConfig

ENTRY_POINT = "slipenv.envs.slip_env:SlipEnv"
# Fitted by ``slipenv reproduce yamauchi --save-model PATH`` (the env preset's world, the
# reproduction's default); version-controlled package data.
YAMAUCHI_MODEL = "yamauchi_slip_model.json"


def yamauchi_model_file() -> Traversable:
    """The shipped slip model of the tracked env, ``slipenv/data/yamauchi_slip_model.json``,
    as an :mod:`importlib.resources` path (read-only: the package never writes it)."""
    return resources.files("slipenv").joinpath("data", YAMAUCHI_MODEL)


def yamauchi_observation() -> dict:
    """Estimator options of the tracked env: Yamauchi's slip-compensated odometry with the
    shipped fitted model (Eq. 9 coefficients and Endo's n), so the observation carries β̂.

    Raises
    ------
    FileNotFoundError
        If the model file is missing: a packaging bug (``pyproject.toml`` package-data), not
        something to paper over with a different observation.
    ValueError
        If the file lacks ``beta_model`` or ``n`` (the message names the file and the key).
    """
    model = yamauchi_model_file()
    if not model.is_file():
        raise FileNotFoundError(
            f"slipenv/data/{YAMAUCHI_MODEL} is missing from the installed package ({model}); "
            "it is package data (pyproject.toml [tool.setuptools.package-data]): reinstall "
            "slipenv, or regenerate it in a source checkout with `slipenv reproduce yamauchi "
            f"--save-model slipenv/data/{YAMAUCHI_MODEL}`")
    saved = json.loads(model.read_text())
    for key in ("beta_model", "n"):
        if key not in saved:
            raise ValueError(f"slipenv/data/{YAMAUCHI_MODEL} has no {key!r} entry")
    return {"estimator": "slip_compensated",
            "estimator_kwargs": {"beta_model": saved["beta_model"], "n": saved["n"]}}


ROVER_MOUNDS = dict(
    vehicle="rover_4ws", terrain={"kind": "mounds", "mound_height_m": 0.06,
                                  "mound_radius_m": 0.4, "mound_count": 30,
                                  "size_m": 14.0, "clear_radius_m": 0.6},
    soil="lunar_simulant", force_model="reina",
    path="slalom", path_kwargs={"n_gates": 3, "gate_spacing_m": 1.5, "amplitude_m": 0.3,
                                "speed_mps": 0.08},
    max_episode_s=90.0,
)
# The visual rover is a separate id, not RoverMounds-v0's default: rendering the camera frame
# (about 5 ms) and FTrace (about 2.5 ms) at 5 Hz cost 2 ms per 20 Hz step, which takes the env
# from about 870 to about 330 steps/s (measured on 2 cores, 300 steps of each). s_x(β) is
# Eq. 12 for flat lunar simulant: Reina's law needs no slip to roll on the flat
# (slipenv.testbed.slip_curve.fit_slip_ratio_for_slope(0, LUNAR_SIMULANT) gives s_x0 = k = 0).
ROVER_VISUAL_ESTIMATOR = dict(
    estimator="scomp",
    estimator_kwargs={"slip_model": {"s_x0": 0.0, "k_per_rad": 0.0, "beta0_rad": 0.0}},
)

PRESETS: dict[str, dict] = {
    "slipenv/FarmField-v0": dict(
        vehicle="farm_2wd", terrain="flat", soil="field_loam", force_model="linear",
        path="lindgren_circles", path_kwargs={"radius_m": 4.0, "speed_mps": 0.5},
        beacons=True, estimator="lindgren_ekf",
        # the castors make the vehicle crab on the circles: the EKF estimates the slip angle
        estimator_kwargs={"scheme": 4, "params": {"lateral_slip_sigma0": 3.0}},
        max_episode_s=170.0,
    ),
    "slipenv/TrackedSlopeCircle-v0": dict(
        vehicle="tracked_patako_wong_chiang",
        terrain={"kind": "slope", "slope_deg": 15.0, "downhill_azimuth_deg": -90.0},
        soil="toyoura_sand", force_model="janosi", **yamauchi_observation(),
        path="circle", path_kwargs={"radius_m": 0.25, "speed_mps": 0.05, "loops": 1.0},
        max_episode_s=60.0,
    ),
    "slipenv/RoverMounds-v0": dict(ROVER_MOUNDS),
    "slipenv/RoverMoundsVisual-v0": dict(ROVER_MOUNDS, **ROVER_VISUAL_ESTIMATOR),
    "slipenv/HuskySand-v0": dict(
        vehicle="husky", terrain="flat", soil="loose_sand", force_model="janosi",
        path="s_curve", path_kwargs={"length_m": 10.0, "offset_m": 2.0, "speed_mps": 0.6},
        max_episode_s=40.0,
    ),
    "slipenv/Configurable-v0": dict(
        force_model="janosi", estimator="gyrodometry", path="circle",
        path_kwargs={"radius_m": 3.0, "speed_mps": 0.5}, max_episode_s=60.0,
    ),
}


def preset_config(env_id: str) -> SlipEnvConfig:
    """The configuration a registered id starts from (``gymnasium.make(env_id)``).

    Raises
    ------
    ValueError
        If ``env_id`` is not a slipenv id (the message lists them).
    """
    if env_id not in PRESETS:
        close = difflib.get_close_matches(env_id, sorted(PRESETS), n=1)
        hint = f"; did you mean {close[0]!r}?" if close else ""
        raise ValueError(f"unknown slipenv env id {env_id!r}{hint} Known ids: {sorted(PRESETS)}")
    return SlipEnvConfig.from_kwargs(None, **PRESETS[env_id])


def register_envs() -> None:
    """Register every slipenv environment id with Gymnasium (idempotent).

    Each id is registered with one kwarg, ``config``: its preset :class:`SlipEnvConfig`.
    ``gymnasium.make(id, **kwargs)`` overrides fields of that preset;
    ``gymnasium.make(id, config=cfg)`` replaces it (e.g. with a model fitted by
    ``slipenv diagnose``, see :func:`slipenv.diagnose.apply_model`).

    No id has a registered ``max_episode_steps``: the env truncates itself after
    ``max_episode_s`` at ``control_hz`` (``env.unwrapped.max_steps``), which are make kwargs,
    whereas a registered step count is fixed when the id is registered and Gymnasium's
    ``TimeLimit`` would cut an episode made longer (``max_episode_s``) or finer
    (``control_hz``) at the preset's count. ``env.spec.max_episode_steps`` is therefore None
    unless ``gymnasium.make(id, max_episode_steps=n)`` adds a ``TimeLimit`` of its own.
    """
    for env_id in PRESETS:
        if env_id in gym.registry:
            continue
        gym.register(
            id=env_id, entry_point=ENTRY_POINT, kwargs={"config": preset_config(env_id)},
            max_episode_steps=None, disable_env_checker=False,
        )
