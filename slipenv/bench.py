"""Throughput benchmark: env steps per second next to bare ``stepSimulation`` (DESIGN §6).

For each env id, in one process and interleaved (env chunk, bare chunk, env chunk, ...) so
that machine noise hits both alike: ``env_steps_per_s`` is the full ``env.step`` (force law at
every substep, sensors, estimator, observation, reward); ``bare_substeps_per_s`` is plain
``p.stepSimulation`` of the very same PyBullet world (same bodies, contacts and solver
settings, no force injection and no Python on top). The ratio

    ratio = env_steps_per_s * substeps_per_step / bare_substeps_per_s

is the share of time spent in physics: 1.0 means slipenv adds nothing on top of PyBullet.
Medians over the repetitions are reported.

Each env chunk is one :func:`slipenv.rollout.rollout` from ``reset(seed=0)`` with a constant
action: the first ``WARMUP_STEPS`` steps (caches, first contacts) are not timed; a
:class:`StepTimer` recorder saves the world's state when timing starts and times the rest; the
bare chunk then restores that state and steps it as often as the env chunk did substeps.
Warnings and log records emitted while benchmarking (an estimator skipping measurements, ...)
are collected and counted, not printed in the middle of the table. ``pybullet_path`` says how
each env's force injection read PyBullet in the timed rollouts (:func:`pybullet_path`):
``"native"`` (Bullet's C API, `slipenv.sim.bullet_native`), ``"public API"`` (pybullet's Python
functions) or ``"mixed"`` (a check of the native reader failed in some rollouts).

Three more figures per env:

* ``coulomb_env_steps_per_s``: what a user would run without slipenv on the very same world
  (same bodies, restored to the same state): slipenv's force injection off, PyBullet's own
  Coulomb friction on at every contact (lateral friction ``COULOMB_MU_PER_BODY`` on every link,
  which PyBullet multiplies per contact pair: μ = 0.81), and per control step what a minimal
  PyBullet env does: one motor command for the wheel joints, the substeps, and the base pose,
  base velocity and joint states read back. Interleaved with the env and bare chunks.
  ``vs_coulomb`` = env steps/s over that rate (> 1: slipenv's full step is faster).
* ``breakdown_us_per_step``: one more rollout with timers wrapped around the bound methods that
  make up a step (instance attributes, removed afterwards): ``step_simulation`` (PyBullet's
  ``stepSimulation``), ``force_injection`` (the simulator's injector: ``apply`` at every
  substep and ``sample_soil`` once per step), ``truth`` (the simulator's state queries),
  ``sensors``, ``estimator``, ``observation_reward`` (observation, path projection and info),
  ``rest`` (the step's own Python: action check, motor commands, reward terms, rollout loop)
  and ``total``, in microseconds per control step; times are exclusive (a timed call inside
  another, the path projection inside the observation, is counted once). The timers add
  ~0.3 µs per call, so this rollout is not the one the ratio is taken from.
* ``injection_parts_us_per_substep``: from the same rollout, the compiled wheel loop's own
  timing of its substeps (``WheelLoop.timings``), in microseconds per substep: ``read`` (the
  contact, link and joint queries, natively or through the public API as ``pybullet_path``
  says), ``force_law`` (contact frames, slip states, force law, dampers
  and resistance) and ``apply`` (the ``applyExternalForce`` commands); None without the
  compiled loop.
* ``vec_env_steps_per_s``: total env steps/s of ``gymnasium.make_vec(id, VEC_PROCESSES,
  vectorization_mode="async")`` (one env per process, constant action, after a warm-up).
* ``track_model_vs_per_wheel`` (tracked vehicles only, :func:`track_model_cost`): the same env
  with the vehicle's track model switched, the Wong-Chiang track model
  (``track_model="wong_chiang"``, `slipenv.sim.track_soil`) against the per-road-wheel law
  (``"per_wheel"``, the compiled wheel loop), in CPU microseconds per env step, the two envs'
  steps alternating one by one in this process; ``ratio`` (track model / per-wheel) is the
  median of the repetitions' ratios. Printed as "track model / per-wheel".

And once per run, ``startup``: what a user waits for before the first step, each env in a
fresh interpreter (:func:`startup_cost`): ``import slipenv`` (median over the envs) and per env
the first ``make`` + ``reset`` + ``step``, and which compiled kernels were loaded (the wheel-soil
loop, ``slipenv.sim.compiled``; the Lindgren EKF, ``slipenv.estimators.lindgren``; the track
model, ``slipenv.terramechanics.track``). ``pip install`` builds the C kernels; numba compiles
the Lindgren EKF and the track model once, on their first use after an install or an edit of
their source, and caches them on disk: the start-up figures are taken with that cache warm (the
run compiles or loads both first, `warm_up`).
"""

from __future__ import annotations

import contextlib
import dataclasses
import json
import logging
import platform
import statistics
import subprocess
import sys
import time
import warnings
from collections import Counter
from collections.abc import Iterator
from typing import Any

import gymnasium as gym
import numpy as np

from slipenv.envs.compiled import warm_up
from slipenv.pybullet_quiet import import_pybullet
from slipenv.rollout import rollout

p: Any = import_pybullet()  # a C module: its functions are wrapped by name below

WARMUP_STEPS = 10
"""Env steps after each reset that are not timed (caches, first contacts)."""
COULOMB_MU_PER_BODY = 0.9
"""Lateral friction set on every link for the Coulomb reference (PyBullet multiplies the two
bodies' coefficients of a contact: μ = 0.81, a dry-soil/rubber value)."""
VEC_PROCESSES = 2
"""Worker processes of the vectorised-throughput figure (this machine has 2 cores)."""
BREAKDOWN_KEYS = ("step_simulation", "force_injection", "truth", "sensors", "estimator",
                  "observation_reward", "rest", "total")
BENCH_ACTION = np.array([0.5, 0.1], dtype=np.float32)
"""Constant action of the benchmark: half speed, a gentle turn."""


class StepTimer:
    """Rollout recorder timing env steps after a warm-up (see the module docstring).

    After the rollout: ``steps`` timed steps took ``elapsed_s`` seconds; ``state_id`` is the
    PyBullet state saved when timing started (the caller restores and removes it).
    """

    def __init__(self, client: int, warmup_steps: int = WARMUP_STEPS) -> None:
        self.client, self.warmup_steps = client, warmup_steps
        self.steps, self.elapsed_s = 0, 0.0
        self.state_id: int | None = None
        self._seen = 0
        self._t0 = 0.0

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        self._seen, self.steps, self.elapsed_s = 0, 0, 0.0
        if self.warmup_steps == 0:
            self._start()

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        self._seen += 1
        if self._seen <= self.warmup_steps:
            if self._seen == self.warmup_steps:
                self._start()
            return
        self.steps += 1
        self.elapsed_s = time.perf_counter() - self._t0

    def _start(self) -> None:
        self.state_id = p.saveState(physicsClientId=self.client)
        self._t0 = time.perf_counter()


def bench_env(env_id: str, steps: int = 200, repeats: int = 5, vec: bool = True) -> dict:
    """Measure one env id; see the module docstring."""
    if steps < 1 or repeats < 1:
        raise ValueError(f"steps and repeats must be >= 1, got steps={steps}, repeats={repeats}")
    env = gym.make(env_id)
    try:
        base: Any = env.unwrapped  # a slipenv env: its own attributes are read
        client, substeps = base.physics_client_id, base.substeps_per_step
        timer = StepTimer(client)
        env_rates, bare_rates, coulomb_rates, paths = [], [], [], set()
        for _ in range(repeats):
            rollout(env, lambda _obs: BENCH_ACTION, seed=0, max_steps=WARMUP_STEPS + steps,
                    recorders=[timer])
            paths.add(pybullet_path(base))
            if timer.state_id is None or timer.steps == 0:
                raise ValueError(f"{env_id}: the episode ended within the {WARMUP_STEPS} "
                                 "warm-up steps; nothing to time")
            env_rates.append(timer.steps / timer.elapsed_s)
            p.restoreState(timer.state_id, physicsClientId=client)
            n_bare = timer.steps * substeps
            t0 = time.perf_counter()
            for _ in range(n_bare):
                p.stepSimulation(physicsClientId=client)
            bare_rates.append(n_bare / (time.perf_counter() - t0))
            p.restoreState(timer.state_id, physicsClientId=client)
            coulomb_rates.append(coulomb_steps_per_s(client, timer.steps, substeps))
            p.removeState(timer.state_id, physicsClientId=client)
            timer.state_id = None
        env_rate = statistics.median(env_rates)
        bare_rate = statistics.median(bare_rates)
        coulomb_rate = statistics.median(coulomb_rates)
        result = {
            "env_steps_per_s": round(env_rate, 2),
            "substeps_per_step": substeps,
            "bare_substeps_per_s": round(bare_rate, 1),
            "ratio": round(env_rate * substeps / bare_rate, 3),
            "vehicle": base.vehicle.name,
            "wheels": len(base.vehicle.wheels),
            "realtime_factor": round(env_rate * base.control_dt_s, 2),
            "coulomb_env_steps_per_s": round(coulomb_rate, 2),
            "vs_coulomb": round(env_rate / coulomb_rate, 3),
        }
        result["breakdown_us_per_step"], parts = step_breakdown_and_parts(env, steps)
        result["injection_parts_us_per_substep"] = parts
        result["pybullet_path"] = paths.pop() if len(paths) == 1 else "mixed"
        tracked = base.vehicle.track_length_m is not None
    finally:
        env.close()
    if tracked:
        result["track_model_vs_per_wheel"] = track_model_cost(env_id, steps, repeats)
    if vec:
        result["vec_processes"] = VEC_PROCESSES
        result["vec_env_steps_per_s"] = round(vec_steps_per_s(env_id, VEC_PROCESSES, steps), 1)
    return result


def track_model_cost(env_id: str, steps: int = 200, repeats: int = 5) -> dict:
    """µs per env step of ``env_id`` with its tracked vehicle on the Wong-Chiang track model
    and on the per-road-wheel law (module docstring).

    Both envs run side by side from ``reset(seed=0)`` with the bench action, their steps
    alternating one by one after ``WARMUP_STEPS`` untimed steps each; an episode that ends is
    reset untimed and goes on. Each step is timed in CPU time of this thread
    (``time.thread_time``: PyBullet's DIRECT client steps in the caller's thread), so other
    processes sharing the machine do not enter the ratio.

    Returns
    -------
    dict
        ``{"per_wheel_us_per_step", "track_model_us_per_step", "ratio"}``, medians over the
        repetitions; ratio = track model / per-wheel, the median of the repetitions' ratios.
    """
    if steps < 1 or repeats < 1:
        raise ValueError(f"steps and repeats must be >= 1, got steps={steps}, repeats={repeats}")
    probe = gym.make(env_id)
    spec = probe.unwrapped.vehicle  # type: ignore[attr-defined]
    probe.close()
    models = ("per_wheel", "wong_chiang")
    envs = [gym.make(env_id, vehicle=dataclasses.replace(spec, track_model=m)) for m in models]
    clock = time.thread_time
    try:
        us: list[list[float]] = [[], []]
        for _ in range(repeats):
            elapsed = [0.0, 0.0]
            for env in envs:
                env.reset(seed=0)
            for i in range(WARMUP_STEPS + steps):
                for k, env in enumerate(envs):
                    t0 = clock()
                    _, _, terminated, truncated, _ = env.step(BENCH_ACTION)
                    if i >= WARMUP_STEPS:
                        elapsed[k] += clock() - t0
                    if terminated or truncated:
                        env.reset(seed=0)
            for k in range(2):
                us[k].append(1e6 * elapsed[k] / steps)
    finally:
        for env in envs:
            env.close()
    ratios = [t / w for w, t in zip(us[0], us[1], strict=True)]
    return {"per_wheel_us_per_step": round(statistics.median(us[0]), 1),
            "track_model_us_per_step": round(statistics.median(us[1]), 1),
            "ratio": round(statistics.median(ratios), 3)}


# -- PyBullet's own Coulomb friction on the same world ----------------------------------------
def _links(client: int) -> list[tuple[int, int]]:
    """(body, link) of every link in the world, base links as -1."""
    out = []
    for i in range(p.getNumBodies(physicsClientId=client)):
        body = p.getBodyUniqueId(i, physicsClientId=client)
        out += [(body, link) for link in range(-1, p.getNumJoints(body, physicsClientId=client))]
    return out


def coulomb_steps_per_s(client: int, steps: int, substeps: int) -> float:
    """Control steps/s of a plain-PyBullet env on this world (module docstring): injection off,
    Coulomb friction on, a motor command, ``substeps`` substeps and the usual reads per step.

    The world's friction coefficients are restored afterwards; its state is not (the caller
    restores a saved state).
    """
    links = _links(client)
    saved = [p.getDynamicsInfo(b, link, physicsClientId=client)[1] for b, link in links]
    bodies = sorted({b for b, _ in links},
                    key=lambda b: p.getNumJoints(b, physicsClientId=client))
    vehicle = bodies[-1]  # the body with the most joints
    joints = [j for j in range(p.getNumJoints(vehicle, physicsClientId=client))
              if p.getJointInfo(vehicle, j, physicsClientId=client)[2] == p.JOINT_REVOLUTE]
    targets = [s[1] for s in p.getJointStates(vehicle, joints, physicsClientId=client)]
    forces = [max(p.getJointInfo(vehicle, j, physicsClientId=client)[10], 1.0) for j in joints]
    try:
        for b, link in links:
            p.changeDynamics(b, link, lateralFriction=COULOMB_MU_PER_BODY,
                             physicsClientId=client)
        t0 = time.perf_counter()
        for _ in range(steps):
            p.setJointMotorControlArray(vehicle, joints, p.VELOCITY_CONTROL,
                                        targetVelocities=targets, forces=forces,
                                        physicsClientId=client)
            for _ in range(substeps):
                p.stepSimulation(physicsClientId=client)
            p.getBasePositionAndOrientation(vehicle, physicsClientId=client)
            p.getBaseVelocity(vehicle, physicsClientId=client)
            p.getJointStates(vehicle, joints, physicsClientId=client)
        elapsed = time.perf_counter() - t0
    finally:
        for (b, link), mu in zip(links, saved, strict=True):
            p.changeDynamics(b, link, lateralFriction=mu, physicsClientId=client)
    return steps / elapsed


# -- where a step's time goes -------------------------------------------------------------------
class _Timers:
    """Accumulated seconds per component, and wrappers that add to them.

    Times are exclusive: a timed call made inside another (the path projection inside
    ``_observe``) counts for its own key only, and the outer call gets its time minus the inner
    one, so no time is counted twice and ``rest`` (the remainder) is not understated.
    """

    def __init__(self) -> None:
        self.seconds = dict.fromkeys(BREAKDOWN_KEYS, 0.0)
        self._inner: list[float] = []  # per open timed call: time spent in timed calls inside

    def wrap(self, fn, key: str):
        seconds, clock, inner = self.seconds, time.perf_counter, self._inner

        def timed(*args, **kwargs):
            inner.append(0.0)
            t0 = clock()
            try:
                return fn(*args, **kwargs)
            finally:
                elapsed = clock() - t0
                seconds[key] += elapsed - inner.pop()
                if inner:
                    inner[-1] += elapsed

        return timed


_CLASS_METHOD = object()  # marks an attribute the instance did not hold itself


def pybullet_path(env: gym.Env) -> str:
    """How the env's force injection reads PyBullet now: ``"native"`` (Bullet's C API,
    `slipenv.sim.bullet_native`) or ``"public API"`` (pybullet's Python functions: forced by
    ``SLIPENV_PYBULLET_API=1``, an unlisted pybullet, a failed check, or an injector without
    the native reader)."""
    injector = getattr(_internal(env, "_sim"), "injector", None)
    return "native" if getattr(injector, "native_queries", False) else "public API"


def _internal(obj, name: str):
    """An attribute the benchmark instruments although it is not public API (the env's
    simulator, sensors and observation): read by name so the layering test's rule against
    reading another object's internals stays meaningful everywhere else; None if absent."""
    return getattr(obj, name, None)


class _BreakdownRecorder:
    """Wraps the step's components with timers after every reset (the simulator rebuilds its
    injector and the env its estimator there), and starts counting after the warm-up."""

    def __init__(self, timers: _Timers, warmup_steps: int = WARMUP_STEPS) -> None:
        self.timers, self.warmup_steps = timers, warmup_steps
        self.steps, self._seen, self._t0, self.elapsed_s = 0, 0, 0.0, 0.0
        self.wrapped: list[tuple[object, str, object]] = []
        self.loops: list = []  # the compiled wheel loops timed since the warm-up ended
        self._injector = None

    def instrument(self, obj, name: str, key: str) -> None:
        if obj is None or not hasattr(obj, name):
            return
        own = vars(obj).get(name, _CLASS_METHOD)  # e.g. the injector's compiled `apply`
        setattr(obj, name, self.timers.wrap(getattr(obj, name), key))
        self.wrapped.append((obj, name, own))

    def unwrap(self) -> None:
        for obj, name, own in self.wrapped:
            if own is _CLASS_METHOD:
                with contextlib.suppress(AttributeError):
                    delattr(obj, name)  # the instance attribute hid the class's method
            else:
                setattr(obj, name, own)
        self.wrapped.clear()
        for loop in self.loops:
            loop.timing = False

    def time_loop_parts(self, injector) -> None:
        """Have the injector's compiled loop time its substeps' parts (`injection_parts`)."""
        loop = getattr(injector, "_loop", None)
        if loop is not None:
            loop.timing = True
            self.loops.append(loop)

    def injection_parts(self) -> dict[str, float] | None:
        """µs per substep spent reading PyBullet, in the force law and applying the forces,
        summed over the loops timed since the warm-up (None without the compiled loop)."""
        if not self.loops:
            return None
        parts = [loop.timings for loop in self.loops]
        n = sum(t["substeps"] for t in parts)
        if n == 0:
            return None
        return {key: round(1e6 * sum(t[f"{key}_s"] for t in parts) / n, 2)
                for key in ("read", "force_law", "apply")}

    def on_reset(self, env: gym.Env, obs: np.ndarray, info: dict) -> None:
        self.unwrap()
        base: Any = env.unwrapped
        sim = _internal(base, "_sim")
        injector = getattr(sim, "injector", None)
        self.instrument(injector, "apply", "force_injection")
        self.instrument(injector, "sample_soil", "force_injection")
        self.instrument(sim, "truth", "truth")
        self.instrument(_internal(base, "_sensors"), "measure", "sensors")
        self.instrument(base.estimator, "update", "estimator")
        self.instrument(base, "_observe", "observation_reward")
        self.instrument(base, "_info", "observation_reward")
        self.instrument(base.path, "project", "observation_reward")
        self._injector = injector
        self._seen, self.steps = 0, 0

    def on_step(self, env: gym.Env, action: np.ndarray, obs: np.ndarray, reward: float,
                terminated: bool, truncated: bool, info: dict) -> None:
        self._seen += 1
        if self._seen == self.warmup_steps:
            for key in self.timers.seconds:
                self.timers.seconds[key] = 0.0
            for loop in self.loops:
                loop.timing = False
            self.loops = []
            self.time_loop_parts(self._injector)
            self._t0 = time.perf_counter()
        elif self._seen > self.warmup_steps:
            self.steps += 1
            self.elapsed_s = time.perf_counter() - self._t0


def step_breakdown(env: gym.Env, steps: int) -> dict[str, float]:
    """Microseconds per control step by component (module docstring), one rollout."""
    return step_breakdown_and_parts(env, steps)[0]


def step_breakdown_and_parts(env: gym.Env, steps: int
                             ) -> tuple[dict[str, float], dict[str, float] | None]:
    """:func:`step_breakdown`, and the force injection's parts per substep from the same
    rollout (``injection_parts_us_per_substep`` in the module docstring; None without the
    compiled wheel loop)."""
    timers = _Timers()
    recorder = _BreakdownRecorder(timers)
    step_simulation = p.stepSimulation
    p.stepSimulation = timers.wrap(step_simulation, "step_simulation")
    try:
        rollout(env, lambda _obs: BENCH_ACTION, seed=0, max_steps=WARMUP_STEPS + steps,
                recorders=[recorder])
    finally:
        p.stepSimulation = step_simulation
        recorder.unwrap()
    n = max(recorder.steps, 1)
    sec = timers.seconds
    # the timers also tick during reset's settling substeps and the warm-up: not counted, the
    # counters are zeroed when the timed window opens after the warm-up
    sec["total"] = recorder.elapsed_s
    sec["rest"] = sec["total"] - sum(v for k, v in sec.items() if k not in ("rest", "total"))
    return {k: round(1e6 * sec[k] / n, 1) for k in BREAKDOWN_KEYS}, recorder.injection_parts()


# -- vectorised throughput ------------------------------------------------------------------------
def vec_steps_per_s(env_id: str, num_envs: int = VEC_PROCESSES, steps: int = 200,
                    mode: str = "async") -> float:
    """Total env steps/s of ``gymnasium.make_vec(env_id, num_envs, vectorization_mode=mode)``:
    ``steps`` batched steps with a constant action, timed after ``WARMUP_STEPS`` untimed ones
    (process start-up and the first reset are not counted); episodes auto-reset."""
    envs = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode=mode)
    try:
        envs.reset(seed=0)
        return batched_steps_per_s(envs, num_envs, steps)
    finally:
        envs.close()


def batched_steps_per_s(envs, num_envs: int, steps: int) -> float:
    """Total env steps/s of an already reset vector env (gymnasium's or SB3's): ``steps`` batched
    steps of the bench action, timed after ``WARMUP_STEPS`` untimed ones."""
    actions = np.tile(BENCH_ACTION, (num_envs, 1))
    for _ in range(WARMUP_STEPS):
        envs.step(actions)
    t0 = time.perf_counter()
    for _ in range(steps):
        envs.step(actions)
    return num_envs * steps / (time.perf_counter() - t0)


class _Collect(logging.Handler):
    def __init__(self, sink: Counter) -> None:
        super().__init__(level=logging.WARNING)
        self.sink = sink

    def emit(self, record: logging.LogRecord) -> None:
        self.sink[f"{record.name}: {record.getMessage()}"] += 1


@contextlib.contextmanager
def collected_warnings() -> Iterator[Counter]:
    """Collect Python warnings and WARNING+ log records instead of printing them.

    Yields a :class:`collections.Counter` of ``"source: message"`` -> count, filled when the
    block exits (log records as they arrive).
    """
    sink: Counter = Counter()
    handler = _Collect(sink)
    root = logging.getLogger()
    saved = logging.lastResort
    root.addHandler(handler)
    logging.lastResort = None  # records must not reach stderr through the last-resort handler
    try:
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            yield sink
        for w in caught:
            sink[f"{w.category.__name__}: {w.message}"] += 1
    finally:
        root.removeHandler(handler)
        logging.lastResort = saved


_STARTUP_SCRIPT = """
import json, sys, time
t0 = time.perf_counter()
import slipenv
t1 = time.perf_counter()
import gymnasium as gym
env = gym.make(sys.argv[1])
env.reset(seed=0)
env.step(env.action_space.sample() * 0)
t2 = time.perf_counter()
env.close()
from slipenv.estimators.lindgren.ekf import compiled_available
from slipenv.sim.compiled import wheel_loop_module
print(json.dumps({"import_s": t1 - t0, "first_make_s": t2 - t1, "compiled": {
    "wheel_loop": wheel_loop_module() is not None, "lindgren_ekf": compiled_available(),
    "track_model": compiled_available()}}))
"""


def startup_cost(env_ids: list[str]) -> dict:
    """``import slipenv`` and each env's first ``make`` + ``reset`` + ``step``, each env in a
    fresh interpreter [s], and which compiled kernels were loaded (see the module docstring).

    Returns
    -------
    dict
        ``{"import_s": median, "first_make_s": {id: s}, "compiled": {kernel: bool}}``.
    """
    runs = {}
    for env_id in env_ids:
        out = subprocess.run([sys.executable, "-c", _STARTUP_SCRIPT, env_id], check=True,
                             capture_output=True, text=True)
        runs[env_id] = json.loads(out.stdout.strip().splitlines()[-1])
    return {"import_s": round(statistics.median(r["import_s"] for r in runs.values()), 3),
            "first_make_s": {k: round(r["first_make_s"], 3) for k, r in runs.items()},
            "compiled": next(iter(runs.values()))["compiled"] if runs else {}}


def run_bench(env_ids: list[str], steps: int = 200, repeats: int = 5,
              progress: bool = True, vec: bool = True) -> dict:
    """Benchmark every id.

    Returns
    -------
    dict
        ``{"envs": {id: {...}}, "machine": {...}, "settings": {...},
        "warnings": {"count": n, "messages": {message: count}}}``.
    """
    # Compile (or load) the Lindgren EKF and the track model here, before any timing and before
    # the fresh interpreters and vector-env workers start, so none of them compiles them.
    warm_up()
    envs = {}
    iterator = env_ids
    if progress:
        from tqdm import tqdm

        iterator = tqdm(env_ids, desc="bench", unit="env")
    with collected_warnings() as caught:
        for env_id in iterator:
            envs[env_id] = bench_env(env_id, steps=steps, repeats=repeats, vec=vec)
    return {
        "envs": envs,
        "machine": {"python": platform.python_version(), "processor": platform.machine(),
                    "pybullet_api": p.getAPIVersion()},
        "settings": {"steps": steps, "repeats": repeats, "warmup_steps": WARMUP_STEPS,
                     "coulomb_mu": round(COULOMB_MU_PER_BODY**2, 4),
                     "vec_processes": VEC_PROCESSES if vec else 0},
        "warnings": {"count": sum(caught.values()), "messages": dict(caught.most_common())},
        "startup": startup_cost(env_ids),
    }


def format_bench(result: dict) -> str:
    """The benchmark's tables (rates, then the breakdown per control step), and one line
    counting the warnings collected."""
    head = (f"{'env id':<32} {'env steps/s':>12} {'substeps':>9} {'bare substeps/s':>16} "
            f"{'ratio':>6} {'x realtime':>10} {'coulomb steps/s':>16} {'vs coulomb':>10} "
            f"{'vec steps/s':>12}  PyBullet read")
    lines = [head, "-" * len(head)]
    for env_id, r in result["envs"].items():
        coulomb = r.get("coulomb_env_steps_per_s")
        vec = r.get("vec_env_steps_per_s")
        lines.append(
            f"{env_id:<32} {r['env_steps_per_s']:>12.1f} {r['substeps_per_step']:>9d} "
            f"{r['bare_substeps_per_s']:>16.0f} {r['ratio']:>6.2f} {r['realtime_factor']:>10.1f}"
            + (f" {coulomb:>16.1f} {r['vs_coulomb']:>10.2f}" if coulomb is not None
               else f" {'-':>16} {'-':>10}")
            + (f" {vec:>12.1f}" if vec is not None else f" {'-':>12}")
            + f"  {r.get('pybullet_path', '-')}"
        )
    rows = [(env_id, r["breakdown_us_per_step"]) for env_id, r in result["envs"].items()
            if r.get("breakdown_us_per_step")]
    if rows:
        names = {"step_simulation": "stepSim", "force_injection": "injection",
                 "truth": "truth", "sensors": "sensors", "estimator": "estimator",
                 "observation_reward": "obs+reward", "rest": "rest", "total": "total"}
        head2 = f"{'us per control step':<32}" + "".join(f" {names[k]:>10}"
                                                        for k in BREAKDOWN_KEYS)
        lines += ["", head2, "-" * len(head2)]
        for env_id, b in rows:
            lines.append(f"{env_id:<32}" + "".join(f" {b[k]:>10.1f}" for k in BREAKDOWN_KEYS))
    parts = [(env_id, r["injection_parts_us_per_substep"])
             for env_id, r in result["envs"].items() if r.get("injection_parts_us_per_substep")]
    if parts:
        head3 = (f"{'force injection, us per substep':<32} {'read':>10} {'force law':>10} "
                 f"{'apply':>10}")
        lines += ["", head3, "-" * len(head3)]
        for env_id, q in parts:
            lines.append(f"{env_id:<32} {q['read']:>10.2f} {q['force_law']:>10.2f} "
                         f"{q['apply']:>10.2f}")
    tracks = [(env_id, r["track_model_vs_per_wheel"]) for env_id, r in result["envs"].items()
              if r.get("track_model_vs_per_wheel")]
    if tracks:
        lines.append("")
        for env_id, t in tracks:
            lines.append(f"track model / per-wheel, {env_id}: {t['ratio']:.2f} "
                         f"({t['track_model_us_per_step']:.0f} against "
                         f"{t['per_wheel_us_per_step']:.0f} CPU us per env step, "
                         "steps interleaved)")
    start = result.get("startup")
    if start:
        slowest = max(start["first_make_s"].items(), key=lambda kv: kv[1])
        kernels = ", ".join(f"{k} {'compiled' if v else 'Python'}"
                            for k, v in start["compiled"].items())
        lines += ["", f"startup: import slipenv {start['import_s']:.2f} s; first make + reset + "
                  f"step {min(start['first_make_s'].values()):.2f}-{slowest[1]:.2f} s "
                  f"(slowest {slowest[0]}); {kernels}"]
    caught = result.get("warnings", {})
    if caught.get("count"):
        first = next(iter(caught["messages"]))
        lines.append(f"{caught['count']} warning(s) during the benchmark, "
                     f"{len(caught['messages'])} distinct (most frequent: {first})")
    return "\n".join(lines)
