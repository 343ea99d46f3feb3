"""Yamauchi §3 law: gain validation, stability of the linearised loop, the feed-forward term."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

from slipenv.contracts.observation import (
    OBS_CROSS_TRACK,
    OBS_CURVATURE,
    OBS_DIM,
    OBS_HEADING_ERROR,
    OBS_REF_SPEED,
    OBS_SLIP_ANGLE,
    OBS_SPEED,
    OBS_YAW_RATE,
)
from slipenv.controllers import YamauchiController, is_hurwitz


def test_default_gains_give_a_hurwitz_polynomial_at_every_speed_up_to_v_max(scaling):
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # the defaults must construct without warnings
        ctrl = YamauchiController(**scaling)
    for v in np.linspace(0.01, ctrl.v_max_mps, 50):
        poly = ctrl.characteristic_polynomial(v)
        assert is_hurwitz(poly)
        # Routh-Hurwitz for s^3 + a s^2 + b s + c: all positive and a b > c.
        assert poly[1] * poly[2] > poly[3] > 0.0


def test_from_poles_places_a_triple_pole():
    ctrl = YamauchiController.from_poles(0.8, 0.5, v_max_mps=1.0, omega_max_rps=1.0, dt_s=0.05)
    roots = np.roots(ctrl.characteristic_polynomial(0.5))
    np.testing.assert_allclose(roots, -0.8, atol=1e-4)  # a triple root is ill-conditioned
    assert ctrl.k_eta == pytest.approx(0.8**3 / 0.5)


def test_unstable_gains_warn_and_hurwitz_detects_them():
    with pytest.warns(RuntimeWarning, match="unstable"):
        ctrl = YamauchiController(v_max_mps=2.0, omega_max_rps=1.0, dt_s=0.05, k_eta=10.0,
                                  k_phi=1.0, k_omega=1.0)
    assert not is_hurwitz(ctrl.characteristic_polynomial(2.0))
    with pytest.warns(RuntimeWarning, match="too fast"):
        YamauchiController(v_max_mps=1.0, omega_max_rps=1.0, dt_s=0.5)


@pytest.mark.parametrize("argument", ["k_eta", "k_phi", "k_omega"])
@pytest.mark.parametrize("value", [0.0, -1.0, math.nan, math.inf])
def test_invalid_gains_raise_value_error_naming_the_gain(scaling, argument, value):
    with pytest.raises(ValueError, match=argument):
        YamauchiController(**scaling, **{argument: value})


@pytest.mark.parametrize("argument", ["v_max_mps", "omega_max_rps", "dt_s"])
def test_invalid_scaling_raises_value_error_naming_the_argument(scaling, argument):
    with pytest.raises(ValueError, match=argument):
        YamauchiController(**{**scaling, argument: 0.0})


def _on_path_obs(phi: float, beta_hat: float) -> np.ndarray:
    """Vehicle on a 4 m circle at 1 m/s, turning at the path's rate, heading error ``phi``."""
    obs = np.zeros(OBS_DIM)
    obs[[OBS_SPEED, OBS_REF_SPEED, OBS_CURVATURE, OBS_YAW_RATE]] = 1.0, 1.0, 0.25, 0.25
    obs[OBS_HEADING_ERROR], obs[OBS_SLIP_ANGLE], obs[OBS_CROSS_TRACK] = phi, beta_hat, 0.0
    return obs


def test_feedforward_holds_the_crab_angle_that_cancels_the_slip(scaling):
    # With course = yaw + β along the path, φ = -β: Eq. 10 then commands no change of ω,
    # while the conventional Eq. 9 turns the vehicle back to φ = 0 (and off the path).
    beta = 0.2
    ff = YamauchiController(**scaling)
    fb = YamauchiController(use_feedforward=False, **scaling)
    a_ff, a_fb = ff.act(_on_path_obs(-beta, beta)), fb.act(_on_path_obs(-beta, beta))
    assert a_ff[1] * ff.omega_max_rps == pytest.approx(0.25, abs=1e-6)  # stays at v κ
    expected = 0.25 + fb.k_phi * beta * fb.dt_s  # one step of ω' = -k_φ φ
    assert a_fb[1] * fb.omega_max_rps == pytest.approx(expected, abs=1e-6)


def test_yaw_rate_command_starts_from_the_path_rate_and_is_clipped(scaling):
    ctrl = YamauchiController(**scaling)
    obs = _on_path_obs(0.0, 0.0)
    obs[[OBS_SPEED, OBS_YAW_RATE]] = 0.0, 0.0  # at rest on a curved path
    assert ctrl.act(obs)[1] * ctrl.omega_max_rps == pytest.approx(0.25)
    obs[OBS_CROSS_TRACK] = 1e3  # far off: saturates instead of winding up
    for _ in range(50):
        action = ctrl.act(obs)
    assert action[1] == pytest.approx(-1.0)
    obs[OBS_CROSS_TRACK], obs[OBS_YAW_RATE] = 0.0, -ctrl.omega_max_rps  # turning hard right
    assert ctrl.act(obs)[1] > -0.9  # leaves saturation at once: the integrator did not wind up
