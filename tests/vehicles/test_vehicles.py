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
