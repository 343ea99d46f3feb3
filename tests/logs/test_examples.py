"""The example logs shipped in the package: found by name, valid, small, attributed."""

from __future__ import annotations

import pytest

from slipenv.logs import read_log
from slipenv.logs.examples import NAMES, path, root

MAX_TOTAL_BYTES = 1_000_000  # the package carries them: keep them well under a megabyte


def test_every_example_is_a_valid_log_inside_the_package():
    import slipenv

    package = path("synthetic").parents[2]
    assert package.samefile(slipenv.__path__[0])
    for name in NAMES:
        log = read_log(path(name), require_ground_truth=name != "borealtc")
        assert len(log) > 100, name


def test_examples_stay_small():
    total = sum(f.stat().st_size for f in root().rglob("*") if f.is_file())
    assert total < MAX_TOTAL_BYTES


def test_the_real_examples_carry_their_source_and_license():
    boreal = read_log(path("borealtc"), require_ground_truth=False)
    assert boreal.meta.data["source"]["license"] == "CC0 1.0 (dataset)"
    assert boreal.meta.data["borealtc"]["terrain"] == "SNOW"
    assert {"gyro_z", "current_left"} <= set(boreal.columns)
    assert "LaRocque" in (path("borealtc") / "ATTRIBUTION.md").read_text()
    opti = read_log(path("optiodom"))
    assert opti.meta.data["source"]["license"].startswith("MIT")
    license_text = (path("optiodom") / "LICENSE").read_text()
    assert "Copyright (c) 2021 Ricardo Sousa" in license_text
    assert "Permission is hereby granted" in license_text


def test_the_generated_example_names_its_hidden_effect():
    synth = read_log(path("synthetic")).meta.data["synth"]
    assert synth["effect"] == "rolling_radius"
    assert set(synth["truth"]) == {"radius_left_m", "radius_right_m"}


def test_an_unknown_example_lists_the_known_ones():
    with pytest.raises(ValueError, match="borealtc, optiodom, synthetic"):
        path("husky")
