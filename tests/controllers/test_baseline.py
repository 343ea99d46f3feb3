"""The env's baseline controller, built from a duck-typed public surface (no simulator)."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np
import pytest

from slipenv.controllers import BASELINE_NAMES, baseline_controller
from slipenv.controllers.baseline import baseline_pole_rps
from slipenv.controllers.pure_pursuit import PurePursuitController
from slipenv.controllers.stanley import StanleyController
from slipenv.controllers.yamauchi import YamauchiController
from slipenv.paths.library import straight


def surface(speed_mps: float = 1.0, dt_s: float = 0.05) -> SimpleNamespace:
    """What an env exposes: vehicle limits, the path, the control period."""
    vehicle = SimpleNamespace(max_speed_mps=2.0, max_yaw_rate_rad_s=1.5)
    return SimpleNamespace(vehicle=vehicle, path=straight(10.0, speed_mps=speed_mps),
                           control_dt_s=dt_s)


def test_the_pole_covers_about_one_vehicle_length_and_is_clipped():
    assert baseline_pole_rps(0.3) == pytest.approx(0.5)  # 0.3 m/s / 0.6 m
    assert baseline_pole_rps(0.05) == pytest.approx(0.15)  # slow tracked vehicle: lower clip
    assert baseline_pole_rps(5.0) == pytest.approx(1.0)  # fast: upper clip


def test_yamauchi_baseline_places_a_triple_pole_for_the_reference_speed():
    ctrl = baseline_controller(surface(speed_mps=0.3))
    assert isinstance(ctrl, YamauchiController) and ctrl.use_feedforward
    roots = np.roots(ctrl.characteristic_polynomial(0.3))
    np.testing.assert_allclose(roots, -0.5, atol=2e-4)  # (s + 0.5)^3 (a triple root)
    assert ctrl.v_max_mps == 2.0 and ctrl.omega_max_rps == 1.5 and ctrl.dt_s == 0.05


def test_every_advertised_name_builds_a_controller_with_predict_and_act():
    kinds = {"yamauchi": YamauchiController, "yamauchi_feedback": YamauchiController,
             "pure_pursuit": PurePursuitController, "stanley": StanleyController}
    assert set(BASELINE_NAMES) == set(kinds)
    obs = np.zeros(12)
    obs[2], obs[10] = 1.0, 1.0  # heading along the path, reference speed 1 m/s
    for name in BASELINE_NAMES:
        ctrl = baseline_controller(surface(), name)
        assert isinstance(ctrl, kinds[name])
        action, _ = ctrl.predict(obs)
        np.testing.assert_array_equal(action, ctrl.act(obs))
        assert action.shape == (2,) and action.dtype == np.float32
    assert baseline_controller(surface(), "yamauchi_feedback").use_feedforward is False


def test_a_gym_style_wrapper_is_unwrapped():
    wrapped = SimpleNamespace(unwrapped=surface(speed_mps=0.3))
    assert baseline_controller(wrapped).k_omega == pytest.approx(3 * 0.5)


def test_unknown_names_and_surfaces_are_clear_errors():
    with pytest.raises(ValueError, match="unknown controller 'mpc'; known controllers: yamauchi"):
        baseline_controller(surface(), "mpc")
    with pytest.raises(TypeError, match="lacks path, control_dt_s"):
        baseline_controller(SimpleNamespace(vehicle=None))
