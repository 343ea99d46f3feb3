"""The PyBullet body built from a spec: the rover's passive pivoting axle (rocker suspension)."""

from __future__ import annotations

import math

import numpy as np
import pybullet as p
import pytest

from slipenv.contracts.constants import G_MPS2
from slipenv.envs.factory import make_force_model, make_soil_map
from slipenv.sim.simulator import Simulator
from slipenv.terrain.terrain import TerrainSpec
from slipenv.vehicles.kinematics import twist_to_commands
from slipenv.vehicles.presets import rover_4ws

FL, FR, RL, RR = range(4)  # rover_4ws wheel order


@pytest.fixture
def rover_sim():
    """``rover_sim(rocker, terrain=None)`` -> a Simulator of rover_4ws on lunar simulant at the
    origin (yaw 0), settled; closed after."""
    sims = []

    def build(rocker: bool, terrain: TerrainSpec | None = None) -> Simulator:
        spec = rover_4ws(rocker=rocker)
        sim = Simulator(spec, terrain or TerrainSpec(), make_force_model("reina", spec),
                        make_soil_map("lunar_simulant", None))
        sims.append(sim)
        sim.reset(0.0, 0.0, 0.0)
        return sim

    yield build
    for sim in sims:
        sim.close()


def _bump_under_front_left(height_m: float) -> TerrainSpec:
    """A Gaussian bump of peak ``height_m`` under the front-left wheel only (the others stand
    more than 6 standard deviations away, on the level plane)."""
    x, y, _ = rover_4ws().wheels[FL].position_m
    return TerrainSpec(kind="mounds", mound_count=0, placed_mounds=((x, y, 0.08, height_m),),
                       size_m=4.0, resolution_m=0.02)


def _held_loads(sim: Simulator, seconds: float = 2.0) -> np.ndarray:
    steps = int(round(seconds / sim.control_dt_s))
    for _ in range(steps):
        sim.step([0.0] * 4, [0.0] * 4)
    return np.asarray(sim.injector.contact_state().load_n, dtype=float)


def _pivot_angle_rad(sim: Simulator) -> float:
    return p.getJointState(sim.body.body_id, sim.body.pivot_joint,
                           physicsClientId=sim.client)[0]


def test_a_bump_under_one_wheel_unloads_the_rigid_rover_but_not_the_pivoting_axle(rover_sim):
    h = 0.06  # two thirds of the wheel radius
    rigid = _held_loads(rover_sim(False, _bump_under_front_left(h)))
    rocker_sim = rover_sim(True, _bump_under_front_left(h))
    rocker = _held_loads(rocker_sim)
    share = rocker_sim.spec.mass_kg * G_MPS2 / 4
    # Rigid: the rover stands on the diagonal FL-RR; FR and RL carry almost nothing.
    assert min(rigid[FR], rigid[RL]) < 0.15 * share
    # Free pivot at the axle midpoint: no roll moment through it, so the two front loads are
    # equal (moment balance about the pivot) and the chassis rests level on the rear pair.
    assert rocker.min() > 0.8 * share
    assert abs(rocker[FL] - rocker[FR]) < 0.1 * share
    assert abs(rocker[FL] - rocker[FR]) < 0.2 * abs(rigid[FL] - rigid[FR])
    assert rocker.sum() == pytest.approx(rocker_sim.spec.mass_kg * G_MPS2, rel=0.03)


def test_the_axle_tilts_by_the_bump_over_the_track_width(rover_sim):
    h = 0.06
    sim = rover_sim(True, _bump_under_front_left(h))
    _held_loads(sim)
    # Rear pair on the level plane keeps the chassis level; the front axle rotates until its
    # right wheel touches the plane: sin(angle) = h / track.
    expected = math.asin(h / sim.spec.track_width_m)
    assert abs(_pivot_angle_rad(sim)) == pytest.approx(expected, abs=math.radians(0.3))


def test_the_pivot_angle_stays_within_its_stops_on_a_bump_taller_than_they_allow(rover_sim):
    sim = rover_sim(True, _bump_under_front_left(0.2))
    limit = sim.spec.pivot_axle.limit_rad
    assert math.asin(0.2 / sim.spec.track_width_m) > limit  # the free axle would exceed it
    angles = []
    for _ in range(40):
        sim.step([0.0] * 4, [0.0] * 4)
        angles.append(_pivot_angle_rad(sim))
    assert max(abs(a) for a in angles) <= limit + math.radians(0.2)
    assert abs(angles[-1]) == pytest.approx(limit, abs=math.radians(0.2))  # on the stop


def test_on_flat_ground_the_pivot_leaves_the_static_loads_and_a_straight_drive_unchanged(
        rover_sim):
    rigid_sim, rocker_sim = rover_sim(False), rover_sim(True)
    assert _held_loads(rocker_sim, 1.0) == pytest.approx(_held_loads(rigid_sim, 1.0), rel=0.02)
    speeds, steer = twist_to_commands(rigid_sim.spec, 0.08, 0.0)
    ends = []
    for sim in (rigid_sim, rocker_sim):
        for _ in range(int(round(5.0 / sim.control_dt_s))):
            truth = sim.step(speeds, steer)
        ends.append((np.asarray(truth.position_m), truth.yaw_rad))
    (rigid_xyz, rigid_yaw), (rocker_xyz, rocker_yaw) = ends
    assert rigid_xyz[0] > 0.3  # it did drive
    assert np.linalg.norm(rocker_xyz - rigid_xyz) < 0.003
    assert abs(rocker_yaw - rigid_yaw) < math.radians(0.1)
    assert abs(_pivot_angle_rad(rocker_sim)) < math.radians(0.1)


def test_the_pivot_joint_precedes_the_wheels_it_carries_and_the_body_reports_their_links(
        rover_sim):
    sim = rover_sim(True)
    bid, cid = sim.body.body_id, sim.client
    info = p.getJointInfo(bid, sim.body.pivot_joint, physicsClientId=cid)
    assert info[2] == p.JOINT_REVOLUTE and tuple(info[13]) == (1.0, 0.0, 0.0)
    for k in (FL, FR):  # front wheels hang from their steering link, which hangs from the axle
        steer = sim.body.steer_joints[k]
        assert p.getJointInfo(bid, steer, physicsClientId=cid)[16] == sim.body.pivot_joint
    for k in (RL, RR):
        assert p.getJointInfo(bid, sim.body.steer_joints[k], physicsClientId=cid)[16] == -1
    assert sorted(sim.injector.links) == sorted(sim.body.wheel_links)
    assert sim.body.pivot_joint not in sim.body.wheel_links
