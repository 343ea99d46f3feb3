"""The numbers Lindgren et al. report in §5 ("Relating torque and slip in an odometric model
for an autonomous agricultural vehicle"), each with the table, figure or passage it is from.

:data:`PAPER` keeps the layout of the experiment's JSON ``"paper"`` entry.
"""

from __future__ import annotations

MEAN_DEVIATION_M = {"scheme3": 0.243, "scheme4": 0.127}
"""[m] Mean deviation of schemes 3 and 4 from scheme 1 on the circles (Table 1)."""

NIS = {"scheme3": 5.1860, "scheme4": 3.1836}
"""Time-averaged NIS of the odometric innovations, Eq. 43 (Table 3)."""

NIS_BAND = [1.8831, 2.1204]
"""95 % region of the NIS for K n_z = 2198 by Eq. 44 (§5, text after Eq. 44)."""

AUTOCORR_MEAN = {"scheme3": 0.2068, "scheme4": 0.0081}
"""Mean of the autocorrelation statistic ρ̄(l), Eq. 42 (Table 2)."""

AUTOCORR_VAR = {"scheme3": 0.0678, "scheme4": 0.0444}
"""Variance of ρ̄(l) over the lags (Table 2)."""

AUTOCORR_SHARE_INSIDE = {"scheme3": 0.0, "scheme4": 0.9709}
"""Share of ρ̄(l) inside ±1.96/√K (§5 on Fig. 6: "all of the points lie outside"; 97.09 %)."""

N_SAMPLES = 1099
"""K, odometric innovations in the statistics (§5, text on Fig. 6 and Eq. 44)."""

DROPOUT_FINAL_ERROR_M = {"no_slip_model": 1.97, "slip_model": 0.21, "oracle": None}
"""[m] Final position error after the laser cut at 50 s (§5 on Fig. 7; the paper has no
oracle)."""

PAPER = {
    "mean_deviation_m": MEAN_DEVIATION_M,
    "nis": {**NIS, "band": NIS_BAND},
    "autocorr_mean": AUTOCORR_MEAN,
    "autocorr_var": AUTOCORR_VAR,
    "autocorr_share_inside": AUTOCORR_SHARE_INSIDE,
    "n_samples": N_SAMPLES,
    "dropout_final_error_m": DROPOUT_FINAL_ERROR_M,
}
"""Every number above, in the layout of the experiment's ``metrics``."""
