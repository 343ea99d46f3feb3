"""The Yamauchi world can run on the Wong-Chiang track model and a loose sand (issue 16)."""

from __future__ import annotations

from slipenv.experiments.yamauchi import Settings, make_world


def test_settings_choose_the_vehicle_and_soil_of_every_world():
    cfg = Settings(vehicle="tracked_patako_wong_chiang", soil="dry_sand")
    env = make_world(8.0, cfg.soil, cfg.vehicle)
    try:
        env.reset(seed=0)
        assert env.unwrapped.vehicle.track_model == "wong_chiang"
        assert env.unwrapped.config.soil == "dry_sand"
    finally:
        env.close()
    default = make_world(0.0)
    try:
        default.reset(seed=0)
        assert default.unwrapped.vehicle.track_model == "per_wheel"
        assert default.unwrapped.config.soil == "toyoura_sand"
    finally:
        default.close()
