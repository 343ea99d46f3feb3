"""Hit rate of ``slipenv diagnose`` on logs with one hidden effect (or none) from the physics.

Generates ``--n`` logs with :func:`slipenv.diagnose.synth.generate` — each with a random kind
of effect (or none), random size, random vehicle kind, route, noise, optional columns and
ground-truth gaps — diagnoses each, and prints per effect: logs, correctly named, false alarms
on clean logs, parameters within 3 reported standard errors of the truth (a sensor offset's
set value; for the other effects, whose effective value the vehicle's own dynamics shift a
little, the value fitted on a long noise-free calibration run of the same world), the median
relative error against the value set in the physics where there is one, and timings.
A log whose hidden effect's physics shows as another effect on that vehicle kind
(``Effect.confounds``: torque slip on a skid-steer is turning slip) and is named so is a
miss, counted in the ``confounded`` column.

``--vehicles`` generates ``--n`` logs on each listed generator vehicle (``synth.VEHICLES``:
``diff_drive`` farm robot, ``skid_steer`` four-wheel skid-steer, ``tracked`` Patako's tracked
vehicle, ``rover4ws`` 4WD/4WS rover), each effect hidden on it equally often, and adds the
effect x vehicle table.

``--durations 60,120,300`` generates the same seeds (the same worlds and routes) at every
length and adds the vehicle x length table (named right / logs, false alarms on the clean
logs, confounded logs); logs are printed as they finish, clean logs first and the rest round
by round over lengths and vehicles, so a run stopped early has covered every cell alike.
``--by-length`` runs the lengths one after another instead (each table completes before the
next starts). ``--first SEEDS`` runs those seeds' logs before the others (a last run's misses,
to see a fix early). ``--jsonl FILE`` appends each outcome as it finishes, ``--resume`` skips
the logs FILE already holds, and ``--tables-from FILE`` prints the tables of what a run,
finished or stopped, saved there.

The generator's seeds change every run (printed; pass ``--seed`` to repeat a run).

``--kinematic N`` also runs the kinematic generator (``slipenv.diagnose.kinematic``: correlated
wheel-speed noise, no physics engine) on N seeds of each of: a 1 % track-width error, a
right wheel 1.5 % larger together with a 2 % wider track (both must be named), a one-way
circle with the 1 % track-width error (a geometric cause, flagged not separable), and a clean
log (``none``); for the first two, also whether the fitted radii and track width lie within
3 reported standard errors of those set.

``--kinds N`` runs the kinematic generator for every vehicle kind (``diff_drive``,
``skid_steer``, ``rover4ws``) and every log length of ``--lengths`` (default 60, 120, 300 s)
on N seeds of: a single effect (right wheels 1.5 % larger), two effects (that and a 2 % wider
track; both must be named) and a clean log (no false alarm), and prints the table with the
mean diagnosis time.

    python benchmarks/diagnose_hit_rate.py --n 40 --duration 120 --jobs 2
    python benchmarks/diagnose_hit_rate.py --n 16 --duration 120 --jobs 1 \\
        --vehicles diff_drive,skid_steer,tracked,rover4ws
    python benchmarks/diagnose_hit_rate.py --n 6 --durations 60,120,300 --jobs 2 \\
        --vehicles diff_drive,skid_steer,tracked,rover4ws
    python benchmarks/diagnose_hit_rate.py --n 0 --kinematic 30 --duration 120
    python benchmarks/diagnose_hit_rate.py --n 0 --kinds 5 --lengths 60,120,300
    python benchmarks/diagnose_hit_rate.py --n 0 --soil 10

``--soil N`` diagnoses N kinematic logs (seeds 3 … N + 2; seed 3 is the tests' log) of an
8 m field swept lane by lane for 3 minutes over each soil layout of ``SOIL_LAYOUTS`` (two
rectangles, those of ``tests/diagnose/test_kinds_and_soil_map.py``; two rectangles turned
30 degrees to the lanes; a disc and an L-shaped field) and prints what each is named, the
soil map's regions, its held-out error ratio and p on the short segments and its gain on the
long route. ``--soil-kinds`` says under which vehicles: the differential drive crosses every
layout, the skid-steer vehicle and the rover the tests' two rectangles (every wheel slips by
its own torque times the compliance under the vehicle).

    python benchmarks/diagnose_hit_rate.py --n 0 --soil 10 --soil-kinds skid_steer,rover4ws
"""

from __future__ import annotations

import argparse
import json
import os
import time
from concurrent.futures import ProcessPoolExecutor, as_completed
from pathlib import Path

import numpy as np

from slipenv.diagnose.effects import EFFECTS
from slipenv.diagnose.kinematic import KINDS
from slipenv.diagnose.synth import DRAWN, GENERATED
from slipenv.diagnose.synth import KINDS as HIDDEN_ON

Z_LIMIT = 3.0  # |estimate - truth| <= 3 standard errors counts as recovered


def run_one(job: tuple) -> dict:
    """Generate and diagnose one log (``(seed, effect, duration[, vehicle])``); the outcome."""
    from slipenv.diagnose import replay
    from slipenv.diagnose.fit import Problem
    from slipenv.diagnose.select import select
    from slipenv.diagnose.synth import generate

    seed, effect, duration = job[:3]
    vehicle = job[3] if len(job) > 3 else None
    t0 = time.perf_counter()
    synth = generate(seed, effect, vehicle, duration_s=duration)
    t1 = time.perf_counter()
    seg = replay.build_segments([synth.log])
    sel = select(Problem.from_segments(seg), logs=[synth.log])
    t2 = time.perf_counter()
    z: dict[str, float] = {}
    rel: dict[str, float] = {}
    if sel.cause == effect and effect != "none" and EFFECTS[effect].hiding.compare:
        rep = {}
        for fit in sel.fits.values():
            rep.update(fit.report(seg))
        z = {k: (rep[k][0] - v) / max(rep[k][1], 1e-300) for k, v in synth.truth.items()
             if k in rep}
        rel = {k: abs(rep[k][0] / v - 1.0) for k, v in synth.world.items()
               if k in rep and isinstance(v, float) and v != 0 and not k.startswith("patch_c")}
    conf = None if effect == "none" else EFFECTS[effect].confound(synth.log.meta.kind)
    return {"seed": seed, "effect": effect, "kind": synth.log.meta.kind, "duration": duration,
            "vehicle": vehicle or synth.log.meta.kind, "cause": sel.cause,
            "confounded": conf is not None and sel.cause == conf.shows_as,
            "also": sel.also, "z": z, "rel": rel, "gen_s": t1 - t0, "diag_s": t2 - t1,
            "columns": [c for c in synth.log.columns if not c.startswith(("enc_", "gt_"))]}


def _extra(results: list[dict]) -> str:
    """Logs named right whose ``also`` adds causes that were not hidden (one effect is)."""
    right = [r for r in results if r["cause"] == r["effect"] != "none"]
    return f"{sum(bool(set(r['also']) - {r['effect']}) for r in right)}/{len(right)}" \
        if right else "-"


def table(results: list[dict]) -> str:
    """The hit-rate table (markdown)."""
    rows = ["| effect | logs | named right | hit rate | confounded | false alarms "
            "| more causes in `also` | params within 3 SE | median rel. error vs set value "
            "| diagnosis time (mean) |",
            "|---|---|---|---|---|---|---|---|---|---|"]
    for effect in GENERATED:
        rs = [r for r in results if r["effect"] == effect]
        if not rs:
            continue
        hits = sum(r["cause"] == effect for r in rs)
        fa = sum(r["cause"] != "none" for r in rs) if effect == "none" else None
        zs = [r for r in rs if r["z"]]
        within = sum(all(abs(v) <= Z_LIMIT for v in r["z"].values()) for r in zs)
        rels = [v for r in rs for v in r["rel"].values()]
        conf = sum(r["confounded"] for r in rs)
        rows.append(f"| {effect} | {len(rs)} | {hits} | {100 * hits / len(rs):.0f} % | "
                    f"{conf or '-'} | {'-' if fa is None else fa} | {_extra(rs)} | "
                    f"{f'{within}/{len(zs)}' if zs else '-'} | "
                    f"{f'{100 * np.median(rels):.1f} %' if rels else '-'} | "
                    f"{np.mean([r['diag_s'] for r in rs]):.1f} s |")
    hits = sum(r["cause"] == r["effect"] for r in results)
    clean = [r for r in results if r["effect"] == "none"]
    alarms = sum(r["cause"] != "none" for r in clean)
    rows.append(f"| **all** | {len(results)} | {hits} | {100 * hits / len(results):.0f} % | "
                f"{sum(r['confounded'] for r in results) or '-'} | {alarms}/{len(clean)} | "
                f"{_extra(results)} | | | "
                f"{np.mean([r['diag_s'] for r in results]):.1f} s |")
    return "\n".join(rows)


def vehicle_table(results: list[dict], vehicles: list[str]) -> str:
    """Effect x vehicle table (markdown): named right / logs; false alarms on clean logs."""
    head = " | ".join(vehicles)
    rows = [f"| effect | {head} |", "|---|" + "---|" * len(vehicles)]
    for effect in GENERATED:
        if not any(r["effect"] == effect for r in results):
            continue
        cells = []
        for v in vehicles:
            rs = [r for r in results if r["effect"] == effect and r["vehicle"] == v]
            if not rs:
                cells.append("–")
            elif effect == "none":
                alarms = sum(r["cause"] != "none" for r in rs)
                cells.append(f"{len(rs) - alarms}/{len(rs)} ({alarms} false alarm"
                             f"{'' if alarms == 1 else 's'})")
            else:
                conf = [r["cause"] for r in rs if r["confounded"]]
                cells.append(f"{sum(r['cause'] == effect for r in rs)}/{len(rs)}"
                             + (f" ({len(conf)} named {conf[0]}: confounded)" if conf else ""))
        rows.append(f"| {effect} | {' | '.join(cells)} |")
    cells = [_extra([r for r in results if r["vehicle"] == v]) for v in vehicles]
    rows.append(f"| more causes in `also` (of those named right) | {' | '.join(cells)} |")
    cells = []
    for v in vehicles:
        rs = [r for r in results if r["vehicle"] == v]
        cells.append(f"**{sum(r['cause'] == r['effect'] for r in rs)}/{len(rs)}**, "
                     f"{np.mean([r['diag_s'] for r in rs]):.1f} s" if rs else "–")
    rows.append(f"| **all** (mean diagnosis time) | {' | '.join(cells)} |")
    return "\n".join(rows)


def length_table(by_length: dict[float, list[dict]], vehicles: list[str]) -> str:
    """Vehicle x log length table (markdown): named right / logs, confounded and false alarms
    on clean logs said in the cell; the last row and column pool them."""
    lengths = list(by_length)

    def cell(rs: list[dict]) -> str:
        if not rs:
            return "–"
        clean = [r for r in rs if r["effect"] == "none"]
        alarms = sum(r["cause"] != "none" for r in clean)
        conf = sum(r["confounded"] for r in rs)
        return (f"{sum(r['cause'] == r['effect'] for r in rs)}/{len(rs)} "
                f"({alarms}/{len(clean)} false alarms" + (f", {conf} confounded" if conf else "")
                + ")")

    head = " | ".join(f"{d / 60:g} min" for d in lengths)
    rows = [f"| vehicle | {head} | all |", "|---|" + "---|" * (len(lengths) + 1)]
    for v in vehicles:
        cells = [cell([r for r in by_length[d] if r["vehicle"] == v]) for d in lengths]
        cells.append(cell([r for d in lengths for r in by_length[d] if r["vehicle"] == v]))
        rows.append(f"| {v} | {' | '.join(cells)} |")
    cells = [cell(by_length[d]) for d in lengths]
    cells.append(cell([r for d in lengths for r in by_length[d]]))
    rows.append(f"| **all** | {' | '.join(cells)} |")
    return "\n".join(rows)


KINEMATIC_CASES = {
    # case: (true radii L, R and track width for a nominal 0.1 m / 0.5 m robot, route, wanted)
    "track_width_1pct": ((0.1, 0.1, 0.505), "mixed", {"track_width"}),
    "radius+track_width": ((0.1, 0.1015, 0.51), "mixed", {"rolling_radius", "track_width"}),
    "circle_track_width_1pct": ((0.1, 0.1, 0.505), "circle", None),
    "none": (None, "mixed", set()),
}


def kinematic_one(job: tuple[str, int, float]) -> dict:
    """Diagnose one kinematic log; whether the wanted causes were named."""
    from slipenv.diagnose.cli import diagnose
    from slipenv.diagnose.kinematic import KinematicTruth, kinematic_log

    case, seed, duration = job
    geometry, route, wanted = KINEMATIC_CASES[case]
    truth = KinematicTruth(*geometry) if geometry else None
    t0 = time.perf_counter()
    report, _ = diagnose([kinematic_log(seed, truth, duration_s=duration, route=route)], case)
    named = {report["cause"], *report["also"]} - {"none"}
    if wanted is None:  # one-way circle: a geometric cause, and the confound reported
        ok = bool(named & {"rolling_radius", "track_width"}) and \
            not report["calibration"]["separable"]
    else:
        ok = named == wanted if not wanted else wanted <= named
    # the geometry set in the log against the fitted values, in reported standard errors
    within = None
    if truth is not None and wanted:
        set_values = {"radius_left_m": truth.radius_left_m, "radius_right_m": truth.radius_right_m,
                      "track_width_m": truth.track_width_m}
        fitted = {k: v for k, v in report["parameters"].items() if k in set_values}
        within = ok and bool(fitted) and all(
            abs(v[0] - set_values[k]) <= Z_LIMIT * v[1] for k, v in fitted.items())
    return {"case": case, "seed": seed, "named": sorted(named), "ok": ok, "within": within,
            "s": time.perf_counter() - t0}


def kinematic_table(n: int, duration: float, jobs: int) -> str:
    """Hit rates of the kinematic cases over seeds 0..n-1 (markdown)."""
    work = [(case, seed, duration) for case in KINEMATIC_CASES for seed in range(n)]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(kinematic_one, work))
    rows = [f"| kinematic case ({duration:g} s logs) | logs | right | rate | "
            f"right, parameters within {Z_LIMIT:g} SE | mean time |",
            "|---|---|---|---|---|---|"]
    for case in KINEMATIC_CASES:
        rs = [r for r in results if r["case"] == case]
        hits = sum(r["ok"] for r in rs)
        within = ("–" if KINEMATIC_CASES[case][2] in (None, set())
                  else f"{sum(bool(r['within']) for r in rs)}/{len(rs)}")
        rows.append(f"| {case} | {len(rs)} | {hits} | {100 * hits / len(rs):.0f} % | {within} | "
                    f"{np.mean([r['s'] for r in rs]):.1f} s |")
    return "\n".join(rows)


KIND_CASES = {
    # case: (true radii L, R and track width for a nominal 0.1 m / 0.5 m robot, wanted)
    "single (radius R +1.5 %)": ((0.1, 0.1015, 0.5), {"rolling_radius"}),
    "two (radius R +1.5 %, track +2 %)": ((0.1, 0.1015, 0.51), {"rolling_radius", "track_width"}),
    "clean": (None, set()),
}
def kind_one(job: tuple[str, str, float, int]) -> dict:
    """Diagnose one kinematic log of a vehicle kind; whether the answer is right."""
    from slipenv.diagnose.cli import diagnose
    from slipenv.diagnose.kinematic import KinematicTruth, kinematic_log

    case, kind, duration, seed = job
    geometry, wanted = KIND_CASES[case]
    truth = KinematicTruth(*geometry) if geometry else None
    log = kinematic_log(seed, truth, duration_s=duration, kind=kind)
    t0 = time.perf_counter()
    report, _ = diagnose([log], case)
    named = {report["cause"], *report["also"]} - {"none"}
    ok = (not named) if not wanted else wanted <= named
    return {"case": case, "kind": kind, "duration": duration, "seed": seed, "ok": ok,
            "named": sorted(named), "s": time.perf_counter() - t0}


def kinds_table(n: int, lengths: list[float], jobs: int) -> str:
    """Rates per vehicle kind, case and log length over seeds 0..n-1 (markdown)."""
    work = [(case, kind, d, 1000 * k + seed) for k, kind in enumerate(KINDS)
            for case in KIND_CASES for d in lengths for seed in range(n)]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(kind_one, work))
    head = " | ".join(f"{d / 60:g} min" for d in lengths)
    rows = [f"| kind | case | {head} | mean time ({lengths[-1] / 60:g} min) |",
            "|---|---|" + "---|" * len(lengths) + "---|"]
    for kind in KINDS:
        for case in KIND_CASES:
            cells = []
            for d in lengths:
                rs = [r for r in results if r["kind"] == kind and r["case"] == case
                      and r["duration"] == d]
                cells.append(f"{sum(r['ok'] for r in rs)}/{len(rs)}")
            last = [r["s"] for r in results if r["kind"] == kind and r["case"] == case
                    and r["duration"] == lengths[-1]]
            rows.append(f"| {kind} | {case} | {' | '.join(cells)} | {np.mean(last):.1f} s |")
    return "\n".join(rows)


# soil layouts of the field logs: (x0, y0, x1, y1, compliance [1/(N m)], angle [rad])
# rectangles and (centre x, centre y, radius, compliance) discs, in the 8 m field [-4, 4]^2
SOIL_LAYOUTS = {
    # two rectangles not aligned with the lanes' ends (the tests' layout)
    "two rectangles": ((-4.0, -4.0, -0.5, 0.0, 0.008, 0.0), (1.0, 0.5, 4.0, 4.0, 0.006, 0.0)),
    # the same kind of fields turned 30 deg to the lanes
    "two turned rectangles": ((-3.5, -3.0, -0.5, -0.5, 0.008, 0.52),
                              (0.5, 0.5, 3.5, 3.0, 0.006, 0.52)),
    # a disc and an L-shaped field (two rectangles of one soil)
    "disc and L-shape": ((-1.5, 1.5, 1.8, 0.008),
                         (0.5, -3.5, 3.5, -1.5, 0.006, 0.0), (2.0, -1.5, 3.5, 1.0, 0.006, 0.0)),
}


def _soil_regions(layout: str) -> tuple:
    from slipenv.diagnose.kinematic import SoilDisc, SoilRegion

    return tuple(SoilDisc(*r) if len(r) == 4 else SoilRegion(*r)
                 for r in SOIL_LAYOUTS[layout])


def soil_one(case: tuple[str, int, str]) -> dict:
    """Diagnose one field log of a soil layout (``(layout, seed, vehicle kind)``); the cause
    and the map's scores."""
    from slipenv.diagnose import replay
    from slipenv.diagnose.fit import Problem
    from slipenv.diagnose.kinematic import kinematic_log
    from slipenv.diagnose.select import select

    layout, seed, kind = case
    log = kinematic_log(seed, None, duration_s=180.0, route="field",
                        soil_regions=_soil_regions(layout), kind=kind)
    seg = replay.build_segments([log])
    start = time.perf_counter()
    sel = select(Problem.from_segments(seg), logs=[log])
    m = next(c for c in sel.candidates if c.name == "soil_map")
    final = sel.fits.get(m.channel)  # the named model, when the map is in it
    return {"layout": layout, "kind": kind, "seed": seed, "cause": sel.cause, "also": sel.also,
            "ratio": m.error_ratio, "p": m.p_value,
            "long_gain": None if m.long is None else m.long.gain_relative,
            "regions": final.params["soil_map"].regions
            if final is not None and "soil_map" in final.effects else None,
            "seconds": time.perf_counter() - start}


def soil_cases(kinds: list[str]) -> list[tuple[str, str]]:
    """(layout, vehicle kind) pairs: every layout under a differential drive, the tests' two
    rectangles under the other kinds."""
    return [(layout, kind) for kind in kinds
            for layout in (SOIL_LAYOUTS if kind == "diff_drive" else ("two rectangles",))]


def soil_table(n: int, jobs: int, kinds: list[str]) -> str:
    """What the field logs of every soil layout are named (markdown)."""
    pairs = soil_cases(kinds)
    cases = [(layout, seed, kind) for layout, kind in pairs for seed in range(3, 3 + n)]
    with ProcessPoolExecutor(max_workers=jobs) as pool:
        results = list(pool.map(soil_one, cases))
    rows = ["| layout | vehicle | seed | named | regions | soil_map held-out error ratio | "
            "p (short) | gain (long) | time |", "|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        long = "-" if r["long_gain"] is None else f"{r['long_gain']:+.2f}"
        regions = "-" if r["regions"] is None else str(r["regions"])
        rows.append(f"| {r['layout']} | {r['kind']} | {r['seed']} | "
                    f"{'+'.join([r['cause'], *r['also']])} | {regions} | {r['ratio']:.3f} | "
                    f"{r['p']:.2g} | {long} | {r['seconds']:.0f} s |")
    summary = ["", "| layout | vehicle | soil_map named | held-out error ratio (median, range) |",
               "|---|---|---|---|"]
    for layout, kind in pairs:
        mine = [r for r in results if (r["layout"], r["kind"]) == (layout, kind)]
        named = sum(r["cause"] == "soil_map" or "soil_map" in r["also"] for r in mine)
        ratios = [r["ratio"] for r in mine]
        summary.append(f"| {layout} | {kind} | {named}/{len(mine)} | {np.median(ratios):.3f} "
                       f"({min(ratios):.3f}-{max(ratios):.3f}) |")
    return "\n".join(rows + summary)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--n", type=int, default=40, help="number of logs (default 40)")
    parser.add_argument("--duration", type=float, default=120.0, help="log length [s]")
    parser.add_argument("--durations", default=None,
                        help="comma-separated log lengths [s] of the PyBullet logs: the same "
                             "seeds (the same worlds and routes) at every length, and the "
                             "vehicle x length table (default: --duration alone)")
    parser.add_argument("--seed", type=int, default=None, help="base seed (default: random)")
    parser.add_argument("--jobs", type=int, default=2, help="worker processes")
    parser.add_argument("--effects", default=",".join(DRAWN),
                        help="comma-separated effects to draw from (default: those drawn at "
                             f"random, {','.join(DRAWN)}; also: "
                             f"{','.join(e for e in GENERATED if e not in DRAWN)})")
    parser.add_argument("--vehicles", default=None,
                        help="comma-separated generator vehicles (synth.VEHICLES labels: "
                             "diff_drive, skid_steer, tracked, rover4ws): --n logs per "
                             "vehicle, effects drawn among those hidden on it, and the "
                             "effect x vehicle table (default: one random vehicle per log)")
    parser.add_argument("--kinematic", type=int, default=0,
                        help="seeds per case of the kinematic generator (default 0: skip)")
    parser.add_argument("--kinds", type=int, default=0,
                        help="seeds per vehicle kind, case and length (default 0: skip)")
    parser.add_argument("--soil", type=int, default=0,
                        help="field logs per soil layout (default 0: skip)")
    parser.add_argument("--soil-kinds", default="diff_drive",
                        help="comma-separated vehicle kinds of --soil (diff_drive: every "
                             "layout; skid_steer, rover4ws: the tests' two rectangles)")
    parser.add_argument("--jsonl", default=None,
                        help="append each PyBullet log's outcome to this file as it finishes "
                             "(one JSON line; a run stopped early keeps what it found)")
    parser.add_argument("--first", default="",
                        help="comma-separated seeds whose logs run first, shortest length "
                             "first (e.g. the last run's misses); the seeds and the rest of "
                             "the order are unchanged")
    parser.add_argument("--resume", action="store_true",
                        help="with --jsonl: skip the logs (seed and length) the file already "
                             "holds, and put them in the tables")
    parser.add_argument("--by-length", action="store_true",
                        help="run the lengths one after another, shortest first (each "
                             "length's table completes before the next starts), instead of "
                             "round by round over them")
    parser.add_argument("--tables-from", default=None,
                        help="print the tables of outcomes saved by --jsonl instead of "
                             "running (with --vehicles for the effect x vehicle table)")
    parser.add_argument("--lengths", default="60,120,300",
                        help="comma-separated log lengths [s] of --kinds")
    args = parser.parse_args(argv)
    # every input checked before any long work starts
    soil_kinds = args.soil_kinds.split(",")
    unknown = sorted(set(soil_kinds) - set(KINDS))
    if unknown:
        parser.error(f"--soil-kinds: unknown kind(s) {unknown}; use {', '.join(KINDS)}")
    effects = args.effects.split(",")
    unknown = sorted(set(effects) - set(GENERATED))
    if unknown:
        parser.error(f"--effects: cannot hide {unknown}; the generator hides {GENERATED}")
    vehicles = args.vehicles.split(",") if args.vehicles else [None]
    unknown = sorted(set(vehicles) - {None, *HIDDEN_ON["none"]})
    if unknown:
        parser.error(f"--vehicles: unknown {unknown}; use {', '.join(HIDDEN_ON['none'])}")
    for v in vehicles:
        if v is not None and not any(v in HIDDEN_ON[e] for e in effects):
            parser.error(f"--effects {args.effects}: none is hidden on {v} "
                         f"(see slipenv.diagnose.synth.KINDS)")
    if args.tables_from:
        saved = [json.loads(line) for line in Path(args.tables_from).read_text().splitlines()
                 if line.strip()]
        found = sorted({r["duration"] for r in saved})
        print_tables({d: [r for r in saved if r["duration"] == d] for d in found},
                     vehicles if args.vehicles else None)
        return 0
    if args.kinds > 0:
        lengths = [float(v) for v in args.lengths.split(",")]
        print(kinds_table(args.kinds, lengths, args.jobs), flush=True)
    if args.soil > 0:
        print(soil_table(args.soil, args.jobs, soil_kinds), flush=True)
    if args.kinematic > 0:
        print(kinematic_table(args.kinematic, args.duration, args.jobs), flush=True)
    if args.n <= 0:
        return 0
    durations = ([float(v) for v in args.durations.split(",")] if args.durations
                 else [args.duration])
    base = args.seed if args.seed is not None else int.from_bytes(os.urandom(3), "little")
    rng = np.random.default_rng(base)
    draws_of = []
    for v in vehicles:
        # every effect hidden on the vehicle equally often (clean logs included), random order
        mine = [e for e in effects if v is None or v in HIDDEN_ON[e]]
        draws = [mine[i % len(mine)] for i in range(args.n)]
        rng.shuffle(draws)
        draws_of.append((v, draws))
    print(f"base seed {base}: {args.n} logs of {', '.join(f'{d:g}' for d in durations)} s "
          f"per vehicle {vehicles}, effects {effects}", flush=True)
    jobs = []
    for duration in durations:  # the same seeds at every length
        mine = []
        for v, draws in draws_of:
            mine += [(base * 1000 + len(mine) + i, e, duration, v) for i, e in enumerate(draws)]
        jobs += mine
    # run order (not seeds): clean logs first, then round by round over lengths and vehicles,
    # so that a run stopped early has covered every cell alike
    rank = {(j[0], j[2]): (j[1] != "none", (j[0] - base * 1000) % max(args.n, 1),
                           durations.index(j[2])) for j in jobs}
    first = [int(v) for v in args.first.split(",") if v]
    jobs.sort(key=lambda j: (durations.index(j[2]) if args.by_length else 0,
                             j[0] not in first,
                             (durations.index(j[2]), first.index(j[0])) if j[0] in first
                             else rank[(j[0], j[2])]))
    by_length: dict[float, list[dict]] = {d: [] for d in durations}
    if args.resume and args.jsonl and Path(args.jsonl).exists():
        done = {}
        for line in Path(args.jsonl).read_text().splitlines():
            if line.strip():
                r = json.loads(line)
                done[(r["seed"], r["duration"])] = r
        for j in jobs:
            if (j[0], j[2]) in done:
                by_length[j[2]].append(done[(j[0], j[2])])
        jobs = [j for j in jobs if (j[0], j[2]) not in done]
        print(f"resumed: {sum(map(len, by_length.values()))} logs from {args.jsonl}, "
              f"{len(jobs)} to run", flush=True)
    start = time.perf_counter()
    # one pool for every length: a worker's cached calibration runs serve all its logs
    with ProcessPoolExecutor(max_workers=args.jobs) as pool:
        # printed as they finish (a 5-minute log does not hold back the short ones)
        for done in as_completed([pool.submit(run_one, j) for j in jobs]):
            r = done.result()
            flag = ("ok " if r["cause"] == r["effect"] else
                    "CONF" if r["confounded"] else "MISS")
            zs = " ".join(f"{k}={v:+.1f}" for k, v in r["z"].items())
            print(f"{flag} {r['duration']:g} s seed {r['seed']} {r['vehicle']:10s} "
                  f"{r['effect']:15s} -> {r['cause']}"
                  f"{'+' + '+'.join(r['also']) if r['also'] else ''}  "
                  f"[{r['diag_s']:.1f} s]  {zs}", flush=True)
            by_length[r["duration"]].append(r)
            if args.jsonl:
                with open(args.jsonl, "a") as out:
                    out.write(json.dumps(r) + "\n")
    print_tables(by_length, vehicles if args.vehicles else None)
    print(f"\nwall time {time.perf_counter() - start:.0f} s", flush=True)
    return 0


def print_tables(by_length: dict[float, list[dict]], vehicles: list[str] | None) -> None:
    """The hit-rate table of every length, the effect x vehicle tables with ``vehicles``, and
    the vehicle x length table when there are several lengths."""
    for duration, results in by_length.items():
        results.sort(key=lambda r: r["seed"])
        print(f"\n{duration:g} s logs:")
        print(table(results))
        if vehicles:
            print()
            print(vehicle_table(results, vehicles))
    if len(by_length) > 1 and vehicles:
        print()
        print(length_table(by_length, vehicles))


if __name__ == "__main__":
    raise SystemExit(main())
