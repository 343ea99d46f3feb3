"""Cost per control step of every pose estimator and of the onboard sensors (issue 15, item 3).

Records one FarmField-v0 episode (Lindgren's 2WD farm vehicle: encoders, torque sensors, IMU,
inclinometer, compass and the beacon scanner, 20 Hz) -- the ground truth the sensor suite was
given and the frames it produced -- and then, with PyBullet out of the loop, replays:

* the sensor suite over the recorded truths (``SensorSuite.measure``, beacons included);
* every estimator over the recorded frames (``reset`` once, then ``update`` per frame):
  dead reckoning, gyrodometry, Endo's skid-steer odometry, Reina's compass odometry and the
  Lindgren EKF in schemes 1-4, on its compiled kernel (``_ekf.c``, when built) and, as
  ``lindgren_ekf_s*_numpy``, on the numpy reference (``SLIPENV_LINDGREN_NUMPY=1``).

Each cost is the median over ``--repeats`` passes of (time for the whole pass) / (frames), in
microseconds per control step, and next to it the fastest pass (on a loaded machine, the closer
to the cost on a quiet one); passes of different estimators are interleaved so that load from
other processes hits all alike. Run from the repository root::

    python benchmarks/estimator_cost.py [--steps 300] [--repeats 7] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

import slipenv  # noqa: F401  (registers the envs)
from slipenv.envs.estimation import make_estimator, odometry_geometry
from slipenv.estimators.lindgren.ekf import FORCE_NUMPY_ENV, compiled_available
from slipenv.estimators.reina.odometry import CompassOdometry
from slipenv.sensors.onboard import SensorSuite

ENV_ID = "slipenv/FarmField-v0"


def record(steps: int, seed: int = 0):
    """Truths, frames, start pose and the env's sensor suite and estimator factory inputs."""
    env = gym.make(ENV_ID)
    base = env.unwrapped
    suite: SensorSuite = base._sensors  # benchmark-only peek: the env's own sensor suite
    truths, frames = [], []
    measure = suite.measure

    def recording_measure(truth, rng):
        frame = measure(truth, rng)
        truths.append(truth)
        frames.append(frame)
        return frame

    suite.measure = recording_measure  # type: ignore[method-assign]
    try:
        env.reset(seed=seed)
        pose0 = (float(base.estimator.x[0]), float(base.estimator.x[1]),
                 float(base.estimator.x[2]))
        for _ in range(steps):
            _, _, term, trunc, _ = env.step(np.array([0.5, 0.1], dtype=np.float32))
            if term or trunc:
                break
        context = {"dt_s": base.control_dt_s, "beacons_xy": base.beacons_xy,
                   "true_soil": lambda: None}
        return truths, frames, pose0, suite, base.vehicle, context
    finally:
        suite.measure = measure  # type: ignore[method-assign]
        env.close()


def estimator_factories(spec, context) -> dict[str, Callable[[], object]]:
    geometry = odometry_geometry(spec)
    f: dict[str, Callable[[], object]] = {
        "dead_reckoning": lambda: make_estimator("dead_reckoning", spec, context),
        "gyrodometry": lambda: make_estimator("gyrodometry", spec, context),
        "skid_steer_endo": lambda: make_estimator("endo", spec, context),
        "reina_compass_odometry": lambda: CompassOdometry(geometry),
    }
    for scheme in (1, 2, 3, 4):
        f[f"lindgren_ekf_s{scheme}"] = (
            lambda s=scheme: make_estimator("lindgren_ekf", spec, context, scheme=s))
    if compiled_available():
        for scheme in (1, 2, 3, 4):
            f[f"lindgren_ekf_s{scheme}_numpy"] = (
                lambda s=scheme: _numpy_lindgren(spec, context, s))
    return f


def _numpy_lindgren(spec, context, scheme: int) -> object:
    """The Lindgren EKF on its numpy reference (the kernel is chosen at construction)."""
    old = os.environ.get(FORCE_NUMPY_ENV)
    os.environ[FORCE_NUMPY_ENV] = "1"
    try:
        return make_estimator("lindgren_ekf", spec, context, scheme=scheme)
    finally:
        if old is None:
            del os.environ[FORCE_NUMPY_ENV]
        else:
            os.environ[FORCE_NUMPY_ENV] = old


def time_estimator(make: Callable[[], object], frames, pose0) -> float:
    est = make()
    est.reset(*pose0, frames[0])  # type: ignore[attr-defined]
    update = est.update  # type: ignore[attr-defined]
    t0 = time.perf_counter()
    for frame in frames[1:]:
        update(frame)
    return (time.perf_counter() - t0) / (len(frames) - 1)


def time_sensors(suite: SensorSuite, truths) -> float:
    rng = np.random.default_rng(1)
    suite.reset()
    measure = suite.measure
    t0 = time.perf_counter()
    for truth in truths:
        measure(truth, rng)
    return (time.perf_counter() - t0) / len(truths)


def run(steps: int = 300, repeats: int = 7) -> dict:
    truths, frames, pose0, suite, spec, context = record(steps)
    factories = estimator_factories(spec, context)
    samples: dict[str, list[float]] = {name: [] for name in ["sensors", *factories]}
    for _ in range(repeats):
        samples["sensors"].append(time_sensors(suite, truths))
        for name, make in factories.items():
            samples[name].append(time_estimator(make, frames, pose0))
    n_bearings = sum(len(f.beacon_bearings_rad) for f in frames[1:])
    return {
        "env": ENV_ID, "frames": len(frames) - 1, "repeats": repeats,
        "bearings_per_step": round(n_bearings / (len(frames) - 1), 2),
        "lindgren_compiled": compiled_available(),
        "us_per_step": {k: round(1e6 * statistics.median(v), 1) for k, v in samples.items()},
        "us_per_step_min": {k: round(1e6 * min(v), 1) for k, v in samples.items()},
    }


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=300)
    ap.add_argument("--repeats", type=int, default=7)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    result = run(args.steps, args.repeats)
    print(f"{result['env']}: {result['frames']} control steps, "
          f"{result['bearings_per_step']} bearings per step, median of {result['repeats']}; "
          f"Lindgren kernel: {'compiled' if result['lindgren_compiled'] else 'numpy'}")
    print(f"{'component':<26} {'us / control step':>18} {'fastest pass':>13}")
    for name, us in result["us_per_step"].items():
        print(f"{name:<26} {us:>18.1f} {result['us_per_step_min'][name]:>13.1f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)


if __name__ == "__main__":
    main()
