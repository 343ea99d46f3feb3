"""The injected force law, measured in the PyBullet world (a single-wheel test bed)."""

from __future__ import annotations

import numpy as np
import pytest

from slipenv.terramechanics.contact import ContactGeometry
from slipenv.terramechanics.models import force_model_by_name
from slipenv.terramechanics.presets import soil_by_name
from slipenv.terramechanics.soil_map import UniformSoil
from tests.sim.rig import CONTACT_M, RADIUS_M, WIDTH_M, SingleWheelRig

GROUND_SPEED_MPS = 0.08  # Reina's test speed


@pytest.mark.parametrize("model_name", ["reina", "janosi", "linear"])
def test_drawbar_pull_at_fixed_slip_matches_the_force_law_within_5_percent(model_name):
    geometry = ContactGeometry(radius_m=RADIUS_M, width_m=WIDTH_M, contact_length_m=CONTACT_M)
    # the law itself: no slip-sinkage state, whatever the wheels' default
    model = force_model_by_name(model_name, geometry, slip_sinkage=None)
    soil = UniformSoil(soil_by_name("lunar_simulant"))
    params = soil.params_at(np.zeros(1), np.zeros(1))
    rig = SingleWheelRig(model, soil)
    try:
        for slip in (0.02, 0.05, 0.1, 0.2, 0.3, 0.45, 0.6):
            omega = GROUND_SPEED_MPS / (RADIUS_M * (1.0 - slip))
            run = rig.drag(GROUND_SPEED_MPS, omega)
            assert run["slip"] == pytest.approx(slip, abs=1e-3)
            load = np.array([run["load_n"]])
            fx, _ = model(np.array([slip]), np.zeros(1), load, params)
            expected = float(fx[0] - model.resistance_n(load, params)[0])
            # 5 % of the pull, or of the traction where the pull crosses zero.
            tol = 0.05 * max(abs(expected), 0.2 * float(fx[0]))
            assert run["drawbar_pull_n"] == pytest.approx(expected, abs=tol), slip
    finally:
        rig.close()


def test_the_load_seen_at_the_contact_is_the_rig_weight():
    geometry = ContactGeometry(radius_m=RADIUS_M, width_m=WIDTH_M, contact_length_m=CONTACT_M)
    rig = SingleWheelRig(force_model_by_name("reina", geometry),
                         UniformSoil(soil_by_name("loose_sand")))
    try:
        run = rig.drag(0.0, 0.0, seconds=1.0)
        assert run["load_n"] == pytest.approx(rig.load_n, rel=0.01)
    finally:
        rig.close()


def test_a_wheel_spinning_up_on_soft_soil_settles_smoothly_to_full_slip():
    geometry = ContactGeometry(radius_m=RADIUS_M, width_m=WIDTH_M, contact_length_m=CONTACT_M)
    rig = SingleWheelRig(force_model_by_name("janosi", geometry),
                         UniformSoil(soil_by_name("loose_sand")))
    try:
        # Carriage held still, wheel spinning: s -> 1 without division by zero or chatter.
        rig.drag(0.0, 5.0, seconds=0.5, average_s=0.1)
        slips = []
        for _ in range(20):
            slips.append(rig.drag(0.0, 5.0, seconds=0.05, average_s=0.05)["slip"])
        assert np.all(np.isfinite(slips))
        assert slips[-1] == pytest.approx(1.0, abs=1e-3)
        assert np.all(np.diff(slips) >= -1e-9)  # monotone, no oscillation
    finally:
        rig.close()


def test_the_injector_reports_the_soil_and_rolling_radius_under_each_wheel():
    geometry = ContactGeometry(radius_m=RADIUS_M, width_m=WIDTH_M, contact_length_m=CONTACT_M)
    soil = soil_by_name("loose_sand")
    rig = SingleWheelRig(force_model_by_name("janosi", geometry), UniformSoil(soil))
    try:
        assert rig.injector.soil_at_wheel(0) == soil.params()
        assert rig.injector.rolling_radius_m(0) == pytest.approx(
            RADIUS_M * soil.rolling_radius_scale, rel=1e-15)
    finally:
        rig.close()


@pytest.mark.parametrize("option", ["dt_s", "min_relaxation_m", "resistance_stick_m",
                                    "low_speed_mps", "damping_speed_mps", "damping_ratio"])
def test_injector_options_out_of_range_raise_naming_the_option(option):
    from slipenv.sim.wheel_soil import WheelSoilInjector

    kwargs = {"dt_s": 1.0 / 240.0, option: -1.0}
    with pytest.raises(ValueError, match=option):
        WheelSoilInjector(0, None, None, 0, None, None, **kwargs)
