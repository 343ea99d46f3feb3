"""Does one PyBullet world carrying N vehicles pay against N worlds?

N copies of slipenv's Husky (``vehicle_by_name("husky")``, built by
:func:`slipenv.vehicles.body.build_vehicle` as the env builds it) on pybullet_data's plane,
driving (velocity-controlled wheels, PyBullet's Coulomb contact with μ = 0.81), 4 m apart,
with collision filtering so that vehicles never collide with
each other (collision group 2 whose mask only admits the ground's group 1). Measured on the
same machine, interleaved and repeated (medians):

* ``one_world``: one client with N vehicles, ``stepSimulation`` once per substep;
* ``n_worlds``: N clients with one vehicle each, ``stepSimulation`` on each per substep;

both as microseconds per substep *for all N vehicles*, and ``one_world / n_worlds`` (< 1: the
batched world pays). Only the bare physics is timed: slipenv's injection, sensors and
estimator stay per vehicle in either layout, so they do not change the comparison. Contact
constraint solving is per island in Bullet, so the batched world can only save the fixed
per-call cost of a step (broadphase set-up, Python->C call, solver bookkeeping).

Run from the repository root::

    python benchmarks/batched_world.py [--n 1 2 4 8] [--substeps 600] [--repeats 5]
"""

from __future__ import annotations

import argparse
import json
import statistics
import time

import pybullet_data

from slipenv.pybullet_quiet import import_pybullet
from slipenv.vehicles.body import build_vehicle
from slipenv.vehicles.presets import vehicle_by_name

p = import_pybullet()
SPACING_M = 4.0
WHEEL_SPEED_RAD_S = 4.0


def make_world(n: int) -> int:
    """A DIRECT client with a plane and ``n`` driving Huskies that ignore each other."""
    cid = p.connect(p.DIRECT)
    p.setAdditionalSearchPath(pybullet_data.getDataPath(), physicsClientId=cid)
    p.setGravity(0, 0, -9.81, physicsClientId=cid)
    p.setTimeStep(1.0 / 240.0, physicsClientId=cid)
    plane = p.loadURDF("plane.urdf", physicsClientId=cid)
    p.setCollisionFilterGroupMask(plane, -1, 1, 0xFFFF, physicsClientId=cid)
    p.changeDynamics(plane, -1, lateralFriction=0.9, physicsClientId=cid)
    spec = vehicle_by_name("husky")
    for i in range(n):
        body = build_vehicle(spec, cid, (SPACING_M * i, 0.0, 0.4), (0.0, 0.0, 0.0, 1.0))
        husky = body.body_id
        wheels = [j for j in body.spin_joints if j is not None]
        for j in range(-1, p.getNumJoints(husky, physicsClientId=cid)):
            p.setCollisionFilterGroupMask(husky, j, 2, 1, physicsClientId=cid)
            p.changeDynamics(husky, j, lateralFriction=0.9, physicsClientId=cid)
        p.setJointMotorControlArray(husky, wheels, p.VELOCITY_CONTROL,
                                    targetVelocities=[WHEEL_SPEED_RAD_S] * len(wheels),
                                    forces=[50.0] * len(wheels), physicsClientId=cid)
    for _ in range(120):  # settle and start rolling
        p.stepSimulation(physicsClientId=cid)
    return cid


def time_substeps(clients: list[int], substeps: int) -> float:
    """Seconds per substep of stepping every client once."""
    t0 = time.perf_counter()
    for _ in range(substeps):
        for cid in clients:
            p.stepSimulation(physicsClientId=cid)
    return (time.perf_counter() - t0) / substeps


def run(ns: list[int], substeps: int = 600, repeats: int = 5) -> dict:
    out = {}
    for n in ns:
        one = [make_world(n)]
        many = [make_world(1) for _ in range(n)]
        a, b = [], []
        try:
            for _ in range(repeats):
                a.append(time_substeps(one, substeps))
                b.append(time_substeps(many, substeps))
        finally:
            for cid in one + many:
                p.disconnect(physicsClientId=cid)
        t_one, t_many = statistics.median(a), statistics.median(b)
        out[str(n)] = {"one_world_us": round(1e6 * t_one, 1),
                       "n_worlds_us": round(1e6 * t_many, 1),
                       "one_over_n": round(t_one / t_many, 3)}
    return out


def main(argv: list[str] | None = None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, nargs="+", default=[1, 2, 4, 8])
    ap.add_argument("--substeps", type=int, default=600)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--json", default=None)
    args = ap.parse_args(argv)
    r = run(args.n, args.substeps, args.repeats)
    print(f"{'N vehicles':>10} {'one world us/substep':>21} {'N worlds us/substep':>20} "
          f"{'one/N':>7}")
    for n, v in r.items():
        print(f"{n:>10} {v['one_world_us']:>21.1f} {v['n_worlds_us']:>20.1f} "
              f"{v['one_over_n']:>7.3f}")
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(r, fh, indent=2)


if __name__ == "__main__":
    main()
