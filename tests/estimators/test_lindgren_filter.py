"""LindgrenEKF mechanics: schemes, one step against the plain functions and filterpy, sign
conventions at the SensorFrame boundary, association and gating, covariance health, bad input."""

from __future__ import annotations

import dataclasses
import logging
import math

import numpy as np
import pytest
from filterpy.kalman import ExtendedKalmanFilter

from slipenv.contracts.frame import SensorFrame
from slipenv.estimators.base import Estimator, OdometryGeometry
from slipenv.estimators.lindgren import kernel
from slipenv.estimators.lindgren import models as lm
from slipenv.estimators.lindgren import observations as lo
from slipenv.estimators.lindgren.ekf import (
    LindgrenEKF,
    LindgrenNoise,
    OracleSoil,
    Scheme,
    parse_scheme,
    warm_up,
)
from slipenv.sensors.beacons import BeaconScanner, default_beacons_xy
from tests.estimators.lindgren_synth import simulate, straight_and_turn, torque, truth0

GEOM = OdometryGeometry(wheel_radius_m=0.275, track_width_m=1.5, counts_per_rad=285.0)
CROSS = np.array([[10.0, 0.0], [0.0, 10.0], [-10.0, 0.0], [0.0, -10.0]])


def frame(t: float, counts=(0.0, 0.0), torque=(0.0, 0.0), **kw) -> SensorFrame:
    return SensorFrame(t_s=t, enc_counts=np.array(counts, dtype=float),
                       wheel_torque_nm=np.array(torque, dtype=float), **kw)


def synthetic(n_steps: int, seed: int = 3):
    return simulate(GEOM, truth0(), n_steps, 0.05, np.random.default_rng(seed),
                    reference=straight_and_turn(), torque=torque, scanner=BeaconScanner())


def snapshot(ekf: LindgrenEKF) -> tuple:
    return ekf.x.copy(), ekf.P.copy(), {k: len(v) for k, v in ekf.history.items()}


def assert_unchanged(ekf: LindgrenEKF, snap: tuple) -> None:
    np.testing.assert_array_equal(ekf.x, snap[0])
    np.testing.assert_array_equal(ekf.P, snap[1])
    assert {k: len(v) for k, v in ekf.history.items()} == snap[2]


def test_schemes_by_number_and_name() -> None:
    assert parse_scheme(4) is Scheme.ALL_SLIP
    assert parse_scheme("laser_inertial") is Scheme.LASER_INERTIAL
    assert parse_scheme("2") is Scheme.ODOMETRY_ONLY
    with pytest.raises(ValueError, match="unknown scheme"):
        parse_scheme("all")
    assert parse_scheme(5) is parse_scheme("all_slip_okello") is Scheme.ALL_SLIP_OKELLO
    with pytest.raises(ValueError, match="unknown scheme"):
        parse_scheme(6)
    assert LindgrenEKF(GEOM, "all_slip").n == 13
    assert LindgrenEKF(GEOM, 5).n == 15
    assert LindgrenEKF(GEOM, 3).n == 9
    lateral = LindgrenNoise(lateral_slip_sigma0=3.0)
    assert [LindgrenEKF(GEOM, s, lateral).n for s in (3, 4, 5)] == [10, 14, 16]
    assert LindgrenEKF(GEOM, 4, lateral).state_names[-1] == "k_beta"
    with pytest.raises(ValueError, match="lateral_slip_sigma0"):
        LindgrenNoise(lateral_slip_sigma0=-1.0)
    assert LindgrenEKF(GEOM, 4, oracle=OracleSoil((0.28, 0.28), (2e3, 2e3))).n == 9
    with pytest.raises(ValueError, match="oracle"):
        LindgrenEKF(GEOM, 3, oracle=OracleSoil((0.28, 0.28), (2e3, 2e3)))
    with pytest.raises(ValueError, match="beacons_xy"):
        LindgrenEKF(GEOM, 1)
    with pytest.raises(ValueError, match="jerk_psd_v"):
        LindgrenNoise(jerk_psd_v=-1.0)
    with pytest.raises(TypeError):
        LindgrenNoise(jerk=1.0)  # unknown keys are an error


def test_protocol_reset_and_extras() -> None:
    ekf = LindgrenEKF(GEOM, 4, beacons_xy=CROSS)
    assert isinstance(ekf, Estimator)
    est = ekf.reset(1.0, 2.0, 3.5, frame(0.0, pitch_rad=-0.05, roll_rad=0.02))
    assert (est.x_m, est.y_m) == (1.0, 2.0)
    assert est.yaw_rad == pytest.approx(3.5 - 2.0 * math.pi)
    assert est.cov.shape == (3, 3)
    assert est.extras["R_wl_m"] == 0.275 and est.extras["k_sr"] == LindgrenNoise().k_s0
    assert (ekf.x[lm.IA1], ekf.x[lm.IA2]) == (0.05, -0.02)  # REP 103 -> Lindgren signs
    with pytest.raises(RuntimeError, match="before reset"):
        LindgrenEKF(GEOM, 3).update(frame(0.1))


def test_one_step_matches_plain_functions_and_filterpy() -> None:
    """Predict (Eq. 6-7), then gyro and odometer updates equal filterpy's EKF to 1e-12."""
    params = LindgrenNoise()
    ekf = LindgrenEKF(GEOM, 3, params, beacons_xy=CROSS)
    x0 = np.array([1.0, 2.0, 0.3, 0.8, 0.1, 0.2, -0.1, 0.01, 0.02])
    P0 = np.diag(np.linspace(0.01, 0.1, 9) ** 2)
    ekf.reset_state(x0, P0, frame(0.0, counts=(100.0, 200.0)))
    tau, gz, dc = 0.05, 0.12, np.array([44.0, 48.0])
    ekf.update(frame(tau, counts=(100.0 + dc[0], 200.0 + dc[1]), gyro_z_rad_s=gz))
    F = lm.process_F(x0, tau, params.tilt_psd)
    Q = lm.process_Q(x0, tau, params.jerk_psd_v, params.jerk_psd_omega, params.tilt_psd)
    kf = ExtendedKalmanFilter(dim_x=9, dim_z=1)
    kf.x, kf.P = lm.process_fx(x0, tau, params.tilt_psd), F @ P0 @ F.T + Q
    kf.update(np.array([gz]), lambda s: lo.ins_H(s)[2:], lambda s: lo.ins_hx(s)[2:],
              R=np.array([[params.gyro_var_rad2ps2]]))
    args = (tau, 0.275, 1.5, 285.0)
    kf.update(dc, lambda s: lo.odo_H(s, *args), lambda s: lo.odo_hx(s, *args),
              R=np.eye(2) * params.odometer_var_rad2 * 285.0**2)
    np.testing.assert_allclose(ekf.x, kf.x, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(ekf.P, kf.P, rtol=1e-10, atol=1e-12)
    assert ekf.skipped == {"acc_nan": 1, "tilt_nan": 1}


def test_slope_signs_at_the_sensor_frame_boundary() -> None:
    """At rest, nose up 0.1 rad and left side up 0.05 rad (REP 103: pitch -0.1, roll +0.05):
    accelerometers read +0.1 g forward and +0.05 g left. The filter must explain both with
    tilt, not with acceleration."""
    g = lm.G_MPS2
    ekf = LindgrenEKF(GEOM, 3, beacons_xy=CROSS)
    ekf.reset(0.0, 0.0, 0.0, frame(0.0))
    for k in range(1, 41):
        est = ekf.update(frame(0.05 * k, gyro_z_rad_s=0.0, acc_x_mps2=0.1 * g,
                               acc_y_mps2=0.05 * g, pitch_rad=-0.1, roll_rad=0.05))
    assert ekf.x[lm.IA1] == pytest.approx(0.1, abs=1e-3)
    assert ekf.x[lm.IA2] == pytest.approx(-0.05, abs=1e-3)
    assert abs(ekf.x[lm.IVD]) < 0.01 and abs(est.speed_mps) < 1e-3


def test_association_picks_the_beacon_and_gates_an_outlier(
        caplog: pytest.LogCaptureFixture) -> None:
    def fresh() -> LindgrenEKF:
        ekf = LindgrenEKF(GEOM, 1, beacons_xy=CROSS)
        ekf.reset(0.0, 0.0, 0.0, frame(0.0))
        return ekf

    good = math.pi / 2 + 0.005  # beacon (0, 10), 5 mrad off
    outlier = math.pi / 4  # halfway between two beacons: no beacon is near
    a, b = fresh(), fresh()
    with caplog.at_level(logging.WARNING, logger="slipenv.estimators.lindgren.ekf"):
        a.update(frame(0.05, beacon_bearings_rad=np.array([outlier, good]),
                       beacon_times_s=np.array([0.05, 0.03])))
    assert "bearing_gated" not in caplog.text  # gating is routine: counted, not warned about
    b.update(frame(0.05, beacon_bearings_rad=np.array([good]),
                   beacon_times_s=np.array([0.03])))
    (t, y, S), = a.history["bearing"]
    assert t == 0.03 and y.shape == (1,) and S.shape == (1, 1)
    assert y[0] == pytest.approx(0.005, abs=1e-4)  # matched (0, 10), not a neighbour
    assert a.skipped["bearing_gated"] == 1 and "bearing_gated" not in b.skipped
    assert a.estimate().extras["skipped"]["bearing_gated"] == 1
    np.testing.assert_array_equal(a.x, b.x)  # the outlier changed nothing
    np.testing.assert_array_equal(a.P, b.P)


def test_covariance_stays_symmetric_positive_definite() -> None:
    """100 s of straight-and-turn with the slip model; laser cut after 50 s (Lindgren §5)."""
    run = synthetic(2000)
    ekf = LindgrenEKF(GEOM, 4, beacons_xy=default_beacons_xy())
    ekf.reset(*truth0()[:3], run.frames[0])
    min_eig = np.inf
    for f in run.frames[1:]:
        if f.t_s > 50.0:
            f = dataclasses.replace(f, beacon_bearings_rad=np.zeros(0),
                                    beacon_times_s=np.zeros(0))
        ekf.update(f)
        np.testing.assert_array_equal(ekf.P, ekf.P.T)
        np.linalg.cholesky(ekf.P)
        min_eig = min(min_eig, np.linalg.eigvalsh(ekf.P).min())
    assert min_eig > 0.0
    assert np.all(np.isfinite(ekf.x))


def test_rejected_frames_leave_the_state_unchanged() -> None:
    run = synthetic(21)
    ekf = LindgrenEKF(GEOM, 4, beacons_xy=default_beacons_xy())
    ekf.reset(*truth0()[:3], run.frames[0])
    for f in run.frames[1:20]:
        ekf.update(f)
    snap, t = snapshot(ekf), run.frames[19].t_s
    nxt = run.frames[20]
    bad = {
        "out of order": dataclasses.replace(nxt, t_s=t),
        "not finite": dataclasses.replace(nxt, t_s=math.nan),
        "encoder": dataclasses.replace(nxt, enc_counts=np.array([math.nan, 1.0])),
        "enc_counts has shape": dataclasses.replace(nxt, enc_counts=np.zeros(1)),
        "outside": dataclasses.replace(nxt, beacon_bearings_rad=np.array([0.1]),
                                       beacon_times_s=np.array([t - 0.01])),
        "one length": dataclasses.replace(nxt, beacon_times_s=np.zeros(7)),
    }
    for message, f in bad.items():
        with pytest.raises(ValueError, match=message):
            ekf.update(f)
        assert_unchanged(ekf, snap)

    real_kernel = kernel.filter_frame

    def boom(*args):  # the frame's arithmetic runs (on the filter's copies), then fails
        real_kernel(*args)
        raise FloatingPointError("injected")

    with pytest.MonkeyPatch.context() as mp:
        mp.setattr(kernel, "filter_frame", boom)
        with pytest.raises(FloatingPointError):
            ekf.update(nxt)
    assert_unchanged(ekf, snap)
    ekf.update(nxt)
    assert len(ekf.history["odo"]) == snap[2]["odo"] + 1


def test_odometry_update_that_would_make_k_s_negative_is_undone() -> None:
    """Counts beyond the prediction (a 40 % slip: a rolling wheel, inside the small-slip range)
    with a loose k_s prior push k_s below zero: the update is dropped (``odo_invalid_soil``)
    and the state is the prediction alone."""
    x = np.zeros(lm.N_SLIP)
    x[lm.IV], x[lm.IRL:lm.IRR + 1], x[lm.IKL:] = 1.0, 0.275, 100.0
    P = np.diag([1e-2] * 9 + [1e-4, 1e-4, 1e6, 1e6])
    ekf, pred = LindgrenEKF(GEOM, 4), LindgrenEKF(GEOM, 4)
    for f in (ekf, pred):
        f.reset_state(x, P, frame(0.0, torque=(10.0, 10.0)))
    pred.predict_to(0.05)
    ekf.update(frame(0.05, counts=(87.0, 87.0), torque=(10.0, 10.0)))
    assert ekf.skipped["odo_invalid_soil"] == 1 and ekf.history["odo"] == []
    np.testing.assert_array_equal(ekf.x, pred.x)
    np.testing.assert_array_equal(ekf.P, pred.P)


def test_what_the_filter_hands_out_never_changes_afterwards() -> None:
    """x, P, an estimate (its covariance and extras) and the innovation history, once read,
    stay as they were through later frames and predictions: the filter writes each frame into
    a spare state vector and hands out copies or arrays it never writes again."""
    run = synthetic(30)
    ekf = LindgrenEKF(GEOM, 4, params=LindgrenNoise(lateral_slip_sigma0=3.0),
                      beacons_xy=default_beacons_xy())
    ekf.reset(*truth0()[:3], run.frames[0])
    for f in run.frames[1:10]:
        ekf.update(f)
    est = ekf.update(run.frames[10])
    _, y_old, S_old = ekf.history["odo"][-1]
    handed_out = {"x": ekf.x, "P": ekf.P, "cov": est.cov, "y": y_old, "S": S_old}
    kept = {k: v.copy() for k, v in handed_out.items()}
    extras = dict(est.extras)
    for f in run.frames[11:]:
        ekf.update(f)
    ekf.predict_to(run.frames[-1].t_s + 0.1)
    assert not np.array_equal(ekf.P, kept["P"])  # it did move on
    for key, array in handed_out.items():
        np.testing.assert_array_equal(array, kept[key], err_msg=key)
    assert est.extras == extras
    x_set = ekf.x + 1.0  # setting x replaces the state, not the arrays read before
    ekf.x = x_set
    np.testing.assert_array_equal(ekf.x, x_set)
    np.testing.assert_array_equal(handed_out["x"], kept["x"])


def test_estimates_share_no_mutable_object_with_the_filter_or_each_other() -> None:
    """Each estimate owns its extras and skip counts, and its covariance shares no memory with
    another's: a user who edits one estimate changes neither the filter nor any other one."""
    run = synthetic(40)
    ekf = LindgrenEKF(GEOM, 4, params=LindgrenNoise(lateral_slip_sigma0=3.0), beacons_xy=CROSS)
    ests = [ekf.reset(*truth0()[:3], run.frames[0])]
    for f in run.frames[1:]:
        ests.append(ekf.update(f))
    ests.append(ekf.estimate())
    assert ekf.skipped  # the drive skips something, so the skip counts are worth copying
    skipped = dict(ekf.skipped)
    for a, b in zip(ests, ests[1:], strict=False):
        assert a.extras is not b.extras and a.extras["skipped"] is not b.extras["skipped"]
        assert not np.shares_memory(a.cov, b.cov)
    for est in ests:
        assert est.extras["skipped"] is not ekf.skipped
        assert est.extras["n_skipped"] == sum(est.extras["skipped"].values())
    last = ests[-1]
    kept = [dict(e.extras, skipped=dict(e.extras["skipped"])) for e in ests[:-1]]
    last.extras["skipped"]["bearing_gated"] = 10**6
    last.extras["n_bearings_used"] = -1
    assert ekf.skipped == skipped
    assert [dict(e.extras, skipped=dict(e.extras["skipped"])) for e in ests[:-1]] == kept
    assert ekf.estimate().extras["n_bearings_used"] == len(ekf.history["bearing"])


def test_bearing_arrays_of_any_layout_give_the_state_of_contiguous_ones() -> None:
    """The filter hands the usual frame's bearing arrays to the kernel's compiled code for
    contiguous float64 arrays as they are; strided views, big-endian or read-only arrays,
    arrays whose dtype is an equal copy of float64's (as unpickled ones have) and frames with
    more bearings than usual must give bitwise the state that contiguous copies give."""
    run = synthetic(60)
    rng = np.random.default_rng(5)

    def strided(a: np.ndarray) -> np.ndarray:
        return np.repeat(a, 2)[::2]  # the same values, every other element of a buffer

    def big_endian(a: np.ndarray) -> np.ndarray:
        return a.astype(">f8")

    def read_only(a: np.ndarray) -> np.ndarray:
        a = a.copy()
        a.flags.writeable = False
        return a

    def copied_dtype(a: np.ndarray) -> np.ndarray:
        return np.frombuffer(a.tobytes(), dtype=np.dtype("<f8").newbyteorder("="))

    def crowded(f: SensorFrame) -> SensorFrame:  # six bearings in the frame's interval
        t = np.sort(f.t_s - 0.05 * rng.uniform(0.0, 1.0, 6))
        return dataclasses.replace(f, beacon_times_s=t,
                                   beacon_bearings_rad=rng.uniform(-1.0, 1.0, 6))

    base = [run.frames[0]] + [crowded(f) if k % 7 == 3 else f
                              for k, f in enumerate(run.frames[1:])]
    assert any(len(f.beacon_times_s) > 4 for f in base)
    ref = LindgrenEKF(GEOM, 4, beacons_xy=CROSS)
    ref.reset(*truth0()[:3], base[0])
    for f in base[1:]:
        ref.update(f)
    for layout in (strided, big_endian, read_only, copied_dtype):
        ekf = LindgrenEKF(GEOM, 4, beacons_xy=CROSS)
        ekf.reset(*truth0()[:3], base[0])
        for f in base[1:]:
            ekf.update(dataclasses.replace(f, beacon_times_s=layout(f.beacon_times_s),
                                           beacon_bearings_rad=layout(f.beacon_bearings_rad)))
        np.testing.assert_array_equal(ekf.x, ref.x, err_msg=layout.__name__)
        np.testing.assert_array_equal(ekf.P, ref.P, err_msg=layout.__name__)
        assert ekf.skipped == ref.skipped
        assert [t for t, _, _ in ekf.history["bearing"]] == [
            t for t, _, _ in ref.history["bearing"]]


def test_nan_optional_sensors_are_counted_and_logged(caplog: pytest.LogCaptureFixture) -> None:
    run = synthetic(2)
    ekf = LindgrenEKF(GEOM, 4, beacons_xy=default_beacons_xy())
    ekf.reset(*truth0()[:3], run.frames[0])
    f = run.frames[1]
    f = dataclasses.replace(
        f, gyro_z_rad_s=math.nan, acc_x_mps2=math.nan, wheel_torque_nm=np.array([1.0, np.nan]),
        beacon_bearings_rad=np.array([0.1, math.nan]), beacon_times_s=np.array([0.02, 0.03]))
    with caplog.at_level(logging.WARNING, logger="slipenv.estimators.lindgren.ekf"):
        est = ekf.update(f)
    assert est.extras["skipped"] == {"gyro_nan": 1, "acc_nan": 1, "torque_nan": 1,
                                     "bearing_nan": 1}
    assert "torque_nan" in caplog.text and "gyro_nan" in caplog.text
    assert len(ekf.history["tilt"]) == 1 and len(ekf.history["odo"]) == 0
    assert np.all(np.isfinite(ekf.x))


def test_skips_repeating_from_frame_to_frame_are_counted_each_time_and_warned_once(
        caplog: pytest.LogCaptureFixture) -> None:
    """A sensor missing in frame after frame: every missing reading counted, one warning per
    reason, the rest logged at debug level; the accepted bearings still add up."""
    run = synthetic(40)
    ekf = LindgrenEKF(GEOM, 4, beacons_xy=CROSS)
    ekf.reset(*run.truth[0, :3], run.frames[0])
    n_missing = 0
    with caplog.at_level(logging.DEBUG, logger="slipenv.estimators.lindgren.ekf"):
        for k, f in enumerate(run.frames[1:], start=1):
            if k % 3:
                f = dataclasses.replace(f, gyro_z_rad_s=math.nan, roll_rad=math.nan)
                n_missing += 1
            est = ekf.update(f)
    assert n_missing > 20
    assert est.extras["skipped"]["gyro_nan"] == est.extras["skipped"]["tilt_nan"] == n_missing
    assert len(ekf.history["gyro"]) == len(run.frames) - 1 - n_missing
    for reason in ("gyro_nan", "tilt_nan"):
        logged = [r for r in caplog.records if f"({reason})" in r.getMessage()]
        assert [r.levelno for r in logged] == [logging.WARNING] + [logging.DEBUG] * (
            n_missing - 1)
    assert est.extras["n_bearings_used"] == len(ekf.history["bearing"]) > 0


def test_a_frame_without_bearings_gives_one_state_whatever_its_empty_arrays() -> None:
    """No scan in a frame: numpy's empty array (strides (0,)), an empty column of a 2-D array
    and empty lists give the same state."""
    run = synthetic(40)
    empties = (np.zeros(0), np.zeros((0, 2))[:, 0], [])
    ekfs = [LindgrenEKF(GEOM, 4, beacons_xy=CROSS) for _ in empties]
    for ekf, empty in zip(ekfs, empties, strict=True):
        ekf.reset(*run.truth[0, :3], run.frames[0])
        for f in run.frames[1:]:
            if len(f.beacon_times_s) == 0:
                f = dataclasses.replace(f, beacon_bearings_rad=empty, beacon_times_s=empty)
            ekf.update(f)
    assert sum(len(f.beacon_times_s) == 0 for f in run.frames[1:]) > 5
    for ekf in ekfs[1:]:
        np.testing.assert_array_equal(ekf.x, ekfs[0].x)
        np.testing.assert_array_equal(ekf.P, ekfs[0].P)
        assert ekf.skipped == ekfs[0].skipped


def test_history_layout() -> None:
    run = synthetic(40)
    ekf = LindgrenEKF(GEOM, 4, beacons_xy=default_beacons_xy())
    ekf.reset(*truth0()[:3], run.frames[0])
    for f in run.frames[1:]:
        ekf.update(f)
    dims = {"gyro": 1, "acc": 2, "tilt": 2, "odo": 2, "bearing": 1}
    for sensor, n_z in dims.items():
        recs = ekf.history[sensor]
        assert len(recs) >= 40
        assert all(y.shape == (n_z,) and S.shape == (n_z, n_z) for _, y, S in recs)
        assert np.all(np.diff([r[0] for r in recs]) >= 0.0)
    assert ekf.estimate().extras["n_bearings_used"] == len(ekf.history["bearing"])


def test_warm_up_runs_every_sensor_quietly(caplog: pytest.LogCaptureFixture) -> None:
    with caplog.at_level(logging.WARNING, logger="slipenv.estimators.lindgren.ekf"):
        warm_up()
    assert caplog.text == ""


def test_unsorted_and_nan_bearings_give_the_state_of_the_sorted_finite_ones() -> None:
    """The kernel takes a frame's bearings as they come and hands back the frame when they are
    out of order or NaN; the filter then sorts them, drops the NaN ones (counted) and runs the
    frame again: the same state as a frame that had them in order."""
    run = synthetic(120)
    messy = []
    for f in run.frames:
        t, z = f.beacon_times_s, f.beacon_bearings_rad
        if len(t) >= 2:  # reversed, with a NaN bearing added at the frame's time
            f = dataclasses.replace(f, beacon_times_s=np.append(t[::-1], f.t_s),
                                    beacon_bearings_rad=np.append(z[::-1], math.nan))
        messy.append(f)
    assert sum(len(f.beacon_times_s) >= 3 for f in messy) > 10
    ekfs = [LindgrenEKF(GEOM, 4, beacons_xy=CROSS) for _ in range(2)]
    for ekf, frames in zip(ekfs, (run.frames, messy), strict=True):
        ekf.reset(*run.truth[0, :3], frames[0])
        for f in frames[1:]:
            ekf.update(f)
    np.testing.assert_array_equal(ekfs[1].x, ekfs[0].x)
    np.testing.assert_array_equal(ekfs[1].P, ekfs[0].P)
    n_nan = sum(len(f.beacon_times_s) >= 3 for f in messy[1:])
    assert ekfs[1].skipped.get("bearing_nan") == n_nan
    assert ekfs[0].skipped.get("bearing_nan") is None


@pytest.mark.parametrize("scheme", [4, 5])
def test_odometers_correct_a_soil_estimate_that_gives_the_torque_too_much_slip(
        scheme: int) -> None:
    """A k_s prior so low that the measured torque would slip the wheels beyond the small-slip
    range (|T| / k_s > max_slip) while the counts show them rolling at a few per cent: the soil
    estimate is outside the model, not the wheels. The odometers must still be used and move
    k_s towards the truth; a range check on the estimate's own slip would reject every
    odometer reading and keep the wrong k_s for good (no sensor but the odometers sees k_s)."""
    run = synthetic(400)  # true k_s 2500 / 2200, torque 150 ± 100 N m: true slip ~0.07
    params = LindgrenNoise(k_s0=200.0)  # the estimate's slip: 0.25 to 1.25
    ekf = LindgrenEKF(GEOM, scheme, params)  # no beacons: odometers and inertial sensors
    ekf.reset(*run.truth[0, :3], run.frames[0])
    for f in run.frames[1:]:
        ekf.update(f)
    assert ekf.skipped.get("slip_out_of_range", 0) == 0
    assert len(ekf.history["odo"]) >= 0.95 * (len(run.frames) - 1)
    k_s = ekf.x[lm.IKL:lm.IKR + 1]
    assert np.all(k_s > 3.0 * params.k_s0), k_s
