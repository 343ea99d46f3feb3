"""The virtual single-wheel test bed (Reina §3): forces at the carriage against the law."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np
import pytest

from slipenv.terramechanics.models import ReinaForceModel
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
    model = ReinaForceModel(REINA_WHEEL.geometry(), rolling_resistance_coeff=0.0)
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


def test_carriage_forces_reproduce_the_law_within_5_percent(sweep):
    """Slips 0.05-0.6, slip angles 0-25 deg (simulation convention): Reina Eq. 5-9."""
    for t in sweep:
        assert t.law_tan_beta == pytest.approx(math.tan(math.radians(t.slip_angle_deg)),
                                               abs=1e-3)
        fx, fy = law(t.slip_ratio, math.tan(math.radians(t.slip_angle_deg)), t.normal_load_n)
        assert t.fx_n == pytest.approx(fx, rel=0.05), t
        assert t.fy_n == pytest.approx(fy, rel=0.05, abs=0.05), t


def test_at_small_slip_the_bed_matches_reinas_law_at_the_imposed_slip_angle(reina_sweep):
    for t in reina_sweep:
        if t.slip_ratio == 0.05:
            fx, fy = law(t.slip_ratio, math.tan(math.radians(t.slip_angle_deg)), t.normal_load_n)
            assert (t.fx_n, t.fy_n) == pytest.approx((fx, fy), rel=0.05, abs=0.05), t


@pytest.mark.xfail(strict=True, reason=(
    "known modelling defect, kept visible: slip_dynamics.relax_slip relaxes tan(beta) to "
    "v_lat / max(|r omega|, |v_x|), which is v_lat/(r omega) in drive, not Reina's v_lat/v_x "
    "(Eq. 4); at large slip the bed's side force therefore falls short of the law at the "
    "imposed angle (small slips match within 5 %, test above). The state equation is right "
    "for the isotropic Janosi law (it keeps (s, tan beta) along the sliding velocity); the "
    "fix belongs in the Reina law's input (v_lat/v_x from the state), which moves the rover's "
    "lateral dynamics and the Reina reproduction, so it waits for a change that re-runs them"))
def test_at_large_slip_the_bed_matches_reinas_law_at_the_imposed_slip_angle(reina_sweep):
    for t in reina_sweep:
        fx, fy = law(t.slip_ratio, math.tan(math.radians(t.slip_angle_deg)), t.normal_load_n)
        assert (t.fx_n, t.fy_n) == pytest.approx((fx, fy), rel=0.05, abs=0.05), t


def test_lateral_slip_costs_traction_and_traction_costs_side_force(sweep):
    """Reina Figs. 9-11: F_x falls with slip angle at a given slip, |F_y| with slip."""
    fx = np.array([t.fx_n for t in sweep]).reshape(len(ANGLES_DEG), len(SLIPS))
    fy = np.array([t.fy_n for t in sweep]).reshape(len(ANGLES_DEG), len(SLIPS))
    assert np.all(np.diff(fx, axis=1) > 0)   # F_x grows with slip at every angle
    assert np.all(np.diff(fx, axis=0) < 0)   # ... and falls with slip angle (Fig. 9)
    assert np.all(np.diff(np.abs(fy[1:]), axis=1) < 0)  # |F_y| falls with slip (Fig. 10)
    assert np.all(np.diff(-fy, axis=0) > 0)  # and grows with slip angle (Fig. 8)


def test_saturated_traction_follows_eq_10_for_small_a_x():
    """Eq. 10: F_x -> mu W / sqrt(1 + tan^2 beta) as s -> 1 when A_x ~ 0.

    A stiff soil (C_x = 20 mu W) saturates the exponential of Eq. 5 well before s = 1.
    """
    soil = replace(LUNAR_SIMULANT, a_x=0.0, a_y=0.0, c_x_n=800.0, c_y_n=800.0)
    model = ReinaForceModel(REINA_WHEEL.geometry(), rolling_resistance_coeff=0.0)
    with VirtualTestBed(model, soil) as bed:
        for angle in (0.0, 10.0, 25.0):
            t = bed.trial(0.99, angle, convention="simulation")
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
        trials = bed.sweep((0.1, 0.4), (0.0, 10.0, 25.0), convention="simulation")
    path = plot_reina_figures(trials, tmp_path)
    assert path.name == "reina_figs_7_11.png" and path.stat().st_size > 20_000
