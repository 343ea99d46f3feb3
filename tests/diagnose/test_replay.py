"""Kinematic replay against closed forms, slope geometry, and fits on exact kinematic data."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.diagnose import geometry, replay
from slipenv.diagnose.effects import EFFECTS, effect
from slipenv.diagnose.fit import Problem, fit
from slipenv.logs import Log, LogMeta

R, W, CPR = 0.3, 1.2, 1000.0  # [m], [m], [counts/rad]


def kinematic_log(wl, wr, dt=0.05, r_true=(R, R), w_true=W, slope=0.0, azimuth=None,
                  gyro_bias=None, seed=0) -> Log:
    """Exact differential-drive log from wheel speeds (rad/s) per interval."""
    n = len(wl) + 1
    t = np.arange(n) * dt
    phl = np.concatenate([[0.0], np.cumsum(np.asarray(wl) * dt)])
    phr = np.concatenate([[0.0], np.cumsum(np.asarray(wr) * dt)])
    dl, dr = np.diff(phl) * r_true[0], np.diff(phr) * r_true[1]
    ds, dth = 0.5 * (dl + dr), (dr - dl) / w_true
    th = np.concatenate([[0.0], np.cumsum(dth)])
    mid = th[:-1] + 0.5 * dth
    u = np.concatenate([[0.0], np.cumsum(ds * np.cos(mid))])
    v = np.concatenate([[0.0], np.cumsum(ds * np.sin(mid))])
    tilt = geometry.tilt_matrix(slope, azimuth)
    x, y = tilt[0, 0] * u + tilt[0, 1] * v, tilt[1, 0] * u + tilt[1, 1] * v
    meta = LogMeta.new("diff_drive", ["left", "right"], R, W, CPR, slope_deg=slope,
                       slope_downhill_azimuth_deg=azimuth)
    cols = dict(t=t, enc_left=np.round(phl * CPR), enc_right=np.round(phr * CPR), gt_x=x,
                gt_y=y, gt_yaw=geometry.yaw_from_heading(th, tilt))
    if gyro_bias is not None:
        rng = np.random.default_rng(seed)
        cols["gyro_z"] = np.concatenate([[0.0], dth / dt]) + gyro_bias + rng.normal(0, 1e-3, n)
    return Log.from_arrays(meta, **cols)


def route(n=2400, seed=0):
    rng = np.random.default_rng(seed)
    v = np.repeat(rng.uniform(0.5, 1.5, n // 80 + 1), 80)[:n]
    om = np.repeat(rng.uniform(-0.5, 0.5, n // 80 + 1), 80)[:n]
    return (v - om * W / 2) / R, (v + om * W / 2) / R


def test_straight_and_circle_closed_form():
    wl = np.full(200, 2.0)
    log = kinematic_log(wl, wl)
    seg = replay.build_segments([log], 5.0)
    pred = replay.simulate(seg, {})
    # 2 rad/s × 0.3 m over 5 s = 3 m straight ahead
    assert pred[0, -1, 0] == pytest.approx(3.0, abs=2e-3)
    # a circle: v = 1 m/s, Ω = π/4 rad/s -> radius 4/π m; a quarter turn after 2 s
    v, om = 1.0, math.pi / 4
    wl, wr = np.full(400, (v - om * W / 2) / R), np.full(400, (v + om * W / 2) / R)
    seg = replay.build_segments([kinematic_log(wl, wr)], 4.0)
    pred = replay.simulate(seg, {})
    assert pred[0, 40, :2] == pytest.approx([4 / math.pi, 4 / math.pi], abs=2e-3)
    assert pred[0, 40, 2] == pytest.approx(math.pi / 2, abs=1e-3)


def test_nominal_replay_matches_exact_log_on_a_slope():
    wl, wr = route(600)
    log = kinematic_log(wl, wr, slope=12.0, azimuth=40.0)
    seg = replay.build_segments([log])
    res = replay.pose_residuals(seg, replay.simulate(seg, {}))
    assert np.abs(res[seg.gt_ok][:, :2]).max() < 2e-3  # only encoder quantisation


@pytest.mark.parametrize("slope", [0.0, 10.0])
def test_geometry_round_trip(slope):
    tilt = geometry.tilt_matrix(slope, 123.0)
    theta = np.linspace(-3, 3, 13)
    assert geometry.heading_from_yaw(geometry.yaw_from_heading(theta, tilt), tilt) == \
        pytest.approx(theta, abs=1e-12)


def test_roll_sign_on_a_side_slope():
    # downhill towards +y (north); heading east: the left side (north) is downhill
    tilt = geometry.tilt_matrix(10.0, 90.0)
    assert math.degrees(float(geometry.roll_from_heading(np.array(0.0), tilt))) == \
        pytest.approx(-10.0, abs=1e-9)


@pytest.mark.parametrize("radii,width", [((0.29, 0.305), W), ((R, R), 1.3)])
def test_fit_recovers_geometry_on_exact_data(radii, width):
    wl, wr = route()
    log = kinematic_log(wl, wr, r_true=radii, w_true=width)
    problem = Problem.from_segments(replay.build_segments([log]))
    f = fit(problem, ("rolling_radius", "track_width"))
    radius, track = f.params["rolling_radius"], f.params["track_width"]
    assert [radius.left_m, radius.right_m, track.width_m] == \
        pytest.approx([*radii, width], rel=2e-4)
    assert all(v > 0 for per_effect in f.se.values() for v in per_effect.values())


def test_gyro_bias_fit():
    wl, wr = route(1200)
    log = kinematic_log(wl, wr, gyro_bias=0.01)
    problem = Problem.from_segments(replay.build_segments([log]))
    f = fit(problem, ("gyro_bias",))
    se = f.se["gyro_bias"]["bias_rad_s"]
    assert f.params["gyro_bias"].bias_rad_s == pytest.approx(0.01, abs=3 * se + 1e-4)


def test_contract_names_round_trip():
    wheels, sides = ["left", "right"], np.array([0, 1])
    radius = effect("rolling_radius").params(0.28, 0.29)
    out = effect("rolling_radius").to_contract(
        radius, {"left_m": 1e-5, "right_m": 1e-5}, wheels, sides)
    assert out == {"radius_left_m": [0.28, 1e-5], "radius_right_m": [0.29, 1e-5]}
    torque = effect("torque_slip")
    ks = torque.to_contract(torque.params(1e-3, 2e-3), dict.fromkeys(torque.fields(), 1e-5),
                            wheels, sides)
    assert ks["k_s_left_nm"][0] == pytest.approx(1000.0)
    back = torque.from_contract({k: v[0] for k, v in ks.items()}, wheels, sides)
    assert [back.compliance_left_per_nm, back.compliance_right_per_nm] == \
        pytest.approx([1e-3, 2e-3])
    for eff in EFFECTS.values():
        assert eff.contract_names(wheels)


def test_wheel_sides_by_name_or_order():
    assert replay.wheel_sides(["rear_left", "front_right", "front_left"]).tolist() == [0, 1, 0]
    assert replay.wheel_sides(["a", "b", "c", "d"]).tolist() == [0, 0, 1, 1]
    with pytest.raises(ValueError, match="left from right"):
        replay.wheel_sides(["a", "b", "c"])


def test_combined_slip_named_on_a_kinematic_log():
    """Reina Eq. 12 hidden kinematically on a side slope (the PyBullet generator cannot isolate
    it: a slip angle never comes without side slip): the slip angle follows the roll,
    β = -0.4 roll (Yamauchi), and the longitudinal slip grows with it, s_x0 + k_β (|β| - β0).
    Both effects must be named, with k_β recovered."""
    from slipenv.diagnose.select import select

    n, dt, slope, az = 2400, 0.05, 12.0, 30.0
    tilt = geometry.tilt_matrix(slope, az)
    wl, wr = route(n, seed=5)
    th, u, v = [0.0], [0.0], [0.0]
    for k in range(n):
        beta = -0.4 * float(geometry.roll_from_heading(np.array(th[-1]), tilt))
        sx = 0.01 + 0.8 * max(abs(beta) - 0.02, 0.0)
        dl, dr = wl[k] * dt * R * (1 - sx), wr[k] * dt * R * (1 - sx)
        ds, dth = 0.5 * (dl + dr), (dr - dl) / W
        mid = th[-1] + 0.5 * dth
        lat = abs(ds) * math.tan(beta)
        u.append(u[-1] + ds * math.cos(mid) - lat * math.sin(mid))
        v.append(v[-1] + ds * math.sin(mid) + lat * math.cos(mid))
        th.append(th[-1] + dth)
    u, v, th = np.array(u), np.array(v), np.array(th)
    phl = np.concatenate([[0.0], np.cumsum(wl * dt)])
    phr = np.concatenate([[0.0], np.cumsum(wr * dt)])
    meta = LogMeta.new("diff_drive", ["left", "right"], R, W, CPR, slope_deg=slope,
                       slope_downhill_azimuth_deg=az)
    log = Log.from_arrays(meta, t=np.arange(n + 1) * dt, enc_left=np.round(phl * CPR),
                          enc_right=np.round(phr * CPR),
                          gt_x=tilt[0, 0] * u + tilt[0, 1] * v,
                          gt_y=tilt[1, 0] * u + tilt[1, 1] * v,
                          gt_yaw=geometry.yaw_from_heading(th, tilt))
    sel = select(Problem.from_segments(replay.build_segments([log])))
    assert {sel.cause, *sel.also} == {"slope_side_slip", "combined_slip"}
    p = sel.fits["pose"].params
    assert p["slope_side_slip"].beta_per_roll == pytest.approx(-0.4, abs=0.05)
    assert p["combined_slip"].k_beta == pytest.approx(0.8, rel=0.25)
