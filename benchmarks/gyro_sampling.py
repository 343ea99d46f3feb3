"""How far the simulated gyro's 20 Hz samples are from the turn they should integrate to.

The simulated IMU reads the body's instantaneous yaw rate at each control step
(`slipenv.sensors.onboard.Imu`). A body whose yaw rate chatters between control steps is then
sampled, not averaged, and the integral of the readings misses the turn; a rate-integrating
IMU (one that reports the mean rate over its interval) would not. This script measures it on
the diagnosis generator's drives (`slipenv.diagnose.synth.drive`: random waypoints, speed
changes, ramped commands), noise-free sensors, for every generator vehicle:

* ``rms_rad_s``: RMS of (gyro sample - the interval mean rate, Δyaw/Δt from the true pose);
* ``integral_miss``: (Σ gyro Δt - true net turn) / Σ |Δyaw|, per seed.

Run from the repository root::

    python benchmarks/gyro_sampling.py [--seconds 40] [--seeds 1,2,3]
"""

from __future__ import annotations

import argparse

import numpy as np

from slipenv.diagnose import synth


def measure(kind: str, seed: int, seconds: float) -> tuple[float, float]:
    """(RMS of gyro - interval mean [rad/s], integral miss / total turn) of one drive."""
    cfg = synth.base_config(kind)
    log = synth.drive(cfg, kind, np.random.default_rng(seed), seconds, columns={"imu"},
                      exact=True).log
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
    print(f"{'vehicle':<12} {'RMS(gyro - interval mean) rad/s':>32}  "
          "integral miss / turn, per seed")
    for kind in synth.VEHICLES:
        rows = [measure(kind, seed, args.seconds) for seed in seeds]
        rms = float(np.mean([r for r, _ in rows]))
        misses = ", ".join(f"{m:+.3f}" for _, m in rows)
        print(f"{kind:<12} {rms:>32.4f}  {misses}")


if __name__ == "__main__":
    main()
