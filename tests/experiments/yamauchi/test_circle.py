"""The oracle gain of the circle: each law's best triple pole of a grid, judged on the laps'
own true maximum error (the quantity that decides whether every lap stays in the corridor)."""

from __future__ import annotations

import pytest

from slipenv.experiments.yamauchi.circle import best_gain
from slipenv.experiments.yamauchi.settings import Settings

CORRIDOR_M = 0.1


def lap(mean_m: float, max_m: float) -> dict:
    """A lap as :func:`~slipenv.experiments.yamauchi.circle.circle_episode` reports it."""
    return {"mean_error_m": mean_m, "rmse_m": 1.2 * mean_m, "max_error_m": max_m,
            "completed": max_m <= CORRIDOR_M, "slip_angle_swing_deg": 50.0,
            "corridor_m": CORRIDOR_M}


def test_the_oracle_picks_the_pole_whose_worst_lap_strays_least_not_the_best_mean():
    laps = {0.5: [lap(0.01, 0.05), lap(0.01, 0.30)],  # best mean, one lap leaves the corridor
            1.0: [lap(0.03, 0.08), lap(0.03, 0.09)],  # every lap inside
            2.0: [lap(0.04, 0.12), lap(0.04, 0.11)]}
    best = best_gain(laps)
    assert best["pole_rps"] == 1.0
    assert best["worst_max_error_m"] == pytest.approx(0.09)
    assert best["max_error_m"] == pytest.approx(0.085)  # the laps' mean of their maxima
    assert best["mean_error_m"] == pytest.approx(0.03)
    assert (best["completed"], best["laps_run"], best["corridor_m"]) == (2, 2, CORRIDOR_M)


def test_the_oracle_reports_every_pole_of_its_grid():
    laps = {0.15: [lap(0.2, 0.6)], 3.0: [lap(0.02, 0.07)]}
    by_pole = best_gain(laps)["by_pole"]
    assert list(by_pole) == ["0.15", "3"]
    assert by_pole["0.15"] == {"mean_error_m": 0.2, "worst_max_error_m": 0.6, "completed": 0}
    assert by_pole["3"]["completed"] == 1


def test_a_tie_goes_to_the_first_pole_of_the_grid():
    laps = {0.4: [lap(0.05, 0.2)], 0.15: [lap(0.05, 0.2)]}
    assert best_gain(laps)["pole_rps"] == 0.4


@pytest.mark.parametrize("laps", [{}, {1.0: []}])
def test_the_oracle_needs_laps_to_choose_from(laps):
    with pytest.raises(ValueError, match="at least one lap"):
        best_gain(laps)


@pytest.mark.parametrize("grid", [(), (0.0, 1.0), (-0.5,)])
def test_settings_refuse_an_oracle_grid_without_positive_poles(grid):
    with pytest.raises(ValueError, match="oracle_poles_rps must be positive"):
        Settings(oracle_poles_rps=grid)

