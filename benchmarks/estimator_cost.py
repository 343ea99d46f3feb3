"""Cost per control step of every pose estimator and of the onboard sensors.

Records one FarmField-v0 episode (Lindgren's 2WD farm vehicle: encoders, torque sensors, IMU,
inclinometer, compass and the beacon scanner, 20 Hz) -- the ground truth the sensor suite was
given and the frames it produced -- and then, with PyBullet out of the loop, replays:

* the sensor suite over the recorded truths (``SensorSuite.measure``, beacons included);
* every estimator over the recorded frames (``reset`` once, then ``update`` per frame):
  dead reckoning, gyrodometry, Endo's skid-steer odometry, Reina's compass odometry and the
  Lindgren EKF in schemes 1-5 (compiled by numba from its Python text), and schemes 4 and 5
  with the lateral slip gain (scheme 4's is FarmField-v0's own filter).

Before the timed passes it also reports the Lindgren EKF's one-off costs in this process:
importing it (numba included) and its first frame, which loads the compiled code from numba's
on-disk cache, or compiles it when the cache is cold (the first run after an install or an
edit of the filter's source; run twice to see both). And the compiled code's heap allocations
per frame of FarmField-v0's filter (numba's allocation statistics, in a fresh interpreter with
``NUMBA_NRT_STATS=1``): 0, since the frame kernel runs without numba's reference-counted
runtime (its models write into the filter's workspace, and its array arguments are not
wrapped in runtime records); a model that allocates would not compile in it.

Each cost is the median over ``--repeats`` passes of (time for the whole pass) / (frames), in
microseconds per control step, and next to it the fastest pass (on a loaded machine, the closer
to the cost on a quiet one); passes of different estimators are interleaved so that load from
other processes hits all alike. Run from the repository root::

    python benchmarks/estimator_cost.py [--steps 300] [--repeats 7] [--json PATH]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time
from collections.abc import Callable

import gymnasium as gym
import numpy as np

import slipenv  # noqa: F401  (registers the envs)
from slipenv.envs.estimation import make_estimator, odometry_geometry
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
    for scheme in (1, 2, 3, 4, 5):
        f[f"lindgren_ekf_s{scheme}"] = (
            lambda s=scheme: make_estimator("lindgren_ekf", spec, context, scheme=s))
    # FarmField-v0's own filter: scheme 4 with the lateral slip gain
    lateral = {"lateral_slip_sigma0": 3.0}
    f["lindgren_ekf_s4_lateral"] = (
        lambda: make_estimator("lindgren_ekf", spec, context, scheme=4, params=lateral))
    f["lindgren_ekf_s5_lateral"] = (
        lambda: make_estimator("lindgren_ekf", spec, context, scheme=5, params=lateral))
    return f


_STARTUP = """
import json, time
import numpy as np
t0 = time.perf_counter()
from slipenv.contracts.frame import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren.ekf import LindgrenEKF
t1 = time.perf_counter()
ekf = LindgrenEKF(OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=285.0),
                  4, beacons_xy=np.array([[10.0, 0.0], [0.0, 10.0]]))
frame = lambda t: SensorFrame(t_s=t, enc_counts=np.zeros(2), wheel_torque_nm=np.zeros(2),
                              gyro_z_rad_s=0.0, acc_x_mps2=0.0, acc_y_mps2=0.0,
                              beacon_bearings_rad=np.array([0.0]), beacon_times_s=np.array([t]))
ekf.reset(0.0, 0.0, 0.0, frame(0.0))
ekf.update(frame(0.05))
t2 = time.perf_counter()
print(json.dumps({"import_s": round(t1 - t0, 3), "first_frame_s": round(t2 - t1, 3)}))
"""


def lindgren_startup() -> dict[str, float]:
    """In a fresh interpreter: seconds to import the Lindgren EKF (numba included) and to run
    its first frame (scheme 4, one bearing, every sensor), which loads the compiled code from
    numba's cache or, when the cache is cold, compiles it."""
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _STARTUP], capture_output=True, text=True,
                          check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


_ALLOCATIONS = """
import json
import numpy as np
from numba.core.runtime import rtsys
from slipenv.contracts.frame import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren.ekf import LindgrenEKF, LindgrenNoise
ekf = LindgrenEKF(OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=285.0),
                  4, params=LindgrenNoise(lateral_slip_sigma0=3.0),
                  beacons_xy=np.array([[10.0, 0.0], [0.0, 10.0], [-10.0, 0.0]]))
def frame(k):
    t = 0.05 * k
    return SensorFrame(t_s=t, enc_counts=np.array([2.0, 2.1]) * k,
                       wheel_torque_nm=np.array([40.0, 42.0]), gyro_z_rad_s=0.01,
                       acc_x_mps2=0.0, acc_y_mps2=0.0, pitch_rad=0.0, roll_rad=0.0,
                       beacon_bearings_rad=np.array([0.1, 1.6]),
                       beacon_times_s=np.array([t - 0.03, t - 0.01]))
ekf.reset(0.0, 0.0, 0.0, frame(0))
for k in range(1, 20):
    ekf.update(frame(k))
before = rtsys.get_allocation_stats().alloc
for k in range(20, 120):
    ekf.update(frame(k))
print(json.dumps({"per_frame": (rtsys.get_allocation_stats().alloc - before) / 100}))
"""


def lindgren_allocations() -> float:
    """In a fresh interpreter with numba's allocation statistics on: heap allocations of the
    compiled code per frame of FarmField-v0's filter (scheme 4 with the lateral slip gain;
    two bearings, every sensor)."""
    import os
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", _ALLOCATIONS], capture_output=True, text=True,
                          check=True, env={**os.environ, "NUMBA_NRT_STATS": "1"})
    return json.loads(done.stdout.strip().splitlines()[-1])["per_frame"]


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
    startup = lindgren_startup()
    allocations = lindgren_allocations()
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
        "lindgren_startup_s": startup,
        "lindgren_allocations_per_frame": allocations,
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
          f"{result['bearings_per_step']} bearings per step, median of {result['repeats']}")
    st = result["lindgren_startup_s"]
    print(f"Lindgren EKF in a fresh interpreter: import {st['import_s']} s, first frame "
          f"{st['first_frame_s']} s (loads the compiled code from numba's cache, or compiles)")
    print(f"Lindgren EKF heap allocations per frame: {result['lindgren_allocations_per_frame']:g}"
          " (the frame kernel runs without numba's runtime: 0)")
    print(f"{'component':<26} {'us / control step':>18} {'fastest pass':>13}")
    for name, us in result["us_per_step"].items():
        print(f"{name:<26} {us:>18.1f} {result['us_per_step_min'][name]:>13.1f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(result, fh, indent=2)


if __name__ == "__main__":
    main()
