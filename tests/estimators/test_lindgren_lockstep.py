"""The compiled Lindgren EKF against the plain-Python text of the same functions, in lockstep.

The filter's arithmetic is numba-compiled from the text of :mod:`.kernel`, :mod:`.models` and
:mod:`.observations`; every other test runs the compiled code. Here the same filter runs a
second time with every compiled function of those modules replaced by its ``py_func`` (the
Python it was compiled from, run by the interpreter and numpy), on one generated drive whose
frames take every branch of the frame kernel: bearings in order, bearings out of order or NaN
(the Python path that sorts them), NaN gyro and inclinometer, NaN torque, and the χ² gate.
The two runs must give the same states, covariances, estimates and innovation history to
rounding: a compiled-only behaviour (an argument packed in the wrong slot, a workspace region
shared by two temporaries, a type the compiler narrows) shows up as a difference here.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest
from numba.core.registry import CPUDispatcher

from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren import ekf as ekf_module
from slipenv.estimators.lindgren import kernel
from slipenv.estimators.lindgren import models as lm
from slipenv.estimators.lindgren import observations as lo
from slipenv.estimators.lindgren.ekf import LindgrenEKF, LindgrenNoise, OracleSoil
from slipenv.sensors.beacons import BeaconScanner
from tests.estimators.lindgren_synth import simulate, straight_and_turn, torque, truth0

GEOM = OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=285.0)
CROSS = np.array([[10.0, 0.0], [0.0, 10.0], [-10.0, 0.0], [0.0, -10.0]])
N_FRAMES = 60
# (scheme, lateral slip gain, oracle): every layout the env and the reproductions build
VARIANTS = [(1, False, False), (2, False, False), (3, False, False), (4, False, False),
            (5, False, False), (4, True, False), (5, True, False), (4, False, True)]


def drive() -> list:
    """A generated drive whose frames take every branch of the frame kernel."""
    run = simulate(GEOM, truth0(), N_FRAMES, 0.05, np.random.default_rng(11),
                   reference=straight_and_turn(), torque=torque, scanner=BeaconScanner())
    frames = list(run.frames)
    with_two = [k for k, f in enumerate(frames) if len(f.beacon_times_s) >= 2]
    with_one = [k for k, f in enumerate(frames) if len(f.beacon_times_s) == 1]
    assert with_two and with_one, "the drive needs frames with one and with several bearings"
    k = with_two[0]  # out of order: the Python path sorts them
    f = frames[k]
    frames[k] = dataclasses.replace(f, beacon_bearings_rad=f.beacon_bearings_rad[::-1].copy(),
                                    beacon_times_s=f.beacon_times_s[::-1].copy())
    k = with_one[-1]  # a NaN bearing next to a good one
    f = frames[k]
    frames[k] = dataclasses.replace(
        f, beacon_bearings_rad=np.array([f.beacon_bearings_rad[0], np.nan]),
        beacon_times_s=np.array([f.beacon_times_s[0], f.beacon_times_s[0]]))
    for k in range(7, N_FRAMES, 13):
        frames[k] = dataclasses.replace(frames[k], gyro_z_rad_s=np.nan, pitch_rad=np.nan)
    for k in range(11, N_FRAMES, 17):
        frames[k] = dataclasses.replace(frames[k], wheel_torque_nm=np.full(2, np.nan))
    return frames


def run_filter(scheme: int, lateral: bool, oracle: bool, frames: list) -> dict:
    params = LindgrenNoise(lateral_slip_sigma0=3.0 if lateral else 0.0)
    soil = OracleSoil(wheel_radius_m=(0.283, 0.287), k_s=(2500.0, 2200.0)) if oracle else None
    # one beacon far off the map's others: some bearings fail the χ² gate
    beacons = np.vstack([CROSS, [[3.0, -2.0]]])
    ekf = LindgrenEKF(GEOM, scheme, params=params, beacons_xy=beacons, oracle=soil)
    estimates = [ekf.reset(*truth0()[:3], frames[0])]
    states, covs = [ekf.x.copy()], [ekf.P.copy()]
    for f in frames[1:]:
        estimates.append(ekf.update(f))
        states.append(ekf.x)
        covs.append(ekf.P)
    ekf.predict_to(frames[-1].t_s + 0.3)
    states.append(ekf.x)
    covs.append(ekf.P)
    pose = [[e.x_m, e.y_m, e.yaw_rad, e.speed_mps, e.yaw_rate_rps, e.slip_angle_rad]
            for e in estimates]
    history = {s: [(t, y.copy(), S.copy()) for t, y, S in h] for s, h in ekf.history.items()}
    return {"x": np.array(states), "P": np.array(covs), "pose": np.array(pose),
            "cov": np.array([e.cov for e in estimates]),
            "extras": [{k: v for k, v in e.extras.items() if k != "skipped"}
                       for e in estimates],
            "skipped": estimates[-1].extras["skipped"], "history": history}


@pytest.fixture(scope="module")
def frames() -> list:
    return drive()


def as_python(monkeypatch: pytest.MonkeyPatch) -> int:
    """Replace every compiled function of the filter's modules by the Python it is compiled
    from; the functions call each other through these module globals. Returns how many."""
    n = 0
    for module in (kernel, lm, lo):
        for name, obj in list(vars(module).items()):
            if isinstance(obj, CPUDispatcher):
                monkeypatch.setattr(module, name, obj.py_func)
                n += 1
    return n


def close(a: np.ndarray, b: np.ndarray) -> None:
    """Equal to rounding: 1e-12 of the magnitude of each entry (and of 1); the same NaN or
    infinity where one is not finite (the fixed k_s of the schemes without the slip model,
    Okello's B = 1/b at b = 0)."""
    finite = np.isfinite(a)
    assert np.array_equal(finite, np.isfinite(b))
    assert np.array_equal(a[~finite], b[~finite], equal_nan=True)
    a, b = a[finite], b[finite]
    scale = np.maximum(np.abs(a), 1.0)
    assert np.all(np.abs(a - b) <= 1e-12 * scale), float(np.max(np.abs(a - b) / scale))


@pytest.mark.parametrize(("scheme", "lateral", "oracle"), VARIANTS)
def test_compiled_filter_equals_its_python_text(scheme: int, lateral: bool, oracle: bool,
                                                frames: list,
                                                monkeypatch: pytest.MonkeyPatch) -> None:
    if not ekf_module.compiled_available():
        pytest.skip("NUMBA_DISABLE_JIT=1 runs only the Python text: no compiled filter to compare")
    compiled = run_filter(scheme, lateral, oracle, frames)
    assert as_python(monkeypatch) >= 40  # the kernel's, the models' and the observations'
    assert not isinstance(kernel.filter_frame, CPUDispatcher)
    python = run_filter(scheme, lateral, oracle, frames)

    for key in ("x", "P", "pose", "cov"):
        close(compiled[key], python[key])
    for a, b in zip(compiled["extras"], python["extras"], strict=True):
        assert a.keys() == b.keys()
        close(np.array(list(a.values()), dtype=float), np.array(list(b.values()), dtype=float))
    assert compiled["skipped"] == python["skipped"]
    for sensor, hist in compiled["history"].items():
        other = python["history"][sensor]
        assert [t for t, _, _ in hist] == [t for t, _, _ in other], sensor
        for (_, y, S), (_, y2, S2) in zip(hist, other, strict=True):
            close(y, y2)
            close(S, S2)


@pytest.mark.parametrize(("scheme", "lateral", "oracle"), VARIANTS)
def test_frame_does_not_read_what_its_workspace_held(scheme: int, lateral: bool, oracle: bool,
                                                     frames: list,
                                                     monkeypatch: pytest.MonkeyPatch) -> None:
    """The frame kernel reuses one workspace frame after frame, and its models write their
    predictions and Jacobians into it: with the workspaces filled with NaN, or with huge
    numbers, before every frame, the filter must give exactly what it gives otherwise (a
    temporary read before it is written, or a Jacobian entry left from the last frame, would
    show here)."""
    clean = run_filter(scheme, lateral, oracle, frames)
    frame_kernel = kernel.filter_frame
    for poison in (np.nan, -1e300):
        def poisoned(*args, poison=poison):
            ctx = args[2]  # the workspaces, float and integer, are its tail
            ctx[int(ctx[kernel.C_WORK_AT]):].fill(poison)
            return frame_kernel(*args)

        monkeypatch.setattr(kernel, "filter_frame", poisoned)
        dirty = run_filter(scheme, lateral, oracle, frames)
        for key in ("x", "P", "pose", "cov"):
            np.testing.assert_array_equal(dirty[key], clean[key])
        assert dirty["skipped"] == clean["skipped"]


def test_drive_takes_every_branch(frames: list) -> None:
    """The drive above reaches what the lockstep test claims to cover: accepted, gated and
    NaN bearings, skipped gyro, inclinometer and odometers, in the env's scheme."""
    ekf = LindgrenEKF(GEOM, 4, params=LindgrenNoise(lateral_slip_sigma0=3.0),
                      beacons_xy=np.vstack([CROSS, [[3.0, -2.0]]]))
    ekf.reset(*truth0()[:3], frames[0])
    for f in frames[1:]:
        ekf.update(f)
    skipped = ekf.skipped
    assert {"bearing_nan", "gyro_nan", "tilt_nan", "torque_nan"} <= set(skipped)
    assert len(ekf.history["bearing"]) >= 5
    assert len(ekf.history["odo"]) < N_FRAMES


def test_the_kernel_compiles_without_numbas_runtime_only_where_numba_knows_the_option() -> None:
    """The runtime-free option is numba's private one: a numba without it gets the kernel
    compiled with the runtime (no option) instead of an error at its first call."""

    class WithoutOption:
        pass

    class WithOption:
        _nrt = None

    assert kernel.nrt_free_options(WithoutOption) == {}
    assert kernel.nrt_free_options(WithOption) == {"_nrt": False}
    # the installed numba knows it, and the kernel was compiled with it
    assert kernel.filter_frame.targetoptions.get("_nrt") is False
