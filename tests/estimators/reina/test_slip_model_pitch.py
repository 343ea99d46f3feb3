"""The pitch term of s_x(β, θ) (Reina §3.3, Eq. 12 with s_x0 following the climb angle)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from slipenv.estimators.reina import SlipRatioModel, fit_slip_ratio_model
from slipenv.terramechanics.presets import soil_by_name
from slipenv.testbed.slip_curve import slip_ratio_for_slope


def test_pitch_term_is_linear_in_tan_climb_about_the_reference() -> None:
    m = SlipRatioModel(0.2, 1.0, math.radians(4.0), k_pitch=2.0, pitch_ref_rad=math.radians(5.0))
    beta, up, flat = math.radians(10.0), math.radians(8.0), math.radians(5.0)
    assert m(beta, flat) == pytest.approx(0.2 + math.radians(6.0))
    assert m(beta, up) == pytest.approx(m(beta, flat) + 2.0 * (math.tan(up) - math.tan(flat)))
    assert m(beta) == pytest.approx(m(beta, flat))  # no pitch: the reference climb
    np.testing.assert_allclose(m([beta, beta], [math.nan, up]), [m(beta, flat), m(beta, up)])
    assert SlipRatioModel(0.2, 1.0)(beta, up) == pytest.approx(0.2 + beta)  # k_θ = 0: Eq. 12


def test_fit_to_the_force_law_at_several_pitches_gives_the_inverse_traction_slope() -> None:
    # Reina §3.3: s_x0 solves F_x0(s)/N = tan θ (Eq. 5), so d s_x0/d tan θ = 1/f'(s_x0) with
    # f'(s) = (C_x/N) e^{-C_x s/(μ N)} - A_x, C_x/N the law's stiffness per unit load.
    soil = soil_by_name("loose_sand")
    beta = np.radians(np.linspace(0.0, 15.0, 16))
    climbs_deg = np.linspace(3.0, 7.0, 9)
    b, th, s = [], [], []
    for c in climbs_deg:
        b.append(beta)
        th.append(np.full(beta.size, math.radians(c)))
        s.append(slip_ratio_for_slope(beta, c, soil))
    b, th, s = np.concatenate(b), np.concatenate(th), np.concatenate(s)
    fit = fit_slip_ratio_model(b, s, pitch_rad=th)
    m = fit.model
    s_ref = float(slip_ratio_for_slope([0.0], math.degrees(m.pitch_ref_rad), soil)[0])
    c_x = soil.c_x_n / soil.reference_load_n
    k_closed = 1.0 / (c_x * math.exp(-c_x * s_ref / soil.mu) - soil.a_x)
    assert m.pitch_ref_rad == pytest.approx(math.radians(5.0), abs=math.radians(0.05))
    assert m.s_x0 == pytest.approx(s_ref, abs=0.004)
    assert m.k_pitch == pytest.approx(k_closed, rel=0.03)
    np.testing.assert_allclose(m(b, th), s, atol=0.006)
    # Over these 4° the law's s_x0 moves by more than 0.15: Eq. 12 without pitch cannot follow.
    assert (slip_ratio_for_slope([0.0], 7.0, soil) - slip_ratio_for_slope([0.0], 3.0, soil)
            )[0] > 0.15


def test_fit_recovers_a_known_pitch_gain_from_noisy_samples() -> None:
    rng = np.random.default_rng(7)
    truth = SlipRatioModel(0.25, 0.9, math.radians(3.0), k_pitch=2.4,
                           pitch_ref_rad=math.radians(5.0))
    beta = rng.uniform(-math.radians(20.0), math.radians(20.0), 400)
    climb = math.radians(5.0) + rng.normal(0.0, math.radians(3.0), beta.size)
    s = truth(beta, climb) + rng.normal(0.0, 0.02, beta.size)
    fit = fit_slip_ratio_model(beta, s, pitch_rad=climb)
    assert abs(fit.model.k_pitch - 2.4) < 4.0 * fit.k_pitch_std_error
    assert fit.model.k_pitch == pytest.approx(2.4, rel=0.08)
    # θ_ref is the samples' mean climb: s_x0 is the slip there, not at 5° exactly.
    assert fit.model.s_x0 == pytest.approx(float(truth(0.0, fit.model.pitch_ref_rad)), abs=0.006)
    assert fit.model.k_per_rad == pytest.approx(0.9, rel=0.1)
    assert fit.rms == pytest.approx(0.02, rel=0.15)
    assert math.isnan(fit_slip_ratio_model(beta, s).k_pitch_std_error)


@pytest.mark.parametrize(("kwargs", "name"), [({"k_pitch": math.inf}, "k_pitch"),
                                              ({"pitch_ref_rad": 2.0}, "pitch_ref_rad")])
def test_bad_pitch_parameters_name_the_field(kwargs: dict, name: str) -> None:
    with pytest.raises(ValueError, match=name):
        SlipRatioModel(0.1, 1.0, **kwargs)


def test_fit_rejects_pitches_of_the_wrong_length_or_not_finite() -> None:
    beta, s = np.linspace(0.0, 0.3, 6), np.linspace(0.1, 0.3, 6)
    with pytest.raises(ValueError, match="pitch_rad"):
        fit_slip_ratio_model(beta, s, pitch_rad=np.zeros(5))
    with pytest.raises(ValueError, match="pitch_rad"):
        fit_slip_ratio_model(beta, s, pitch_rad=np.full(6, np.nan))
