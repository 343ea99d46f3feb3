"""Wall time of ``slipenv diagnose`` on a 5-minute, 20 Hz log (JSON + full human report).

Generates seven logs — a skid-steer vehicle with turning slip (Endo's exponent needs
several starts), a differential-drive one with a soil patch (the disc search), a skid-steer
vehicle with a torque column (every slip law and their joint fits are tried), torque slip
hidden on the skid-steer, tracked and rover vehicles (the slowest logs of the PyBullet
hit-rate table: forward selection refits the joint models fold by fold on the long route)
and a clean tracked log — writes each, and times the command line end to end, PyBullet
replay for the report included. Limit the process to 2 cores to match the requirement, e.g.
``taskset -c 0,1 python benchmarks/diagnose_time.py``.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
from pathlib import Path

from slipenv.cli import main as slipenv_main
from slipenv.diagnose.synth import generate
from slipenv.logs import write_log


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--duration", type=float, default=300.0, help="log length [s]")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"{cores} core(s) available")
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        cases = (("turning_slip", "skid_steer", None), ("soil_patch", "diff_drive", None),
                 ("rolling_radius", "skid_steer", {"cmd", "torque", "imu"}),
                 # the slowest logs of the PyBullet hit-rate table: torque slip on the
                 # skid-steer and tracked vehicles (named turning_slip, a calibration added)
                 ("torque_slip", "skid_steer", None), ("torque_slip", "tracked", None),
                 ("torque_slip", "rover4ws", None), ("none", "tracked", None))
        for effect, kind, columns in cases:
            synth = generate(args.seed, effect, kind, duration_s=args.duration, columns=columns)
            folder = write_log(synth.log, Path(tmp) / effect)
            start = time.perf_counter()
            code = slipenv_main(["diagnose", str(folder), "--json", str(Path(tmp) / "d.json"),
                                 "--report", str(Path(tmp) / f"report_{effect}"), "--quiet"])
            rows.append((effect, kind, len(synth.log), time.perf_counter() - start, code,
                         "torque" if columns and "torque" in columns else ""))
    print("\n| log | samples | slipenv diagnose (JSON + report) |\n|---|---|---|")
    for effect, kind, n, seconds, code, extra in rows:
        what = f"{kind}{', with torque' if extra else ''}, hidden {effect}"
        print(f"| {what}, {args.duration / 60:g} min at 20 Hz | {n} | "
              f"{seconds:.1f} s{'' if code == 0 else f' (exit {code})'} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
