"""The virtual single-wheel test bed (Reina §3): forces at the carriage against the law."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from slipenv.terramechanics.models import JanosiForceModel, ReinaForceModel
from slipenv.terramechanics.presets import LUNAR_SIMULANT
from slipenv.terramechanics.reina import reina_forces, reina_max_longitudinal_force_n
from slipenv.testbed.bed import REINA_WHEEL, BedWheel, VirtualTestBed

SOIL = LUNAR_SIMULANT.params()
SLIPS = (0.05, 0.2, 0.4, 0.6)
ANGLES_DEG = (0.0, 5.0, 15.0, 25.0)


def law(slip: float, tan_beta: float, load_n: float) -> tuple[float, float]:
    """Reina Eq. 5-9 with the load-scaled stiffness the model uses."""
    k = load_n / SOIL.reference_load_n
    return reina_forces(slip, tan_beta, load_n, SOIL.mu, SOIL.c_x_n * k, SOIL.c_y_n * k,
                        SOIL.a_x, SOIL.a_y)


def run_sweep(convention: str):
    # The law alone: no rolling resistance, no slip-sinkage state (Reina's Table 3 is a net
    # law measured on a wheel that sank as it slipped).
    model = ReinaForceModel(REINA_WHEEL.geometry(), rolling_resistance_coeff=0.0,
                            slip_sinkage=None)
    with VirtualTestBed(model, LUNAR_SIMULANT) as bed:
        return bed.sweep(SLIPS, ANGLES_DEG, convention=convention)


@pytest.fixture(scope="module")
def sweep():
    return run_sweep("simulation")


@pytest.fixture(scope="module")
def reina_sweep():
    return run_sweep("reina")


def test_bed_carries_the_set_vertical_load(sweep):
    for t in sweep:
        assert t.normal_load_n == pytest.approx(REINA_WHEEL.load_n, rel=0.01)


def test_bed_imposes_the_slip_ratio(sweep):
    for t in sweep:
        assert t.law_slip == pytest.approx(t.slip_ratio, abs=1e-3)


def test_carriage_forces_reproduce_reinas_law_within_5_percent_in_reinas_convention(reina_sweep):
    """Slips 0.05-0.6, slip angles 0-25 deg imposed as Reina's rig does, tan(beta) = v_lat/v_x
    (Reina Eq. 4): the wheel's law sees that slip angle, and the forces at the carriage are
    Reina Eq. 5-9 at the imposed (s, beta) within 5 %. At s = 0.6 the sliding-velocity slip
    angle would be 0.4 tan(beta) and the side force about 40 % of the law."""
    for t in reina_sweep:
        tan_b = math.tan(math.radians(t.slip_angle_deg))
        assert t.law_tan_beta == pytest.approx(tan_b, rel=0.01, abs=1e-4), t
        fx, fy = law(t.slip_ratio, tan_b, t.normal_load_n)
        assert (t.fx_n, t.fy_n) == pytest.approx((fx, fy), rel=0.05, abs=0.05), t


def test_in_the_sliding_velocity_convention_reinas_law_sees_tan_beta_over_one_minus_slip(sweep):
    """A trial imposed with tan(beta) = v_lat/(r omega) (the shear laws' convention) has
    v_lat/v_x = tan(beta)/(1 - s): Reina's law is evaluated there, not at tan(beta), up to
    the state's saturation at 45 deg (s = 0.6, 25 deg: v_lat/v_x = 1.17, the law sees 1)."""
    for t in sweep:
        tan_reina = math.tan(math.radians(t.slip_angle_deg)) / (1.0 - t.slip_ratio)
        tan_reina = min(tan_reina, 1.0)
        assert t.law_tan_beta == pytest.approx(tan_reina, rel=0.01, abs=1e-4), t
        fx, fy = law(t.slip_ratio, tan_reina, t.normal_load_n)
        assert (t.fx_n, t.fy_n) == pytest.approx((fx, fy), rel=0.05, abs=0.05), t


def test_the_janosi_law_takes_the_sliding_velocity_slip_angle():
    """The shear law's slip angle is v_lat/(r omega) (its shear displacement per unit patch
    length): (1 - s) tan(beta) for a trial imposed in Reina's convention."""
    model = JanosiForceModel(REINA_WHEEL.geometry())
    with VirtualTestBed(model, LUNAR_SIMULANT) as bed:
        for slip, angle in ((0.4, 15.0), (0.0, 10.0)):
            t = bed.trial(slip, angle, convention="reina")
            want = (1.0 - slip) * math.tan(math.radians(angle))
            assert t.law_tan_beta == pytest.approx(want, rel=0.01), t
            t = bed.trial(slip, angle, convention="simulation")
            assert t.law_tan_beta == pytest.approx(math.tan(math.radians(angle)), rel=0.01), t


def test_lateral_slip_costs_traction_and_traction_costs_side_force(reina_sweep):
    """Reina Figs. 9-11: F_x falls with slip angle at a given slip, |F_y| with slip."""
    fx = np.array([t.fx_n for t in reina_sweep]).reshape(len(ANGLES_DEG), len(SLIPS))
    fy = np.array([t.fy_n for t in reina_sweep]).reshape(len(ANGLES_DEG), len(SLIPS))
    assert np.all(np.diff(fx, axis=1) > 0)   # F_x grows with slip at every angle
    assert np.all(np.diff(fx, axis=0) < 0)   # ... and falls with slip angle (Fig. 9)
    assert np.all(np.diff(np.abs(fy[1:]), axis=1) < 0)  # |F_y| falls with slip (Fig. 10)
    assert np.all(np.diff(-fy, axis=0) > 0)  # and grows with slip angle (Fig. 8)


def test_saturated_traction_follows_eq_10_for_small_a_x():
    """Eq. 10: F_x -> mu W / sqrt(1 + tan^2 beta) as s -> 1 when A_x ~ 0.

    A stiff soil (C_x = 20 mu W) saturates the exponential of Eq. 5 well before s = 1.
    """
    soil = replace(LUNAR_SIMULANT, a_x=0.0, a_y=0.0, c_x_n=800.0, c_y_n=800.0)
    model = ReinaForceModel(REINA_WHEEL.geometry(), rolling_resistance_coeff=0.0,
                            slip_sinkage=None)  # the law alone
    with VirtualTestBed(model, soil) as bed:
        for angle in (0.0, 10.0, 25.0):
            t = bed.trial(0.99, angle, convention="reina")
            f_max = float(reina_max_longitudinal_force_n(math.tan(math.radians(angle)),
                                                         t.normal_load_n, SOIL.mu))
            assert t.fx_n == pytest.approx(f_max, rel=0.02), t


def test_bed_rejects_bad_trials():
    model = ReinaForceModel(REINA_WHEEL.geometry())
    with VirtualTestBed(model, LUNAR_SIMULANT) as bed:
        with pytest.raises(ValueError, match="slip_ratio"):
            bed.trial(1.2, 0.0)
        with pytest.raises(ValueError, match="slip_angle_deg"):
            bed.trial(0.2, 95.0)
    with pytest.raises(ValueError, match="BedWheel.load_n"):
        BedWheel(load_n=-1.0)


def test_figures_7_to_11_are_drawn_from_a_bed_sweep(tmp_path):
    from slipenv.testbed.figures import plot_reina_figures

    model = ReinaForceModel(REINA_WHEEL.geometry(), rolling_resistance_coeff=0.0)
    with VirtualTestBed(model, LUNAR_SIMULANT) as bed:
        trials = bed.sweep((0.1, 0.4), (0.0, 10.0, 25.0), convention="reina")
    path = plot_reina_figures(trials, tmp_path)
    assert path.name == "reina_figs_7_11.png" and path.stat().st_size > 20_000
