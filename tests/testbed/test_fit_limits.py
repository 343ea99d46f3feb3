"""fit-soil says when it cannot tell: parameters at a bound or not determined, a soil only from
an accepted law, misses found on the slip x slip angle grid, the side-wall law when the data
need it, and the data's slip-angle definition honoured."""

from __future__ import annotations

import math
import re

import numpy as np
import pytest

from slipenv.terramechanics.models import force_model_by_name
from slipenv.terramechanics.presets import LUNAR_SIMULANT
from slipenv.terramechanics.sidewall import sidewall_force_n
from slipenv.terramechanics.track import slip_sinkage_factor
from slipenv.testbed.bed import REINA_WHEEL, VirtualTestBed, write_trials
from slipenv.testbed.csv_format import read_testbed, write_testbed
from slipenv.testbed.fit import SIDEWALL_LAW, convert_slip_state, fit_law
from slipenv.testbed.report import analyse, describe_misfit
from tests.testbed.conftest import ANGLES_DEG, NOISE_N, SLIPS

SINKAGE0_M = 0.05  # static sinkage of the side-wall data's wheel [m]
UNIT_WEIGHT = 1.6e4  # [N/m^3] dry sand


def sidewall_sinkage_m(slip: float) -> float:
    """The side-wall data's sinkage: Lyasko's slip sinkage on SINKAGE0_M, below the radius."""
    return min(SINKAGE0_M * float(slip_sinkage_factor(slip)), 0.95 * REINA_WHEEL.radius_m)


class ReinaWithSideWall:
    """Reina's law plus the side-wall bulldozing force of a wheel that sinks with slip: a side
    force beyond mu W that no friction law makes."""

    slip_angle_convention = "reina"

    def __init__(self) -> None:
        self.base = force_model_by_name("reina", REINA_WHEEL.geometry())

    def scalar_kernel(self, soil):
        kernel = self.base.scalar_kernel(soil)
        c, phi = float(soil.cohesion_pa), float(soil.friction_angle_rad)

        def with_wall(slip, tan_beta, load_n):
            fx, fy, res = kernel(slip, tan_beta, load_n)
            wall = sidewall_force_n(sidewall_sinkage_m(slip), REINA_WHEEL.radius_m, c, phi,
                                    UNIT_WEIGHT)
            return fx, fy - math.copysign(wall, tan_beta) if tan_beta else fy, res
        return with_wall

    def __call__(self, slip, tan_beta, load_n, soil):
        k = self.scalar_kernel(soil)
        out = np.array([k(s, t, w)[:2] for s, t, w in np.broadcast(slip, tan_beta, load_n)])
        return out[:, 0], out[:, 1]

    def resistance_n(self, load_n, soil):
        return self.base.resistance_n(load_n, soil)


def _sweep(model, convention, slips=SLIPS, angles=ANGLES_DEG):
    with VirtualTestBed(model, LUNAR_SIMULANT) as bed:
        return bed.sweep(slips, angles, convention=convention)


def _reina():
    return force_model_by_name("reina", REINA_WHEEL.geometry())


@pytest.fixture(scope="module")
def reina_convention_dir(tmp_path_factory):
    """Reina's law on the bed, slip angles imposed in Reina's definition (tan beta = v_lat/v_x)."""
    return write_trials(tmp_path_factory.mktemp("reina_conv"), _sweep(_reina(), "reina"),
                        REINA_WHEEL, noise_n=NOISE_N, seed=5, slip_angle_definition="reina")


@pytest.fixture(scope="module")
def sidewall_dir(tmp_path_factory):
    """Reina + side wall on the bed; the rows carry the wheel's sinkage, as real rigs record."""
    trials = _sweep(ReinaWithSideWall(), "reina")
    rng = np.random.default_rng(7)
    rows = []
    for t in trials:
        ex, ey = rng.normal(0.0, NOISE_N, 2)
        rows.append({"slip_ratio": t.slip_ratio, "slip_angle_deg": t.slip_angle_deg,
                     "normal_load_n": t.normal_load_n, "fx_n": t.fx_n + ex, "fy_n": t.fy_n + ey,
                     "sinkage_m": sidewall_sinkage_m(t.law_slip),
                     "fx_std_n": math.hypot(t.fx_std_n, NOISE_N),
                     "fy_std_n": math.hypot(t.fy_std_n, NOISE_N)})
    meta = {"wheel_radius_m": REINA_WHEEL.radius_m, "wheel_width_m": REINA_WHEEL.width_m,
            "contact_length_m": REINA_WHEEL.contact_length_m, "slip_angle_definition": "reina"}
    return write_testbed(tmp_path_factory.mktemp("sidewall"), rows, meta)


class SideForceKeepsWithSlip(ReinaWithSideWall):
    """Reina's F_x, but a side force that does not fall with slip (F_y at s = 0): a miss of
    Reina's combined slip that grows with the slip ratio at every slip angle."""

    def scalar_kernel(self, soil):
        kernel = self.base.scalar_kernel(soil)

        def keeps(slip, tan_beta, load_n):
            fx, _, res = kernel(slip, tan_beta, load_n)
            return fx, kernel(0.0, tan_beta, load_n)[1], res
        return keeps


def _three_trials_dir(tmp_path, angle_deg):
    trials = _sweep(_reina(), "reina", slips=(0.1, 0.3, 0.6), angles=(angle_deg,))
    return write_trials(tmp_path, trials, REINA_WHEEL, noise_n=NOISE_N, seed=5,
                        slip_angle_definition="reina")


# -- parameters at a bound, parameters not determined --------------------------------------
def test_a_parameter_at_a_search_bound_gets_no_standard_error_and_rejects_the_soil(
        peaked_bed_dir):
    """A traction peak Janosi cannot make drives its shear modulus to the 0.1 mm bound."""
    data = read_testbed(peaked_bed_dir)
    fit = fit_law("janosi", data, LUNAR_SIMULANT)
    assert fit.parameter_status()["shear_modulus_m"] == "at bound"
    assert fit.parameters()["shear_modulus_m"] == [pytest.approx(1e-4), None]
    assert fit.parameter_status()["friction_angle_rad"] == "determined"
    report, _ = analyse(data, LUNAR_SIMULANT, laws=("janosi",))
    assert not report["accepted"] and "soil" not in report
    assert report["rejected_soil"]["shear_modulus_m"] == pytest.approx(1e-4)
    assert any("shear_modulus_m" in w and "bound" in w for w in report["warnings"])


def test_three_trials_at_zero_slip_angle_leave_the_lateral_parameters_not_determined(tmp_path):
    data = read_testbed(_three_trials_dir(tmp_path, 0.0))
    fit = fit_law("reina", data, LUNAR_SIMULANT)
    status = fit.parameter_status()
    # F_y = 0 at beta = 0 whatever C_y and A_y: the Jacobian cannot see them.
    assert status["c_y_n"] == status["a_y"] == "not determined"
    assert fit.parameters()["c_y_n"][1] is None and fit.parameters()["a_y"][1] is None
    # Three F_x points for mu, C_x, A_x: mu runs to its bound rather than being measured.
    assert status["mu"] == "at bound"
    report, _ = analyse(data, LUNAR_SIMULANT, folds=3, laws=("reina",))
    from slipenv.testbed.cli import _markdown
    text = _markdown(report)
    assert "c_y_n = not determined" in text and "a_y = not determined" in text
    assert not re.search(r"± 0(\.0*)?[ ,|]", text), text
    assert not report["accepted"]


def test_the_linear_law_in_its_linear_range_determines_only_tan_phi_over_k(janosi_bed_dir):
    """Below saturation Lindgren Eq. 24 is (A c + W tan phi) s L/(2K): phi and K trade off."""
    fit = fit_law("linear", read_testbed(janosi_bed_dir), LUNAR_SIMULANT)
    assert fit.parameter_status() == {"friction_angle_rad": "not determined",
                                      "shear_modulus_m": "not determined"}
    assert np.all(np.isinf(fit.std_errors))


def test_the_generating_law_is_accepted_and_its_soil_written(reina_bed_dir):
    report, _ = analyse(read_testbed(reina_bed_dir), LUNAR_SIMULANT)
    assert report["accepted"] and report["warnings"] == []
    assert "rejected_soil" not in report and report["soil"]["mu"] == pytest.approx(0.6, rel=0.05)
    assert set(report["laws"]["reina"]["parameter_status"].values()) == {"determined"}


# -- the slip x slip angle grid ------------------------------------------------------------
def test_the_verdict_names_the_slip_ratio_and_slip_angle_of_the_largest_miss(tmp_path):
    data = read_testbed(write_trials(tmp_path, _sweep(SideForceKeepsWithSlip(), "reina"),
                                     REINA_WHEEL, noise_n=NOISE_N, seed=5,
                                     slip_angle_definition="reina"))
    misfit = describe_misfit(fit_law("reina", data, LUNAR_SIMULANT), data)
    cells = [c for c in misfit["fy_vs_slip_and_angle"] if c["systematic"]]
    worst = max(cells, key=lambda c: abs(c["mean_residual_n"]))
    # The side force misses most at the largest slip ratios, where Reina's combined slip
    # takes it away and the data keep it.
    assert worst["slip"] > 0.45
    assert -worst["mean_residual_n"] > 4.0 * NOISE_N  # measured |F_y| above the law
    grid = [f for f in misfit["findings"] if "slip x slip angle grid" in f and "|F_y|" in f]
    assert grid and f"at slip {worst['slip']:.3g} and slip angle" in grid[0]
    assert "lies above the law" in grid[0]


# -- the side-wall law ---------------------------------------------------------------------
def test_side_wall_data_get_the_side_wall_law_which_recovers_the_unit_weight(sidewall_dir):
    data = read_testbed(sidewall_dir)
    assert np.max(np.abs(data.fy_n) / data.normal_load_n) > LUNAR_SIMULANT.mu  # beyond mu W
    report, fits = analyse(data, LUNAR_SIMULANT)
    assert report["sidewall_offered"] and report["best"] == SIDEWALL_LAW
    assert report["law_is_adequate"]
    gamma, se = report["laws"][SIDEWALL_LAW]["parameters"]["unit_weight_n_m3"]
    assert abs(gamma - UNIT_WEIGHT) < 3.0 * se and se < 0.05 * UNIT_WEIGHT
    assert fits[SIDEWALL_LAW].parameters()["mu"][0] == pytest.approx(LUNAR_SIMULANT.mu, rel=0.05)
    # Every friction law misses it by far more than the noise.
    for law in ("janosi", "reina", "linear"):
        assert report["laws"][law]["heldout_over_noise"] > 10.0
    # The simulation has no side-wall force: the soil is not accepted for it.
    assert not report["accepted"] and "soil" not in report
    assert any("side-wall" in w for w in report["warnings"])


def test_the_side_wall_law_is_not_offered_to_data_friction_explains(reina_bed_dir):
    report, _ = analyse(read_testbed(reina_bed_dir), LUNAR_SIMULANT)
    assert not report["sidewall_offered"] and SIDEWALL_LAW not in report["laws"]


# -- the slip-angle definition of meta.json ------------------------------------------------
def test_convert_slip_state_follows_each_definitions_velocities():
    s, tan_r = np.array([0.4, 0.4, -0.3, 0.9]), np.array([0.5, -0.2, 0.5, 2.0])
    # Driving: v_x = (1 - s) r omega, so v_lat/(r omega) = (1 - s) tan beta_Reina.
    s_sim, t_sim = convert_slip_state(s[:3], tan_r[:3], "reina", "simulation")
    np.testing.assert_allclose(t_sim, [0.3, -0.12, 0.5])  # braking: v is the reference
    np.testing.assert_allclose(s_sim, s[:3])
    back = convert_slip_state(s_sim, t_sim, "simulation", "reina")
    np.testing.assert_allclose(back[1], tan_r[:3])
    # Beyond 45 deg (tan beta = 2: v_lat = 0.2 > v_x = 0.1 r omega) Reina's state is +-1,
    # the simulation's clip, and the slip keeps its reference r omega.
    s4, t4 = convert_slip_state(s[3:], tan_r[3:], "reina", "reina")
    np.testing.assert_allclose((s4, t4), ([0.9], [1.0]))
    with pytest.raises(ValueError, match="45 deg"):
        convert_slip_state([0.1], [1.2], "simulation", "reina")


def _recovered(directory) -> dict:
    fit = fit_law("reina", read_testbed(directory), LUNAR_SIMULANT)
    return {n: abs(v - getattr(LUNAR_SIMULANT, n)) / e
            for n, (v, e) in fit.parameters().items() if n in ("mu", "c_x_n", "c_y_n")}


def test_trials_in_reinas_definition_recover_reinas_parameters(reina_convention_dir):
    assert read_testbed(reina_convention_dir).meta["slip_angle_definition"] == "reina"
    assert all(z < 3.0 for z in _recovered(reina_convention_dir).values())


def test_trials_in_the_simulations_definition_recover_reinas_parameters(reina_bed_dir):
    assert read_testbed(reina_bed_dir).meta["slip_angle_definition"] == "simulation"
    assert all(z < 3.0 for z in _recovered(reina_bed_dir).values())


def test_a_wrong_slip_angle_definition_in_meta_json_is_not_fitted_away(reina_convention_dir,
                                                                       tmp_path):
    """The same trials declared in the other definition: the law misses them."""
    data = read_testbed(reina_convention_dir)
    rows = [{"slip_ratio": s, "slip_angle_deg": b, "normal_load_n": w, "fx_n": fx, "fy_n": fy,
             "fx_std_n": ex, "fy_std_n": ey}
            for s, b, w, fx, fy, ex, ey in zip(data.slip_ratio, data.slip_angle_deg,
                                               data.normal_load_n, data.fx_n, data.fy_n,
                                               data.fx_std_n, data.fy_std_n, strict=True)]
    meta = {k: data.meta[k] for k in ("wheel_radius_m", "wheel_width_m", "contact_length_m")}
    wrong = write_testbed(tmp_path, rows, {**meta, "slip_angle_definition": "simulation"})
    right, _ = analyse(data, LUNAR_SIMULANT, laws=("reina",))
    report, _ = analyse(read_testbed(wrong), LUNAR_SIMULANT, laws=("reina",))
    assert right["law_is_adequate"] and right["heldout_over_noise"] < 1.5
    assert not report["law_is_adequate"] and report["heldout_over_noise"] > 3.0
