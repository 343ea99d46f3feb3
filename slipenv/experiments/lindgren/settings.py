"""What ``slipenv reproduce lindgren`` runs: the env, the paths' size and the filter settings.

Each constant says why it has its value; departures from the estimator's defaults are in
:data:`FILTER` and each is also run at the default (:data:`VARIANTS`) to show its effect.
"""

from __future__ import annotations

from dataclasses import dataclass

ENV_ID = "slipenv/FarmField-v0"
STEER_SCHEME = 1  # the env's EKF scheme the path follower steers by (laser + inertial)
SPEED_MPS = 0.5  # [m/s] path speed (assumed: Lindgren gives none), as the FarmField preset
CIRCLE_RADIUS_M = 4.0  # [m] Lindgren Fig. 3
SETTLE_M = 5.0  # [m] start of the clockwise arc left out while the slip states converge
LAGS = 100  # autocorrelation lags 1..LAGS (Fig. 6)
CUT_S = 50.0  # [s] laser cut (Lindgren §5, Fig. 7)
FIELD_NOISE = {"radius_var_per_m": 1e-8,  # [m²/m]: R_w within ~1 mm per 100 m (one soil)
               "k_s_rel_var_per_m": 1e-5}  # [1/m]: k_s within ~3 % per 100 m (load shifts)
FILTER = {**FIELD_NOISE, "bearing_gate_prob": 1.0}  # + the paper's ungated association
# Extra filters: one of FILTER's settings put back to the estimator's default, to show its effect.
VARIANTS = {"scheme3_gated": ("scheme3", ("bearing_gate_prob",)),
            "scheme4_default_soil_noise": ("scheme4", tuple(FIELD_NOISE))}
SCHEMES = ("scheme1", "scheme2", "scheme3", "scheme4", "oracle", "scheme3_gated")
DROPOUT_FILTERS = ("scheme3", "scheme4", "oracle")


@dataclass(frozen=True)
class Config:
    """One run's size.

    Attributes
    ----------
    circle_loops : float
        Loops each way on the circles (clockwise, then counter-clockwise) [-].
    straight_legs : int
        Straights of experiment (b), joined by alternating 180° turns.
    dropout_drives : int
        Drives of experiment (b), seeds ``seed``, ``seed + 1``, ...
    """

    circle_loops: float
    straight_legs: int
    dropout_drives: int

    def __post_init__(self) -> None:
        if not self.circle_loops > 0.0:
            raise ValueError(f"circle_loops must be > 0, got {self.circle_loops}")
        if self.straight_legs < 1:
            raise ValueError(f"straight_legs must be >= 1, got {self.straight_legs}")
        if self.dropout_drives < 1:
            raise ValueError(f"dropout_drives must be >= 1, got {self.dropout_drives}")


FULL, QUICK = Config(1.5, 4, 12), Config(1.0, 3, 12)
