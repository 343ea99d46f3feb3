"""Cost of each part of the per-substep force injection.

For each env id: the env is reset (seed 0) and driven ``--warmup`` steps with a constant action
so that the wheels are loaded; then, interleaved over ``--repeats`` rounds (so that load from
other processes hits all alike), in microseconds per physics substep:

* ``apply_total``: ``WheelSoilInjector.apply`` timed in situ over ``--steps`` env steps (the
  instance's bound method wrapped, as ``slipenv bench`` does);
* ``step_simulation``: PyBullet's own substep in the same loop, for scale;
* the PyBullet queries of one substep repeated on the frozen world, called as ``apply`` calls
  them (positional arguments): ``get_contact_points`` (one batched call, wheel body vs
  ground), ``get_link_states_vel`` (all wheel links, with velocities), ``get_joint_states``
  (the spin joints);
* ``apply_external_force``: one call's cost times the calls per substep actually made (counted
  in the in-situ loop);
* ``compute``: apply_total minus the queries and the force calls: the frame, slip and force
  laws (``slipenv/terramechanics/_laws.h``, run by the loop ``slipenv/sim/_wheel_loop.c``);
* ``apply_native`` and ``apply_python_api``: ``apply`` in situ with the loop reading PyBullet
  through Bullet's C API (``slipenv/sim/bullet_native.h``) and through pybullet's Python
  functions (``SLIPENV_PYBULLET_API=1``), alternated in each round (NaN without native
  access). The query and force columns above are the Python API's costs, which the native
  path avoids.

and, for deciding what to cut, alternatives (``alt_*``, not part of the sum): link states
without velocities (one call), the three queries with keyword arguments (their sum, as the
code once called them), one ``applyExternalForce`` with keyword arguments and one
``applyExternalTorque`` (what a force moved to another point would need for its moment).
Medians over rounds. Run from the repository root::

    python benchmarks/injection_cost.py [ENV_ID ...] [--steps 100] [--repeats 5] [--json PATH]
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
from slipenv.envs.registration import PRESETS
from slipenv.pybullet_quiet import import_pybullet

p = import_pybullet()

PARTS = ("get_contact_points", "get_link_states_vel", "get_joint_states", "apply_external_force")


def _per_call_us(fn: Callable[[], object], calls: int) -> float:
    """Mean cost of one ``fn()`` [µs] over ``calls`` calls."""
    t0 = time.perf_counter()
    for _ in range(calls):
        fn()
    return (time.perf_counter() - t0) / calls * 1e6


def _forces_applied(injector) -> int:
    """``applyExternalForce`` calls the last substep made (the loop's rule: a loaded driven
    wheel applies its shear, and every loaded wheel its resistance unless it is zero)."""
    state = injector.contact_state()
    return sum(int(load > 0.0) * (int(driven) + int(res != 0.0)) for load, driven, res in
               zip(state.load_n, injector.driven, state.resistance_n, strict=True))


def _in_situ(env: gym.Env, action: np.ndarray, steps: int) -> tuple[float, float, float]:
    """(apply µs per substep, stepSimulation µs per substep, applyExternalForce calls per
    substep) over ``steps`` env steps."""
    sim = env.unwrapped._sim
    injector = sim.injector
    spent = {"apply": 0.0, "step": 0.0, "calls": 0}
    had_own = "apply" in vars(injector)  # the loop's apply is bound on the instance
    inner_apply = injector.apply
    inner_step = p.stepSimulation

    def timed_apply() -> None:
        t0 = time.perf_counter()
        inner_apply()
        spent["apply"] += time.perf_counter() - t0
        spent["calls"] += _forces_applied(injector)

    def timed_step(*args, **kwargs):
        t0 = time.perf_counter()
        out = inner_step(*args, **kwargs)
        spent["step"] += time.perf_counter() - t0
        return out

    injector.apply = timed_apply
    p.stepSimulation = timed_step
    try:
        for _ in range(steps):
            env.step(action)
    finally:
        p.stepSimulation = inner_step
        if had_own:
            injector.apply = inner_apply
        else:
            del injector.apply
    substeps = steps * sim.substeps  # (the force count runs outside the timed span)
    return (spent["apply"] / substeps * 1e6, spent["step"] / substeps * 1e6,
            spent["calls"] / substeps)


def _queries(env: gym.Env, calls: int) -> dict[str, float]:
    """One call of each PyBullet query of a substep [µs], on the current (frozen) world."""
    sim = env.unwrapped._sim
    inj = sim.injector
    cid, bid, gid = sim.client, inj.body_id, inj.ground_id
    links, joints = list(inj.links), list(inj.spin_joints)
    link, world = links[0], p.WORLD_FRAME
    force, pos = (0.0, 0.0, 0.0), (0.0, 0.0, 0.0)
    return {
        "get_contact_points": _per_call_us(
            lambda: p.getContactPoints(bid, gid, -2, -2, cid), calls),
        "get_link_states_vel": _per_call_us(
            lambda: p.getLinkStates(bid, links, 1, 0, cid), calls),
        "get_joint_states": _per_call_us(lambda: p.getJointStates(bid, joints, cid), calls),
        "apply_external_force_1": _per_call_us(
            lambda: p.applyExternalForce(bid, link, force, pos, world, cid), calls),
        "alt_get_link_states_novel": _per_call_us(
            lambda: p.getLinkStates(bid, links, 0, 0, cid), calls),
        "alt_keyword_queries": (
            _per_call_us(lambda: p.getContactPoints(bodyA=bid, bodyB=gid, physicsClientId=cid),
                         calls)
            + _per_call_us(lambda: p.getLinkStates(bid, links, computeLinkVelocity=1,
                                                   physicsClientId=cid), calls)
            + _per_call_us(lambda: p.getJointStates(bid, joints, physicsClientId=cid), calls)),
        "alt_apply_external_force_keyword": _per_call_us(
            lambda: p.applyExternalForce(bid, link, force, pos, world, physicsClientId=cid),
            calls),
        "alt_apply_external_torque": _per_call_us(
            lambda: p.applyExternalTorque(bid, link, force, world, cid), calls),
    }


def measure(env_id: str, steps: int, repeats: int, warmup: int = 20,
            calls: int = 2000) -> dict[str, float]:
    """Median per-part costs [µs per substep] of ``env_id`` (see the module docstring)."""
    env = gym.make(env_id)
    try:
        env.reset(seed=0)
        action = np.zeros(env.action_space.shape, dtype=env.action_space.dtype)
        action.flat[0] = 0.5 * float(env.action_space.high.flat[0])
        for _ in range(warmup):
            env.step(action)
        loop = getattr(env.unwrapped._sim.injector, "_loop", None)
        native = loop is not None and bool(loop.native)
        rounds: list[dict[str, float]] = []
        for _ in range(repeats):
            by_path = {"apply_native": float("nan"), "apply_python_api": float("nan")}
            if native:
                for key, on in (("apply_python_api", False), ("apply_native", True)):
                    loop.native = on
                    by_path[key] = _in_situ(env, action, steps)[0]
            apply_us, step_us, n_force = _in_situ(env, action, steps)
            q = _queries(env, calls)
            row = {"apply_total": apply_us, "step_simulation": step_us, **by_path,
                   "force_calls_per_substep": n_force,
                   "apply_external_force": q.pop("apply_external_force_1") * n_force, **q}
            # With native access `apply` makes none of the Python calls timed above: the
            # compute share is then what the Python-API path spends beyond them.
            total = by_path["apply_python_api"] if native else apply_us
            row["compute"] = total - sum(row[k] for k in PARTS)
            rounds.append(row)
        return {k: statistics.median(r[k] for r in rounds) for k in rounds[0]}
    finally:
        env.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("env_ids", nargs="*", default=sorted(PRESETS))
    parser.add_argument("--steps", type=int, default=100)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", default=None)
    args = parser.parse_args()
    cols = ("apply_total", "apply_native", "apply_python_api", *PARTS, "compute",
            "force_calls_per_substep", "step_simulation",
            "alt_get_link_states_novel", "alt_keyword_queries",
            "alt_apply_external_force_keyword", "alt_apply_external_torque")
    short = ("apply", "native", "py-api", "contacts", "links+vel", "joints", "forces", "compute",
             "n_force", "stepSim", "a:links", "a:kwqry", "a:kwforce", "a:torque")
    print(f"{'env (us per substep)':32s}" + "".join(f"{s:>10s}" for s in short))
    out = {}
    for env_id in args.env_ids:
        row = measure(env_id, args.steps, args.repeats)
        out[env_id] = row
        print(f"{env_id:32s}" + "".join(f"{row[c]:10.2f}" for c in cols), flush=True)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(out, fh, indent=2)


if __name__ == "__main__":
    main()
