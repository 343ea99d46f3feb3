"""Vehicle specs, presets and twist kinematics."""

from __future__ import annotations

import dataclasses
import math

import pytest

from slipenv.vehicles.kinematics import twist_to_commands
from slipenv.vehicles.presets import VEHICLES, vehicle_by_name


@pytest.mark.parametrize("name", sorted(VEHICLES))
def test_every_preset_is_valid_and_names_what_it_assumes(name):
    spec = vehicle_by_name(name)
    assert spec.mass_kg > 0 and spec.assumed
    assert spec.left_channels and spec.right_channels


def test_the_papers_numbers_are_in_the_presets():
    farm = vehicle_by_name("farm_2wd")
    assert farm.counts_per_rad == 285.0 and farm.wheel_radius_nominal_m == 0.275
    assert [w.soil_rolling_radius_m for w in farm.wheels[:2]] == [0.283, 0.287]
    tracked = vehicle_by_name("tracked_patako")
    # Table 1's 0.60 m track wraps the sprocket and idler: it bears on the ground between their
    # axles, 0.60 m minus one radius at each end.
    r = tracked.wheel_radius_nominal_m
    assert tracked.track_width_m == 0.41 and tracked.track_length_m == pytest.approx(0.60 - 2 * r)
    assert sum(w.contact_length_m for w in tracked.wheels if w.channel == "left") == \
        pytest.approx(0.60 - 2 * r)


def test_unknown_vehicle_lists_the_known_ones():
    with pytest.raises(ValueError, match="farm_2wd"):
        vehicle_by_name("tractor")


def test_differential_kinematics_turn_a_twist_into_wheel_speeds():
    spec = vehicle_by_name("husky")
    speeds, _ = twist_to_commands(spec, 0.5, 0.4)
    r, half = spec.wheel_radius_nominal_m, spec.track_width_m / 2
    assert speeds == pytest.approx([(0.5 - 0.4 * half) / r, (0.5 + 0.4 * half) / r])


def test_four_wheel_steering_points_each_wheel_along_its_velocity():
    spec = vehicle_by_name("rover_4ws")
    speeds, steer = twist_to_commands(spec, 0.2, 0.3)
    for (x, y), speed, delta in zip(spec.channel_xy_m(), speeds, steer, strict=True):
        vx, vy = 0.2 - 0.3 * y, 0.3 * x
        assert delta == pytest.approx(math.atan2(vy, vx))
        assert speed * spec.wheel_radius_nominal_m == pytest.approx(math.hypot(vx, vy))


def test_wheel_speeds_are_scaled_together_to_the_motor_limit():
    spec = vehicle_by_name("husky")
    speeds, _ = twist_to_commands(spec, 10.0, 1.0)
    assert max(abs(s) for s in speeds) == pytest.approx(spec.max_wheel_speed_rad_s)
    assert speeds[1] / speeds[0] == pytest.approx((10 + 0.5 * spec.track_width_m) /
                                                  (10 - 0.5 * spec.track_width_m))


def test_a_driven_wheel_without_channel_or_an_unknown_channel_is_rejected():
    spec = vehicle_by_name("husky")
    wheel = dataclasses.replace(spec.wheels[0], channel="middle")
    with pytest.raises(ValueError, match="unknown channel"):
        dataclasses.replace(spec, wheels=(wheel, *spec.wheels[1:]))


@pytest.mark.parametrize(("field", "value"), [
    ("chassis_mass_kg", 1e9), ("chassis_mass_kg", 1e-6), ("max_wheel_torque_nm", 1e12),
    ("max_speed_mps", 1e4), ("track_width_m", 1e9), ("counts_per_rad", float("nan")),
    ("chassis_mass_kg", True),
])
def test_a_physically_implausible_vehicle_is_a_value_error_naming_the_field(field, value):
    import dataclasses

    from slipenv.vehicles.presets import husky

    with pytest.raises(ValueError, match=field):
        dataclasses.replace(husky(), **{field: value})


def test_every_preset_lies_within_the_plausible_bounds():
    from slipenv.vehicles.presets import VEHICLES

    for build in VEHICLES.values():
        build()  # validated on construction


def test_the_rover_names_its_rocker_suspension_as_assumed_and_the_rigid_variant_has_none():
    from slipenv.vehicles.presets import rover_4ws

    rover = rover_4ws()
    assert rover.pivot_axle is not None
    assert set(rover.pivot_axle.wheels) == {"front_left", "front_right"}
    assert rover.pivot_origin_m() == pytest.approx((rover.wheelbase_m / 2, 0.0, 0.0))
    assert any("pivot_axle" in a for a in rover.assumed)
    rigid = rover_4ws(rocker=False)
    assert rigid.pivot_axle is None and rigid.pivot_origin_m() is None
    assert not any("pivot_axle" in a for a in rigid.assumed)


@pytest.mark.parametrize(("wheels", "match"), [
    (("front_left", "nose"), "distinct wheels"),
    (("front_left", "front_left"), "distinct wheels"),
    (("front_left", "rear_right"), "one axle"),
    (("front_left",), "at least two"),
])
def test_a_pivot_axle_that_is_not_one_axle_of_the_vehicle_is_a_value_error(wheels, match):
    from slipenv.vehicles.presets import rover_4ws
    from slipenv.vehicles.spec import PivotAxleSpec

    with pytest.raises(ValueError, match=match):
        dataclasses.replace(rover_4ws(), pivot_axle=PivotAxleSpec(wheels))


@pytest.mark.parametrize(("field", "value"), [
    ("limit_rad", 0.0), ("limit_rad", 2.0), ("damping_nms", -1.0), ("height_m", float("nan")),
])
def test_a_pivot_axle_with_an_implausible_number_is_a_value_error_naming_it(field, value):
    from slipenv.vehicles.spec import PivotAxleSpec

    with pytest.raises(ValueError, match=field):
        PivotAxleSpec(("front_left", "front_right"), **{field: value})


def test_a_pivot_axle_on_a_urdf_vehicle_is_a_value_error():
    from slipenv.vehicles.spec import PivotAxleSpec

    axle = PivotAxleSpec(("front_left", "front_right"))
    with pytest.raises(ValueError, match="URDF"):
        dataclasses.replace(vehicle_by_name("husky"), pivot_axle=axle)


@pytest.mark.parametrize("assumed", [("mass", ""), ["mass"], ("mass", 3)])
def test_assumed_must_be_a_tuple_of_non_empty_strings(assumed):
    with pytest.raises(ValueError, match="assumed"):
        dataclasses.replace(vehicle_by_name("husky"), assumed=assumed)
