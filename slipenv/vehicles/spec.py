"""Vehicle specifications: frozen dataclasses in SI units, validated on construction.

A vehicle is a rigid chassis plus wheels. Wheels that share one commanded speed and one
encoder form a *drive channel* (one wheel of a differential-drive vehicle, one track of a
skid-steer vehicle whose road wheels all turn with the sprocket, one side of the Husky). The
channel is what the action commands and what the encoders and torque sensors report.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

VEHICLE_KINDS = ("diff_drive", "skid_steer", "rover4ws")
TRACK_MODELS = ("per_wheel", "wong_chiang")
TRACK_SHEAR_LAWS = ("resultant", "decoupled")  # slipenv.terramechanics.track.SHEAR_LAWS
WHEEL_ROLES = ("driven", "caster")


# Plausible bounds of a ground vehicle, from a toy rover to a large tractor: values outside
# them are typos or unit mistakes (a 1e9 kg chassis), not vehicles the force laws were fitted
# for. Each is (low, high), both inclusive, in the field's unit.
BOUNDS: dict[str, tuple[float, float]] = {
    "chassis_mass_kg": (0.1, 1e5),  # 100 g toy to 100 t
    "wheel_mass_kg": (1e-3, 1e4),
    "wheel_radius_m": (5e-3, 2.0),  # 5 mm to the largest tyres (about 2 m)
    "wheel_width_m": (1e-3, 2.0),
    "contact_length_m": (1e-3, 5.0),
    "chassis_dimension_m": (1e-2, 20.0),
    "chassis_center_height_m": (-10.0, 10.0),
    "wheel_offset_m": (-20.0, 20.0),  # wheel centre coordinates in the chassis frame
    "track_width_m": (1e-2, 10.0),
    "wheelbase_m": (1e-2, 20.0),
    "track_length_m": (1e-2, 20.0),
    "max_wheel_speed_rad_s": (1e-3, 1000.0),
    "max_wheel_torque_nm": (1e-3, 1e5),
    "max_speed_mps": (1e-3, 50.0),
    "max_yaw_rate_rad_s": (1e-3, 20.0),
    "counts_per_rad": (1e-3, 1e7),
    "contact_sinkage_m": (1e-6, 0.5),
    "pivot_height_m": (-2.0, 2.0),  # roll axis above the wheel-centre plane
    "pivot_limit_rad": (1e-3, math.pi / 2),
    "pivot_damping_nms": (0.0, 1e5),  # [N m s/rad]
    "shear_modulus_ratio": (0.05, 20.0),  # a track's K_x or K_y over the soil's K
}


def _check_positive(owner: str, **values: float) -> None:
    for name, value in values.items():
        if not (isinstance(value, (int, float)) and not isinstance(value, bool)
                and math.isfinite(value) and value > 0.0):
            raise ValueError(f"{owner}.{name} must be a finite number > 0, got {value!r}")


def _check_range(owner: str, name: str, value: float, bound: str | None = None) -> None:
    """``value`` must be a finite number within ``BOUNDS[bound or name]``."""
    low, high = BOUNDS[bound or name]
    if not (isinstance(value, (int, float)) and not isinstance(value, bool)
            and math.isfinite(value) and low <= value <= high):
        raise ValueError(f"{owner}.{name} must be a finite number in [{low:g}, {high:g}] "
                         f"(plausible for a ground vehicle), got {value!r}")


@dataclass(frozen=True)
class WheelSpec:
    """One wheel (or one road wheel of a track).

    Attributes
    ----------
    name : str
        Unique name, e.g. ``"front_left"``.
    position_m : tuple[float, float, float]
        Wheel centre in the chassis frame (x forward, y left, z up) [m].
    radius_m : float
        Rolling radius on rigid ground; also the collision sphere radius [m].
    width_m : float
        Tyre or track width [m] (contact patch width in the force law).
    mass_kg : float
        Wheel mass [kg].
    channel : str | None
        Drive channel the wheel belongs to (``None`` for casters).
    role : str
        ``"driven"`` (revolute spin joint with a speed-controlled motor) or ``"caster"`` (passive
        support that only resists motion: rolling resistance, no traction or side force).
    contact_length_m : float
        Length of the contact patch along the travel direction [m] (a track's share of its
        ground contact length for road wheels).
    steered : bool
        Whether a steering joint sits between chassis and wheel (4WS rover).
    soil_rolling_radius_m : float | None
        Effective rolling radius on deformable soil when it is known per wheel (Lindgren §3.2:
        0.283 / 0.287 m on soil against 0.275 m on concrete); ``None`` uses
        ``radius_m * soil.rolling_radius_scale``.
    rolling_radius_m : float | None
        Effective rolling radius on every surface, when a fitted model extension sets it
        (``slipenv diagnose``, effect ``rolling_radius``); overrides both of the above.
    """

    name: str
    position_m: tuple[float, float, float]
    radius_m: float
    width_m: float
    mass_kg: float
    channel: str | None
    role: str = "driven"
    contact_length_m: float = 0.1
    steered: bool = False
    soil_rolling_radius_m: float | None = None
    rolling_radius_m: float | None = None

    def __post_init__(self) -> None:
        owner = f"WheelSpec({self.name!r})"
        _check_positive(
            owner,
            radius_m=self.radius_m,
            width_m=self.width_m,
            mass_kg=self.mass_kg,
            contact_length_m=self.contact_length_m,
        )
        if self.role not in WHEEL_ROLES:
            raise ValueError(f"{owner}.role must be one of {WHEEL_ROLES}, got {self.role!r}")
        if self.role == "driven" and self.channel is None:
            raise ValueError(f"{owner}: a driven wheel needs a drive channel")
        if len(self.position_m) != 3 or not all(math.isfinite(v) for v in self.position_m):
            raise ValueError(f"{owner}.position_m must be three finite numbers")
        for name, value, bound in (
            ("radius_m", self.radius_m, "wheel_radius_m"),
            ("width_m", self.width_m, "wheel_width_m"),
            ("mass_kg", self.mass_kg, "wheel_mass_kg"),
            ("contact_length_m", self.contact_length_m, None),
            *((f"position_m[{i}]", v, "wheel_offset_m") for i, v in enumerate(self.position_m)),
        ):
            _check_range(owner, name, value, bound)
        for name in ("soil_rolling_radius_m", "rolling_radius_m"):
            if getattr(self, name) is not None:
                _check_range(owner, name, getattr(self, name), "wheel_radius_m")
        if self.soil_rolling_radius_m is not None:
            _check_positive(owner, soil_rolling_radius_m=self.soil_rolling_radius_m)
        if self.rolling_radius_m is not None:
            _check_positive(owner, rolling_radius_m=self.rolling_radius_m)


@dataclass(frozen=True)
class PivotAxleSpec:
    """A passive axle that pivots about the chassis's longitudinal axis (a rocker suspension).

    The wheels it carries hang from one revolute joint whose axis runs along the chassis x axis
    through the axle's midpoint: the joint transmits no roll moment, so a four-wheeled vehicle
    with one pivoting axle is statically determinate and keeps all four wheels loaded on
    uneven ground: the pivoting front axle of farm tractors, and the passive roll freedom of
    the rocker-type suspensions of four-wheeled rovers (Thueer, Krebs & Siegwart 2006 compare
    such passive suspensions).

    Attributes
    ----------
    wheels : tuple[str, ...]
        Names of the wheels on the axle (at least two, one each side, same x).
    height_m : float
        Height of the pivot axis above the wheel-centre plane, in the chassis frame [m].
    limit_rad : float
        Symmetric stop of the pivot angle, ``|angle| <= limit_rad`` [rad].
    damping_nms : float
        Viscous damping of the pivot [N m s/rad] (0: a free pivot).
    """

    wheels: tuple[str, ...]
    height_m: float = 0.0
    limit_rad: float = math.radians(15.0)
    damping_nms: float = 0.0

    def __post_init__(self) -> None:
        owner = "PivotAxleSpec"
        if (not isinstance(self.wheels, tuple) or len(self.wheels) < 2
                or not all(isinstance(w, str) and w for w in self.wheels)):
            raise ValueError(f"{owner}.wheels must be a tuple of at least two wheel names, "
                             f"got {self.wheels!r}")
        _check_range(owner, "height_m", self.height_m, "pivot_height_m")
        _check_range(owner, "limit_rad", self.limit_rad, "pivot_limit_rad")
        _check_range(owner, "damping_nms", self.damping_nms, "pivot_damping_nms")


@dataclass(frozen=True)
class VehicleSpec:
    """A whole vehicle.

    Attributes
    ----------
    name : str
        Preset name.
    kind : str
        ``diff_drive`` | ``skid_steer`` | ``rover4ws`` (the log-format vehicle kinds).
    chassis_mass_kg : float
        Chassis mass without wheels [kg].
    chassis_size_m : tuple[float, float, float]
        Chassis box length, width, height [m].
    chassis_center_height_m : float
        Height of the chassis box centre above the wheel-centre plane [m].
    wheels : tuple[WheelSpec, ...]
        All wheels, left side first within each axle.
    channels : tuple[str, ...]
        Drive channel names, left side first (encoders and torque sensors report per channel).
    track_width_m : float
        Lateral distance between the left and right contact lines [m].
    wheel_radius_nominal_m : float
        The radius the operator believes in for odometry (calibrated on concrete) [m].
    max_wheel_speed_rad_s : float
        Motor speed limit [rad/s].
    max_wheel_torque_nm : float
        Motor torque limit per wheel [N m] (brakes hold up to the same torque).
    max_speed_mps : float
        Forward speed at action +1 [m/s].
    max_yaw_rate_rad_s : float
        Yaw rate at action +1 [rad/s].
    counts_per_rad : float
        Encoder resolution [counts/rad] (Lindgren: 285).
    wheelbase_m : float | None
        Front-rear axle distance for ``rover4ws`` [m].
    urdf : str | None
        A ``pybullet_data`` URDF to load instead of building the body from the spec (Husky);
        its wheel joints are matched by ``urdf_wheel_joints``.
    urdf_wheel_joints : tuple[str, ...]
        Joint names of the URDF wheels in the order of ``wheels``.
    track_length_m : float | None
        Ground contact length of each track for a tracked vehicle [m] (its road wheels split
        it into ``contact_length_m`` shares); ``None`` for wheeled vehicles.
    contact_sinkage_m : float
        Static sinkage of the compliant wheel-ground contact under the vehicle's own weight [m].
        Soil is not rigid: the compliance spreads the load over a track's road wheels (a rigid
        contact leaves them statically indeterminate, with two or three carrying everything).
    track_model : str
        Soil force model of a tracked vehicle: ``"per_wheel"`` (every road wheel its own
        contact patch and slip state, ``slipenv.sim.wheel_soil``) or ``"wong_chiang"`` (one
        shear field along each track, with sinkage, rut and side-wall resistance,
        ``slipenv.terramechanics.track`` and ``slipenv.sim.track_soil``); needs
        ``track_length_m`` and a ``skid_steer`` vehicle.
    track_shear_law : str
        Shear law of the ``"wong_chiang"`` track model (`TRACK_SHEAR_LAWS`): ``"resultant"``
        (default; Wong-Chiang's tau(|j|) against the sliding direction) or ``"decoupled"``
        (Ishigami et al. 2007: each shear component of its own displacement, the resultant
        capped at the Mohr-Coulomb strength, where the soil deforms; on rigid ground the
        resultant law, the tread's Coulomb friction: ``slipenv.terramechanics.track``).
    track_longitudinal_shear_modulus_ratio, track_lateral_shear_modulus_ratio : float
        K_x/K and K_y/K of the ``"decoupled"`` shear law: its shear deformation moduli along
        and across the track over the soil's Janosi K (Ishigami et al. 2007 identify separate
        K_x, K_y for a grousered wheel). 1 (default): the soil's K; within [0.05, 20].
    pivot_axle : PivotAxleSpec | None
        A passive axle pivoting about the longitudinal axis (rocker suspension); ``None``: the
        chassis and all wheel mounts form one rigid body.
    assumed : tuple[str, ...]
        Fields whose values the source paper leaves out and that are assumed here (non-empty
        strings).

    Notes
    -----
    Every number must lie within :data:`BOUNDS` (a toy rover to a 100 t tractor: chassis
    0.1 kg-100 t, wheel radius 5 mm-2 m, torque <= 1e5 N m per wheel, speed <= 50 m/s, ...);
    anything else is a ``ValueError`` naming the field.
    """

    name: str
    kind: str
    chassis_mass_kg: float
    chassis_size_m: tuple[float, float, float]
    chassis_center_height_m: float
    wheels: tuple[WheelSpec, ...]
    channels: tuple[str, ...]
    track_width_m: float
    wheel_radius_nominal_m: float
    max_wheel_speed_rad_s: float
    max_wheel_torque_nm: float
    max_speed_mps: float
    max_yaw_rate_rad_s: float
    counts_per_rad: float = 285.0
    wheelbase_m: float | None = None
    urdf: str | None = None
    urdf_wheel_joints: tuple[str, ...] = ()
    track_length_m: float | None = None
    contact_sinkage_m: float = 0.001
    track_model: str = "per_wheel"
    track_shear_law: str = "resultant"
    track_longitudinal_shear_modulus_ratio: float = 1.0
    track_lateral_shear_modulus_ratio: float = 1.0
    pivot_axle: PivotAxleSpec | None = None
    assumed: tuple[str, ...] = field(default_factory=tuple)

    def __post_init__(self) -> None:
        owner = f"VehicleSpec({self.name!r})"
        if self.kind not in VEHICLE_KINDS:
            raise ValueError(f"{owner}.kind must be one of {VEHICLE_KINDS}, got {self.kind!r}")
        _check_positive(
            owner,
            chassis_mass_kg=self.chassis_mass_kg,
            track_width_m=self.track_width_m,
            wheel_radius_nominal_m=self.wheel_radius_nominal_m,
            max_wheel_speed_rad_s=self.max_wheel_speed_rad_s,
            max_wheel_torque_nm=self.max_wheel_torque_nm,
            max_speed_mps=self.max_speed_mps,
            max_yaw_rate_rad_s=self.max_yaw_rate_rad_s,
            counts_per_rad=self.counts_per_rad,
            contact_sinkage_m=self.contact_sinkage_m,
        )
        size = dict(zip(("length", "width", "height"), self.chassis_size_m, strict=True))
        _check_positive(owner, **{f"chassis_{k}_m": v for k, v in size.items()})
        for name in ("chassis_mass_kg", "chassis_center_height_m", "track_width_m",
                     "max_wheel_speed_rad_s", "max_wheel_torque_nm", "max_speed_mps",
                     "max_yaw_rate_rad_s", "counts_per_rad", "contact_sinkage_m"):
            _check_range(owner, name, getattr(self, name))
        _check_range(owner, "wheel_radius_nominal_m", self.wheel_radius_nominal_m,
                     "wheel_radius_m")
        for k, v in size.items():
            _check_range(owner, f"chassis_size_m ({k})", v, "chassis_dimension_m")
        for name in ("wheelbase_m", "track_length_m"):
            if getattr(self, name) is not None:
                _check_range(owner, name, getattr(self, name))
        if not self.wheels or not self.channels:
            raise ValueError(f"{owner}: a vehicle needs wheels and drive channels")
        names = [w.name for w in self.wheels]
        if len(set(names)) != len(names):
            raise ValueError(f"{owner}: wheel names must be unique, got {names}")
        for wheel in self.wheels:
            if wheel.channel is not None and wheel.channel not in self.channels:
                raise ValueError(
                    f"{owner}: wheel {wheel.name!r} names unknown channel {wheel.channel!r}; "
                    f"channels are {self.channels}"
                )
        empty = [c for c in self.channels if not any(w.channel == c for w in self.wheels)]
        if empty:
            raise ValueError(f"{owner}: channels without wheels: {empty}")
        if self.kind == "rover4ws" and self.wheelbase_m is None:
            raise ValueError(f"{owner}: a rover4ws vehicle needs wheelbase_m")
        if self.track_model not in TRACK_MODELS:
            raise ValueError(f"{owner}.track_model must be one of {TRACK_MODELS}, "
                             f"got {self.track_model!r}")
        if self.track_model == "wong_chiang" and (self.track_length_m is None
                                                   or self.kind != "skid_steer"):
            raise ValueError(f"{owner}.track_model='wong_chiang' needs a skid_steer vehicle "
                             "with track_length_m")
        if self.track_shear_law not in TRACK_SHEAR_LAWS:
            raise ValueError(f"{owner}.track_shear_law must be one of {TRACK_SHEAR_LAWS}, "
                             f"got {self.track_shear_law!r}")
        for name in ("track_longitudinal_shear_modulus_ratio",
                     "track_lateral_shear_modulus_ratio"):
            _check_range(owner, name, getattr(self, name), "shear_modulus_ratio")
        if self.urdf is not None and len(self.urdf_wheel_joints) != len(self.wheels):
            raise ValueError(f"{owner}: urdf_wheel_joints must name one joint per wheel")
        if (not isinstance(self.assumed, tuple)
                or not all(isinstance(a, str) and a.strip() for a in self.assumed)):
            raise ValueError(f"{owner}.assumed must be a tuple of non-empty strings, "
                             f"got {self.assumed!r}")
        if self.pivot_axle is not None:
            self._check_pivot_axle(owner, self.pivot_axle)

    def _check_pivot_axle(self, owner: str, axle: PivotAxleSpec) -> None:
        if self.urdf is not None:
            raise ValueError(f"{owner}.pivot_axle needs a body built from the spec, not a URDF")
        by_name = {w.name: w for w in self.wheels}
        unknown = [n for n in axle.wheels if n not in by_name]
        if unknown or len(set(axle.wheels)) != len(axle.wheels):
            raise ValueError(f"{owner}.pivot_axle.wheels must name distinct wheels of the "
                             f"vehicle, got {axle.wheels}; wheels are {tuple(by_name)}")
        on_axle = [by_name[n] for n in axle.wheels]
        xs = [w.position_m[0] for w in on_axle]
        if max(xs) - min(xs) > 1e-9:
            raise ValueError(f"{owner}.pivot_axle wheels must share one axle (one x), got {xs}")
        ys = [w.position_m[1] for w in on_axle]
        if not (min(ys) < 0.0 < max(ys)):
            raise ValueError(f"{owner}.pivot_axle needs a wheel on each side, got y = {ys}")
        if len(on_axle) == len(self.wheels):
            raise ValueError(f"{owner}.pivot_axle cannot carry every wheel: the chassis would "
                             "roll freely about it")

    def pivot_origin_m(self) -> tuple[float, float, float] | None:
        """Point on the pivot axis in the chassis frame (axle midpoint at the pivot height)."""
        if self.pivot_axle is None:
            return None
        ws = [w for w in self.wheels if w.name in self.pivot_axle.wheels]
        n = len(ws)
        return (sum(w.position_m[0] for w in ws) / n, sum(w.position_m[1] for w in ws) / n,
                sum(w.position_m[2] for w in ws) / n + self.pivot_axle.height_m)

    @property
    def mass_kg(self) -> float:
        """Total mass, chassis plus wheels [kg]."""
        return self.chassis_mass_kg + sum(w.mass_kg for w in self.wheels)

    @property
    def left_channels(self) -> tuple[int, ...]:
        """Indices of channels whose wheels sit on the left (y > 0)."""
        return tuple(i for i, c in enumerate(self.channels) if self._channel_y(c) > 0.0)

    @property
    def right_channels(self) -> tuple[int, ...]:
        """Indices of channels whose wheels sit on the right (y < 0)."""
        return tuple(i for i, c in enumerate(self.channels) if self._channel_y(c) < 0.0)

    def _channel_y(self, channel: str) -> float:
        ys = [w.position_m[1] for w in self.wheels if w.channel == channel]
        return sum(ys) / len(ys)

    def channel_xy_m(self) -> list[tuple[float, float]]:
        """Mean (x, y) of each channel's wheels in the chassis frame [m]."""
        out = []
        for channel in self.channels:
            ws = [w for w in self.wheels if w.channel == channel]
            out.append((sum(w.position_m[0] for w in ws) / len(ws), self._channel_y(channel)))
        return out
