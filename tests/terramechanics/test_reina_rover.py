"""Reina's law is the net force: the rover's slip on flat ground and on Reina's 12 deg slope.

Reina fitted Eq. 5 to the net force the test bed measured, so a rover driving steadily needs
sum F_x(s) = m g sin(theta) + f_r m g cos(theta). With the load-scaled law F_x = W f(s) and all
four wheels at one slip, f(s) = tan(theta) + f_r: the slip follows from Eq. 5 alone. Before the
fix (Bekker compaction added on top of the net law) the rover slipped 46 % on flat ground.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.optimize import brentq

from slipenv.envs.factory import make_force_model, make_soil_map, make_vehicle
from slipenv.sim.simulator import Simulator
from slipenv.terrain.terrain import TerrainSpec
from slipenv.terramechanics.bekker import compaction_resistance_n, wheel_sinkage_m
from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import ReinaForceModel
from slipenv.terramechanics.presets import LUNAR_SIMULANT
from slipenv.terramechanics.reina import reina_reference_force_n
from slipenv.vehicles.kinematics import twist_to_commands

SOIL = LUNAR_SIMULANT.params()
SPEED_MPS = 0.08  # Reina §5: about 8 cm/s


def eq5_slip(slope_deg: float, rolling_coeff: float) -> float:
    """Slip s with f(s) = F_x0(s)/W = tan(theta) + f_r (Reina Eq. 5 at unit load, C/W_ref)."""
    need = math.tan(math.radians(slope_deg)) + rolling_coeff
    c_unit = SOIL.c_x_n / SOIL.reference_load_n

    def excess(s: float) -> float:
        return float(reina_reference_force_n(s, 1.0, SOIL.mu, c_unit, SOIL.a_x)) - need
    return brentq(excess, 1e-9, 1.0, xtol=1e-12)


def steady_rover_slip(slope_deg: float) -> tuple[float, ReinaForceModel]:
    spec = make_vehicle("rover_4ws")
    model = make_force_model("reina", spec)
    terrain = (TerrainSpec(kind="slope", slope_deg=slope_deg, downhill_azimuth_deg=180.0)
               if slope_deg else TerrainSpec())
    sim = Simulator(spec, terrain, model, make_soil_map("lunar_simulant", None))
    try:
        sim.reset(0.0, 0.0, 0.0)  # facing +x: uphill
        speeds, steer = twist_to_commands(spec, SPEED_MPS, 0.0)
        slips = []
        for i in range(int(round(10.0 / sim.control_dt_s))):
            sim.step(speeds, steer)
            if i * sim.control_dt_s >= 5.0:  # steady state
                slips.append(sim.injector.contact_state().slip)
        return float(np.mean(slips)), model
    finally:
        sim.close()


@pytest.mark.parametrize("slope_deg", [0.0, 12.0])
def test_rover_steady_slip_agrees_with_reina_eq_5_within_10_percent(slope_deg):
    slip, model = steady_rover_slip(slope_deg)
    expected = eq5_slip(slope_deg, model.rolling_resistance_coeff)
    assert slip == pytest.approx(expected, rel=0.10)


def test_rover_climbs_reinas_12_degree_slope_near_the_commanded_speed():
    slip, _ = steady_rover_slip(12.0)
    assert slip < 0.5  # before the fix: 83 % slip, creeping at 1.3 cm/s


def test_reina_model_adds_no_compaction_by_default():
    wheel = ContactGeometry(radius_m=0.09, width_m=0.11, contact_length_m=0.05)
    load = np.array([30.0, 65.0])
    res = ReinaForceModel(wheel, rolling_resistance_coeff=0.0).resistance_n(load, SOIL)
    np.testing.assert_array_equal(res, 0.0)


def test_reina_compaction_option_uses_the_law_as_gross_thrust():
    """Thrust minus compaction is -R_c at zero slip and Reina's net curve at high slip."""
    wheel = ContactGeometry(radius_m=0.09, width_m=0.11, contact_length_m=0.05)
    net = ReinaForceModel(wheel, rolling_resistance_coeff=0.0).scalar_kernel(SOIL)
    gross = ReinaForceModel(wheel, rolling_resistance_coeff=0.0, compaction=True)
    kernel = gross.scalar_kernel(SOIL)
    w = 65.0
    r_c = float(compaction_resistance_n(
        wheel_sinkage_m(w, 0.11, 0.18, SOIL.k_c, SOIL.k_phi, SOIL.n_exp), 0.11, SOIL.k_c,
        SOIL.k_phi, SOIL.n_exp))
    assert r_c > 1.0
    fx0, _, res0 = kernel(0.0, 0.0, w)
    assert res0 == pytest.approx(r_c, rel=1e-12) and fx0 - res0 == pytest.approx(-r_c)
    fx, _, res = kernel(1.0, 0.0, w)
    y = SOIL.c_x_n / SOIL.reference_load_n / SOIL.mu
    assert fx - res == pytest.approx(net(1.0, 0.0, w)[0] - r_c * math.exp(-y), rel=1e-12)
    assert fx - res < net(1.0, 0.0, w)[0]  # gross - compaction never beats the measured net
