import pytest

from slipenv.contracts.names import did_you_mean, lookup


def test_a_misspelt_name_gets_the_closest_choice():
    assert did_you_mean("cirle", ["circle", "slalom"]) == "; did you mean 'circle'?"


def test_a_part_of_a_name_hints_the_whole_name():
    assert did_you_mean("sand", ["loose_sand", "clay"]) == "; did you mean 'loose_sand'?"


def test_nothing_close_gives_no_hint():
    assert did_you_mean("xyz", ["circle", "slalom"]) == ""


def test_lookup_returns_the_entry():
    assert lookup({"a": 1}, "a", "thing") == 1


@pytest.mark.parametrize("name", ["b", None, ["a"]])
def test_lookup_of_an_unknown_name_is_a_value_error_listing_the_known_ones(name):
    with pytest.raises(ValueError, match=r"unknown thing .*known things: a, c"):
        lookup({"a": 1, "c": 2}, name, "thing")
