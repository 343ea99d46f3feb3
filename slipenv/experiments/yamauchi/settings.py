"""What ``slipenv reproduce yamauchi`` runs (Yamauchi et al. §2.3 and §3.1) and its targets."""

from __future__ import annotations

from dataclasses import dataclass

ENV_ID = "slipenv/TrackedSlopeCircle-v0"
DEFAULT_VEHICLE = "tracked_patako_wong_chiang"  # the env preset's world: the Wong-Chiang
DEFAULT_SOIL = "toyoura_sand"  # track model on the paper's loose, cohesionless Toyoura sand
REPRODUCTION_VEHICLE = DEFAULT_VEHICLE  # the reproduction runs in the env's own world
REPRODUCTION_SOIL = DEFAULT_SOIL
ORACLE_MAX_SLIP_ANGLE_RAD = 1.5  # [rad] the true β is not clipped like a regression's (1 rad)
TARGETS = {"odometry_ratio_max": 0.4,  # each direction; paper: 0.18
           "feedforward_ratio_max": 0.5,  # feed-forward / gyrodometry feedback; paper: 0.14
           "endo_n_tolerance": 0.05}  # |n - paper| at each tilt
CALIBRATED = {
    "toyoura_sand Bekker set (k_c, k_phi, n: Wong's LLL dry sand, not Ishigami's wheel set)":
        "Sec. 2.3: Patako completed its 90 deg rotations at 10-30 deg/s on the loose field; "
        "with Ishigami's set (28 mm static, 90-100 mm turning sinkage) the simulated vehicle "
        "turns 20 deg in 12 s at 30 deg/s on flat sand",
    "Endo n per tilt (Eq. 8)": "fitted on the simulated rotation runs, as the paper did on its "
                               "own (Fig. 4); not tuned to the paper's values",
    "Eq. 9 coefficients": "fitted on the simulated training rotation runs (Eq. 10's least "
                          "squares), scored on held-out runs",
    "path-following gains (triple pole)": "chosen on flat rigid ground (Sec. 3.1: 'determined "
                                          "on a solid floor in advance')",
}
"""What was set from a measurement, and which: nothing else in the world is fitted. The
odometry improvement (82 %) and the circle (9.1 -> 1.3 cm) are validation only."""
WORLD_CALIBRATED = {
    "tracked_patako_decoupled": {
        "decoupled shear moduli K_x, K_y (K_x = 2.3 K, K_y = 0.69 K of toyoura_sand's K)":
            "Sec. 2.4: Endo n 0.832 / 0.817 / 0.824 at 0 / 8 / 15 deg, the grid point of "
            "benchmarks/yamauchi_shear_calibration.py nearest it at every tilt over three run "
            "plans, rounded",
    },
}
"""What a vehicle preset of another world adds to :data:`CALIBRATED`."""
STEER_ON = ("observation", "true_beta", "truth")
"""What a circle episode steers on: the env's observation (what a user gets); slip-compensated
odometry with the true β in place of Eq. 9 (a limit: perfect slip-angle regression, Endo's
slip ratios); the true pose and β (a limit: perfect odometry)."""


@dataclass(frozen=True)
class Settings:
    """What the experiment runs; ``QUICK`` has fewer repetitions, the same experiments.

    Angles in degrees, speeds in m/s, times in s, as named.
    """

    tilts_deg: tuple[float, ...] = (0.0, 8.0, 15.0)
    turn_rates_dps: tuple[float, ...] = (10.0, 20.0, 30.0)  # §2.3
    directions: tuple[int, ...] = (1, -1)  # counter-clockwise, clockwise
    repeats: int = 4  # runs per (tilt, rate, direction)
    speed_mps: float = 0.05  # §2.3
    rotation_deg: float = 90.0  # §2.3: "about 90 degrees"
    heading_jitter_deg: float = 5.0  # start heading ± this, uniform (set by hand in the paper)
    max_rotation_s: float = 30.0
    start_heading_deg: float = 0.0
    """Start heading of a rotation run [deg] from across the slope (0: across, downhill to the
    right; -90: facing downhill). §2.3 sets the robot "parallel to the long side" of a field
    tilted "by jacking up one side": which side is not said, so the runs start across and a
    limit starts them facing downhill (`metrics.limits.fall_line_start`)."""
    cv_folds: int = 3
    """Folds of the cross-validated odometry ratio (every run held out once, by run)."""
    test_fraction: float = 1.0 / 3.0
    smooth_steps: int = 5  # centred window of the slip derivatives [control steps]
    min_speed_mps: float = 0.01  # the slip angle of a vehicle at rest is undefined
    circle_tilt_deg: float = 15.0  # §3.1
    circle_radius_m: float = 0.25  # §3.1
    circle_seeds: int = 3  # §3.1: "three times for each control law", one lap each
    poles_rps: tuple[float, ...] = (0.15, 0.25, 0.4, 0.6, 1.0)  # rigid-ground gain search
    oracle_poles_rps: tuple[float, ...] = (0.15, 0.25, 0.4, 0.6, 1.0, 1.5, 2.0, 3.0)
    """An oracle grid, not a calibration: the triple poles [rad/s] among which each law's best
    gain is chosen on the slope's own laps, by their true maximum error (a limit: what any gain
    of the law can do, on the truth and on the env's observation). The headline gains come
    from ``poles_rps`` on rigid ground (§3.1); nothing of this grid reaches them."""
    # The world: None keeps the env preset's (the Wong-Chiang track model on toyoura_sand,
    # also the world of the command's plans FULL and QUICK); e.g. "tracked_patako" runs the
    # per-wheel track law, "dry_sand" Wong's cohesive LLL sand.
    vehicle: str | None = None
    soil: str | None = None

    def __post_init__(self) -> None:
        if not self.tilts_deg or any(not 0.0 <= t < 90.0 for t in self.tilts_deg):
            raise ValueError(f"tilts_deg must be angles in [0, 90), got {self.tilts_deg}")
        if set(self.directions) - {1, -1} or not self.directions:
            raise ValueError(f"directions must be 1 and/or -1, got {self.directions}")
        if not -180.0 <= self.start_heading_deg <= 180.0:
            raise ValueError(f"start_heading_deg must be in [-180, 180], got "
                             f"{self.start_heading_deg}")
        if self.cv_folds < 2:
            raise ValueError(f"cv_folds must be >= 2, got {self.cv_folds}")
        for name in ("repeats", "smooth_steps", "circle_seeds"):
            if getattr(self, name) < 1:
                raise ValueError(f"{name} must be >= 1, got {getattr(self, name)}")
        for name in ("speed_mps", "rotation_deg", "max_rotation_s", "circle_radius_m"):
            if not getattr(self, name) > 0.0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if not 0.0 < self.test_fraction < 1.0:
            raise ValueError(f"test_fraction must be in (0, 1), got {self.test_fraction}")
        for name in ("poles_rps", "oracle_poles_rps"):
            poles = getattr(self, name)
            if not poles or min(poles) <= 0.0:
                raise ValueError(f"{name} must be positive, got {poles}")


FULL = Settings(vehicle=REPRODUCTION_VEHICLE, soil=REPRODUCTION_SOIL)
"""What ``slipenv reproduce yamauchi`` runs: the Wong-Chiang track model on ``toyoura_sand``."""
QUICK = Settings(repeats=2, poles_rps=(0.15, 0.3, 0.6), oracle_poles_rps=(0.15, 2.0),
                 vehicle=REPRODUCTION_VEHICLE, soil=REPRODUCTION_SOIL)
"""``--quick``: fewer repetitions, the same experiments, the same world."""


def world_of(vehicle: str | None, soil: str | None) -> tuple[str, str]:
    """The (vehicle, soil) names a run uses: ``None`` is the env preset's."""
    return vehicle or DEFAULT_VEHICLE, soil or DEFAULT_SOIL


def page_name(vehicle: str | None, soil: str | None) -> str:
    """The results page of a world: ``yamauchi`` for the env preset's (the reproduction's
    default), ``yamauchi_per_wheel`` for the per-wheel track law on ``toyoura_sand``, else
    ``yamauchi_<vehicle>_<soil>`` with the preset's name left out when it is kept."""
    v, s = world_of(vehicle, soil)
    if (v, s) == (DEFAULT_VEHICLE, DEFAULT_SOIL):
        return "yamauchi"
    if (v, s) == ("tracked_patako", DEFAULT_SOIL):
        return "yamauchi_per_wheel"
    parts = [x for x, default in ((v, DEFAULT_VEHICLE), (s, DEFAULT_SOIL)) if x != default]
    return "yamauchi_" + "_".join(parts)


def is_env_world(vehicle: str | None, soil: str | None) -> bool:
    """Whether a run's world is the env preset's (the one whose fitted model the tracked env
    observes with: ``--save-model`` needs it)."""
    return world_of(vehicle, soil) == (DEFAULT_VEHICLE, DEFAULT_SOIL)
