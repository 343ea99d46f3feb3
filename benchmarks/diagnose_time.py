"""Wall time of ``slipenv diagnose`` on a 5-minute, 20 Hz log (JSON + full human report).

Generates seven logs — a skid-steer vehicle with turning slip (Endo's exponent needs
several starts), a differential-drive one with a soil patch (the disc search), a skid-steer
vehicle with a torque column (every slip law and their joint fits are tried), torque slip
hidden on the skid-steer, tracked and rover vehicles (the slowest logs of the PyBullet
hit-rate table: forward selection refits the joint models fold by fold on the long route)
and a clean tracked log — writes each, and times the command line end to end, PyBullet
replay for the report included, once per ``--jobs`` value (``slipenv diagnose --jobs N``:
the fits on N processes; the reports are the same, which the benchmark checks). Limit the
process to 2 cores to match the requirement, e.g.
``taskset -c 0,1 python benchmarks/diagnose_time.py`` (``--jobs 1,2``: one process, then
the default on two cores).
"""

from __future__ import annotations

import argparse
import contextlib
import io
import json
import tempfile
import time
from pathlib import Path

from slipenv.cli import main as slipenv_main
from slipenv.diagnose.synth import generate
from slipenv.diagnose.workers import available_cores
from slipenv.logs import write_log


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--duration", type=float, default=300.0, help="log length [s]")
    parser.add_argument("--seed", type=int, default=1)
    parser.add_argument("--jobs", default="1,2",
                        help="comma-separated process counts to time each log with")
    args = parser.parse_args(argv)
    try:
        jobs = [int(j) for j in args.jobs.split(",")]
    except ValueError:
        parser.error(f"--jobs must be comma-separated whole numbers, got {args.jobs!r}")
    if not jobs or min(jobs) < 1:
        parser.error(f"--jobs must be whole numbers >= 1, got {args.jobs!r}")
    print(f"{available_cores()} core(s) available")
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
            times, reports = [], []
            for n in jobs:
                out = Path(tmp) / f"d{n}.json"
                start = time.perf_counter()
                with contextlib.redirect_stdout(io.StringIO()):  # its summary: in the JSON
                    code = slipenv_main(["diagnose", str(folder), "--json", str(out), "--jobs",
                                         str(n), "--report",
                                         str(Path(tmp) / f"report_{effect}"), "--quiet"])
                times.append((time.perf_counter() - start, code))
                reports.append(json.loads(out.read_text()) if code == 0 else None)
            if any(r != reports[0] for r in reports):
                raise SystemExit(f"{effect} on {kind}: the report depends on --jobs")
            rows.append((effect, kind, len(synth.log), times,
                         "torque" if columns and "torque" in columns else ""))
    head = " | ".join(f"{n} process{'es' if n > 1 else ''}" for n in jobs)
    print(f"\n| log | samples | {head} |\n|---|---|{'---|' * len(jobs)}")
    for effect, kind, n, times, extra in rows:
        what = f"{kind}{', with torque' if extra else ''}, hidden {effect}"
        cells = " | ".join(f"{seconds:.1f} s{'' if code == 0 else f' (exit {code})'}"
                           for seconds, code in times)
        print(f"| {what}, {args.duration / 60:g} min at 20 Hz | {n} | {cells} |")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
