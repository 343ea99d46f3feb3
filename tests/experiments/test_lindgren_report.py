"""The Lindgren table and targets when a filter's odometry was rejected throughout the window
(no NIS, no band): the target is reported missed with "n/a", never a crash or a NaN."""

from __future__ import annotations

from slipenv.experiments.lindgren.report import nis_distance, target_lines, targets


def _metrics(nis4: float | None, band: list) -> dict:
    return {"mean_deviation_m": {"no_slip_model": 0.3, "slip_model": 0.07},
            "deviation_from_scheme1_m": {"no_slip_model": 0.3, "slip_model": 0.25},
            "nis": {"no_slip_model": 12.0, "slip_model": nis4, "band": band},
            "dropout_final_error_m": {"no_slip_model": 12.0, "slip_model": 0.7, "oracle": 0.1}}


def test_nis_distance_is_zero_inside_the_band_and_none_without_a_nis():
    assert nis_distance(2.0, [1.9, 2.1]) == 0.0
    assert abs(nis_distance(2.5, [1.9, 2.1]) - 0.4) < 1e-12
    assert nis_distance(None, [1.9, 2.1]) is None
    assert nis_distance(2.0, [None, None]) is None


def test_a_filter_without_odometry_statistics_misses_its_nis_target_and_prints_n_a():
    tg = targets(_metrics(None, [None, None]))
    row = tg["slip_model NIS closer to band than no_slip_model"]
    assert row["value"] is None and row["met"] is False
    assert tg["slip_model NIS inside the 95 % band"]["met"] is False
    assert tg["slip_model mean error <= 0.7 no_slip_model"]["met"] is True
    assert tg["slip_model deviation from scheme 1 <= 0.7 no_slip_model"]["met"] is False
    lines = target_lines(tg)
    assert "[MISSED] slip_model NIS closer to band than no_slip_model: n/a vs n/a" in lines
    assert not any("nan" in line.lower() for line in lines)


def test_with_statistics_the_nis_target_is_judged_on_the_band_distance():
    tg = targets(_metrics(2.0, [1.9, 2.1]))
    assert tg["slip_model NIS closer to band than no_slip_model"]["met"] is True
    assert tg["slip_model NIS inside the 95 % band"]["met"] is True
