"""The numbers Yamauchi, Nagatani, Hashimoto and Fujino report ("Slip compensated odometry for
a tracked vehicle when rotating on a loose weak slope"), each with its section, table or
figure. :data:`PAPER` keeps the layout of the experiment's JSON ``"paper"`` entry.
"""

from __future__ import annotations

ENDO_N = {"0": 0.832, "8": 0.817, "15": 0.824}
"""Endo's exponent n (Eq. 8) on Toyoura sand at tilts 0, 8 and 15° (§2.4, Fig. 4)."""

ENDO_N_HARD_FLOOR = 0.824
"""Endo's n of the vehicle on a solid floor (Table 1)."""

ODOMETRY_IMPROVEMENT_VS_GYRODOMETRY = 0.82
"""Position RMSE of slip-compensated odometry 82 % below gyrodometry's (§2.4, Fig. 6)."""

CIRCLE_FEEDBACK_GYRODOMETRY_MEAN_ERROR_M = 0.091
"""[m] Mean error of Eq. 9 on gyrodometry, r = 0.25 m circle on 15° at 5 cm/s (§3.1, Fig. 8A)."""

CIRCLE_FEEDFORWARD_MEAN_ERROR_M = 0.013
"""[m] Mean error of Eq. 10 on slip-compensated odometry, same circle (§3.1, Fig. 8B)."""

CIRCLE_RMSE_IMPROVEMENT = 0.60
"""RMSE of Eq. 10 about 60 % below Eq. 9 on gyrodometry (§3.1)."""

PAPER = {
    "endo_n": ENDO_N,
    "endo_n_hard_floor": ENDO_N_HARD_FLOOR,
    "odometry_improvement_vs_gyrodometry": ODOMETRY_IMPROVEMENT_VS_GYRODOMETRY,
    "path_following": {
        "feedback_gyrodometry": {"mean_error_m": CIRCLE_FEEDBACK_GYRODOMETRY_MEAN_ERROR_M},
        "feedforward": {"mean_error_m": CIRCLE_FEEDFORWARD_MEAN_ERROR_M},
        "rmse_improvement": CIRCLE_RMSE_IMPROVEMENT,
    },
}
"""Every number above, in the layout of the experiment's ``metrics``."""
