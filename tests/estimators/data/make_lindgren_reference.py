"""Freeze the Lindgren EKF's outputs on a fixed input sequence (issue 15, item 3).

Run once, BEFORE a change to the filter's implementation, from the repository root::

    python tests/estimators/data/make_lindgren_reference.py --force

(without ``--force`` it refuses to overwrite an existing fixture: regenerating it with the
changed filter would make the test compare the filter with itself). The fixture in the tree was
made with the product-form Joseph filter of before issue 15, on the simulation of that day.

It drives ``slipenv/FarmField-v0`` (2WD farm vehicle, beacons, torque sensor) for ``N_STEPS``
control steps with a seeded, varying action, keeps the sensor frames the env produced, perturbs a
few of them to reach the filter's rarer branches (a missing gyro, accelerometer, inclinometer and
torque reading, a NaN bearing, a clutter bearing far from every beacon), and then runs the filter
in every variant (schemes 1-4 and the oracle) over those frames, saving the state ``x`` and
covariance ``P`` after every frame and the skip counts at the end. The frames themselves are
saved too, so the test (``tests/estimators/test_lindgren_reference.py``) replays them without
PyBullet and does not depend on the simulation staying the same.
"""

from __future__ import annotations

from pathlib import Path

import gymnasium as gym
import numpy as np

import slipenv  # noqa: F401  (registers the envs)
from slipenv.contracts import SensorFrame
from slipenv.estimators.base import OdometryGeometry
from slipenv.estimators.lindgren import LindgrenEKF, LindgrenNoise, OracleSoil

N_STEPS = 300
OUT = Path(__file__).with_name("lindgren_reference.npz")
VARIANTS = ("s1", "s2", "s3", "s4", "oracle")
FRAME_SCALARS = ("t_s", "gyro_z_rad_s", "acc_x_mps2", "acc_y_mps2", "roll_rad", "pitch_rad",
                 "heading_rad")


def record_frames() -> tuple[list[SensorFrame], dict]:
    """Frames of one FarmField episode (reset frame first), and the filter's set-up."""
    env = gym.make("slipenv/FarmField-v0")
    rng = np.random.default_rng(15)
    try:
        _, info = env.reset(seed=3)
        frames = [info["sensors"]]
        base = env.unwrapped
        pose0 = base.estimator.x[:3].copy()  # the start pose the env gave the filter
        for k in range(N_STEPS):
            action = np.array([0.6 + 0.3 * np.sin(k / 25.0), 0.4 * np.sin(k / 40.0)])
            action = np.clip(action + rng.normal(0.0, 0.1, 2), -1, 1).astype(np.float32)
            _, _, term, trunc, info = env.step(action)
            frames.append(info["sensors"])
            if term or trunc:
                break
        est = base.estimator
        setup = {"geometry": est.geometry, "params": est.params,
                 "beacons_xy": np.asarray(base.beacons_xy, dtype=float),
                 "pose0": pose0}
    finally:
        env.close()
    return frames, setup


def perturb(frames: list[SensorFrame], beacons_xy: np.ndarray) -> list[SensorFrame]:
    """Reach the rare branches: missing readings, a NaN bearing, a clutter bearing."""
    from dataclasses import replace

    out = list(frames)
    nan = float("nan")
    out[20] = replace(out[20], gyro_z_rad_s=nan)
    out[21] = replace(out[21], acc_x_mps2=nan)
    out[22] = replace(out[22], pitch_rad=nan)
    out[23] = replace(out[23], wheel_torque_nm=np.full_like(out[23].wheel_torque_nm, nan))
    out[24] = replace(out[24], wheel_torque_nm=np.full_like(out[24].wheel_torque_nm, nan))
    for k in (40, 41):
        f = out[k]
        t_prev = out[k - 1].t_s
        tb = np.concatenate([f.beacon_times_s, [t_prev + 0.3 * (f.t_s - t_prev)] * 2])
        zb = np.concatenate([f.beacon_bearings_rad, [nan, 2.9 if k == 40 else -0.7]])
        out[k] = replace(f, beacon_times_s=tb, beacon_bearings_rad=zb)
    return out


def make_filter(variant: str, setup: dict) -> LindgrenEKF:
    geometry: OdometryGeometry = setup["geometry"]
    params: LindgrenNoise = setup["params"]
    if variant == "oracle":
        soil = OracleSoil((0.99 * geometry.wheel_radius_m, 1.01 * geometry.wheel_radius_m),
                          (1.2 * params.k_s0, 0.9 * params.k_s0))
        return LindgrenEKF(geometry, 4, params, setup["beacons_xy"], oracle=soil)
    return LindgrenEKF(geometry, int(variant[1]), params, setup["beacons_xy"])


def run_filter(variant: str, setup: dict, frames: list[SensorFrame]
               ) -> tuple[np.ndarray, np.ndarray, dict]:
    ekf = make_filter(variant, setup)
    x0, y0, yaw0 = setup["pose0"]
    ekf.reset(x0, y0, yaw0, frames[0])
    xs, Ps = [ekf.x.copy()], [ekf.P.copy()]
    for f in frames[1:]:
        ekf.update(f)
        xs.append(ekf.x.copy())
        Ps.append(ekf.P.copy())
    hist = {k: len(v) for k, v in ekf.history.items()}
    return np.array(xs), np.array(Ps), {"skipped": dict(ekf.skipped), "history": hist}


def pack_frames(frames: list[SensorFrame]) -> dict[str, np.ndarray]:
    d: dict[str, np.ndarray] = {}
    for name in FRAME_SCALARS:
        d[f"frame_{name}"] = np.array([getattr(f, name) for f in frames], dtype=float)
    d["frame_enc_counts"] = np.array([f.enc_counts for f in frames])
    d["frame_wheel_torque_nm"] = np.array([f.wheel_torque_nm for f in frames], dtype=float)
    nb = [len(np.atleast_1d(f.beacon_bearings_rad)) for f in frames]
    d["frame_bearing_offsets"] = np.concatenate([[0], np.cumsum(nb)]).astype(np.int64)
    d["frame_bearings_rad"] = np.concatenate(
        [np.atleast_1d(np.asarray(f.beacon_bearings_rad, dtype=float)) for f in frames])
    d["frame_bearing_times_s"] = np.concatenate(
        [np.atleast_1d(np.asarray(f.beacon_times_s, dtype=float)) for f in frames])
    return d


def unpack_frames(d) -> list[SensorFrame]:
    """The frames saved by :func:`pack_frames` (used by the test)."""
    off = d["frame_bearing_offsets"]
    frames = []
    for k in range(len(d["frame_t_s"])):
        sl = slice(int(off[k]), int(off[k + 1]))
        frames.append(SensorFrame(
            **{name: float(d[f"frame_{name}"][k]) for name in FRAME_SCALARS},
            enc_counts=d["frame_enc_counts"][k].copy(),
            wheel_torque_nm=d["frame_wheel_torque_nm"][k].copy(),
            beacon_bearings_rad=d["frame_bearings_rad"][sl].copy(),
            beacon_times_s=d["frame_bearing_times_s"][sl].copy()))
    return frames


def main() -> None:
    import sys

    if OUT.exists() and "--force" not in sys.argv[1:]:
        raise SystemExit(f"{OUT} exists; pass --force to overwrite the frozen reference")
    frames, setup = record_frames()
    frames = perturb(frames, setup["beacons_xy"])
    g: OdometryGeometry = setup["geometry"]
    data = pack_frames(frames)
    # replay from the packed frames so that the test sees exactly these inputs
    frames = unpack_frames(data)
    data.update(
        geometry=np.array([g.wheel_radius_m, g.track_width_m, g.counts_per_rad]),
        geometry_left=np.array(g.left), geometry_right=np.array(g.right),
        k_s0=np.array(setup["params"].k_s0), beacons_xy=setup["beacons_xy"],
        pose0=setup["pose0"])
    for v in VARIANTS:
        xs, Ps, counts = run_filter(v, setup, frames)
        data[f"{v}_x"], data[f"{v}_P"] = xs, Ps
        data[f"{v}_skipped"] = np.array(repr(sorted(counts["skipped"].items())))
        data[f"{v}_history"] = np.array(repr(sorted(counts["history"].items())))
        print(v, counts)
    np.savez_compressed(OUT, **data)
    print(f"wrote {OUT} ({OUT.stat().st_size} bytes, {len(frames)} frames)")


if __name__ == "__main__":
    main()
