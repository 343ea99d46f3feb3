"""The wheel substep as physics: steady slip under a torque, mirror symmetry, dissipation,
determinism, and a user's force law run through the same loop.

Each test states a closed form or an invariant of the laws (``slipenv/terramechanics/_laws.h``)
and checks what the simulation does with them, to a tolerance that a wrong sign or factor in a
law breaks by far.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from slipenv.pybullet_quiet import import_pybullet
from slipenv.sim.wheel_soil import WheelSoilInjector
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import JanosiForceModel, force_model_by_name, wheel_kernel
from slipenv.terramechanics.presets import soil_by_name
from slipenv.terramechanics.soil_map import UniformSoil
from tests.sim.conftest import drive, turn_and_stop
from tests.sim.rig import CONTACT_M, RADIUS_M, WIDTH_M, SingleWheelRig

p = import_pybullet()

GEOMETRY = ContactGeometry(radius_m=RADIUS_M, width_m=WIDTH_M, contact_length_m=CONTACT_M)
GROUND_SPEED_MPS = 0.08


def _patch(soil_name: str, load_n: float) -> tuple[float, float]:
    """(F_max, L/K) of the rig's patch: Mohr-Coulomb limit A c + W tan phi (Lindgren Eq. 3)
    and the shear length over the shear modulus."""
    soil = soil_by_name(soil_name)
    f_max = GEOMETRY.area_m2 * soil.cohesion_pa + load_n * math.tan(soil.friction_angle_rad)
    return f_max, GEOMETRY.shear_length_m / soil.shear_modulus_m


@pytest.mark.parametrize("torque_nm", [0.5, 1.5])
def test_steady_slip_under_a_constant_torque_is_the_linear_laws_closed_form(torque_nm):
    """A wheel driven by torque T at constant ground speed settles where the soil's thrust
    balances it, F(s) = T/r; the linear law F = F_max (L/2K) s (Lindgren Eq. 23-24) gives
    s = 2 T K/(r F_max L)."""
    rig = SingleWheelRig(force_model_by_name("linear", GEOMETRY),
                         UniformSoil(soil_by_name("lunar_simulant")))
    try:
        run = rig.drive_torque(GROUND_SPEED_MPS, torque_nm)
    finally:
        rig.close()
    f_max, ratio = _patch("lunar_simulant", run["load_n"])
    expected = 2.0 * torque_nm / (RADIUS_M * f_max * ratio)
    assert expected < 1.0
    assert run["slip"] == pytest.approx(expected, rel=0.02)
    assert run["thrust_n"] == pytest.approx(torque_nm / RADIUS_M, rel=0.01)


def test_steady_slip_under_a_constant_torque_inverts_okellos_curve():
    """The same with Janosi-Hanamoto shear: F(s) = F_max [1 - (K/(sL))(1 - e^{-sL/K})]
    (Lindgren Eq. 18-20) = T/r, solved for s."""
    torque_nm = 1.5
    rig = SingleWheelRig(force_model_by_name("janosi", GEOMETRY),
                         UniformSoil(soil_by_name("lunar_simulant")))
    try:
        run = rig.drive_torque(GROUND_SPEED_MPS, torque_nm)
    finally:
        rig.close()
    f_max, ratio = _patch("lunar_simulant", run["load_n"])

    def excess(s: float) -> float:
        x = s * ratio
        return f_max * (1.0 - (1.0 - math.exp(-x)) / x) - torque_nm / RADIUS_M

    assert run["slip"] == pytest.approx(brentq(excess, 1e-6, 1.0), rel=0.02)


def test_a_torque_beyond_the_mohr_coulomb_limit_spins_the_wheel_to_full_slip():
    rig = SingleWheelRig(force_model_by_name("janosi", GEOMETRY),
                         UniformSoil(soil_by_name("lunar_simulant")))
    try:
        f_max, _ = _patch("lunar_simulant", rig.load_n)
        run = rig.drive_torque(GROUND_SPEED_MPS, 1.2 * f_max * RADIUS_M, seconds=4.0,
                               average_s=0.2)
    finally:
        rig.close()
    assert run["slip"] > 0.98
    assert run["thrust_n"] < f_max  # the soil cannot give more than its shear strength


def _turn(make_sim, yaw_rate: float) -> tuple[np.ndarray, float]:
    sim = make_sim("husky", "loose_sand", "janosi")
    sim.reset(0.0, 0.0, 0.0)
    truth = drive(sim, 0.5, yaw_rate, 3.0)[-1]
    return np.array(truth.position_m), truth.yaw_rad


def test_turning_left_and_right_are_mirror_images(make_sim):
    """The vehicle and the soil are symmetric about the vehicle's x-z plane, so are the laws:
    a left turn is the mirror image of the right one (y and yaw change sign)."""
    left, yaw_left = _turn(make_sim, 0.8)
    right, yaw_right = _turn(make_sim, -0.8)
    assert yaw_left > 0.5
    assert yaw_right == pytest.approx(-yaw_left, abs=0.01 * yaw_left)
    assert right[0] == pytest.approx(left[0], abs=5e-3)
    assert right[1] == pytest.approx(-left[1], abs=5e-3)


def test_driving_straight_stays_on_the_line(make_sim):
    position, yaw = _turn(make_sim, 0.0)
    assert position[0] > 1.0
    assert abs(position[1]) < 1e-3 and abs(yaw) < 1e-3


@pytest.mark.parametrize("vehicle,soil,model", [("husky", "loose_sand", "janosi"),
                                                ("farm_2wd", "field_loam", "linear"),
                                                ("rover_4ws", "lunar_simulant", "reina")])
def test_the_soil_never_does_positive_work(make_sim, vehicle, soil, model):
    """Shear opposes the sliding of the contact (fx s >= 0: the thrust points along
    r omega - v; fy tan beta <= 0), and the motion resistance opposes the wheel's travel once
    it slides (its elastic pre-sliding only stores R x_0). Checked on every wheel after every
    control step of a drive, a turn and a stop."""
    sim = make_sim(vehicle, soil, model)
    sim.reset(0.0, 0.0, 0.0)
    inj = sim.injector
    sliding_checked = 0
    for v, w in ((0.6, 0.0), (0.4, 1.0), (0.0, 0.0)):
        for truth in drive(sim, v, w, 1.5):
            del truth
            s, b, fx, fy = (np.array(x) for x in (inj.s, inj.b, inj.fx, inj.fy))
            assert np.all(fx * s >= 0.0) and np.all(fy * b <= 0.0)
            links = p.getLinkStates(inj.body_id, inj.links, 1, 0, sim.client)
            for k, state in enumerate(links):
                velocity = np.array(state[6])
                if np.linalg.norm(velocity) > 0.05 and inj.res[k] > 0.0:
                    power = float(np.dot(inj.resistance_force_n[k], velocity))
                    assert power <= 0.0, (k, power)
                    sliding_checked += 1
    assert sliding_checked > 100


def test_the_same_commands_give_the_same_trajectory_bit_for_bit(make_sim):
    runs = []
    for _ in range(2):
        sim = make_sim("farm_2wd", "field_loam", "linear", multi_pass=True)
        sim.reset(0.0, 0.0, 0.0)
        runs.append(turn_and_stop(sim))
    assert np.array_equal(runs[0], runs[1])


class PythonJanosi:
    """A user's force law: slipenv's Janosi kernel behind a Python function (no
    ``kernel_constants``), so the loop calls it back instead of running the C law."""

    def __init__(self, model: JanosiForceModel) -> None:
        self.model = model
        self.geometry = model.geometry
        self.rolling_resistance_coeff = model.rolling_resistance_coeff
        self.calls = 0

    def scalar_kernel(self, soil):
        inner = wheel_kernel(self.model, soil)

        def kernel(slip, tan_beta, load_n):
            self.calls += 1
            return inner(slip, tan_beta, load_n)
        return kernel

    def __call__(self, slip, tan_beta, load_n, soil):
        return self.model(slip, tan_beta, load_n, soil)

    def resistance_n(self, load_n, soil):
        return self.model.resistance_n(load_n, soil)


def test_a_users_law_runs_through_the_same_loop_as_slipenvs(make_sim):
    """The loop runs a user's Python law with the same steps as a C law: the same law behind
    Python gives the same trajectory, bit for bit."""
    runs = []
    for wrap in (False, True):
        sim = make_sim("husky", "loose_sand", "janosi")
        # a user's Python law has no slip-sinkage state (the loop keeps it for slipenv's C
        # laws only): compare without it, whatever the wheels' default
        model = JanosiForceModel(sim.force_model.geometry, slip_sinkage=None)
        user = PythonJanosi(model) if wrap else model
        sim.force_model = user  # the injector that reset builds runs it
        sim.reset(0.0, 0.0, 0.0)
        assert sim.injector.force_model is user
        runs.append(turn_and_stop(sim))
    assert user.calls > 1000
    assert np.array_equal(runs[0], runs[1])


def test_an_error_in_a_users_law_is_raised_from_the_substep(make_sim):
    class Broken(PythonJanosi):
        def scalar_kernel(self, soil):
            def kernel(slip, tan_beta, load_n):
                raise RuntimeError("broken law")
            return kernel

    sim = make_sim("husky", "loose_sand", "janosi")
    with pytest.raises(RuntimeError, match="broken law"):
        injector = WheelSoilInjector(sim.client, sim.spec, sim.body, sim.terrain.body_id,
                                     Broken(sim.injector.force_model), sim.injector.soil_map,
                                     sim.dt_s)
        for _ in range(10):
            injector.apply()
            p.stepSimulation(physicsClientId=sim.client)
