"""The wheel-injection defects of the audit (physics-notes §1), in the world.

Each test failed on the injector before the fix: a stalled vehicle crept at 1.5 cm/s; the farm
vehicle's castors dragged along the chassis axis on a circle; the relaxation length was the
soil's K; no damper share was reported.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.terrain.terrain import TerrainSpec
from slipenv.terramechanics.bekker import (
    compaction_resistance_n,
    wheel_compaction_law,
    wheel_sinkage_m,
)
from tests.sim.conftest import drive


def test_a_husky_commanded_up_a_slope_beyond_its_traction_limit_stalls_instead_of_creeping(
        make_sim):
    """25° on field loam: W sin 25° = 0.42 W exceeds what the wheels can pull against the
    compaction resistance (measured before the fix: creep at 1.49 cm/s forward, slip 0.97).
    The compaction resistance is rate-independent, so the vehicle stalls: speed -> 0,
    slip -> 1 (physics-notes §1, defect 2)."""
    sim = make_sim("husky", "field_loam", "janosi",
                   TerrainSpec(kind="slope", slope_deg=25.0, downhill_azimuth_deg=180.0))
    sim.reset(0.0, 0.0, 0.0)  # facing uphill (+x), downhill is -x
    truths = drive(sim, 0.5, 0.0, 6.0)
    x = np.array([t.position_m[0] for t in truths[-40:]])  # the last 2 s
    v = np.array([t.velocity_body_mps[0] for t in truths[-40:]])
    assert abs(x[-1] - x[0]) < 1e-3  # < 0.5 mm/s mean over 2 s (was 3 cm)
    assert np.abs(v).max() < 2e-3
    assert np.all(sim.injector.contact_state().slip > 0.99)


def test_farm_castor_drag_points_against_the_castor_contact_velocity_on_a_4_m_circle(make_sim):
    """The castors trail 1.5 m behind the driven axle: on a 4 m circle they travel at
    atan(1.5/4) = 20.6° to the chassis axis, so about a third of their compaction drag is a
    side force (physics-notes §1, defect 4)."""
    sim = make_sim("farm_2wd", "field_loam", "linear")
    sim.reset(0.0, 0.0, 0.0)
    v = 0.4
    drive(sim, v, v / 4.0, 8.0)
    injector = sim.injector
    castors = [k for k, w in enumerate(sim.spec.wheels) if w.role == "caster"]
    links = [injector.links[k] for k in castors]
    import pybullet as p

    states = p.getLinkStates(sim.body.body_id, links, computeLinkVelocity=1,
                             physicsClientId=sim.client)
    yaw = sim.truth().yaw_rad
    forward = np.array([math.cos(yaw), math.sin(yaw)])
    for k, state in zip(castors, states, strict=True):
        vel = np.array(state[6][:2])
        force = np.array(injector.resistance_force_n[k][:2])
        assert np.linalg.norm(force) == pytest.approx(injector.contact_state().resistance_n[k],
                                                      rel=1e-6)
        cos_angle = -force @ vel / (np.linalg.norm(force) * np.linalg.norm(vel))
        assert cos_angle > math.cos(math.radians(1.0))  # along -v of the castor within 1°
        # and the castor travels well off the chassis axis (the drive slips under the castors'
        # drag, so the circle is wider than 4 m): a real side force, the sine of that angle
        off_axis = abs(forward[0] * vel[1] - forward[1] * vel[0]) / np.linalg.norm(vel)
        side = abs(forward[0] * force[1] - forward[1] * force[0])
        assert off_axis > math.sin(math.radians(8.0))
        assert side == pytest.approx(off_axis * np.linalg.norm(force), rel=0.03)


def test_relaxation_length_is_the_front_contact_arc_from_bekker_sinkage(make_sim):
    """sigma = r acos(1 - z/r) (the front arc the shear builds over; Wong Ch. 5; Pacejka §7.2
    sigma ~ a), z the Bekker sinkage at the static load share, floored at min_relaxation_m."""
    sim = make_sim("farm_2wd", "field_loam", "linear")
    injector = sim.injector
    spec = sim.spec
    soil = injector.soil_at_wheel(0)
    wheel = spec.wheels[0]
    load = spec.mass_kg * 9.81 / len(spec.wheels)
    z = float(wheel_sinkage_m(load, wheel.width_m, 2 * wheel.radius_m, soil.k_c, soil.k_phi,
                              soil.n_exp))
    expected = wheel.radius_m * math.acos(1.0 - z / wheel.radius_m)
    assert 0.08 < expected < 0.09  # about half the 0.18 m patch, not the soil's K = 2.5 cm
    assert injector.relaxation_length_m(0) == pytest.approx(expected, rel=1e-9)
    rigid = make_sim("husky", "concrete", "janosi").injector
    assert rigid.relaxation_length_m(0) == rigid.min_relaxation_m


@pytest.mark.parametrize("vehicle,soil,model,v,omega", [
    ("farm_2wd", "field_loam", "linear", 0.5, 0.0),     # Lindgren: straight ...
    ("farm_2wd", "field_loam", "linear", 0.4, 0.1),     # ... and the 4 m circle
    ("tracked_patako", "toyoura_sand", "janosi", 0.05, math.radians(11.5)),  # Yamauchi circle
])
def test_the_soil_dampers_carry_under_1_percent_of_the_traction_in_the_tested_regimes(
        make_sim, vehicle, soil, model, v, omega):
    sim = make_sim(vehicle, soil, model)
    sim.reset(0.0, 0.0, 0.0)
    drive(sim, v, omega, 4.0)
    damper, traction = [], []
    for _ in range(20):
        drive(sim, v, omega, 0.05)
        contact = sim.injector.contact_state()
        damper.append(np.abs(contact.damper_n).sum())
        traction.append(np.hypot(contact.fx_n, contact.fy_n).sum())
    assert np.mean(damper) < 0.01 * np.mean(traction)


def test_farm_castors_in_the_front_wheels_ruts_meet_only_the_compaction_below_the_rut(make_sim):
    """multi_pass=True (Wong §2.4 repetitive loading; `bekker.rut_following_compaction_n`),
    castors on their own geometry: driving straight, each castor runs in the rut of the
    driven wheel ahead of it and meets f_r W_c + max(R_c(z_c) - R_c(z_rut), 0), R_c Bekker's
    compaction for the castor's width, z_c its own sinkage, z_rut the front wheel's. The
    driven wheels' slip sinkage is off: this is the static ruts' law alone."""
    from slipenv.sim.wheel_soil import WheelSoilInjector

    sim = make_sim("farm_2wd", "field_loam", "linear", force_options={"slip_sinkage": None})
    sim.reset(0.0, 0.0, 0.0)
    injector = WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                                 sim.force_model, sim.soil_map, sim.dt_s, multi_pass=True,
                                 castor_own_geometry=True)
    assert injector.leaders == [(-1, 2), (-1, 3), (0, -1), (1, -1)]
    sim.injector = injector
    drive(sim, 0.5, 0.0, 3.0)
    contact = injector.contact_state()
    soil = injector.soil_at_wheel(0)
    f_r = sim.force_model.rolling_resistance_coeff
    castor_w, front_w = sim.spec.wheels[2], sim.spec.wheels[0]

    def compaction(wheel, load):  # gamma W^e of `wheel`'s own geometry (Wong Ch. 5)
        gamma, e = wheel_compaction_law(wheel.width_m, 2 * wheel.radius_m, soil.k_c,
                                        soil.k_phi, soil.n_exp, soil.deformable)
        return float(gamma) * load ** float(e)

    for castor, front in ((2, 0), (3, 1)):
        w_c, w_f = contact.load_n[castor], contact.load_n[front]
        # The castor's compaction at the depth of the front wheel's rut: from the front
        # wheel's Bekker sinkage, Bekker's R_c(z) for the castor's width.
        z_rut = float(wheel_sinkage_m(w_f, front_w.width_m, 2 * front_w.radius_m, soil.k_c,
                                      soil.k_phi, soil.n_exp))
        at_rut = float(compaction_resistance_n(z_rut, castor_w.width_m, soil.k_c, soil.k_phi,
                                               soil.n_exp))
        expected = f_r * w_c + max(compaction(castor_w, w_c) - at_rut, 0.0)
        assert contact.resistance_n[castor] == pytest.approx(expected, rel=1e-6)
        # The rut helps, but the narrow castor sinks below the wide wheel's rut: it still
        # compacts soil there (a wheel alike would not: it is lighter than the wheel ahead).
        full = f_r * w_c + compaction(castor_w, w_c)
        assert f_r * w_c + 0.1 * (full - f_r * w_c) < contact.resistance_n[castor] < 0.9 * full
        assert compaction(front_w, w_c) < compaction(front_w, w_f)
    # The driven wheels lead: nothing ahead of them when driving forward.
    assert contact.resistance_n[0] == pytest.approx(
        f_r * contact.load_n[0] + compaction(front_w, contact.load_n[0]), rel=1e-9)


def test_the_env_info_reports_the_damper_share_per_wheel():
    import gymnasium as gym

    import slipenv  # noqa: F401  (registers the envs)

    env = gym.make("slipenv/HuskySand-v0")
    try:
        env.reset(seed=0)
        _, _, _, _, info = env.step(env.action_space.sample() * 0.0)
        damper = info["wheel_damper_n"]
        assert damper.shape == info["wheel_load_n"].shape
        assert np.all(np.isfinite(damper)) and np.all(damper >= 0.0)
    finally:
        env.close()


def test_farm_castor_resistance_is_the_bekker_compaction_of_its_own_wheel(make_sim):
    """A castor cuts its own rut: its resistance is f_r W + gamma W^e with gamma, e of its own
    width and diameter (Bekker via Wong Ch. 5, `bekker.wheel_compaction_law`), not of the
    driven wheels' (0.12 m x 0.30 m castor against 0.25 m x 0.55 m: it sinks deeper per
    newton, about twice the drag at the farm vehicle's load)."""
    sim = make_sim("farm_2wd", "field_loam", "linear", castor_own_geometry=True)
    sim.reset(0.0, 0.0, 0.0)
    drive(sim, 0.5, 0.0, 4.0)
    state = sim.injector.contact_state()
    soil = sim.injector.soil_at_wheel(0)
    f_r = sim.force_model.rolling_resistance_coeff
    driven = next(w for w in sim.spec.wheels if w.role == "driven")
    for k, wheel in enumerate(sim.spec.wheels):
        if wheel.role != "caster":
            continue
        load = state.load_n[k]
        gamma, e = wheel_compaction_law(wheel.width_m, 2 * wheel.radius_m, soil.k_c, soil.k_phi,
                                        soil.n_exp, soil.deformable)
        own = f_r * load + float(gamma) * load ** float(e)
        gamma_d, e_d = wheel_compaction_law(driven.width_m, 2 * driven.radius_m, soil.k_c,
                                            soil.k_phi, soil.n_exp, soil.deformable)
        assert state.resistance_n[k] == pytest.approx(own, rel=1e-9)  # sliding: full R
        assert own > 1.5 * (f_r * load + float(gamma_d) * load ** float(e_d))
