"""The Wong-Chiang track injector on the tracked vehicle: the track thrust of a steady climb
against Wong's equation, mirror-symmetric turns, parking, turning and climbing on slopes,
static sinkage."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.sim.injector import Injector
from slipenv.sim.simulator import Simulator
from slipenv.sim.track_soil import TrackModelParams, TrackSoilInjector
from slipenv.terrain.terrain import TerrainSpec
from slipenv.terramechanics.bekker import track_sinkage_m
from slipenv.terramechanics.presets import DRY_SAND
from tests.sim.conftest import drive, hold

G = 9.81


@pytest.fixture
def tracked():
    sims = []

    def build(terrain: TerrainSpec | None = None, soil=DRY_SAND) -> Simulator:
        spec = make_vehicle("tracked_patako_wong_chiang")
        assert spec.track_model == "wong_chiang"
        sim = Simulator(spec, terrain or TerrainSpec(), make_force_model("janosi", spec),
                        make_soil_map(soil, None))
        assert isinstance(sim.injector, TrackSoilInjector)
        sims.append(sim)
        return sim

    yield build
    for sim in sims:
        sim.close()


def test_the_per_wheel_model_stays_selectable_and_the_choice_is_validated():
    spec = make_vehicle("tracked_patako_wong_chiang")
    old = make_vehicle("tracked_patako")
    assert old.track_model == "per_wheel"
    sim = Simulator(old, TerrainSpec(), make_force_model("janosi", old),
                    make_soil_map("dry_sand", None))
    try:
        assert not isinstance(sim.injector, TrackSoilInjector)
    finally:
        sim.close()
    with pytest.raises(ValueError, match="track_model"):
        dataclasses.replace(spec, track_model="wong")
    with pytest.raises(ValueError, match="track_model"):
        dataclasses.replace(make_vehicle("husky"), track_model="wong_chiang")
    with pytest.raises(ValueError, match="n_cells"):
        TrackModelParams(n_cells=2)


@pytest.mark.parametrize("downhill_deg", [-90.0, 180.0])  # side-on, facing uphill
def test_parked_on_a_15_degree_slope_the_tracked_vehicle_holds(tracked, downhill_deg):
    sim = tracked(TerrainSpec(kind="slope", slope_deg=15.0, downhill_azimuth_deg=downhill_deg))
    sim.reset(0.0, 0.0, 0.0)
    start = np.array(hold(sim, 3.0).position_m)
    end = np.array(hold(sim, 10.0).position_m)
    assert np.linalg.norm(end - start) < 1e-3


def test_static_sinkage_is_bekkers_for_the_ground_pressure(tracked):
    sim = tracked()
    sim.reset(0.0, 0.0, 0.0)
    hold(sim, 1.0)
    inj = sim.injector
    weight = sum(inj.load)
    assert weight == pytest.approx(sim.spec.mass_kg * G, rel=0.02)
    b, length = inj.width[0], inj.length_m
    z_bekker = float(track_sinkage_m(weight / 2.0, b, length, DRY_SAND.k_c, DRY_SAND.k_phi,
                                     DRY_SAND.n_exp))
    assert 2e-3 < z_bekker < 5e-3  # loose sand: millimetres, not LETE's 0.06 mm
    assert inj.sinkage_m.mean() == pytest.approx(z_bekker, rel=0.2)


def _downhill_drift_m(sim: Simulator, omega: float, seconds: float) -> float:
    """Integral of the body's lateral sliding velocity along the downhill direction (-y) [m]:
    zero for a vehicle that follows its tracks' kinematics."""
    drift = 0.0
    for truth in drive(sim, 0.05, omega, seconds):
        vy = truth.velocity_body_mps[1]
        # Downhill is world -y; the body's left axis is (-sin yaw, cos yaw).
        drift += vy * -math.cos(truth.yaw_rad) * sim.control_dt_s
    return drift


@pytest.mark.xfail(strict=True, reason=(
    "one expects more downhill drift turning downhill; the model gives the opposite: "
    "6 s at 0.2 rad/s, 5 cm/s on 15° dry sand, lateral drift 19 mm turning downhill against "
    "35 mm turning uphill (without the side walls 34 against 44 mm). Turning downhill the "
    "front of each track sweeps downhill into fresh soil and its side wall mobilises the "
    "berm over the whole pass (23 + 18 N uphill); turning uphill only the rear half pushes "
    "downhill soil (7 - 5 N). Whether real tracks differ by the effects the model leaves out "
    "(track-edge shear, soil flow around the track ends) is not measured here"))
def test_turning_on_a_slope_it_drifts_downhill_more_turning_downhill_than_uphill(tracked):
    """Across a 15° slope (downhill on the right), a right turn heads downhill and a left turn
    uphill."""
    terrain = TerrainSpec(kind="slope", slope_deg=15.0, downhill_azimuth_deg=-90.0)
    drifts = {}
    for name, omega in (("downhill", -0.2), ("uphill", 0.2)):
        sim = tracked(terrain)
        sim.reset(0.0, 0.0, 0.0)
        hold(sim, 1.0)
        drifts[name] = _downhill_drift_m(sim, omega, 6.0)
    assert drifts["uphill"] > 0.0
    assert drifts["downhill"] > 1.2 * drifts["uphill"]


def test_commanded_beyond_traction_uphill_it_stalls_and_does_not_creep(tracked):
    """Facing up a slope just below the Mohr-Coulomb limit of the tracks (gravity = c A +
    W cos θ tan φ - 2 N): the belt spins (slip -> 1) and the vehicle stops, held by the
    rate-independent rut resistance it would have to overcome to advance (no creep). The dry
    sand without its cohesion, so that the limit lies below the terrain's 45° bound."""
    soil = dataclasses.replace(DRY_SAND, name="dry_sand_cohesionless", cohesion_pa=0.0)
    c, tan_phi = soil.cohesion_pa, math.tan(soil.friction_angle_rad)
    spec = make_vehicle("tracked_patako_wong_chiang")
    w = spec.mass_kg * G
    area = 2 * 0.11 * spec.track_length_m

    def margin(theta: float) -> float:
        return c * area + w * math.cos(theta) * tan_phi - w * math.sin(theta)

    lo, hi = 0.0, 1.2
    for _ in range(60):  # bisection for the slope where gravity meets the traction limit
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if margin(mid) > 2.0 else (lo, mid)
    sim = tracked(TerrainSpec(kind="slope", slope_deg=math.degrees(lo), size_m=20.0,
                              downhill_azimuth_deg=180.0), soil)
    sim.reset(0.0, 0.0, 0.0)
    hold(sim, 1.0)
    drive(sim, 0.1, 0.0, 15.0)
    x0 = sim.truth().position_m[0]
    truths = drive(sim, 0.1, 0.0, 5.0)
    assert abs(truths[-1].position_m[0] - x0) < 3e-3  # no creep over the last 5 s
    assert abs(truths[-1].velocity_body_mps[0]) < 1e-3
    assert min(sim.injector.track_slip) > 0.95


@pytest.mark.parametrize("slope_deg", [10.0, 20.0])
def test_climbing_straight_each_track_pulls_with_wongs_thrust_at_its_slip(tracked, slope_deg):
    """Driving straight up a slope at a steady 0.1 m/s, the soil under a track has been sheared
    by j = i s at a distance s behind the front (slip i), so the thrust is Wong's integral of
    the Janosi stress, F = b sum (c + p tan phi)(1 - e^{-i s/K}) dx over the injector's own
    cell pressures p (Wong Ch. 4; with a uniform p it is (A c + W tan phi)[1 - K/(iL)(1 -
    e^{-iL/K})]); and the two thrusts carry the weight's downhill component and the rut
    resistance."""
    theta = math.radians(slope_deg)
    sim = tracked(TerrainSpec(kind="slope", slope_deg=slope_deg, size_m=20.0,
                              downhill_azimuth_deg=180.0))
    sim.reset(0.0, 0.0, 0.0)
    hold(sim, 1.0)
    drive(sim, 0.1, 0.0, 12.0)
    inj = sim.injector
    soil = DRY_SAND
    load = np.array(inj.load)
    pressure = (inj.spread_all @ load).reshape(len(inj.tracks), -1) / (inj.width[0] * inj.dx_m)
    thrusts = []
    for t, wheels in enumerate(inj.tracks):
        slip = inj.track_slip[t]
        assert 0.005 < slip < 0.2
        s = inj.length_m / 2.0 - (inj.x_cell[t] - inj.x_cell[t].mean())  # behind the front
        wong = (inj.width[t] * inj.dx_m * (soil.cohesion_pa + pressure[t]
                                           * math.tan(soil.friction_angle_rad))
                * -np.expm1(-slip * s / soil.shear_modulus_m)).sum()
        thrust = sum(inj.fx[k] for k in wheels)
        assert thrust == pytest.approx(wong, rel=1e-3)
        thrusts.append(thrust)
    assert sum(thrusts) == pytest.approx(sim.spec.mass_kg * G * math.sin(theta) + sum(inj.res),
                                         rel=0.02)


def test_left_and_right_turns_on_flat_ground_are_mirror_images(tracked):
    """The same turn to the left and to the right: mirrored paths (y and yaw change sign, x
    does not) and mirrored forces, the left track of one turn doing what the right track of
    the other does."""
    runs = []
    for omega in (0.4, -0.4):
        sim = tracked()
        sim.reset(0.0, 0.0, 0.0)
        hold(sim, 1.0)
        truth = drive(sim, 0.1, omega, 4.0)[-1]
        inj = sim.injector
        per_track = [[sum(getattr(inj, f)[k] for k in ks) for ks in inj.tracks]
                     for f in ("fx", "fy", "damping_n")]
        runs.append((truth, np.array(per_track), list(inj.track_slip)))
    (left, f_left, slip_left), (right, f_right, slip_right) = runs
    assert abs(left.yaw_rad) > 1.0 and abs(left.position_m[1]) > 0.1  # it did turn
    assert right.position_m[0] == pytest.approx(left.position_m[0], abs=1e-4)
    assert right.position_m[1] == pytest.approx(-left.position_m[1], abs=1e-4)
    assert right.yaw_rad == pytest.approx(-left.yaw_rad, abs=1e-4)
    mirror = np.array([1.0, -1.0, 1.0])[:, None]  # fx and damper magnitude keep their sign
    np.testing.assert_allclose(f_right[:, ::-1], mirror * f_left, rtol=0.01, atol=0.05)
    assert slip_right[::-1] == pytest.approx(slip_left, abs=1e-3)


def test_the_track_injector_offers_what_the_simulator_reads(tracked):
    sim = tracked()
    assert isinstance(sim.injector, Injector)
    sim.reset(0.0, 0.0, 0.0)
    hold(sim, 0.5)
    state = sim.injector.contact_state()
    assert state.load_n.sum() == pytest.approx(sim.spec.mass_kg * G, rel=0.02)
    assert len(sim.injector.links) == len(sim.spec.wheels)


# -- reading PyBullet natively ------------------------------------------------------------------
def _turn_on_slope(sim: Simulator) -> np.ndarray:
    """1.5 s of turning across a 15° slope from rest; the truths (position, yaw, velocities)."""
    sim.reset(0.0, 0.0, 0.0)
    truths = drive(sim, 0.05, 0.3, 1.5)
    return np.array([[*t.position_m, t.yaw_rad, *t.velocity_body_mps] for t in truths])


def test_natively_the_injector_reads_and_applies_exactly_what_the_python_api_does(
        tracked, monkeypatch):
    """Bullet's C API and pybullet's Python API give the same readings bit for bit, checked
    on the way, and the same forces applied make the same trajectory bit for bit."""
    slope = TerrainSpec(kind="slope", slope_deg=15.0, downhill_azimuth_deg=-90.0)
    native = tracked(slope)
    if not native.injector.native_queries:
        pytest.skip("native PyBullet access is unavailable on this pybullet")
    run_native = _turn_on_slope(native)
    inj = native.injector
    assert not inj.native_mismatch and inj.native_verifications >= 2
    a, b = np.zeros_like(inj._reading), np.zeros_like(inj._reading)
    inj._io.read(a)
    inj._read_python(b)
    assert a.tobytes() == b.tobytes() and a[13:13 + inj.n].sum() > 0.0
    monkeypatch.setenv("SLIPENV_PYBULLET_API", "1")
    python = tracked(slope)
    assert not python.injector.native_queries
    assert _turn_on_slope(python).tobytes() == run_native.tobytes()


def test_a_broken_guard_switches_to_the_python_api_and_warns(tracked):
    from slipenv.sim.bullet_native import NativeReaderWarning

    sim = tracked()
    if not sim.injector.native_queries:
        pytest.skip("native PyBullet access is unavailable on this pybullet")
    sim.reset(0.0, 0.0, 0.0)
    sim.injector._io.scribble_guard()
    with pytest.warns(NativeReaderWarning, match="guard region"):
        hold(sim, 0.1)
    assert not sim.injector.native_queries and sim.injector.native_mismatch
    assert sum(sim.injector.load) > 0.0  # it goes on, through the Python API


def test_the_compiled_hull_frame_is_pybullets_quaternion_matrix():
    from slipenv.pybullet_quiet import import_pybullet
    from slipenv.sim.track_soil import _hull_kinematics

    p = import_pybullet()
    rng = np.random.default_rng(5)
    rot, hull, tracks_now = np.zeros(9), np.zeros(3), np.zeros((5, 1))
    for _ in range(200):
        q = rng.normal(size=4)
        q /= np.linalg.norm(q)
        reading = np.concatenate((np.zeros(3), q, np.zeros(6), [1.0], [0.0], [0.0]))
        _hull_kinematics(reading, np.zeros(1, dtype=np.int64), np.ones((4, 1)), rot, hull,
                         tracks_now)
        np.testing.assert_allclose(rot, p.getMatrixFromQuaternion(q.tolist()), rtol=0,
                                   atol=1e-15)
