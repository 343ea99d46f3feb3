"""Per-episode metrics from a recorder fed synthetic env outputs (closed forms)."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from slipenv.contracts import SensorFrame
from slipenv.evaluation.metrics import (
    TraceRecorder,
    aggregate,
    episode_metrics,
    worst_episode,
)

COUNTS_PER_RAD = 100.0


def _env(torque_scale: float = 1.0):
    base = SimpleNamespace(config=SimpleNamespace(sensor_noise=SimpleNamespace(
        counts_per_rad=None, torque_scale=torque_scale)),
        vehicle=SimpleNamespace(counts_per_rad=COUNTS_PER_RAD))
    return SimpleNamespace(unwrapped=base)


def _info(k: int, torque: np.ndarray, omega: np.ndarray, dt: float, scale: float,
          ct: float) -> dict:
    angle = omega * k * dt
    frame = SensorFrame(t_s=k * dt, enc_counts=np.floor(angle * COUNTS_PER_RAD).astype(np.int64),
                        wheel_torque_nm=scale * torque)
    x = 0.1 * k
    return {"t_s": k * dt, "true_pose": np.array([x, ct, 0.0]),
            "estimated_pose": np.array([x + 0.01 * k, ct, 0.0]), "sensors": frame,
            "cross_track_true_m": ct, "progress_true": k / 100, "is_success": False}


def _run(steps: int = 100, torque=(2.0, -3.0), omega=(4.0, 2.0), scale: float = 1.0,
         ct: float = 0.02) -> TraceRecorder:
    dt = 0.05
    torque, omega = np.array(torque), np.array(omega)
    rec = TraceRecorder(seed=7)
    env = _env(scale)
    rec.on_reset(env, np.zeros(12), _info(0, torque, omega, dt, scale, ct))
    for k in range(1, steps + 1):
        rec.on_step(env, np.zeros(2), np.zeros(12), 1.0, False, False,
                    _info(k, torque, omega, dt, scale, ct))
    return rec


def test_energy_is_the_integral_of_torque_times_wheel_speed_magnitudes():
    # ∫ Σ|τ ω| dt = (2·4 + 3·2) W × 5 s = 70 J; encoders quantise the angle to 1/100 rad.
    m = episode_metrics(_run().trace)
    assert m["energy_j"] == pytest.approx(70.0, abs=0.2)


def test_energy_divides_out_the_torque_sensor_scale():
    assert episode_metrics(_run(scale=2.5).trace)["energy_j"] == pytest.approx(
        episode_metrics(_run().trace)["energy_j"], rel=1e-12)


def test_cross_track_and_odometry_metrics_use_true_and_estimated_poses():
    m = episode_metrics(_run(ct=-0.03).trace, rpe_delta_steps=10)
    assert m["cross_track_rmse_m"] == pytest.approx(0.03)
    assert m["mean_cross_track_m"] == pytest.approx(0.03)
    assert m["odometry_final_error_m"] == pytest.approx(1.0)  # 0.01 m/step × 100 steps
    assert m["odometry_mean_error_m"] == pytest.approx(0.5)  # mean of 0..1 m over 101 poses
    assert m["rpe_rmse_m"] == pytest.approx(0.1)  # 0.01 m/step × Δ = 10 steps
    assert m["duration_s"] == pytest.approx(5.0)
    assert m["steps"] == 100 and m["seed"] == 7 and m["progress"] == pytest.approx(1.0)


def test_aggregate_means_episodes_and_worst_episode_picks_by_metric_direction():
    eps = [dict(episode_metrics(_run(ct=c).trace), seed=s, success=ok)
           for s, c, ok in ((0, 0.01, True), (1, 0.05, False), (2, 0.02, True))]
    agg = aggregate(eps)
    assert agg["cross_track_rmse_m"] == pytest.approx((0.01 + 0.05 + 0.02) / 3)
    assert agg["success_rate"] == pytest.approx(2 / 3)
    assert worst_episode(eps, "cross_track_rmse_m")["seed"] == 1
    assert worst_episode(eps, "success_rate")["seed"] == 1
    with pytest.raises(ValueError, match="unknown metric"):
        worst_episode(eps, "cross_track")


def test_a_nan_metric_is_the_worst_episode():
    eps = [dict(episode_metrics(_run().trace), seed=s) for s in range(3)]
    eps[2]["energy_j"] = math.nan
    assert worst_episode(eps, "energy_j")["seed"] == 2
