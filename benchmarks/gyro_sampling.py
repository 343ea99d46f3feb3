"""How far the simulated gyro's 20 Hz readings integrate from the body's true turn.

The simulated gyro integrates (`slipenv.sensors.onboard.Imu`, ``sampling="mean"``): it reads
the rotation about body z over each sample interval, summed over the physics substeps,
divided by the interval, as a MEMS gyro behind its decimation filter does. A gyro that samples
the instantaneous rate (``sampling="instant"``, the model before) misses the turn of a body
whose yaw rate chatters between control steps, as the rover's does. This script measures both
on the diagnosis generator's drives (`slipenv.diagnose.synth.drive`: random waypoints, speed
changes, ramped commands; level ground), noise-free sensors, for every generator vehicle:

* ``rms``: RMS of (gyro reading - the interval mean rate Δyaw/Δt from the true pose) [rad/s];
* ``miss``: (Σ gyro Δt - true net turn) / Σ |Δyaw|, per seed.

Run from the repository root::

    python benchmarks/gyro_sampling.py [--seconds 40] [--seeds 1,2,3]
"""

from __future__ import annotations

import argparse

import numpy as np

from slipenv.diagnose import synth


def measure(kind: str, seed: int, seconds: float, sampling: str) -> tuple[float, float]:
    """(RMS of gyro - interval mean [rad/s], integral miss / total turn) of one drive."""
    cfg = synth.base_config(kind)
    log = synth.drive(cfg, kind, np.random.default_rng(seed), seconds, columns={"imu"},
                      exact=True, gyro_sampling=sampling).log
    yaw = np.unwrap(log.signals["gt_yaw"])
    gyro = np.asarray(log.signals["gyro_z"])
    dt = np.diff(log.t)
    mean_rate = np.diff(yaw) / dt
    rms = float(np.sqrt(np.mean((gyro[1:] - mean_rate) ** 2)))
    miss = float((np.sum(gyro[1:] * dt) - (yaw[-1] - yaw[0])) / np.sum(np.abs(np.diff(yaw))))
    return rms, miss


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=40.0)
    ap.add_argument("--seeds", default="1,2,3")
    args = ap.parse_args(argv)
    seeds = [int(s) for s in args.seeds.split(",")]
    print(f"{'vehicle':<12} {'gyro':<8} {'rms rad/s':>10}  miss / turn, per seed")
    for kind in synth.VEHICLES:
        for sampling in ("instant", "mean"):
            rows = [measure(kind, seed, args.seconds, sampling) for seed in seeds]
            rms = float(np.mean([r for r, _ in rows]))
            misses = ", ".join(f"{m:+.2e}" for _, m in rows)
            print(f"{kind:<12} {sampling:<8} {rms:>10.2e}  {misses}")


if __name__ == "__main__":
    main()
