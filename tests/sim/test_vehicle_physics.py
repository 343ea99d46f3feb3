"""Whole-vehicle physics: parking, slip on rigid and soft soil, side slopes, skid steering."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terrain.terrain import TerrainSpec
from tests.sim.conftest import drive, hold

SLOPE_15 = dict(kind="slope", slope_deg=15.0)


@pytest.mark.parametrize(
    "vehicle,soil,model,downhill_deg",
    [
        ("husky", "field_loam", "janosi", 0.0),      # facing downhill
        ("husky", "field_loam", "janosi", 90.0),     # side-on, downhill to the left
        ("tracked_patako", "toyoura_sand", "janosi", 180.0),  # facing uphill
        ("tracked_patako", "toyoura_sand", "janosi", -90.0),  # side-on
        ("rover_4ws", "lunar_simulant", "reina", 0.0),
        ("farm_2wd", "field_loam", "linear", 0.0),  # facing downhill: weight on the drive
    ],
)
def test_a_vehicle_parked_on_a_15_degree_soil_slope_moves_less_than_1_mm_in_10_s(
    make_sim, vehicle, soil, model, downhill_deg
):
    sim = make_sim(vehicle, soil, model,
                   TerrainSpec(**SLOPE_15, downhill_azimuth_deg=downhill_deg))
    sim.reset(0.0, 0.0, 0.0)
    start = np.array(hold(sim, 5.0).position_m)  # parked: the soil has taken the load
    end = np.array(hold(sim, 10.0).position_m)
    assert np.linalg.norm(end - start) < 1e-3


def test_brakes_cannot_hold_beyond_the_mohr_coulomb_limit(make_sim):
    """Facing uphill, the farm vehicle's weight moves onto its castors, which carry no traction;
    the braked front wheels reach the soil's shear strength c A + W tan φ (Lindgren Eq. 3) and
    the vehicle slides back, slowly and at exactly that force. On 20°: on 15° the castors'
    rate-independent compaction resistance (Coulomb-like at rest) makes up the 3 % the brakes
    lack, and the vehicle holds. The shear limit alone, so without slip sinkage (with it the
    sliding wheels dig in and hold: tests/sim/test_wheel_slip_sinkage.py)."""
    sim = make_sim("farm_2wd", "field_loam", "linear",
                   TerrainSpec(kind="slope", slope_deg=20.0, downhill_azimuth_deg=180.0),
                   force_options={"slip_sinkage": None})
    sim.reset(0.0, 0.0, 0.0)
    start = np.array(hold(sim, 2.0).position_m)
    end = np.array(hold(sim, 5.0).position_m)
    assert end[0] - start[0] < -1e-3  # sliding downhill (-x)
    contact = sim.injector.contact_state()
    soil = sim.injector.soil_at_wheel(0)
    geometry = sim.injector.force_model.geometry
    area = geometry.width_m * geometry.contact_length_m
    limit = soil.cohesion_pa * area + contact.load_n[:2] * math.tan(soil.friction_angle_rad)
    assert contact.fx_n[:2] == pytest.approx(limit, rel=0.01)


def test_parking_on_the_slope_is_held_by_the_soil_not_by_friction(make_sim):
    sim = make_sim("husky", "field_loam", "janosi", TerrainSpec(**SLOPE_15))
    sim.reset(0.0, 0.0, 0.0)
    hold(sim, 3.0)
    contact = sim.injector.contact_state()
    weight = sim.spec.mass_kg * 9.81
    # The soil's longitudinal forces, shear and the ruts' resistance (Coulomb-like at rest),
    # carry the downhill component of the weight (PyBullet's own friction is zero everywhere).
    assert contact.resistance_n.sum() - contact.fx_n.sum() == pytest.approx(
        weight * math.sin(math.radians(15)), rel=0.03)
    assert np.all(contact.slip < 0)  # braking slip on every wheel


def test_straight_driving_on_rigid_soil_slips_less_than_1_percent(make_sim):
    sim = make_sim("husky", "concrete", "janosi")
    sim.reset(0.0, 0.0, 0.0)
    drive(sim, 0.6, 0.0, 4.0)
    slip = sim.injector.contact_state().slip
    assert np.all(np.abs(slip) < 0.01)
    assert np.all(slip > 0)  # driving slip, however small


@pytest.mark.parametrize("vehicle,model", [("farm_2wd", "linear"), ("husky", "janosi")])
def test_on_soft_soil_slip_grows_with_drawbar_load_and_follows_t_equals_ks_s(
    make_sim, vehicle, model
):
    """Lindgren Eq. 24: wheel torque T = k_s s, through the origin, at small slip.

    A drawbar load (a rearward pull at axle height) is raised step by step. At each level the
    motor torque of every channel must equal r F(s, W) of the force law at the wheels' own
    slip and load. With Lindgren's linear law, the torque/slip points of one wheel lie on a
    line through the origin whose slope is the law's stiffness k_s = r dF/ds.
    """
    import pybullet as p

    from slipenv.vehicles.kinematics import twist_to_commands

    sim = make_sim(vehicle, "field_loam", model)
    sim.reset(0.0, 0.0, 0.0)
    weight = sim.spec.mass_kg * 9.81
    law = sim.injector.force_model
    driven = [k for k, w in enumerate(sim.spec.wheels) if w.role == "driven"]
    radius = sim.spec.wheels[driven[0]].radius_m
    hitch = list(sim.body.base_to_reference_m)
    speeds, steer = twist_to_commands(sim.spec, 0.5, 0.0)
    slips, torques, loads = [], [], []
    for fraction in (0.0, 0.02, 0.04, 0.06, 0.08):
        pull = fraction * weight
        sim.command(speeds, steer)
        for _ in range(60):
            for _ in range(sim.substeps):
                p.applyExternalForce(sim.body.body_id, -1, [-pull, 0, 0], hitch, p.LINK_FRAME,
                                     physicsClientId=sim.client)
                sim._substep()
            truth = sim.truth()
        contact = sim.injector.contact_state()
        soil = sim.injector.soil_at_wheel(driven[0])
        f, _ = law(contact.slip, np.zeros(sim.injector.n), contact.load_n, soil)
        for c, channel in enumerate(sim.spec.channels):
            members = [k for k in driven if sim.spec.wheels[k].channel == channel]
            expected = radius * float(np.sum(f[members]))
            assert truth.channel_torque_nm[c] == pytest.approx(expected, rel=0.03, abs=0.5)
        slips.append(float(contact.slip[driven[0]]))
        torques.append(radius * float(f[driven[0]]))
        loads.append(float(contact.load_n[driven[0]]))
    slips, torques = np.array(slips), np.array(torques)
    assert np.all(np.diff(slips) > 0), slips  # more drawbar load, more slip
    if model != "linear":
        return  # Janosi/Okello bends at these slips (Lindgren Eq. 23); checked pointwise above
    # The pull pitches the vehicle and moves load between the axles, and k_s grows with the
    # load (T_max = r (A c + W tan phi), Lindgren Eq. 24): each point is brought to the last
    # point's load before the line is fitted.
    shear = soil.cohesion_pa * law.geometry.area_m2
    tan_phi = math.tan(soil.friction_angle_rad)
    torques = torques * (shear + loads[-1] * tan_phi) / (shear + np.array(loads) * tan_phi)
    slope, intercept = np.polyfit(slips, torques, 1)
    load = np.array([loads[-1]])
    ds = 1e-4
    f1, _ = law(np.array([ds]), np.zeros(1), load, soil)
    k_s = radius * float(f1[0]) / ds
    assert slope == pytest.approx(k_s, rel=0.10)
    assert abs(intercept) < 0.05 * abs(torques[-1])  # through the origin (Lindgren §3.2)


def test_driving_across_a_side_slope_drifts_downhill(make_sim):
    # Downhill is -y; the vehicle heads +x, so downhill is to its right.
    sim = make_sim("husky", "toyoura_sand", "janosi",
                   TerrainSpec(kind="slope", slope_deg=15.0, downhill_azimuth_deg=-90.0))
    sim.reset(0.0, 0.0, 0.0)
    truths = drive(sim, 0.5, 0.0, 6.0)
    last = truths[-1]
    assert last.position_m[1] < -0.05  # drifted downhill
    assert last.velocity_body_mps[1] < 0  # lateral velocity towards downhill (right)
    assert last.slip_angle_rad < -math.radians(0.5)  # slip angle of the downhill sign
    assert last.roll_rad > math.radians(10)  # right side low, left up: roll > 0 (REP 103)
    wheel_beta = np.arctan(sim.injector.contact_state().tan_beta)
    assert np.all(wheel_beta < 0)


def test_the_tracked_vehicle_turning_on_sand_slips_on_both_tracks(make_sim):
    sim = make_sim("tracked_patako", "toyoura_sand", "janosi")
    sim.reset(0.0, 0.0, 0.0)
    truths = drive(sim, 0.05, math.radians(20.0), 6.0)
    slip = sim.injector.contact_state().slip
    left, right = slip[:5], slip[5:]
    # Skid steering: the outer (right) track drives with positive slip, the inner (left) one
    # is dragged: both slip by several percent.
    assert np.all(np.abs(left) > 0.05) and np.all(np.abs(right) > 0.05)
    assert np.mean(right) > 0
    # And the vehicle turns slower than commanded (lateral track resistance).
    yaw_rate = truths[-1].yaw_rate_rad_s
    assert 0.0 < yaw_rate < math.radians(20.0)


def test_a_tracked_vehicle_turning_uphill_at_crawling_speed_moves_smoothly(make_sim):
    """Yamauchi's circle speed and yaw rate (5 cm/s, 11.5 °/s) facing up the 15° sand slope.

    The soil's lateral relaxation state is a spring; undamped at crawling speed it made the
    vehicle rock and slide sideways at several Hz (forward speed swinging from -3 to +10 cm/s,
    the yaw rate reversing). Sampled at every control step the motion must be steady.
    """
    sim = make_sim("tracked_patako", "toyoura_sand", "janosi",
                   TerrainSpec(**SLOPE_15, downhill_azimuth_deg=-90.0))
    sim.reset(0.0, 0.0, math.pi / 2)  # facing uphill
    truths = drive(sim, 0.05, math.radians(11.5), 5.0)[-60:]  # the last 3 s
    v_x = np.array([t.velocity_body_mps[0] for t in truths])
    yaw_rate = np.array([t.yaw_rate_rad_s for t in truths])
    assert v_x.max() - v_x.min() < 0.005
    assert 0.02 < v_x.min() and v_x.max() < 0.06
    assert yaw_rate.min() > 0.0
    assert yaw_rate.max() - yaw_rate.min() < math.radians(2.0)
