"""What an effect of the diagnosis vocabulary is made of (one module per effect beside this one).

An effect module defines

- its **parameters**: a frozen dataclass of floats with units in the field names, subclass of
  :class:`Term`, validated in ``__post_init__``; the same object is the effect's **replay
  term**: it overrides the hooks of :class:`Term` that ``replay.simulate`` calls;
- how it is **fitted**: the :class:`Bound` (start, bounds, scale) of each field for the data
  at hand, and optionally starting guesses computed from the data (:class:`StartContext`);
- how the **contract** (``log-format.md``) names its parameters: :class:`Scalar` and
  :class:`PerSide` entries;
- how it is **applied to the simulation**: ``apply(edit, params)`` on a
  :class:`slipenv.diagnose.effects.world.WorldEdit`;
- how a **hidden instance is drawn** for the tests (:class:`Hiding`: a function of a seeded
  ``np.random.Generator`` and a :class:`DrawContext`);

and ends with ``EFFECT = Effect(...)``: the registry (``effects/__init__.py``) collects it.

Per-wheel parameters are fitted per *side* (left, right): wheels of one side of a skid-steer
vehicle turn together, so their radii or stiffnesses cannot be told apart; each wheel reports
its side's value.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from slipenv.contracts.constants import G_MPS2
from slipenv.diagnose.segments import Segments

HUGE = 1e12  # stiffness reported for a zero compliance (JSON has no infinity)


class Term:
    """Replay hooks of a parameter object; each default leaves the nominal replay unchanged.

    Array shapes: S segments, L samples, ``n_wheels`` wheels (``replay.py`` numbers the steps).
    """

    def wheel_radius(self, seg: Segments, radius: np.ndarray) -> np.ndarray:
        """Step 1: the rolling radius of each wheel, (S, n_wheels) [m]."""
        return radius

    def slip(self, seg: Segments, pos: np.ndarray) -> np.ndarray | None:
        """Step 2: longitudinal slip added by this term, broadcastable to (S, L-1, n_wheels)
        [-]; ``pos`` (S, L-1, 2) [m] are the interval midpoints. None: no slip."""
        return None

    def split(self, seg: Segments, left: np.ndarray, right: np.ndarray
              ) -> tuple[np.ndarray, np.ndarray]:
        """Step 3: the left/right ground travel per interval, (S, L-1) [m]."""
        return left, right

    def track_width(self, seg: Segments, track: np.ndarray | float) -> np.ndarray | float:
        """Step 4: the width W in dθ = (g_R - g_L)/W, (S,) or a float [m]."""
        return track

    def slip_angle(self, seg: Segments, ds: np.ndarray, dtheta: np.ndarray,
                   mid: np.ndarray) -> np.ndarray | None:
        """Step 5: body slip angle added by this term, (S, L-1) [rad], from the forward travel
        ``ds`` [m], turn ``dtheta`` [rad] and midpoint heading ``mid`` [rad]. None: none."""
        return None

    def gyro_rate(self, seg: Segments, rate: np.ndarray) -> np.ndarray:
        """Gyro channel: the yaw rate the gyro says, corrected, (S, L-1) [rad/s]."""
        return rate


def require(condition: bool | np.bool_, owner: object, message: str) -> None:
    """``ValueError`` naming the parameter class unless ``condition`` (for ``__post_init__``)."""
    if not condition:
        raise ValueError(f"{type(owner).__name__}: {message}")


def applicable_to_world(condition: bool, effect: str, names: str, why: str) -> None:
    """``ValueError`` naming the effect and its contract names unless ``condition``: for an
    ``apply`` given values a fit may return (the bounds straddle them) but the simulation
    cannot take (a negative stiffness)."""
    if not condition:
        raise ValueError(f"effect {effect!r}: {names} cannot be applied to the simulation: "
                         f"{why}")


def finite(owner: object) -> None:
    """``ValueError`` naming the field unless every field of ``owner`` (a dataclass) is a
    finite number."""
    if not dataclasses.is_dataclass(owner):
        raise TypeError(f"{type(owner).__name__} is not a dataclass")
    for f in dataclasses.fields(owner):
        value = getattr(owner, f.name)
        require(isinstance(value, int | float) and not isinstance(value, bool)
                and math.isfinite(value), owner, f"{f.name} must be a finite number, "
                f"got {value!r}")


@dataclass(frozen=True)
class Bound:
    """Start, bounds and typical scale (for the optimiser's ``x_scale``) of one field."""

    start: float
    lower: float
    upper: float
    scale: float


@dataclass(frozen=True)
class Scalar:
    """A field reported one to one under a contract name."""

    field: str
    name: str


@dataclass(frozen=True)
class PerSide:
    """Two fields (left side, right side) reported for every wheel of that side.

    ``template`` holds ``{w}`` for the wheel name; ``reciprocal`` reports 1/value (a fitted
    compliance c [1/(N m)] as a stiffness k_s = 1/c [N m], its standard error by the delta
    method; per-wheel stiffnesses read back as the reciprocal of their side's mean).
    """

    left: str
    right: str
    template: str
    reciprocal: bool = False

    def pattern(self) -> re.Pattern:
        """Regex of the template, the wheel name captured as ``wheel``."""
        head, tail = self.template.split("{w}")
        return re.compile(f"^{re.escape(head)}(?P<wheel>[A-Za-z0-9_]+?){re.escape(tail)}$")


@dataclass(frozen=True)
class StartContext:
    """What a starting-guess function sees.

    Attributes
    ----------
    seg : Segments
        The training segments.
    model : dict
        Every effect being fitted at its default start (or the caller's start).
    residuals : callable
        ``residuals(model) -> ndarray``: the flat training residuals of a model of the same
        effects (for guesses by search).
    """

    seg: Segments
    model: dict[str, Term]
    residuals: Callable[[dict[str, Term]], np.ndarray]


@dataclass(frozen=True)
class DrawContext:
    """The world a hidden instance is drawn for (``synth.hidden_world``).

    Attributes
    ----------
    kind : str
        Vehicle kind.
    spec : VehicleSpec
        The clean world's vehicle.
    arena_m : float
        Half-size of the waypoint box [m].
    focus : tuple of float
        Point every other waypoint is near (x, y) [m].
    typical_torque_nm : callable
        ``() -> float``: median |channel torque| of the clean world [N m] (costly, cached).
    slope_deg : float
        Slope of the ground the vehicle stands on [deg] (0: level).
    """

    kind: str
    spec: Any
    arena_m: float
    focus: tuple[float, float]
    typical_torque_nm: Callable[[], float]
    slope_deg: float = 0.0

    def grade_torque_nm(self) -> float:
        """Channel torque that holds the vehicle on its slope, m g sin α r / n_channels
        [N m]."""
        spec = self.spec
        return (spec.mass_kg * G_MPS2 * float(np.sin(np.radians(self.slope_deg)))
                * spec.wheel_radius_nominal_m / len(spec.channels))

    def slip_torque_nm(self) -> float:
        """The torque a drawn torque compliance is sized for [N m]: the rover's grade torque
        (on level rigid ground its only drive torque is its wheels fighting one another),
        else the clean world's typical torque."""
        return self.grade_torque_nm() if self.kind == "rover4ws" else self.typical_torque_nm()


@dataclass(frozen=True)
class Hidden:
    """A drawn hidden instance: parameters applied through ``apply``, or settings of the
    world's force law (``ScaledSlip`` options) where the effect emerges from the physics."""

    params: Term | None = None
    slip_options: dict[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Hiding:
    """How the test generator hides an effect in the physics.

    Attributes
    ----------
    kinds : tuple of str
        Vehicle kinds it is hidden on.
    draw : callable
        ``draw(rng, ctx: DrawContext) -> Hidden``.
    slope_deg : (float, float) or None
        The vehicle always stands on a slope drawn in this range [deg] (on the kinds of
        ``slope_kinds``).
    slope_kinds : tuple of str or None
        Vehicle kinds ``slope_deg`` applies to (None: every kind of ``kinds``).
    random_slope : bool
        A differential-drive vehicle may stand on a random slope (30 % of the logs).
    columns : frozenset of str
        Optional column groups the log must have (``logs.export.OPTIONAL_GROUPS``).
    drop_columns : frozenset of str
        Column groups the log must not have.
    exact : bool
        The physics takes the parameters one to one (else the truth is calibrated).
    level_width : bool
        The log's nominal track width is calibrated on level ground of the same world.
    compare : bool
        The fitted parameters can be compared with a truth. False for a soil map: its layout
        is a model-order choice, and two layouts' regions do not correspond one to one.
    drawn : bool
        Among the effects a generator draws at random (``synth.DRAWN``); False: hidden only
        when asked for by name, so that the seeds of tables made before it still give the
        same logs.
    """

    kinds: tuple[str, ...]
    draw: Callable[[np.random.Generator, DrawContext], Hidden]
    slope_deg: tuple[float, float] | None = None
    slope_kinds: tuple[str, ...] | None = None
    random_slope: bool = True
    columns: frozenset[str] = frozenset()
    drop_columns: frozenset[str] = frozenset()
    exact: bool = False
    level_width: bool = False
    compare: bool = True
    drawn: bool = True

    def slope_range(self, kind: str) -> tuple[float, float] | None:
        """``slope_deg`` if a vehicle of ``kind`` always stands on a slope, else None."""
        if self.slope_kinds is None or kind in self.slope_kinds:
            return self.slope_deg
        return None


@dataclass(frozen=True)
class Confound:
    """A vehicle kind on which the effect's physics shows as another effect of the vocabulary.

    Attributes
    ----------
    kind : str
        Vehicle kind.
    shows_as : str
        The effect the log then names (the same change of the world, seen through this
        kind's kinematics).
    why : str
        One sentence for the report: what was measured.
    """

    kind: str
    shows_as: str
    why: str


def always(seg: Segments) -> str | None:
    """Every log can test the effect."""
    return None


def needs_torque(seg: Segments) -> str | None:
    return None if seg.torque is not None else "no torque_<wheel> columns"


def torque_scale(seg: Segments) -> float:
    """Typical |torque| [N m] of the moving samples (sets the compliance scale)."""
    if seg.torque is None:
        raise ValueError("no torque_<wheel> columns")
    moving = np.abs(seg.dphi).sum(axis=-1) > 0
    tq = np.abs(seg.torque[moving]) if moving.any() else np.abs(seg.torque)
    return max(float(np.median(tq)), 1e-3)


def compliance_bound(seg: Segments) -> Bound:
    """Bound of a torque compliance c [1/(N m)]: 0 start, scale = 5 % slip at typical torque."""
    scale = 0.05 / torque_scale(seg)
    return Bound(0.0, -10 * scale, 20 * scale, scale)


def stiffness_nm(compliance_per_nm: float) -> float:
    """Torque-slip stiffness k_s = 1/c [N m] of a compliance c [1/(N m)]; ``HUGE`` for c = 0."""
    return 1.0 / compliance_per_nm if abs(compliance_per_nm) > 1.0 / HUGE else HUGE


def side_values(values: ArrayLike, seg: Segments) -> np.ndarray:
    """Per-side values (left, right) spread to the wheels, (n_wheels,)."""
    return np.asarray(values, dtype=float)[seg.sides]


@dataclass(frozen=True)
class Effect:
    """One entry of the vocabulary (``log-format.md``), as its module defines it.

    Attributes
    ----------
    name : str
        Effect id.
    meaning : str
        One line for the human report.
    params : type
        The frozen :class:`Term` dataclass of its parameters.
    bounds : callable
        ``bounds(seg) -> {field: Bound}`` for the data at hand (every field).
    contract : tuple of Scalar / PerSide
        The contract's names of the fields (reported in this order).
    apply : callable
        ``apply(edit: WorldEdit, params) -> None``: the effect carried into the simulation.
    rank : float
        Place in the vocabulary (``log-format.md`` order): simpler causes first, the order
        ties of parsimony are broken in.
    applicable : callable
        ``applicable(seg) -> None`` or the reason the data cannot test the effect.
    channel : str
        ``"pose"`` (encoder replay against ground-truth pose) or ``"gyro"`` (the gyro's heading
        against ground-truth heading).
    start : callable or None
        ``start(ctx: StartContext) -> list[params]``: starting guesses from the data (several:
        short trial fits pick the best); None: the bounds' starts.
    hiding : Hiding or None
        How the test generator hides it; None: not generated.
    confounds : tuple of Confound
        Vehicle kinds on which its physics shows as another effect (measured; the report
        names the effect as the confounded alternative when the log names that one).
    mechanism : str or None
        Effects of the same mechanism are never fitted together (one torque-slip law).
    clash_prefix : str
        Prefix of its contract names that another effect of the same model also reports
        (``patch_`` for the soil patch's ``k_s_<wheel>_nm`` beside torque slip's).
    optional : dict
        Contract names that may be omitted from a model, with the value that switches them off.
    fixed : tuple of str
        Layout fields (a map's frame and its regions' corners): chosen by ``start`` (a model-order
        choice on the data), then held while the other fields are fitted; their standard
        error is 0.
    calibration : bool
        A geometric parameter of the odometry (wheel radii, track width). Once a cause is
        named, such an effect is added when held-out data support it (p and gain) even if
        its own drift is below the materiality rule: it is the calibration a user applies.
        Any other added effect must be material as well (a slip law below that size is the
        unmodelled slip every physics engine and vehicle holds).
    redundant : dict
        Fields that are the same degree of freedom as another effect's parameters, by that
        effect's id: held at their bounds' start when it is fitted too (combined slip's s_x0
        scales every wheel's travel by 1 - s_x0, as a common wheel radius does).
    local : bool
        The effect acts on part of the ground only (a soil patch, a soil map): it shows on
        the short segments that cross it, which is what the short route weighs. Added to a
        named cause it is judged on the short route only: the long route, which refits the
        model on every block replayed whole, is for slow drifts, and is the costliest step.
    condense : callable, optional
        ``{contract name: [value, se]} -> (kept, lines)``: how a report shows its parameters
        when one line each would bury them (a map's regions, one line each, not four corners):
        ``kept`` are listed one per line, ``lines`` follow them. None: every one listed.
    used : callable, optional
        ``used(params) -> int``: the fields a fitted instance uses, when its layout leaves
        some unused (a map of one disc has no use for four more shapes' corners); its
        parameter count (:func:`slipenv.diagnose.fit.param_count`). None: every field.
    """

    name: str
    meaning: str
    params: type
    bounds: Callable[[Segments], dict[str, Bound]]
    contract: tuple[Scalar | PerSide, ...]
    apply: Callable[[Any, Any], None]
    rank: float
    applicable: Callable[[Segments], str | None] = always
    channel: str = "pose"
    start: Callable[[StartContext], list] | None = None
    hiding: Hiding | None = None
    confounds: tuple[Confound, ...] = ()
    mechanism: str | None = None
    clash_prefix: str = ""
    optional: dict[str, float] = field(default_factory=dict)
    fixed: tuple[str, ...] = ()
    calibration: bool = False
    redundant: dict[str, str] = field(default_factory=dict)
    local: bool = False
    condense: Callable[[dict[str, Any]], tuple[dict[str, Any], list[str]]] | None = None
    used: Callable[[Any], int] | None = None

    def __post_init__(self) -> None:
        names = self.fields()
        covered = [n for c in self.contract for n in
                   ((c.field,) if isinstance(c, Scalar) else (c.left, c.right))]
        if sorted(covered) != sorted(names):
            raise ValueError(f"effect {self.name!r}: the contract covers {covered}, the "
                             f"parameters are {list(names)}")
        if self.channel not in ("pose", "gyro"):
            raise ValueError(f"effect {self.name!r}: channel must be 'pose' or 'gyro'")
        for flag in ("calibration", "local"):
            if not isinstance(getattr(self, flag), bool):
                raise ValueError(f"effect {self.name!r}: {flag} must be True or False")
        for hook in ("condense", "used"):
            if getattr(self, hook) is not None and not callable(getattr(self, hook)):
                raise ValueError(f"effect {self.name!r}: {hook} must be a function or None")
        for f, other in self.redundant.items():
            if f not in names or not isinstance(other, str) or other == self.name:
                raise ValueError(f"effect {self.name!r}: redundant maps its own fields "
                                 f"{list(names)} to another effect's id, got {f!r}: {other!r}")

    def confound(self, kind: str) -> Confound | None:
        """The :class:`Confound` of vehicle ``kind``, None if its physics shows as itself."""
        return next((c for c in self.confounds if c.kind == kind), None)

    def held(self, effects: tuple[str, ...]) -> tuple[str, ...]:
        """Fields held at their start when fitted together with ``effects`` (``redundant``)."""
        return tuple(f for f, other in self.redundant.items() if other in effects)

    def fields(self) -> tuple[str, ...]:
        """The parameter fields, in the order of the fitted vector."""
        return tuple(f.name for f in dataclasses.fields(self.params))

    def from_vector(self, x) -> Term:
        return self.params(*(float(v) for v in x))

    def to_vector(self, params: Term) -> list[float]:
        return [float(getattr(params, name)) for name in self.fields()]

    def contract_names(self, wheels: list[str]) -> list[str]:
        """The contract parameter names this effect reports for ``wheels``."""
        names = [c.name for c in self.contract if isinstance(c, Scalar)]
        for c in self.contract:
            if isinstance(c, PerSide):
                names += [c.template.format(w=w) for w in wheels]
        return names

    def wheels_named(self, keys) -> list[str]:
        """Wheel names found in ``keys`` by the per-side templates, sorted."""
        found = set()
        for c in self.contract:
            if isinstance(c, PerSide):
                found |= {m["wheel"] for k in keys if (m := c.pattern().match(k))}
        return sorted(found)

    def matches(self, key: str) -> bool:
        """True if ``key`` is one of this effect's contract names (any wheel)."""
        return any(key == c.name if isinstance(c, Scalar) else bool(c.pattern().match(key))
                   for c in self.contract)

    def to_contract(self, params: Term, se: dict[str, float], wheels: list[str],
                    sides: np.ndarray) -> dict[str, list[float]]:
        """Values and standard errors (``{field: se}``) -> ``{contract name: [value, se]}``."""
        out: dict[str, list[float]] = {}
        for c in (c for c in self.contract if isinstance(c, Scalar)):
            out[c.name] = [float(getattr(params, c.field)), float(se[c.field])]
        for p in (c for c in self.contract if isinstance(c, PerSide)):
            for w, side in zip(wheels, sides, strict=True):
                name = (p.left, p.right)[side]
                v, e = float(getattr(params, name)), float(se[name])
                if p.reciprocal:
                    v, e = (1.0 / v, e / v**2) if abs(v) > 1.0 / HUGE else (HUGE, HUGE)
                out[p.template.format(w=w)] = [v, e]
        return out

    def from_contract(self, values: dict[str, float], wheels: list[str],
                      sides: np.ndarray) -> Term:
        """``{contract name: value}`` -> parameters (per-side means of per-wheel values)."""
        kw: dict[str, float] = {}
        for c in self.contract:
            if isinstance(c, Scalar):
                kw[c.field] = float(values[c.name])
                continue
            for side, name in ((0, c.left), (1, c.right)):
                vals = [float(values[c.template.format(w=w)])
                        for w, s in zip(wheels, sides, strict=True) if s == side]
                if not vals:
                    raise ValueError(f"effect {self.name!r}: no {('left', 'right')[side]} "
                                     f"wheel among {wheels}")
                v = float(np.mean(vals))
                if c.reciprocal and v == 0.0:
                    raise ValueError(f"effect {self.name!r}: {c.template.format(w='<wheel>')} "
                                     f"must be nonzero (the reciprocal of {name}; a rigid "
                                     f"wheel's is {HUGE:g})")
                kw[name] = 1.0 / v if c.reciprocal else v
        return self.params(**kw)
