"""The four vehicles of slipenv, with the source of every number.

Values the papers leave out are listed in each spec's ``assumed`` field and commented here.
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Callable

from slipenv.vehicles.spec import PivotAxleSpec, VehicleSpec, WheelSpec


def farm_2wd() -> VehicleSpec:
    """Lindgren's agricultural vehicle: two independently driven front wheels, passive rear.

    Lindgren §2.1-2.2: hydrostatic drive of each front wheel, 285 counts/rad encoders, effective
    rolling radius 0.275 m on concrete and 0.283 / 0.287 m (left / right) on soil (§3.2). The
    vehicle spans one 2 m crop bed; mass, track width and wheelbase are not given and assumed.
    """
    r = 0.275
    track = 1.6  # assumed: spans a 2 m bed with the wheels in the furrows
    front_x = 0.75  # assumed: 1.5 m wheelbase
    wheels = (
        WheelSpec("front_left", (front_x, track / 2, 0.0), r, 0.25, 20.0, "left",
                  contact_length_m=0.18, soil_rolling_radius_m=0.283),
        WheelSpec("front_right", (front_x, -track / 2, 0.0), r, 0.25, 20.0, "right",
                  contact_length_m=0.18, soil_rolling_radius_m=0.287),
        # Passive rear support modelled as castors (Lindgren: "passive"; type assumed).
        WheelSpec("rear_left", (-front_x, track / 2, -0.125), 0.15, 0.12, 5.0, None,
                  role="caster", contact_length_m=0.08),
        WheelSpec("rear_right", (-front_x, -track / 2, -0.125), 0.15, 0.12, 5.0, None,
                  role="caster", contact_length_m=0.08),
    )
    return VehicleSpec(
        name="farm_2wd",
        kind="diff_drive",
        chassis_mass_kg=450.0,  # assumed: a light petrol-engined gantry vehicle
        chassis_size_m=(2.0, 1.8, 0.4),
        chassis_center_height_m=0.45,
        wheels=wheels,
        channels=("left", "right"),
        track_width_m=track,
        wheel_radius_nominal_m=r,
        max_wheel_speed_rad_s=6.0,
        max_wheel_torque_nm=900.0,  # assumed: hydrostatic drive, ample for 15° slopes
        max_speed_mps=1.2,
        max_yaw_rate_rad_s=0.8,
        counts_per_rad=285.0,
        assumed=("chassis_mass_kg", "track_width_m", "wheel positions", "rear castors",
                 "max_wheel_torque_nm"),
    )


def tracked_patako(road_wheels_per_side: int = 5, track_model: str = "per_wheel") -> VehicleSpec:
    """Yamauchi's skid-steer tracked vehicle Patako (Table 1): tread 0.41 m, tracks 0.60 × 0.11 m.

    Table 1, as published: dimensions L503 × W686 × H522 mm, tread 0.41 m, track length 0.60 m,
    track width 0.11 m, Endo's n on a solid floor 0.824. The mass column is garbled in our copy
    (it repeats the tread's "0.41 [m]"), and no other source we could find gives it: 30 kg in
    all is assumed (26 kg hull, ten 0.4 kg road wheels). The 0.60 m tracks cannot fit a 503 mm
    long body, so L and W read as swapped: 686 mm long (the tracks plus the hull's overhang),
    503 mm wide (tread + track width = 0.52 m, the tracks' outer edges). The hull box here is
    0.503 m long and 0.30 m wide between the tracks (its inertia only; the tracks carry it).

    Each track is ``road_wheels_per_side`` road wheels that share one sprocket speed (one drive
    channel), each carrying an equal share of the track's ground contact length.

    Contact length, derived (not published): Table 1's 0.60 m is the length of the track; it
    wraps around the sprocket and the idler, so on firm ground it bears on the soil only between
    their axles (Wong, Theory of Ground Vehicles, Ch. 4: the contact length of a track is the
    distance between the centres of sprocket and idler), 0.60 m - 2r = 0.48 m with the
    sprocket/idler radius r = 6 cm (not published: assumed). Sand adds
    the sinkage-deep arcs of the sprocket and idler, about 2 sqrt(2 r z) = 4 cm at the 3 mm
    static sinkage of ``toyoura_sand``, which is neglected. Grousers: not published (Fig. 3's
    photograph is not in our copy); none are modelled, their effect on the shear is in the
    soil's K.

    ``track_model`` selects the soil model: ``"per_wheel"`` (default: each road wheel its own
    Janosi patch) or ``"wong_chiang"`` (one shear field along each track, sinkage, rut and
    side-wall resistance; ``slipenv.sim.track_soil``), registered as the vehicle
    ``tracked_patako_wong_chiang``, the one ``slipenv/TrackedSlopeCircle-v0`` drives.
    """
    tread, track_length, width = 0.41, 0.60, 0.11
    r = 0.06  # assumed road-wheel / sprocket / idler radius
    # Ground contact between the sprocket and idler axles (docstring): 0.48 m, not 0.60 m.
    length = track_length - 2.0 * r
    share = length / road_wheels_per_side
    xs = [-length / 2 + share * (i + 0.5) for i in range(road_wheels_per_side)]
    wheels = tuple(
        WheelSpec(f"{side}_{i}", (x, y, 0.0), r, width, 0.4, side, contact_length_m=share)
        for side, y in (("left", tread / 2), ("right", -tread / 2))
        for i, x in enumerate(xs)
    )
    return VehicleSpec(
        name="tracked_patako",
        kind="skid_steer",
        chassis_mass_kg=26.0,  # assumed (Table 1's mass is garbled in our copy)
        chassis_size_m=(0.503, 0.30, 0.30),
        chassis_center_height_m=0.17,
        wheels=wheels,
        channels=("left", "right"),
        track_width_m=tread,
        wheel_radius_nominal_m=r,
        max_wheel_speed_rad_s=8.0,
        max_wheel_torque_nm=15.0,
        max_speed_mps=0.3,
        max_yaw_rate_rad_s=math.radians(45.0),
        counts_per_rad=285.0,
        track_length_m=length,
        track_model=track_model,
        assumed=("chassis_mass_kg", "road wheel radius", "road_wheels_per_side",
                 "track_length_m (derived: 0.60 m track less the assumed sprocket radius)",
                 "grousers (none modelled)"),
    )


def tracked_patako_wong_chiang() -> VehicleSpec:
    """:func:`tracked_patako` with the Wong-Chiang track model: one Janosi shear
    field along each track, Bekker sinkage with slip-sinkage, a rut state and side-wall
    bulldozing (``slipenv.terramechanics.track``, ``slipenv.sim.track_soil``).

    Shear law: Wong & Chiang's resultant law (the spec's default), the stress against the
    sliding velocity, with the soil's sourced K: on ``toyoura_sand`` it puts Yamauchi's Endo n
    within 0.05 of the paper's at every tilt with nothing calibrated. Ishigami et al.'s
    decoupled components (``track_shear_law="decoupled"``, applied where the soil deforms, the
    resultant law kept on rigid ground) need two moduli no source gives for a track:
    :func:`tracked_patako_decoupled` calibrates them on the same n (docs/physics.md)."""
    return dataclasses.replace(tracked_patako(track_model="wong_chiang"),
                               name="tracked_patako_wong_chiang")


def tracked_patako_decoupled() -> VehicleSpec:
    """:func:`tracked_patako_wong_chiang` with Ishigami et al.'s decoupled shear law and its two
    shear deformation moduli calibrated on Yamauchi's measured Endo n (§2.4: 0.832 / 0.817 /
    0.824 at 0 / 8 / 15°), the alternative world of ``slipenv reproduce yamauchi --vehicle
    tracked_patako_decoupled``.

    No source gives a track's K_x and K_y on Toyoura sand (the Tohoku group's 28.3 mm is one K
    of a 0.1 m wheel). ``benchmarks/yamauchi_shear_calibration.py`` runs the reproduction's
    rotation runs over a grid of (K_x, K_y/K_x) and three run plans and keeps the point whose
    n is nearest the paper's at every tilt: K_x = 2.3 K = 65 mm along the track, K_y = 0.69 K
    = 19.5 mm across it (K = ``toyoura_sand``'s 28.3 mm; docs/physics.md has the table). The
    odometry and the circle are validation only; the env keeps the resultant law (the
    preset above), whose sourced K already puts n within 0.05 of the paper's at every tilt.
    """
    spec = tracked_patako_wong_chiang()
    return dataclasses.replace(spec, name="tracked_patako_decoupled",
                               track_shear_law="decoupled",
                               track_longitudinal_shear_modulus_ratio=2.3,
                               track_lateral_shear_modulus_ratio=0.69,
                               assumed=(*spec.assumed, "track shear moduli K_x, K_y "
                                        "(calibrated on Yamauchi's Endo n)"))


def rover_4ws(rocker: bool = True) -> VehicleSpec:
    """Reina's El-Dorado-like 4WD/4WS rover: about 6.6 kg load per wheel (Reina §3).

    Wheel radius, wheelbase and track are not given for El-Dorado and are assumed for a ~0.6 m
    rover with 0.18 m wheels (inside the 5-25 cm range of Reina's single-wheel test bed).

    Reina §1: El-Dorado features "a rocker-type suspension system". Neither the paper nor the
    sources we could find give its layout or dimensions, so it is modelled as the simplest
    passive suspension that gives a four-wheeled vehicle the same property (one roll freedom
    between the axles: all four wheels stay loaded on uneven ground): a front axle pivoting
    freely about the chassis's longitudinal axis at the wheel-centre height, with ±15° stops.
    ``rocker=False`` gives the rigid chassis (all four wheel mounts on one body).
    """
    r, half_l, half_w = 0.09, 0.30, 0.25
    wheels = tuple(
        WheelSpec(name, (x, y, 0.0), r, 0.08, 0.5, name, contact_length_m=0.05, steered=True)
        for name, x, y in (
            ("front_left", half_l, half_w),
            ("front_right", half_l, -half_w),
            ("rear_left", -half_l, half_w),
            ("rear_right", -half_l, -half_w),
        )
    )
    return VehicleSpec(
        name="rover_4ws",
        kind="rover4ws",
        chassis_mass_kg=24.4,  # 4 × 6.6 kg wheel load (Reina §3) minus the wheels
        chassis_size_m=(0.7, 0.4, 0.2),
        chassis_center_height_m=0.15,
        wheels=wheels,
        channels=tuple(w.name for w in wheels),
        track_width_m=2 * half_w,
        wheel_radius_nominal_m=r,
        max_wheel_speed_rad_s=4.0,
        max_wheel_torque_nm=8.0,
        max_speed_mps=0.3,
        max_yaw_rate_rad_s=0.6,
        counts_per_rad=285.0,
        wheelbase_m=2 * half_l,
        # Assumed (docstring): a pivoting front axle standing in for El-Dorado's unpublished
        # rocker layout; pivot at the wheel-centre height, ±15° stops, no damping.
        pivot_axle=PivotAxleSpec(("front_left", "front_right"), height_m=0.0,
                                 limit_rad=math.radians(15.0), damping_nms=0.0)
        if rocker else None,
        assumed=("wheel radius", "wheelbase_m", "track_width_m", "max_wheel_torque_nm",
                 *(("pivot_axle: El-Dorado's rocker-type suspension (Reina §1) as a front axle "
                    "pivoting about the longitudinal axis (layout unpublished)",
                    "pivot_axle.height_m = 0 (wheel-centre height)",
                    "pivot_axle.limit_rad = 15°", "pivot_axle.damping_nms = 0")
                   if rocker else ())),
    )


def husky() -> VehicleSpec:
    """Clearpath Husky A200 from ``pybullet_data`` (``husky/husky.urdf``), skid-steer.

    Geometry as in the URDF: wheel radius 0.1651 m, wheel centres at x = +0.343 / -0.169 m,
    y = ±0.285 m relative to the chassis joint; 50 kg in total. Each side is one channel.
    """
    r = 0.1651
    wheels = (
        WheelSpec("front_left", (0.256, 0.2854, 0.0), r, 0.1143, 2.637, "left"),
        WheelSpec("front_right", (0.256, -0.2854, 0.0), r, 0.1143, 2.637, "right"),
        WheelSpec("rear_left", (-0.256, 0.2854, 0.0), r, 0.1143, 2.637, "left"),
        WheelSpec("rear_right", (-0.256, -0.2854, 0.0), r, 0.1143, 2.637, "right"),
    )
    return VehicleSpec(
        name="husky",
        kind="skid_steer",
        chassis_mass_kg=39.5,
        chassis_size_m=(1.0, 0.57, 0.27),
        chassis_center_height_m=0.1,
        wheels=wheels,
        channels=("left", "right"),
        track_width_m=0.5708,
        wheel_radius_nominal_m=r,
        max_wheel_speed_rad_s=6.0,
        max_wheel_torque_nm=30.0,
        max_speed_mps=1.0,
        max_yaw_rate_rad_s=1.5,
        counts_per_rad=285.0,
        urdf="husky/husky.urdf",
        urdf_wheel_joints=("front_left_wheel", "front_right_wheel",
                           "rear_left_wheel", "rear_right_wheel"),
        assumed=("max_wheel_torque_nm", "counts_per_rad"),
    )


VEHICLES: dict[str, Callable[[], VehicleSpec]] = {
    "farm_2wd": farm_2wd,
    "tracked_patako": tracked_patako,
    "tracked_patako_wong_chiang": tracked_patako_wong_chiang,
    "tracked_patako_decoupled": tracked_patako_decoupled,
    "rover_4ws": rover_4ws,
    "husky": husky,
}


def vehicle_by_name(name: str) -> VehicleSpec:
    """Return the preset called ``name``; an unknown name is a ``ValueError`` listing them."""
    try:
        return VEHICLES[name]()
    except KeyError:
        raise ValueError(f"unknown vehicle {name!r}; known vehicles: {sorted(VEHICLES)}") from None
