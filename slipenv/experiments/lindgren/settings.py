"""What ``slipenv reproduce lindgren`` runs: the env, the paths' size and the filter settings.

Each constant says why it has its value. The experiment runs two blocks on the same paths and
seeds (:class:`Setting`): :data:`HEADLINE`, the world the filter does not assume (the curved
Janosi/Okello law on the field loam, the estimator's default process noise, per-wheel radii
measured on a calibration drive for the no-slip filter), and :data:`ABLATION`, the same with
the world's law swapped for the filter's own linear law. Departures from the estimator's
defaults are in :data:`FILTER`; each block's extra filters (:class:`Variant`) put one setting
back or change it, to show its effect.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field, fields

from slipenv.envs.registration import PRESETS
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
# The paper's bearing association (nearest innovation, no χ² gate, Lindgren §2.4): the paper's
# method, not a property of the simulated world, so every block keeps it.
FILTER = {"bearing_gate_prob": 1.0}
ESTIMATOR_NOISE = {k: getattr(LindgrenNoise, k) for k in (*FIELD_NOISE, "bearing_gate_prob")}
CALIBRATION_M = 6.0  # [m] straight drive that measures the effective radii
CALIBRATION_SETTLE_M = 1.0  # [m] left out at each end of it (start-up, stop)


# The slip-model schemes the filter offers: Lindgren's linear law (scheme 4) and Okello's curve
# (scheme 5). Each block reports the one with the lower mean final error after the laser cut as
# its slip model, and every one's numbers.
SLIP_SCHEMES = ("scheme4", "scheme5")
NO_SLIP_SCHEME = "scheme3"
BASE_FILTERS = ("scheme1", "scheme2", "scheme3", *SLIP_SCHEMES, "oracle")
DROPOUT_FILTERS = ("scheme3", *SLIP_SCHEMES, "oracle")
# The farm vehicle's filter carries the lateral slip gain k_β (FarmField-v0's EKF: the castors
# make the vehicle crab on the circles), so the slip-model schemes carry it, with FarmField's
# prior. The no-slip schemes stay the paper's filter, which had no such state: they are the
# paper's baseline. The oracle stays the paper's scheme 4 with the true soil: the limit its
# soil states can reach, not a second lateral model (a variant row shows it with k_β).
LATERAL = {"lateral_slip_sigma0":
           PRESETS[ENV_ID]["estimator_kwargs"]["params"]["lateral_slip_sigma0"]}
LATERAL_FILTERS = SLIP_SCHEMES


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
    one_radius : bool
        The no-slip schemes use one radius for both wheels, measured on the block's calibration
        drive as the distance over the wheels' mean rotation, instead of each wheel's own.
    secant_k_s : bool
        The oracle gets the secant k_s measured on the block's calibration drive (torque over
        slip at straight driving) instead of the law's slope at zero slip.
    cut_factor : float
        Experiment (b) only: the laser is cut at ``cut_factor`` × :data:`CUT_S` (more of the
        path, and its turns, seen with bearings) [-], > 0.
    lateral : bool or None
        Whether the filter carries the lateral slip gain (:data:`LATERAL`); None: as its
        scheme does (those of :data:`LATERAL_FILTERS` do, the others do not).
    """

    scheme: str
    noise: Mapping[str, float] = field(default_factory=dict)
    nominal_radius: bool = False
    one_radius: bool = False
    secant_k_s: bool = False
    cut_factor: float = 1.0
    lateral: bool | None = None

    def __post_init__(self) -> None:
        if self.scheme not in BASE_FILTERS:
            raise ValueError(f"Variant.scheme must be one of {BASE_FILTERS}, got {self.scheme!r}")
        unknown = set(self.noise) - {f.name for f in fields(LindgrenNoise)}
        if unknown:
            raise ValueError(f"Variant.noise has unknown LindgrenNoise field(s) {sorted(unknown)}")
        if not self.cut_factor > 0.0:
            raise ValueError(f"Variant.cut_factor must be > 0, got {self.cut_factor!r}")
        if self.nominal_radius and self.one_radius:
            raise ValueError("Variant.nominal_radius and Variant.one_radius exclude each other")
        if self.lateral and self.scheme not in (*LATERAL_FILTERS, "oracle"):
            raise ValueError(f"Variant.lateral: the no-slip schemes stay the paper's filter, "
                             f"got {self.scheme!r}")
        if self.secant_k_s and self.scheme != "oracle":
            raise ValueError(f"Variant.secant_k_s needs scheme 'oracle', got {self.scheme!r}")


@dataclass(frozen=True)
class Setting:
    """One block of the experiment: the world the vehicle drives in and what the filters know.

    Attributes
    ----------
    name : str
        ``"headline"`` or ``"ablation"`` (the key of its metrics in the JSON).
    world : str
        What the block's world is, in words (the page's row label).
    force_model : str or None
        The world's force law (:func:`slipenv.terramechanics.force_model_by_name`); None keeps
        the env preset's (Lindgren's linear law on FarmField-v0).
    noise : Mapping[str, float]
        :class:`~slipenv.estimators.lindgren.LindgrenNoise` fields every filter gets, on top
        of the estimator's defaults and the k_s prior.
    measured_radius : bool
        The no-slip schemes (2, 3) get each wheel's effective radius measured on a
        :data:`CALIBRATION_M` straight drive in this world (:mod:`.calibration`) instead of
        the nominal concrete radius.
    variants : Mapping[str, Variant]
        Extra filters, each putting one setting back, to show its effect.
    """

    name: str
    world: str
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


# Extra filters, each changing one setting of its block to show its effect.
GATED = Variant("scheme3", {"bearing_gate_prob": ESTIMATOR_NOISE["bearing_gate_prob"]})
ONE_RADIUS = Variant("scheme3", one_radius=True)
NOMINAL_RADIUS = Variant("scheme3", nominal_radius=True)
UNIFORM_FIELD = Variant("scheme4", FIELD_NOISE)  # the walk a uniform field needs
# the paper's state: what the lateral slip gain brings, and the oracle with it
LATERAL_VARIANTS = {"scheme4_no_lateral": Variant("scheme4", lateral=False),
                    "oracle_lateral": Variant("oracle", lateral=True)}
# why the slip model trails the oracle after the cut: how long it had to learn R_w, k_s
CUT_X2 = {"scheme4_cut_x2": Variant("scheme4", cut_factor=2.0),
          "oracle_cut_x2": Variant("oracle", cut_factor=2.0)}
# The headline: the world the filter does not assume. The curved Janosi/Okello law on the field
# loam (not the filter's linear law), the estimator's default soil random walk, and for the
# no-slip filter each wheel's effective radius measured on a calibration drive on that soil, as
# the paper's operators gave theirs "a carefully measured effective wheel radius" (§5, Fig. 7).
HEADLINE = Setting(
    "headline", "curved Janosi/Okello law on field_loam", "janosi", FILTER, measured_radius=True,
    variants={"scheme3_gated": GATED, "scheme3_one_radius": ONE_RADIUS,
              "scheme3_nominal_radius": NOMINAL_RADIUS,
              "scheme4_field_soil_noise": UNIFORM_FIELD, **LATERAL_VARIANTS,
              "oracle_secant": Variant("oracle", secant_k_s=True), **CUT_X2})
# The ablation: the same filters in a world that injects the filter's own linear law (Lindgren
# Eq. 24, FarmField-v0's preset), to separate the law's curvature from everything else.
ABLATION = Setting(
    "ablation", "Lindgren's linear law (Eq. 24) on field_loam", None, FILTER,
    measured_radius=True,
    variants={"scheme3_gated": GATED, "scheme3_one_radius": ONE_RADIUS,
              "scheme3_nominal_radius": NOMINAL_RADIUS,
              "scheme4_field_soil_noise": UNIFORM_FIELD, **LATERAL_VARIANTS, **CUT_X2})
BLOCKS = (HEADLINE, ABLATION)


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
