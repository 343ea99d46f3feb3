"""What ``slipenv reproduce lindgren`` runs: the env, the paths' size and the filter settings.

Each constant says why it has its value; departures from the estimator's defaults are in
:data:`FILTER` and each is also run at the default (:data:`VARIANTS`) to show its effect. The
experiment runs two blocks on the same paths and seeds (:class:`Setting`): :data:`HEADLINE`, the
world with the filter's own linear law and the uniform-field settings, and :data:`ROBUST`
which leans on none of them.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields

from slipenv.estimators.lindgren import LindgrenNoise

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
ESTIMATOR_NOISE = {k: getattr(LindgrenNoise, k) for k in (*FIELD_NOISE, "bearing_gate_prob")}
CALIBRATION_M = 6.0  # [m] straight drive that measures the effective radius (robust block)
CALIBRATION_SETTLE_M = 1.0  # [m] left out at each end of it (start-up, stop)
BASE_FILTERS = ("scheme1", "scheme2", "scheme3", "scheme4", "oracle")
DROPOUT_FILTERS = ("scheme3", "scheme4", "oracle")


@dataclass(frozen=True)
class Variant:
    """An extra filter run beside the schemes to show the effect of one setting.

    Attributes
    ----------
    scheme : str
        The scheme it varies (``"scheme3"``, ``"scheme4"``).
    noise : Mapping[str, float]
        :class:`~slipenv.estimators.lindgren.LindgrenNoise` fields set on top of the block's.
    nominal_radius : bool
        The no-slip schemes use the nominal (concrete) radius even if the block measured one.
    secant_k_s : bool
        The oracle gets the secant k_s measured on the block's calibration drive (torque over
        slip at straight driving) instead of the law's slope at zero slip.
    cut_factor : float
        Experiment (b) only: the laser is cut at ``cut_factor`` × :data:`CUT_S` (more of the
        path, and its turns, seen with bearings) [-], > 0.
    """

    scheme: str
    noise: Mapping[str, float] = field(default_factory=dict)
    nominal_radius: bool = False
    secant_k_s: bool = False
    cut_factor: float = 1.0

    def __post_init__(self) -> None:
        if self.scheme not in BASE_FILTERS:
            raise ValueError(f"Variant.scheme must be one of {BASE_FILTERS}, got {self.scheme!r}")
        unknown = set(self.noise) - {f.name for f in fields(LindgrenNoise)}
        if unknown:
            raise ValueError(f"Variant.noise has unknown LindgrenNoise field(s) {sorted(unknown)}")
        if not self.cut_factor > 0.0:
            raise ValueError(f"Variant.cut_factor must be > 0, got {self.cut_factor!r}")
        if self.secant_k_s and self.scheme != "oracle":
            raise ValueError(f"Variant.secant_k_s needs scheme 'oracle', got {self.scheme!r}")


@dataclass(frozen=True)
class Setting:
    """One block of the experiment: the world the vehicle drives in and what the filters know.

    Attributes
    ----------
    name : str
        ``"headline"`` or ``"robust"`` (the key of its metrics in the JSON).
    force_model : str or None
        The world's force law (:func:`slipenv.terramechanics.force_model_by_name`); None keeps
        the env preset's (Lindgren's linear law on FarmField-v0).
    noise : Mapping[str, float]
        :class:`~slipenv.estimators.lindgren.LindgrenNoise` fields every filter gets, on top
        of the estimator's defaults and the k_s prior.
    measured_radius : bool
        The no-slip schemes (2, 3) get the effective radius measured on a
        :data:`CALIBRATION_M` straight drive in this world (:mod:`.calibration`) instead of
        the nominal concrete radius.
    variants : Mapping[str, Variant]
        Extra filters, each putting one setting back, to show its effect.
    """

    name: str
    force_model: str | None
    noise: Mapping[str, float]
    measured_radius: bool
    variants: Mapping[str, Variant]

    def __post_init__(self) -> None:
        if not self.name:
            raise ValueError("Setting.name must be non-empty")
        clash = set(self.variants) & set(BASE_FILTERS)
        if clash:
            raise ValueError(f"Setting.variants may not reuse the scheme names {sorted(clash)}")

    @property
    def circle_filters(self) -> tuple[str, ...]:
        """The filters run on the circles: the schemes, the oracle and the variants (except
        those that only move the laser cut of experiment (b))."""
        return BASE_FILTERS + tuple(k for k, v in self.variants.items() if v.cut_factor == 1.0)


# Extra filters: one of FILTER's settings put back to the estimator's default, to show its effect.
GATED = Variant("scheme3", {"bearing_gate_prob": ESTIMATOR_NOISE["bearing_gate_prob"]})
HEADLINE = Setting(
    "headline", None, FILTER, measured_radius=False,
    variants={"scheme3_gated": GATED,
              "scheme4_default_soil_noise": Variant(
                  "scheme4", {k: ESTIMATOR_NOISE[k] for k in FIELD_NOISE}),
              # why scheme 4 trails the oracle after the cut: how long it had to learn R_w, k_s
              "scheme4_cut_x2": Variant("scheme4", cut_factor=2.0),
              "oracle_cut_x2": Variant("oracle", cut_factor=2.0)})
# The robust block: the curved Janosi/Okello law in the world (not the filter's linear one), the
# estimator's default soil random walk, and a measured radius for the no-slip filter. Only the
# paper's ungated bearing association is kept (it is the paper's method, not a property of the
# simulated world).
ROBUST = Setting(
    "robust", "janosi", {"bearing_gate_prob": 1.0}, measured_radius=True,
    variants={"scheme3_gated": GATED,
              "scheme3_nominal_radius": Variant("scheme3", nominal_radius=True),
              "scheme4_field_soil_noise": Variant("scheme4", FIELD_NOISE),
              "oracle_secant": Variant("oracle", secant_k_s=True)})
VARIANTS = HEADLINE.variants
SCHEMES = HEADLINE.circle_filters

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
